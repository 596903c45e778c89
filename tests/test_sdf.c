/* Tests for solver/sdf/lsm_sdf.c: exact distance transform, signed distance of
 * masks and outlines, outline filling by parity, convex-hull centroid. */
#include "tests/lsm_test.h"

#include "solver/base/lsm_grid.h"
#include "solver/sdf/lsm_sdf.h"
#include "solver/base/lsm_status.h"

#ifdef _OPENMP
#include <omp.h>
#endif

/* ------------------------------------------------------------------------ */
/* helpers                                                                   */

static lsm_mask new_mask(int w, int h) {
  lsm_mask m;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_mask_create(w, h, &m, &err), LSM_OK);
  return m;
}

static lsm_grid *new_grid(int w, int h, float dx, float dy) {
  lsm_grid *g = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_grid_create(w, h, dx, dy, &g, &err), LSM_OK);
  return g;
}

static void set_px(lsm_mask *m, int i, int j) {
  if (i >= 0 && i < m->width && j >= 0 && j < m->height)
    m->pixels[(size_t)j * (size_t)m->width + (size_t)i] = 1;
}

static int get_px(const lsm_mask *m, int i, int j) {
  return m->pixels[(size_t)j * (size_t)m->width + (size_t)i];
}

/* Thin 8-connected circle outline (midpoint algorithm), clipped to the image. */
static void draw_circle(lsm_mask *m, int cx, int cy, int r) {
  int x = r, y = 0, e = 1 - r;
  while (x >= y) {
    set_px(m, cx + x, cy + y);
    set_px(m, cx - x, cy + y);
    set_px(m, cx + x, cy - y);
    set_px(m, cx - x, cy - y);
    set_px(m, cx + y, cy + x);
    set_px(m, cx - y, cy + x);
    set_px(m, cx + y, cy - x);
    set_px(m, cx - y, cy - x);
    ++y;
    if (e < 0) {
      e += 2 * y + 1;
    } else {
      --x;
      e += 2 * (y - x) + 1;
    }
  }
}

static double dist(int i, int j, double cx, double cy) {
  return hypot(i - cx, j - cy);
}

/* Distance in pixels from (i, j) to the nearest set pixel of m. */
static double nearest_px(const lsm_mask *m, int i, int j) {
  double best = INFINITY;
  for (int jj = 0; jj < m->height; ++jj)
    for (int ii = 0; ii < m->width; ++ii)
      if (m->pixels[(size_t)jj * (size_t)m->width + (size_t)ii] && dist(ii, jj, i, j) < best)
        best = dist(ii, jj, i, j);
  return best;
}

/* O(N^2) reference: squared anisotropic distance to the nearest feature. */
static void brute_edt(const uint8_t *f, int w, int h, double dx, double dy, double *out) {
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      double best = INFINITY;
      for (int jj = 0; jj < h; ++jj)
        for (int ii = 0; ii < w; ++ii) {
          if (!f[jj * w + ii]) continue;
          const double ax = dx * (ii - i), ay = dy * (jj - j);
          const double d = ax * ax + ay * ay;
          if (d < best) best = d;
        }
      out[j * w + i] = best;
    }
}

static void check_edt_against_brute(const uint8_t *f, int w, int h, double dx, double dy) {
  double *got = malloc((size_t)w * (size_t)h * sizeof *got);
  double *want = malloc((size_t)w * (size_t)h * sizeof *want);
  assert_non_null(got);
  assert_non_null(want);
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_edt_squared(f, w, h, dx, dy, got, &err), LSM_OK);
  brute_edt(f, w, h, dx, dy, want);
  for (int k = 0; k < w * h; ++k) {
    if (isinf(want[k])) {
      assert_true(isinf(got[k]) && got[k] > 0);
    } else {
      assert_false(isnan(got[k]));
      assert_close(got[k], want[k], 1e-9);
    }
  }
  free(got);
  free(want);
}

/* ------------------------------------------------------------------------ */
/* distance transform                                                        */

static void test_edt_random_vs_brute(void **state) {
  (void)state;
  uint64_t rng = 0x9E3779B97F4A7C15ull;
  for (int c = 0; c < 20; ++c) {
    int w = 1 + (int)(lsm_test_rand(&rng) % 40), h = 1 + (int)(lsm_test_rand(&rng) % 33);
    const int density = 1 + (int)(lsm_test_rand(&rng) % 50); /* percent */
    if (c == 0) w = h = 1;            /* 1x1, empty */
    if (c == 1) w = h = 1;            /* 1x1, one feature */
    if (c == 2) w = 40, h = 33;       /* all empty */
    if (c == 3) w = 40, h = 33;       /* single feature pixel */
    uint8_t *f = calloc((size_t)w * (size_t)h, 1);
    assert_non_null(f);
    if (c == 1) f[0] = 1;
    if (c == 3) f[17 * w + 29] = 1;
    if (c >= 4)
      for (int k = 0; k < w * h; ++k) f[k] = (lsm_test_rand(&rng) % 100) < (uint64_t)density;
    if (c >= 4 && c % 3 == 0) /* empty rows */
      for (int j = 0; j < h; ++j)
        if (lsm_test_rand(&rng) % 2)
          for (int i = 0; i < w; ++i) f[j * w + i] = 0;
    if (c >= 4 && c % 3 == 1) /* empty columns */
      for (int i = 0; i < w; ++i)
        if (lsm_test_rand(&rng) % 2)
          for (int j = 0; j < h; ++j) f[j * w + i] = 0;
    check_edt_against_brute(f, w, h, 1.0, 1.0);
    check_edt_against_brute(f, w, h, 0.7, 1.3);
    free(f);
  }
}

