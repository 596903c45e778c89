/* lsm_parts: parts of a slice that moved off their place (see the header). */
#include "solver/recon/lsm_parts.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "solver/base/lsm_flood.h"

/* Slices with more components than this are left alone (noise, not parts). */
#define LSM_PARTS_COMPONENTS 256

typedef struct part {
  size_t area;
  double cx, cy; /* mean pixel position */
  int free;      /* overlaps nothing of the other slice, off the border */
} part;

/* 8-connected components of m: label per pixel (-1 outside), and per part
 * its area, centre and whether it is free.  *n = -1 when there are more than
 * LSM_PARTS_COMPONENTS. */
static void label_parts(const lsm_mask *m, const lsm_mask *other, int32_t *label, int32_t *queue,
                        part *parts, int *n) {
  const int w = m->width, h = m->height;
  const size_t cells = (size_t)w * (size_t)h;
  for (size_t k = 0; k < cells; ++k) label[k] = m->pixels[k] ? -1 : -2;
  const int32_t count = lsm_flood_components(label, w, h, 8, -1, 0, queue);
  *n = count > LSM_PARTS_COMPONENTS ? -1 : (int)count;
  for (int c = 0; c < *n; ++c) parts[c] = (part){0, 0.0, 0.0, 1};
  for (size_t k = 0; k < cells; ++k) {
    const int32_t c = label[k];
    if (c < 0) {
      label[k] = -1;
      continue;
    }
    if (*n < 0) continue;
    const int x = (int)(k % (size_t)w), y = (int)(k / (size_t)w);
    part *p = &parts[c];
    p->area++;
    p->cx += x; /* sums of whole numbers: exact in any order */
    p->cy += y;
    if (other->pixels[k] || x == 0 || y == 0 || x == w - 1 || y == h - 1) p->free = 0;
  }
  for (int c = 0; c < *n; ++c) {
    parts[c].cx /= (double)parts[c].area;
    parts[c].cy /= (double)parts[c].area;
  }
}

/* The part of `to` nearest to point (x, y), with the distance to it and to
 * the next nearest (INFINITY when there is none). */
static int nearest(const part *to, int n, double x, double y, double *d1, double *d2) {
  int best = -1;
  *d1 = *d2 = INFINITY;
  for (int k = 0; k < n; ++k) {
    const double d = hypot(to[k].cx - x, to[k].cy - y);
    if (d < *d1) {
      *d2 = *d1;
      *d1 = d;
      best = k;
    } else if (d < *d2) {
      *d2 = d;
    }
  }
  return best;
}

/* Pixels of part ia (labels la) that land on part ib (labels lb) once moved
 * by (dx, dy). */
static size_t part_overlap(const int32_t *la, const int32_t *lb, int w, int h, int ia, int ib,
                           int dx, int dy) {
  size_t count = 0;
  for (int y = 0; y < h; ++y) {
    const int yb = y + dy;
    if (yb < 0 || yb >= h) continue;
    for (int x = 0; x < w; ++x) {
      const int xb = x + dx;
      if (xb < 0 || xb >= w || la[(size_t)y * w + x] != ia) continue;
      count += lb[(size_t)yb * w + xb] == ib;
    }
  }
  return count;
}

static lsm_status part_mask(const int32_t *label, int w, int h, int id, lsm_mask *out,
                            lsm_err *err) {
  LSM_TRY(lsm_mask_create(w, h, out, err));
  for (size_t k = 0; k < (size_t)w * (size_t)h; ++k) out->pixels[k] = label[k] == id;
  return LSM_OK;
}

void lsm_part_move_free(lsm_part_move *move) {
  lsm_mask_free(&move->part_a);
  lsm_mask_free(&move->part_b);
  memset(move, 0, sizeof *move);
}

