/* lsm_pinholes: pinholes of the two-sided morph and the output slices (see the header). */
#include "solver/recon/lsm_pinholes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "solver/base/lsm_flood.h"

/* Classes of a cell for mark_enclosed (a label image, lsm_flood): the
 * outside is open to the flood from the border and from the open cells. */
enum { CELL_REACHED = 0, CELL_OUTSIDE = -1, CELL_INSIDE = -2, CELL_OPEN = -3 };

/* The class of a sample of phi: inside (phi <= 0), outside, or outside and
 * at least `thin` from the inside (open by itself). */
static inline int32_t cell_class(float phi, float thin) {
  return phi <= 0.0f ? CELL_INSIDE : phi >= thin ? CELL_OPEN : CELL_OUTSIDE;
}

/* The enclosed outside of an nx x ny image of cell classes: the 4-connected
 * components of its outside that neither reach the border nor hold an open
 * cell.  (4-connected: the dual of the 8-connected insides of
 * lsm_grid_label_components, so an outside closed by a diagonal step of the
 * inside is closed.)  On return cls[k] is 1 on those cells and 0 elsewhere. */
static size_t mark_enclosed_in(int32_t *cls, int nx, int ny, int32_t *queue) {
  const size_t n = (size_t)nx * (size_t)ny;
  size_t tail = 0;
  for (size_t k = 0; k < n; ++k) {
    const int i = (int)(k % (size_t)nx), j = (int)(k / (size_t)nx);
    const int border = i == 0 || j == 0 || i == nx - 1 || j == ny - 1;
    if (cls[k] == CELL_OPEN || (cls[k] == CELL_OUTSIDE && border)) {
      cls[k] = CELL_REACHED;
      queue[tail++] = (int32_t)k;
    }
  }
  lsm_flood(cls, nx, ny, 4, CELL_OUTSIDE, queue, tail);
  size_t marked = 0;
  for (size_t k = 0; k < n; ++k) {
    cls[k] = cls[k] == CELL_OUTSIDE;
    marked += (size_t)cls[k];
  }
  return marked;
}

/* mark_enclosed_in on the box of the inside cells: an enclosed outside lies
 * within it, and an outside cell on the box's edge is joined to the border by
 * the cells beyond, which are all outside.  The box is compacted to the front
 * of cls and moved back; the cells beyond it get 0.  queue holds nx * ny
 * cells.  Returns the number of cells marked. */
static size_t mark_enclosed(int32_t *cls, int nx, int ny, int32_t *queue) {
  int i0 = nx, i1 = -1, j0 = ny, j1 = -1;
  for (int j = 0; j < ny; ++j) {
    const int32_t *row = cls + (size_t)j * (size_t)nx;
    for (int i = 0; i < nx; ++i) {
      if (row[i] != CELL_INSIDE) continue;
      i0 = i < i0 ? i : i0;
      i1 = i > i1 ? i : i1;
      j0 = j < j0 ? j : j0;
      j1 = j;
    }
  }
  const size_t n = (size_t)nx * (size_t)ny, cell = sizeof *cls;
  if (i1 < 0) {
    memset(cls, 0, n * cell);
    return 0;
  }
  const int bw = i1 - i0 + 1, bh = j1 - j0 + 1;
  const size_t box_w = (size_t)bw;
  for (int r = 0; r < bh; ++r)
    memmove(cls + (size_t)r * box_w, cls + (size_t)(j0 + r) * (size_t)nx + (size_t)i0,
            box_w * cell);
  const size_t marked = mark_enclosed_in(cls, bw, bh, queue);
  for (int r = bh - 1; r >= 0; --r)
    memmove(cls + (size_t)(j0 + r) * (size_t)nx + (size_t)i0, cls + (size_t)r * box_w,
            box_w * cell);
  memset(cls, 0, (size_t)j0 * (size_t)nx * cell);
  for (int j = j0; j <= j1; ++j) {
    int32_t *row = cls + (size_t)j * (size_t)nx;
    memset(row, 0, (size_t)i0 * cell);
    memset(row + i1 + 1, 0, (size_t)(nx - 1 - i1) * cell);
  }
  memset(cls + (size_t)(j1 + 1) * (size_t)nx, 0, (size_t)(ny - 1 - j1) * (size_t)nx * cell);
  return marked;
}

/* Marks (hole[k] = 1) the cells of phi's pinholes: the enclosed outside
 * components of phi that lie everywhere less than `thin` from the inside.
 * cls and queue hold nx * ny cells.  Returns the number of cells marked. */
