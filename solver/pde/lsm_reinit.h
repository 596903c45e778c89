/* lsm_reinit: restore phi to a signed distance function without moving its zero
 * level (PDE reinitialisation with the Russo–Smereka subcell fix).
 *
 *   phi_tau + S(phi0) (|grad phi| - 1) = 0,   phi(tau = 0) = phi0.
 *
 * Why PDE reinitialisation rather than fast marching: it is a local stencil
 * iteration, so the same per-cell code (kernels/lsm_cell.h) runs on the C path
 * and in OpenCL; the Russo–Smereka fix keeps the interface cells anchored to
 * the subcell position of the zero level of phi0, so the front does not drift
 * (the plain scheme moves it by O(dx) per reinitialisation).  Each iteration
 * corrects a band about dtau = 0.5 min(dx, dy) wider, so `iterations` sets the
 * width of the band that becomes a distance function.
 */
#ifndef LSM_REINIT_H
#define LSM_REINIT_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"

typedef struct lsm_reinit lsm_reinit;

lsm_status lsm_reinit_create(const lsm_grid *like, lsm_reinit **out, lsm_err *err);
void lsm_reinit_destroy(lsm_reinit **reinit);

/* Runs `iterations` pseudo-time steps (forward Euler, dtau = 0.5 min(dx,dy))
 * on phi in place. */
void lsm_reinit_run(lsm_reinit *reinit, lsm_grid *phi, int iterations, int threads);

#endif
