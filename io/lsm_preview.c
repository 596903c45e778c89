/* lsm_preview: montage of sample slices and a ray-marched rendering of the
 * surface (see lsm_preview.h). */
#include "io/lsm_preview.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/lsm_io.h"

#define KEEP_MAX 64   /* thumbnails kept (even) */
#define SHOW_MAX 16   /* thumbnails shown */
#define THUMB_MAX 200 /* longest thumbnail side before upscaling */
#define THUMB_MIN 96  /* small slices are enlarged to about this */

typedef struct thumb {
  uint8_t *cov; /* tw * th coverage, 0..255 */
  size_t index; /* output slice number, from 0 */
  long input;   /* input index or -1 */
  double z;
} thumb;

struct lsm_preview {
  int nx, ny;
  double sx, sy;
  /* montage */
  int g, tw, th; /* thumbnail decimation and size */
  thumb kept[KEEP_MAX];
  int nkept;
  thumb last;
  size_t stride;
  size_t count;
  /* decimated volume */
  int f, dnx, dny;
  size_t plane_n;
  float *vol; /* LSM_PREVIEW_Z planes of dnx * dny */
  int nplanes;
  double z0, step;
  float *prev, *cur;
  double prev_z;
};

/* ---- set-up ----------------------------------------------------------------------------------- */

lsm_status lsm_preview_open(int nx, int ny, double sx, double sy, double dz, lsm_preview **out,
                            lsm_err *err) {
  if (out) *out = NULL;
  if (!out) return lsm_fail(err, LSM_ERR_INTERNAL, "preview", "bad arguments");
  if (nx <= 0 || ny <= 0)
    return lsm_fail(err, LSM_ERR_INPUT, "preview", "slice size %dx%d is not positive", nx, ny);
  if (!(isfinite(sx) && sx > 0 && isfinite(sy) && sy > 0))
    return lsm_fail(err, LSM_ERR_INPUT, "preview", "pixel size %g x %g must be positive", sx, sy);
  (void)dz;
  lsm_preview *p = calloc(1, sizeof *p);
  if (!p) return lsm_fail(err, LSM_ERR_NOMEM, "preview", "cannot allocate the preview");
  p->nx = nx;
  p->ny = ny;
  p->sx = sx;
  p->sy = sy;
  int longest = nx > ny ? nx : ny;
  p->g = (longest + THUMB_MAX - 1) / THUMB_MAX;
  p->tw = (nx + p->g - 1) / p->g;
  p->th = (ny + p->g - 1) / p->g;
  p->stride = 1;
  p->f = (longest + LSM_PREVIEW_XY - 1) / LSM_PREVIEW_XY;
  p->dnx = (nx + p->f - 1) / p->f;
  p->dny = (ny + p->f - 1) / p->f;
  p->plane_n = (size_t)p->dnx * (size_t)p->dny;
  p->step = p->f * (sx < sy ? sx : sy);
  size_t tn = (size_t)p->tw * (size_t)p->th;
  int ok = 1;
  for (int k = 0; k < KEEP_MAX; ++k) ok &= (p->kept[k].cov = malloc(tn)) != NULL;
  ok &= (p->last.cov = malloc(tn)) != NULL;
  ok &= (p->vol = malloc((size_t)LSM_PREVIEW_Z * p->plane_n * sizeof(float))) != NULL;
  ok &= (p->prev = malloc(p->plane_n * sizeof(float))) != NULL;
  ok &= (p->cur = malloc(p->plane_n * sizeof(float))) != NULL;
  if (!ok) {
    lsm_preview_free(&p);
    return lsm_fail(err, LSM_ERR_NOMEM, "preview", "cannot allocate the preview buffers");
  }
  *out = p;
  return LSM_OK;
}

void lsm_preview_free(lsm_preview **pp) {
  if (!pp || !*pp) return;
  lsm_preview *p = *pp;
  for (int k = 0; k < KEEP_MAX; ++k) free(p->kept[k].cov);
  free(p->last.cov);
  free(p->vol);
  free(p->prev);
  free(p->cur);
  free(p);
  *pp = NULL;
}

/* ---- streaming ---------------------------------------------------------------------------------- */

