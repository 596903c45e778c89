#include "solver/base/lsm_grid.h"

#include "solver/base/lsm_flood.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

lsm_status lsm_mask_create(int width, int height, lsm_mask *out, lsm_err *err) {
  out->width = out->height = 0;
  out->pixels = NULL;
  if (width <= 0 || height <= 0)
    return lsm_fail(err, LSM_ERR_INPUT, NULL, "mask size %dx%d is not positive", width, height);
  size_t n;
  if (!lsm_size_mul((size_t)width, (size_t)height, &n) || n > (size_t)LSM_GRID_CELLS_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "a %dx%d mask has more than %lld cells", width,
                    height, (long long)LSM_GRID_CELLS_MAX);
  out->pixels = calloc(n, 1);
  if (!out->pixels) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate a %dx%d mask", width, height);
  out->width = width;
  out->height = height;
  return LSM_OK;
}

void lsm_mask_free(lsm_mask *mask) {
  if (!mask) return;
  free(mask->pixels);
  mask->pixels = NULL;
  mask->width = mask->height = 0;
}

size_t lsm_mask_count(const lsm_mask *mask) {
  size_t n = (size_t)mask->width * (size_t)mask->height, count = 0;
  for (size_t k = 0; k < n; ++k) count += mask->pixels[k] != 0;
  return count;
}

int lsm_mask_bounds(const lsm_mask *mask, int *x0, int *y0, int *x1, int *y1) {
  int bx0 = mask->width, by0 = mask->height, bx1 = -1, by1 = -1;
  for (int y = 0; y < mask->height; ++y) {
    const uint8_t *row = mask->pixels + (size_t)y * (size_t)mask->width;
    for (int x = 0; x < mask->width; ++x) {
      if (!row[x]) continue;
      if (x < bx0) bx0 = x;
      if (x > bx1) bx1 = x;
      if (y < by0) by0 = y;
      if (y > by1) by1 = y;
    }
  }
  if (bx1 < 0) return 0;
  *x0 = bx0;
  *y0 = by0;
  *x1 = bx1;
  *y1 = by1;
  return 1;
}

/* Allocates the grid; zero-fills it unless the caller overwrites every value. */
static lsm_status grid_alloc(int nx, int ny, float dx, float dy, int zero, lsm_grid **out,
                             lsm_err *err) {
  *out = NULL;
  if (nx <= 0 || ny <= 0)
    return lsm_fail(err, LSM_ERR_INPUT, NULL, "grid size %dx%d is not positive", nx, ny);
  if (!(dx > 0.0f) || !(dy > 0.0f) || !isfinite(dx) || !isfinite(dy))
    return lsm_fail(err, LSM_ERR_INPUT, NULL, "grid spacing %g x %g is not positive", (double)dx, (double)dy);
  size_t rows = (size_t)ny + 2u * LSM_GHOST, cols = (size_t)nx + 2u * LSM_GHOST, n;
  if (!lsm_size_mul(rows, cols, &n))
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "grid size %dx%d overflows", nx, ny);
  /* cell indices are 32-bit where cells are labelled (lsm_grid_label_components) */
  if ((uint64_t)nx * (uint64_t)ny > LSM_GRID_CELLS_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "a %dx%d grid has more than %lld cells", nx, ny,
                    (long long)LSM_GRID_CELLS_MAX);
  lsm_grid *g = malloc(sizeof *g);
  if (!g) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate a grid");
  g->base = lsm_alloc(n, sizeof(float), err, "grid");
  if (!g->base) {
    free(g);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  if (zero) memset(g->base, 0, n * sizeof(float));
  g->nx = nx;
  g->ny = ny;
  g->ghost = LSM_GHOST;
  g->stride = (ptrdiff_t)cols;
  g->dx = dx;
  g->dy = dy;
  g->data = g->base + LSM_GHOST * g->stride + LSM_GHOST;
  *out = g;
  return LSM_OK;
}

lsm_status lsm_grid_create(int nx, int ny, float dx, float dy, lsm_grid **out,
                           lsm_err *err) {
  return grid_alloc(nx, ny, dx, dy, 1, out, err);
}

