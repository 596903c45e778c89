#include "solver/pde/lsm_reinit.h"

#include "kernels/lsm_stencil.h"

void lsm_reinit_sweep_on(lsm_grid *out, const lsm_grid *in, const lsm_grid *phi0,
                         const lsm_runs *runs, int threads) {
  const float inv_dx = 1.0f / in->dx, inv_dy = 1.0f / in->dy;
  const float h = lsm_reinit_h(in->dx, in->dy), dtau = lsm_reinit_dtau(h);
  const ptrdiff_t s = in->stride, n = lsm_runs_count(in, runs);
  const float *p = in->data, *a = phi0->data;
  float *o = out->data;
#pragma omp parallel for num_threads(lsm_runs_threads(in, runs, threads)) schedule(static)
  for (ptrdiff_t q = 0; q < n; ++q) {
    const ptrdiff_t row = lsm_runs_start(in, runs, q);
    const int len = lsm_runs_length(in, runs, q);
    for (int i = 0; i < len; ++i)
      o[row + i] = lsm_reinit_at(p, a, row + i, s, inv_dx, inv_dy, h, dtau);
  }
}

void lsm_reinit_sweep(lsm_grid *out, const lsm_grid *in, const lsm_grid *phi0, int threads) {
  lsm_reinit_sweep_on(out, in, phi0, NULL, threads);
}
