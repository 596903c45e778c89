/* lsm_cell.h — per-cell numerics of lsmorph, written once.
 *
 * Pure functions of plain values: no memory access patterns, no I/O, no
 * globals.  The C backend and the OpenCL kernels both include this file
 * (through kernels/lsm_stencil.h), so both run the same arithmetic.  Floats
 * throughout; lengths in physical units.  The derivations: solver/README.md.
 *
 * Notation: dxm = (phi[i] - phi[i-1]) / dx, dxp = (phi[i+1] - phi[i]) / dx
 * (backward and forward differences), dym, dyp along y.  The morph equation
 * phi_t + F |grad phi| = 0, F = phi - phi_target, has the Hamiltonian
 * H(p, q) = F sqrt(p^2 + q^2), H1 = F p / |(p, q)|, H2 = F q / |(p, q)|.
 */
#ifndef LSM_CELL_H
#define LSM_CELL_H

#ifdef __OPENCL_VERSION__
#define LSM_FN inline
#define LSM_SQRT(x) sqrt(x)
#define LSM_FABS(x) fabs(x)
#define LSM_PRIV __private
#define LSM_GLOBAL __global
#define LSM_IDX int
#define LSM_UNROLL _Pragma("unroll")
#else
#include <math.h>
#include <stddef.h>
#define LSM_FN static inline
#define LSM_SQRT(x) sqrtf(x)
#define LSM_FABS(x) fabsf(x)
#define LSM_PRIV
#define LSM_GLOBAL
#define LSM_IDX ptrdiff_t /* grid offsets (OpenCL: int, the host keeps grids below 2^31 floats) */
#define LSM_UNROLL
#endif

/* Branch-free max/min that compilers vectorise (no NaN semantics needed:
 * callers never pass NaN; a NaN in phi is caught by the driver). */
LSM_FN float lsm_maxf(float a, float b) { return a > b ? a : b; }
LSM_FN float lsm_minf(float a, float b) { return a < b ? a : b; }
/* A cell outside the narrow band (solver/pde/lsm_band.h): phi_target + amplitude g, g the
 * relaxation of a cell where phi is a distance over the steps taken. */
LSM_FN float lsm_relaxed(float target, float amplitude, float g) { return target + amplitude * g; }
/* One strictly positive and the other strictly negative. */
LSM_FN int lsm_opposite(float a, float b) { return (a > 0.0f && b < 0.0f) || (a < 0.0f && b > 0.0f); }

/* ---- Godunov upwind (Rouy & Tourin; solver/README.md §4) -------------------------
 * F |grad phi| with, per axis, the larger of the two upwind one-sided slopes:
 *   F > 0: |grad phi|^2 ~ max(max(dxm,0)^2, min(dxp,0)^2) + (the same in y)
 *   F < 0: |grad phi|^2 ~ max(min(dxm,0)^2, max(dxp,0)^2) + (the same in y)
 * The max (not Osher & Sethian's sum) keeps the update a convex combination
 * of upwind values under the CFL step: monotone. */
LSM_FN float lsm_upwind_hamiltonian(float F, float dxm, float dxp, float dym, float dyp) {
  float ax = lsm_maxf(dxm, 0.0f), bx = lsm_minf(dxp, 0.0f);
  float ay = lsm_maxf(dym, 0.0f), by = lsm_minf(dyp, 0.0f);
  float cx = lsm_minf(dxm, 0.0f), ex = lsm_maxf(dxp, 0.0f);
  float cy = lsm_minf(dym, 0.0f), ey = lsm_maxf(dyp, 0.0f);
  /* max(u, v) = -min(-u, -v) exactly; the y terms are written so only that
   * they do not mirror the x terms, which LLVM would pack into 2-wide vectors,
   * leaving PoCL's work-group vectoriser the kernel scalar. */
  float grad2_pos = lsm_maxf(ax * ax, bx * bx) - lsm_minf(-(ay * ay), -(by * by));
  float grad2_neg = lsm_maxf(cx * cx, ex * ex) - lsm_minf(-(cy * cy), -(ey * ey));
  /* One square root of the chosen side (the same value as choosing between
   * two roots: the root is correctly rounded). */
  return F * LSM_SQRT(F > 0.0f ? grad2_pos : grad2_neg);
}

