/* lsm_motion_cell.h — per-cell numerics of the correspondence field, written once.
 *
 * The symmetric log-domain demons registration of two slices' signed distances and the
 * maps of its stationary velocity field (solver/README.md §9): bilinear samples, one
 * squaring step of the exponential, a warp, the demons update, a Gaussian tap sum.  Pure
 * functions of plain arrays, shared by the C path (solver/motion) and the OpenCL kernels
 * (kernels/motion.cl, host kernels/opencl/lsm_cl_motion.c), so both run the same arithmetic.
 *
 * Fields live on node grids: nx x ny floats, row-major, no ghost layer; a vector field is
 * two such planes (x, y), in node units.  Samples outside the grid take the nearest edge
 * value (the field and the clipped distances go on flat beyond the canvas).
 */
#ifndef LSM_MOTION_CELL_H
#define LSM_MOTION_CELL_H

#include "kernels/lsm_cell.h"

#ifdef __OPENCL_VERSION__
#define LSM_FLOORF(x) floor(x)
#else
#define LSM_FLOORF(x) floorf(x)
#endif

/* Bilinear sample of plane f (nx x ny, rows `stride` floats apart) at (x, y), node units,
 * clamped to the grid. */
LSM_FN float lsm_bilinear_strided(LSM_GLOBAL const float *f, LSM_IDX stride, int nx, int ny,
                                  float x, float y) {
  x = lsm_minf(lsm_maxf(x, 0.0f), (float)(nx - 1));
  y = lsm_minf(lsm_maxf(y, 0.0f), (float)(ny - 1));
  int i = (int)LSM_FLOORF(x), j = (int)LSM_FLOORF(y);
  if (i > nx - 2) i = nx > 1 ? nx - 2 : 0;
  if (j > ny - 2) j = ny > 1 ? ny - 2 : 0;
  const int i1 = nx > 1 ? i + 1 : i, j1 = ny > 1 ? j + 1 : j;
  const float fx = x - (float)i, fy = y - (float)j;
  const LSM_IDX r0 = (LSM_IDX)j * stride, r1 = (LSM_IDX)j1 * stride;
  const float top = (1.0f - fx) * f[r0 + i] + fx * f[r0 + i1];
  const float bottom = (1.0f - fx) * f[r1 + i] + fx * f[r1 + i1];
  return (1.0f - fy) * top + fy * bottom;
}

/* The same on a plane of rows nx floats apart. */
LSM_FN float lsm_bilinear(LSM_GLOBAL const float *f, int nx, int ny, float x, float y) {
  return lsm_bilinear_strided(f, (LSM_IDX)nx, nx, ny, x, y);
}

/* A distance clipped to +-clip (the band the registration sees). */
LSM_FN float lsm_motion_clip(float v, float clip) {
  return v > clip ? clip : v < -clip ? -clip : v;
}

/* Whether a node informs the registration: either warped distance inside the clip band (the
 * demons update is zero elsewhere; the mean squared mismatch is taken over these nodes). */
LSM_FN int lsm_motion_active(float a, float b, float clip) {
  return LSM_FABS(a) < clip || LSM_FABS(b) < clip;
}

/* t^2 |v|^2 at a node: the squared step of exp(t v) before scaling (its largest value over
 * the nodes sets the number of squarings). */
LSM_FN float lsm_motion_norm2(float t, float vx, float vy) {
  return t * t * (vx * vx + vy * vy);
}

/* A coarser level's field component c (cnx x cny nodes) at node (i, j) of a finer level:
 * bilinear at (i ratio, j ratio), times gain (coarse node units in fine ones). */
LSM_FN float lsm_motion_upsample_at(LSM_GLOBAL const float *c, int cnx, int cny, float ratio,
                                   float gain, int i, int j) {
  return gain * lsm_bilinear(c, cnx, cny, (float)i * ratio, (float)j * ratio);
}

/* One squaring of the exponential at node (i, j): the map x -> x + d(x) composed with
 * itself, x -> x + d(x) + d(x + d(x)); component `comp` (0: x, 1: y) of the result. */
LSM_FN float lsm_motion_square(LSM_GLOBAL const float *dx, LSM_GLOBAL const float *dy, int nx,
                               int ny, int i, int j, int comp) {
  const LSM_IDX k = (LSM_IDX)j * nx + i;
  const float px = (float)i + dx[k], py = (float)j + dy[k];
  return comp == 0 ? dx[k] + lsm_bilinear(dx, nx, ny, px, py)
                   : dy[k] + lsm_bilinear(dy, nx, ny, px, py);
}

