#include "solver/pde/lsm_particles.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "kernels/lsm_particle_cell.h"

/* Per-particle state bits (the state array). */
enum {
  PCL_LEFT = 1u,    /* advection left the domain: removed by the next correction */
  PCL_ESCAPED = 2u, /* escaped in the current correction */
  PCL_DROP = 4u     /* attraction failed: removed by the seeding's compaction */
};

/* Random draws per particle (the 'draw' counter of lsm_pcl_uniform). */
enum { DRAW_X = 0, DRAW_Y = 1, DRAW_GOAL = 2 };

#define ATTRACT_ITERS 10
#define MAX_HALVINGS 30

struct lsm_particles {
  lsm_pls_opts opts;
  int nx, ny;
  float dx, dy, inv_dx, inv_dy, inv_2dx, inv_2dy;
  float vmin, vmax, rmin, rmax, band;
  size_t n, cap;
  size_t left_pending; /* particles flagged PCL_LEFT since the last correction */
  int keep_start;      /* the current step has later stages that read x0, y0 */
  size_t *escaped;     /* indices of the escaped particles of a correction */
  size_t escaped_cap;
  float *x, *y, *x0, *y0, *radius;
  int8_t *sign;
  uint8_t *state;
  /* correction scratch, nx*ny each: phi_plus, phi_minus, touched marks */
  float *plus, *minus;
  /* advection scratch, three planes of nx*ny floats (row-major, like phi
   * without ghosts): F = phi - phi_target and the central-difference gradient
   * gx, gy of phi, rebuilt at every stage */
  float *velocity;
  uint8_t *mark;
  uint64_t gen; /* seeding generation (0 at creation) */
  lsm_pls_stats stats;
};

void lsm_pls_opts_default(lsm_pls_opts *o) {
  o->particles_per_cell = 16;
  o->reseed_every = 0;
  o->radius_adjust = 0;
  o->seed = LSM_PLS_DEFAULT_SEED;
  o->threads = 1;
  o->skip_attraction = 0;
}

static int pls_threads(const lsm_particles *p, size_t n) {
  return n < (size_t)LSM_PLS_MIN_PARALLEL || p->opts.threads < 1 ? 1 : p->opts.threads;
}

/* ---- interpolation ---------------------------------------------------------------- */

/* Forced inlining into the particle loops (GCC 12 left them out of line at
 * -O3; validation/measurements/pde.md). */
#if defined(__GNUC__)
#define PCL_INLINE static inline __attribute__((always_inline))
#else
#define PCL_INLINE static inline
#endif

/* Loops that vectorise: GCC function multi-versioning picks the AVX-512 or AVX2 clone at
 * load time (same arithmetic, no FMA contraction in C17). */
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
#define PCL_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define PCL_CLONES
#endif

/* phi at (x, y) and the unit normal there (interpolated central differences,
 * lsm_pcl_phi_normal on the clamped 4x4 neighbourhood); int offsets on phi's
 * rows (checked at creation), so it vectorises in attract_first. */
PCL_INLINE float phi_normal_int(const float *restrict g, int stride, int nx, int ny, float inv_dx,
                                float inv_dy, float inv_2dx, float inv_2dy, float x, float y,
                                float *n_x, float *n_y) {
  float fx, fy;
  const int i = lsm_pcl_locate(x, nx, &fx), j = lsm_pcl_locate(y, ny, &fy);
  const int c0 = i > 0 ? i - 1 : 0, c3 = i + 2 < nx ? i + 2 : nx - 1;
  const int r0 = j > 0 ? j - 1 : 0, r3 = j + 2 < ny ? j + 2 : ny - 1;
  const int o0 = r0 * stride, o1 = j * stride, o2 = o1 + stride, o3 = r3 * stride;
  const float st[16] = {g[o0 + c0], g[o0 + i], g[o0 + i + 1], g[o0 + c3],
                        g[o1 + c0], g[o1 + i], g[o1 + i + 1], g[o1 + c3],
                        g[o2 + c0], g[o2 + i], g[o2 + i + 1], g[o2 + c3],
                        g[o3 + c0], g[o3 + i], g[o3 + i + 1], g[o3 + c3]};
  const float wx0 = i + 1 - c0 == 2 ? inv_2dx : inv_dx, wx1 = c3 - i == 2 ? inv_2dx : inv_dx;
  const float wy0 = j + 1 - r0 == 2 ? inv_2dy : inv_dy, wy1 = r3 - j == 2 ? inv_2dy : inv_dy;
  return lsm_pcl_phi_normal(st, fx, fy, wx0, wx1, wy0, wy1, n_x, n_y);
}

PCL_INLINE float eval_phi_normal(const lsm_particles *p, const lsm_grid *g, float x, float y,
                                 float *n_x, float *n_y) {
  return phi_normal_int(g->data, (int)g->stride, p->nx, p->ny, p->inv_dx, p->inv_dy, p->inv_2dx,
                        p->inv_2dy, x, y, n_x, n_y);
}

