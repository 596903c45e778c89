/* Tests for solver/recon/lsm_pchip.h: the PCHIP slopes against scipy's
 * PchipInterpolator (derivatives at the knots, uneven intervals, a local
 * extremum, the end rule and its 3 d clamp; values printed by scipy 1.10 with
 * %.17g), and the properties the z-profile relies on. */
#include "tests/lsm_test.h"

#include "solver/recon/lsm_pchip.h"

typedef struct knots3 {
  double x[3], y[3];
  double slope[3]; /* scipy: PchipInterpolator(x, y).derivative()(x) */
} knots3;

static const knots3 cases[] = {
    {{0, 2, 7}, {0, 2, 17}, {0.42857142857142855, 1.3999999999999999, 4.4285714285714288}},
    {{0, 5, 6}, {1, -4, -4.5}, {-1.4166666666666667, -0.62068965517241381, -0.41666666666666663}},
    {{0, 1, 2}, {0, 1, 0}, {2, 0, -2}},
    {{0, 3, 4}, {2, 1, 3}, {-1, 0, 2.583333333333333}},
    {{0, 0.5, 4}, {0, 3, 3.5}, {6.7321428571428568, 0.36641221374045801, 0}},
    {{0, 1, 2}, {0, 1, 5}, {0, 1.6000000000000001, 5.5}},
    {{0, 1, 3}, {0, -1, 5}, {-2.3333333333333335, 0, 5.666666666666667}},
    {{0, 0.1, 1}, {0, 1, 0}, {11.111111111111111, 0, -3.3333333333333335}},
    {{0, 1, 10}, {0, 1, -5}, {1.1666666666666665, 0, -1.9999999999999998}}, /* clamped to 3 d */
};

static void test_matches_scipy(void **state) {
  (void)state;
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
    const knots3 *k = &cases[c];
    const double h0 = k->x[1] - k->x[0], h1 = k->x[2] - k->x[1];
    const double d0 = (k->y[1] - k->y[0]) / h0, d1 = (k->y[2] - k->y[1]) / h1;
    assert_close(lsm_pchip_edge_slope(h0, h1, d0, d1), k->slope[0], 1e-12);
    assert_close(lsm_pchip_slope(h0, h1, d0, d1), k->slope[1], 1e-12);
    assert_close(lsm_pchip_edge_slope(h1, h0, d1, d0), k->slope[2], 1e-12);
  }
}

/* Zero at an extremum or a flat side; same sign as the secants and at most
 * 3 min(|d0|, |d1|) otherwise; scaling both lengths by c scales the slope by
 * 1/c (the secants scale so). */
static void test_properties(void **state) {
  (void)state;
  uint64_t seed = 12345;
  for (int t = 0; t < 10000; ++t) {
    const double h0 = 0.01 + (double)(lsm_test_rand(&seed) % 1000) / 100.0;
    const double h1 = 0.01 + (double)(lsm_test_rand(&seed) % 1000) / 100.0;
    const double d0 = (double)(lsm_test_rand(&seed) % 2001) / 100.0 - 10.0;
    const double d1 = (double)(lsm_test_rand(&seed) % 2001) / 100.0 - 10.0;
    const double m = lsm_pchip_slope(h0, h1, d0, d1);
    if (d0 * d1 <= 0.0) {
      assert_true(m == 0.0);
    } else {
      assert_true(m * d0 > 0.0);
      assert_true(fabs(m) <= 3.0 * fmin(fabs(d0), fabs(d1)) * (1.0 + 1e-12));
    }
    const double c = 1e3;
    assert_close(lsm_pchip_slope(c * h0, c * h1, d0 / c, d1 / c), m / c, 1e-12 * (1.0 + fabs(m)));
    const double e = lsm_pchip_edge_slope(h0, h1, d0, d1);
    assert_true(e == 0.0 || e * d0 > 0.0);
    assert_true(fabs(e) <= 3.0 * fabs(d0) * (1.0 + 1e-12));
  }
  assert_true(lsm_pchip_slope(1.0, 1.0, 1e-300, 1e-300) > 0.0); /* no underflow to 0 */
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_matches_scipy),
      cmocka_unit_test(test_properties),
  };
  return cmocka_run_group_tests_name("pchip", tests, NULL, NULL);
}
