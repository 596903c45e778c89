#include "solver/pde/lsm_reinit.h"

#include <stdlib.h>

#include "kernels/lsm_stencil.h"

struct lsm_reinit {
  lsm_grid *phi0; /* the field at the start: fixes signs and the interface */
  lsm_grid *next; /* the iterate being written */
};

lsm_status lsm_reinit_create(const lsm_grid *like, lsm_reinit **out, lsm_err *err) {
  *out = NULL;
  lsm_reinit *r = calloc(1, sizeof *r);
  if (!r) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate reinitialisation");
  lsm_status status = lsm_grid_create(like->nx, like->ny, like->dx, like->dy, &r->phi0, err);
  if (status == LSM_OK)
    status = lsm_grid_create(like->nx, like->ny, like->dx, like->dy, &r->next, err);
  if (status != LSM_OK) {
    lsm_reinit_destroy(&r);
    return status;
  }
  *out = r;
  return LSM_OK;
}

void lsm_reinit_destroy(lsm_reinit **reinit) {
  if (!reinit || !*reinit) return;
  lsm_grid_destroy(&(*reinit)->phi0);
  lsm_grid_destroy(&(*reinit)->next);
  free(*reinit);
  *reinit = NULL;
}

void lsm_reinit_run(lsm_reinit *r, lsm_grid *phi, int iterations, int threads) {
  if (iterations <= 0) return;
  lsm_grid_fill_ghosts(phi);
  lsm_grid_copy(r->phi0, phi);
  const float inv_dx = 1.0f / phi->dx, inv_dy = 1.0f / phi->dy;
  const float h = phi->dx < phi->dy ? phi->dx : phi->dy;
  const float dtau = 0.5f * h;
  const lsm_grid *p0 = r->phi0;
  for (int it = 0; it < iterations; ++it) {
    lsm_grid_fill_ghosts(phi);
    lsm_grid *nx = r->next;
    const ptrdiff_t s = phi->stride;
    const float *p = phi->data, *a = p0->data;
    float *o = nx->data;
#pragma omp parallel for num_threads(lsm_grid_threads(phi, threads)) schedule(static)
    for (int j = 0; j < phi->ny; ++j) {
      const ptrdiff_t row = (ptrdiff_t)j * s;
      for (int i = 0; i < phi->nx; ++i)
        o[row + i] = lsm_reinit_at(p, a, row + i, s, inv_dx, inv_dy, h, dtau);
    }
    lsm_grid_copy(phi, nx);
  }
  lsm_grid_fill_ghosts(phi);
}
