/* morph.cl — the OpenCL kernels of lsmorph (host code: kernels/lsm_backend_cl.c).
 *
 * One job per kernel, composed by the host in the same order as the C path
 * (solver/lsm_scheme.c, solver/lsm_reinit.c):
 *   lsm_fill_ghosts    zero-gradient extension into the ghost ring
 *   lsm_stage_upwind   out = c0 u0 + c1 (in - dt Hhat(in)), Godunov upwind
 *   lsm_stage_roefix   the same with the Roe-Fix Hamiltonian (+-3 widened sets)
 *   lsm_cfl_partial    max of lsm_cfl_rate per work-group
 *   lsm_residual_partial  sum of (phi - phi_target)^2 per work-group
 *   lsm_reinit_step    one Russo–Smereka pseudo-time step
 * The per-cell arithmetic is kernels/lsm_cell.h, shared with the C path: the
 * build embeds this file with that header spliced in at the #include below
 * (build/gen/lsm_kernels.h), so the program needs no include path at run time.
 *
 * Buffers hold whole grids, ghosts included, laid out as lsm_grid: row stride
 * `stride` = nx + 2 LSM_GHOST floats, cell (i, j) of the interior at
 * (j + LSM_GHOST) * stride + i + LSM_GHOST.  LSM_GHOST comes from the build
 * options (-DLSM_GHOST=4, the value in solver/lsm_grid.h).
 *
 * NDRanges are 2D over the interior (dimension 0 = column i, 1 = row j),
 * rounded up to whole work-groups: every kernel bounds-checks.  Offsets are
 * int (the host keeps whole grids below 2^31 floats).
 *
 * No contraction into fused multiply-adds: the C path (ISO C17, GCC's default
 * -ffp-contract=off there) rounds every product, so must we. */
#pragma OPENCL FP_CONTRACT OFF

#include "lsm_cell.h"

#ifndef LSM_GHOST
#error "build with -DLSM_GHOST=<ghost width of solver/lsm_grid.h>"
#endif

/* Offset of interior cell (i, j).  int arithmetic: the host refuses grids of
 * 2^31 floats or more, and 64-bit offsets keep PoCL from vectorising. */
inline int lsm_cl_at(int i, int j, int stride) {
  return (j + LSM_GHOST) * stride + i + LSM_GHOST;
}

/* Cell kernels (stages, reinitialisation) run on work-groups (LX, LY) over
 * nx x ny rounded up to whole groups; the host uses row segments, LY = 1.
 * Groups wholly inside the interior (all but the last of each row of groups)
 * take a path without per-item checks, which CPU implementations (PoCL)
 * vectorise across work-items (the checked path runs about 2x slower there);
 * the others check i < nx and j < ny. */
inline int lsm_cl_group_inside(int nx, int ny) {
  return (int)((get_group_id(0) + 1) * get_local_size(0)) <= nx &&
         (int)((get_group_id(1) + 1) * get_local_size(1)) <= ny;
}

/* ---- ghost fill ------------------------------------------------------------------
 * lsm_grid_fill_ghosts extends each interior row sideways, then copies the
 * first and last full-width rows (ghost columns included) up and down.  Cell
 * by cell that is: ghost (i, j) = interior (clamp(i), clamp(j)), which is what
 * one work-item per ghost cell writes here (reads interior cells only, so the
 * work-items are independent).  1D range over the ring:
 *   [0, 2 G ny)                  left and right ghosts of the interior rows
 *   [2 G ny, 2 G ny + 2 G stride) the G rows above and below, full width. */
__kernel void lsm_fill_ghosts(__global float *g, int nx, int ny, int stride) {
  const int G = LSM_GHOST;
  int k = (int)get_global_id(0);
  const int side = 2 * G * ny, ring = side + 2 * G * stride;
  int i, j;
  if (k < side) {
    j = k / (2 * G);
    int r = k - j * 2 * G;
    i = r < G ? -1 - r : nx + (r - G);
  } else if (k < ring) {
    k -= side;
    int row = k / stride;
    i = k - row * stride - G;
    j = row < G ? -1 - row : ny + (row - G);
  } else {
    return;
  }
  g[lsm_cl_at(i, j, stride)] = g[lsm_cl_at(clamp(i, 0, nx - 1), clamp(j, 0, ny - 1), stride)];
}

/* ---- one Shu–Osher stage: out = c0 u0 + c1 (in - dt Hhat(in)) ----------------------
 * out may be u0 (the last stage of RK2/RK3), never in; in's ghosts are filled. */
