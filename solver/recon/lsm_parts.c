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

/* The part of `to` nearest to point (x, y), with the distance to it; -1 when
 * two are nearest alike (which part went where is then not told, and the
 * pairing must not depend on the order the parts were labelled in). */
static int nearest(const part *to, int n, double x, double y, double *distance) {
  int best = -1, tie = 0;
  *distance = INFINITY;
  for (int k = 0; k < n; ++k) {
    const double d = hypot(to[k].cx - x, to[k].cy - y);
    tie = d == *distance ? 1 : d < *distance ? 0 : tie;
    if (d < *distance) {
      *distance = d;
      best = k;
    }
  }
  return tie ? -1 : best;
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
    double d1, e1;
    const int j = nearest(pb, nb, pa[i].cx, pa[i].cy, &d1);
    if (j < 0 || !pb[j].free || nearest(pa, na, pb[j].cx, pb[j].cy, &e1) != i) continue;
    const double ratio = (double)pa[i].area / (double)pb[j].area;
    if (lsm_rule_on(rules, LSM_RULE_PARTS_AREA) &&
        (ratio > rules->parts_area_ratio || ratio < 1.0 / rules->parts_area_ratio))
      continue;
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
