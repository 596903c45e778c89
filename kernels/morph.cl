/* morph.cl — the OpenCL kernels of lsmorph (host code: kernels/opencl/).
 *
 * One job per kernel; each backend op enqueues the kernels that do it, in the
 * order the driver (solver/pde/lsm_fields.c) calls the ops on both backends:
 *   lsm_fill_ghosts    zero-gradient extension into the ghost ring
 *   lsm_stage_upwind   out = c0 u0 + c1 (in - dt Hhat(in)), Godunov upwind
 *   lsm_stage_roefix   the same with the Roe-Fix Hamiltonian (+-3 widened sets)
 *   lsm_stage_weno5    the same with fifth-order WENO derivatives (+-3 cells)
 *   lsm_cfl_partial    max of lsm_cfl_rate per work-group
 *   lsm_residual_partial  sum of (phi - phi_target)^2 per work-group
 *   lsm_reinit_step    one Russo–Smereka pseudo-time step
 * the same on the narrow band's cells (lsm_band_*: stages, CFL and residual partials,
 * reinitialisation) and its rim and entering cells (lsm_band_fill_rim, lsm_band_write),
 * and the particle level set (solver/pde/lsm_particles.c on the C path):
 *   lsm_pcl_velocity   the stage's node field F, grad phi (build_velocity)
 *   lsm_pcl_advect     one Runge–Kutta stage of every particle (lsm_pls_stage)
 *   lsm_pcl_detect     removal of flagged particles, escaped-particle detection,
 *                      strays, phi_plus / phi_minus at escaped particles' corners
 *   lsm_pcl_apply      Eq. 3.26 at the touched corners (lsm_pls_correct)
 *   lsm_pcl_adjust_radius  the radius adjustment option
 * The per-cell arithmetic and its stencil gathers are kernels/lsm_cell.h and
 * kernels/lsm_stencil.h, the per-particle arithmetic kernels/lsm_particle_cell.h,
 * shared with the C path: the build embeds this file with those headers
 * spliced in at the #includes below (build/gen/lsm_kernels.h), so the program
 * needs no include path at run time.
 *
 * Buffers hold whole grids, ghosts included, laid out as lsm_grid: row stride
 * `stride` = nx + 2 LSM_GHOST floats, cell (i, j) of the interior at
 * (j + LSM_GHOST) * stride + i + LSM_GHOST.  LSM_GHOST comes from the build
 * options (-DLSM_GHOST=4, the value in solver/base/lsm_grid.h).
 *
 * NDRanges are 2D over the interior (dimension 0 = column i, 1 = row j),
 * rounded up to whole work-groups: every kernel bounds-checks.  Offsets are
 * int (the host keeps whole grids below 2^31 floats).
 *
 * No contraction into fused multiply-adds: the C path (ISO C17, GCC's default
 * -ffp-contract=off there) rounds every product, so must we. */
#pragma OPENCL FP_CONTRACT OFF

#include "lsm_cell.h"
#include "lsm_stencil.h"
#include "lsm_particle_cell.h"

#ifndef LSM_GHOST
#error "build with -DLSM_GHOST=<ghost width of solver/base/lsm_grid.h>"
#endif
#ifndef LSM_BAND_SEGMENT
#error "build with -DLSM_BAND_SEGMENT=<segment of solver/pde/lsm_band.h>"
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
 * vectorise across work-items; the others check i < nx and j < ny. */
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
 * out may be u0 (the last stage of RK2/RK3), never in; in's ghosts are filled.
 * The cell's value: kernels/lsm_stencil.h, as on the C path. */
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

LSM_CL_STAGE_KERNEL(lsm_stage_upwind, lsm_stage_upwind_at)
LSM_CL_STAGE_KERNEL(lsm_stage_roefix, lsm_stage_roefix_at)
LSM_CL_STAGE_KERNEL(lsm_stage_weno5, lsm_stage_weno5_at)

