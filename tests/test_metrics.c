/* Tests for solver/app/lsm_metrics.c (what `lsmorph score` reports): every field
 * of lsm_score_slice against a brute-force evaluation of the definitions in
 * lsm_metrics.h, on random masks of odd, non-square sizes that touch the
 * image border; the one-side-empty penalty; the nearest-rank quantile. */
#include "tests/lsm_test_mask.h"

#include "solver/app/lsm_metrics.h"

/* Boundary by definition: an inside pixel on the image border or with a
 * 4-neighbour outside. */
static int brute_boundary(const lsm_mask *m, int x, int y) {
  const int w = m->width, h = m->height;
  if (!m->pixels[(size_t)y * w + x]) return 0;
  if (x == 0 || y == 0 || x == w - 1 || y == h - 1) return 1;
  return !m->pixels[(size_t)y * w + x - 1] || !m->pixels[(size_t)y * w + x + 1] ||
         !m->pixels[(size_t)(y - 1) * w + x] || !m->pixels[(size_t)(y + 1) * w + x];
}

/* Distance from (x, y) to the nearest boundary pixel centre of m, rows
 * row_step apart (columns 1). */
static double brute_nearest(const lsm_mask *m, int x, int y, double row_step) {
  double best = INFINITY;
  for (int v = 0; v < m->height; ++v)
    for (int u = 0; u < m->width; ++u)
      if (brute_boundary(m, u, v)) {
        const double dy = (v - y) * row_step;
        const double d = sqrt((double)((u - x) * (u - x)) + dy * dy);
        if (d < best) best = d;
      }
  return best;
}

