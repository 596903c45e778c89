/* Mask helpers shared by lsmorph's cmocka tests of solver code on binary
 * slices (lsm_mask). */
#ifndef LSM_TEST_MASK_H
#define LSM_TEST_MASK_H

#include "tests/lsm_test.h"

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"

/* A w x h mask of zeros (fails the test if it cannot be had). */
static inline lsm_mask lsm_test_mask(int w, int h) {
  lsm_mask m;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_mask_create(w, h, &m, &err), LSM_OK);
  return m;
}

/* Sets the pixels whose centres lie in the disc of radius r at (cx, cy). */
static inline void lsm_test_paint_disc(lsm_mask *m, double cx, double cy, double r) {
  for (int y = 0; y < m->height; ++y)
    for (int x = 0; x < m->width; ++x)
      if ((x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r)
        m->pixels[(size_t)y * (size_t)m->width + (size_t)x] = 1;
}

#endif
