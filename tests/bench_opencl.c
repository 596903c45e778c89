/* bench_opencl: the OpenCL backend against the C path.
 * Usage: bench_opencl [device] [repeats]   (device: -1 = first GPU else first
 * device, the default; repeats: best of N timings, default 3).
 *
 *   1. The upwind stage, cells/s, at 256^2, 1024^2 and 4096^2:
 *        c1      lsm_scheme_stage, one thread (ghost fill + one Euler stage)
 *        cN      the same on all cores (omp_get_num_procs)
 *        opencl  ops->step (Euler, upwind: ghost fill + one stage kernel),
 *                many steps then one blocking residual to wait for the queue
 *   2. A whole 1024x1024 pair morph: lsm_morph_create (upload, CFL, residual),
 *      100 steps with the residual after each (default options: upwind, Euler,
 *      CP tracked), one lsm_morph_phi (download), lsm_morph_destroy; seconds
 *      for C one thread, C on all cores and OpenCL, and the ratio C1 / OpenCL.
 * The kernel cache is warmed before timing (the build time is printed).
 * Lines: "stage N BACKEND cells_per_second", "pair 1024 BACKEND seconds",
 * "pair 1024 ratio c1/opencl R". */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>

#include "solver/base/lsm_clock.h"
#include "solver/pde/lsm_backend.h"
#include "solver/pde/lsm_fields.h"
#include "solver/pde/lsm_morph.h"
#include "solver/pde/lsm_scheme.h"

static int die(const lsm_err *err) {
  fprintf(stderr, "bench_opencl: error: %s\n", err->msg);
  return 1;
}

/* phi = SDF of a disc, target = an offset squashed disc (as bench_scheme). */
static void fill(lsm_grid *phi, lsm_grid *target) {
  const int n = phi->nx;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      double x = i - 0.5 * n, y = j - 0.5 * n;
      LSM_AT(phi, i, j) = (float)(hypot(x, y) - 0.3 * n);
      LSM_AT(target, i, j) = (float)(hypot(x - 0.1 * n, 1.5 * y) - 0.25 * n);
    }
  lsm_grid_fill_ghosts(phi);
  lsm_grid_fill_ghosts(target);
}

static double stage_c(lsm_grid *phi, lsm_grid *target, lsm_grid *out, int threads, int reps,
                      float dt) {
  lsm_scheme_stage(LSM_SCHEME_UPWIND, out, phi, phi, target, 0.0f, 1.0f, dt, threads);
  double t0 = lsm_clock_seconds();
  for (int r = 0; r < reps; ++r)
    lsm_scheme_stage(LSM_SCHEME_UPWIND, out, phi, phi, target, 0.0f, 1.0f, dt, threads);
  return lsm_clock_seconds() - t0;
}

static lsm_status stage_cl(const lsm_backend *b, lsm_grid *phi, lsm_grid *target, int reps,
                           float dt, double *sec, lsm_err *err) {
  lsm_fields *f = NULL;
  double res;
  LSM_TRY(lsm_fields_create(b, phi, target, 1, &f, err));
  lsm_status s = lsm_fields_step(f, LSM_SCHEME_UPWIND, LSM_TIME_EULER, dt, err);
  if (s == LSM_OK) s = lsm_fields_residual(f, &res, err);
  double t0 = lsm_clock_seconds();
  for (int r = 0; r < reps && s == LSM_OK; ++r)
    s = lsm_fields_step(f, LSM_SCHEME_UPWIND, LSM_TIME_EULER, dt, err);
  if (s == LSM_OK) s = lsm_fields_residual(f, &res, err); /* waits for the queue */
  *sec = lsm_clock_seconds() - t0;
  lsm_fields_destroy(&f);
  return s;
}

static lsm_status pair(const lsm_grid *a, const lsm_grid *b, const lsm_backend *backend,
                       int threads, int steps, double *sec, lsm_err *err) {
  lsm_morph_opts o;
  lsm_morph_opts_default(&o);
  o.threads = threads;
  o.backend = backend;
  lsm_morph *m = NULL;
  double t0 = lsm_clock_seconds();
  LSM_TRY(lsm_morph_create(a, b, &o, &m, err));
  lsm_status s = LSM_OK;
  for (int k = 0; k < steps && s == LSM_OK; ++k) s = lsm_morph_step(m, INFINITY, err);
  if (s == LSM_OK && !lsm_morph_phi(m))
    s = lsm_fail(err, lsm_morph_error(m)->status, NULL, "%s", lsm_morph_error(m)->msg);
  lsm_morph_destroy(&m);
  *sec = lsm_clock_seconds() - t0;
  return s;
}

