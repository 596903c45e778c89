/* lsm_reinit: restore phi to a signed distance function without moving its zero
 * level (PDE reinitialisation with the Russo–Smereka subcell fix,
 * solver/README.md §10).
 *
 *   phi_tau + S(phi0) (|grad phi| - 1) = 0,   phi(tau = 0) = phi0.
 *
 * A local stencil iteration, so the same per-cell code (kernels/lsm_cell.h)
 * runs on the C path and in OpenCL; the subcell fix keeps the interface cells
 * anchored to the zero level of phi0.  Each pseudo-time step (dtau = 0.5
 * min(dx, dy)) corrects a band about dtau wider.  The loop over the steps is
 * lsm_fields_reinit; this is the C reference's sweep.
 */
#ifndef LSM_REINIT_H
#define LSM_REINIT_H

#include "solver/base/lsm_grid.h"
#include "solver/pde/lsm_scheme.h"

/* One pseudo-time step out <- in, phi0 the field at the start (ghosts of in and
 * phi0 filled); rows in parallel. */
void lsm_reinit_sweep(lsm_grid *out, const lsm_grid *in, const lsm_grid *phi0, int threads);
/* The same on the cells of runs (NULL: every cell). */
void lsm_reinit_sweep_on(lsm_grid *out, const lsm_grid *in, const lsm_grid *phi0,
                         const lsm_runs *runs, int threads);

#endif
