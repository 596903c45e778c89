/* bench_morph: one pair morph with the narrow band and with the full grid (--band off), on the
 * C path: the morph's seconds (creation, steps, rebuilds: all of it), its steps, its cell
 * updates and cells updated per second.
 * Usage: bench_morph [threads [band|full]]   (default 1, both).  Prints one line per size and
 * mode:
 *   mode N threads seconds steps cell_updates cells_per_second
 * the best of three runs.  The pair: phi = the distance of a disc of radius 0.3 N, the target an
 * offset, squashed disc, morphed to s = 3/4 (t = ln 4); a part of the target (a disc of radius
 * 0.05 N) lies far from the source, as a lobe of an organ that appears in one slice does, and
 * sets the full grid's step through |phi - phi_target| around it. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "solver/base/lsm_clock.h"
#include "solver/pde/lsm_morph.h"

int main(int argc, char **argv) {
  int threads = argc > 1 ? atoi(argv[1]) : 1;
  if (threads < 1) threads = 1;
  const char *only = argc > 2 ? argv[2] : "";
  const int sizes[] = {256, 512, 1024};
  for (size_t q = 0; q < sizeof sizes / sizeof *sizes; ++q) {
    const int n = sizes[q];
    lsm_grid *phi = NULL, *target = NULL;
    lsm_err err;
    lsm_err_clear(&err);
    if (lsm_grid_create(n, n, 1.0f, 1.0f, &phi, &err) ||
        lsm_grid_create(n, n, 1.0f, 1.0f, &target, &err)) {
      fprintf(stderr, "bench_morph: error: %s\n", err.msg);
      return 1;
    }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double x = i - 0.4 * n, y = j - 0.5 * n;
        LSM_AT(phi, i, j) = (float)(hypot(x, y) - 0.3 * n);
        const double body = hypot(x - 0.04 * n, 1.2 * y) - 0.27 * n;
        const double lobe = hypot(i - 0.88 * n, j - 0.15 * n) - 0.05 * n;
        LSM_AT(target, i, j) = (float)(body < lobe ? body : lobe);
      }
    lsm_grid_fill_ghosts(phi);
    lsm_grid_fill_ghosts(target);
    for (int band = 1; band >= 0; --band) {
      if ((band && strcmp(only, "full") == 0) || (!band && strcmp(only, "band") == 0)) continue;
      double best = INFINITY;
      int steps = 0;
      long long updates = 0;
      for (int run = 0; run < 3; ++run) {
        lsm_morph_opts o;
        lsm_morph_opts_default(&o);
        o.band = band;
        o.threads = threads;
        o.track_cp = 0;
        lsm_morph *m = NULL;
        const double t0 = lsm_clock_seconds();
        if (lsm_morph_create(phi, target, &o, &m, &err) != LSM_OK ||
            lsm_morph_advance_to(m, log(4.0), 1000000, &err) != LSM_OK) {
          fprintf(stderr, "bench_morph: error: %s\n", err.msg);
          return 1;
        }
        const double sec = lsm_clock_seconds() - t0;
        if (sec < best) best = sec;
        steps = lsm_morph_iterations(m);
        updates = lsm_morph_cell_updates(m);
        lsm_morph_destroy(&m);
      }
      printf("%s %d %d %.4g %d %lld %.4g\n", band ? "band" : "full", n, threads, best, steps,
             updates, (double)updates / best);
    }
    lsm_grid_destroy(&phi);
    lsm_grid_destroy(&target);
  }
  return 0;
}
