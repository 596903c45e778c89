/* lsm_sdf: exact Euclidean distance transform, signed distance of masks and
 * outlines, outline filling by parity, convex-hull centroid.
 *
 * The distance transform follows P. F. Felzenszwalb and D. P. Huttenlocher,
 * "Distance Transforms of Sampled Functions", Theory of Computing 8 (2012)
 * 415-428: the squared Euclidean distance is separable, so a 2D transform is
 * a 1D transform along every column followed by one along every row, and the
 * 1D transform of a sampled function f,
 *
 *     D(q) = min_p ( s^2 (q - p)^2 + f(p) ),
 *
 * is the lower envelope of the parabolas rooted at (p, f(p)), built in one
 * left-to-right sweep (linear time).  Distances are doubles; +INFINITY means
 * "no feature".
 */
#include "solver/sdf/lsm_sdf.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "solver/base/lsm_flood.h"

#ifdef _OPENMP
#include <omp.h>
#define LSM_OMP(directive) _Pragma(#directive)
#else
#define LSM_OMP(directive)
#endif

/* Images with fewer pixels than this are transformed on one thread: below it
 * starting a team costs more than it saves. */
#define EDT_PARALLEL_MIN_PIXELS ((size_t)1 << 14)

/* Columns per task in the column pass (64 doubles: 512 bytes of each row). */
#define EDT_COLUMN_BLOCK 64

/* ------------------------------------------------------------------------ */
/* 1D transform                                                              */

/* Per-thread scratch of the 1D transform for rows of n = width samples. */
typedef struct edt_scratch {
  double *f; /* the sampled function of the current line, n */
  double *z; /* envelope breakpoints, n + 1 */
  int *v;    /* envelope parabola roots, n */
} edt_scratch;

/* D(q) = min_p (s2 (q-p)^2 + f[p]) for q = 0..n-1, written to out[q].
 * s2 is the squared sample spacing.  Samples with f[p] = +INF are no parabola
 * at all and are skipped, so the intersection formula never sees an infinity
 * (inf - inf would be NaN); a line without a finite sample gives +INF.
 *
 * Envelope: v[0..k] are the roots of the parabolas that form the lower
 * envelope, left to right; parabola v[i] is the lowest one on [z[i], z[i+1]].
 * Two parabolas rooted at p < q intersect at
 *
 *     s = ((f[q] + s2 q^2) - (f[p] + s2 p^2)) / (2 s2 (q - p))
 *       = (f[q] - f[p]) / (2 s2 (q - p)) + (q + p) / 2,
 *
 * (the second form keeps the terms small).  A new parabola q hides the last
 * envelope parabola v[k] when they cross left of z[k], where v[k] starts. */
static void edt_1d(const double *f, int n, double s2, double *out, int *v, double *z) {
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (isinf(f[q])) continue;
    if (k < 0) {
      k = 0;
      v[0] = q;
      z[0] = -INFINITY;
      z[1] = INFINITY;
      continue;
    }
    double s;
    for (;;) {
      const int p = v[k];
      s = (f[q] - f[p]) / (2.0 * s2 * (double)(q - p)) + 0.5 * (double)(q + p);
      /* z[0] = -INF, so the first envelope parabola is never popped. */
      if (s <= z[k]) {
        --k;
      } else {
        break;
      }
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = INFINITY;
  }
  if (k < 0) {
    for (int q = 0; q < n; ++q) out[q] = INFINITY;
    return;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < (double)q) ++k;
    const double d = (double)(q - v[k]);
    out[q] = s2 * d * d + f[v[k]];
  }
}

void lsm_edt_squared_1d(const double *f, int n, double spacing, double *out, int *v, double *z) {
  edt_1d(f, n, spacing * spacing, out, v, z);
}

/* ------------------------------------------------------------------------ */
/* 2D transform                                                              */

lsm_status lsm_edt_squared(const uint8_t *feature, int width, int height, double dx,
                           double dy, double *out, lsm_err *err) {
  if (!feature || !out || width <= 0 || height <= 0)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL,
                    "distance transform: bad arguments (%dx%d image)", width, height);
  if (!(dx > 0.0) || !(dy > 0.0) || !isfinite(dx) || !isfinite(dy))
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL,
                    "distance transform: pixel size %g x %g is not positive", dx, dy);
  size_t npix;
  if (!lsm_size_mul((size_t)width, (size_t)height, &npix))
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "distance transform: %dx%d image is too large",
                    width, height);

  const int n = width; /* the 1D transform runs along rows only */
  int nthreads = 1;
