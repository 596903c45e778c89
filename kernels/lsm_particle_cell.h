/* lsm_particle_cell.h — per-particle numerics of the particle level set, written once.
 *
 * Pure functions of plain values, in the style of kernels/lsm_cell.h.  The C
 * path (solver/pde/lsm_particles.c) and the OpenCL kernels (kernels/morph.cl)
 * both include it, so both run the same arithmetic.
 *
 * Units.  Particle positions are in CELL coordinates: x = column, y = row,
 * continuous, with cell centres (grid nodes) at integers.  phi, radii, band
 * limits and distances are PHYSICAL (multiply a cell offset by dx or dy).
 * A "grid cell" here is the square between the 4 nodes (i,j), (i+1,j),
 * (i,j+1), (i+1,j+1) (Figure 3.18 of the design document).
 *
 * The method: solver/README.md §11 (the design document's Algorithms 3.2 and
 * 3.3, Eq. 3.15–3.26; Enright, Fedkiw, Ferziger & Mitchell 2002).
 */
#ifndef LSM_PARTICLE_CELL_H
#define LSM_PARTICLE_CELL_H

#include "kernels/lsm_cell.h"

#ifdef __OPENCL_VERSION__
#define LSM_U64 ulong
#define LSM_NEXTAFTER(x, y) nextafter(x, y)
#else
#include <stdint.h>
#define LSM_U64 uint64_t
#define LSM_NEXTAFTER(x, y) nextafterf(x, y)
#endif

/* 1/sqrt(2): the arbitrary unit normal (Eq. 3.18) used where grad phi = 0. */
#define LSM_PCL_INV_SQRT2 0.70710678118654752440f

/* ---- Counter-based random numbers ----------------------------------------------
 * splitmix64's finaliser (Steele, Lea & Flood 2014) chained over the counters,
 * so a draw depends only on (seed, generation, cell, particle, draw): no
 * shared state, identical for any thread count and on any device. */
