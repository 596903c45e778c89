/* A morph pair for the backend tests (test_backend.c, test_opencl.c). */
#ifndef LSM_TEST_PAIR_H
#define LSM_TEST_PAIR_H

#include "tests/lsm_test.h"

#include "solver/base/lsm_grid.h"

static inline lsm_grid *new_grid(int nx, int ny, float dx, float dy) {
  lsm_grid *g = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_grid_create(nx, ny, dx, dy, &g, &err), LSM_OK);
  return g;
}

/* Source: SDF of a disc; target: an offset, squashed disc (an ellipse-like
 * field, not exactly a distance), so F changes sign and every Roe-Fix branch
 * is taken. */
static inline void fill_pair(lsm_grid *src, lsm_grid *dst) {
  const int nx = src->nx, ny = src->ny;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      double x = (i + 0.5) * src->dx, y = (j + 0.5) * src->dy;
      double ex = 0.42 * nx * src->dx, ey = 0.5 * ny * src->dy, r = 0.3 * ny * src->dy;
      LSM_AT(src, i, j) = (float)(hypot(x - ex, y - ey) - r);
      LSM_AT(dst, i, j) = (float)(hypot(x - 0.58 * nx * src->dx, 1.4 * (y - 0.55 * ny * src->dy)) -
                                  0.26 * ny * src->dy);
    }
  lsm_grid_fill_ghosts(src);
  lsm_grid_fill_ghosts(dst);
}

#endif
