/* lsm_register: translation of largest overlap between two masks (see the header). */
#include "solver/recon/lsm_register.h"

#include <stdint.h>
#include <stdlib.h>

/* An inclusive pixel box; empty when x0 > x1. */
typedef struct box {
  int x0, y0, x1, y1;
} box;

static box mask_box(const lsm_mask *m) {
  box b = {0, 0, -1, -1};
  lsm_mask_bounds(m, &b.x0, &b.y0, &b.x1, &b.y1);
  return b;
}

static int imin(int a, int b) { return a < b ? a : b; }
static int imax(int a, int b) { return a > b ? a : b; }

/* One level of a coverage pyramid over the crop box: level l holds, per
 * block of 2^l x 2^l pixels, how many of them are inside.  Level 0 is the
 * mask itself (not copied). */
typedef struct level {
  int width, height;   /* level size */
  float *count;        /* width x height (NULL at level 0) */
  box shape;           /* the shape's box at this level, crop coordinates */
} level;

/* Overlap at one level: sum over cells p of A(p) B(p + t), restricted to the
 * rows and columns where both shapes' boxes meet. */
static double level_overlap(const level *la, const level *lb, const lsm_mask *ma,
                            const lsm_mask *mb, int ox, int oy, int tx, int ty) {
  const int y0 = imax(la->shape.y0, lb->shape.y0 - ty), y1 = imin(la->shape.y1, lb->shape.y1 - ty);
  const int x0 = imax(la->shape.x0, lb->shape.x0 - tx), x1 = imin(la->shape.x1, lb->shape.x1 - tx);
  double sum = 0.0;
  if (y0 > y1 || x0 > x1) return 0.0;
  if (!la->count) { /* level 0: the masks, offset by the crop origin */
    for (int y = y0; y <= y1; ++y) {
      const uint8_t *pa = ma->pixels + (size_t)(y + oy) * (size_t)ma->width + ox;
      const uint8_t *pb = mb->pixels + (size_t)(y + ty + oy) * (size_t)mb->width + ox + tx;
      size_t n = 0;
      for (int x = x0; x <= x1; ++x) n += pa[x] & pb[x];
      sum += (double)n;
    }
    return sum;
  }
  for (int y = y0; y <= y1; ++y) {
    const float *pa = la->count + (size_t)y * (size_t)la->width;
    const float *pb = lb->count + (size_t)(y + ty) * (size_t)lb->width + tx;
    float row = 0.0f; /* whole numbers below 2^24: exact */
    for (int x = x0; x <= x1; ++x) row += pa[x] * pb[x];
    sum += (double)row;
  }
  return sum;
}

size_t lsm_mask_overlap(const lsm_mask *a, const lsm_mask *b, int dx, int dy) {
  size_t count = 0;
  for (int y = 0; y < a->height; ++y) {
    const int yb = y + dy;
    if (yb < 0 || yb >= b->height) continue;
    const uint8_t *pa = a->pixels + (size_t)y * (size_t)a->width;
    const uint8_t *pb = b->pixels + (size_t)yb * (size_t)b->width;
    for (int x = 0; x < a->width; ++x) {
      const int xb = x + dx;
      if (xb >= 0 && xb < b->width) count += pa[x] && pb[xb];
    }
  }
  return count;
}

/* Fills levels 1..top of one mask over the crop box (origin ox, oy; size
 * cw x ch), level 0 being the mask. */
