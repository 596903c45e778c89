#include "solver/pde/lsm_reinit.h"

#include "kernels/lsm_stencil.h"

void lsm_reinit_sweep(lsm_grid *out, const lsm_grid *in, const lsm_grid *phi0, int threads) {
  const float inv_dx = 1.0f / in->dx, inv_dy = 1.0f / in->dy;
  const float h = lsm_reinit_h(in->dx, in->dy), dtau = lsm_reinit_dtau(h);
  const ptrdiff_t s = in->stride;
  const float *p = in->data, *a = phi0->data;
  float *o = out->data;
#pragma omp parallel for num_threads(lsm_grid_threads(in, threads)) schedule(static)
  for (int j = 0; j < in->ny; ++j) {
    const ptrdiff_t row = (ptrdiff_t)j * s;
    for (int i = 0; i < in->nx; ++i)
      o[row + i] = lsm_reinit_at(p, a, row + i, s, inv_dx, inv_dy, h, dtau);
  }
}
