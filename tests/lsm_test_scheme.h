/* Analytic fields shared by the morph solver's tests (test_scheme.c,
 * test_scheme_cfl.c, test_scheme_reinit.c): circles and planes written on a
 * grid centred on the origin, and the front radius measured from the zero
 * crossings.  Grids come from new_grid (tests/lsm_test_pair.h). */
#ifndef LSM_TEST_SCHEME_H
#define LSM_TEST_SCHEME_H

#include "tests/lsm_test.h"
#include "tests/lsm_test_pair.h"

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"

/* Physical coordinates of cell centres, the grid centred on the origin. */
static inline double cx_of(const lsm_grid *g, int i) { return (i + 0.5) * g->dx - 0.5 * g->nx * g->dx; }
static inline double cy_of(const lsm_grid *g, int j) { return (j + 0.5) * g->dy - 0.5 * g->ny * g->dy; }

/* phi = scale * (|x - c| - r), analytic (not through the EDT). */
static inline void fill_circle(lsm_grid *g, double x0, double y0, double r, double scale) {
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i < g->nx; ++i)
      LSM_AT(g, i, j) = (float)(scale * (hypot(cx_of(g, i) - x0, cy_of(g, j) - y0) - r));
  lsm_grid_fill_ghosts(g);
}

/* phi = a x + b y + off. */
static inline void fill_linear(lsm_grid *g, double a, double b, double off) {
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i < g->nx; ++i)
      LSM_AT(g, i, j) = (float)(a * cx_of(g, i) + b * cy_of(g, j) + off);
  lsm_grid_fill_ghosts(g);
}

/* Zero crossings of phi along every grid row and column, located by linear
 * interpolation between the two cells that straddle it.  Returns the mean
 * distance of the crossings from (x0, y0) and, in *maxdev, the largest
 * |distance - r_ref|; *count gets the number of crossings. */
static inline double front_radius(const lsm_grid *g, double x0, double y0, double r_ref, double *maxdev,
                           int *count) {
  double sum = 0.0, dev = 0.0;
  int n = 0;
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i + 1 < g->nx; ++i) {
      const double a = LSM_AT(g, i, j), b = LSM_AT(g, i + 1, j);
      if ((a <= 0.0) == (b <= 0.0)) continue;
      const double x = cx_of(g, i) + g->dx * a / (a - b), y = cy_of(g, j);
      const double r = hypot(x - x0, y - y0);
      sum += r;
      dev = fmax(dev, fabs(r - r_ref));
      ++n;
    }
  for (int i = 0; i < g->nx; ++i)
    for (int j = 0; j + 1 < g->ny; ++j) {
      const double a = LSM_AT(g, i, j), b = LSM_AT(g, i, j + 1);
      if ((a <= 0.0) == (b <= 0.0)) continue;
      const double x = cx_of(g, i), y = cy_of(g, j) + g->dy * a / (a - b);
      const double r = hypot(x - x0, y - y0);
      sum += r;
      dev = fmax(dev, fabs(r - r_ref));
      ++n;
    }
  if (maxdev) *maxdev = dev;
  if (count) *count = n;
  assert_true(n > 0);
  return sum / n;
}

#endif