lsm_status lsm_parts_moved(const lsm_mask *a, const lsm_mask *b, const lsm_rules *rules,
                           lsm_part_move *moves, int *count, lsm_err *err) {
  *count = 0;
  if (!rules) rules = lsm_rules_defaults();
  const int clear = lsm_rule_on(rules, LSM_RULE_PARTS_CLEAR);
  const int w = a->width, h = a->height;
  const size_t cells = (size_t)w * (size_t)h;
  int32_t *la = lsm_alloc(cells, sizeof *la, err, "part labels");
  int32_t *lb = la ? lsm_alloc(cells, sizeof *lb, err, "part labels") : NULL;
  int32_t *queue = lb ? lsm_alloc(cells, sizeof *queue, err, "part queue") : NULL;
  part *pa = queue ? lsm_alloc(2 * LSM_PARTS_COMPONENTS, sizeof *pa, err, "parts") : NULL;
  if (!pa) {
    free(la);
    free(lb);
    free(queue);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  part *pb = pa + LSM_PARTS_COMPONENTS;
  int na, nb;
  label_parts(a, b, la, queue, pa, &na);
  label_parts(b, a, lb, queue, pb, &nb);
  /* candidate pairs, then the nearest LSM_PARTS_MAX of them */
  int pair_a[LSM_PARTS_COMPONENTS];
  int pair_b[LSM_PARTS_COMPONENTS];
  double dist[LSM_PARTS_COMPONENTS];
  int pairs = 0;
  for (int i = 0; i < na && nb > 0; ++i) {
    if (!pa[i].free) continue;
    double d1, d2, e1, e2;
    const int j = nearest(pb, nb, pa[i].cx, pa[i].cy, &d1, &d2);
    if (!pb[j].free || (clear && d2 < rules->parts_clear * d1)) continue;
    if (nearest(pa, na, pb[j].cx, pb[j].cy, &e1, &e2) != i || (clear && e2 < rules->parts_clear * e1))
      continue;
    const double ratio = (double)pa[i].area / (double)pb[j].area;
    if (lsm_rule_on(rules, LSM_RULE_PARTS_AREA) &&
        (ratio > rules->parts_area_ratio || ratio < 1.0 / rules->parts_area_ratio))
      continue;
    const int dx = (int)lround(pb[j].cx - pa[i].cx), dy = (int)lround(pb[j].cy - pa[i].cy);
    const size_t inter = part_overlap(la, lb, w, h, i, j, dx, dy);
    const double iou = (double)inter / (double)(pa[i].area + pb[j].area - inter);
    if (lsm_rule_on(rules, LSM_RULE_PARTS_IOU) && iou < rules->parts_iou) continue;
    pair_a[pairs] = i;
    pair_b[pairs] = j;
    dist[pairs] = d1;
    pairs++;
  }
  lsm_status st = LSM_OK;
  while (st == LSM_OK && pairs > 0 && *count < LSM_PARTS_MAX) {
    int k = 0;
    for (int q = 1; q < pairs; ++q)
      if (dist[q] < dist[k]) k = q;
    lsm_part_move *m = &moves[*count];
    memset(m, 0, sizeof *m);
    st = part_mask(la, w, h, pair_a[k], &m->part_a, err);
    if (st == LSM_OK) st = part_mask(lb, w, h, pair_b[k], &m->part_b, err);
    if (st != LSM_OK) {
      lsm_part_move_free(m);
      break;
    }
    m->dx = pb[pair_b[k]].cx - pa[pair_a[k]].cx;
    m->dy = pb[pair_b[k]].cy - pa[pair_a[k]].cy;
    ++*count;
    pairs--;
    pair_a[k] = pair_a[pairs];
    pair_b[k] = pair_b[pairs];
    dist[k] = dist[pairs];
  }
  if (st != LSM_OK) {
    for (int k = 0; k < *count; ++k) lsm_part_move_free(&moves[k]);
    *count = 0;
  }
  free(la);
  free(lb);
  free(queue);
  free(pa);
  return st;
}