/* Large enough to take the multithreaded path; result independent of the
 * number of threads, bit for bit. */
static void test_edt_large_threads(void **state) {
  (void)state;
  const int w = 256, h = 193;
  uint8_t *f = calloc((size_t)w * h, 1);
  assert_non_null(f);
  uint64_t rng = 12345;
  for (int k = 0; k < w * h; ++k) f[k] = lsm_test_rand(&rng) % 1000 < 2;
  check_edt_against_brute(f, w, h, 0.7, 1.3);

  double *a = malloc((size_t)w * h * sizeof *a), *b = malloc((size_t)w * h * sizeof *b);
  assert_non_null(a);
  assert_non_null(b);
  lsm_err err;
  lsm_err_clear(&err);
#ifdef _OPENMP
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
#endif
  assert_int_equal(lsm_edt_squared(f, w, h, 0.7, 1.3, a, &err), LSM_OK);
#ifdef _OPENMP
  omp_set_num_threads(5);
#endif
  assert_int_equal(lsm_edt_squared(f, w, h, 0.7, 1.3, b, &err), LSM_OK);
#ifdef _OPENMP
  omp_set_num_threads(saved);
#endif
  assert_memory_equal(a, b, (size_t)w * h * sizeof *a);
  free(a);
  free(b);
  free(f);
}

static void test_edt_bad_arguments(void **state) {
  (void)state;
  uint8_t f[4] = {0, 1, 0, 0};
  double out[4];
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_edt_squared(f, 0, 4, 1.0, 1.0, out, &err), LSM_ERR_INTERNAL);
  assert_true(strlen(err.msg) > 0);
  lsm_err_clear(&err);
  assert_int_equal(lsm_edt_squared(f, 2, 2, 1.0, -1.0, out, &err), LSM_ERR_INTERNAL);
  lsm_err_clear(&err);
  assert_int_equal(lsm_edt_squared(f, 2, 2, NAN, 1.0, out, &err), LSM_ERR_INTERNAL);
  assert_int_equal(lsm_edt_squared(f, 2, 2, 1.0, 1.0, out, NULL), LSM_OK);
  assert_close(out[0], 1.0, 0);
  assert_close(out[3], 1.0, 0);
  assert_close(out[2], 2.0, 0);
}

/* ------------------------------------------------------------------------ */
/* signed distance of a mask                                                 */

static void check_half_plane(float h) {
  const int W = 20, H = 10;
  lsm_mask m = new_mask(W, H);
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W / 2; ++i) set_px(&m, i, j);
  lsm_grid *phi = new_grid(W, H, h, h);
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_sdf_from_mask(&m, phi, &err), LSM_OK);
  for (int j = 0; j < H; ++j) {
    assert_close(LSM_AT(phi, W / 2 - 1, j), -0.5 * h, 1e-6);
    assert_close(LSM_AT(phi, W / 2, j), 0.5 * h, 1e-6);
    for (int i = 0; i < W; ++i) /* exact signed distance to x = W/2 - 1/2 */
      assert_close(LSM_AT(phi, i, j), h * (i - (W / 2 - 0.5)), 1e-5);
    for (int i = 1; i < W - 1; ++i) /* |grad phi| = 1 */
      assert_close((LSM_AT(phi, i + 1, j) - LSM_AT(phi, i - 1, j)) / (2.0 * h), 1.0, 1e-5);
    /* ghosts filled (zero-gradient) */
    assert_close(LSM_AT(phi, -1, j), LSM_AT(phi, 0, j), 0);
    assert_close(LSM_AT(phi, W + 3, j), LSM_AT(phi, W - 1, j), 0);
  }
  assert_close(LSM_AT(phi, 3, -4), LSM_AT(phi, 3, 0), 0);
  lsm_grid_destroy(&phi);
  lsm_mask_free(&m);
}

static void test_sdf_half_plane(void **state) {
  (void)state;
  check_half_plane(1.0f);
  check_half_plane(0.5f);
}

