#include "solver/pde/lsm_scheme.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "kernels/lsm_stencil.h"

LSM_NAME_FUNCTIONS(lsm_scheme, LSM_SCHEME_LIST, lsm_scheme_name, lsm_scheme_from_name)
LSM_NAME_FUNCTIONS(lsm_time, LSM_TIME_LIST, lsm_time_name, lsm_time_from_name)

int lsm_time_stages(lsm_time time) {
  return time == LSM_TIME_RK3 ? 3 : time == LSM_TIME_RK2 ? 2 : 1;
}

/* ---- CFL ------------------------------------------------------------------------ */

void lsm_cfl_dt(lsm_grid *phi, const lsm_grid *phi_target, lsm_scheme scheme, double cfl,
                int threads, double *dt) {
  lsm_grid_fill_ghosts(phi);
  const int roefix = scheme == LSM_SCHEME_ROEFIX;
  const float inv_dx = 1.0f / phi->dx, inv_dy = 1.0f / phi->dy;
  const ptrdiff_t s = phi->stride;
  const float *p = phi->data, *t = phi_target->data;
  float rate = 0.0f;
#pragma omp parallel for num_threads(lsm_grid_threads(phi, threads)) schedule(static) reduction(max : rate)
  for (int j = 0; j < phi->ny; ++j) {
    const ptrdiff_t row = (ptrdiff_t)j * s;
    float row_rate = 0.0f;
    for (int i = 0; i < phi->nx; ++i)
      row_rate = lsm_maxf(row_rate, lsm_cfl_rate_at(p, t, row + i, s, inv_dx, inv_dy, roefix));
    rate = lsm_maxf(rate, row_rate);
  }
  *dt = rate > 0.0f ? cfl / (double)rate : INFINITY;
}

/* ---- one stage -------------------------------------------------------------------- */

/* The upwind and WENO5 sweeps are the hot loops: compiled for AVX-512F and
 * AVX2 as well as the baseline and picked at load time (GCC function
 * multi-versioning).  Every clone gives the same bits: C17 mode contracts no
 * a*b+c into FMA, and the vector square root, like the scalar one, is
 * correctly rounded. */
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
#define LSM_HOT_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define LSM_HOT_CLONES
#endif

/* A sweep of one stage over the interior, the cell's value from `cell`
 * (kernels/lsm_stencil.h); rows in parallel. */
#define LSM_STAGE_SWEEP(name, cell)                                                          \
  static void name(lsm_grid *out, const lsm_grid *u0, const lsm_grid *in,                   \
                   const lsm_grid *phi_target, float c0, float c1, float dt, int threads) { \
    const float inv_dx = 1.0f / in->dx, inv_dy = 1.0f / in->dy;                              \
    const ptrdiff_t s = in->stride;                                                          \
    const float *u = u0->data, *p = in->data, *t = phi_target->data;                         \
    float *o = out->data;                                                                    \
    _Pragma("omp parallel for num_threads(lsm_grid_threads(in, threads)) schedule(static)") \
    for (int j = 0; j < in->ny; ++j) {                                                       \
      const ptrdiff_t row = (ptrdiff_t)j * s;                                                \
      for (int i = 0; i < in->nx; ++i)                                                       \
        o[row + i] = cell(u, p, t, row + i, s, inv_dx, inv_dy, c0, c1, dt);                  \
    }                                                                                        \
  }

LSM_HOT_CLONES LSM_STAGE_SWEEP(stage_upwind, lsm_stage_upwind_at)
LSM_STAGE_SWEEP(stage_roefix, lsm_stage_roefix_at)
LSM_HOT_CLONES LSM_STAGE_SWEEP(stage_weno5, lsm_stage_weno5_at)

void lsm_scheme_stage(lsm_scheme scheme, lsm_grid *out, const lsm_grid *u0, lsm_grid *in,
                      const lsm_grid *phi_target, float c0, float c1, float dt, int threads) {
  lsm_grid_fill_ghosts(in);
  switch (scheme) {
  case LSM_SCHEME_ROEFIX:
    stage_roefix(out, u0, in, phi_target, c0, c1, dt, threads);
    break;
  case LSM_SCHEME_WENO5:
    stage_weno5(out, u0, in, phi_target, c0, c1, dt, threads);
    break;
  default:
    stage_upwind(out, u0, in, phi_target, c0, c1, dt, threads);
    break;
  }
}

/* ---- integrators ---------------------------------------------------------------------- */

struct lsm_stepper {
  lsm_grid *stage1, *stage2;
};

lsm_status lsm_stepper_create(const lsm_grid *like, lsm_stepper **out, lsm_err *err) {
  *out = NULL;
  lsm_stepper *st = calloc(1, sizeof *st);
  if (!st) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the integrator");
  lsm_status status = lsm_grid_create(like->nx, like->ny, like->dx, like->dy, &st->stage1, err);
  if (status == LSM_OK)
    status = lsm_grid_create(like->nx, like->ny, like->dx, like->dy, &st->stage2, err);
  if (status != LSM_OK) {
    lsm_stepper_destroy(&st);
    return status;
  }
  *out = st;
  return LSM_OK;
}