void lsm_grid_destroy(lsm_grid **grid) {
  if (!grid || !*grid) return;
  free((*grid)->base);
  free(*grid);
  *grid = NULL;
}

static size_t grid_floats(const lsm_grid *g) {
  return (size_t)(g->ny + 2 * g->ghost) * (size_t)g->stride;
}

lsm_status lsm_grid_clone(const lsm_grid *src, lsm_grid **out, lsm_err *err) {
  LSM_TRY(grid_alloc(src->nx, src->ny, src->dx, src->dy, 0, out, err));
  lsm_grid_copy(*out, src);
  return LSM_OK;
}

void lsm_grid_copy(lsm_grid *dst, const lsm_grid *src) {
  memcpy(dst->base, src->base, grid_floats(src) * sizeof(float));
}

void lsm_grid_swap(lsm_grid *a, lsm_grid *b) {
  float *base = a->base, *data = a->data;
  a->base = b->base;
  a->data = b->data;
  b->base = base;
  b->data = data;
}

void lsm_grid_fill(lsm_grid *grid, float value) {
  size_t n = grid_floats(grid);
  for (size_t k = 0; k < n; ++k) grid->base[k] = value;
}

void lsm_grid_fill_ghosts(lsm_grid *g) {
  const int G = g->ghost;
  for (int j = 0; j < g->ny; ++j) {
    float *row = &LSM_AT(g, 0, j);
    for (int k = 1; k <= G; ++k) {
      row[-k] = row[0];
      row[g->nx - 1 + k] = row[g->nx - 1];
    }
  }
  const size_t row_bytes = (size_t)g->stride * sizeof(float);
  for (int k = 1; k <= G; ++k) {
    memcpy(&LSM_AT(g, -G, -k), &LSM_AT(g, -G, 0), row_bytes);
    memcpy(&LSM_AT(g, -G, g->ny - 1 + k), &LSM_AT(g, -G, g->ny - 1), row_bytes);
  }
}

float lsm_grid_min(const lsm_grid *g) {
  float m = INFINITY;
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i < g->nx; ++i) m = fminf(m, LSM_AT(g, i, j));
  return m;
}

float lsm_grid_max(const lsm_grid *g) {
  float m = -INFINITY;
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i < g->nx; ++i) m = fmaxf(m, LSM_AT(g, i, j));
  return m;
}

float lsm_grid_sample(const lsm_grid *g, double x, double y) {
  if (x < 0.0) x = 0.0;
  if (y < 0.0) y = 0.0;
  if (x > g->nx - 1) x = g->nx - 1;
  if (y > g->ny - 1) y = g->ny - 1;
  int i0 = (int)floor(x), j0 = (int)floor(y);
  if (i0 > g->nx - 2) i0 = g->nx > 1 ? g->nx - 2 : 0;
  if (j0 > g->ny - 2) j0 = g->ny > 1 ? g->ny - 2 : 0;
  double fx = x - i0, fy = y - j0;
  int i1 = g->nx > 1 ? i0 + 1 : i0, j1 = g->ny > 1 ? j0 + 1 : j0;
  double v00 = LSM_AT(g, i0, j0), v10 = LSM_AT(g, i1, j0);
  double v01 = LSM_AT(g, i0, j1), v11 = LSM_AT(g, i1, j1);
  return (float)((1 - fy) * ((1 - fx) * v00 + fx * v10) + fy * ((1 - fx) * v01 + fx * v11));
}

int32_t lsm_grid_label_components(const lsm_grid *phi, float level, int32_t *label,
                                  int32_t *queue) {
  const int nx = phi->nx, ny = phi->ny;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) label[(size_t)j * nx + i] = LSM_AT(phi, i, j) <= level ? -1 : -2;
  const int32_t count = lsm_flood_components(label, nx, ny, 8, -1, 0, queue);
  const size_t n = (size_t)nx * (size_t)ny;
  for (size_t k = 0; k < n; ++k)
    if (label[k] < 0) label[k] = -1;
  return count;
}
