/* lsm_preview: montage of sample slices and a ray-marched rendering of the
 * surface (see lsm_preview.h). */
#include "io/lsm_preview.h"

#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/lsm_io.h"
#include "io/lsm_preview_render.h"

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
  /* preview3d.png, drawn as the planes arrive when the heights were expected */
  lsm_render *render;
  int drawn;           /* cells below plane `drawn` are drawn */
  int expected_planes; /* the framing's (0: none expected) */
  /* one row of block sums, for thumbnails and decimation */
  uint32_t *row_in;
  double *row_sum;
  uint32_t *row_n;
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
  ok &= (p->row_in = malloc((size_t)p->tw * sizeof *p->row_in)) != NULL;
  ok &= (p->row_sum = malloc((size_t)p->dnx * sizeof *p->row_sum)) != NULL;
  ok &= (p->row_n = malloc((size_t)p->dnx * sizeof *p->row_n)) != NULL;
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
  free(p->row_in);
  free(p->row_sum);
  free(p->row_n);
  lsm_render_free(&p->render);
  free(p);
  *pp = NULL;
}

static void draw_arrived(lsm_preview *p);

/* ---- streaming ---------------------------------------------------------------------------------- */

/* The fraction inside (phi <= 0) of each g x g block, 0..255, a row of
 * blocks at a time. */
static void make_thumb(const lsm_preview *p, const float *phi, uint8_t *cov) {
  const int g = p->g;
  const size_t nx = (size_t)p->nx;
  if (g == 1) {
    for (size_t k = 0; k < nx * (size_t)p->ny; ++k) cov[k] = phi[k] <= 0.0f ? 255 : 0;
    return;
  }
  uint32_t *in = p->row_in;
  for (int tj = 0; tj < p->th; ++tj) {
    memset(in, 0, (size_t)p->tw * sizeof *in);
    const int j1 = (tj + 1) * g < p->ny ? (tj + 1) * g : p->ny;
    for (int j = tj * g; j < j1; ++j) {
      const float *row = phi + (size_t)j * nx;
      for (int i = 0; i < p->nx; ++i) in[i / g] += row[i] <= 0.0f;
    }
    for (int ti = 0; ti < p->tw; ++ti) {
      const int cols = (ti + 1) * g < p->nx ? g : p->nx - ti * g;
      const uint32_t all = (uint32_t)cols * (uint32_t)(j1 - tj * g);
      cov[(size_t)tj * (size_t)p->tw + (size_t)ti] = (uint8_t)((255 * in[ti] + all / 2) / all);
    }
  }
}

/* The mean of the finite values of each f x f block (1e30 where none is),
 * a row of blocks at a time. */