/* Anisotropic pixels, dx = 1, dy = 2.  Every value by hand from
 * lsm_sdf_from_mask's rule: outside, phi = d - half with d the distance to the
 * nearest inside pixel centre; inside, phi = -(d - half) with d the distance
 * to the nearest outside pixel centre; half = min(dx, dy) / 2 = 0.5 ("the
 * smaller half-size" of the pixel, lsm_sdf.c).  At dx = dy every test above
 * has min = max; here half = max(dx, dy) / 2 would put 1 in place of 0.5. */
static void test_sdf_anisotropic(void **state) {
  (void)state;
  const int W = 12, H = 8;
  lsm_err err;
  lsm_err_clear(&err);
  lsm_grid *phi = new_grid(W, H, 1.0f, 2.0f);
  /* vertical boundary: columns 0..5 inside.  Across it d = dx |i - i'|:
   * column 5 is -(1 - 0.5) = -0.5, column 6 +0.5, column i: (i - 5) - 0.5
   * outside, -((6 - i) - 0.5) inside. */
  lsm_mask m = new_mask(W, H);
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < 6; ++i) set_px(&m, i, j);
  assert_int_equal(lsm_sdf_from_mask(&m, phi, &err), LSM_OK);
  for (int j = 0; j < H; ++j) {
    assert_close(LSM_AT(phi, 5, j), -0.5, 1e-6);
    assert_close(LSM_AT(phi, 6, j), 0.5, 1e-6);
    for (int i = 0; i < W; ++i)
      assert_close(LSM_AT(phi, i, j), i >= 6 ? (i - 5) - 0.5 : -((6 - i) - 0.5), 1e-6);
  }
  lsm_mask_free(&m);
  /* horizontal boundary: rows 0..3 inside.  Across it d = dy |j - j'| = 2, 4,
   * ...: row 3 is -(2 - 0.5) = -1.5, row 4 +1.5 (the zero level still midway
   * between them, at the boundary); row j: 2 (j - 3) - 0.5 outside,
   * -(2 (4 - j) - 0.5) inside. */
  m = new_mask(W, H);
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < W; ++i) set_px(&m, i, j);
  assert_int_equal(lsm_sdf_from_mask(&m, phi, &err), LSM_OK);
  for (int i = 0; i < W; ++i) {
    assert_close(LSM_AT(phi, i, 3), -1.5, 1e-6);
    assert_close(LSM_AT(phi, i, 4), 1.5, 1e-6);
    for (int j = 0; j < H; ++j)
      assert_close(LSM_AT(phi, i, j), j >= 4 ? 2.0 * (j - 3) - 0.5 : -(2.0 * (4 - j) - 0.5), 1e-6);
  }
  lsm_mask_free(&m);
  /* a corner: inside columns 0..5 and rows 0..3.  Outside cells: distance to
   * the inside corner pixel (5, 3) where both offsets are positive, else to
   * the nearest inside row or column; inside cells: the nearer of the two
   * boundaries, min(dx (6 - i), dy (4 - j)). */
  m = new_mask(W, H);
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 6; ++i) set_px(&m, i, j);
  assert_int_equal(lsm_sdf_from_mask(&m, phi, &err), LSM_OK);
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i) {
      double want;
      if (i < 6 && j < 4) {
        want = -(fmin(6.0 - i, 2.0 * (4 - j)) - 0.5);
      } else {
        const double ox = i >= 6 ? i - 5.0 : 0.0, oy = j >= 4 ? 2.0 * (j - 3) : 0.0;
        want = hypot(ox, oy) - 0.5;
      }
      assert_close(LSM_AT(phi, i, j), want, 1e-5);
    }
  /* the diagonal neighbour: sqrt(1 + 4) - 0.5 */
  assert_close(LSM_AT(phi, 6, 4), sqrt(5.0) - 0.5, 1e-6);
  lsm_mask_free(&m);
  lsm_grid_destroy(&phi);
}

static void test_sdf_disc(void **state) {
  (void)state;
  const int N = 65, c = 32, R = 20;
  lsm_mask m = new_mask(N, N);
  for (int j = 0; j < N; ++j)
    for (int i = 0; i < N; ++i)
      if ((i - c) * (i - c) + (j - c) * (j - c) <= R * R) set_px(&m, i, j);
  lsm_grid *phi = new_grid(N, N, 1.0f, 1.0f);
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_sdf_from_mask(&m, phi, &err), LSM_OK);
  /* zero crossing along the four axis directions from the centre */
  const int dirs[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (int d = 0; d < 4; ++d) {
    double radius = -1;
    for (int s = 1; s < N / 2; ++s) {
      const double a = LSM_AT(phi, c + dirs[d][0] * (s - 1), c + dirs[d][1] * (s - 1));
      const double b = LSM_AT(phi, c + dirs[d][0] * s, c + dirs[d][1] * s);
      if (a < 0 && b >= 0) {
        radius = (s - 1) + a / (a - b);
        break;
      }
    }
    assert_close(radius, R, 0.5);
  }
  assert_true(LSM_AT(phi, c, c) < -19.0f);
  assert_true(LSM_AT(phi, 0, 0) > 0.0f);
  lsm_grid_destroy(&phi);
  lsm_mask_free(&m);
}