/* The composition x -> x + d1(x) then + d2 there: x + d1(x) + d2(x + d1(x)), component
 * `comp` at node (i, j) (d1, d2 on the same grid). */
LSM_FN float lsm_motion_compose_at(LSM_GLOBAL const float *d1x, LSM_GLOBAL const float *d1y,
                                LSM_GLOBAL const float *d2, int nx, int ny, int i, int j,
                                int comp) {
  const LSM_IDX k = (LSM_IDX)j * nx + i;
  const float px = (float)i + d1x[k], py = (float)j + d1y[k];
  return (comp == 0 ? d1x[k] : d1y[k]) + lsm_bilinear(d2, nx, ny, px, py);
}

/* An image pulled back through a map: a(x + d(x)) at node (i, j). */
LSM_FN float lsm_motion_warp(LSM_GLOBAL const float *a, LSM_GLOBAL const float *dx,
                             LSM_GLOBAL const float *dy, int nx, int ny, int i, int j) {
  const LSM_IDX k = (LSM_IDX)j * nx + i;
  return lsm_bilinear(a, nx, ny, (float)i + dx[k], (float)j + dy[k]);
}

/* The symmetric demons update at node (i, j) from the two warped distances a' = A(Phi^-1/2),
 * b' = B(Phi^1/2) (physical units) on a grid of node spacing hx, hy (physical):
 *   r = b' - a',  J = (grad a' + grad b') / 2,  u = -r J / (|J|^2 + r^2 / h^2),
 * h = min(hx, hy).  Moving w by u changes r by J.u to first order (each side takes half),
 * so for |r| << h |J| the step removes r (Gauss-Newton); |u| <= h / 2 always (the maximum
 * of |r| |J| / (|J|^2 + r^2 / h^2) over r), so a large mismatch pulls no farther than half a
 * node per iteration.  Writes u in node units to *ux, *uy and returns r^2 (0 where both
 * distances are clipped flat: no information there). */
LSM_FN float lsm_motion_demons(LSM_GLOBAL const float *wa, LSM_GLOBAL const float *wb, int nx,
                               int ny, int i, int j, float hx, float hy, float clip,
                               LSM_PRIV float *ux, LSM_PRIV float *uy) {
  const LSM_IDX k = (LSM_IDX)j * nx + i;
  const int i0 = i > 0 ? i - 1 : i, i1 = i < nx - 1 ? i + 1 : i;
  const int j0 = j > 0 ? j - 1 : j, j1 = j < ny - 1 ? j + 1 : j;
  const LSM_IDX r0 = (LSM_IDX)j0 * nx, r1 = (LSM_IDX)j1 * nx, rj = (LSM_IDX)j * nx;
  *ux = 0.0f;
  *uy = 0.0f;
  const float a = wa[k], b = wb[k];
  if (!lsm_motion_active(a, b, clip)) return 0.0f;
  const float lx = (float)(i1 - i0) * hx, ly = (float)(j1 - j0) * hy; /* central span */
  const float jx = i1 > i0 ? 0.5f * ((wa[rj + i1] - wa[rj + i0]) + (wb[rj + i1] - wb[rj + i0])) / lx
                           : 0.0f;
  const float jy = j1 > j0 ? 0.5f * ((wa[r1 + i] - wa[r0 + i]) + (wb[r1 + i] - wb[r0 + i])) / ly
                           : 0.0f;
  const float r = b - a, h = lsm_minf(hx, hy);
  const float den = jx * jx + jy * jy + (r * r) / (h * h);
  if (den > 0.0f) {
    *ux = -r * jx / den / hx;
    *uy = -r * jy / den / hy;
  }
  return r * r;
}

/* The Gaussian tap sum along x (axis 0) or y (axis 1) at node (i, j): sum over t of
 * kern[t] f(i + t - radius) (edge value beyond the grid). */
LSM_FN float lsm_motion_blur(LSM_GLOBAL const float *f, int nx, int ny, int i, int j, int axis,
                             LSM_GLOBAL const float *kern, int radius) {
  float sum = 0.0f;
  for (int t = -radius; t <= radius; ++t) {
    int ii = axis == 0 ? i + t : i, jj = axis == 0 ? j : j + t;
    ii = ii < 0 ? 0 : ii > nx - 1 ? nx - 1 : ii;
    jj = jj < 0 ? 0 : jj > ny - 1 ? ny - 1 : jj;
    sum += kern[t + radius] * f[(LSM_IDX)jj * nx + ii];
  }
  return sum;
}

#endif
