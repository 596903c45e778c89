/* Helpers shared by the cmocka tests of the particle level set
 * (tests/test_particles_*.c): grids, disc signed distances, an independent
 * bilinear interpolation, and lsm_particles calls that must succeed. */
#ifndef LSM_TEST_PARTICLES_H
#define LSM_TEST_PARTICLES_H

#include "tests/lsm_test.h"

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/pde/lsm_particles.h"

/* ------------------------------------------------------------------------ */
/* helpers                                                                   */

static inline lsm_grid *new_grid(int w, int h, float dx, float dy) {
  lsm_grid *g = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_grid_create(w, h, dx, dy, &g, &err), LSM_OK);
  return g;
}

/* Signed distance to a disc (negative inside), physical units, centre in cells. */
static inline void fill_disc(lsm_grid *g, double cx, double cy, double radius) {
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i < g->nx; ++i) {
      double ex = (i - cx) * g->dx, ey = (j - cy) * g->dy;
      LSM_AT(g, i, j) = (float)(sqrt(ex * ex + ey * ey) - radius);
    }
  lsm_grid_fill_ghosts(g);
}

/* Independent bilinear interpolation (double) at cell coordinates. */
static inline double bilinear(const lsm_grid *g, double x, double y) {
  int i = (int)floor(x), j = (int)floor(y);
  if (i > g->nx - 2) i = g->nx - 2;
  if (j > g->ny - 2) j = g->ny - 2;
  if (i < 0) i = 0;
  if (j < 0) j = 0;
  double fx = x - i, fy = y - j;
  return (1 - fy) * ((1 - fx) * LSM_AT(g, i, j) + fx * LSM_AT(g, i + 1, j)) +
         fy * ((1 - fx) * LSM_AT(g, i, j + 1) + fx * LSM_AT(g, i + 1, j + 1));
}

static inline lsm_particles *new_pls(const lsm_grid *phi, const lsm_pls_opts *o) {
  lsm_particles *p = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = lsm_pls_create(phi, o, &p, &err);
  if (st != LSM_OK) fail_msg("lsm_pls_create: %s", err.msg);
  assert_non_null(p);
  return p;
}

/* lsm_pls_stage, which must succeed. */
static inline void stage(lsm_particles *p, const lsm_grid *in, const lsm_grid *target,
                         float c0, float c1, float dt) {
  lsm_err err;
  lsm_err_clear(&err);
  if (lsm_pls_stage(p, in, target, c0, c1, dt, &err) != LSM_OK) fail_msg("lsm_pls_stage: %s", err.msg);
}

static inline void correct(lsm_particles *p, lsm_grid *phi) {
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = lsm_pls_correct(p, phi, &err);
  if (st != LSM_OK) fail_msg("lsm_pls_correct: %s", err.msg);
}

#endif