/* Random blobs, at the borders or not: phi from brute-force distances, both pixel shapes. */
static void test_sdf_random_vs_brute(void **state) {
  (void)state;
  uint64_t rng = 0x2545F4914F6CDD1Dull;
  for (int c = 0; c < 60; ++c) {
    const int w = 1 + (int)(lsm_test_rand(&rng) % 30), h = 1 + (int)(lsm_test_rand(&rng) % 30);
    const float dx = c % 2 ? 0.7f : 1.0f, dy = c % 2 ? 1.3f : 1.0f;
    lsm_mask m = new_mask(w, h);
    for (int b = (int)(lsm_test_rand(&rng) % 4), i0, j0, bw, bh; b >= 0; --b) {
      i0 = (int)(lsm_test_rand(&rng) % 30), j0 = (int)(lsm_test_rand(&rng) % 30);
      bw = 1 + (int)(lsm_test_rand(&rng) % 9), bh = 1 + (int)(lsm_test_rand(&rng) % 9);
      for (int k = 0; k < bw * bh; ++k) set_px(&m, i0 + k % bw, j0 + k / bw);
    }
    const size_t n = (size_t)w * (size_t)h;
    uint8_t *out = malloc(n);
    double *d_in = malloc(n * sizeof(double)), *d_out = malloc(n * sizeof(double));
    assert_true(out && d_in && d_out);
    for (size_t k = 0; k < n; ++k) out[k] = !m.pixels[k];
    brute_edt(m.pixels, w, h, dx, dy, d_out), brute_edt(out, w, h, dx, dy, d_in);
    lsm_grid *phi = new_grid(w, h, dx, dy);
    assert_int_equal(lsm_sdf_from_mask(&m, phi, NULL), LSM_OK);
    const double half = 0.5 * (double)(dx < dy ? dx : dy);
    for (size_t k = 0; k < n; ++k) /* (empty or full: no finite distance, LSM_SDF_FAR) */
      if (!isinf(d_out[k]) && !isinf(d_in[k]))
        assert_close(LSM_AT(phi, (int)(k % (size_t)w), (int)(k / (size_t)w)),
                     m.pixels[k] ? -(sqrt(d_in[k]) - half) : sqrt(d_out[k]) - half, 1e-5);
    free(out), free(d_in), free(d_out), lsm_mask_free(&m), lsm_grid_destroy(&phi);
  }
}

static void test_sdf_empty_full_and_errors(void **state) {
  (void)state;
  lsm_mask m = new_mask(7, 5);
  lsm_grid *phi = new_grid(7, 5, 1.0f, 1.0f);
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_sdf_from_mask(&m, phi, &err), LSM_OK);
  assert_close(lsm_grid_min(phi), LSM_SDF_FAR, 0);
  assert_close(LSM_AT(phi, -4, -4), LSM_SDF_FAR, 0);
  memset(m.pixels, 1, 35);
  assert_int_equal(lsm_sdf_from_mask(&m, phi, &err), LSM_OK);
  assert_close(lsm_grid_max(phi), -LSM_SDF_FAR, 0);
  assert_close(LSM_AT(phi, 10, 8), -LSM_SDF_FAR, 0);

  lsm_grid *wrong = new_grid(5, 7, 1.0f, 1.0f);
  assert_int_equal(lsm_sdf_from_mask(&m, wrong, &err), LSM_ERR_INTERNAL);
  assert_int_equal(err.status, LSM_ERR_INTERNAL);
  assert_true(strlen(err.msg) > 0);
  lsm_err_clear(&err);
  assert_int_equal(lsm_sdf_from_outline(&m, wrong, &err), LSM_ERR_INTERNAL);
  lsm_grid_destroy(&wrong);
  lsm_grid_destroy(&phi);

  /* far is counted in cells: with 1/1024 unit cells the field is 1024 times smaller */
  phi = new_grid(7, 5, 0.0009765625f, 0.0009765625f);
  assert_int_equal(lsm_sdf_from_mask(&m, phi, &err), LSM_OK);
  assert_close(lsm_grid_max(phi), -LSM_SDF_FAR / 1024, 0);
  memset(m.pixels, 0, 35);
  assert_int_equal(lsm_sdf_from_mask(&m, phi, &err), LSM_OK);
  assert_close(lsm_grid_min(phi), LSM_SDF_FAR / 1024, 0);
  assert_int_equal(lsm_sdf_from_outline(&m, phi, &err), LSM_OK);
  assert_close(lsm_grid_min(phi), LSM_SDF_FAR / 1024, 0);
  lsm_grid_destroy(&phi);
  lsm_mask_free(&m);

  /* cells are labelled with 32-bit indices: larger grids and masks are refused, unallocated */
  lsm_grid *big = NULL;
  assert_int_equal(lsm_grid_create(46341, 46341, 1.0f, 1.0f, &big, &err), LSM_ERR_LIMIT);
  assert_null(big);
  lsm_mask bigm;
  assert_int_equal(lsm_mask_create(46341, 46341, &bigm, &err), LSM_ERR_LIMIT);
  assert_null(bigm.pixels);
}