/* ---- CFL rate (solver/README.md §4): dt = cfl / max over the grid -----------------
 * Upwind: the largest over the four one-sided pairs (p in {dxm,dxp}, q in
 * {dym,dyp}) of |H1|/dx + |H2|/dy = |F| (|p|/dx + |q|/dy) / |(p,q)|, the
 * monotone bound of the update above for cfl <= 1.  Roe-Fix: |F| (1/dx +
 * 1/dy), which bounds its Lax–Friedrichs dissipation. */
LSM_FN float lsm_cfl_pair(float p, float q, float inv_dx, float inv_dy) {
  float g = LSM_SQRT(p * p + q * q);
  return g > 0.0f ? (LSM_FABS(p) * inv_dx + LSM_FABS(q) * inv_dy) / g : 0.0f;
}
LSM_FN float lsm_cfl_rate(float F, float dxm, float dxp, float dym, float dyp, float inv_dx,
                          float inv_dy) {
  float r = lsm_maxf(lsm_maxf(lsm_cfl_pair(dxm, dym, inv_dx, inv_dy),
                              lsm_cfl_pair(dxm, dyp, inv_dx, inv_dy)),
                     lsm_maxf(lsm_cfl_pair(dxp, dym, inv_dx, inv_dy),
                              lsm_cfl_pair(dxp, dyp, inv_dx, inv_dy)));
  return LSM_FABS(F) * r;
}

/* The largest rate a cell where |phi - phi_target| = |F| can take whatever its gradient:
 * upwind (and WENO5) |F| sqrt(1/dx^2 + 1/dy^2), written so no square overflows; Roe-Fix
 * |F| (1/dx + 1/dy). */
LSM_FN float lsm_cfl_rate_bound(int roefix, float F, float inv_dx, float inv_dy) {
  if (roefix) return LSM_FABS(F) * (inv_dx + inv_dy);
  const float a = lsm_maxf(inv_dx, inv_dy), t = lsm_minf(inv_dx, inv_dy) / a;
  return LSM_FABS(F) * a * LSM_SQRT(1.0f + t * t);
}

/* The rate of a scheme: roefix 0 (upwind) or 1 (Roe-Fix).  A cell flat in all
 * four differences (an empty slice's constant value) moves nothing: rate 0,
 * however large F is there; flat along one axis only is not enough, since it
 * does not stay flat. */
LSM_FN float lsm_cfl_rate_of(int roefix, float F, float dxm, float dxp, float dym, float dyp,
                             float inv_dx, float inv_dy) {
  const int flat = dxm == 0.0f && dxp == 0.0f && dym == 0.0f && dyp == 0.0f;
  if (!roefix) {
    const float rate = lsm_cfl_rate(F, dxm, dxp, dym, dyp, inv_dx, inv_dy);
    if (inv_dx == inv_dy || flat) return rate;
    /* Unequal spacing: the pairwise rate can grow by up to max(dx,dy)/min(dx,dy)
     * once the front turns, and the step is fixed from phi_0: the bound over
     * all directions. */
    return lsm_maxf(rate, lsm_cfl_rate_bound(0, F, inv_dx, inv_dy));
  }
  return flat ? 0.0f : lsm_cfl_rate_bound(1, F, inv_dx, inv_dy);
}

/* ---- Roe-Fix (Osher & Fedkiw ch. 5.3; solver/README.md §4) -------------------------
 * Inputs are the one-sided differences on a +-3 cell stencil:
 *   xm[k] = phi_x^- at column i-3+k, xp[k] = phi_x^+ at column i-3+k (k = 0..6),
 *   ym[k], yp[k] likewise along the column; index 3 is the cell itself.
 * I_x = {xm[3], xp[3]}, I_x_new = {xm[k], xp[k] : k = 0..6} (same for y).
 *   1. If H1 and H2 each keep one sign over I_x x I_y: pure upwind, no dissipation.
 *   2. Otherwise, with H1 over I_x x I_y_new and H2 over I_x_new x I_y:
 *      H1 one-signed, H2 not: phi_x* upwind, phi_y* = mean, alpha_y = max|H2|;
 *      H2 one-signed, H1 not: symmetric;
 *      neither: both means, alpha_x = max|H1|, alpha_y = max|H2|.
 *   Hhat = H(phi_x*, phi_y*) - alpha_x (xp - xm)/2 - alpha_y (yp - ym)/2.
 * "One sign" allows zeros (all >= 0 or all <= 0). */