static size_t mark_pinholes(const lsm_grid *phi, float thin, uint8_t *hole, int32_t *cls,
                            int32_t *queue) {
  const int nx = phi->nx, ny = phi->ny;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      cls[(size_t)j * (size_t)nx + (size_t)i] = cell_class(LSM_AT(phi, i, j), thin);
  const size_t marked = mark_enclosed(cls, nx, ny, queue);
  const size_t n = (size_t)nx * (size_t)ny;
  for (size_t k = 0; k < n; ++k) hole[k] = (uint8_t)cls[k];
  return marked;
}

/* Whether a slice's region has a hole: an outside component that does not
 * reach the image border.  cls and queue hold width x height cells. */
int lsm_mask_has_hole(const lsm_mask *m, int32_t *cls, int32_t *queue) {
  const size_t n = (size_t)m->width * (size_t)m->height;
  for (size_t k = 0; k < n; ++k) cls[k] = m->pixels[k] ? CELL_INSIDE : CELL_OUTSIDE;
  return mark_enclosed(cls, m->width, m->height, queue) > 0;
}

/* Such holes are not interpolated from the slices but made by the morph where
 * two parts merge: the outside between them, a ridge of phi, does not sink
 * below zero all at once.  Larger thin holes are left: most of their pixels
 * are notches whose mouth the morph closed, outside in the truth too. */
lsm_status lsm_pinholes_fill(lsm_pinhole_fill *f, const lsm_stack_opts *o, int width, int height,
                             float *out, lsm_err *err) {
  const float thin = (float)(o->rules.pinhole_fill_thin_px * fmax(o->pixel_dx, o->pixel_dy));
  const size_t most = (size_t)o->rules.pinhole_fill_cells;
  const int nx = width, ny = height;
  const size_t n = (size_t)nx * (size_t)ny;
  int32_t *cls = f->cls, *queue = f->queue;
  for (size_t k = 0; k < n; ++k) cls[k] = cell_class(out[k], thin);
  if (mark_enclosed(cls, nx, ny, queue) == 0) return LSM_OK;
  for (size_t start = 0; start < n; ++start) {
    if (cls[start] != 1) continue;
    cls[start] = 2; /* one hole at a time: its cells 1 -> 2 */
    queue[0] = (int32_t)start;
    const size_t tail = lsm_flood(cls, nx, ny, 4, 1, queue, 1);
    if (tail > most) continue;
    if (!f->phi_a) {
      const float hx = (float)o->pixel_dx, hy = (float)o->pixel_dy;
      LSM_TRY(lsm_grid_create(nx, ny, hx, hy, &f->phi_a, err));
      LSM_TRY(lsm_grid_create(nx, ny, hx, hy, &f->phi_b, err));
      LSM_TRY(lsm_slice_phi(f->a, o, 0, 0, f->phi_a, err));
      LSM_TRY(lsm_slice_phi(f->b, o, 0, 0, f->phi_b, err));
    }
    int inside_one = 1;
    for (size_t q = 0; q < tail && inside_one; ++q) {
      const int i = queue[q] % nx, j = queue[q] / nx;
      inside_one = fminf(LSM_AT(f->phi_a, i, j), LSM_AT(f->phi_b, i, j)) < 0.0f;
    }
    for (size_t q = 0; q < tail && inside_one; ++q) {
      const int i = queue[q] % nx, j = queue[q] / nx;
      const float low = fminf(LSM_AT(f->phi_a, i, j), LSM_AT(f->phi_b, i, j));
      out[queue[q]] = fmaxf(-out[queue[q]], low);
    }
  }
  return LSM_OK;
}

lsm_status lsm_pinholes_find(const lsm_grid *phi_a, const lsm_grid *phi_b, float thin_px,
                             uint8_t **pinhole, lsm_err *err) {
  const int nx = phi_a->nx, ny = phi_a->ny;
  const size_t cells = (size_t)nx * (size_t)ny;
  const float thin = thin_px * fmaxf(phi_a->dx, phi_a->dy);
  uint8_t *hole_a = lsm_alloc(cells, 1, err, "pinholes");
  uint8_t *hole_b = hole_a ? lsm_alloc(cells, 1, err, "pinholes") : NULL;
  int32_t *cls = hole_b ? lsm_alloc(cells, sizeof *cls, err, "pinholes") : NULL;
  int32_t *queue = cls ? lsm_alloc(cells, sizeof *queue, err, "pinholes") : NULL;
  if (!queue) {
    free(hole_a);
    free(hole_b);
    free(cls);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  const size_t marked = mark_pinholes(phi_a, thin, hole_a, cls, queue) +
                        mark_pinholes(phi_b, thin, hole_b, cls, queue);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const size_t k = (size_t)j * (size_t)nx + (size_t)i;
      hole_a[k] = LSM_AT(phi_a, i, j) > 0.0f ? hole_a[k] : hole_b[k];
    }
  free(hole_b);
  free(cls);
  free(queue);
  if (marked) *pinhole = hole_a;
  else free(hole_a);
  return LSM_OK;
}
