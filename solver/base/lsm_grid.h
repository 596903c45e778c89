/* lsm_grid: the two image types every module shares.
 *
 * lsm_mask  — a binary slice: width x height bytes, row-major, row 0 at the top
 *             (PNG order), 1 = inside the object, 0 = outside.
 * lsm_grid  — a float field (phi) on cell centres with a ghost layer of width
 *             LSM_GHOST around the nx x ny interior, so stencils up to +-4 cells
 *             run without bounds checks.  Values are in physical units; dx, dy
 *             are the cell spacings (pixel size).  LSM_AT(g, i, j) is cell
 *             (column i, row j); i in [-ghost, nx+ghost), j likewise.
 */
#ifndef LSM_GRID_H
#define LSM_GRID_H

#include <stddef.h>
#include <stdint.h>

#include "solver/base/lsm_status.h"

/* Roe-Fix's widened sets reach 3 cells away and differences one more. */
#define LSM_GHOST 4

/* The most cells (interior) of a grid or mask: connected parts are labelled
 * with 32-bit cell indices.  Creating a larger one fails with LSM_ERR_LIMIT. */
#define LSM_GRID_CELLS_MAX INT32_MAX

typedef struct lsm_mask {
  int width, height;
  uint8_t *pixels; /* width*height, 1 inside, 0 outside */
} lsm_mask;

typedef struct lsm_grid {
  int nx, ny;        /* interior size in cells */
  int ghost;         /* ghost width (LSM_GHOST) */
  ptrdiff_t stride;  /* floats per row, nx + 2*ghost */
  float dx, dy;      /* physical cell size */
  float *base;       /* owned allocation */
  float *data;       /* &cell(0,0) */
} lsm_grid;

#define LSM_AT(g, i, j) ((g)->data[(ptrdiff_t)(j) * (g)->stride + (i)])

/* Threads worth using for a sweep over g: below about 2^16 cells a parallel
 * region costs more than it saves, so small grids run on one thread. */
static inline int lsm_grid_threads(const lsm_grid *g, int threads) {
  return (long)g->nx * (long)g->ny < 65536L || threads < 1 ? 1 : threads;
}

/* Allocates an nx x ny mask of zeros. */
lsm_status lsm_mask_create(int width, int height, lsm_mask *out, lsm_err *err);
void lsm_mask_free(lsm_mask *mask);
/* Number of inside pixels. */
size_t lsm_mask_count(const lsm_mask *mask);
/* Bounding box of the inside pixels, inclusive; 0 (box untouched) if there
 * are none. */
int lsm_mask_bounds(const lsm_mask *mask, int *x0, int *y0, int *x1, int *y1);

/* Allocates an nx x ny grid (ghosts included) filled with zeros. */
lsm_status lsm_grid_create(int nx, int ny, float dx, float dy, lsm_grid **out,
                           lsm_err *err);
void lsm_grid_destroy(lsm_grid **grid);
/* Same size and spacing as src, contents copied (ghosts included). */
lsm_status lsm_grid_clone(const lsm_grid *src, lsm_grid **out, lsm_err *err);
void lsm_grid_copy(lsm_grid *dst, const lsm_grid *src);
/* Exchanges the contents of two grids of the same size and spacing in O(1)
 * (their buffers change hands; the grid structs stay where they are). */
void lsm_grid_swap(lsm_grid *a, lsm_grid *b);
void lsm_grid_fill(lsm_grid *grid, float value);
/* Zero-gradient (nearest interior value) extension into the ghost layer. */
void lsm_grid_fill_ghosts(lsm_grid *grid);
/* Interior min / max. */
float lsm_grid_min(const lsm_grid *grid);
float lsm_grid_max(const lsm_grid *grid);
/* Bilinear sample at continuous cell coordinates (x, y) (cell centres at
 * integers), clamped to the interior. */
float lsm_grid_sample(const lsm_grid *grid, double x, double y);

/* Connected components (8-neighbours) of {phi <= level} over the interior:
 * label[i + j nx] = the component (0, 1, ... in row-major order of their first
 * cell) or -1; returns the count.  label and queue hold nx * ny entries.
 * (lsm_flood labels other images.) */
int32_t lsm_grid_label_components(const lsm_grid *phi, float level, int32_t *label,
                                  int32_t *queue);

#endif
