/* lsm_preview_render: preview3d.png drawn cell by cell (see the header). */
#include "io/lsm_preview_render.h"

#include "io/lsm_preview.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* Pixels per unit: the box's larger projected half-extent spans this many. */
#define HALF_EXTENT_PX 180.0

struct lsm_render {
  double d[3], r[3], u[3], c[3]; /* view direction, screen right and up, box centre */
  double inv_d[3];                /* 1 / d (0 where d is 0) */
  double light[3];
  double scale, far; /* pixels per unit; rays start this far before the screen plane */
  int w, h, planes;
  float *depth; /* along each pixel's ray: the nearest hit so far (+inf: none) */
  uint8_t *rgb;
};

/* (fmin and fmax are library calls without -ffinite-math-only) */
static inline double min2(double a, double b) { return a < b ? a : b; }
static inline double max2(double a, double b) { return a > b ? a : b; }

static void normalize3(double v[3]) {
  double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (l > 0) {
    v[0] /= l;
    v[1] /= l;
    v[2] /= l;
  }
}

/* The box the samples fill: each sample +- half a spacing. */
static void box_of(const lsm_render_volume *v, double lo[3], double hi[3]) {
  for (int a = 0; a < 3; ++a) {
    lo[a] = v->o[a] - 0.5 * v->h[a];
    hi[a] = v->o[a] + (v->n[a] - 0.5) * v->h[a];
  }
}

lsm_render *lsm_render_new(const lsm_render_volume *v) {
  lsm_render *r = calloc(1, sizeof *r);
  if (!r) return NULL;
  double lo[3], hi[3];
  box_of(v, lo, hi);
  /* camera: oblique (from -x, +y), 25 degrees above, z up */
  const double deg = 3.14159265358979323846 / 180.0;
  const double az = 125.0 * deg, el = 25.0 * deg;
  double *d = r->d, *right = r->r, *up = r->u;
  d[0] = -cos(el) * cos(az);
  d[1] = -cos(el) * sin(az);
  d[2] = -sin(el);
  right[0] = d[1]; /* d x z */
  right[1] = -d[0];
  right[2] = 0.0;
  normalize3(right);
  for (int a = 0; a < 3; ++a) r->inv_d[a] = fabs(d[a]) < 1e-12 ? 0.0 : 1.0 / d[a];
  up[0] = right[1] * d[2] - right[2] * d[1];
  up[1] = right[2] * d[0] - right[0] * d[2];
  up[2] = right[0] * d[1] - right[1] * d[0];
  double ext_r = 0, ext_u = 0;
  for (int a = 0; a < 3; ++a) r->c[a] = 0.5 * (lo[a] + hi[a]);
  for (int k = 0; k < 8; ++k) {
    const double q[3] = {(k & 1 ? hi[0] : lo[0]) - r->c[0], (k & 2 ? hi[1] : lo[1]) - r->c[1],
                         (k & 4 ? hi[2] : lo[2]) - r->c[2]};
    ext_r = fmax(ext_r, fabs(q[0] * right[0] + q[1] * right[1] + q[2] * right[2]));
    ext_u = fmax(ext_u, fabs(q[0] * up[0] + q[1] * up[1] + q[2] * up[2]));
  }
  const double big = fmax(ext_r, ext_u);
  r->scale = big > 0 ? HALF_EXTENT_PX / big : 1.0;
  r->w = (int)fmax(64.0, ceil(2 * ext_r * r->scale) + 64);
  r->h = (int)fmax(64.0, ceil(2 * ext_u * r->scale) + 64);
  const double hmin = fmin(v->h[0], fmin(v->h[1], v->h[2]));
  /* rays start well outside the box, in its own units (a constant 1 lost all
   * precision at pixel sizes of 1e-12 and below) */
  r->far = 4.0 * (ext_r + ext_u) + hmin;
  r->planes = v->n[2];
  for (int a = 0; a < 3; ++a) r->light[a] = -d[a] + 0.6 * up[a] - 0.5 * right[a];
  normalize3(r->light);
  const size_t pixels = (size_t)r->w * (size_t)r->h;
  r->depth = malloc(pixels * sizeof *r->depth);
  r->rgb = malloc(pixels * 3);
  if (!r->depth || !r->rgb) {
    lsm_render_free(&r);
    return NULL;
  }
  for (int y = 0; y < r->h; ++y) {
    const double bg = 238 - 40.0 * y / r->h;
    const uint8_t grey = (uint8_t)(bg + 0.5), blue = (uint8_t)(bg + 4 + 0.5);
    for (int x = 0; x < r->w; ++x) {
      uint8_t *o = r->rgb + 3 * ((size_t)y * (size_t)r->w + (size_t)x);
      o[0] = o[1] = grey;
      o[2] = blue;
    }
  }
  for (size_t k = 0; k < pixels; ++k) r->depth[k] = INFINITY;
  return r;
}

