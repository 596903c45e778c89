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

/* A Shu–Osher stage's value at a cell of value c and Hamiltonian H:
 * c0 u0 + c1 (c - dt H). */
LSM_FN float lsm_stage_value(float c0, float u0, float c1, float c, float dt, float H) {
  return c0 * u0 + c1 * (c - dt * H);
}

/* The 2 reach + 1 values of the row and of the column through the cell (reach <= 4). */
LSM_FN void lsm_cross_at(LSM_GLOBAL const float *in, LSM_IDX k, LSM_IDX s, int reach,
                         LSM_PRIV float *row, LSM_PRIV float *col) {
  LSM_UNROLL
  for (int d = 0; d <= 2 * reach; ++d) {
    row[d] = in[k + (d - reach)];
    col[d] = in[k + (d - reach) * s];
  }
}

/* One Shu–Osher stage at a cell, out = c0 u0 + c1 (in - dt Hhat(in)), with the
 * Godunov upwind Hamiltonian on the four one-sided differences. */
LSM_FN float lsm_stage_upwind_at(LSM_GLOBAL const float *u0, LSM_GLOBAL const float *in,
                                 LSM_GLOBAL const float *target, LSM_IDX k, LSM_IDX s,
                                 float inv_dx, float inv_dy, float c0, float c1, float dt) {
  const float c = in[k];
  const float H = lsm_upwind_hamiltonian(c - target[k], (c - in[k - 1]) * inv_dx,
                                         (in[k + 1] - c) * inv_dx, (c - in[k - s]) * inv_dy,
                                         (in[k + s] - c) * inv_dy);
  return lsm_stage_value(c0, u0[k], c1, c, dt, H);
}

/* The same with Roe-Fix: the 9-cell row and column through the cell give the
 * one-sided differences of the +-3 widened sets. */
LSM_FN float lsm_stage_roefix_at(LSM_GLOBAL const float *u0, LSM_GLOBAL const float *in,
                                 LSM_GLOBAL const float *target, LSM_IDX k, LSM_IDX s,
                                 float inv_dx, float inv_dy, float c0, float c1, float dt) {
  float row[9], col[9], xm[7], xp[7], ym[7], yp[7];
  lsm_cross_at(in, k, s, 4, row, col);
  LSM_UNROLL
  for (int q = 0; q < 7; ++q) {
    xm[q] = (row[q + 1] - row[q]) * inv_dx;
    xp[q] = (row[q + 2] - row[q + 1]) * inv_dx;
    ym[q] = (col[q + 1] - col[q]) * inv_dy;
    yp[q] = (col[q + 2] - col[q + 1]) * inv_dy;
  }
  const float H = lsm_roefix_hamiltonian(row[4] - target[k], xm, xp, ym, yp);
  return lsm_stage_value(c0, u0[k], c1, row[4], dt, H);
}

/* The same with WENO5 derivatives: the 7-cell row and column through the cell. */
LSM_FN float lsm_stage_weno5_at(LSM_GLOBAL const float *u0, LSM_GLOBAL const float *in,
                                LSM_GLOBAL const float *target, LSM_IDX k, LSM_IDX s,
                                float inv_dx, float inv_dy, float c0, float c1, float dt) {
  float row[7], col[7];
  lsm_cross_at(in, k, s, 3, row, col);
  const float H = lsm_weno5_hamiltonian(row[3] - target[k], row, col, inv_dx, inv_dy);
  return lsm_stage_value(c0, u0[k], c1, row[3], dt, H);
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