static void build_pyramid(const lsm_mask *m, int ox, int oy, int cw, int ch, box shape, level *lv,
                          int top) {
  lv[0].width = cw;
  lv[0].height = ch;
  lv[0].count = NULL;
  lv[0].shape = (box){shape.x0 - ox, shape.y0 - oy, shape.x1 - ox, shape.y1 - oy};
  for (int l = 1; l <= top; ++l) {
    level *up = &lv[l];
    const level *dn = &lv[l - 1];
    for (size_t k = 0; k < (size_t)up->width * (size_t)up->height; ++k) up->count[k] = 0.0f;
    for (int y = 0; y < dn->height; ++y)
      for (int x = 0; x < dn->width; ++x) {
        const float v = dn->count ? dn->count[(size_t)y * (size_t)dn->width + x]
                                  : (float)m->pixels[(size_t)(y + oy) * (size_t)m->width + x + ox];
        up->count[(size_t)(y >> 1) * (size_t)up->width + (x >> 1)] += v;
      }
    up->shape = (box){dn->shape.x0 >> 1, dn->shape.y0 >> 1, dn->shape.x1 >> 1, dn->shape.y1 >> 1};
  }
}

/* Is (tx, ty) with overlap v better than the best so far? */
static int better(double v, int tx, int ty, double best, int bx, int by) {
  if (v != best) return v > best;
  return (long)tx * tx + (long)ty * ty < (long)bx * bx + (long)by * by;
}

#define LSM_REGISTER_LEVELS 24

lsm_status lsm_register_shift(const lsm_mask *a, const lsm_mask *b, int *dx, int *dy,
                              lsm_err *err) {
  *dx = *dy = 0;
  const box ba = mask_box(a), bb = mask_box(b);
  if (ba.x0 > ba.x1 || bb.x0 > bb.x1) return LSM_OK;
  /* the crop: both shapes' box */
  const int ox = imin(ba.x0, bb.x0), oy = imin(ba.y0, bb.y0);
  const int cw = imax(ba.x1, bb.x1) - ox + 1, ch = imax(ba.y1, bb.y1) - oy + 1;
  int top = 0;
  while (top + 1 < LSM_REGISTER_LEVELS && (imax(cw, ch) >> top) > LSM_REGISTER_COARSE) ++top;
  level la[LSM_REGISTER_LEVELS], lb[LSM_REGISTER_LEVELS];
  float *store = NULL;
  size_t total = 0;
  for (int l = 1; l <= top; ++l) {
    la[l].width = lb[l].width = ((cw - 1) >> l) + 1;
    la[l].height = lb[l].height = ((ch - 1) >> l) + 1;
    total += 2 * (size_t)la[l].width * (size_t)la[l].height;
  }
  if (total) {
    store = malloc(total * sizeof *store);
    if (!store)
      return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate %zu floats to register two slices",
                      total);
    float *next = store;
    for (int l = 1; l <= top; ++l) {
      const size_t n = (size_t)la[l].width * (size_t)la[l].height;
      la[l].count = next;
      lb[l].count = next + n;
      next += 2 * n;
    }
  }
  build_pyramid(a, ox, oy, cw, ch, ba, la, top);
  build_pyramid(b, ox, oy, cw, ch, bb, lb, top);

  /* exhaustive at the top: every shift where the two boxes meet */
  const level *ta = &la[top], *tb = &lb[top];
  int tx = 0, ty = 0;
  double best = -1.0;
  for (int sy = tb->shape.y0 - ta->shape.y1; sy <= tb->shape.y1 - ta->shape.y0; ++sy)
    for (int sx = tb->shape.x0 - ta->shape.x1; sx <= tb->shape.x1 - ta->shape.x0; ++sx) {
      const double v = level_overlap(ta, tb, a, b, ox, oy, sx, sy);
      if (better(v, sx, sy, best, tx, ty)) best = v, tx = sx, ty = sy;
    }
  /* refine: the 3 x 3 shifts around the doubled one, level by level */
  for (int l = top - 1; l >= 0; --l) {
    const int cx = 2 * tx, cy = 2 * ty;
    best = -1.0;
    for (int sy = cy - 1; sy <= cy + 1; ++sy)
      for (int sx = cx - 1; sx <= cx + 1; ++sx) {
        const double v = level_overlap(&la[l], &lb[l], a, b, ox, oy, sx, sy);
        if (better(v, sx, sy, best, tx, ty)) best = v, tx = sx, ty = sy;
      }
  }
  free(store);
  *dx = tx;
  *dy = ty;
  return LSM_OK;
}
