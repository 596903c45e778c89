/* lsm_motion: the correspondence field of a slice pair (see the header). */
#include "solver/motion/lsm_motion.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "kernels/lsm_motion_cell.h"
#include "solver/base/lsm_clock.h"

void lsm_motion_params_default(lsm_motion_params *p) {
  memset(p, 0, sizeof *p);
  p->levels = 3;
  p->step[0] = 8;
  p->step[1] = 4;
  p->step[2] = 2;
  p->iterations[0] = 50;
  p->iterations[1] = 50;
  p->iterations[2] = 30;
  p->clip_nodes = 5.0;
  p->sigma_update_px = 1.0;
  p->sigma_field_px = 6.0;
  p->stop_window = 5;
  p->stop_drop = 0.01;
}

/* Threads worth using on n nodes (below 2^16 a parallel region costs more than it saves). */
static int node_threads(size_t n, int threads) { return n < 65536u || threads < 1 ? 1 : threads; }

/* Nodes spaced `step` covering cells 0 .. cells - 1. */
static int nodes_over(int cells, int step) { return (cells - 1 + step - 1) / step + 1; }

/* ---- maps ------------------------------------------------------------------------------ */

int lsm_motion_squarings(float most2, float t, float *scale) {
  float most = sqrtf(most2);
  int K = 0;
  while (most > 0.5f && K < 40) { /* each of the 2^K steps within half a node */
    most *= 0.5f;
    ++K;
  }
  *scale = ldexpf(t, -K);
  return K;
}

/* exp(t v) on an nx x ny grid into (dx, dy), scaling and squaring; (sx, sy) scratch. */
static void exp_planes(const float *vx, const float *vy, float t, int nx, int ny, float *dx,
                       float *dy, float *sx, float *sy, int threads) {
  const size_t n = (size_t)nx * (size_t)ny;
  float most = 0.0f;
  for (size_t k = 0; k < n; ++k) {
    const float m = lsm_motion_norm2(t, vx[k], vy[k]);
    if (m > most) most = m;
  }
  float scale;
  const int K = lsm_motion_squarings(most, t, &scale);
  for (size_t k = 0; k < n; ++k) {
    dx[k] = scale * vx[k];
    dy[k] = scale * vy[k];
  }
  float *ax = dx, *ay = dy, *bx = sx, *by = sy;
  const int nt = node_threads(n, threads);
  for (int q = 0; q < K; ++q) {
#pragma omp parallel for num_threads(nt) schedule(static)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        bx[(size_t)j * nx + i] = lsm_motion_square(ax, ay, nx, ny, i, j, 0);
        by[(size_t)j * nx + i] = lsm_motion_square(ax, ay, nx, ny, i, j, 1);
      }
    float *tx = ax, *ty = ay;
    ax = bx;
    ay = by;
    bx = tx;
    by = ty;
  }
  if (ax != dx) {
    memcpy(dx, ax, n * sizeof *dx);
    memcpy(dy, ay, n * sizeof *dy);
  }
}

/* ---- the registration ------------------------------------------------------------------ */

/* A Gaussian of sigma nodes, truncated at 3 sigma and normalised; radius 0 (no smoothing)
 * below a fifth of a node. */
static int gauss_kernel(double sigma, float *kern, int most) {
  if (!(sigma >= 0.2)) return 0;
  int radius = (int)ceil(3.0 * sigma);
  if (radius > most) radius = most;
  double sum = 0.0, w[2 * 64 + 1];
  for (int t = -radius; t <= radius; ++t) sum += w[t + radius] = exp(-0.5 * t * t / (sigma * sigma));
  for (int t = 0; t <= 2 * radius; ++t) kern[t] = (float)(w[t] / sum);
  return radius;
}

/* Both planes of a vector field smoothed in place (tmp: one plane of scratch per component). */
static void blur_field(float *fx, float *fy, float *tx, float *ty, int nx, int ny,
                       const float *kern, int radius, int threads) {
  if (radius == 0) return;
  const int nt = node_threads((size_t)nx * (size_t)ny, threads);
#pragma omp parallel for num_threads(nt) schedule(static)
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      tx[(size_t)j * nx + i] = lsm_motion_blur(fx, nx, ny, i, j, 0, kern, radius);
      ty[(size_t)j * nx + i] = lsm_motion_blur(fy, nx, ny, i, j, 0, kern, radius);
    }
#pragma omp parallel for num_threads(nt) schedule(static)
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      fx[(size_t)j * nx + i] = lsm_motion_blur(tx, nx, ny, i, j, 1, kern, radius);
      fy[(size_t)j * nx + i] = lsm_motion_blur(ty, nx, ny, i, j, 1, kern, radius);
    }
}