/* Bilinear value of g at (x, y). */
PCL_INLINE float eval_phi(const lsm_particles *p, const lsm_grid *g, float x, float y) {
  float fx, fy;
  int i = lsm_pcl_locate(x, p->nx, &fx), j = lsm_pcl_locate(y, p->ny, &fy);
  return lsm_pcl_bilinear(LSM_AT(g, i, j), LSM_AT(g, i + 1, j), LSM_AT(g, i, j + 1),
                          LSM_AT(g, i + 1, j + 1), fx, fy);
}

/* The stage's node field: F = phi - phi_target and grad phi by central
 * differences (one-sided at the grid edge, as in lsm_pcl_phi_normal).  One
 * vectorisable pass over the grid; each particle then needs three bilinear
 * interpolations from one 4-node neighbourhood instead of a 4x4 stencil. */
/* One row j of the node field (lsm_pcl_node_field at every node; branch-free,
 * so it vectorises). */
PCL_CLONES
static void velocity_row(float *restrict F, float *restrict gx, float *restrict gy,
                         const float *restrict c, const float *restrict t,
                         const float *restrict dn, const float *restrict up, int j,
                         const lsm_particles *p) {
  const int nx = p->nx, ny = p->ny;
  const float idx = p->inv_dx, idy = p->inv_dy, i2dx = p->inv_2dx, i2dy = p->inv_2dy;
  for (int i = 1; i < nx - 1; ++i) /* interior columns: no clamping */
    lsm_pcl_node_field(i, j, nx, ny, c[i], t[i], c[i - 1], c[i + 1], dn[i], up[i], idx, idy, i2dx,
                       i2dy, &F[i], &gx[i], &gy[i]);
  for (int i = 0; i < nx; i += nx > 1 ? nx - 1 : 1) { /* the two edge columns */
    const int l = i > 0 ? i - 1 : 0, r = i + 1 < nx ? i + 1 : nx - 1;
    lsm_pcl_node_field(i, j, nx, ny, c[i], t[i], c[l], c[r], dn[i], up[i], idx, idy, i2dx, i2dy,
                       &F[i], &gx[i], &gy[i]);
  }
}

static void build_velocity(lsm_particles *p, const lsm_grid *in, const lsm_grid *target, int nt) {
  const int nx = p->nx, ny = p->ny;
#pragma omp parallel for num_threads(nt) schedule(static)
  for (int j = 0; j < ny; ++j) {
    const float *c = &LSM_AT(in, 0, j), *t = &LSM_AT(target, 0, j);
    const float *dn = &LSM_AT(in, 0, j > 0 ? j - 1 : 0), *up = &LSM_AT(in, 0, j + 1 < ny ? j + 1 : ny - 1);
    const size_t row = (size_t)j * nx, plane = (size_t)nx * ny;
    velocity_row(p->velocity + row, p->velocity + plane + row, p->velocity + 2 * plane + row, c, t,
                 dn, up, j, p);
  }
}

static float clampf(float v, float lo, float hi) { return v < lo ? lo : (v > hi ? hi : v); }

/* ---- storage ------------------------------------------------------------------------ */

static lsm_status reserve(lsm_particles *p, size_t need, lsm_err *err) {
  if (need <= p->cap) return LSM_OK;
  size_t cap = p->cap + p->cap / 2;
  if (cap < need) cap = need;
  size_t fbytes, bbytes;
  if (!lsm_size_mul(cap, sizeof(float), &fbytes) || !lsm_size_mul(cap, 1, &bbytes))
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "particles: %zu particles overflow", need);
  float **fa[5] = {&p->x, &p->y, &p->x0, &p->y0, &p->radius};
  for (int k = 0; k < 5; ++k) {
    float *q = realloc(*fa[k], fbytes);
    if (!q) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "particles: cannot allocate %zu particles", cap);
    *fa[k] = q;
  }
  int8_t *s = realloc(p->sign, bbytes);
  if (!s) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "particles: cannot allocate %zu particles", cap);
  p->sign = s;
  uint8_t *st = realloc(p->state, bbytes);
  if (!st) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "particles: cannot allocate %zu particles", cap);
  p->state = st;
  p->cap = cap;
  return LSM_OK;
}

/* Removes every particle with any of the given state bits, keeping the order;
 * returns the number removed. */
static size_t compact(lsm_particles *p, unsigned bits) {
  size_t w = 0;
  for (size_t k = 0; k < p->n; ++k) {
    if (p->state[k] & bits) continue;
    if (w != k) {
      p->x[w] = p->x[k];
      p->y[w] = p->y[k];
      p->x0[w] = p->x0[k];
      p->y0[w] = p->y0[k];
      p->radius[w] = p->radius[k];
      p->sign[w] = p->sign[k];
      p->state[w] = p->state[k];
    }
    ++w;
  }
  size_t removed = p->n - w;
  p->n = w;
  return removed;
}

/* ---- seeding (Algorithm 3.2) -------------------------------------------------------- */