/* Sign flags of H1 = F p / |(p,q)| over p in P (np values) x q in Q (nq values),
 * and the largest |H1|.  Works for H2 too with the roles of p and q swapped. */
LSM_FN void lsm_roefix_scan(float F, const LSM_PRIV float *P, int np, const LSM_PRIV float *Q,
                            int nq, LSM_PRIV int *has_pos, LSM_PRIV int *has_neg,
                            LSM_PRIV float *max_abs) {
  int pos = 0, neg = 0;
  float m = 0.0f;
  for (int a = 0; a < np; ++a) {
    for (int b = 0; b < nq; ++b) {
      float g = LSM_SQRT(P[a] * P[a] + Q[b] * Q[b]);
      float h = g > 0.0f ? F * P[a] / g : 0.0f;
      pos |= h > 0.0f;
      neg |= h < 0.0f;
      m = lsm_maxf(m, LSM_FABS(h));
    }
  }
  *has_pos = pos;
  *has_neg = neg;
  *max_abs = m;
}

/* Which flags (reason codes) the Roe-Fix step took; tests check each branch. */
enum {
  LSM_ROEFIX_UPWIND = 0,      /* both one-signed on the narrow sets */
  LSM_ROEFIX_LLF_Y = 1,       /* H1 one-signed, H2 not (dissipation in y) */
  LSM_ROEFIX_LLF_X = 2,       /* H2 one-signed, H1 not (dissipation in x) */
  LSM_ROEFIX_LLF_XY = 3       /* neither one-signed */
};

LSM_FN float lsm_roefix_hamiltonian_ex(float F, const LSM_PRIV float *xm, const LSM_PRIV float *xp,
                                       const LSM_PRIV float *ym, const LSM_PRIV float *yp,
                                       LSM_PRIV int *branch) {
  float Ix[2] = {xm[3], xp[3]}, Iy[2] = {ym[3], yp[3]};
  int p1, n1, p2, n2;
  float m1, m2;
  lsm_roefix_scan(F, Ix, 2, Iy, 2, &p1, &n1, &m1);
  lsm_roefix_scan(F, Iy, 2, Ix, 2, &p2, &n2, &m2);
  float px, py, alpha_x = 0.0f, alpha_y = 0.0f;
  if (!(p1 && n1) && !(p2 && n2)) {
    px = p1 ? xm[3] : xp[3];
    py = p2 ? ym[3] : yp[3];
    *branch = LSM_ROEFIX_UPWIND;
  } else {
    float Ixw[14], Iyw[14];
    for (int k = 0; k < 7; ++k) {
      Ixw[2 * k] = xm[k];
      Ixw[2 * k + 1] = xp[k];
      Iyw[2 * k] = ym[k];
      Iyw[2 * k + 1] = yp[k];
    }
    lsm_roefix_scan(F, Ix, 2, Iyw, 14, &p1, &n1, &m1); /* H1 over I_x x I_y_new */
    lsm_roefix_scan(F, Iy, 2, Ixw, 14, &p2, &n2, &m2); /* H2 over I_x_new x I_y */
    int one1 = !(p1 && n1), one2 = !(p2 && n2);
    if (one1 && !one2) {
      px = p1 ? xm[3] : xp[3];
      py = 0.5f * (ym[3] + yp[3]);
      alpha_y = m2;
      *branch = LSM_ROEFIX_LLF_Y;
    } else if (one2 && !one1) {
      px = 0.5f * (xm[3] + xp[3]);
      py = p2 ? ym[3] : yp[3];
      alpha_x = m1;
      *branch = LSM_ROEFIX_LLF_X;
    } else if (!one1 && !one2) {
      px = 0.5f * (xm[3] + xp[3]);
      py = 0.5f * (ym[3] + yp[3]);
      alpha_x = m1;
      alpha_y = m2;
      *branch = LSM_ROEFIX_LLF_XY;
    } else {
      /* Both one-signed once widened: only possible through zero gradients;
       * the narrow-set choice stands. */
      px = p1 ? xm[3] : xp[3];
      py = p2 ? ym[3] : yp[3];
      *branch = LSM_ROEFIX_UPWIND;
    }
  }
  return F * LSM_SQRT(px * px + py * py) - alpha_x * 0.5f * (xp[3] - xm[3]) -
         alpha_y * 0.5f * (yp[3] - ym[3]);
}