/* ------------------------------------------------------------------------ */
/* outline fill                                                              */

static lsm_mask fill(const lsm_mask *outline) {
  lsm_mask f = {0, 0, NULL}; /* allocated by lsm_outline_fill */
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_outline_fill(outline, &f, &err), LSM_OK);
  assert_int_equal(f.width, outline->width);
  assert_int_equal(f.height, outline->height);
  return f;
}

/* Expected inside/outside from the distance to (cx, cy) for concentric
 * outlines of the given radii (outermost first): inside where an odd number
 * of circles enclose the pixel; only pixels at least 1.5 px from every circle
 * are checked (a midpoint-circle pixel is within 0.5 px of its radius).
 * Outline pixels themselves must be filled. */
static void check_concentric(const lsm_mask *outline, const lsm_mask *f, double cx, double cy,
                             const int *radii, int nr) {
  for (int j = 0; j < f->height; ++j)
    for (int i = 0; i < f->width; ++i) {
      if (get_px(outline, i, j)) {
        assert_int_equal(get_px(f, i, j), 1);
        continue;
      }
      const double d = dist(i, j, cx, cy);
      int enclosing = 0, near = 0;
      for (int r = 0; r < nr; ++r) {
        if (d < radii[r]) ++enclosing;
        if (fabs(d - radii[r]) < 1.5) near = 1;
      }
      if (near) continue;
      if (get_px(f, i, j) != (enclosing & 1))
        fail_msg("pixel (%d,%d) at distance %.2f: filled %d, expected %d", i, j, d,
                 get_px(f, i, j), enclosing & 1);
    }
}

static void test_fill_small_exact(void **state) {
  (void)state;
  /* 7x6, a 5x4 rectangle outline: the 3x2 interior is filled */
  lsm_mask m = new_mask(7, 6);
  for (int i = 1; i <= 5; ++i) set_px(&m, i, 1), set_px(&m, i, 4);
  for (int j = 1; j <= 4; ++j) set_px(&m, 1, j), set_px(&m, 5, j);
  lsm_mask f = fill(&m);
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 7; ++i)
      assert_int_equal(get_px(&f, i, j), (i >= 1 && i <= 5 && j >= 1 && j <= 4));
  lsm_mask_free(&f);
  lsm_mask_free(&m);
}

static void test_fill_disc(void **state) {
  (void)state;
  lsm_mask m = new_mask(41, 41);
  draw_circle(&m, 20, 20, 10);
  lsm_mask f = fill(&m);
  const int radii[] = {10};
  check_concentric(&m, &f, 20, 20, radii, 1);
  assert_int_equal(get_px(&f, 20, 20), 1);
  assert_int_equal(get_px(&f, 0, 0), 0);
  lsm_mask_free(&f);
  lsm_mask_free(&m);
}

static void test_fill_ring(void **state) {
  (void)state;
  lsm_mask m = new_mask(41, 41);
  draw_circle(&m, 20, 20, 15);
  draw_circle(&m, 20, 20, 7);
  lsm_mask f = fill(&m);
  const int radii[] = {15, 7};
  check_concentric(&m, &f, 20, 20, radii, 2);
  assert_int_equal(get_px(&f, 20, 20), 0); /* the hole */
  assert_int_equal(get_px(&f, 31, 20), 1); /* the annulus */
  lsm_mask_free(&f);
  lsm_mask_free(&m);
}

static void test_fill_three_nested(void **state) {
  (void)state;
  lsm_mask m = new_mask(45, 45);
  draw_circle(&m, 22, 22, 18);
  draw_circle(&m, 22, 22, 12);
  draw_circle(&m, 22, 22, 6);
  lsm_mask f = fill(&m);
  const int radii[] = {18, 12, 6};
  check_concentric(&m, &f, 22, 22, radii, 3);
  assert_int_equal(get_px(&f, 22, 22), 1); /* the island in the hole */
  assert_int_equal(get_px(&f, 22 + 9, 22), 0);
  assert_int_equal(get_px(&f, 22 + 15, 22), 1);
  lsm_mask_free(&f);
  lsm_mask_free(&m);
}