int lsm_render_frames(const lsm_render *r, int planes) { return r && r->planes == planes; }

const uint8_t *lsm_render_pixels(const lsm_render *r, int *w, int *h) {
  *w = r->w;
  *h = r->h;
  return r->rgb;
}

void lsm_render_free(lsm_render **rp) {
  if (!rp || !*rp) return;
  free((*rp)->depth);
  free((*rp)->rgb);
  free(*rp);
  *rp = NULL;
}

/* ---- one cell ---------------------------------------------------------------------------- */

typedef struct cell {
  int idx[3];        /* its first corner */
  int edge_lo[3], edge_hi[3]; /* its faces on the volume's boundary */
  double lo[3], hi[3]; /* its box: a boundary cell reaches the volume's box */
  double v[8];       /* corner values, bit 0 x, bit 1 y, bit 2 z */
} cell;

/* Whether phi rises along d everywhere in the cell: a ray cannot first meet
 * the surface there, where it leaves the object.  Along each axis the
 * derivative of trilinear phi is a blend of the cell's four differences
 * along that axis, so d . grad phi is at least the sum of the worst ones. */
static int receding(const cell *c, const double d[3], const double h[3]) {
  double least = 0.0;
  for (int a = 0; a < 3; ++a) {
    const int e = 1 << a;
    double lo = INFINITY, hi = -INFINITY;
    for (int q = 0; q < 8; ++q) {
      if (q & e) continue;
      const double diff = c->v[q | e] - c->v[q];
      lo = min2(lo, diff);
      hi = max2(hi, diff);
    }
    least += (d[a] > 0 ? d[a] * lo : d[a] * hi) / h[a];
  }
  return least > 0.0;
}

/* Trilinear phi at cell coordinates s (each in [0, 1]). */
static double trilinear(const double v[8], const double s[3]) {
  const double x00 = v[0] + s[0] * (v[1] - v[0]), x10 = v[2] + s[0] * (v[3] - v[2]);
  const double x01 = v[4] + s[0] * (v[5] - v[4]), x11 = v[6] + s[0] * (v[7] - v[6]);
  const double y0 = x00 + s[1] * (x10 - x00), y1 = x01 + s[1] * (x11 - x01);
  return y0 + s[2] * (y1 - y0);
}

/* A point of the ray, in cell coordinates (clamped: beyond the outer
 * samples phi holds their values): s = base + t * slope. */
static double phi_at(const cell *c, const double base[3], const double slope[3], double t,
                     double s[3]) {
  for (int a = 0; a < 3; ++a) s[a] = min2(1.0, max2(0.0, base[a] + t * slope[a]));
  return trilinear(c->v, s);
}

/* The central differences (over one spacing each way, indices clamped to
 * the samples) at the cell's corners, per unit length. */
