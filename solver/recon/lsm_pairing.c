/* lsm_pairing: which parts take the correspondence field (see the header). */
#include "solver/recon/lsm_pairing.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "solver/base/lsm_flood.h"
#include "solver/sdf/lsm_sdf.h"

struct lsm_pairing {
  int width, height, pad;
  int32_t na, nb;             /* parts: A's 0 .. na - 1, B's na .. na + nb - 1 */
  int32_t *label_a, *label_b; /* per mask pixel: the part (B's from 0), -1 outside */
  int32_t *group;             /* per part: its group's root in place */
  int32_t *count_a, *count_b; /* per root: the group's parts of A and of B */
  int32_t *partner;           /* per A part of a 1:1 group in place: its B part, else -1 */
  uint8_t *moved;             /* per A part of a 1:1 group: moved or turned off itself */
};

static int32_t root(int32_t *up, int32_t v) {
  while (up[v] != v) v = up[v] = up[up[v]];
  return v;
}

static void join(int32_t *up, int32_t u, int32_t v) {
  const int32_t ru = root(up, u), rv = root(up, v);
  if (ru != rv) up[rv] = ru;
}

/* Roots every part (up[v] = its root) and counts each group's parts of A and of B. */
static void count_groups(int32_t *up, int32_t na, int32_t nb, int32_t *count_a, int32_t *count_b) {
  for (int32_t v = 0; v < na + nb; ++v) count_a[v] = count_b[v] = 0;
  for (int32_t v = 0; v < na + nb; ++v) {
    up[v] = root(up, v);
    if (v < na) count_a[up[v]]++;
    else count_b[up[v]]++;
  }
}

/* Labels the 8-connected parts of m 0, 1, ... (outside: -1); returns the count. */
static int32_t label_parts(const lsm_mask *m, int32_t *label, int32_t *queue) {
  const size_t n = (size_t)m->width * (size_t)m->height;
  for (size_t k = 0; k < n; ++k) label[k] = m->pixels[k] ? -2 : -1;
  return lsm_flood_components(label, m->width, m->height, 8, -2, 0, queue);
}

void lsm_pairing_destroy(lsm_pairing **p) {
  if (!p || !*p) return;
  free((*p)->label_a);
  free((*p)->label_b);
  free((*p)->group);
  free((*p)->moved);
  free(*p);
  *p = NULL;
}