LSM_FN LSM_U64 lsm_pcl_mix64(LSM_U64 z) {
  z += (LSM_U64)0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * (LSM_U64)0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * (LSM_U64)0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/* Uniform float in [0, 1) (24 random bits) for draw number 'draw' of particle
 * 'k' of grid cell 'cell' in seeding generation 'gen' (0 at creation, then one
 * per reseeding). */
LSM_FN float lsm_pcl_uniform(LSM_U64 seed, LSM_U64 gen, LSM_U64 cell, LSM_U64 k, LSM_U64 draw) {
  LSM_U64 h = lsm_pcl_mix64(seed);
  h = lsm_pcl_mix64(h ^ gen);
  h = lsm_pcl_mix64(h ^ cell);
  h = lsm_pcl_mix64(h ^ k);
  h = lsm_pcl_mix64(h ^ draw);
  return (float)(h >> 40) * (1.0f / 16777216.0f);
}

/* Seeding coordinate i + u inside [i, i+1) for u in [0, 1): float rounding of
 * i + u (u close to 1, i large) could land on i+1; such a value is moved to
 * the largest float below i+1, so a seeded particle always lies in its cell. */
LSM_FN float lsm_pcl_seed_coord(int i, float u) {
  float lo = (float)i, hi = (float)(i + 1), x = lo + u;
  return x < hi ? x : LSM_NEXTAFTER(hi, lo);
}

/* ---- Locating a particle --------------------------------------------------------
 * Grid cell index along one axis for the position x on n >= 2 nodes: x is
 * clamped to [0, n-1] (NaN to 0), i = floor(x) clamped to [0, n-2]; *frac = x - i in
 * [0, 1] is the bilinear weight of node i+1. */
LSM_FN int lsm_pcl_locate(float x, int n, LSM_PRIV float *frac) {
  float hi = (float)(n - 1);
  x = x > 0.0f ? x : 0.0f; /* also maps NaN to 0 */
  x = x < hi ? x : hi;
  int i = (int)x; /* x >= 0: truncation is floor */
  if (i > n - 2) i = n - 2;
  if (i < 0) i = 0;
  *frac = x - (float)i;
  return i;
}

/* 1 when (x, y) lies in the computational domain [0, nx-1] x [0, ny-1]. */
LSM_FN int lsm_pcl_in_domain(float x, float y, int nx, int ny) {
  return x >= 0.0f && y >= 0.0f && x <= (float)(nx - 1) && y <= (float)(ny - 1);
}

/* Bilinear interpolation of the 4 node values of a cell:
 *   v00 at (i,j), v10 at (i+1,j), v01 at (i,j+1), v11 at (i+1,j+1). */
LSM_FN float lsm_pcl_bilinear(float v00, float v10, float v01, float v11, float fx, float fy) {
  float a = v00 + fx * (v10 - v00);
  float b = v01 + fx * (v11 - v01);
  return a + fy * (b - a);
}

/* ---- phi and the unit normal at a particle ---------------------------------------
 * s is the 4x4 neighbourhood of the particle's cell, row-major, s[r*4 + c] =
 * phi(i-1+c, j-1+r) with the indices clamped to the grid (so no ghost cells
 * are read).  Node gradients are central differences, one-sided at the grid
 * edge: the caller passes, per corner column/row, inv_w = 1 / (span * h)
 * where span is the index distance of the two neighbours used (2 inside,
 * 1 at an edge) and h is dx or dy.  grad phi is interpolated bilinearly
 * (design document: "interpolated central differences"); N = grad/|grad|,
 * or (1/sqrt2, 1/sqrt2) where the interpolated gradient is zero (Eq. 3.18).
 * Returns phi(p); writes N to *n_x, *n_y. */
LSM_FN void lsm_pcl_normal(float gx, float gy, LSM_PRIV float *n_x, LSM_PRIV float *n_y) {
  float g = LSM_SQRT(gx * gx + gy * gy);
  if (g > 0.0f) {
    float inv = 1.0f / g;
    *n_x = gx * inv;
    *n_y = gy * inv;
  } else {
    *n_x = LSM_PCL_INV_SQRT2;
    *n_y = LSM_PCL_INV_SQRT2;
  }
}

LSM_FN float lsm_pcl_phi_normal(const LSM_PRIV float *s, float fx, float fy, float inv_wx0,
                                float inv_wx1, float inv_wy0, float inv_wy1,
                                LSM_PRIV float *n_x, LSM_PRIV float *n_y) {
  /* corners: (0,0) = s[5], (1,0) = s[6], (0,1) = s[9], (1,1) = s[10] */
  float gx00 = (s[6] - s[4]) * inv_wx0, gx10 = (s[7] - s[5]) * inv_wx1;
  float gx01 = (s[10] - s[8]) * inv_wx0, gx11 = (s[11] - s[9]) * inv_wx1;
  float gy00 = (s[9] - s[1]) * inv_wy0, gy10 = (s[10] - s[2]) * inv_wy0;
  float gy01 = (s[13] - s[5]) * inv_wy1, gy11 = (s[14] - s[6]) * inv_wy1;
  float gx = lsm_pcl_bilinear(gx00, gx10, gx01, gx11, fx, fy);
  float gy = lsm_pcl_bilinear(gy00, gy10, gy01, gy11, fx, fy);
  lsm_pcl_normal(gx, gy, n_x, n_y);
  return lsm_pcl_bilinear(s[5], s[6], s[9], s[10], fx, fy);
}

/* ---- Seeding and attraction (Algorithm 3.2) ---------------------------------------
 * A grid cell is in the seeding band when any of its 4 corners has
 * |phi| < 3 max(dx, dy). */
LSM_FN int lsm_pcl_band_cell(float p00, float p10, float p01, float p11, float band) {
  return (LSM_FABS(p00) < band) | (LSM_FABS(p10) < band) | (LSM_FABS(p01) < band) |
         (LSM_FABS(p11) < band);
}

/* 1 when phi at the particle lies in its band: sign s (+1 / -1) and
 * v_min <= s phi <= v_max (Eq. 3.15). */
LSM_FN int lsm_pcl_in_band(int s, float phi, float vmin, float vmax) {
  float sp = (float)s * phi;
  return sp >= vmin && sp <= vmax;
}

/* Radius (Eq. 3.19): clamp(s phi, r_min, r_max). */
LSM_FN float lsm_pcl_radius(int s, float phi, float rmin, float rmax) {
  float r = (float)s * phi;
  return r > rmax ? rmax : (r < rmin ? rmin : r);
}

/* ---- Correction (Algorithm 3.3) ----------------------------------------------------
 * Escaped: sign(phi(p)) != s and |phi(p)| > r.  (phi(p) = 0 never escapes.) */
LSM_FN int lsm_pcl_escaped(int s, float phi, float r) {
  int sg = phi > 0.0f ? 1 : (phi < 0.0f ? -1 : 0);
  return sg != s && LSM_FABS(phi) > r;
}

/* Physical distance from the particle to a node: the offset (ox, oy) in cells
 * times (dx, dy). */
LSM_FN float lsm_pcl_distance(float ox, float oy, float dx, float dy) {
  float a = ox * dx, b = oy * dy;
  return LSM_SQRT(a * a + b * b);
}

/* Local level set of an escaped particle at a corner v, the design document's
 * smoothed variant (Eq. 3.23):
 *   phi_p(v) = s r - |v - p|   if phi(v) <= 0
 *            = s r + |v - p|   if phi(v) >  0
 * phi_v is the (uncorrected) grid value at v, dist = |v - p| physical. */
LSM_FN float lsm_pcl_corner_value(int s, float r, float phi_v, float dist) {
  float sr = (float)s * r;
  return phi_v <= 0.0f ? sr - dist : sr + dist;
}

/* Merge of a corner value into phi_plus (positive particles, Eq. 3.24: max) or
 * phi_minus (negative particles, Eq. 3.25: min). */
LSM_FN float lsm_pcl_merge(int s, float acc, float phi_p) {
  return s > 0 ? lsm_maxf(acc, phi_p) : lsm_minf(acc, phi_p);
}

/* Final value at a node (Eq. 3.26): phi_plus if |phi_plus| <= |phi_minus|,
 * else phi_minus. */
LSM_FN float lsm_pcl_select(float phi_plus, float phi_minus) {
  return LSM_FABS(phi_plus) <= LSM_FABS(phi_minus) ? phi_plus : phi_minus;
}

/* ---- Set constants, the node field, stages, strays -----------------------------------
 * Called by solver/pde/lsm_particles.c (inside its vectorised loops) and by the
 * OpenCL path (kernels/morph.cl, kernels/opencl/lsm_cl_particles.c); each
 * comment names the C function that uses it. */

/* Constants of a particle set on a dx x dy grid, as lsm_pls_create sets them:
 * r_min = 0.1 min(dx,dy), r_max = 0.5 min(dx,dy); and the stray distance of
 * lsm_pls_correct, 1.5 max(dx,dy). */
LSM_FN float lsm_pcl_rmin(float dx, float dy) { return 0.1f * (dx < dy ? dx : dy); }
LSM_FN float lsm_pcl_rmax(float dx, float dy) { return 0.5f * (dx < dy ? dx : dy); }
LSM_FN float lsm_pcl_far(float dx, float dy) { return 1.5f * (dx > dy ? dx : dy); }

/* build_velocity: the node field of a stage at node (i, j) of an nx x ny grid,
 * F = phi - phi_target and grad phi by central differences, one-sided at the
 * grid edge.  c, t: phi and phi_target at the node; l, r, d, u: phi at the
 * clamped neighbours (i-1, i+1, j-1, j+1); inv_dx = 1/dx, inv_2dx = 0.5/dx
 * (likewise y), computed in float as lsm_pls_create does. */
LSM_FN void lsm_pcl_node_field(int i, int j, int nx, int ny, float c, float t, float l, float r,
                               float d, float u, float inv_dx, float inv_dy, float inv_2dx,
                               float inv_2dy, LSM_PRIV float *F, LSM_PRIV float *gx,
                               LSM_PRIV float *gy) {
  const float wx = (i > 0 && i + 1 < nx) ? inv_2dx : inv_dx;
  const float wy = (j > 0 && j + 1 < ny) ? inv_2dy : inv_dy;
  *F = c - t;
  *gx = (r - l) * wx;
  *gy = (u - d) * wy;
}

/* advect: one coordinate after a Runge–Kutta stage,
 *   c0 x_u0 + c1 (x + dt F n / h)   (inv_h = 1/dx or 1/dy),
 * with the products in the C path's order (no contraction on either side).
 * The unit normal n is lsm_pcl_normal of the interpolated gradient, which is
 * advect's arithmetic too (1/g, then g_x * (1/g); the diagonal where g = 0). */
LSM_FN float lsm_pcl_stage_coord(float c0, float x_u0, float c1, float x, float dt, float F,
                                 float n, float inv_h) {
  return c0 * x_u0 + c1 * (x + dt * F * n * inv_h);
}

/* lsm_pls_stage: a coordinate of a particle that left the domain, clamped to
 * [0, hi] (hi = n-1); NaN is parked at 0. */
LSM_FN float lsm_pcl_clamp_coord(float v, float hi) {
  return v == v ? (v < 0.0f ? 0.0f : (v > hi ? hi : v)) : 0.0f;
}

/* detect: an escaped particle farther than `far` outside its side (|phi| >
 * far) is a stray: removed, not used for the correction. */
LSM_FN int lsm_pcl_stray(int escaped, float phi, float far) {
  return escaped && LSM_FABS(phi) > far;
}

/* lsm_pls_correct's radius adjustment applies to particles on their own side:
 * s phi > 0. */
LSM_FN int lsm_pcl_own_side(int s, float phi) {
  return (s > 0 && phi > 0.0f) || (s < 0 && phi < 0.0f);
}

#endif