LSM_FN float lsm_roefix_hamiltonian(float F, const LSM_PRIV float *xm, const LSM_PRIV float *xp,
                                    const LSM_PRIV float *ym, const LSM_PRIV float *yp) {
  int branch;
  return lsm_roefix_hamiltonian_ex(F, xm, xp, ym, yp, &branch);
}

/* ---- Fifth-order HJ-WENO (Jiang & Peng 2000; solver/README.md §4) -------------------
 * The one-sided derivative phi_x^- at cell i from the backward differences
 * v1..v5 = D^- phi at i-2 .. i+2 (phi_x^+: the forward ones at i+2 .. i-2):
 * three third-order candidates weighted by their smoothness, the ideal weights
 * 1/10, 6/10, 3/10 where phi is smooth.  The indicators are taken of
 * v / max |v_k| with eps = 12e-6, so the weights do not depend on the scale of
 * phi and nothing overflows in float; all-zero differences give 0. */
LSM_FN float lsm_weno5(float v1, float v2, float v3, float v4, float v5) {
  float a = lsm_maxf(lsm_maxf(lsm_maxf(LSM_FABS(v1), LSM_FABS(v2)),
                                    lsm_maxf(LSM_FABS(v3), LSM_FABS(v4))),
                           LSM_FABS(v5));
  /* all-zero differences: w = 0 and every candidate 0 (a select, not a
   * branch, so that the cell loop vectorises) */
  a = lsm_maxf(a, 1.17549435e-38f);
  const float w1 = v1 / a, w2 = v2 / a, w3 = v3 / a, w4 = v4 / a, w5 = v5 / a;
  const float q1 = w1 - 2.0f * w2 + w3, r1 = w1 - 4.0f * w2 + 3.0f * w3;
  const float q2 = w2 - 2.0f * w3 + w4, r2 = w2 - w4;
  const float q3 = w3 - 2.0f * w4 + w5, r3 = 3.0f * w3 - 4.0f * w4 + w5;
  const float e1 = 12e-6f + (13.0f * (q1 * q1) + 3.0f * (r1 * r1));
  const float e2 = 12e-6f + (13.0f * (q2 * q2) + 3.0f * (r2 * r2));
  const float e3 = 12e-6f + (13.0f * (q3 * q3) + 3.0f * (r3 * r3));
  const float a1 = 1.0f / (e1 * e1), a2 = 6.0f / (e2 * e2), a3 = 3.0f / (e3 * e3);
  const float p1 = (2.0f * v1 - 7.0f * v2 + 11.0f * v3) / 6.0f;
  const float p2 = (-v2 + 5.0f * v3 + 2.0f * v4) / 6.0f;
  const float p3 = (2.0f * v3 + 5.0f * v4 - v5) / 6.0f;
  /* normalised weights first: alpha_k p_k could pass FLT_MAX for large phi */
  const float norm = 1.0f / (a1 + a2 + a3);
  return (a1 * norm) * p1 + (a2 * norm) * p2 + (a3 * norm) * p3;
}

/* The WENO5 Hamiltonian of a cell from the seven values of its row and of its
 * column centred on it (row[3] = col[3] = phi at the cell): the Godunov
 * Hamiltonian of lsm_upwind_hamiltonian on the WENO one-sided derivatives (as
 * LSMLIB's and OpenVDB's HJWENO5).  Not monotone. */