#ifdef _OPENMP
  if (npix >= EDT_PARALLEL_MIN_PIXELS) nthreads = omp_get_max_threads();
  if (nthreads < 1) nthreads = 1;
#endif

  /* Scratch for every thread, allocated once: per thread f (n) and z (n + 1)
   * doubles, v (n) ints. */
  const size_t nd = 2 * (size_t)n + 1;
  size_t dcount, icount;
  if (!lsm_size_mul(nd, (size_t)nthreads, &dcount) ||
      !lsm_size_mul((size_t)n, (size_t)nthreads, &icount))
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "distance transform: scratch size overflows");
  double *dscratch = lsm_alloc(dcount, sizeof(double), err, "distance transform scratch");
  if (!dscratch) return err ? err->status : LSM_ERR_NOMEM;
  int *iscratch = lsm_alloc(icount, sizeof(int), err, "distance transform scratch");
  if (!iscratch) {
    free(dscratch);
    return err ? err->status : LSM_ERR_NOMEM;
  }

  const double sx2 = dx * dx, sy2 = dy * dy;
  const ptrdiff_t w = width;
  const int nblocks = (width + EDT_COLUMN_BLOCK - 1) / EDT_COLUMN_BLOCK;

  /* Every line is transformed independently and by the same code, so the
   * result does not depend on the number of threads. */
  LSM_OMP(omp parallel num_threads(nthreads) if (nthreads > 1))
  {
    int t = 0;
#ifdef _OPENMP
    t = omp_get_thread_num();
#endif
    edt_scratch sc = {dscratch + (size_t)t * nd, dscratch + (size_t)t * nd + (size_t)n,
                      iscratch + (size_t)t * (size_t)n};

    /* Pass 1, along columns.  The sampled function is 0 on feature pixels and
     * +INF elsewhere, for which the 1D transform reduces to
     * D(j) = dy^2 c(j)^2 with c(j) the number of rows to the nearest feature
     * pixel in the column (the lowest parabolas are those rooted nearest).
     * c is found with one downward and one upward sweep over the rows, which
     * reads the image row by row (cache-friendly and vectorisable, where a
     * column-by-column transform strides across the whole image).  out holds
     * c (an integer or +INF) until pass 2 squares it. */
    LSM_OMP(omp for schedule(static))
    for (int b = 0; b < nblocks; ++b) {
      const int i0 = b * EDT_COLUMN_BLOCK;
      const int i1 = i0 + EDT_COLUMN_BLOCK < width ? i0 + EDT_COLUMN_BLOCK : width;
      for (int i = i0; i < i1; ++i) out[i] = feature[i] ? 0.0 : INFINITY;
      for (int j = 1; j < height; ++j) {
        const uint8_t *frow = feature + (ptrdiff_t)j * w;
        double *row = out + (ptrdiff_t)j * w;
        const double *above = row - w;
        for (int i = i0; i < i1; ++i) row[i] = frow[i] ? 0.0 : above[i] + 1.0;
      }
      for (int j = height - 2; j >= 0; --j) {
        double *row = out + (ptrdiff_t)j * w;
        const double *below = row + w;
        for (int i = i0; i < i1; ++i) {
          const double c = below[i] + 1.0;
          row[i] = c < row[i] ? c : row[i];
        }
      }
    }
    /* (implicit barrier: pass 2 reads what other threads wrote in pass 1) */

    /* Pass 2, along rows (spacing dx): the F-H 1D transform of the column
     * distances dy^2 c^2.  Rows that are +INF everywhere (no feature in the
     * image) stay +INF. */
    LSM_OMP(omp for schedule(static))
    for (int j = 0; j < height; ++j) {
      double *row = out + (ptrdiff_t)j * w;
      for (int i = 0; i < width; ++i) sc.f[i] = sy2 * row[i] * row[i];
      edt_1d(sc.f, width, sx2, row, sc.v, sc.z);
    }
  }

  free(iscratch);
  free(dscratch);
  return LSM_OK;
}

/* ------------------------------------------------------------------------ */
/* Signed distance of a mask                                                 */

