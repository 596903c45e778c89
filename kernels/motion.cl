/* motion.cl — the OpenCL kernels of the correspondence field's registration
 * (--motion field; host code: kernels/opencl/lsm_cl_motion.c, the C path:
 * solver/motion/lsm_motion.c).  Built into the same program as morph.cl.
 *
 * One job per kernel, each a thin wrapper over kernels/lsm_motion_cell.h (the
 * same functions the C path calls at each node), in the order of a level's
 * iteration (lsm_motion_level):
 *   lsm_motion_row_max     largest lsm_motion_norm2 of each row (the host takes
 *                          the largest of the rows: exact in any order)
 *   lsm_motion_scale       d = scale v, the first step of scaling and squaring
 *   lsm_motion_square_k    one squaring of the exponential
 *   lsm_motion_warp_k      a' = A(M), b' = B(P)
 *   lsm_motion_demons_k    the update u, r^2 and the active flag per node (the
 *                          host sums them in double, rows in order, as C does)
 *   lsm_motion_blur_k      a Gaussian tap sum along one axis, both components
 *   lsm_motion_add         w += u
 *
 * Node planes are nx x ny floats, row-major, no ghosts.  2D NDRanges are
 * (column i, row j), rounded up to whole work-groups: every kernel
 * bounds-checks.  No contraction (morph.cl's FP_CONTRACT OFF, repeated). */
#pragma OPENCL FP_CONTRACT OFF

#include "lsm_motion_cell.h"

__kernel void lsm_motion_row_max(__global const float *vx, __global const float *vy, int nx,
                                 int ny, float t, __global float *row_max) {
  const int j = get_global_id(0);
  if (j >= ny) return;
  float most = 0.0f;
  for (int i = 0; i < nx; ++i) {
    const float m = lsm_motion_norm2(t, vx[j * nx + i], vy[j * nx + i]);
    if (m > most) most = m;
  }
  row_max[j] = most;
}

__kernel void lsm_motion_scale(__global float *dx, __global float *dy, __global const float *vx,
                               __global const float *vy, int n, float scale) {
  const int k = get_global_id(0);
  if (k >= n) return;
  dx[k] = scale * vx[k];
  dy[k] = scale * vy[k];
}

__kernel void lsm_motion_square_k(__global float *bx, __global float *by,
                                  __global const float *ax, __global const float *ay, int nx,
                                  int ny) {
  const int i = get_global_id(0), j = get_global_id(1);
  if (i >= nx || j >= ny) return;
  bx[j * nx + i] = lsm_motion_square(ax, ay, nx, ny, i, j, 0);
  by[j * nx + i] = lsm_motion_square(ax, ay, nx, ny, i, j, 1);
}

__kernel void lsm_motion_warp_k(__global float *wa, __global float *wb, __global const float *a,
                                __global const float *b, __global const float *mx,
                                __global const float *my, __global const float *px,
                                __global const float *py, int nx, int ny) {
  const int i = get_global_id(0), j = get_global_id(1);
  if (i >= nx || j >= ny) return;
  wa[j * nx + i] = lsm_motion_warp(a, mx, my, nx, ny, i, j);
  wb[j * nx + i] = lsm_motion_warp(b, px, py, nx, ny, i, j);
}

/* r2c: r^2 in [0, nx ny), the active flag (0 or 1) in [nx ny, 2 nx ny). */
__kernel void lsm_motion_demons_k(__global float *ux, __global float *uy, __global float *r2c,
                                  __global const float *wa, __global const float *wb, int nx,
                                  int ny, float hx, float hy, float clip) {
  const int i = get_global_id(0), j = get_global_id(1);
  if (i >= nx || j >= ny) return;
  const int k = j * nx + i;
  float u, v;
  r2c[k] = lsm_motion_demons(wa, wb, nx, ny, i, j, hx, hy, clip, &u, &v);
  r2c[nx * ny + k] = (float)lsm_motion_active(wa[k], wb[k], clip);
  ux[k] = u;
  uy[k] = v;
}

__kernel void lsm_motion_blur_k(__global float *ox, __global float *oy, __global const float *fx,
                                __global const float *fy, int nx, int ny, int axis,
                                __global const float *kern, int radius) {
  const int i = get_global_id(0), j = get_global_id(1);
  if (i >= nx || j >= ny) return;
  ox[j * nx + i] = lsm_motion_blur(fx, nx, ny, i, j, axis, kern, radius);
  oy[j * nx + i] = lsm_motion_blur(fy, nx, ny, i, j, axis, kern, radius);
}

__kernel void lsm_motion_add(__global float *wx, __global float *wy, __global const float *ux,
                             __global const float *uy, int n) {
  const int k = get_global_id(0);
  if (k >= n) return;
  wx[k] += ux[k];
  wy[k] += uy[k];
}