inline float lsm_cl_upwind(__global const float *u0, __global const float *in,
                           __global const float *target, int k, int stride, float inv_dx,
                           float inv_dy, float c0, float c1, float dt) {
  const float c = in[k];
  const float H = lsm_upwind_hamiltonian(c - target[k], (c - in[k - 1]) * inv_dx,
                                         (in[k + 1] - c) * inv_dx, (c - in[k - stride]) * inv_dy,
                                         (in[k + stride] - c) * inv_dy);
  return c0 * u0[k] + c1 * (c - dt * H);
}

/* The 9-cell row and column through the cell, loaded once; the one-sided
 * differences are formed from them exactly as stage_roefix does. */
inline float lsm_cl_roefix(__global const float *u0, __global const float *in,
                           __global const float *target, int k, int stride, float inv_dx,
                           float inv_dy, float c0, float c1, float dt) {
  float row[9], col[9];
#pragma unroll
  for (int d = 0; d < 9; ++d) {
    row[d] = in[k + (d - 4)];
    col[d] = in[k + (d - 4) * stride];
  }
  float xm[7], xp[7], ym[7], yp[7];
#pragma unroll
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

#define LSM_CL_STAGE_KERNEL(name, cell)                                                    \
  __kernel void name(__global float *out, __global const float *u0,                        \
                     __global const float *in, __global const float *target, int nx, int ny, \
                     int stride, float inv_dx, float inv_dy, float c0, float c1, float dt) { \
    const int i = (int)get_global_id(0), j = (int)get_global_id(1);                        \
    const int k = lsm_cl_at(i, j, stride);                                                 \
    if (lsm_cl_group_inside(nx, ny))                                                       \
      out[k] = cell(u0, in, target, k, stride, inv_dx, inv_dy, c0, c1, dt);                \
    else if (i < nx && j < ny)                                                             \
      out[k] = cell(u0, in, target, k, stride, inv_dx, inv_dy, c0, c1, dt);                \
  }

LSM_CL_STAGE_KERNEL(lsm_stage_upwind, lsm_cl_upwind)
LSM_CL_STAGE_KERNEL(lsm_stage_roefix, lsm_cl_roefix)

/* ---- reinitialisation: one pseudo-time step, next <- phi (phi, phi0 ghosts filled) ---- */
inline float lsm_cl_reinit(__global const float *phi, __global const float *phi0, int k,
                           int stride, float inv_dx, float inv_dy, float h, float dtau) {
  const float c = phi[k];
  return lsm_reinit_cell(c, phi0[k], phi0[k - 1], phi0[k + 1], phi0[k - stride],
                         phi0[k + stride], (c - phi[k - 1]) * inv_dx, (phi[k + 1] - c) * inv_dx,
                         (c - phi[k - stride]) * inv_dy, (phi[k + stride] - c) * inv_dy, inv_dx,
                         inv_dy, h, dtau);
}

__kernel void lsm_reinit_step(__global float *next, __global const float *phi,
                              __global const float *phi0, int nx, int ny, int stride,
                              float inv_dx, float inv_dy, float h, float dtau) {
  const int i = (int)get_global_id(0), j = (int)get_global_id(1);
  const int k = lsm_cl_at(i, j, stride);
  if (lsm_cl_group_inside(nx, ny))
    next[k] = lsm_cl_reinit(phi, phi0, k, stride, inv_dx, inv_dy, h, dtau);
  else if (i < nx && j < ny)
    next[k] = lsm_cl_reinit(phi, phi0, k, stride, inv_dx, inv_dy, h, dtau);
}

/* ---- reductions --------------------------------------------------------------------
 * Work-item (r, j0) covers the run of `run` cells of columns [r run, r run + run)
 * in rows j0, j0 + global_size(1), ...: run = 1 on GPUs (neighbouring
 * work-items read neighbouring cells), a longer run on CPUs (a plain inner
 * loop).  Each work-group combines its work-items' values (LSM_CL_COMBINE) and
 * writes partial[group_id(1) * num_groups(0) + group_id(0)]; the host finishes. */

/* Combining a work-group's values scratch[0..n) (n a power of two) with
 * op into `result`, written by work-item 0.  GPUs: a tree in local memory.
 * CPUs (-DLSM_CL_SERIAL_COMBINE): work-item 0 alone, eight lanes at a time,
 * which saves PoCL a barrier per tree level.  op must accept float and float8
 * (+ or max). */
#define LSM_CL_ADD(a, b) ((a) + (b))
#ifdef LSM_CL_SERIAL_COMBINE
#define LSM_CL_COMBINE(scratch, lid, n, op, result)                                        \
  do {                                                                                     \
    barrier(CLK_LOCAL_MEM_FENCE);                                                          \
    if ((lid) == 0) {                                                                      \
      float acc_ = (scratch)[0];                                                           \
      int q_ = 1;                                                                          \
      if ((n) >= 8) {                                                                      \
        float8 v_ = vload8(0, (scratch));                                                  \
        for (q_ = 8; q_ + 8 <= (n); q_ += 8) v_ = op(v_, vload8(0, (scratch) + q_));       \
        const float4 v4_ = op(v_.lo, v_.hi);                                               \
        const float2 v2_ = op(v4_.lo, v4_.hi);                                             \
        acc_ = op(v2_.x, v2_.y);                                                           \
      }                                                                                    \
      for (; q_ < (n); ++q_) acc_ = op(acc_, (scratch)[q_]);                               \
      (result) = acc_;                                                                     \
    }                                                                                      \
  } while (0)
#else
#define LSM_CL_COMBINE(scratch, lid, n, op, result)                                        \
  do {                                                                                     \
    barrier(CLK_LOCAL_MEM_FENCE);                                                          \
    for (int s_ = (n) / 2; s_ > 0; s_ >>= 1) {                                             \
      if ((lid) < s_) (scratch)[lid] = op((scratch)[lid], (scratch)[(lid) + s_]);          \
      barrier(CLK_LOCAL_MEM_FENCE);                                                        \
    }                                                                                      \
    if ((lid) == 0) (result) = (scratch)[0];                                               \
  } while (0)
#endif

/* max over the interior of lsm_cfl_rate (phi's ghosts filled). */
__kernel void lsm_cfl_partial(__global const float *phi, __global const float *target, int nx,
                              int ny, int stride, int run, float inv_dx, float inv_dy,
                              __local float *scratch, __global float *partial) {
  const int lid = (int)(get_local_id(1) * get_local_size(0) + get_local_id(0));
  const int n = (int)(get_local_size(0) * get_local_size(1));
  const int i0 = (int)get_global_id(0) * run, i1 = min(i0 + run, nx);
  float rate = 0.0f;
  for (int j = (int)get_global_id(1); j < ny; j += (int)get_global_size(1)) {
    const int b = lsm_cl_at(0, j, stride);
    for (int i = i0; i < i1; ++i) {
      const int k = b + i;
      const float c = phi[k];
      const float r = lsm_cfl_rate(c - target[k], (c - phi[k - 1]) * inv_dx,
                                   (phi[k + 1] - c) * inv_dx, (c - phi[k - stride]) * inv_dy,
                                   (phi[k + stride] - c) * inv_dy, inv_dx, inv_dy);
      rate = lsm_maxf(rate, r);
    }
  }
  scratch[lid] = rate;
  LSM_CL_COMBINE(scratch, lid, n, max,
                 partial[get_group_id(1) * get_num_groups(0) + get_group_id(0)]);
}

/* Sum over the interior of (phi - target)^2, in float per group (the host adds
 * the partial sums in double).  Runs are summed eight lanes at a time (float8),
 * the rest of a run one cell at a time. */
__kernel void lsm_residual_partial(__global const float *phi, __global const float *target,
                                   int nx, int ny, int stride, int run, __local float *scratch,
                                   __global float *partial) {
  const int lid = (int)(get_local_id(1) * get_local_size(0) + get_local_id(0));
  const int n = (int)(get_local_size(0) * get_local_size(1));
  const int i0 = (int)get_global_id(0) * run, i1 = min(i0 + run, nx);
  float8 sum8 = (float8)(0.0f);
  float sum = 0.0f;
  for (int j = (int)get_global_id(1); j < ny; j += (int)get_global_size(1)) {
    const int b = lsm_cl_at(0, j, stride);
    int i = i0;
    for (; i + 8 <= i1; i += 8) {
      const float8 d = vload8(0, phi + b + i) - vload8(0, target + b + i);
      sum8 += d * d;
    }
    for (; i < i1; ++i) {
      const float d = phi[b + i] - target[b + i];
      sum += d * d;
    }
  }
  const float4 s4 = sum8.lo + sum8.hi;
  const float2 s2 = s4.lo + s4.hi;
  scratch[lid] = sum + (s2.x + s2.y);
  LSM_CL_COMBINE(scratch, lid, n, LSM_CL_ADD,
                 partial[get_group_id(1) * get_num_groups(0) + get_group_id(0)]);
}
