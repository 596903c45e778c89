#include "solver/pde/lsm_scheme.h"

#include <math.h>
#include <stdlib.h>

#include "kernels/lsm_stencil.h"

LSM_NAME_FUNCTIONS(lsm_scheme, LSM_SCHEME_LIST, lsm_scheme_name, lsm_scheme_from_name)
LSM_NAME_FUNCTIONS(lsm_time, LSM_TIME_LIST, lsm_time_name, lsm_time_from_name)

int lsm_time_stages(lsm_time time) {
  return time == LSM_TIME_RK3 ? 3 : time == LSM_TIME_RK2 ? 2 : 1;
}

/* ---- CFL ------------------------------------------------------------------------ */

float lsm_cfl_max_rate_on(const lsm_grid *phi, const lsm_grid *phi_target, lsm_scheme scheme,
                          const lsm_runs *runs, int threads) {
  const int roefix = scheme == LSM_SCHEME_ROEFIX;
  const float inv_dx = 1.0f / phi->dx, inv_dy = 1.0f / phi->dy;
  const ptrdiff_t s = phi->stride, n = lsm_runs_count(phi, runs);
  const float *p = phi->data, *t = phi_target->data;
  float rate = 0.0f;
#pragma omp parallel for num_threads(lsm_runs_threads(phi, runs, threads)) schedule(static) reduction(max : rate)
  for (ptrdiff_t q = 0; q < n; ++q) {
    const ptrdiff_t row = lsm_runs_start(phi, runs, q);
    const int len = lsm_runs_length(phi, runs, q);
    float row_rate = 0.0f;
    for (int i = 0; i < len; ++i)
      row_rate = lsm_maxf(row_rate, lsm_cfl_rate_at(p, t, row + i, s, inv_dx, inv_dy, roefix));
    rate = lsm_maxf(rate, row_rate);
  }
  return rate;
}

float lsm_cfl_max_rate(const lsm_grid *phi, const lsm_grid *phi_target, lsm_scheme scheme,
                       int threads) {
  return lsm_cfl_max_rate_on(phi, phi_target, scheme, NULL, threads);
}

double lsm_cfl_step(double cfl, float rate) { return rate > 0.0f ? cfl / (double)rate : INFINITY; }

void lsm_cfl_dt(lsm_grid *phi, const lsm_grid *phi_target, lsm_scheme scheme, double cfl,
                int threads, double *dt) {
  lsm_grid_fill_ghosts(phi);
  *dt = lsm_cfl_step(cfl, lsm_cfl_max_rate(phi, phi_target, scheme, threads));
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

/* A sweep of one stage over the cells of runs (NULL: the interior), the cell's value from
 * `cell` (kernels/lsm_stencil.h); runs (rows) in parallel. */
#define LSM_STAGE_SWEEP(name, cell)                                                          \
  static void name(lsm_grid *out, const lsm_grid *u0, const lsm_grid *in,                   \
                   const lsm_grid *phi_target, float c0, float c1, float dt,                \
                   const lsm_runs *runs, int threads) {                                     \
    const float inv_dx = 1.0f / in->dx, inv_dy = 1.0f / in->dy;                              \
    const ptrdiff_t s = in->stride, n = lsm_runs_count(in, runs);                                 \
    const float *u = u0->data, *p = in->data, *t = phi_target->data;                         \
    float *o = out->data;                                                                    \
    _Pragma("omp parallel for num_threads(lsm_runs_threads(in, runs, threads)) schedule(static)") \
    for (ptrdiff_t q = 0; q < n; ++q) {                                                      \
      const ptrdiff_t row = lsm_runs_start(in, runs, q);                                          \
      const int len = lsm_runs_length(in, runs, q);                                               \
      for (int i = 0; i < len; ++i)                                                          \
        o[row + i] = cell(u, p, t, row + i, s, inv_dx, inv_dy, c0, c1, dt);                  \
    }                                                                                        \
  }

LSM_HOT_CLONES LSM_STAGE_SWEEP(stage_upwind, lsm_stage_upwind_at)
LSM_STAGE_SWEEP(stage_roefix, lsm_stage_roefix_at)
LSM_HOT_CLONES LSM_STAGE_SWEEP(stage_weno5, lsm_stage_weno5_at)

void lsm_scheme_stage_on(lsm_scheme scheme, lsm_grid *out, const lsm_grid *u0, const lsm_grid *in,
                         const lsm_grid *phi_target, float c0, float c1, float dt,
                         const lsm_runs *runs, int threads) {
  switch (scheme) {
  case LSM_SCHEME_ROEFIX:
    stage_roefix(out, u0, in, phi_target, c0, c1, dt, runs, threads);
    break;
  case LSM_SCHEME_WENO5:
    stage_weno5(out, u0, in, phi_target, c0, c1, dt, runs, threads);
    break;
  default:
    stage_upwind(out, u0, in, phi_target, c0, c1, dt, runs, threads);
    break;
  }
}

void lsm_scheme_stage(lsm_scheme scheme, lsm_grid *out, const lsm_grid *u0, lsm_grid *in,
                      const lsm_grid *phi_target, float c0, float c1, float dt, int threads) {
  lsm_grid_fill_ghosts(in);
  lsm_scheme_stage_on(scheme, out, u0, in, phi_target, c0, c1, dt, NULL, threads);
}

/* ---- norms -------------------------------------------------------------------------- */

/* Sum of squared differences of one row, in double, with 8 running partial
 * sums (lane l takes elements l, l+8, ...) combined in a fixed order: the
 * same result whatever the vector width the compiler picks (no reassociation
 * is needed to vectorise it), and vectorised, unlike one serial sum. */
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

double lsm_grid_diff_norm_on(const lsm_grid *a, const lsm_grid *b, const lsm_runs *runs,
                             int threads) {
  const ptrdiff_t n = lsm_runs_count(a, runs);
  double *rows = malloc((size_t)(n > 0 ? n : 1) * sizeof *rows);
  double total = 0.0;
  if (rows) {
#pragma omp parallel for num_threads(lsm_runs_threads(a, runs, threads)) schedule(static)
    for (ptrdiff_t q = 0; q < n; ++q)
      rows[q] = row_sq_diff(a->data + lsm_runs_start(a, runs, q), b->data + lsm_runs_start(a, runs, q),
                            lsm_runs_length(a, runs, q));
    for (ptrdiff_t q = 0; q < n; ++q) total += rows[q];
    free(rows);
  } else {
    for (ptrdiff_t q = 0; q < n; ++q)
      total += row_sq_diff(a->data + lsm_runs_start(a, runs, q), b->data + lsm_runs_start(a, runs, q),
                           lsm_runs_length(a, runs, q));
  }
  return sqrt(total);
}

double lsm_grid_diff_norm(const lsm_grid *a, const lsm_grid *b, int threads) {
  return lsm_grid_diff_norm_on(a, b, NULL, threads);
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