static lsm_status check_slice(const lsm_mask *mask, const lsm_grid *phi, const char *what,
                              lsm_err *err) {
  if (!mask || !mask->pixels || mask->width <= 0 || mask->height <= 0 || !phi)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "%s: bad arguments", what);
  if (phi->nx != mask->width || phi->ny != mask->height)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "%s: %dx%d slice into a %dx%d grid", what,
                    mask->width, mask->height, phi->nx, phi->ny);
  return LSM_OK;
}

/* The box of a mask's inside pixels widened by one pixel within the image:
 * columns i0..i1, rows j0..j1.  Returns the number of inside pixels. */
static size_t inside_box(const lsm_mask *mask, int *i0, int *i1, int *j0, int *j1) {
  const int W = mask->width, H = mask->height;
  size_t count = 0;
  *i0 = W;
  *i1 = -1;
  *j0 = H;
  *j1 = -1;
  for (int j = 0; j < H; ++j) {
    const uint8_t *row = mask->pixels + (size_t)j * (size_t)W;
    for (int i = 0; i < W; ++i) {
      if (!row[i]) continue;
      ++count;
      *i0 = i < *i0 ? i : *i0;
      *i1 = i > *i1 ? i : *i1;
      *j0 = *j0 < H ? *j0 : j;
      *j1 = j;
    }
  }
  if (count) {
    *i0 -= *i0 > 0;
    *j0 -= *j0 > 0;
    *i1 += *i1 + 1 < W;
    *j1 += *j1 + 1 < H;
  }
  return count;
}