static void decimate(const lsm_preview *p, const float *phi, float *out) {
  const int f = p->f;
  const size_t nx = (size_t)p->nx;
  if (f == 1) {
    for (size_t k = 0; k < nx * (size_t)p->ny; ++k) out[k] = isfinite(phi[k]) ? phi[k] : 1e30f;
    return;
  }
  double *sum = p->row_sum;
  uint32_t *n = p->row_n;
  for (int b = 0; b < p->dny; ++b) {
    memset(sum, 0, (size_t)p->dnx * sizeof *sum);
    memset(n, 0, (size_t)p->dnx * sizeof *n);
    for (int j = b * f; j < (b + 1) * f && j < p->ny; ++j) {
      const float *row = phi + (size_t)j * nx;
      for (int i = 0; i < p->nx; ++i)
        if (isfinite(row[i])) {
          sum[i / f] += row[i];
          n[i / f]++;
        }
    }
    for (int a = 0; a < p->dnx; ++a)
      out[(size_t)b * (size_t)p->dnx + (size_t)a] = n[a] ? (float)(sum[a] / n[a]) : 1e30f;
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
    if (p->render && z != p->z0) lsm_render_free(&p->render); /* not the height expected */
    p->z0 = z;
    memcpy(p->vol, p->cur, p->plane_n * sizeof(float));
    p->nplanes = 1;
  } else {
    for (;;) {
      double zt = p->z0 + p->nplanes * p->step;
      if (zt > z) break;
      if (p->nplanes == LSM_PREVIEW_Z) { /* (the expected framing no longer holds) */
        lsm_render_free(&p->render);
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
  draw_arrived(p);
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
  const int x1 = x0 + w < im->w ? x0 + w : im->w, y1 = y0 + h < im->h ? y0 + h : im->h;
  if (x0 < 0) x0 = 0;
  if (y0 < 0) y0 = 0;
  for (int y = y0; y < y1; ++y) {
    uint8_t *o = im->px + 3 * ((size_t)y * (size_t)im->w + (size_t)x0);
    for (int x = x0; x < x1; ++x, o += 3) {
      o[0] = (uint8_t)r;
      o[1] = (uint8_t)g;
      o[2] = (uint8_t)b;
    }
  }
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
    for (int y = 0; y < TH; ++y) {
      const uint8_t *src = t->cov + (size_t)y * (size_t)p->th / (size_t)TH * (size_t)p->tw;
      for (int x = 0; x < TW; ++x) {
        const int v = src[(size_t)x * (size_t)p->tw / (size_t)TW];
        const int gv = 12 + v * 218 / 255;
        put(&im, x0 + F + x, y0 + F + y, gv, gv, gv);
      }
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

static lsm_render_volume volume_of(const lsm_preview *p, int planes) {
  lsm_render_volume v = {p->vol,
                         {p->dnx, p->dny, planes},
                         {0.5 * (p->f - 1) * p->sx, 0.5 * (p->f - 1) * p->sy, p->z0},
                         {p->f * p->sx, p->f * p->sy, p->step}};
  return v;
}

/* Draws the cells whose neighbour planes have all arrived, while slices
 * still stream in (the framing is the expected one). */
static void draw_arrived(lsm_preview *p) {
  if (!p->render || p->nplanes - 2 <= p->drawn) return;
  const lsm_render_volume v = volume_of(p, p->nplanes);
  lsm_render_cells(p->render, &v, p->drawn, p->nplanes - 2, 0, 1);
  p->drawn = p->nplanes - 2;
}

static lsm_status write_render(lsm_preview *p, lsm_err *err) {
  const lsm_render_volume v = volume_of(p, p->nplanes);
  /* the expected framing holds unless more planes came: else draw it all now */
  if (p->render && !(p->nplanes <= p->expected_planes)) lsm_render_free(&p->render);
  if (!p->render) {
    p->drawn = 0;
    if (!(p->render = lsm_render_new(&v)))
      return lsm_fail(err, LSM_ERR_NOMEM, "preview", "cannot allocate the rendering");
  }
  const int threads = omp_get_max_threads() > 0 ? omp_get_max_threads() : 1;
  lsm_render_cells(p->render, &v, p->drawn, p->nplanes, 1, threads);
  p->drawn = p->nplanes;
  return LSM_OK;
}

lsm_status lsm_preview_write(lsm_preview *p, const char *montage_path, const char *render_path,
                             lsm_err *err) {
  if (!p) return lsm_fail(err, LSM_ERR_INTERNAL, "preview", "bad arguments to write");
  if (p->count == 0) return lsm_fail(err, LSM_ERR_INPUT, "preview", "no slices were added");
  if (render_path) LSM_TRY(write_render(p, err));
  /* the two pictures are encoded side by side */
  lsm_status st[2] = {LSM_OK, LSM_OK};
  lsm_err errs[2];
  lsm_err_clear(&errs[0]);
  lsm_err_clear(&errs[1]);
#pragma omp parallel sections num_threads(2)
  {
#pragma omp section
    if (montage_path) st[0] = write_montage(p, montage_path, &errs[0]);
#pragma omp section
    if (render_path) {
      int w, h;
      const uint8_t *px = lsm_render_pixels(p->render, &w, &h);
      st[1] = lsm_png_write_rgb8(render_path, px, w, h, &errs[1]);
    }
  }
  for (int q = 0; q < 2; ++q)
    if (st[q] != LSM_OK) {
      if (err) *err = errs[q];
      return st[q];
    }
  return LSM_OK;
}

lsm_status lsm_preview_expect(lsm_preview *p, double z_first, double z_last, lsm_err *err) {
  if (!p || p->count > 0 || p->render)
    return lsm_fail(err, LSM_ERR_INTERNAL, "preview", "heights expected after the first slice");
  if (!(isfinite(z_first) && isfinite(z_last) && z_last >= z_first)) return LSM_OK;
  /* the plane step the doubling would end with (see lsm_preview_add_slice) */
  double planes = floor((z_last - z_first) / p->step * (1 + 1e-12)) + 1;
  while (planes > LSM_PREVIEW_Z) {
    p->step *= 2;
    planes = floor((z_last - z_first) / p->step * (1 + 1e-12)) + 1;
  }
  p->z0 = z_first;
  p->expected_planes = (int)planes;
  const lsm_render_volume v = volume_of(p, p->expected_planes);
  p->render = lsm_render_new(&v); /* none: all is drawn at the end */
  return LSM_OK;
}