static int is_band_cell(const lsm_particles *p, const lsm_grid *phi, int i, int j) {
  return lsm_pcl_band_cell(LSM_AT(phi, i, j), LSM_AT(phi, i + 1, j), LSM_AT(phi, i, j + 1),
                           LSM_AT(phi, i + 1, j + 1), p->band);
}

/* Attracts particle k to its band on phi; returns 1 on success (position and
 * radius stored), 0 when it should be discarded. */
static int attract(const lsm_particles *p, const lsm_grid *phi, size_t k, float goal) {
  const int s = p->sign[k];
  float px = p->x[k], py = p->y[k], n_x, n_y;
  float ph = eval_phi_normal(p, phi, px, py, &n_x, &n_y);
  for (int it = 0; it < ATTRACT_ITERS; ++it) {
    float step = goal - ph, lambda = 1.0f, qx = px, qy = py;
    for (int h = 0; h <= MAX_HALVINGS; ++h, lambda *= 0.5f) {
      qx = px + lambda * step * n_x * p->inv_dx;
      qy = py + lambda * step * n_y * p->inv_dy;
      if (lsm_pcl_in_domain(qx, qy, p->nx, p->ny)) break;
    }
    px = clampf(qx, 0.0f, (float)(p->nx - 1));
    py = clampf(qy, 0.0f, (float)(p->ny - 1));
    ph = eval_phi_normal(p, phi, px, py, &n_x, &n_y);
    if (lsm_pcl_in_band(s, ph, p->vmin, p->vmax)) {
      p->x[k] = p->x0[k] = px;
      p->y[k] = p->y0[k] = py;
      p->radius[k] = lsm_pcl_radius(s, ph, p->rmin, p->rmax);
      return 1;
    }
  }
  return 0;
}

/* The first attraction step of every particle at once (vectorised): the
 * same arithmetic as attract's first iteration with lambda = 1.  A particle
 * whose full step stays in the domain and lands in its band is done (position
 * and radius stored, state 0); any other gets PCL_RETRY and goes through
 * attract from its seeded position (which it then repeats exactly). */
enum { PCL_RETRY = 16u };

PCL_CLONES
static void attract_first(int n, float *restrict x, float *restrict y, float *restrict x0,
                          float *restrict y0, float *restrict radius, const int8_t *restrict sign,
                          uint8_t *restrict state, const lsm_grid *phi, const lsm_particles *p) {
  const int nx = p->nx, ny = p->ny, stride = (int)phi->stride;
  const float *restrict g = phi->data;
  const float inv_dx = p->inv_dx, inv_dy = p->inv_dy, inv_2dx = p->inv_2dx, inv_2dy = p->inv_2dy;
  const float vmin = p->vmin, vmax = p->vmax, rmin = p->rmin, rmax = p->rmax;
#pragma omp simd
  for (int k = 0; k < n; ++k) {
    float n_x, n_y;
    const float px = x[k], py = y[k];
    const float ph0 = phi_normal_int(g, stride, nx, ny, inv_dx, inv_dy, inv_2dx, inv_2dy, px, py,
                                     &n_x, &n_y);
    const float step = radius[k] - ph0, lambda = 1.0f; /* radius holds the goal */
    const float qx = px + lambda * step * n_x * inv_dx;
    const float qy = py + lambda * step * n_y * inv_dy;
    const float ph1 = phi_normal_int(g, stride, nx, ny, inv_dx, inv_dy, inv_2dx, inv_2dy, qx, qy,
                                     &n_x, &n_y);
    /* in the domain, attract's clamp of (qx, qy) is the identity */
    const int ok = lsm_pcl_in_domain(qx, qy, nx, ny) & lsm_pcl_in_band(sign[k], ph1, vmin, vmax);
    const float xs = ok ? qx : px, ys = ok ? qy : py;
    x[k] = xs;
    y[k] = ys;
    x0[k] = xs;
    y0[k] = ys;
    radius[k] = ok ? lsm_pcl_radius(sign[k], ph1, rmin, rmax) : radius[k];
    state[k] = (uint8_t)(ok ? 0 : PCL_RETRY);
  }
}