static void make_thumb(const lsm_preview *p, const float *phi, uint8_t *cov) {
  const int g = p->g;
  for (int tj = 0; tj < p->th; ++tj) {
    for (int ti = 0; ti < p->tw; ++ti) {
      int in = 0, all = 0;
      for (int j = tj * g; j < (tj + 1) * g && j < p->ny; ++j)
        for (int i = ti * g; i < (ti + 1) * g && i < p->nx; ++i) {
          in += phi[(size_t)j * (size_t)p->nx + (size_t)i] <= 0.0f;
          all++;
        }
      cov[(size_t)tj * (size_t)p->tw + (size_t)ti] = (uint8_t)(all ? (255 * in + all / 2) / all : 0);
    }
  }
}

static void decimate(const lsm_preview *p, const float *phi, float *out) {
  const int f = p->f;
  for (int b = 0; b < p->dny; ++b) {
    for (int a = 0; a < p->dnx; ++a) {
      double sum = 0;
      int n = 0;
      for (int j = b * f; j < (b + 1) * f && j < p->ny; ++j)
        for (int i = a * f; i < (a + 1) * f && i < p->nx; ++i) {
          float v = phi[(size_t)j * (size_t)p->nx + (size_t)i];
          if (isfinite(v)) {
            sum += v;
            n++;
          }
        }
      out[(size_t)b * (size_t)p->dnx + (size_t)a] = n ? (float)(sum / n) : 1e30f;
    }
  }
}

lsm_status lsm_preview_add_slice(lsm_preview *p, const float *phi, double z, long input_index,
                                 lsm_err *err) {
  if (!p || !phi) return lsm_fail(err, LSM_ERR_INTERNAL, "preview", "bad arguments to add a slice");
  if (!isfinite(z) || (p->count > 0 && !(z > p->prev_z)))
    return lsm_fail(err, LSM_ERR_INPUT, "preview", "slice height %g does not increase", z);
  const size_t k = p->count;
  const size_t tn = (size_t)p->tw * (size_t)p->th;
  /* montage sample */
  if (k % p->stride == 0) {
    if (p->nkept == KEEP_MAX) { /* drop every other one, double the stride */
      int n = 0;
      for (int q = 0; q < p->nkept; ++q) {
        if (p->kept[q].index % (2 * p->stride) != 0) continue;
        thumb t = p->kept[n];
        p->kept[n] = p->kept[q];
        p->kept[q] = t;
        n++;
      }
      p->nkept = n;
      p->stride *= 2;
    }
    if (k % p->stride == 0) {
      thumb *t = &p->kept[p->nkept++];
      make_thumb(p, phi, t->cov);
      t->index = k;
      t->input = input_index;
      t->z = z;
    }
  }
  if (p->nkept > 0 && p->kept[p->nkept - 1].index == k)
    memcpy(p->last.cov, p->kept[p->nkept - 1].cov, tn);
  else
    make_thumb(p, phi, p->last.cov);
  p->last.index = k;
  p->last.input = input_index;
  p->last.z = z;

  /* decimated volume, resampled at heights z0 + m * step */
  decimate(p, phi, p->cur);
  if (k == 0) {
    p->z0 = z;
    memcpy(p->vol, p->cur, p->plane_n * sizeof(float));
    p->nplanes = 1;
  } else {
    for (;;) {
      double zt = p->z0 + p->nplanes * p->step;
      if (zt > z) break;
      if (p->nplanes == LSM_PREVIEW_Z) {
        for (int q = 0; 2 * q < p->nplanes; ++q)
          memmove(p->vol + (size_t)q * p->plane_n, p->vol + (size_t)(2 * q) * p->plane_n,
                  p->plane_n * sizeof(float));
        p->nplanes = (p->nplanes + 1) / 2;
        p->step *= 2;
        continue;
      }
      float s = (float)((zt - p->prev_z) / (z - p->prev_z));
      float *dst = p->vol + (size_t)p->nplanes * p->plane_n;
      for (size_t q = 0; q < p->plane_n; ++q) dst[q] = p->prev[q] + s * (p->cur[q] - p->prev[q]);
      p->nplanes++;
    }
  }
  float *t = p->prev;
  p->prev = p->cur;
  p->cur = t;
  p->prev_z = z;
  p->count++;
  return LSM_OK;
}

