/* Tests for solver/recon/lsm_register.c: mask overlap under a shift, and the
 * coarse-to-fine translation of largest overlap against brute force. */
#include "tests/lsm_test_mask.h"

#include "solver/base/lsm_grid.h"
#include "solver/recon/lsm_register.h"
#include "solver/base/lsm_status.h"


static void paint_rect(lsm_mask *m, int x0, int y0, int x1, int y1) {
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) m->pixels[(size_t)y * (size_t)m->width + (size_t)x] = 1;
}

/* Overlap by definition: pixel p of a against pixel p + (dx, dy) of b. */
static size_t brute_overlap(const lsm_mask *a, const lsm_mask *b, int dx, int dy) {
  size_t n = 0;
  for (int y = 0; y < a->height; ++y)
    for (int x = 0; x < a->width; ++x) {
      const int xb = x + dx, yb = y + dy;
      if (xb < 0 || yb < 0 || xb >= b->width || yb >= b->height) continue;
      n += a->pixels[(size_t)y * (size_t)a->width + (size_t)x] &&
           b->pixels[(size_t)yb * (size_t)b->width + (size_t)xb];
    }
  return n;
}

/* A random blob: a few overlapping discs (connected enough to have one
 * clear best shift, irregular enough to have local maxima). */
static void paint_blob(lsm_mask *m, uint64_t *seed, double cx, double cy, double size) {
  for (int k = 0; k < 5; ++k) {
    const double ox = ((double)(lsm_test_rand(seed) % 1000) / 1000.0 - 0.5) * size;
    const double oy = ((double)(lsm_test_rand(seed) % 1000) / 1000.0 - 0.5) * size;
    const double r = (0.15 + 0.25 * (double)(lsm_test_rand(seed) % 1000) / 1000.0) * size;
    lsm_test_paint_disc(m, cx + ox, cy + oy, r);
  }
}

static void register_ok(const lsm_mask *a, const lsm_mask *b, int *dx, int *dy) {
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_register_shift(a, b, dx, dy, &err), LSM_OK);
}

static void test_overlap_matches_definition(void **state) {
  (void)state;
  uint64_t seed = 7;
  lsm_mask a = lsm_test_mask(37, 23), b = lsm_test_mask(37, 23);
  paint_blob(&a, &seed, 15, 11, 14);
  paint_blob(&b, &seed, 22, 12, 14);
  for (int dy = -25; dy <= 25; dy += 3)
    for (int dx = -40; dx <= 40; dx += 3)
      assert_int_equal(lsm_mask_overlap(&a, &b, dx, dy), brute_overlap(&a, &b, dx, dy));
  lsm_mask_free(&a);
  lsm_mask_free(&b);
}

/* Shapes within LSM_REGISTER_COARSE pixels: the search is exhaustive, so it
 * must find the brute-force maximum (shortest shift among equals). */
static void test_small_is_exhaustive(void **state) {
  (void)state;
  uint64_t seed = 99;
  for (int trial = 0; trial < 40; ++trial) {
    lsm_mask a = lsm_test_mask(48, 40), b = lsm_test_mask(48, 40);
    paint_blob(&a, &seed, 20, 18, 10);
    paint_blob(&b, &seed, 26, 20, 10);
    int dx, dy;
    register_ok(&a, &b, &dx, &dy);
    size_t best = 0;
    long best_len = 0;
    for (int sy = -40; sy <= 40; ++sy)
      for (int sx = -48; sx <= 48; ++sx) {
        const size_t v = brute_overlap(&a, &b, sx, sy);
        const long len = (long)sx * sx + (long)sy * sy;
        if (v > best || (v == best && len < best_len)) best = v, best_len = len;
      }
    assert_int_equal(lsm_mask_overlap(&a, &b, dx, dy), best);
    assert_int_equal((long)dx * dx + (long)dy * dy, best_len);
    lsm_mask_free(&a);
    lsm_mask_free(&b);
  }
}

/* A shape moved by a known shift, large against the coarse level: found
 * exactly, on images of several sizes (so several pyramid levels). */
static void test_known_shift(void **state) {
  (void)state;
  const int sizes[3] = {96, 300, 1100};
  for (int k = 0; k < 3; ++k) {
    const int n = sizes[k];
    uint64_t seed = 1234 + (uint64_t)k;
    lsm_mask a = lsm_test_mask(n, n), b = lsm_test_mask(n, n);
    const double size = 0.3 * n;
    const int sx = (int)(0.31 * n), sy = -(int)(0.17 * n);
    paint_blob(&a, &seed, 0.35 * n, 0.6 * n, size);
    /* b is a moved by (sx, sy) */
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const int xa = x - sx, ya = y - sy;
        if (xa >= 0 && ya >= 0 && xa < n && ya < n)
          b.pixels[(size_t)y * (size_t)n + (size_t)x] = a.pixels[(size_t)ya * (size_t)n + (size_t)xa];
      }
    int dx, dy;
    register_ok(&a, &b, &dx, &dy);
    print_message("%dx%d: shift (%d, %d), found (%d, %d)\n", n, n, sx, sy, dx, dy);
    assert_int_equal(dx, sx);
    assert_int_equal(dy, sy);
    lsm_mask_free(&a);
    lsm_mask_free(&b);
  }
}

/* A part grows out of a shape that stays: a disc (r = 20), then a smaller
 * disc (r = 16) in the same place with a thin bar leaving it to the right.
 * The centroid moves some 40 px along the bar; the translation of largest
 * overlap moves the big disc only as far as it still covers the small one
 * (4 px: each further pixel uncovers a crescent of ~30 px of it and gains 5
 * px of bar). */
static void test_growth_is_not_motion(void **state) {
  (void)state;
  lsm_mask a = lsm_test_mask(200, 120), b = lsm_test_mask(200, 120);
  lsm_test_paint_disc(&a, 50, 60, 20);
  lsm_test_paint_disc(&b, 50, 60, 16);
  paint_rect(&b, 50, 58, 190, 62);
  int dx, dy;
  register_ok(&a, &b, &dx, &dy);
  assert_int_equal(dx, 4);
  assert_int_equal(dy, 0);
  lsm_mask_free(&a);
  lsm_mask_free(&b);
}

static void test_empty_and_identical(void **state) {
  (void)state;
  lsm_mask a = lsm_test_mask(64, 64), b = lsm_test_mask(64, 64);
  int dx = 5, dy = 5;
  register_ok(&a, &b, &dx, &dy); /* both empty */
  assert_int_equal(dx, 0);
  assert_int_equal(dy, 0);
  lsm_test_paint_disc(&a, 20, 30, 8);
  dx = dy = 5;
  register_ok(&a, &b, &dx, &dy); /* b empty */
  assert_int_equal(dx, 0);
  assert_int_equal(dy, 0);
  lsm_test_paint_disc(&b, 20, 30, 8);
  register_ok(&a, &b, &dx, &dy); /* identical: no shift */
  assert_int_equal(dx, 0);
  assert_int_equal(dy, 0);
  lsm_mask_free(&a);
  lsm_mask_free(&b);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_overlap_matches_definition),
      cmocka_unit_test(test_small_is_exhaustive),
      cmocka_unit_test(test_known_shift),
      cmocka_unit_test(test_growth_is_not_motion),
      cmocka_unit_test(test_empty_and_identical),
  };
  return cmocka_run_group_tests_name("register", tests, NULL, NULL);
}