static void corner_gradients(const lsm_render_volume *v, const cell *c, double g[8][3]) {
  const size_t stride[3] = {1, (size_t)v->n[0], (size_t)v->n[0] * (size_t)v->n[1]};
  for (int q = 0; q < 8; ++q) {
    int p[3];
    for (int a = 0; a < 3; ++a) {
      const int up = (q >> a) & 1;
      p[a] = c->idx[a] + up < v->n[a] ? c->idx[a] + up : v->n[a] - 1;
    }
    const size_t at = (size_t)p[0] * stride[0] + (size_t)p[1] * stride[1] + (size_t)p[2] * stride[2];
    for (int a = 0; a < 3; ++a) {
      const size_t plus = p[a] + 1 < v->n[a] ? stride[a] : 0, minus = p[a] > 0 ? stride[a] : 0;
      g[q][a] = ((double)v->vol[at + plus] - (double)v->vol[at - minus]) / v->h[a];
    }
  }
}

static void shade(const lsm_render *r, double n[3], uint8_t *out) {
  double diff = n[0] * r->light[0] + n[1] * r->light[1] + n[2] * r->light[2];
  if (diff < 0) diff = 0;
  double spec = 0; /* the reflected light toward the viewer, to the 24th */
  for (int a = 0; a < 3; ++a) spec -= (2 * diff * n[a] - r->light[a]) * r->d[a];
  if (spec > 0) {
    const double s2 = spec * spec, s8 = s2 * s2 * s2 * s2;
    spec = s8 * s8 * s8;
  } else {
    spec = 0;
  }
  static const double base[3] = {0.86, 0.74, 0.58};
  for (int a = 0; a < 3; ++a) {
    const double val = 255.0 * (base[a] * (0.16 + 0.84 * diff) + 0.22 * spec);
    out[a] = (uint8_t)((val > 255 ? 255 : val) + 0.5);
  }
}

/* Draws the cell into rows [y_lo, y_hi): for each pixel whose ray crosses
 * its box nearer than the pixel's hit so far, the first point with phi <= 0
 * on the ray within the box (sampled every `fine`, then false position). */