/* ---- drawing helpers ------------------------------------------------------------------------------ */

typedef struct image {
  uint8_t *px;
  int w, h;
} image;

static void put(image *im, int x, int y, int r, int g, int b) {
  if (x < 0 || y < 0 || x >= im->w || y >= im->h) return;
  uint8_t *o = im->px + 3 * ((size_t)y * (size_t)im->w + (size_t)x);
  o[0] = (uint8_t)r;
  o[1] = (uint8_t)g;
  o[2] = (uint8_t)b;
}

static void fill(image *im, int x0, int y0, int w, int h, int r, int g, int b) {
  for (int y = y0; y < y0 + h; ++y)
    for (int x = x0; x < x0 + w; ++x) put(im, x, y, r, g, b);
}

/* 3x5 glyphs, rows top to bottom, 3 bits each (4 = left column). */
static const char glyph_chars[] = "0123456789.-+=ez";
static const uint8_t glyphs[][5] = {
    {7, 5, 5, 5, 7}, {2, 6, 2, 2, 7}, {7, 1, 7, 4, 7}, {7, 1, 7, 1, 7}, {5, 5, 7, 1, 1},
    {7, 4, 7, 1, 7}, {7, 4, 7, 5, 7}, {7, 1, 1, 1, 1}, {7, 5, 7, 5, 7}, {7, 5, 7, 1, 7},
    {0, 0, 0, 0, 2}, {0, 0, 7, 0, 0}, {0, 2, 7, 2, 0}, {0, 7, 0, 7, 0}, {0, 7, 7, 4, 7},
    {0, 7, 2, 4, 7}};

/* Draws text at (x, y) with scale s; returns the width drawn. */
static int draw_text(image *im, int x, int y, int s, const char *text, int r, int g, int b) {
  int cx = x;
  for (const char *c = text; *c; ++c) {
    const char *hit = strchr(glyph_chars, *c);
    if (*c != ' ' && hit) {
      const uint8_t *gl = glyphs[hit - glyph_chars];
      for (int row = 0; row < 5; ++row)
        for (int col = 0; col < 3; ++col)
          if (gl[row] & (4 >> col)) fill(im, cx + col * s, y + row * s, s, s, r, g, b);
    }
    cx += 4 * s;
  }
  return cx - x;
}

/* ---- the montage --------------------------------------------------------------------------------- */