lsm_status lsm_pairing_create(const lsm_mask *a, const lsm_mask *b, const lsm_grid *phi_a,
                              const lsm_grid *phi_b, int pad, lsm_pairing **out, int *needs,
                              lsm_err *err) {
  *out = NULL;
  *needs = 0;
  const int w = a->width, h = a->height;
  const size_t cells = (size_t)w * (size_t)h;
  lsm_pairing *p = lsm_alloc(1, sizeof *p, err, "parts of a pair");
  if (!p) return err ? err->status : LSM_ERR_NOMEM;
  memset(p, 0, sizeof *p);
  p->width = w;
  p->height = h;
  p->pad = pad;
  p->label_a = lsm_alloc(cells, sizeof *p->label_a, err, "parts of a pair");
  p->label_b = p->label_a ? lsm_alloc(cells, sizeof *p->label_b, err, "parts of a pair") : NULL;
  int32_t *queue = p->label_b ? lsm_alloc(cells, sizeof *queue, err, "parts of a pair") : NULL;
  if (!queue) {
    lsm_pairing_destroy(&p);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  p->na = label_parts(a, p->label_a, queue);
  p->nb = label_parts(b, p->label_b, queue);
  free(queue);
  const int32_t na = p->na, parts = p->na + p->nb;
  p->group = lsm_alloc((size_t)parts * 4 + 1, sizeof *p->group, err, "parts of a pair");
  p->moved = p->group ? lsm_alloc((size_t)na + 1, 1, err, "parts of a pair") : NULL;
  /* per part: its depth (largest distance inside) and reach (largest distance of its
   * pixels outside the other slice from it), physical units */
  double *depth = p->moved ? lsm_alloc((size_t)parts * 2 + 1, sizeof *depth, err, "parts of a pair")
                           : NULL;
  if (!depth) {
    lsm_pairing_destroy(&p);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  double *reach = depth + parts;
  memset(depth, 0, ((size_t)parts * 2 + 1) * sizeof *depth);
  p->count_a = p->group + parts;
  p->count_b = p->count_a + parts;
  p->partner = p->count_b + parts;
  for (int32_t v = 0; v < parts; ++v) p->group[v] = v;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t k = (size_t)y * w + x;
      const int32_t u = p->label_a[k], v = p->label_b[k] < 0 ? -1 : na + p->label_b[k];
      const double in_a = LSM_AT(phi_a, x + pad, y + pad), in_b = LSM_AT(phi_b, x + pad, y + pad);
      if (u >= 0) depth[u] = fmax(depth[u], -in_a);
      if (v >= 0) depth[v] = fmax(depth[v], -in_b);
      if (u >= 0 && v >= 0) join(p->group, u, v);
      else if (u >= 0) reach[u] = fmax(reach[u], in_b);
      else if (v >= 0) reach[v] = fmax(reach[v], in_a);
    }
  count_groups(p->group, na, p->nb, p->count_a, p->count_b);
  for (int32_t v = 0; v < na; ++v) p->partner[v] = -1;
  for (int32_t v = na; v < parts; ++v) {
    const int32_t r = p->group[v];
    if (p->count_a[r] == 1 && p->count_b[r] == 1) p->partner[r] = v; /* r is the A part */
  }
  int alone_a = 0, alone_b = 0, moved = 0;
  for (int32_t v = 0; v < parts; ++v) {
    const int32_t r = p->group[v];
    if (v >= na) {
      alone_b |= p->count_a[r] == 0;
      continue;
    }
    alone_a |= p->count_b[r] == 0;
    p->moved[v] = 0;
    if (p->partner[v] >= 0) {
      const int32_t q = p->partner[v];
      p->moved[v] = fmin(reach[v], reach[q]) >= 0.5 * fmax(depth[v], depth[q]);
      moved |= p->moved[v];
    }
  }
  free(depth);
  *needs = moved || (alone_a && alone_b);
  *out = p;
  return LSM_OK;
}

/* The part of a mask's labels at canvas point (x, y) (nearest pixel), -1 outside. */
static int32_t part_at(const int32_t *label, int width, int height, int pad, float x, float y) {
  const long px = lroundf(x) - pad, py = lroundf(y) - pad;
  if (px < 0 || py < 0 || px >= width || py >= height) return -1;
  return label[(size_t)py * width + (size_t)px];
}

/* take[v] = 1 for the parts that take the field, given the groups `mid` of the parts
 * carried to the mid frame (roots and counts as in place; member_a: scratch per part);
 * returns how many. */
static int choose(const lsm_pairing *p, const int32_t *mid, const int32_t *mid_a,
                  const int32_t *mid_b, int32_t *member_a, uint8_t *take) {
  const int32_t na = p->na, parts = p->na + p->nb;
  memset(take, 0, (size_t)parts + 1);
  for (int32_t u = 0; u < na; ++u) member_a[mid[u]] = u;
  int taken = 0;
  for (int32_t q = na; q < parts; ++q) {
    const int32_t m = mid[q]; /* B part q: its mid-frame group must be 1:1 */
    if (mid_a[m] != 1 || mid_b[m] != 1) continue;
    const int32_t pa = member_a[m];
    const int32_t r = p->group[pa], s = p->group[q];
    const int alone = p->count_a[r] == 1 && p->count_b[r] == 0 && p->count_a[s] == 0 &&
                      p->count_b[s] == 1;
    const int moved = r == s && p->partner[pa] == q && p->moved[pa];
    if (alone || moved) {
      take[pa] = take[q] = 1;
      taken += 2;
    }
  }
  return taken;
}

lsm_status lsm_pairing_weigh(const lsm_pairing *p, lsm_motion_field *w, int threads, int *taken,
                             lsm_err *err) {
  *taken = 0;
  const int32_t na = p->na, parts = p->na + p->nb;
  const size_t nodes = (size_t)w->nx * (size_t)w->ny, canvas = (size_t)w->cnx * (size_t)w->cny;
  lsm_motion_map back = {0}, fwd = {0}, scratch = {0};
  int32_t *mid = lsm_alloc((size_t)parts * 4 + 1, sizeof *mid, err, "parts of a pair");
  uint8_t *take = mid ? lsm_alloc((size_t)parts + 1, 1, err, "parts of a pair") : NULL;
  uint8_t *still = take ? lsm_alloc(canvas, 1, err, "parts of a pair") : NULL;
  double *dist = still ? lsm_alloc(canvas, sizeof *dist, err, "parts of a pair") : NULL;
  lsm_status st = dist ? LSM_OK : err ? err->status : LSM_ERR_NOMEM;
  if (st == LSM_OK) st = lsm_motion_map_create(w, &back, err);
  if (st == LSM_OK) st = lsm_motion_map_create(w, &fwd, err);
  if (st == LSM_OK) st = lsm_motion_map_create(w, &scratch, err);
  if (st == LSM_OK) {
    /* the groups in the mid frame: A carried half way forward, B half way back */
    lsm_motion_exp(w, -0.5, &back, &scratch, threads);
    lsm_motion_exp(w, 0.5, &fwd, &scratch, threads);
    int32_t *mid_a = mid + parts, *mid_b = mid_a + parts;
    for (int32_t v = 0; v < parts; ++v) mid[v] = v;
    for (int j = 0; j < w->cny; ++j)
      for (int i = 0; i < w->cnx; ++i) {
        float ax, ay, bx, by;
        lsm_motion_map_at(&back, (float)i, (float)j, &ax, &ay);
        const int32_t u = part_at(p->label_a, p->width, p->height, p->pad, i + ax, j + ay);
        if (u < 0) continue;
        lsm_motion_map_at(&fwd, (float)i, (float)j, &bx, &by);
        const int32_t v = part_at(p->label_b, p->width, p->height, p->pad, i + bx, j + by);
        if (v >= 0) join(mid, u, na + v);
      }
    count_groups(mid, na, p->nb, mid_a, mid_b);
    *taken = choose(p, mid, mid_a, mid_b, mid_b + parts, take);
    /* the parts in place, on the canvas */
    int any = 0;
    memset(still, 0, canvas);
    for (int y = 0; y < p->height; ++y)
      for (int x = 0; x < p->width; ++x) {
        const size_t k = (size_t)y * p->width + x;
        const int32_t u = p->label_a[k], v = p->label_b[k];
        const int in_place = (u >= 0 && !take[u]) || (v >= 0 && !take[na + v]);
        still[(size_t)(y + p->pad) * w->cnx + (size_t)(x + p->pad)] = (uint8_t)in_place;
        any |= in_place;
      }
    if (*taken == 0) memset(w->vx, 0, 2 * nodes * sizeof(float)); /* vx, vy: one block */
    else if (any) st = lsm_edt_squared(still, w->cnx, w->cny, 1.0, 1.0, dist, err);
    if (st == LSM_OK && *taken > 0 && any) {
      /* zero at every node of a cell holding a part in place (within sqrt 2 steps), full
       * one step farther */
      const double step = w->step, zero = sqrt(2.0) * step;
      for (int J = 0; J < w->ny; ++J)
        for (int I = 0; I < w->nx; ++I) {
          const int ci = I * w->step < w->cnx ? I * w->step : w->cnx - 1;
          const int cj = J * w->step < w->cny ? J * w->step : w->cny - 1;
          const double d = sqrt(dist[(size_t)cj * w->cnx + ci]);
          const float c = (float)fmin(1.0, fmax(0.0, (d - zero) / step));
          w->vx[(size_t)J * w->nx + I] *= c;
          w->vy[(size_t)J * w->nx + I] *= c;
        }
    }
    if (st == LSM_OK) {
      lsm_motion_exp(w, 1.0, &fwd, &scratch, threads);
      double most = 0.0;
      for (size_t k = 0; k < nodes; ++k) most = fmax(most, hypot(fwd.dx[k], fwd.dy[k]));
      w->max_displacement = most * w->step;
    }
  }
  lsm_motion_map_free(&back);
  lsm_motion_map_free(&fwd);
  lsm_motion_map_free(&scratch);
  free(mid);
  free(take);
  free(still);
  free(dist);
  return st;
}