static void test_fill_side_by_side(void **state) {
  (void)state;
  lsm_mask m = new_mask(50, 30);
  draw_circle(&m, 12, 15, 8);
  draw_circle(&m, 36, 15, 8);
  lsm_mask f = fill(&m);
  for (int j = 0; j < 30; ++j)
    for (int i = 0; i < 50; ++i) {
      const int left = i < 24;
      const double d = dist(i, j, left ? 12 : 36, 15);
      if (get_px(&m, i, j) || fabs(d - 8) < 1.5) continue;
      assert_int_equal(get_px(&f, i, j), d < 8);
    }
  assert_int_equal(get_px(&f, 24, 15), 0); /* between them */
  lsm_mask_free(&f);
  lsm_mask_free(&m);
}

/* A contour cut open by the image border encloses nothing: the background
 * inside the arc touches the border and so belongs to the outside (depth 0).
 * Only the contour pixels are filled. */
static void test_fill_open_at_border(void **state) {
  (void)state;
  lsm_mask m = new_mask(41, 41);
  draw_circle(&m, 3, 20, 10);
  lsm_mask f = fill(&m);
  assert_memory_equal(f.pixels, m.pixels, 41 * 41);
  lsm_mask_free(&f);
  lsm_mask_free(&m);
}

/* A closed contour touching the border (tangent), and one running along the
 * whole image frame, do enclose their interior. */
static void test_fill_touching_border(void **state) {
  (void)state;
  lsm_mask m = new_mask(41, 41);
  draw_circle(&m, 10, 20, 10); /* leftmost pixels in column 0 */
  assert_int_equal(get_px(&m, 0, 20), 1);
  lsm_mask f = fill(&m);
  const int radii[] = {10};
  check_concentric(&m, &f, 10, 20, radii, 1);
  assert_int_equal(get_px(&f, 1, 20), 1);
  lsm_mask_free(&f);
  lsm_mask_free(&m);

  lsm_mask frame = new_mask(10, 8);
  for (int i = 0; i < 10; ++i) set_px(&frame, i, 0), set_px(&frame, i, 7);
  for (int j = 0; j < 8; ++j) set_px(&frame, 0, j), set_px(&frame, 9, j);
  f = fill(&frame);
  assert_int_equal(lsm_mask_count(&f), 80);
  lsm_mask_free(&f);
  lsm_mask_free(&frame);
}

/* A square drawn with 8-connected diagonal lines (a diamond): the background
 * inside and outside touch only diagonally, which 4-connectivity does not
 * join, so the inside does not leak out. */
static void test_fill_diamond(void **state) {
  (void)state;
  const int N = 31, c = 15, r = 10;
  lsm_mask m = new_mask(N, N);
  for (int j = 0; j < N; ++j)
    for (int i = 0; i < N; ++i)
      if (abs(i - c) + abs(j - c) == r) set_px(&m, i, j);
  lsm_mask f = fill(&m);
  for (int j = 0; j < N; ++j)
    for (int i = 0; i < N; ++i) assert_int_equal(get_px(&f, i, j), abs(i - c) + abs(j - c) <= r);
  lsm_mask_free(&f);
  lsm_mask_free(&m);
}

/* Contours are 8-connected: a small closed ring touching the outer contour
 * only diagonally is part of the same contour, so crossing into the ring's
 * centre crosses one contour, not two, and the centre is inside. */
static void test_fill_touching_contours(void **state) {
  (void)state;
  lsm_mask m = new_mask(21, 21);
  for (int j = 0; j < 21; ++j)
    for (int i = 0; i < 21; ++i)
      if (abs(i - 10) + abs(j - 10) == 9) set_px(&m, i, j); /* outer diamond */
  for (int j = 4; j <= 6; ++j)
    for (int i = 9; i <= 11; ++i)
      if (i != 10 || j != 5) set_px(&m, i, j); /* ring around (10, 5) */
  /* the ring's corner (9, 4) touches the diamond's (8, 3) diagonally only */
  assert_int_equal(get_px(&m, 8, 3), 1);
  assert_int_equal(get_px(&m, 8, 4) | get_px(&m, 9, 3), 0);
  lsm_mask f = fill(&m);
  assert_int_equal(get_px(&f, 10, 5), 1);  /* ring centre */
  assert_int_equal(get_px(&f, 10, 3), 1);  /* pocket between ring and diamond */
  assert_int_equal(get_px(&f, 10, 12), 1); /* the rest of the diamond */
  assert_int_equal(get_px(&f, 0, 0), 0);
  lsm_mask_free(&f);
  lsm_mask_free(&m);
}

static void test_fill_in_place_and_errors(void **state) {
  (void)state;
  lsm_mask m = new_mask(41, 41);
  draw_circle(&m, 20, 20, 10);
  lsm_mask ref = fill(&m);
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_outline_fill(&m, &m, &err), LSM_OK); /* in place */
  assert_memory_equal(m.pixels, ref.pixels, 41 * 41);
  /* a preallocated output of the wrong size */
  lsm_mask wrong = new_mask(40, 41);
  assert_int_equal(lsm_outline_fill(&m, &wrong, &err), LSM_ERR_INTERNAL);
  assert_true(strlen(err.msg) > 0);
  lsm_mask_free(&wrong);
  lsm_mask_free(&ref);
  lsm_mask_free(&m);
}