lsm_status lsm_sdf_from_mask(const lsm_mask *mask, lsm_grid *phi, lsm_err *err) {
  LSM_TRY(check_slice(mask, phi, "signed distance of a mask", err));
  const int W = mask->width, H = mask->height;
  const size_t npix = (size_t)W * (size_t)H;
  int i0, i1, j0, j1;
  const size_t inside = inside_box(mask, &i0, &i1, &j0, &j1);
  if (inside == 0 || inside == npix) {
    /* No boundary: everything is far outside (empty) or far inside (full). */
    lsm_grid_fill(phi, (inside == 0 ? LSM_SDF_FAR : -LSM_SDF_FAR) * phi->dx);
    return LSM_OK;
  }

  double *d2 = lsm_alloc(npix, sizeof(double), err, "signed distance");
  if (!d2) return err ? err->status : LSM_ERR_NOMEM;
  /* Inside pixels find their nearest outside pixel within the box of the
   * inside widened by one pixel: the widening is outside, and clamping a
   * point beyond the box onto it brings it nearer.  So the second transform
   * runs on that box only (bw x bh), with the same lines and sums. */
  const int bw = i1 - i0 + 1, bh = j1 - j0 + 1;
  uint8_t *outside = lsm_alloc((size_t)bw * (size_t)bh, 1, err, "signed distance");
  if (!outside) {
    free(d2);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  for (int j = 0; j < bh; ++j)
    for (int i = 0; i < bw; ++i)
      outside[(size_t)j * (size_t)bw + (size_t)i] =
          mask->pixels[(size_t)(j0 + j) * (size_t)W + (size_t)(i0 + i)] == 0;

  const double dx = phi->dx, dy = phi->dy;
  /* The boundary lies half a pixel from the pixel centres on either side of
   * it; exact for isotropic pixels, the smaller half-size otherwise. */
  const double half = 0.5 * (dx < dy ? dx : dy);

  /* Outside pixels: distance to the nearest inside pixel centre. */
  lsm_status st = lsm_edt_squared(mask->pixels, W, H, dx, dy, d2, err);
  if (st == LSM_OK) {
    for (int j = 0; j < H; ++j)
      for (int i = 0; i < W; ++i) {
        const size_t k = (size_t)j * (size_t)W + (size_t)i;
        if (!mask->pixels[k]) LSM_AT(phi, i, j) = (float)(sqrt(d2[k]) - half);
      }
    /* Inside pixels: minus the distance to the nearest outside pixel centre. */
    st = lsm_edt_squared(outside, bw, bh, dx, dy, d2, err);
  }
  if (st == LSM_OK) {
    for (int j = 0; j < bh; ++j)
      for (int i = 0; i < bw; ++i) {
        const size_t k = (size_t)j * (size_t)bw + (size_t)i;
        if (!outside[k]) LSM_AT(phi, i0 + i, j0 + j) = (float)(-(sqrt(d2[k]) - half));
      }
    lsm_grid_fill_ghosts(phi);
  }
  free(outside);
  free(d2);
  return st;
}

/* ------------------------------------------------------------------------ */
/* Filling outlines by parity                                                */

#define NO_LABEL UINT32_MAX

/* Contract of lsm_outline_fill (the header leaves it open):
 *  - filled->pixels == NULL: the mask is allocated here (lsm_mask_create) and
 *    belongs to the caller;
 *  - otherwise filled must already have the outline's size;
 *  - filled may be the outline itself (filled in place).
 *
 * Method.  The background (value 0) is split into 4-connected components,
 * the contours (value != 0) into 8-connected ones.  With these two
 * connectivities a contour separates the background on its two sides, and
 * every 4-neighbour of a pixel that lies in another component is of the other
 * kind (two 4-adjacent pixels of the same kind are in the same component).
 * So the components form a bipartite graph (background <-> contour) under
 * 4-adjacency, and the image's pixel grid being connected, so is that graph.
 *
 * The outside of the image is one background region of depth 0 adjacent to
 * every border pixel.  A breadth-first search over the component graph
 * starting from it gives every component its depth: a contour reached from a
 * region of depth d gets d + 1, a region reached from a contour of depth k
 * gets k.  Breadth-first order visits components by number of graph steps,
 * and a region's depth is half its number of steps, so each region gets the
 * smallest number of contours crossed from outside the image.  Inside =
 * regions of odd depth, plus all contour pixels.
 *
 * Consequences at the image border: a background component touching the
 * border has depth 0, so a contour left open against the border (a circle cut
 * by the image edge) encloses nothing — only its pixels are filled.  A
 * contour lying along the border is reached from the outside of the image,
 * so a closed outline drawn on the border frame encloses its interior.
 *
 * Linear time and memory: labelling visits each pixel once, the component
 * search scans each component's pixels once (they are grouped with a
 * counting sort).  No recursion: explicit queues. */
lsm_status lsm_outline_fill(const lsm_mask *outline, lsm_mask *filled, lsm_err *err) {
  if (!outline || !outline->pixels || outline->width <= 0 || outline->height <= 0 || !filled)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "outline fill: bad arguments");
  const int W = outline->width, H = outline->height;
  size_t npix;
  if (!lsm_size_mul((size_t)W, (size_t)H, &npix) || npix > (size_t)INT32_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "outline fill: %dx%d image is too large", W, H);
  if (filled->pixels) {
    if (filled->width != W || filled->height != H)
      return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "outline fill: %dx%d outline into a %dx%d mask",
                      W, H, filled->width, filled->height);
  }
  const uint8_t *in = outline->pixels;

  int32_t *label = lsm_alloc(npix, sizeof *label, err, "outline fill");
  int32_t *queue = label ? lsm_alloc(npix, sizeof *queue, err, "outline fill") : NULL;
  uint32_t *start = NULL, *depth = NULL, *cqueue = NULL;
  lsm_status st = LSM_OK;
  if (!queue) {
    st = err ? err->status : LSM_ERR_NOMEM;
    goto done;
  }

  /* 1. Connected components (lsm_flood): contours 8-connected (unlabelled:
   * -2), background 4-connected (-1), numbered in row-major order. */
  for (size_t k = 0; k < npix; ++k) label[k] = in[k] ? -2 : -1;
  uint32_t ncomp = 0;
  for (size_t seed = 0; seed < npix; ++seed) {
    if (label[seed] >= 0) continue;
    const int32_t open = label[seed];
    label[seed] = (int32_t)ncomp++;
    queue[0] = (int32_t)seed;
    lsm_flood(label, W, H, open == -2 ? 8 : 4, open, queue, 1);
  }

  /* 2. Group the pixels by component (counting sort into queue[]): the
   * pixels of component c are queue[start[c] .. start[c+1]). */
  start = lsm_alloc((size_t)ncomp + 1, sizeof *start, err, "outline fill");
  depth = start ? lsm_alloc(ncomp, sizeof *depth, err, "outline fill") : NULL;
  cqueue = depth ? lsm_alloc(ncomp, sizeof *cqueue, err, "outline fill") : NULL;
  if (!cqueue) {
    st = err ? err->status : LSM_ERR_NOMEM;
    goto done;
  }
  memset(start, 0, ((size_t)ncomp + 1) * sizeof *start);
  for (size_t k = 0; k < npix; ++k) ++start[label[k] + 1];
  for (uint32_t c = 0; c < ncomp; ++c) start[c + 1] += start[c];
  /* place with start[c] as the cursor, then shift the cursors back */
  for (size_t k = 0; k < npix; ++k) queue[start[label[k]]++] = (int32_t)k;
  for (uint32_t c = ncomp; c > 0; --c) start[c] = start[c - 1];
  start[0] = 0;

  /* 3. Depths, breadth first from the outside of the image.  Seed the border
   * background components (depth 0) before the border contours (depth 1) so
   * the queue stays ordered by number of steps. */
  for (uint32_t c = 0; c < ncomp; ++c) depth[c] = NO_LABEL;
  size_t chead = 0, ctail = 0;
  for (int pass = 0; pass < 2; ++pass) {
    for (int j = 0; j < H; ++j) {
      /* the border pixels of row j: all of them on the first and last rows */
      const int step = (j == 0 || j == H - 1) ? 1 : (W > 1 ? W - 1 : 1);
      for (int i = 0; i < W; i += step) {
        const size_t k = (size_t)j * (size_t)W + (size_t)i;
        if ((in[k] != 0) != (pass == 1)) continue;
        const uint32_t c = (uint32_t)label[k];
        if (depth[c] != NO_LABEL) continue;
        depth[c] = (uint32_t)pass;
        cqueue[ctail++] = c;
      }
    }
  }
  while (chead < ctail) {
    const uint32_t c = cqueue[chead++];
    const int is_contour = in[queue[start[c]]] != 0;
    const uint32_t next = is_contour ? depth[c] : depth[c] + 1;
    for (uint32_t m = start[c]; m < start[c + 1]; ++m) {
      const uint32_t p = (uint32_t)queue[m];
      const int i = (int)(p % (uint32_t)W), j = (int)(p / (uint32_t)W);
      const size_t nb[4] = {p - 1, p + 1, p - (size_t)W, p + (size_t)W};
      const int ok[4] = {i > 0, i < W - 1, j > 0, j < H - 1};
      for (int m4 = 0; m4 < 4; ++m4) {
        if (!ok[m4]) continue;
        const uint32_t cq = (uint32_t)label[nb[m4]];
        if (depth[cq] != NO_LABEL) continue; /* includes cq == c */
        depth[cq] = next;
        cqueue[ctail++] = cq;
      }
    }
  }

  /* 4. Output (reads in[k] before writing the same k, so in place is fine). */
  if (!filled->pixels) {
    st = lsm_mask_create(W, H, filled, err);
    if (st != LSM_OK) goto done;
  }
  for (size_t k = 0; k < npix; ++k) {
    const uint32_t dk = depth[label[k]];
    filled->pixels[k] = (uint8_t)(in[k] != 0 || (dk != NO_LABEL && (dk & 1u)));
  }