/* The planes one registration needs, sized for its finest level. */
enum { P_A, P_B, P_WX, P_WY, P_UX, P_UY, P_TX, P_TY, P_PX, P_PY, P_MX, P_MY, P_SX, P_SY,
       P_WA, P_WB, P_R, P_C, P_COUNT };

/* phi sampled at the nodes of a level (node (I, J) at cell (I step, J step), clamped to the
 * interior), clipped to +-clip. */
static void sample_level(const lsm_grid *phi, int step, int nx, int ny, float clip, float *out) {
  for (int j = 0; j < ny; ++j) {
    const int cj = j * step < phi->ny ? j * step : phi->ny - 1;
    for (int i = 0; i < nx; ++i) {
      const int ci = i * step < phi->nx ? i * step : phi->nx - 1;
      out[(size_t)j * nx + i] = lsm_motion_clip(LSM_AT(phi, ci, cj), clip);
    }
  }
}

void lsm_motion_mismatch(const float *r2, const float *c, int nx, int ny, double *sum,
                         double *count) {
  *sum = 0.0;
  *count = 0.0;
  for (int j = 0; j < ny; ++j) {
    double row = 0.0, active = 0.0;
    for (int i = 0; i < nx; ++i) {
      row += r2[(size_t)j * nx + i];
      active += c[(size_t)j * nx + i];
    }
    *sum += row;
    *count += active;
  }
}

int lsm_motion_level_stops(const lsm_motion_level *lv, double *history, int it, double sum,
                           double count) {
  history[it] = count > 0.0 ? sum / count : 0.0;
  if (count == 0.0) return 1; /* nothing to register */
  return it >= lv->stop_window &&
         history[it] > (1.0 - lv->stop_drop) * history[it - lv->stop_window];
}

/* One level's iterations on the host (lsm_motion_level; pl: the planes, lv's among them). */
static int run_level(float *const *pl, const lsm_motion_level *lv, int threads) {
  const int nx = lv->nx, ny = lv->ny;
  const size_t n = (size_t)nx * (size_t)ny;
  const int nt = node_threads(n, threads);
  double history[LSM_MOTION_ITERATIONS_MAX];
  int it = 0;
  for (; it < lv->iterations; ++it) {
    exp_planes(pl[P_WX], pl[P_WY], 0.5f, nx, ny, pl[P_PX], pl[P_PY], pl[P_SX], pl[P_SY], threads);
    exp_planes(pl[P_WX], pl[P_WY], -0.5f, nx, ny, pl[P_MX], pl[P_MY], pl[P_SX], pl[P_SY], threads);
#pragma omp parallel for num_threads(nt) schedule(static)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        pl[P_WA][(size_t)j * nx + i] = lsm_motion_warp(pl[P_A], pl[P_MX], pl[P_MY], nx, ny, i, j);
        pl[P_WB][(size_t)j * nx + i] = lsm_motion_warp(pl[P_B], pl[P_PX], pl[P_PY], nx, ny, i, j);
      }
#pragma omp parallel for num_threads(nt) schedule(static)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const size_t k = (size_t)j * nx + i;
        pl[P_R][k] = lsm_motion_demons(pl[P_WA], pl[P_WB], nx, ny, i, j, lv->hx, lv->hy,
                                       lv->clip, &pl[P_UX][k], &pl[P_UY][k]);
        pl[P_C][k] = (float)lsm_motion_active(pl[P_WA][k], pl[P_WB][k], lv->clip);
      }
    double sum, count;
    lsm_motion_mismatch(pl[P_R], pl[P_C], nx, ny, &sum, &count);
    if (lsm_motion_level_stops(lv, history, it, sum, count)) break;
    blur_field(pl[P_UX], pl[P_UY], pl[P_TX], pl[P_TY], nx, ny, lv->ku, lv->ru, threads);
    for (size_t k = 0; k < n; ++k) {
      pl[P_WX][k] += pl[P_UX][k];
      pl[P_WY][k] += pl[P_UY][k];
    }
    blur_field(pl[P_WX], pl[P_WY], pl[P_TX], pl[P_TY], nx, ny, lv->kw, lv->rw, threads);
  }
  return it;
}

/* The field of a coarser level (step sc, grid cnx x cny) read at the nodes of a finer one
 * (step sf): bilinear, rescaled to the finer node unit. */
static void upsample(const float *cx, const float *cy, int cnx, int cny, int sc, float *fx,
                     float *fy, int fnx, int fny, int sf) {
  const float ratio = (float)sf / (float)sc, gain = (float)sc / (float)sf;
  for (int j = 0; j < fny; ++j)
    for (int i = 0; i < fnx; ++i) {
      fx[(size_t)j * fnx + i] = lsm_motion_upsample_at(cx, cnx, cny, ratio, gain, i, j);
      fy[(size_t)j * fnx + i] = lsm_motion_upsample_at(cy, cnx, cny, ratio, gain, i, j);
    }
}