static lsm_status write_montage(lsm_preview *p, const char *path, lsm_err *err) {
  /* candidates: the kept thumbnails and the last slice */
  const thumb *cand[KEEP_MAX + 1];
  int nc = 0;
  for (int q = 0; q < p->nkept; ++q) cand[nc++] = &p->kept[q];
  if (nc == 0 || cand[nc - 1]->index != p->last.index) cand[nc++] = &p->last;
  const thumb *show[SHOW_MAX];
  int ns = 0;
  if (nc <= SHOW_MAX) {
    for (int q = 0; q < nc; ++q) show[ns++] = cand[q];
  } else {
    const double n = (double)(p->count - 1);
    for (int q = 0; q < SHOW_MAX; ++q) {
      double target = n * q / (SHOW_MAX - 1);
      int best = 0;
      for (int c = 1; c < nc; ++c)
        if (fabs((double)cand[c]->index - target) < fabs((double)cand[best]->index - target))
          best = c;
      if (ns == 0 || show[ns - 1] != cand[best]) show[ns++] = cand[best];
    }
  }
  int up = 1;
  int longest = p->tw > p->th ? p->tw : p->th;
  while (longest * (up + 1) <= THUMB_MIN * 2 && longest * up < THUMB_MIN) up++;
  /* thumbnails in the slices' physical proportions: the longer physical side
   * gets the longest side's length (a pixel need not be square) */
  const double ex = p->tw * p->sx, ey = p->th * p->sy, emax = ex > ey ? ex : ey;
  const long tw_shown = lround(longest * up * (ex / emax));
  const long th_shown = lround(longest * up * (ey / emax));
  const int TW = tw_shown > 0 ? (int)tw_shown : 1, TH = th_shown > 0 ? (int)th_shown : 1;
  const int F = 3, G = 6;
  int cols = (int)ceil(sqrt((double)ns));
  if (cols < 1) cols = 1;
  int rows = (ns + cols - 1) / cols;
  image im;
  im.w = G + cols * (TW + 2 * F + G);
  im.h = G + rows * (TH + 2 * F + G);
  im.px = malloc((size_t)im.w * (size_t)im.h * 3);
  if (!im.px) return lsm_fail(err, LSM_ERR_NOMEM, path, "cannot allocate the montage");
  fill(&im, 0, 0, im.w, im.h, 36, 38, 42);
  for (int q = 0; q < ns; ++q) {
    const thumb *t = show[q];
    int x0 = G + (q % cols) * (TW + 2 * F + G), y0 = G + (q / cols) * (TH + 2 * F + G);
    if (t->input >= 0)
      fill(&im, x0, y0, TW + 2 * F, TH + 2 * F, 255, 140, 0);
    else
      fill(&im, x0, y0, TW + 2 * F, TH + 2 * F, 120, 120, 126);
    for (int y = 0; y < TH; ++y)
      for (int x = 0; x < TW; ++x) {
        const size_t ty = (size_t)y * (size_t)p->th / (size_t)TH;
        const size_t tx = (size_t)x * (size_t)p->tw / (size_t)TW;
        int v = t->cov[ty * (size_t)p->tw + tx];
        int gv = 12 + v * 218 / 255;
        put(&im, x0 + F + x, y0 + F + y, gv, gv, gv);
      }
    char label[48];
    snprintf(label, sizeof label, "%zu z=%.4g", t->index + 1, t->z);
    int s = TW >= 120 ? 2 : 1;
    int lw = (int)strlen(label) * 4 * s + s;
    if (lw > TW) {
      snprintf(label, sizeof label, "%zu", t->index + 1);
      lw = (int)strlen(label) * 4 * s + s;
    }
    fill(&im, x0 + F, y0 + F, lw + s, 7 * s, 0, 0, 0);
    if (t->input >= 0)
      draw_text(&im, x0 + F + s, y0 + F + s, s, label, 255, 170, 60);
    else
      draw_text(&im, x0 + F + s, y0 + F + s, s, label, 230, 230, 230);
  }
  lsm_status st = lsm_png_write_rgb8(path, im.px, im.w, im.h, err);
  free(im.px);
  return st;
}

/* ---- the 3D rendering ------------------------------------------------------------------------------ */

#define MACRO 8 /* cells per macro cell (empty-space skipping) */

typedef struct volume_view {
  const float *vol;
  int n[3];        /* dnx, dny, nplanes */
  double o[3];     /* physical position of sample (0, 0, 0) */
  double h[3];     /* sample spacing */
  double lo[3], hi[3]; /* the box: samples +- half a spacing */
  int m[3];        /* macro cells per axis */
  uint8_t *occupied; /* per macro cell: some sample of it (ends included) <= 0 */
} volume_view;

/* Index of the cell (between samples i and i+1) holding sample coordinate u. */
static inline int cell_of(const volume_view *v, int a, double u) {
  int i = u <= 0 ? 0 : (int)u;
  if (i > v->n[a] - 2) i = v->n[a] - 2;
  return i < 0 ? 0 : i;
}

/* Marks the macro cells with an inside sample.  Trilinear interpolation inside
 * a cell whose 8 samples are all > 0 is > 0, so rays may jump over the others. */