/* Seeds the band of phi into an empty set (generation p->gen). */
static lsm_status seed(lsm_particles *p, const lsm_grid *phi, lsm_err *err) {
  p->n = 0;
  p->stats.band_cells = 0;
  if (p->nx < 2 || p->ny < 2) return LSM_OK;
  size_t cells = 0;
  for (int j = 0; j < p->ny - 1; ++j)
    for (int i = 0; i < p->nx - 1; ++i) cells += (size_t)is_band_cell(p, phi, i, j);
  const int ppc = p->opts.particles_per_cell, npos = ppc - ppc / 2;
  size_t total;
  if (!lsm_size_mul(cells, (size_t)ppc, &total) || total > (size_t)PTRDIFF_MAX / 8)
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "particles: %zu band cells x %d particles overflow",
                    cells, ppc);
  LSM_TRY(reserve(p, total, err));
  const uint64_t seedv = p->opts.seed, gen = p->gen;
  size_t k = 0;
  for (int j = 0; j < p->ny - 1; ++j)
    for (int i = 0; i < p->nx - 1; ++i) {
      if (!is_band_cell(p, phi, i, j)) continue;
      const uint64_t cell = (uint64_t)j * (uint64_t)p->nx + (uint64_t)i;
      for (int q = 0; q < ppc; ++q, ++k) {
        p->x[k] = p->x0[k] =
            lsm_pcl_seed_coord(i, lsm_pcl_uniform(seedv, gen, cell, (uint64_t)q, DRAW_X));
        p->y[k] = p->y0[k] =
            lsm_pcl_seed_coord(j, lsm_pcl_uniform(seedv, gen, cell, (uint64_t)q, DRAW_Y));
        p->sign[k] = q < npos ? 1 : -1;
        /* the radius slot holds phi_goal until attraction sets the radius */
        p->radius[k] = (float)p->sign[k] *
                       (p->vmin + lsm_pcl_uniform(seedv, gen, cell, (uint64_t)q, DRAW_GOAL) *
                                      (p->vmax - p->vmin));
        p->state[k] = 0;
      }
    }
  p->n = total;
  p->stats.band_cells = (long long)cells;
  p->stats.seeded += (long long)total;

  if (p->opts.skip_attraction) {
    /* seeding only: radius from phi at the seeded position */
    for (size_t q = 0; q < total; ++q)
      p->radius[q] = lsm_pcl_radius(p->sign[q], eval_phi(p, phi, p->x[q], p->y[q]), p->rmin,
                                    p->rmax);
    return LSM_OK;
  }
  /* Attraction: the first step of all particles in one vectorised pass,
   * then the full iteration for those it did not settle. */
  const ptrdiff_t n = (ptrdiff_t)total;
  const ptrdiff_t chunk = (ptrdiff_t)1 << 30;
  for (ptrdiff_t k0 = 0; k0 < n; k0 += chunk)
    attract_first((int)(n - k0 < chunk ? n - k0 : chunk), p->x + k0, p->y + k0, p->x0 + k0,
                  p->y0 + k0, p->radius + k0, p->sign + k0, p->state + k0, phi, p);
#pragma omp parallel for num_threads(pls_threads(p, total)) schedule(dynamic, 1024)
  for (ptrdiff_t q = 0; q < n; ++q)
    if (p->state[q] & PCL_RETRY)
      p->state[q] = attract(p, phi, (size_t)q, p->radius[q]) ? 0 : PCL_DROP;
  p->stats.discarded += (long long)compact(p, PCL_DROP);
  return LSM_OK;
}

/* ---- public API --------------------------------------------------------------------- */

void lsm_pls_destroy(lsm_particles **pp) {
  if (!pp || !*pp) return;
  lsm_particles *p = *pp;
  void *owned[] = {p->x,     p->y,     p->x0,       p->y0,   p->radius,  p->sign,
                   p->state, p->plus,  p->minus,    p->velocity, p->mark, p->escaped};
  for (size_t k = 0; k < sizeof owned / sizeof *owned; ++k) free(owned[k]);
  free(p);
  *pp = NULL;
}

lsm_status lsm_pls_create_empty(const lsm_grid *like, const lsm_pls_opts *o, lsm_particles **out,
                                lsm_err *err) {
  *out = NULL;
  lsm_pls_opts opts;
  if (o)
    opts = *o;
  else
    lsm_pls_opts_default(&opts);
  if (opts.particles_per_cell < 1 || opts.particles_per_cell > 1024)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "particles per cell %d must be in 1..1024",
                    opts.particles_per_cell);
  if (opts.reseed_every < 0)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "reseeding interval %d must be >= 0",
                    opts.reseed_every);
  if (opts.threads < 1) opts.threads = 1;
  size_t cells;
  /* The particle loops index the node field (4 floats per node) and phi's
   * rows with int offsets (32-bit index vectors in the vectorised loops). */
  if (!lsm_size_mul((size_t)like->nx, (size_t)like->ny, &cells) || cells > (size_t)INT_MAX / 4 ||
      (size_t)like->stride * (size_t)(like->ny + 1) > (size_t)INT_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "particles: grid %dx%d is too large for the particle level set (at most 2^29 nodes)", like->nx, like->ny);
  lsm_particles *p = calloc(1, sizeof *p);
  if (!p) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate a particle set");
  p->opts = opts;
  p->nx = like->nx;
  p->ny = like->ny;
  p->dx = like->dx;
  p->dy = like->dy;
  p->inv_dx = 1.0f / p->dx;
  p->inv_dy = 1.0f / p->dy;
  p->inv_2dx = 0.5f / p->dx;
  p->inv_2dy = 0.5f / p->dy;
  const float hmin = fminf(p->dx, p->dy), hmax = fmaxf(p->dx, p->dy);
  p->vmin = 0.1f * hmin;
  p->vmax = 3.0f * hmax;
  p->rmin = lsm_pcl_rmin(p->dx, p->dy);
  p->rmax = lsm_pcl_rmax(p->dx, p->dy);
  p->band = 3.0f * hmax;
  *out = p;
  return LSM_OK;
}