/* Noise: no crash, outline pixels are always filled, and thin shapes whose
 * background is one border-connected piece fill nothing more. */
static void test_fill_noise(void **state) {
  (void)state;
  uint64_t rng = 777;
  for (int c = 0; c < 10; ++c) {
    const int w = 1 + (int)(lsm_test_rand(&rng) % 60), h = 1 + (int)(lsm_test_rand(&rng) % 60);
    lsm_mask m = new_mask(w, h);
    for (int k = 0; k < w * h; ++k) m.pixels[k] = lsm_test_rand(&rng) % 100 < 30;
    lsm_mask f = fill(&m);
    for (int k = 0; k < w * h; ++k)
      if (m.pixels[k]) assert_int_equal(f.pixels[k], 1);
    lsm_mask_free(&f);
    lsm_mask_free(&m);
  }
}

/* ------------------------------------------------------------------------ */
/* signed distance of an outline                                             */

static void test_sdf_outline_disc(void **state) {
  (void)state;
  const int N = 41, c = 20, R = 10;
  lsm_mask m = new_mask(N, N);
  draw_circle(&m, c, c, R);
  lsm_mask f = fill(&m);
  lsm_grid *phi = new_grid(N, N, 1.0f, 1.0f);
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_sdf_from_outline(&m, phi, &err), LSM_OK);
  for (int j = 0; j < N; ++j)
    for (int i = 0; i < N; ++i) {
      const float v = LSM_AT(phi, i, j);
      if (get_px(&m, i, j))
        assert_true(v == 0.0f);
      else if (get_px(&f, i, j))
        assert_true(v < 0.0f);
      else
        assert_true(v > 0.0f);
      /* |phi| is the distance to the nearest contour pixel: within a pixel
       * of the distance to the circle */
      assert_close(fabs(v), fabs(dist(i, j, c, c) - R), 1.0);
    }
  assert_close(LSM_AT(phi, c, c), -R, 0.5);
  assert_close(LSM_AT(phi, -2, c), LSM_AT(phi, 0, c), 0);
  lsm_grid_destroy(&phi);
  lsm_mask_free(&f);
  lsm_mask_free(&m);
}

static void test_sdf_outline_nested_and_empty(void **state) {
  (void)state;
  lsm_mask m = new_mask(45, 45);
  draw_circle(&m, 22, 22, 18);
  draw_circle(&m, 22, 22, 12);
  draw_circle(&m, 22, 22, 6);
  lsm_grid *phi = new_grid(45, 45, 0.5f, 0.5f);
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_sdf_from_outline(&m, phi, &err), LSM_OK);
  assert_true(LSM_AT(phi, 22, 22) < 0); /* island */
  assert_close(LSM_AT(phi, 22, 22), -0.5 * nearest_px(&m, 22, 22), 1e-6);
  assert_true(LSM_AT(phi, 22 + 9, 22) > 0); /* hole */
  assert_close(LSM_AT(phi, 22 + 9, 22), 0.5 * nearest_px(&m, 22 + 9, 22), 1e-6);
  assert_true(LSM_AT(phi, 22 + 15, 22) < 0); /* outer annulus */
  assert_true(LSM_AT(phi, 1, 1) > 0);        /* outside */
  assert_true(LSM_AT(phi, 22 + 18, 22) == 0.0f);

  memset(m.pixels, 0, 45 * 45);
  assert_int_equal(lsm_sdf_from_outline(&m, phi, &err), LSM_OK);
  assert_close(lsm_grid_min(phi), LSM_SDF_FAR * phi->dx, 0);
  assert_close(LSM_AT(phi, -4, 48), LSM_SDF_FAR * phi->dx, 0);
  lsm_grid_destroy(&phi);
  lsm_mask_free(&m);
}

/* ------------------------------------------------------------------------ */
/* hull centroid                                                             */

static void test_hull_rectangle(void **state) {
  (void)state;
  lsm_mask m = new_mask(20, 16);
  for (int j = 5; j <= 12; ++j)
    for (int i = 3; i <= 10; ++i) set_px(&m, i, j);
  double cx = -1, cy = -1;
  assert_int_equal(lsm_hull_centroid(&m, &cx, &cy), 1);
  assert_true(cx == 6.5); /* exactly */
  assert_true(cy == 8.5);
  /* odd sizes, whole image */
  lsm_mask full = new_mask(7, 5);
  memset(full.pixels, 1, 35);
  assert_int_equal(lsm_hull_centroid(&full, &cx, &cy), 1);
  assert_true(cx == 3.0);
  assert_true(cy == 2.0);
  lsm_mask_free(&full);
  lsm_mask_free(&m);
}

