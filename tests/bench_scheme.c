/* bench_scheme: cells per second of one explicit update of the morph equation
 * (one Euler stage: phi <- phi - dt Hhat(phi)) for each scheme, on the C path.
 * Usage: bench_scheme [threads]   (default 1).  Prints one line per size:
 *   scheme N threads cells_per_second
 * the best of five timed blocks of about 0.06 s each, so that a moment of
 * background load on a shared machine does not decide the figure (the NumPy
 * baseline, tests/bench_numpy.py, is timed the same way).
 * The field is a real morph state: phi = SDF of a disc, target = SDF of an
 * offset ellipse-ish disc, so F changes sign and every branch is exercised. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "solver/base/lsm_clock.h"
#include "solver/pde/lsm_scheme.h"

int main(int argc, char **argv) {
  int threads = argc > 1 ? atoi(argv[1]) : 1;
  if (threads < 1) threads = 1;
  const int sizes[] = {256, 512, 1024, 2048};
  for (int scheme = 0; scheme < LSM_SCHEME_COUNT; ++scheme) {
    for (size_t q = 0; q < sizeof sizes / sizeof *sizes; ++q) {
      const int n = sizes[q];
      lsm_grid *phi = NULL, *target = NULL, *out = NULL;
      lsm_err err;
      lsm_err_clear(&err);
      if (lsm_grid_create(n, n, 1.0f, 1.0f, &phi, &err) || lsm_grid_create(n, n, 1.0f, 1.0f, &target, &err) ||
          lsm_grid_create(n, n, 1.0f, 1.0f, &out, &err)) {
        fprintf(stderr, "bench_scheme: error: %s\n", err.msg);
        return 1;
      }
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          double x = i - 0.5 * n, y = j - 0.5 * n;
          LSM_AT(phi, i, j) = (float)(hypot(x, y) - 0.3 * n);
          LSM_AT(target, i, j) = (float)(hypot(x - 0.1 * n, 1.5 * y) - 0.25 * n);
        }
      double dt;
      lsm_cfl_dt(phi, target, LSM_SCHEME_UPWIND, 0.75, threads, &dt);
      /* Five blocks of sweeps, about 0.06 s each at the upwind speed; the
       * fastest block counts. */
      long long cells = (long long)n * n;
      int reps = (int)(6.0e7 / (double)cells / (scheme == LSM_SCHEME_ROEFIX ? 8 : 1));
      if (reps < 3) reps = 3;
      lsm_scheme_stage((lsm_scheme)scheme, out, phi, phi, target, 0.0f, 1.0f, (float)dt, threads);
      double best = INFINITY;
      for (int block = 0; block < 5; ++block) {
        double t0 = lsm_clock_seconds();
        for (int r = 0; r < reps; ++r)
          lsm_scheme_stage((lsm_scheme)scheme, out, phi, phi, target, 0.0f, 1.0f, (float)dt, threads);
        double sec = lsm_clock_seconds() - t0;
        if (sec < best) best = sec;
      }
      printf("%s %d %d %.4g\n", lsm_scheme_name((lsm_scheme)scheme), n, threads,
             (double)cells * reps / best);
      fflush(stdout);
      lsm_grid_destroy(&phi);
      lsm_grid_destroy(&target);
      lsm_grid_destroy(&out);
    }
  }
  return 0;
}