lsm_status lsm_pls_create(const lsm_grid *phi0, const lsm_pls_opts *o, lsm_particles **out,
                          lsm_err *err) {
  LSM_TRY(lsm_pls_create_empty(phi0, o, out, err));
  lsm_status st = seed(*out, phi0, err);
  if (st != LSM_OK) lsm_pls_destroy(out);
  return st;
}

/* The grid-sized scratch of stages and corrections, allocated on first use (a
 * set that only seeds, as lsm_morph's, needs none). */
static lsm_status scratch(lsm_particles *p, lsm_err *err) {
  if (p->velocity) return LSM_OK;
  const size_t cells = (size_t)p->nx * (size_t)p->ny; /* checked at creation */
  p->plus = lsm_alloc(cells, sizeof(float), err, "particle correction");
  p->minus = p->plus ? lsm_alloc(cells, sizeof(float), err, "particle correction") : NULL;
  p->mark = p->minus ? calloc(cells, 1) : NULL;
  p->velocity = p->mark ? lsm_alloc(cells, 3 * sizeof(float), err, "particle advection") : NULL;
  if (p->velocity) return LSM_OK;
  free(p->plus);
  free(p->minus);
  free(p->mark);
  p->plus = p->minus = NULL;
  p->mark = NULL;
  return lsm_fail(err, LSM_ERR_NOMEM, NULL, "particles: cannot allocate correction scratch");
}

void lsm_pls_begin_step(lsm_particles *p, int stages) {
  /* The copy x0 = x is made by the first stage's loop itself (it reads x
   * anyway), and only when a later stage will read x0. */
  p->keep_start = stages > 1;
}

/* The particle loops of a stage, written branch-free over plain arrays so the
 * compiler vectorises them (GCC function multi-versioning picks the AVX2 or
 * AVX-512 clone at load time, same arithmetic, no FMA contraction in C17).
 * The interpolations' loads stay scalar per lane, two neighbouring floats at
 * a time (load_pair): gather instructions were slower.  F and the unit normal
 * N at a particle come from the node field v (three planes: F, gx, gy),
 * bilinearly interpolated; the new position is lsm_pcl_stage_coord, as on
 * OpenCL. */
PCL_INLINE float float_bits(uint32_t bits) {
  float f;
  memcpy(&f, &bits, sizeof f);
  return f;
}

/* The two floats at p and p + 1 in one 64-bit load: the vectorised loops load
 * each lane's neighbours element by element, and in pairs that is half the
 * loads. */
PCL_INLINE void load_pair(const float *restrict p, float *first, float *second) {
  uint64_t bits;
  memcpy(&bits, p, sizeof bits);
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  *first = float_bits((uint32_t)(bits >> 32));
  *second = float_bits((uint32_t)bits);
#else
  *first = float_bits((uint32_t)bits);
  *second = float_bits((uint32_t)(bits >> 32));
#endif
}

PCL_INLINE void sample_velocity(const float *restrict v, int nx, int ny, float x, float y,
                                float *F, float *n_x, float *n_y) {
  float fx, fy;
  const int i = lsm_pcl_locate(x, nx, &fx), j = lsm_pcl_locate(y, ny, &fy);
  const int plane = nx * ny, a = j * nx + i, b = a + nx;
  float f00, f10, f01, f11, gx00, gx10, gx01, gx11, gy00, gy10, gy01, gy11;
  load_pair(v + a, &f00, &f10);
  load_pair(v + b, &f01, &f11);
  load_pair(v + plane + a, &gx00, &gx10);
  load_pair(v + plane + b, &gx01, &gx11);
  load_pair(v + 2 * plane + a, &gy00, &gy10);
  load_pair(v + 2 * plane + b, &gy01, &gy11);
  *F = lsm_pcl_bilinear(f00, f10, f01, f11, fx, fy);
  const float gx = lsm_pcl_bilinear(gx00, gx10, gx01, gx11, fx, fy);
  const float gy = lsm_pcl_bilinear(gy00, gy10, gy01, gy11, fx, fy);
  lsm_pcl_normal(gx, gy, n_x, n_y);
}

/* One particle's stage: x = c0 x0 + c1 (x + dt F N); returns 1 when the new
 * position left the domain.  A first stage (c0 = 0, c1 = 1) reads no x0, y0;
 * with keep_start it saves the start position there (for the later stages).
 * Called with literal first / keep_start, so each loop gets its own body. */