static int build_macro(volume_view *v) {
  size_t count = 1;
  for (int a = 0; a < 3; ++a) {
    int cells = v->n[a] > 1 ? v->n[a] - 1 : 1;
    v->m[a] = (cells + MACRO - 1) / MACRO;
    count *= (size_t)v->m[a];
  }
  v->occupied = calloc(count, 1);
  if (!v->occupied) return 0;
  const size_t nx = (size_t)v->n[0], nxy = nx * (size_t)v->n[1];
  for (int k = 0; k < v->n[2]; ++k)
    for (int j = 0; j < v->n[1]; ++j)
      for (int i = 0; i < v->n[0]; ++i) {
        if (!(v->vol[(size_t)k * nxy + (size_t)j * nx + (size_t)i] <= 0.0f)) continue;
        /* a sample on a macro boundary belongs to the macro cells on both sides */
        int idx[3] = {i, j, k};
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
          hi[a] = idx[a] / MACRO;
          if (hi[a] >= v->m[a]) hi[a] = v->m[a] - 1;
          lo[a] = idx[a] % MACRO == 0 && idx[a] > 0 ? idx[a] / MACRO - 1 : hi[a];
        }
        for (int c = lo[2]; c <= hi[2]; ++c)
          for (int b = lo[1]; b <= hi[1]; ++b)
            for (int a = lo[0]; a <= hi[0]; ++a)
              v->occupied[((size_t)c * (size_t)v->m[1] + (size_t)b) * (size_t)v->m[0] + (size_t)a] = 1;
      }
  return 1;
}

/* The macro cell holding physical point x: 1 if occupied; else 0 and, in
 * *t_exit, where the ray x + t d (t from t_now) leaves it. */
static int macro_at(const volume_view *v, const double x[3], const double d[3], double t_now,
                    double *t_exit) {
  int mc[3];
  double te = INFINITY;
  for (int a = 0; a < 3; ++a) {
    double u = (x[a] - v->o[a]) / v->h[a];
    mc[a] = cell_of(v, a, u) / MACRO;
    if (mc[a] >= v->m[a]) mc[a] = v->m[a] - 1;
  }
  if (v->occupied[((size_t)mc[2] * (size_t)v->m[1] + (size_t)mc[1]) * (size_t)v->m[0] + (size_t)mc[0]])
    return 1;
  for (int a = 0; a < 3; ++a) {
    if (fabs(d[a]) < 1e-12) continue;
    /* the macro cell spans samples mc*MACRO .. (mc+1)*MACRO; the first and the
     * last reach the box */
    double lo = mc[a] == 0 ? v->lo[a] : v->o[a] + (double)(mc[a] * MACRO) * v->h[a];
    double hi = mc[a] == v->m[a] - 1 ? v->hi[a] : v->o[a] + (double)((mc[a] + 1) * MACRO) * v->h[a];
    double ta = ((d[a] > 0 ? hi : lo) - x[a]) / d[a];
    if (ta < te) te = ta;
  }
  *t_exit = t_now + (te > 0 ? te : 0);
  return 0;
}

/* Trilinear phi at a physical point (clamped to the samples). */
static double sample(const volume_view *v, const double x[3]) {
  int i0[3];
  double fr[3];
  for (int a = 0; a < 3; ++a) {
    double u = (x[a] - v->o[a]) / v->h[a];
    double umax = v->n[a] - 1;
    if (u < 0) u = 0;
    if (u > umax) u = umax;
    int i = (int)u;
    if (i > v->n[a] - 2) i = v->n[a] - 2;
    if (i < 0) i = 0;
    i0[a] = i;
    fr[a] = v->n[a] > 1 ? u - i : 0.0;
  }
  const size_t nx = (size_t)v->n[0], nxy = nx * (size_t)v->n[1];
  const int dx = v->n[0] > 1, dy = v->n[1] > 1, dz = v->n[2] > 1;
  const float *b = v->vol + (size_t)i0[2] * nxy + (size_t)i0[1] * nx + (size_t)i0[0];
  double c00 = b[0] + fr[0] * (b[dx] - b[0]);
  double c10 = b[dy * nx] + fr[0] * (b[dy * nx + (size_t)dx] - b[dy * nx]);
  const float *t = b + (size_t)dz * nxy;
  double c01 = t[0] + fr[0] * (t[dx] - t[0]);
  double c11 = t[dy * nx] + fr[0] * (t[dy * nx + (size_t)dx] - t[dy * nx]);
  double c0 = c00 + fr[1] * (c10 - c00), c1 = c01 + fr[1] * (c11 - c01);
  return c0 + fr[2] * (c1 - c0);
}

static void normalize3(double v[3]) {
  double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (l > 0) {
    v[0] /= l;
    v[1] /= l;
    v[2] /= l;
  }
}