static void draw_cell(lsm_render *r, const lsm_render_volume *v, const cell *c, double fine,
                      int y_lo, int y_hi) {
  double sx = 0, sy = 0, ex = 0, ey = 0;
  for (int a = 0; a < 3; ++a) {
    const double mid = 0.5 * (c->lo[a] + c->hi[a]) - r->c[a], half = 0.5 * (c->hi[a] - c->lo[a]);
    sx += mid * r->r[a];
    sy += mid * r->u[a];
    ex += half * fabs(r->r[a]);
    ey += half * fabs(r->u[a]);
  }
  /* pixel px's centre lies at screen x (px + 0.5 - w / 2) / scale, py's at (h / 2 - py - 0.5) / scale */
  const double cx = sx * r->scale + 0.5 * r->w - 0.5, cy = 0.5 * r->h - 0.5 - sy * r->scale;
  const int x0 = (int)fmax(0.0, ceil(cx - ex * r->scale));
  const int x1 = (int)fmin(r->w - 1.0, floor(cx + ex * r->scale));
  const int y0 = (int)fmax((double)y_lo, ceil(cy - ey * r->scale));
  const int y1 = (int)fmin(y_hi - 1.0, floor(cy + ey * r->scale));
  if (x0 > x1 || y0 > y1) return;
  const double inv_h[3] = {1.0 / v->h[0], 1.0 / v->h[1], 1.0 / v->h[2]};
  double g[8][3];
  int have_g = 0;
  /* the ray of pixel (x, y) starts at o = c + sx r + sy u - far d; it meets
   * the planes x_a = lo_a, hi_a at (lo_a - o_a) / d_a: linear in x and y */
  const double step_x = 1.0 / r->scale;
  for (int y = y0; y <= y1; ++y) {
    const double scr_y = (0.5 * r->h - y - 0.5) / r->scale;
    double o_row[3];
    for (int a = 0; a < 3; ++a)
      o_row[a] = r->c[a] + ((x0 + 0.5 - 0.5 * r->w) / r->scale) * r->r[a] + scr_y * r->u[a] -
                 r->far * r->d[a];
    for (int x = x0; x <= x1; ++x) {
      double o[3], t_in = -INFINITY, t_out = INFINITY;
      int entry = -1;
      for (int a = 0; a < 3; ++a) {
        o[a] = o_row[a] + (x - x0) * step_x * r->r[a];
        if (fabs(r->d[a]) < 1e-12) {
          if (o[a] < c->lo[a] || o[a] > c->hi[a]) t_in = INFINITY;
          continue;
        }
        const double ta = (c->lo[a] - o[a]) * r->inv_d[a], tb = (c->hi[a] - o[a]) * r->inv_d[a];
        const double tn = min2(ta, tb), tf = max2(ta, tb);
        if (tn > t_in) {
          t_in = tn;
          entry = a;
        }
        t_out = min2(t_out, tf);
      }
      float *best = r->depth + (size_t)y * (size_t)r->w + (size_t)x;
      if (!(t_in <= t_out) || entry < 0 || !((float)t_in < *best)) continue;
      double base[3], slope[3], s[3];
      for (int a = 0; a < 3; ++a) {
        if (v->n[a] < 2) {
          base[a] = slope[a] = 0.0;
          continue;
        }
        base[a] = (o[a] - v->o[a]) * inv_h[a] - c->idx[a];
        slope[a] = r->d[a] * inv_h[a];
      }
      double t_hit = t_in, f = phi_at(c, base, slope, t_in, s);
      int cap = 0;
      if (f <= 0) {
        /* inside where the ray enters: a cap if that face is the volume's */
        cap = r->d[entry] > 0 ? c->edge_lo[entry] : c->edge_hi[entry];
      } else {
        const int steps = (int)fmin(64.0, fmax(1.0, ceil((t_out - t_in) / fine)));
        double ta = t_in, fa = f, tb = t_in, fb = f;
        for (int q = 1; q <= steps && fb > 0; ++q) {
          ta = tb;
          fa = fb;
          tb = t_in + (t_out - t_in) * q / steps;
          fb = phi_at(c, base, slope, tb, s);
        }
        if (fb > 0) continue; /* no inside point in this cell */
        for (int it = 0; it < 2; ++it) { /* false position, keeping the bracket */
          const double tm = ta + (tb - ta) * fa / (fa - fb);
          const double fm = phi_at(c, base, slope, tm, s);
          if (fm <= 0) {
            tb = tm;
            fb = fm;
          } else {
            ta = tm;
            fa = fm;
          }
        }
        t_hit = ta + (tb - ta) * fa / (fa - fb);
        phi_at(c, base, slope, t_hit, s);
      }
      if (!((float)t_hit < *best)) continue;
      double n[3] = {0, 0, 0};
      if (cap) {
        n[entry] = r->d[entry] > 0 ? -1.0 : 1.0;
      } else {
        if (!have_g) {
          corner_gradients(v, c, g);
          have_g = 1;
        }
        const double w[2][3] = {{1 - s[0], 1 - s[1], 1 - s[2]}, {s[0], s[1], s[2]}};
        for (int q = 0; q < 8; ++q) {
          const double wq = w[q & 1][0] * w[(q >> 1) & 1][1] * w[(q >> 2) & 1][2];
          for (int a = 0; a < 3; ++a) n[a] += wq * g[q][a];
        }
        normalize3(n);
        if (n[0] * r->d[0] + n[1] * r->d[1] + n[2] * r->d[2] > 0)
          for (int a = 0; a < 3; ++a) n[a] = -n[a];
      }
      *best = (float)t_hit;
      shade(r, n, r->rgb + 3 * ((size_t)y * (size_t)r->w + (size_t)x));
    }
  }
}

