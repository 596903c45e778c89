/* lsm_stencil.h — the stencil gathers of the cell loops, written once.
 *
 * Each function reads one cell's neighbourhood from grids laid out as lsm_grid
 * (row stride s floats, the ghost ring filled; k the cell's offset, the same
 * in every grid of a pair) and applies the per-cell function of
 * kernels/lsm_cell.h.  The C loops (solver/pde/lsm_scheme.c, lsm_reinit.c)
 * and the OpenCL kernels (kernels/morph.cl) call the same functions, so both
 * backends read the same values in the same order.
 */
#ifndef LSM_STENCIL_H
#define LSM_STENCIL_H

#include "kernels/lsm_cell.h"

/* One Shu–Osher stage at a cell, out = c0 u0 + c1 (in - dt Hhat(in)), with the
 * Godunov upwind Hamiltonian on the four one-sided differences. */
LSM_FN float lsm_stage_upwind_at(LSM_GLOBAL const float *u0, LSM_GLOBAL const float *in,
                                 LSM_GLOBAL const float *target, LSM_IDX k, LSM_IDX s,
                                 float inv_dx, float inv_dy, float c0, float c1, float dt) {
  const float c = in[k];
  const float H = lsm_upwind_hamiltonian(c - target[k], (c - in[k - 1]) * inv_dx,
                                         (in[k + 1] - c) * inv_dx, (c - in[k - s]) * inv_dy,
                                         (in[k + s] - c) * inv_dy);
  return c0 * u0[k] + c1 * (c - dt * H);
}

/* The same with Roe-Fix: the 9-cell row and column through the cell, loaded
 * once, give the one-sided differences of the +-3 widened sets. */
LSM_FN float lsm_stage_roefix_at(LSM_GLOBAL const float *u0, LSM_GLOBAL const float *in,
                                 LSM_GLOBAL const float *target, LSM_IDX k, LSM_IDX s,
                                 float inv_dx, float inv_dy, float c0, float c1, float dt) {
  float row[9], col[9];
  LSM_UNROLL
  for (int d = 0; d < 9; ++d) {
    row[d] = in[k + (d - 4)];
    col[d] = in[k + (d - 4) * s];
  }
  float xm[7], xp[7], ym[7], yp[7];
  LSM_UNROLL
  for (int q = 0; q < 7; ++q) {
    xm[q] = (row[q + 1] - row[q]) * inv_dx;
    xp[q] = (row[q + 2] - row[q + 1]) * inv_dx;
    ym[q] = (col[q + 1] - col[q]) * inv_dy;
    yp[q] = (col[q + 2] - col[q + 1]) * inv_dy;
  }
  const float c = row[4];
  const float H = lsm_roefix_hamiltonian(c - target[k], xm, xp, ym, yp);
  return c0 * u0[k] + c1 * (c - dt * H);
}

/* The same with WENO5 derivatives: the 7-cell row and column through the cell. */
LSM_FN float lsm_stage_weno5_at(LSM_GLOBAL const float *u0, LSM_GLOBAL const float *in,
                                LSM_GLOBAL const float *target, LSM_IDX k, LSM_IDX s,
                                float inv_dx, float inv_dy, float c0, float c1, float dt) {
  float row[7], col[7];
  LSM_UNROLL
  for (int d = 0; d < 7; ++d) {
    row[d] = in[k + (d - 3)];
    col[d] = in[k + (d - 3) * s];
  }
  const float c = row[3];
  const float H = lsm_weno5_hamiltonian(c - target[k], row, col, inv_dx, inv_dy);
  return c0 * u0[k] + c1 * (c - dt * H);
}

/* The CFL rate of a cell (lsm_cfl_rate_of; roefix 0 or 1). */
LSM_FN float lsm_cfl_rate_at(LSM_GLOBAL const float *phi, LSM_GLOBAL const float *target,
                             LSM_IDX k, LSM_IDX s, float inv_dx, float inv_dy, int roefix) {
  const float c = phi[k];
  return lsm_cfl_rate_of(roefix, c - target[k], (c - phi[k - 1]) * inv_dx,
                         (phi[k + 1] - c) * inv_dx, (c - phi[k - s]) * inv_dy,
                         (phi[k + s] - c) * inv_dy, inv_dx, inv_dy);
}

/* One reinitialisation pseudo-time step of a cell (lsm_reinit_cell), phi0 the
 * field at the start of the reinitialisation. */
LSM_FN float lsm_reinit_at(LSM_GLOBAL const float *phi, LSM_GLOBAL const float *phi0, LSM_IDX k,
                           LSM_IDX s, float inv_dx, float inv_dy, float h, float dtau) {
  const float c = phi[k];
  return lsm_reinit_cell(c, phi0[k], phi0[k - 1], phi0[k + 1], phi0[k - s], phi0[k + s],
                         (c - phi[k - 1]) * inv_dx, (phi[k + 1] - c) * inv_dx,
                         (c - phi[k - s]) * inv_dy, (phi[k + s] - c) * inv_dy, inv_dx, inv_dy, h,
                         dtau);
}

#endif