PCL_INLINE int advect_one(ptrdiff_t k, float *restrict px, float *restrict py,
                          float *restrict x0, float *restrict y0, int first, int keep_start,
                          const float *restrict v, int nx, int ny, float inv_dx, float inv_dy,
                          float c0, float c1, float dt) {
  const float x = px[k], y = py[k];
  float F, n_x, n_y;
  sample_velocity(v, nx, ny, x, y, &F, &n_x, &n_y);
  const float bx = first ? 0.0f : x0[k], by = first ? 0.0f : y0[k];
  if (first && keep_start) {
    x0[k] = x;
    y0[k] = y;
  }
  px[k] = lsm_pcl_stage_coord(c0, bx, c1, x, dt, F, n_x, inv_dx);
  py[k] = lsm_pcl_stage_coord(c0, by, c1, y, dt, F, n_y, inv_dy);
  return !lsm_pcl_in_domain(px[k], py[k], nx, ny);
}

PCL_CLONES
static int advect_first(ptrdiff_t n, float *restrict px, float *restrict py,
                        float *restrict x0, float *restrict y0, int keep_start,
                        const float *restrict v, int nx, int ny, float inv_dx, float inv_dy,
                        float dt, int nt) {
  int outside = 0;
  if (keep_start) {
#pragma omp parallel for simd num_threads(nt) schedule(static) reduction(| : outside)
    for (ptrdiff_t k = 0; k < n; ++k)
      outside |= advect_one(k, px, py, x0, y0, 1, 1, v, nx, ny, inv_dx, inv_dy, 0.0f, 1.0f, dt);
  } else {
#pragma omp parallel for simd num_threads(nt) schedule(static) reduction(| : outside)
    for (ptrdiff_t k = 0; k < n; ++k)
      outside |= advect_one(k, px, py, x0, y0, 1, 0, v, nx, ny, inv_dx, inv_dy, 0.0f, 1.0f, dt);
  }
  return outside;
}

PCL_CLONES
static int advect(ptrdiff_t n, float *restrict px, float *restrict py, float *restrict x0,
                  float *restrict y0, const float *restrict v, int nx, int ny, float inv_dx,
                  float inv_dy, float c0, float c1, float dt, int nt) {
  int outside = 0;
#pragma omp parallel for simd num_threads(nt) schedule(static) reduction(| : outside)
  for (ptrdiff_t k = 0; k < n; ++k)
    outside |= advect_one(k, px, py, x0, y0, 0, 0, v, nx, ny, inv_dx, inv_dy, c0, c1, dt);
  return outside;
}

lsm_status lsm_pls_stage(lsm_particles *p, const lsm_grid *in, const lsm_grid *phi_target,
                         float c0, float c1, float dt, lsm_err *err) {
  const ptrdiff_t n = (ptrdiff_t)p->n;
  const float hx = (float)(p->nx - 1), hy = (float)(p->ny - 1);
  if (n == 0) return LSM_OK;
  LSM_TRY(scratch(p, err));
  build_velocity(p, in, phi_target, (long)p->nx * p->ny < 65536L ? 1 : pls_threads(p, LSM_PLS_MIN_PARALLEL));
  const int nt = pls_threads(p, p->n);
  const int outside =
      c0 == 0.0f && c1 == 1.0f
          ? advect_first(n, p->x, p->y, p->x0, p->y0, p->keep_start, p->velocity, p->nx, p->ny,
                         p->inv_dx, p->inv_dy, dt, nt)
          : advect(n, p->x, p->y, p->x0, p->y0, p->velocity, p->nx, p->ny, p->inv_dx, p->inv_dy,
                   c0, c1, dt, nt);
  /* Particles that left the domain: flagged (removed at the next correction)
   * and clamped so later stages interpolate inside the grid; a NaN position
   * (never expected) is out of the domain too and parked at 0. */
  for (ptrdiff_t k = 0; outside && k < n; ++k) {
    const float xn = p->x[k], yn = p->y[k];
    if (!lsm_pcl_in_domain(xn, yn, p->nx, p->ny)) {
      if (!(p->state[k] & PCL_LEFT)) p->left_pending++;
      p->state[k] |= PCL_LEFT;
      p->x[k] = lsm_pcl_clamp_coord(xn, hx);
      p->y[k] = lsm_pcl_clamp_coord(yn, hy);
    }
  }
  return LSM_OK;
}

/* Escaped-particle detection (sign(phi(p)) != s_p and |phi(p)| > r_p),
 * branch-free so it vectorises; counts the escaped ones and the strays (int
 * counters keep the vector lanes 32-bit: at most 2^30 particles per call).
 * In blocks of two loops: the interpolation of phi touches only floats and
 * ints, so it vectorises at the full float width; the byte-sized sign and
 * state would otherwise narrow it to four lanes (no AVX512BW). */