/* Draws cells k0 <= k < k1 into rows [y_lo, y_hi). */
static void draw_cells(lsm_render *r, const lsm_render_volume *v, int k0, int k1, int complete,
                       int y_lo, int y_hi) {
  int cells[3];
  for (int a = 0; a < 3; ++a) cells[a] = v->n[a] > 1 ? v->n[a] - 1 : 1;
  double box_lo[3], box_hi[3];
  box_of(v, box_lo, box_hi);
  const double fine = 0.4 * fmin(v->h[0], fmin(v->h[1], v->h[2])); /* phi need not be a distance */
  const size_t nx = (size_t)v->n[0], nxy = nx * (size_t)v->n[1];
  uint8_t sum[LSM_PREVIEW_XY + 1]; /* inside samples of the four rows, by column */
  cell c;
  for (int k = k0; k < k1 && k < cells[2]; ++k) {
    const int k1p = k + 1 < v->n[2] ? k + 1 : k;
    /* within a plane, nearer cells first, so that farther ones fail the depth test */
    for (int jj = 0; jj < cells[1]; ++jj) {
      const int j = r->d[1] < 0 ? cells[1] - 1 - jj : jj;
      const int j1 = j + 1 < v->n[1] ? j + 1 : j;
      const float *row[4] = {v->vol + (size_t)k * nxy + (size_t)j * nx, v->vol + (size_t)k * nxy + (size_t)j1 * nx,
                             v->vol + (size_t)k1p * nxy + (size_t)j * nx, v->vol + (size_t)k1p * nxy + (size_t)j1 * nx};
      unsigned any = 0;
      for (size_t i = 0; i < nx; ++i) {
        sum[i] = (uint8_t)((row[0][i] <= 0.0f) + (row[1][i] <= 0.0f) + (row[2][i] <= 0.0f) +
                           (row[3][i] <= 0.0f));
        any |= sum[i];
      }
      if (!any) continue; /* no cell of this row holds an inside sample */
      for (int ii = 0; ii < cells[0]; ++ii) {
        const int i = r->d[0] < 0 ? cells[0] - 1 - ii : ii;
        const int i1 = i + 1 < v->n[0] ? i + 1 : i;
        const int inside = sum[i] + sum[i1];
        if (inside == 0) continue;
        c.idx[0] = i;
        c.idx[1] = j;
        c.idx[2] = k;
        int edge = 0;
        for (int a = 0; a < 3; ++a) {
          c.edge_lo[a] = c.idx[a] == 0;
          c.edge_hi[a] = c.idx[a] == cells[a] - 1 && (a < 2 || complete);
          edge |= c.edge_lo[a] | c.edge_hi[a];
        }
        if (inside == 8 && !edge) continue;
        for (int q = 0; q < 4; ++q) {
          c.v[2 * q] = row[q][i];
          c.v[2 * q + 1] = row[q][i1];
        }
        if (!edge && receding(&c, r->d, v->h)) continue;
        for (int a = 0; a < 3; ++a) {
          c.lo[a] = c.edge_lo[a] ? box_lo[a] : v->o[a] + c.idx[a] * v->h[a];
          c.hi[a] = c.edge_hi[a] ? box_hi[a] : v->o[a] + (c.idx[a] + 1) * v->h[a];
        }
        draw_cell(r, v, &c, fine, y_lo, y_hi);
      }
    }
  }
}

void lsm_render_cells(lsm_render *r, const lsm_render_volume *v, int k0, int k1, int complete,
                      int threads) {
  if (!r || k0 >= k1) return;
  if (threads <= 1) {
    draw_cells(r, v, k0, k1, complete, 0, r->h);
    return;
  }
  /* each thread its own band of rows: no pixel is shared */
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num(), n = omp_get_num_threads();
    draw_cells(r, v, k0, k1, complete, (int)((long)r->h * t / n), (int)((long)r->h * (t + 1) / n));
  }
}