static int cmp_double(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* Every boundary-to-boundary distance, both directions, sorted; *n of them. */
static double *brute_distances(const lsm_mask *a, const lsm_mask *b, double row_step, size_t *n) {
  double *d = malloc(2 * (size_t)a->width * (size_t)a->height * sizeof *d);
  assert_non_null(d);
  *n = 0;
  for (int y = 0; y < a->height; ++y)
    for (int x = 0; x < a->width; ++x) {
      if (brute_boundary(a, x, y)) d[(*n)++] = brute_nearest(b, x, y, row_step);
      if (brute_boundary(b, x, y)) d[(*n)++] = brute_nearest(a, x, y, row_step);
    }
  qsort(d, *n, sizeof *d, cmp_double);
  return d;
}

/* A few random discs and rectangles, some reaching past the border. */
static void paint_random(lsm_mask *m, uint64_t *seed) {
  const int shapes = 1 + (int)(lsm_test_rand(seed) % 4);
  for (int s = 0; s < shapes; ++s) {
    const double cx = (double)(lsm_test_rand(seed) % (uint64_t)(m->width + 6)) - 3.0;
    const double cy = (double)(lsm_test_rand(seed) % (uint64_t)(m->height + 6)) - 3.0;
    const double r = 1.0 + (double)(lsm_test_rand(seed) % 90) / 10.0;
    if (lsm_test_rand(seed) % 2) {
      lsm_test_paint_disc(m, cx, cy, r);
    } else {
      for (int y = 0; y < m->height; ++y)
        for (int x = 0; x < m->width; ++x)
          if (fabs(x - cx) <= r && fabs(y - cy) <= 0.5 * r) m->pixels[(size_t)y * m->width + x] = 1;
    }
  }
}

static size_t area(const lsm_mask *m) {
  size_t n = 0;
  for (size_t k = 0; k < (size_t)m->width * (size_t)m->height; ++k) n += m->pixels[k] != 0;
  return n;
}

static size_t overlap(const lsm_mask *a, const lsm_mask *b) {
  size_t n = 0;
  for (size_t k = 0; k < (size_t)a->width * (size_t)a->height; ++k) n += a->pixels[k] && b->pixels[k];
  return n;
}

/* Scores result against truth (the call must succeed); *dist gets the
 * boundary distances (the caller frees it).  Returns their count. */
static size_t score(const lsm_mask *result, const lsm_mask *truth, double row_step,
                    lsm_slice_score *s, double **dist) {
  lsm_err err;
  lsm_err_clear(&err);
  *dist = NULL;
  size_t dn = 0, dcap = 0;
  assert_int_equal(lsm_score_slice(result, truth, row_step, s, dist, &dn, &dcap, &err), LSM_OK);
  return dn;
}

/* Rows as far apart as columns, and 2.5 times as far (pixels 2.5 times as
 * tall as they are wide: distances in pixel widths). */
static void test_matches_definitions(void **state) {
  (void)state;
  uint64_t seed = 0x9e3779b97f4a7c15u;
  for (int trial = 0; trial < 80; ++trial) {
    const double row_step = trial < 40 ? 1.0 : 2.5;
    const int w = 17 + (int)(lsm_test_rand(&seed) % 20), h = 11 + (int)(lsm_test_rand(&seed) % 20);
    lsm_mask a = lsm_test_mask(w, h), b = lsm_test_mask(w, h);
    paint_random(&a, &seed);
    paint_random(&b, &seed);
    if (!area(&a) || !area(&b)) {
      lsm_mask_free(&a);
      lsm_mask_free(&b);
      continue; /* one side empty: the next test */
    }
    lsm_slice_score s;
    double *dist;
    const size_t dn = score(&a, &b, row_step, &s, &dist);
    size_t n = 0;
    double *ref = brute_distances(&a, &b, row_step, &n);
    assert_int_equal(s.comparable, 1);
    assert_int_equal(s.area_result, area(&a));
    assert_int_equal(s.area_truth, area(&b));
    assert_close(s.dice, 2.0 * (double)overlap(&a, &b) / (double)(area(&a) + area(&b)), 1e-12);
    assert_int_equal(dn, n);
    qsort(dist, dn, sizeof *dist, cmp_double);
    double total = 0.0;
    for (size_t k = 0; k < n; ++k) {
      assert_close(dist[k], ref[k], 1e-9);
      total += ref[k];
    }
    const size_t rank = (size_t)ceil(0.95 * (double)n); /* nearest rank, 1-based */
    assert_close(s.hd95, ref[rank - 1], 1e-9);
    assert_close(s.hd_max, ref[n - 1], 1e-9);
    assert_close(s.mean_surface, total / (double)n, 1e-9);
    free(ref);
    free(dist);
    lsm_mask_free(&a);
    lsm_mask_free(&b);
  }
}

/* By hand: a 10 x 10 square inside one a pixel larger all round.  Each of
 * the inner square's 36 boundary pixels is 1 from the outer boundary; of the
 * outer square's 44, 40 are 1 from the inner boundary and its 4 corners sqrt 2. */
static void test_known_rings(void **state) {
  (void)state;
  lsm_mask a = lsm_test_mask(30, 20), b = lsm_test_mask(30, 20);
  for (int y = 4; y <= 15; ++y)
    for (int x = 4; x <= 15; ++x) {
      b.pixels[(size_t)y * 30 + x] = 1;
      if (y >= 5 && y <= 14 && x >= 5 && x <= 14) a.pixels[(size_t)y * 30 + x] = 1;
    }
  lsm_slice_score s;
  double *dist;
  const size_t dn = score(&a, &b, 1.0, &s, &dist);
  assert_int_equal(dn, 80);
  assert_close(s.dice, 200.0 / 244.0, 1e-12);
  assert_close(s.hd_max, sqrt(2.0), 1e-12);
  assert_close(s.hd95, 1.0, 1e-12); /* rank 76 of 80 */
  assert_close(s.mean_surface, (76.0 + 4.0 * sqrt(2.0)) / 80.0, 1e-12);
  free(dist);
  lsm_mask_free(&a);
  lsm_mask_free(&b);
}

/* One side empty: not comparable; each boundary pixel of the other counts
 * with the penalty max(width, height * row_step), on a non-square image. */
static void test_one_side_empty(void **state) {
  (void)state;
  lsm_mask a = lsm_test_mask(40, 25), b = lsm_test_mask(40, 25);
  lsm_test_paint_disc(&a, 10, 12, 4);
  size_t edges = 0;
  for (int y = 0; y < 25; ++y)
    for (int x = 0; x < 40; ++x) edges += (size_t)brute_boundary(&a, x, y);
  lsm_err err;
  lsm_err_clear(&err);
  for (int side = 0; side < 4; ++side) {
    const double row_step = side < 2 ? 1.0 : 2.0, penalty = side < 2 ? 40.0 : 50.0;
    lsm_slice_score s;
    double *dist;
    const size_t dn = score(side % 2 ? &b : &a, side % 2 ? &a : &b, row_step, &s, &dist);
    assert_int_equal(s.comparable, 0);
    assert_close(s.dice, 0.0, 0.0);
    assert_true(isinf(s.hd95));
    assert_int_equal(dn, edges);
    for (size_t k = 0; k < dn; ++k) assert_close(dist[k], penalty, 0.0);
    free(dist);
  }
  lsm_slice_score s;
  assert_int_equal(lsm_score_slice(&b, &b, 1.0, &s, NULL, NULL, NULL, &err), LSM_OK);
  assert_int_equal(s.comparable, 1); /* both empty: agree */
  assert_close(s.dice, 1.0, 0.0);
  lsm_mask c = lsm_test_mask(25, 40);
  assert_int_equal(lsm_score_slice(&a, &c, 1.0, &s, NULL, NULL, NULL, &err), LSM_ERR_INPUT);
  assert_int_equal(lsm_score_slice(&a, &a, 0.0, &s, NULL, NULL, NULL, &err), LSM_ERR_INPUT);
  lsm_mask_free(&a);
  lsm_mask_free(&b);
  lsm_mask_free(&c);
}

static void test_quantile_nearest_rank(void **state) {
  (void)state;
  double v[20];
  for (int k = 0; k < 20; ++k) v[k] = (double)(20 - k); /* 20 .. 1, unsorted */
  assert_close(lsm_quantile(v, 20, 0.95), 19.0, 0.0);
  assert_close(lsm_quantile(v, 20, 0.5), 10.0, 0.0);
  assert_close(lsm_quantile(v, 20, 1.0), 20.0, 0.0);
  assert_close(lsm_quantile(v, 20, 0.0), 1.0, 0.0);
  assert_close(lsm_quantile(v, 1, 0.95), 1.0, 0.0);
  assert_true(isnan(lsm_quantile(v, 0, 0.95)));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_matches_definitions),
      cmocka_unit_test(test_known_rings),
      cmocka_unit_test(test_one_side_empty),
      cmocka_unit_test(test_quantile_nearest_rank),
  };
  return cmocka_run_group_tests_name("metrics", tests, NULL, NULL);
}