static lsm_status field_alloc(int cnx, int cny, int step, lsm_motion_field **out, lsm_err *err) {
  lsm_motion_field *f = lsm_alloc(1, sizeof *f, err, "motion field");
  if (!f) return err ? err->status : LSM_ERR_NOMEM;
  memset(f, 0, sizeof *f);
  f->step = step;
  f->cnx = cnx;
  f->cny = cny;
  f->nx = nodes_over(cnx, step);
  f->ny = nodes_over(cny, step);
  const size_t n = (size_t)f->nx * (size_t)f->ny;
  f->vx = lsm_alloc(n, 2 * sizeof(float), err, "motion field");
  if (!f->vx) {
    free(f);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  f->vy = f->vx + n;
  memset(f->vx, 0, n * 2 * sizeof(float));
  *out = f;
  return LSM_OK;
}

void lsm_motion_field_destroy(lsm_motion_field **f) {
  if (!f || !*f) return;
  free((*f)->vx);
  free(*f);
  *f = NULL;
}

lsm_status lsm_motion_field_zero(const lsm_grid *phi, int step, lsm_motion_field **out,
                                 lsm_err *err) {
  return field_alloc(phi->nx, phi->ny, step < 1 ? 1 : step, out, err);
}

lsm_status lsm_motion_field_clone(const lsm_motion_field *f, lsm_motion_field **out,
                                  lsm_err *err) {
  LSM_TRY(field_alloc(f->cnx, f->cny, f->step, out, err));
  lsm_motion_field *c = *out;
  const size_t n = (size_t)f->nx * (size_t)f->ny;
  memcpy(c->vx, f->vx, n * sizeof(float));
  memcpy(c->vy, f->vy, n * sizeof(float));
  c->iterations = f->iterations;
  c->seconds = f->seconds;
  c->max_displacement = f->max_displacement;
  return LSM_OK;
}

lsm_status lsm_motion_register(const lsm_grid *phi_a, const lsm_grid *phi_b,
                               const lsm_motion_params *p, int threads, lsm_motion_field **out,
                               lsm_err *err) {
  const double t0 = lsm_clock_seconds();
  *out = NULL;
  const int levels = p->levels < 1 ? 1 : p->levels > LSM_MOTION_LEVELS_MAX ? LSM_MOTION_LEVELS_MAX
                                                                           : p->levels;
  const int cnx = phi_a->nx, cny = phi_a->ny, finest = p->step[levels - 1];
  LSM_TRY(field_alloc(cnx, cny, finest, out, err));
  lsm_motion_field *f = *out;
  const size_t n = (size_t)f->nx * (size_t)f->ny;
  float *pool = lsm_alloc(n, P_COUNT * sizeof(float), err, "registration planes");
  if (!pool) {
    lsm_motion_field_destroy(out);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  float *pl[P_COUNT];
  for (int q = 0; q < P_COUNT; ++q) pl[q] = pool + (size_t)q * n;
  int pnx = 0, pny = 0, pstep = 0;
  lsm_status st = LSM_OK;
  for (int l = 0; l < levels && st == LSM_OK; ++l) {
    const int step = p->step[l];
    const int nx = nodes_over(cnx, step), ny = nodes_over(cny, step);
    const float hx = phi_a->dx * (float)step, hy = phi_a->dy * (float)step;
    const float clip = (float)p->clip_nodes * (hx < hy ? hx : hy);
    sample_level(phi_a, step, nx, ny, clip, pl[P_A]);
    sample_level(phi_b, step, nx, ny, clip, pl[P_B]);
    if (l == 0) {
      memset(pl[P_WX], 0, (size_t)nx * ny * sizeof(float));
      memset(pl[P_WY], 0, (size_t)nx * ny * sizeof(float));
    } else {
      /* the coarser field moves to the scratch planes first (they may overlap the new grid) */
      memcpy(pl[P_SX], pl[P_WX], (size_t)pnx * pny * sizeof(float));
      memcpy(pl[P_SY], pl[P_WY], (size_t)pnx * pny * sizeof(float));
      upsample(pl[P_SX], pl[P_SY], pnx, pny, pstep, pl[P_WX], pl[P_WY], nx, ny, step);
    }
    float ku[2 * 64 + 1], kw[2 * 64 + 1];
    lsm_motion_level lv = {.nx = nx, .ny = ny, .hx = hx, .hy = hy, .clip = clip,
                           .a = pl[P_A], .b = pl[P_B], .wx = pl[P_WX], .wy = pl[P_WY],
                           .ku = ku, .kw = kw,
                           .ru = gauss_kernel(p->sigma_update_px / step, ku, 64),
                           .rw = gauss_kernel(p->sigma_field_px / step, kw, 64),
                           .iterations = p->iterations[l] < LSM_MOTION_ITERATIONS_MAX
                                             ? p->iterations[l] : LSM_MOTION_ITERATIONS_MAX,
                           .stop_window = p->stop_window, .stop_drop = p->stop_drop};
    int it = 0;
    if (p->device.run_level) st = p->device.run_level(p->device.ctx, &lv, &it, err);
    else it = run_level(pl, &lv, threads);
    f->iterations += it;
    pnx = nx;
    pny = ny;
    pstep = step;
  }
  if (st == LSM_OK) {
    memcpy(f->vx, pl[P_WX], n * sizeof(float));
    memcpy(f->vy, pl[P_WY], n * sizeof(float));
    exp_planes(f->vx, f->vy, 1.0f, f->nx, f->ny, pl[P_PX], pl[P_PY], pl[P_SX], pl[P_SY], threads);
    double most = 0.0;
    for (size_t k = 0; k < n; ++k) {
      const double d = hypot(pl[P_PX][k] * phi_a->dx, pl[P_PY][k] * phi_a->dy) * finest;
      if (d > most) most = d;
    }
    f->max_displacement = most / (phi_a->dx < phi_a->dy ? phi_a->dx : phi_a->dy);
  }
  free(pool);
  if (st != LSM_OK) lsm_motion_field_destroy(out);
  else f->seconds = lsm_clock_seconds() - t0;
  return st;
}

/* ---- maps of a field ---------------------------------------------------------------------- */

lsm_status lsm_motion_map_create(const lsm_motion_field *f, lsm_motion_map *m, lsm_err *err) {
  const size_t n = (size_t)f->nx * (size_t)f->ny;
  m->nx = f->nx;
  m->ny = f->ny;
  m->step = f->step;
  m->dx = lsm_alloc(n, 2 * sizeof(float), err, "motion map");
  if (!m->dx) return err ? err->status : LSM_ERR_NOMEM;
  m->dy = m->dx + n;
  memset(m->dx, 0, 2 * n * sizeof(float));
  return LSM_OK;
}

void lsm_motion_map_free(lsm_motion_map *m) {
  free(m->dx);
  m->dx = m->dy = NULL;
}

void lsm_motion_exp(const lsm_motion_field *f, double t, lsm_motion_map *m,
                    lsm_motion_map *scratch, int threads) {
  exp_planes(f->vx, f->vy, (float)t, f->nx, f->ny, m->dx, m->dy, scratch->dx, scratch->dy,
             threads);
}

void lsm_motion_compose(const lsm_motion_map *first, const lsm_motion_map *second,
                        lsm_motion_map *out, int threads) {
  const int nx = first->nx, ny = first->ny;
  const int nt = node_threads((size_t)nx * (size_t)ny, threads);
#pragma omp parallel for num_threads(nt) schedule(static)
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      out->dx[(size_t)j * nx + i] =
          lsm_motion_compose_at(first->dx, first->dy, second->dx, nx, ny, i, j, 0);
      out->dy[(size_t)j * nx + i] =
          lsm_motion_compose_at(first->dx, first->dy, second->dy, nx, ny, i, j, 1);
    }
}

void lsm_motion_map_at(const lsm_motion_map *m, float x, float y, float *dx, float *dy) {
  const float inv = 1.0f / (float)m->step, s = (float)m->step;
  *dx = s * lsm_bilinear(m->dx, m->nx, m->ny, x * inv, y * inv);
  *dy = s * lsm_bilinear(m->dy, m->nx, m->ny, x * inv, y * inv);
}

void lsm_motion_velocity_at(const lsm_motion_field *f, float x, float y, float *vx, float *vy) {
  const float inv = 1.0f / (float)f->step, s = (float)f->step;
  *vx = s * lsm_bilinear(f->vx, f->nx, f->ny, x * inv, y * inv);
  *vy = s * lsm_bilinear(f->vy, f->nx, f->ny, x * inv, y * inv);
}

void lsm_motion_pull(const lsm_grid *src, const lsm_motion_map *m, lsm_grid *dst, int threads) {
  const int nt = node_threads((size_t)dst->nx * (size_t)dst->ny, threads);
  const float inv = 1.0f / (float)m->step, s = (float)m->step;
#pragma omp parallel for num_threads(nt) schedule(static)
  for (int j = 0; j < dst->ny; ++j)
    for (int i = 0; i < dst->nx; ++i) {
      const float x = (float)i * inv, y = (float)j * inv;
      const float px = (float)i + s * lsm_bilinear(m->dx, m->nx, m->ny, x, y);
      const float py = (float)j + s * lsm_bilinear(m->dy, m->nx, m->ny, x, y);
      LSM_AT(dst, i, j) = lsm_bilinear_strided(src->data, src->stride, src->nx, src->ny, px, py);
    }
  lsm_grid_fill_ghosts(dst);
}