PCL_CLONES
static void detect(int n, const float *restrict px, const float *restrict py,
                   const int8_t *restrict sign, const float *restrict radius,
                   uint8_t *restrict state, const lsm_grid *phi, float far, int *escaped,
                   int *strays, int nt) {
  enum { block = 512 };
  const int nx = phi->nx, ny = phi->ny;
  const int stride = (int)phi->stride; /* int offsets: 32-bit index lanes (checked at creation) */
  const float *restrict g = phi->data;
  const int blocks = (int)(((long)n + block - 1) / block);
  int count = 0, stray = 0;
#pragma omp parallel for num_threads(nt) schedule(static) reduction(+ : count, stray)
  for (int b0 = 0; b0 < blocks; ++b0) {
    float ph[block];
    const int k0 = b0 * block, m = n - k0 < block ? n - k0 : block;
#pragma omp simd
    for (int q = 0; q < m; ++q) {
      float fx, fy;
      const int i = lsm_pcl_locate(px[k0 + q], nx, &fx), j = lsm_pcl_locate(py[k0 + q], ny, &fy);
      const int a = j * stride + i, b = a + stride;
      float g00, g10, g01, g11;
      load_pair(g + a, &g00, &g10);
      load_pair(g + b, &g01, &g11);
      ph[q] = lsm_pcl_bilinear(g00, g10, g01, g11, fx, fy);
    }
#pragma omp simd reduction(+ : count, stray)
    for (int q = 0; q < m; ++q) {
      const int k = k0 + q;
      const int e = lsm_pcl_escaped(sign[k], ph[q], radius[k]);
      /* Escaped by more than `far`: the front has left this particle behind
       * (it no longer marks the interface), and correcting from it would plant
       * a speck of the wrong sign; it is removed instead, as PLS codes do. */
      const int lost = lsm_pcl_stray(e, ph[q], far);
      state[k] = (uint8_t)(lost ? PCL_LEFT : (e ? PCL_ESCAPED : 0));
      count += e && !lost;
      stray += lost;
    }
  }
  *escaped = count;
  *strays = stray;
}

void lsm_pls_count_correction(lsm_pls_stats *q, long long removed, long long strays,
                              long long escaped, long long corrected) {
  q->left_domain += removed;
  q->stray += strays;
  q->escaped_last = escaped;
  q->corrected_last = corrected;
  q->escaped_total += escaped;
  q->corrected_total += corrected;
  q->steps++;
}

lsm_status lsm_pls_correct_into(lsm_particles *p, lsm_grid *phi, lsm_pls_stats *stats,
                                lsm_err *err) {
  if (phi->nx != p->nx || phi->ny != p->ny)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "particles: grid %dx%d, particles seeded on %dx%d",
                    phi->nx, phi->ny, p->nx, p->ny);
  LSM_TRY(scratch(p, err));
  long long removed = 0;
  if (p->left_pending) {
    removed = (long long)compact(p, PCL_LEFT);
    p->left_pending = 0;
  }
  const ptrdiff_t n = (ptrdiff_t)p->n;
  const int nt = pls_threads(p, p->n);

  /* 1. detection (parallel, vectorised; each particle writes its own flag) */
  long long strays = 0, found = 0;
  const float far = lsm_pcl_far(p->dx, p->dy);
  const ptrdiff_t chunk = (ptrdiff_t)1 << 30;
  for (ptrdiff_t k0 = 0; k0 < n; k0 += chunk) {
    const int m = (int)(n - k0 < chunk ? n - k0 : chunk);
    int e = 0, s = 0;
    detect(m, p->x + k0, p->y + k0, p->sign + k0, p->radius + k0, p->state + k0, phi, far, &e, &s,
           nt);
    found += e;
    strays += s;
  }
  p->left_pending += (size_t)strays;

  /* The escaped particles, in particle order (few: a scan of the flags,
   * eight at a time where none of them is set). */
  size_t escaped = 0;
  if (found > 0) {
    if ((size_t)found > p->escaped_cap) {
      size_t *q = realloc(p->escaped, (size_t)found * sizeof *q);
      if (!q) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "particles: cannot list %lld escaped", found);
      p->escaped = q;
      p->escaped_cap = (size_t)found;
    }
    const uint64_t any_escaped = 0x0101010101010101u * PCL_ESCAPED;
    for (ptrdiff_t k = 0; k < n && escaped < (size_t)found;) {
      uint64_t word;
      if (k + 8 <= n && (memcpy(&word, p->state + k, sizeof word), !(word & any_escaped))) {
        k += 8;
        continue;
      }
      if (p->state[k] & PCL_ESCAPED) {
        p->state[k] &= (uint8_t)~PCL_ESCAPED;
        p->escaped[escaped++] = (size_t)k;
      }
      ++k;
    }
  }

  /* 2. phi_plus / phi_minus at the corners of escaped particles (serial, in
   *    particle order; max/min make the order irrelevant anyway).  phi itself
   *    is not written until every particle has been seen. */
  long long corrected = 0;
  const int nx = p->nx;
  for (size_t e = 0; e < escaped; ++e) {
    const size_t k = p->escaped[e];
    const int s = p->sign[k];
    const float r = p->radius[k], x = p->x[k], y = p->y[k];
    float fx, fy;
    const int i = lsm_pcl_locate(x, p->nx, &fx), j = lsm_pcl_locate(y, p->ny, &fy);
    for (int b = 0; b < 2; ++b)
      for (int a = 0; a < 2; ++a) {
        const size_t idx = (size_t)(j + b) * (size_t)nx + (size_t)(i + a);
        const float pv = LSM_AT(phi, i + a, j + b);
        if (!p->mark[idx]) {
          p->mark[idx] = 1;
          p->plus[idx] = p->minus[idx] = pv;
        }
        const float d = lsm_pcl_distance((float)(i + a) - x, (float)(j + b) - y, p->dx, p->dy);
        const float v = lsm_pcl_corner_value(s, r, pv, d);
        if (s > 0)
          p->plus[idx] = lsm_pcl_merge(s, p->plus[idx], v);
        else
          p->minus[idx] = lsm_pcl_merge(s, p->minus[idx], v);
      }
  }

  /* 3. Eq. 3.26 at every touched corner (each once: its mark is cleared). */
  for (size_t e = 0; e < escaped; ++e) {
    const size_t k = p->escaped[e];
    float fx, fy;
    const int i = lsm_pcl_locate(p->x[k], p->nx, &fx), j = lsm_pcl_locate(p->y[k], p->ny, &fy);
    for (int b = 0; b < 2; ++b)
      for (int a = 0; a < 2; ++a) {
        const size_t idx = (size_t)(j + b) * (size_t)nx + (size_t)(i + a);
        if (!p->mark[idx]) continue;
        p->mark[idx] = 0;
        const float v = lsm_pcl_select(p->plus[idx], p->minus[idx]);
        float *cell = &LSM_AT(phi, i + a, j + b);
        if (v != *cell) {
          *cell = v;
          ++corrected;
        }
      }
  }

  /* 4. radius adjustment on the corrected phi (option) */
  if (p->opts.radius_adjust) {
#pragma omp parallel for num_threads(nt) schedule(static)
    for (ptrdiff_t k = 0; k < n; ++k) {
      const int s = p->sign[k];
      const float ph = eval_phi(p, phi, p->x[k], p->y[k]);
      if (lsm_pcl_own_side(s, ph))
        p->radius[k] = lsm_pcl_radius(s, ph, p->rmin, p->rmax);
    }
  }

  lsm_pls_count_correction(stats, removed, strays, (long long)escaped, corrected);
  lsm_grid_fill_ghosts(phi);
  return LSM_OK;
}