void lsm_stepper_destroy(lsm_stepper **stepper) {
  if (!stepper || !*stepper) return;
  lsm_grid_destroy(&(*stepper)->stage1);
  lsm_grid_destroy(&(*stepper)->stage2);
  free(*stepper);
  *stepper = NULL;
}

/* One stage, after telling the hook. */
static void hooked_stage(lsm_scheme scheme, lsm_grid *out, const lsm_grid *u0, lsm_grid *in,
                         const lsm_grid *phi_target, float c0, float c1, float dt, int threads,
                         const lsm_stage_hook *hook) {
  if (hook && hook->stage) {
    lsm_grid_fill_ghosts(in);
    hook->stage(hook->ctx, in, phi_target, c0, c1, dt);
  }
  lsm_scheme_stage(scheme, out, u0, in, phi_target, c0, c1, dt, threads);
}

void lsm_step_hooked(lsm_stepper *st, lsm_scheme scheme, lsm_time time, lsm_grid *phi,
                     const lsm_grid *phi_target, float dt, int threads,
                     const lsm_stage_hook *hook) {
  switch (time) {
  case LSM_TIME_RK2:
    /* phi1 = phi - dt L(phi);  phi = 1/2 phi + 1/2 (phi1 - dt L(phi1)) */
    hooked_stage(scheme, st->stage1, phi, phi, phi_target, 0.0f, 1.0f, dt, threads, hook);
    hooked_stage(scheme, phi, phi, st->stage1, phi_target, 0.5f, 0.5f, dt, threads, hook);
    break;
  case LSM_TIME_RK3:
    /* phi1 = phi - dt L(phi)
     * phi2 = 3/4 phi + 1/4 (phi1 - dt L(phi1))
     * phi  = 1/3 phi + 2/3 (phi2 - dt L(phi2)) */
    hooked_stage(scheme, st->stage1, phi, phi, phi_target, 0.0f, 1.0f, dt, threads, hook);
    hooked_stage(scheme, st->stage2, phi, st->stage1, phi_target, 0.75f, 0.25f, dt, threads, hook);
    hooked_stage(scheme, phi, phi, st->stage2, phi_target, 1.0f / 3.0f, 2.0f / 3.0f, dt, threads,
                 hook);
    break;
  default:
    /* phi = phi - dt L(phi): computed into stage1 (in and out must differ),
     * whose buffer then becomes phi's (no copy). */
    hooked_stage(scheme, st->stage1, phi, phi, phi_target, 0.0f, 1.0f, dt, threads, hook);
    lsm_grid_swap(phi, st->stage1);
    break;
  }
}

void lsm_step(lsm_stepper *st, lsm_scheme scheme, lsm_time time, lsm_grid *phi,
              const lsm_grid *phi_target, float dt, int threads) {
  lsm_step_hooked(st, scheme, time, phi, phi_target, dt, threads, NULL);
}

/* ---- norms -------------------------------------------------------------------------- */

/* Sum of squared differences of one row, in double, with 8 running partial
 * sums (lane l takes elements l, l+8, ...) combined in a fixed order: the
 * same result whatever the vector width the compiler picks (no reassociation
 * is needed to vectorise it), about 8x faster than one serial sum. */
static double row_sq_diff(const float *restrict pa, const float *restrict pb, int n) {
  double acc[8] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  int i = 0;
  for (; i + 8 <= n; i += 8)
    for (int l = 0; l < 8; ++l) {
      const double d = (double)pa[i + l] - (double)pb[i + l];
      acc[l] += d * d;
    }
  for (int l = 0; i < n; ++i, ++l) {
    const double d = (double)pa[i] - (double)pb[i];
    acc[l] += d * d;
  }
  return ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
}

double lsm_grid_diff_norm(const lsm_grid *a, const lsm_grid *b, int threads) {
  double *rows = malloc((size_t)a->ny * sizeof *rows);
  double total = 0.0;
  if (rows) {
#pragma omp parallel for num_threads(lsm_grid_threads(a, threads)) schedule(static)
    for (int j = 0; j < a->ny; ++j) rows[j] = row_sq_diff(&LSM_AT(a, 0, j), &LSM_AT(b, 0, j), a->nx);
    for (int j = 0; j < a->ny; ++j) total += rows[j];
    free(rows);
  } else {
    for (int j = 0; j < a->ny; ++j) total += row_sq_diff(&LSM_AT(a, 0, j), &LSM_AT(b, 0, j), a->nx);
  }
  return sqrt(total);
}

int lsm_grid_all_finite(const lsm_grid *g, int threads) {
  int bad = 0;
#pragma omp parallel for num_threads(lsm_grid_threads(g, threads)) schedule(static) reduction(| : bad)
  for (int j = 0; j < g->ny; ++j) {
    const float *p = &LSM_AT(g, 0, j);
    for (int i = 0; i < g->nx; ++i) bad |= !isfinite(p[i]);
  }
  return !bad;
}