done:
  free(cqueue);
  free(depth);
  free(start);
  free(queue);
  free(label);
  return st;
}

/* ------------------------------------------------------------------------ */
/* Signed distance of an outline                                             */

lsm_status lsm_sdf_from_outline(const lsm_mask *outline, lsm_grid *phi, lsm_err *err) {
  LSM_TRY(check_slice(outline, phi, "signed distance of an outline", err));
  const int W = outline->width, H = outline->height;
  const size_t npix = (size_t)W * (size_t)H;
  if (lsm_mask_count(outline) == 0) {
    lsm_grid_fill(phi, LSM_SDF_FAR * phi->dx);
    return LSM_OK;
  }

  lsm_mask filled = {0, 0, NULL};
  lsm_status st = lsm_outline_fill(outline, &filled, err);
  if (st != LSM_OK) return st;
  double *d2 = lsm_alloc(npix, sizeof(double), err, "signed distance of an outline");
  if (!d2) {
    lsm_mask_free(&filled);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  st = lsm_edt_squared(outline->pixels, W, H, phi->dx, phi->dy, d2, err);
  if (st == LSM_OK) {
    for (int j = 0; j < H; ++j)
      for (int i = 0; i < W; ++i) {
        const size_t k = (size_t)j * (size_t)W + (size_t)i;
        double v;
        if (outline->pixels[k])
          v = 0.0;
        else
          v = filled.pixels[k] ? -sqrt(d2[k]) : sqrt(d2[k]);
        LSM_AT(phi, i, j) = (float)v;
      }
    lsm_grid_fill_ghosts(phi);
  }
  free(d2);
  lsm_mask_free(&filled);
  return st;
}

/* ------------------------------------------------------------------------ */
/* Convex-hull centroid                                                      */

typedef struct hull_pt {
  int64_t x, y;
} hull_pt;

/* z component of (a - o) x (b - o): > 0 for a counter-clockwise turn in a
 * right-handed frame.  Exact for coordinates below 2^31. */
static int64_t hull_cross(hull_pt o, hull_pt a, hull_pt b) {
  return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

/* Andrew's monotone chain on points sorted lexicographically; writes the hull
 * (no collinear vertices, not closed) to h, which has room for 2n points, and
 * returns its number of vertices. */
static size_t monotone_chain(const hull_pt *p, size_t n, hull_pt *h) {
  if (n < 3) {
    for (size_t k = 0; k < n; ++k) h[k] = p[k];
    return n;
  }
  size_t k = 0;
  for (size_t i = 0; i < n; ++i) { /* one chain, first to last point */
    while (k >= 2 && hull_cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (size_t i = n - 1, lo = k + 1; i-- > 0;) { /* the other chain, back */
    while (k >= lo && hull_cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  return k - 1; /* the last point repeats the first */
}

/* Returns 0 for an empty mask, 1 with (cx, cy) set otherwise, and -1 (with cx,
 * cy set to NaN) if scratch memory cannot be allocated — an addition to the
 * header's contract, for the one failure an int result cannot otherwise
 * report. */
int lsm_hull_centroid(const lsm_mask *mask, double *cx, double *cy) {
  if (!mask || !mask->pixels || mask->width <= 0 || mask->height <= 0) return 0;
  const int W = mask->width, H = mask->height;
  /* Candidates: the leftmost and rightmost inside pixel of every row; the
   * hull of all inside pixel centres is the hull of these.  Generated row by
   * row, left before right, they come sorted by (y, x), which is all the
   * monotone chain needs (with the roles of x and y swapped: the cross
   * product's sign flips, the set of hull vertices does not). */
  size_t bytes; /* 2H candidates, then room for a hull of 4H points */
  hull_pt *pts = lsm_size_mul3(6, (size_t)H, sizeof *pts, &bytes) ? malloc(bytes) : NULL;
  if (!pts) {
    *cx = *cy = NAN;
    return -1;
  }
  size_t n = 0;
  for (int j = 0; j < H; ++j) {
    const uint8_t *row = mask->pixels + (size_t)j * (size_t)W;
    int lo = 0, hi = W - 1;
    while (lo < W && !row[lo]) ++lo;
    if (lo == W) continue;
    while (!row[hi]) --hi;
    pts[n++] = (hull_pt){j, lo}; /* (y, x): sorted order */
    if (hi != lo) pts[n++] = (hull_pt){j, hi};
  }
  if (n == 0) {
    free(pts);
    return 0;
  }
  hull_pt *h = pts + 2 * (size_t)H;
  const size_t m = monotone_chain(pts, n, h);

  /* Shoelace sums relative to the first vertex (small exact integers):
   * A2 = sum cross_k, centroid = origin + sum (p_k + p_k+1) cross_k / (3 A2). */
  int64_t a2 = 0;
  double sy = 0.0, sx = 0.0; /* hull_pt is (y, x) */
  for (size_t k = 1; k + 1 < m; ++k) {
    /* fan triangle (h0, hk, hk+1): same sums as the edge form */
    const int64_t c = hull_cross(h[0], h[k], h[k + 1]);
    a2 += c;
    sy += (double)c * (double)((h[k].x - h[0].x) + (h[k + 1].x - h[0].x));
    sx += (double)c * (double)((h[k].y - h[0].y) + (h[k + 1].y - h[0].y));
  }
  if (a2 == 0) {
    /* A point or a segment (all candidates collinear): the midpoint of the
     * two extreme points, which are the first and last in sorted order. */
    *cx = 0.5 * ((double)pts[0].y + (double)pts[n - 1].y);
    *cy = 0.5 * ((double)pts[0].x + (double)pts[n - 1].x);
  } else {
    *cx = (double)h[0].y + sx / (3.0 * (double)a2);
    *cy = (double)h[0].x + sy / (3.0 * (double)a2);
  }
  free(pts);
  return 1;
}