lsm_status lsm_pls_correct(lsm_particles *p, lsm_grid *phi, lsm_err *err) {
  LSM_TRY(lsm_pls_correct_into(p, phi, &p->stats, err));
  /* 5. reseeding (option) */
  if (p->opts.reseed_every > 0 && p->stats.steps % p->opts.reseed_every == 0)
    return lsm_pls_reseed(p, phi, err);
  return LSM_OK;
}

lsm_status lsm_pls_reseed(lsm_particles *p, const lsm_grid *phi, lsm_err *err) {
  if (phi->nx != p->nx || phi->ny != p->ny)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "particles: grid %dx%d, particles seeded on %dx%d",
                    phi->nx, phi->ny, p->nx, p->ny);
  if (p->left_pending) { /* flagged to leave by the last correction: counted as such */
    p->stats.left_domain += (long long)compact(p, PCL_LEFT);
    p->left_pending = 0;
  }
  p->stats.reseed_dropped += (long long)p->n;
  p->n = 0;
  p->gen++;
  p->stats.reseeds++;
  return seed(p, phi, err);
}

const lsm_pls_stats *lsm_pls_stats_get(const lsm_particles *p) { return &p->stats; }

size_t lsm_pls_count(const lsm_particles *p) { return p->n; }

lsm_pls_view lsm_pls_view_get(const lsm_particles *p) {
  lsm_pls_view v = {p->n, p->x, p->y, p->radius, p->sign};
  return v;
}

lsm_status lsm_pls_set(lsm_particles *p, size_t n, const float *x, const float *y,
                       const int8_t *sign, const float *radius, lsm_err *err) {
  if (n > 0 && (p->nx < 2 || p->ny < 2))
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "particles: a %dx%d grid has no cells", p->nx, p->ny);
  for (size_t k = 0; k < n; ++k) {
    if (sign[k] != 1 && sign[k] != -1)
      return lsm_fail(err, LSM_ERR_USAGE, NULL, "particle %zu: sign %d is not +-1", k, sign[k]);
    if (!isfinite(x[k]) || !isfinite(y[k]) || !isfinite(radius[k]))
      return lsm_fail(err, LSM_ERR_USAGE, NULL, "particle %zu: value not finite", k);
  }
  LSM_TRY(reserve(p, n, err));
  const float hx = (float)(p->nx - 1), hy = (float)(p->ny - 1);
  for (size_t k = 0; k < n; ++k) {
    p->x[k] = p->x0[k] = clampf(x[k], 0.0f, hx);
    p->y[k] = p->y0[k] = clampf(y[k], 0.0f, hy);
    p->sign[k] = sign[k];
    p->radius[k] = radius[k];
    p->state[k] = 0;
  }
  p->n = n;
  p->left_pending = 0;
  return LSM_OK;
}