LSM_FN float lsm_weno5_hamiltonian(float F, const LSM_PRIV float *row, const LSM_PRIV float *col,
                                   float inv_dx, float inv_dy) {
  float dx[6], dy[6];
  for (int k = 0; k < 6; ++k) {
    dx[k] = (row[k + 1] - row[k]) * inv_dx;
    dy[k] = (col[k + 1] - col[k]) * inv_dy;
  }
  return lsm_upwind_hamiltonian(F, lsm_weno5(dx[0], dx[1], dx[2], dx[3], dx[4]),
                                lsm_weno5(dx[5], dx[4], dx[3], dx[2], dx[1]),
                                lsm_weno5(dy[0], dy[1], dy[2], dy[3], dy[4]),
                                lsm_weno5(dy[5], dy[4], dy[3], dy[2], dy[1]));
}

/* ---- Reinitialisation (Russo & Smereka 2000; solver/README.md §10) -----------------
 * phi_tau + S(phi0) (|grad phi| - 1) = 0 with the subcell fix: cells whose sign
 * differs from a 4-neighbour's in phi0 keep the interface where phi0 put it. */

/* Godunov |grad phi| for the eikonal part, upwind by the sign of phi0. */
LSM_FN float lsm_godunov_grad(float s, float dxm, float dxp, float dym, float dyp) {
  float gx, gy;
  if (s > 0.0f) {
    float a = lsm_maxf(dxm, 0.0f), b = lsm_minf(dxp, 0.0f);
    float c = lsm_maxf(dym, 0.0f), d = lsm_minf(dyp, 0.0f);
    gx = lsm_maxf(a * a, b * b);
    gy = lsm_maxf(c * c, d * d);
  } else {
    float a = lsm_minf(dxm, 0.0f), b = lsm_maxf(dxp, 0.0f);
    float c = lsm_minf(dym, 0.0f), d = lsm_maxf(dyp, 0.0f);
    gx = lsm_maxf(a * a, b * b);
    gy = lsm_maxf(c * c, d * d);
  }
  return LSM_SQRT(gx + gy);
}

/* The pseudo-time step: dtau = h / 2, h = min(dx, dy). */
LSM_FN float lsm_reinit_h(float dx, float dy) { return dx < dy ? dx : dy; }
LSM_FN float lsm_reinit_dtau(float h) { return 0.5f * h; }

/* One explicit pseudo-time step of size dtau for a cell.
 *   phi, phi0           the cell's current and initial values
 *   l0, r0, d0, u0      phi0 at the 4 neighbours (x-1, x+1, y-1, y+1)
 *   dxm..dyp            one-sided differences of the current phi
 * Far cells: Godunov.  Interface cells (sign change in phi0): Russo–Smereka
 *   phi <- phi - (dtau/h) (sgn(phi0) |phi| - D),  D = phi0 / |grad phi0|_est,
 * |grad phi0|_est = max(central gradient, one-sided slopes, eps). */
LSM_FN float lsm_reinit_cell(float phi, float phi0, float l0, float r0, float d0, float u0,
                             float dxm, float dxp, float dym, float dyp, float inv_dx,
                             float inv_dy, float h, float dtau) {
  /* signs compared, not multiplied: the product underflows at tiny pixel sizes */
  int interface = lsm_opposite(phi0, l0) | lsm_opposite(phi0, r0) | lsm_opposite(phi0, d0) |
                  lsm_opposite(phi0, u0) | (phi0 == 0.0f);
  float s = phi0 > 0.0f ? 1.0f : (phi0 < 0.0f ? -1.0f : 0.0f);
  if (interface) {
    float cx = 0.5f * (r0 - l0) * inv_dx, cy = 0.5f * (u0 - d0) * inv_dy;
    float g = LSM_SQRT(cx * cx + cy * cy);
    g = lsm_maxf(g, LSM_FABS(r0 - phi0) * inv_dx);
    g = lsm_maxf(g, LSM_FABS(phi0 - l0) * inv_dx);
    g = lsm_maxf(g, LSM_FABS(u0 - phi0) * inv_dy);
    g = lsm_maxf(g, LSM_FABS(phi0 - d0) * inv_dy);
    g = lsm_maxf(g, 1e-6f);
    float D = phi0 / g;
    return phi - (dtau / h) * (s * LSM_FABS(phi) - D);
  }
  return phi - dtau * s * (lsm_godunov_grad(s, dxm, dxp, dym, dyp) - 1.0f);
}

#endif