static lsm_status write_render(lsm_preview *p, const char *path, lsm_err *err) {
  volume_view v;
  v.vol = p->vol;
  v.n[0] = p->dnx;
  v.n[1] = p->dny;
  v.n[2] = p->nplanes;
  v.h[0] = p->f * p->sx;
  v.h[1] = p->f * p->sy;
  v.h[2] = p->step;
  v.o[0] = 0.5 * (p->f - 1) * p->sx;
  v.o[1] = 0.5 * (p->f - 1) * p->sy;
  v.o[2] = p->z0;
  for (int a = 0; a < 3; ++a) {
    v.lo[a] = v.o[a] - 0.5 * v.h[a];
    v.hi[a] = v.o[a] + (v.n[a] - 0.5) * v.h[a];
  }
  /* camera: oblique (from -x, +y), 25 degrees above, z up */
  const double deg = 3.14159265358979323846 / 180.0;
  const double az = 125.0 * deg, el = 25.0 * deg;
  double d[3] = {-cos(el) * cos(az), -cos(el) * sin(az), -sin(el)}; /* view direction */
  double r[3] = {d[1], -d[0], 0.0};                                   /* d x z */
  normalize3(r);
  double u[3] = {r[1] * d[2] - r[2] * d[1], r[2] * d[0] - r[0] * d[2], r[0] * d[1] - r[1] * d[0]};
  double c[3], ext_r = 0, ext_u = 0;
  for (int a = 0; a < 3; ++a) c[a] = 0.5 * (v.lo[a] + v.hi[a]);
  for (int k = 0; k < 8; ++k) {
    double q[3] = {(k & 1 ? v.hi[0] : v.lo[0]) - c[0], (k & 2 ? v.hi[1] : v.lo[1]) - c[1],
                   (k & 4 ? v.hi[2] : v.lo[2]) - c[2]};
    double pr = fabs(q[0] * r[0] + q[1] * r[1] + q[2] * r[2]);
    double pu = fabs(q[0] * u[0] + q[1] * u[1] + q[2] * u[2]);
    if (pr > ext_r) ext_r = pr;
    if (pu > ext_u) ext_u = pu;
  }
  const double big = ext_r > ext_u ? ext_r : ext_u;
  const double scale = big > 0 ? 280.0 / big : 1.0; /* pixels per unit */
  image im;
  im.w = (int)ceil(2 * ext_r * scale) + 64;
  im.h = (int)ceil(2 * ext_u * scale) + 64;
  if (im.w < 64) im.w = 64;
  if (im.h < 64) im.h = 64;
  im.px = malloc((size_t)im.w * (size_t)im.h * 3);
  if (!im.px) return lsm_fail(err, LSM_ERR_NOMEM, path, "cannot allocate the rendering");
  double L[3] = {-d[0] + 0.6 * u[0] - 0.5 * r[0], -d[1] + 0.6 * u[1] - 0.5 * r[1],
                 -d[2] + 0.6 * u[2] - 0.5 * r[2]};
  normalize3(L);
  if (!build_macro(&v)) {
    free(im.px);
    return lsm_fail(err, LSM_ERR_NOMEM, path, "cannot allocate the rendering");
  }
  double hmin = v.h[0] < v.h[1] ? v.h[0] : v.h[1];
  if (v.h[2] < hmin) hmin = v.h[2];
  const double fine = 0.4 * hmin;
  /* rays start well outside the box, in its own units (a constant 1 lost all
   * precision at pixel sizes of 1e-12 and below) */
  const double far = 4.0 * (ext_r + ext_u) + hmin;
  const int W = im.w, H = im.h;

#pragma omp parallel for schedule(dynamic, 4)
  for (int py = 0; py < H; ++py) {
    for (int px = 0; px < W; ++px) {
      double bg = 238 - 40.0 * py / H;
      double col[3] = {bg, bg, bg + 4};
      double sx = (px + 0.5 - 0.5 * W) / scale, sy = (0.5 * H - py - 0.5) / scale;
      double o[3];
      for (int a = 0; a < 3; ++a) o[a] = c[a] + sx * r[a] + sy * u[a] - far * d[a];
      /* slab intersection with the box */
      double t0 = -INFINITY, t1 = INFINITY;
      int face = -1;
      for (int a = 0; a < 3; ++a) {
        if (fabs(d[a]) < 1e-12) {
          if (o[a] < v.lo[a] || o[a] > v.hi[a]) t0 = INFINITY;
          continue;
        }
        double ta = (v.lo[a] - o[a]) / d[a], tb = (v.hi[a] - o[a]) / d[a];
        if (ta > tb) {
          double t = ta;
          ta = tb;
          tb = t;
        }
        if (ta > t0) {
          t0 = ta;
          face = a;
        }
        if (tb < t1) t1 = tb;
      }
      if (t0 < t1 && face >= 0) {
        double x[3], n[3] = {0, 0, 0};
        int hit = 0;
        for (int a = 0; a < 3; ++a) x[a] = o[a] + t0 * d[a];
        double phi = sample(&v, x);
        if (phi <= 0) { /* a cap on the volume's boundary */
          hit = 1;
          n[face] = d[face] > 0 ? -1.0 : 1.0;
        } else {
          double t = t0, tp = t0;
          while (t < t1) {
            tp = t;
            double t_exit;
            if (!macro_at(&v, x, d, t, &t_exit))
              t = t_exit + 1e-9 * fine > t + fine ? t_exit + 1e-9 * fine : t + fine;
            else
              t += fine;
            if (t > t1) t = t1;
            for (int a = 0; a < 3; ++a) x[a] = o[a] + t * d[a];
            phi = sample(&v, x);
            if (phi <= 0) {
              hit = 1;
              break;
            }
            if (t >= t1) break;
          }
          if (hit) {
            double ta = tp, tb = t;
            for (int it = 0; it < 12; ++it) {
              double tm = 0.5 * (ta + tb);
              for (int a = 0; a < 3; ++a) x[a] = o[a] + tm * d[a];
              if (sample(&v, x) <= 0)
                tb = tm;
              else
                ta = tm;
            }
            for (int a = 0; a < 3; ++a) x[a] = o[a] + tb * d[a];
            for (int a = 0; a < 3; ++a) {
              double xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]};
              xp[a] += v.h[a];
              xm[a] -= v.h[a];
              n[a] = (sample(&v, xp) - sample(&v, xm)) / v.h[a];
            }
            normalize3(n);
            if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] > 0) {
              n[0] = -n[0];
              n[1] = -n[1];
              n[2] = -n[2];
            }
          }
        }
        if (hit) {
          double diff = n[0] * L[0] + n[1] * L[1] + n[2] * L[2];
          if (diff < 0) diff = 0;
          double rl[3]; /* reflected light */
          for (int a = 0; a < 3; ++a) rl[a] = 2 * diff * n[a] - L[a];
          double spec = -(rl[0] * d[0] + rl[1] * d[1] + rl[2] * d[2]);
          spec = spec > 0 ? pow(spec, 24) : 0;
          static const double base[3] = {0.86, 0.74, 0.58};
          for (int a = 0; a < 3; ++a) {
            double val = 255.0 * (base[a] * (0.16 + 0.84 * diff) + 0.22 * spec);
            col[a] = val > 255 ? 255 : val;
          }
        }
      }
      uint8_t *out = im.px + 3 * ((size_t)py * (size_t)W + (size_t)px);
      for (int a = 0; a < 3; ++a) out[a] = (uint8_t)(col[a] + 0.5);
    }
  }
  free(v.occupied);
  lsm_status st = lsm_png_write_rgb8(path, im.px, im.w, im.h, err);
  free(im.px);
  return st;
}

lsm_status lsm_preview_write(lsm_preview *p, const char *montage_path, const char *render_path,
                             lsm_err *err) {
  if (!p) return lsm_fail(err, LSM_ERR_INTERNAL, "preview", "bad arguments to write");
  if (p->count == 0) return lsm_fail(err, LSM_ERR_INPUT, "preview", "no slices were added");
  if (montage_path) LSM_TRY(write_montage(p, montage_path, err));
  if (render_path) LSM_TRY(write_render(p, render_path, err));
  return LSM_OK;
}
