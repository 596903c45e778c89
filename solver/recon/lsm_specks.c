/* lsm_specks: output slices with no more parts than their gap allows (see the header). */
#include "solver/recon/lsm_specks.h"

#include <stdlib.h>

#include "solver/base/lsm_flood.h"

/* Labels the 8-connected parts of mask m 0, 1, ... (outside: -1); returns the count. */
static int32_t mask_parts(const lsm_mask *m, int32_t *label, int32_t *queue) {
  const size_t n = (size_t)m->width * (size_t)m->height;
  for (size_t k = 0; k < n; ++k) label[k] = m->pixels[k] ? -2 : -1;
  return lsm_flood_components(label, m->width, m->height, 8, -2, 0, queue);
}

static int32_t root(int32_t *up, int32_t v) {
  while (up[v] != v) v = up[v] = up[up[v]];
  return v;
}

lsm_status lsm_specks_allowed(const lsm_mask *a, const lsm_mask *b, int shift_x, int shift_y,
                              int32_t *label, int32_t *queue, int *allowed, lsm_err *err) {
  const int nx = a->width, ny = a->height;
  const size_t n = (size_t)nx * (size_t)ny;
  int32_t *label_b = lsm_alloc(n, sizeof *label_b, err, "parts of a slice");
  if (!label_b) return err ? err->status : LSM_ERR_NOMEM;
  const int32_t na = mask_parts(a, label, queue), nb = mask_parts(b, label_b, queue);
  /* union-find over A's parts 0 .. na - 1 and B's na .. na + nb - 1, then per
   * group its counts */
  int32_t *up = lsm_alloc((size_t)(na + nb) * 3 + 1, sizeof *up, err, "parts of a gap");
  if (!up) {
    free(label_b);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  int32_t *count_a = up + na + nb, *count_b = count_a + na + nb;
  for (int32_t v = 0; v < na + nb; ++v) up[v] = v, count_a[v] = count_b[v] = 0;
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x) {
      const int32_t pb = label_b[(size_t)y * nx + x];
      const int xa = x - shift_x, ya = y - shift_y;
      if (pb < 0 || xa < 0 || ya < 0 || xa >= nx || ya >= ny) continue;
      const int32_t pa = label[(size_t)ya * nx + xa];
      if (pa < 0) continue;
      const int32_t ra = root(up, pa), rb = root(up, na + pb);
      if (ra != rb) up[rb] = ra;
    }
  for (int32_t v = 0; v < na + nb; ++v) {
    const int32_t r = root(up, v);
    if (v < na) count_a[r]++;
    else count_b[r]++;
  }
  int total = 0;
  for (int32_t v = 0; v < na + nb; ++v) total += count_a[v] > count_b[v] ? count_a[v] : count_b[v];
  *allowed = total;
  free(up);
  free(label_b);
  return LSM_OK;
}

typedef struct part_size {
  int32_t part;
  size_t cells;
} part_size;

/* Larger first; of equal size the earlier in row-major order. */
static int larger_first(const void *x, const void *y) {
  const part_size *p = x, *q = y;
  if (p->cells != q->cells) return p->cells < q->cells ? 1 : -1;
  return (p->part > q->part) - (p->part < q->part);
}

lsm_status lsm_specks_drop(const lsm_specks *s, int width, int height, double pixel, float *out,
                           lsm_err *err) {
  const size_t n = (size_t)width * (size_t)height;
  int32_t *label = s->label;
  for (size_t k = 0; k < n; ++k) label[k] = out[k] <= 0.0f ? -2 : -1;
  const int32_t parts = lsm_flood_components(label, width, height, 8, -2, 0, s->queue);
  if (parts <= s->allowed) return LSM_OK;
  part_size *size = lsm_alloc((size_t)parts, sizeof *size, err, "parts of a slice");
  if (!size) return err ? err->status : LSM_ERR_NOMEM;
  for (int32_t p = 0; p < parts; ++p) size[p] = (part_size){p, 0};
  for (size_t k = 0; k < n; ++k)
    if (label[k] >= 0) size[label[k]].cells++;
  qsort(size, (size_t)parts, sizeof *size, larger_first);
  /* label -> kept (1) or dropped (0), in place of the sizes' order */
  uint8_t *keep = lsm_alloc((size_t)parts, 1, err, "parts of a slice");
  if (!keep) {
    free(size);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  for (int32_t q = 0; q < parts; ++q) keep[size[q].part] = q < s->allowed;
  const float above = (float)(1e-6 * pixel);
  for (size_t k = 0; k < n; ++k)
    if (label[k] >= 0 && !keep[label[k]]) out[k] = -out[k] > above ? -out[k] : above;
  free(keep);
  free(size);
  return LSM_OK;
}