int main(int argc, char **argv) {
  const int device = argc > 1 ? atoi(argv[1]) : -1;
  int repeats = argc > 2 ? atoi(argv[2]) : 3;
  if (repeats < 1) repeats = 1;
  const int ncpu = omp_get_num_procs();
  lsm_err err;
  lsm_err_clear(&err);
  lsm_backend *cl = NULL;
  /* The first open may fill the driver's own kernel cache; the second is timed as a warm one. */
  if (lsm_backend_open("opencl", device, 1, &cl, &err) != LSM_OK) return die(&err);
  lsm_backend_fact facts[LSM_BACKEND_FACTS_MAX];
  lsm_backend_facts(cl, facts, LSM_BACKEND_FACTS_MAX);
  const double first_build = facts[1].number; /* build_seconds */
  lsm_backend_close(&cl);
  if (lsm_backend_open("opencl", device, 1, &cl, &err) != LSM_OK) return die(&err);
  lsm_backend_facts(cl, facts, LSM_BACKEND_FACTS_MAX);
  printf("# OpenCL device: %s\n", lsm_backend_device(cl));
  printf("# program build: first open %.3f s, second open %.3f s\n", first_build,
         facts[1].number);
  printf("# best of %d timings; C on all cores = %d threads\n", repeats, ncpu);
  fflush(stdout);

  const int sizes[] = {256, 1024, 4096};
  for (size_t q = 0; q < sizeof sizes / sizeof *sizes; ++q) {
    const int n = sizes[q];
    lsm_grid *phi = NULL, *target = NULL, *out = NULL;
    if (lsm_grid_create(n, n, 1.0f, 1.0f, &phi, &err) ||
        lsm_grid_create(n, n, 1.0f, 1.0f, &target, &err) ||
        lsm_grid_create(n, n, 1.0f, 1.0f, &out, &err))
      return die(&err);
    fill(phi, target);
    double dt;
    lsm_cfl_dt(phi, target, LSM_SCHEME_UPWIND, 0.75, 1, &dt);
    const double cells = (double)n * n;
    int reps = (int)(4.0e8 / cells);
    if (reps < 5) reps = 5;
    double best_c1 = INFINITY, best_cn = INFINITY, best_cl = INFINITY;
    for (int r = 0; r < repeats; ++r) {
      double s = stage_c(phi, target, out, 1, reps, (float)dt);
      if (s < best_c1) best_c1 = s;
      s = stage_c(phi, target, out, ncpu, reps, (float)dt);
      if (s < best_cn) best_cn = s;
      if (stage_cl(cl, phi, target, reps, (float)dt, &s, &err) != LSM_OK) return die(&err);
      if (s < best_cl) best_cl = s;
    }
    printf("stage %d c1 %.4g\n", n, cells * reps / best_c1);
    printf("stage %d c%d %.4g\n", n, ncpu, cells * reps / best_cn);
    printf("stage %d opencl %.4g\n", n, cells * reps / best_cl);
    fflush(stdout);
    lsm_grid_destroy(&phi);
    lsm_grid_destroy(&target);
    lsm_grid_destroy(&out);
  }

  const int n = 1024, steps = 100;
  lsm_grid *a = NULL, *b = NULL;
  if (lsm_grid_create(n, n, 1.0f, 1.0f, &a, &err) || lsm_grid_create(n, n, 1.0f, 1.0f, &b, &err))
    return die(&err);
  fill(a, b);
  double best_c1 = INFINITY, best_cn = INFINITY, best_cl = INFINITY, s;
  for (int r = 0; r < repeats; ++r) {
    if (pair(a, b, NULL, 1, steps, &s, &err) != LSM_OK) return die(&err);
    if (s < best_c1) best_c1 = s;
    if (pair(a, b, NULL, ncpu, steps, &s, &err) != LSM_OK) return die(&err);
    if (s < best_cn) best_cn = s;
    if (pair(a, b, cl, 1, steps, &s, &err) != LSM_OK) return die(&err);
    if (s < best_cl) best_cl = s;
  }
  printf("pair %d c1 %.4g\n", n, best_c1);
  printf("pair %d c%d %.4g\n", n, ncpu, best_cn);
  printf("pair %d opencl %.4g\n", n, best_cl);
  printf("pair %d ratio c1/opencl %.3g (target >= 3)\n", n, best_c1 / best_cl);
  lsm_grid_destroy(&a);
  lsm_grid_destroy(&b);
  lsm_backend_close(&cl);
  return 0;
}