/* ---- reinitialisation: one pseudo-time step, next <- phi (phi, phi0 ghosts filled) ---- */
__kernel void lsm_reinit_step(__global float *next, __global const float *phi,
                              __global const float *phi0, int nx, int ny, int stride,
                              float inv_dx, float inv_dy, float h, float dtau) {
  const int i = (int)get_global_id(0), j = (int)get_global_id(1);
  const int k = lsm_cl_at(i, j, stride);
  if (lsm_cl_group_inside(nx, ny))
    next[k] = lsm_reinit_at(phi, phi0, k, stride, inv_dx, inv_dy, h, dtau);
  else if (i < nx && j < ny)
    next[k] = lsm_reinit_at(phi, phi0, k, stride, inv_dx, inv_dy, h, dtau);
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

/* max over the interior of lsm_cfl_rate_of (phi's ghosts filled). */
__kernel void lsm_cfl_partial(__global const float *phi, __global const float *target, int nx,
                              int ny, int stride, int run, float inv_dx, float inv_dy, int roefix,
                              __local float *scratch, __global float *partial) {
  const int lid = (int)(get_local_id(1) * get_local_size(0) + get_local_id(0));
  const int n = (int)(get_local_size(0) * get_local_size(1));
  const int i0 = (int)get_global_id(0) * run, i1 = min(i0 + run, nx);
  float rate = 0.0f;
  for (int j = (int)get_global_id(1); j < ny; j += (int)get_global_size(1)) {
    const int b = lsm_cl_at(0, j, stride);
    for (int i = i0; i < i1; ++i)
      rate = lsm_maxf(rate, lsm_cfl_rate_at(phi, target, b + i, stride, inv_dx, inv_dy, roefix));
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

/* ---- the narrow band (solver/pde/lsm_band.h) ------------------------------------------------
 * The band's cells are row segments of at most LSM_BAND_SEGMENT cells: seg[2 q] is the buffer
 * offset of segment q's first cell, seg[2 q + 1] its length.  Work-item w takes cell
 * w % LSM_BAND_SEGMENT of segment w / LSM_BAND_SEGMENT (1D NDRanges rounded up to whole groups
 * of a power of two). */
inline int lsm_cl_band_cell(__global const int *seg, int nseg, int *k) {
  const int w = (int)get_global_id(0), q = w / LSM_BAND_SEGMENT, lane = w - q * LSM_BAND_SEGMENT;
  if (q >= nseg || lane >= seg[2 * q + 1]) return 0;
  *k = seg[2 * q] + lane;
  return 1;
}

#define LSM_CL_BAND_STAGE_KERNEL(name, cell)                                                 \
  __kernel void name(__global float *out, __global const float *u0,                        \
                     __global const float *in, __global const float *target,               \
                     __global const int *seg, int nseg, int stride, float inv_dx,          \
                     float inv_dy, float c0, float c1, float dt) {                         \
    int k;                                                                                 \
    if (lsm_cl_band_cell(seg, nseg, &k))                                                   \
      out[k] = cell(u0, in, target, k, stride, inv_dx, inv_dy, c0, c1, dt);                \
  }

LSM_CL_BAND_STAGE_KERNEL(lsm_band_stage_upwind, lsm_stage_upwind_at)
LSM_CL_BAND_STAGE_KERNEL(lsm_band_stage_roefix, lsm_stage_roefix_at)
LSM_CL_BAND_STAGE_KERNEL(lsm_band_stage_weno5, lsm_stage_weno5_at)

__kernel void lsm_band_reinit_step(__global float *next, __global const float *phi,
                                   __global const float *phi0, __global const int *seg, int nseg,
                                   int stride, float inv_dx, float inv_dy, float h, float dtau) {
  int k;
  if (lsm_cl_band_cell(seg, nseg, &k))
    next[k] = lsm_reinit_at(phi, phi0, k, stride, inv_dx, inv_dy, h, dtau);
}

/* max of lsm_cfl_rate over the band per work-group (phi's rim and ghosts filled). */
__kernel void lsm_band_cfl_partial(__global const float *phi, __global const float *target,
                                   __global const int *seg, int nseg, int stride, float inv_dx,
                                   float inv_dy, int roefix, __local float *scratch,
                                   __global float *partial) {
  const int lid = (int)get_local_id(0), n = (int)get_local_size(0);
  int k;
  scratch[lid] = lsm_cl_band_cell(seg, nseg, &k)
                     ? lsm_cfl_rate_at(phi, target, k, stride, inv_dx, inv_dy, roefix)
                     : 0.0f;
  LSM_CL_COMBINE(scratch, lid, n, max, partial[get_group_id(0)]);
}

/* Sum of (phi - target)^2 over the band per work-group, in float (the host adds in double). */
__kernel void lsm_band_residual_partial(__global const float *phi, __global const float *target,
                                        __global const int *seg, int nseg,
                                        __local float *scratch, __global float *partial) {
  const int lid = (int)get_local_id(0), n = (int)get_local_size(0);
  int k;
  float d = 0.0f;
  if (lsm_cl_band_cell(seg, nseg, &k)) d = phi[k] - target[k];
  scratch[lid] = d * d;
  LSM_CL_COMBINE(scratch, lid, n, LSM_CL_ADD, partial[get_group_id(0)]);
}

/* The rim's cells of a field (buffer offsets rim[q], amplitudes amp[q]): lsm_relaxed. */
__kernel void lsm_band_fill_rim(__global float *f, __global const float *target,
                                __global const int *rim, __global const float *amp, int n,
                                float g) {
  const int q = (int)get_global_id(0);
  if (q < n) f[rim[q]] = lsm_relaxed(target[rim[q]], amp[q], g);
}

/* f[cells[q]] = values[q]. */
__kernel void lsm_band_write(__global float *f, __global const int *cells,
                             __global const float *values, int n) {
  const int q = (int)get_global_id(0);
  if (q < n) f[cells[q]] = values[q];
}

/* ---- particle level set ----------------------------------------------------------------
 * Particles are structure-of-arrays buffers (x, y in cells; x0, y0 the
 * Runge–Kutta base; sign; radius; state), n of them, in the order the host
 * seeded them.  Removed particles are not compacted: their state says so and
 * every kernel skips them (the host counts them as solver/pde/lsm_particles.c
 * does).  1D NDRanges over the particles rounded up to whole work-groups:
 * every kernel bounds-checks. */
enum { LSM_PCL_LIVE = 0, LSM_PCL_LEFT = 1, LSM_PCL_DEAD = 2 };

/* Particle kernels take the same fast path as the cell kernels: work-groups
 * wholly below n run without a per-item check (PoCL then vectorises across
 * work-items), the last one checks k < n. */
inline int lsm_cl_group_below(int n) {
  return (int)((get_group_id(0) + 1) * get_local_size(0)) <= n;
}

/* The stage's node field, float4 (F, gx, gy, 0) per node, nx*ny row-major
 * (lsm_pcl_node_field: one-sided at the grid edge, no ghost read). */
inline void lsm_cl_node_field(__global float4 *vel, __global const float *in,
                              __global const float *target, int i, int j, int nx, int ny,
                              int stride, float inv_dx, float inv_dy, float inv_2dx,
                              float inv_2dy) {
  const int k = lsm_cl_at(i, j, stride);
  const int l = i > 0 ? k - 1 : k, r = i + 1 < nx ? k + 1 : k;
  const int d = j > 0 ? k - stride : k, u = j + 1 < ny ? k + stride : k;
  float F, gx, gy;
  lsm_pcl_node_field(i, j, nx, ny, in[k], target[k], in[l], in[r], in[d], in[u], inv_dx, inv_dy,
                     inv_2dx, inv_2dy, &F, &gx, &gy);
  vel[j * nx + i] = (float4)(F, gx, gy, 0.0f);
}

__kernel void lsm_pcl_velocity(__global float4 *vel, __global const float *in,
                               __global const float *target, int nx, int ny, int stride,
                               float inv_dx, float inv_dy, float inv_2dx, float inv_2dy) {
  const int i = (int)get_global_id(0), j = (int)get_global_id(1);
  if (lsm_cl_group_inside(nx, ny))
    lsm_cl_node_field(vel, in, target, i, j, nx, ny, stride, inv_dx, inv_dy, inv_2dx, inv_2dy);
  else if (i < nx && j < ny)
    lsm_cl_node_field(vel, in, target, i, j, nx, ny, stride, inv_dx, inv_dy, inv_2dx, inv_2dy);
}

/* x_out = c0 x_u0 + c1 (x + dt F N / h) per particle, F and grad phi
 * interpolated bilinearly from the node field (solver/pde/lsm_particles.c:
 * advect).  save_base: the step's first stage, which first records the
 * positions as the step's base x_u0 (lsm_pls_begin_step).  A particle that
 * leaves the domain is flagged (removed by the next lsm_pcl_detect) and
 * clamped, as lsm_pls_stage does.  Branch-free (selects) so that it
 * vectorises; removed particles are computed and left as they were. */
inline void lsm_cl_advect(__global float *px, __global float *py, __global float *x0,
                          __global float *y0, __global uchar *state, int k,
                          __global const float4 *vel, int nx, int ny, float inv_dx,
                          float inv_dy, float c0, float c1, float dt, int save_base) {
  const uchar st = state[k];
  const float x = px[k], y = py[k];
  if (save_base) {
    x0[k] = x;
    y0[k] = y;
  }
  const float bx = save_base ? x : x0[k], by = save_base ? y : y0[k];
  float fx, fy;
  const int i = lsm_pcl_locate(x, nx, &fx), j = lsm_pcl_locate(y, ny, &fy);
  const int a = j * nx + i, b = a + nx;
  const float4 v00 = vel[a], v10 = vel[a + 1], v01 = vel[b], v11 = vel[b + 1];
  const float F = lsm_pcl_bilinear(v00.x, v10.x, v01.x, v11.x, fx, fy);
  const float gx = lsm_pcl_bilinear(v00.y, v10.y, v01.y, v11.y, fx, fy);
  const float gy = lsm_pcl_bilinear(v00.z, v10.z, v01.z, v11.z, fx, fy);
  float n_x, n_y;
  lsm_pcl_normal(gx, gy, &n_x, &n_y);
  const float xn = lsm_pcl_stage_coord(c0, bx, c1, x, dt, F, n_x, inv_dx);
  const float yn = lsm_pcl_stage_coord(c0, by, c1, y, dt, F, n_y, inv_dy);
  const int out = !lsm_pcl_in_domain(xn, yn, nx, ny);
  const int dead = st == LSM_PCL_DEAD;
  px[k] = dead ? x : (out ? lsm_pcl_clamp_coord(xn, (float)(nx - 1)) : xn);
  py[k] = dead ? y : (out ? lsm_pcl_clamp_coord(yn, (float)(ny - 1)) : yn);
  state[k] = (st == LSM_PCL_LIVE && out) ? (uchar)LSM_PCL_LEFT : st;
}

__kernel void lsm_pcl_advect(__global float *px, __global float *py, __global float *x0,
                             __global float *y0, __global uchar *state, int n,
                             __global const float4 *vel, int nx, int ny, float inv_dx,
                             float inv_dy, float c0, float c1, float dt, int save_base) {
  const int k = (int)get_global_id(0);
  if (lsm_cl_group_below(n))
    lsm_cl_advect(px, py, x0, y0, state, k, vel, nx, ny, inv_dx, inv_dy, c0, c1, dt, save_base);
  else if (k < n)
    lsm_cl_advect(px, py, x0, y0, state, k, vel, nx, ny, inv_dx, inv_dy, c0, c1, dt, save_base);
}

/* Order-preserving keys of floats for atomic max / min on unsigned ints:
 * key(a) < key(b) iff a < b (with -0 < +0).  The accumulators start at
 * LSM_PCL_KEY_NONE_MAX (below every key of a float that is not NaN) for
 * phi_plus and LSM_PCL_KEY_NONE_MIN for phi_minus, meaning "no particle". */
#define LSM_PCL_KEY_NONE_MAX 0u
#define LSM_PCL_KEY_NONE_MIN 0xFFFFFFFFu
inline uint lsm_pcl_key(float v) {
  const uint b = as_uint(v);
  return (b & 0x80000000u) ? ~b : (b | 0x80000000u);
}
inline float lsm_pcl_unkey(uint k) {
  return as_float((k & 0x80000000u) ? (k & 0x7FFFFFFFu) : ~k);
}

/* Counters (ints, zeroed by the host before the correction):
 * [0] escaped, [1] strays, [2] removed (flagged by the stages or strays of
 * the previous correction), [3] live after detection (strays included, as
 * they stay in the set until the next correction), [4] corrected nodes. */
enum { LSM_PCL_N_ESCAPED, LSM_PCL_N_STRAY, LSM_PCL_N_REMOVED, LSM_PCL_N_LIVE,
       LSM_PCL_N_CORRECTED, LSM_PCL_N_COUNT };

/* lsm_pls_correct steps 1–2: flagged particles are removed; each remaining
 * particle is tested on phi (escaped: wrong sign and |phi| > r; a stray when
 * farther than `far`, flagged for removal); an escaped one merges its local
 * level set at the 4 corners of its cell into phi_plus (s = +1, max) or
 * phi_minus (s = -1, min) with atomics on order-preserving keys, so the
 * result does not depend on the particle order.  phi is only read.  The rare
 * events (removed, stray, escaped) are counted with global atomics; the live
 * particles per work-group in `scratch` (one int per work-item), summed by
 * work-item 0. */
__kernel void lsm_pcl_detect(__global const float *px, __global const float *py,
                             __global const char *sign, __global const float *radius,
                             __global uchar *state, int n, __global const float *phi, int nx,
                             int ny, int stride, float dx, float dy, float far,
                             __global uint *plus, __global uint *minus,
                             __global int *counters, __local int *scratch) {
  const int lid = (int)get_local_id(0), k = (int)get_global_id(0);
  int live = 0;
  if (k < n) {
    const uchar st = state[k];
    if (st == LSM_PCL_LEFT) {
      state[k] = LSM_PCL_DEAD;
      atomic_inc(&counters[LSM_PCL_N_REMOVED]);
    } else if (st == LSM_PCL_LIVE) {
      live = 1;
      const float x = px[k], y = py[k];
      float fx, fy;
      const int i = lsm_pcl_locate(x, nx, &fx), j = lsm_pcl_locate(y, ny, &fy);
      const int a = lsm_cl_at(i, j, stride), b = a + stride;
      const float ph = lsm_pcl_bilinear(phi[a], phi[a + 1], phi[b], phi[b + 1], fx, fy);
      const int s = sign[k];
      const float r = radius[k];
      const int e = lsm_pcl_escaped(s, ph, r);
      if (lsm_pcl_stray(e, ph, far)) {
        state[k] = LSM_PCL_LEFT;
        atomic_inc(&counters[LSM_PCL_N_STRAY]);
      } else if (e) {
        atomic_inc(&counters[LSM_PCL_N_ESCAPED]);
        for (int q = 0; q < 4; ++q) {
          const int ca = q & 1, cb = q >> 1;
          const float pv = phi[(cb ? b : a) + ca];
          const float dist = lsm_pcl_distance((float)(i + ca) - x, (float)(j + cb) - y, dx, dy);
          const uint key = lsm_pcl_key(lsm_pcl_corner_value(s, r, pv, dist));
          const int node = (j + cb) * nx + i + ca;
          if (s > 0)
            atomic_max(&plus[node], key);
          else
            atomic_min(&minus[node], key);
        }
      }
    }
  }
  scratch[lid] = live;
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid == 0) {
    int sum = 0;
    const int m = (int)get_local_size(0);
    for (int q = 0; q < m; ++q) sum += scratch[q];
    if (sum) atomic_add(&counters[LSM_PCL_N_LIVE], sum);
  }
}

/* lsm_pls_correct step 3 at every node an escaped particle touched:
 * phi_plus = merge(phi, plus), phi_minus = merge(phi, minus), then Eq. 3.26;
 * a changed value is written and counted.  The accumulators are reset for the
 * next correction. */
__kernel void lsm_pcl_apply(__global float *phi, int nx, int ny, int stride,
                            __global uint *plus, __global uint *minus,
                            __global int *counters) {
  const int i = (int)get_global_id(0), j = (int)get_global_id(1);
  if (i >= nx || j >= ny) return;
  const int node = j * nx + i;
  const uint kp = plus[node], km = minus[node];
  if (kp == LSM_PCL_KEY_NONE_MAX && km == LSM_PCL_KEY_NONE_MIN) return;
  const int k = lsm_cl_at(i, j, stride);
  const float pv = phi[k];
  const float vp = kp == LSM_PCL_KEY_NONE_MAX ? pv : lsm_pcl_merge(1, pv, lsm_pcl_unkey(kp));
  const float vm = km == LSM_PCL_KEY_NONE_MIN ? pv : lsm_pcl_merge(-1, pv, lsm_pcl_unkey(km));
  const float v = lsm_pcl_select(vp, vm);
  if (v != pv) {
    phi[k] = v;
    atomic_inc(&counters[LSM_PCL_N_CORRECTED]);
  }
  plus[node] = LSM_PCL_KEY_NONE_MAX;
  minus[node] = LSM_PCL_KEY_NONE_MIN;
}

/* lsm_pls_correct step 4 (option): particles on their own side of the
 * corrected phi get r = clamp(s phi, r_min, r_max). */
__kernel void lsm_pcl_adjust_radius(__global const float *px, __global const float *py,
                             __global const char *sign, __global float *radius,
                             __global const uchar *state, int n, __global const float *phi,
                             int nx, int ny, int stride, float rmin, float rmax) {
  const int k = (int)get_global_id(0);
  if (k >= n || state[k] == LSM_PCL_DEAD) return;
  float fx, fy;
  const int i = lsm_pcl_locate(px[k], nx, &fx), j = lsm_pcl_locate(py[k], ny, &fy);
  const int a = lsm_cl_at(i, j, stride), b = a + stride;
  const float ph = lsm_pcl_bilinear(phi[a], phi[a + 1], phi[b], phi[b + 1], fx, fy);
  const int s = sign[k];
  if (lsm_pcl_own_side(s, ph)) radius[k] = lsm_pcl_radius(s, ph, rmin, rmax);
}