static void test_hull_l_shape(void **state) {
  (void)state;
  /* L: a bar of columns 0..9 on rows 0..2 and a leg of columns 0..2 on rows
   * 3..9.  Hull of the pixel centres: (0,0) (9,0) (9,2) (2,9) (0,9), i.e. the
   * 9x9 square [0,9]^2 minus the right triangle (9,2) (9,9) (2,9).
   *   square:   area 81,   centroid (4.5, 4.5)
   *   triangle: area 24.5, centroid ((9+9+2)/3, (2+9+9)/3) = (20/3, 20/3)
   *   hull:     area 56.5, centroid (81*4.5 - 24.5*20/3) / 56.5 on both axes. */
  lsm_mask m = new_mask(12, 11);
  for (int j = 0; j <= 2; ++j)
    for (int i = 0; i <= 9; ++i) set_px(&m, i, j);
  for (int j = 3; j <= 9; ++j)
    for (int i = 0; i <= 2; ++i) set_px(&m, i, j);
  const double want = (81.0 * 4.5 - 24.5 * 20.0 / 3.0) / 56.5;
  double cx, cy;
  assert_int_equal(lsm_hull_centroid(&m, &cx, &cy), 1);
  assert_close(cx, want, 1e-12);
  assert_close(cy, want, 1e-12);
  lsm_mask_free(&m);
}

static void test_hull_degenerate(void **state) {
  (void)state;
  lsm_mask m = new_mask(9, 6);
  double cx = 0, cy = 0;
  assert_int_equal(lsm_hull_centroid(&m, &cx, &cy), 0); /* empty */
  set_px(&m, 7, 4);
  assert_int_equal(lsm_hull_centroid(&m, &cx, &cy), 1); /* single pixel */
  assert_true(cx == 7.0 && cy == 4.0);
  memset(m.pixels, 0, 54);
  for (int i = 2; i <= 8; ++i) set_px(&m, i, 3); /* horizontal segment */
  assert_int_equal(lsm_hull_centroid(&m, &cx, &cy), 1);
  assert_true(cx == 5.0 && cy == 3.0);
  memset(m.pixels, 0, 54);
  for (int j = 0; j <= 5; ++j) set_px(&m, 1, j); /* vertical segment */
  assert_int_equal(lsm_hull_centroid(&m, &cx, &cy), 1);
  assert_true(cx == 1.0 && cy == 2.5);
  memset(m.pixels, 0, 54);
  for (int k = 0; k <= 4; ++k) set_px(&m, 2 * k, k); /* sparse diagonal segment */
  assert_int_equal(lsm_hull_centroid(&m, &cx, &cy), 1);
  assert_true(cx == 4.0 && cy == 2.0);
  lsm_mask_free(&m);
}

static void test_hull_triangle(void **state) {
  (void)state;
  /* pixels with i <= j in an (n+1)^2 box: hull (0,0) (0,n) (n,n), centroid
   * (n/3, 2n/3) */
  const int n = 12;
  lsm_mask m = new_mask(n + 1, n + 1);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= j; ++i) set_px(&m, i, j);
  double cx, cy;
  assert_int_equal(lsm_hull_centroid(&m, &cx, &cy), 1);
  assert_close(cx, n / 3.0, 1e-12);
  assert_close(cy, 2.0 * n / 3.0, 1e-12);
  lsm_mask_free(&m);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_edt_random_vs_brute),
      cmocka_unit_test(test_edt_large_threads),
      cmocka_unit_test(test_edt_bad_arguments),
      cmocka_unit_test(test_sdf_half_plane),
      cmocka_unit_test(test_sdf_disc),
      cmocka_unit_test(test_sdf_anisotropic),
      cmocka_unit_test(test_sdf_random_vs_brute),
      cmocka_unit_test(test_sdf_empty_full_and_errors),
      cmocka_unit_test(test_fill_small_exact),
      cmocka_unit_test(test_fill_disc),
      cmocka_unit_test(test_fill_ring),
      cmocka_unit_test(test_fill_three_nested),
      cmocka_unit_test(test_fill_side_by_side),
      cmocka_unit_test(test_fill_open_at_border),
      cmocka_unit_test(test_fill_touching_border),
      cmocka_unit_test(test_fill_diamond),
      cmocka_unit_test(test_fill_touching_contours),
      cmocka_unit_test(test_fill_in_place_and_errors),
      cmocka_unit_test(test_fill_noise),
      cmocka_unit_test(test_sdf_outline_disc),
      cmocka_unit_test(test_sdf_outline_nested_and_empty),
      cmocka_unit_test(test_hull_rectangle),
      cmocka_unit_test(test_hull_l_shape),
      cmocka_unit_test(test_hull_degenerate),
      cmocka_unit_test(test_hull_triangle),
  };
  return cmocka_run_group_tests_name("sdf", tests, NULL, NULL);
}
