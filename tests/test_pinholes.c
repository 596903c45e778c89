/* Tests for solver/recon/lsm_pinholes.c: the enclosed outside of a slice and
 * of the two slices of a gap, against a flood over the whole image written
 * here (the module floods only the box of the inside and its ring). */
#include "tests/lsm_test.h"

#include "solver/base/lsm_grid.h"
#include "solver/recon/lsm_pinholes.h"

/* Whether each cell of an nx x ny image is enclosed: outside (0 < phi <
 * thin), and not joined by 4-steps through such cells to the image border or
 * to a cell at least `thin` outside.  enclosed: nx * ny bytes. */
static void enclosed_by_flood(const float *phi, int nx, int ny, float thin, uint8_t *enclosed) {
  const size_t n = (size_t)nx * (size_t)ny;
  uint8_t *reached = calloc(n, 1);
  int *queue = malloc(n * sizeof *queue);
  assert_non_null(reached);
  assert_non_null(queue);
  size_t tail = 0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int k = j * nx + i, border = i == 0 || j == 0 || i == nx - 1 || j == ny - 1;
      if (phi[k] >= thin || (phi[k] > 0.0f && border)) reached[k] = 1, queue[tail++] = k;
    }
  for (size_t head = 0; head < tail; ++head) {
    const int k = queue[head], i = k % nx, j = k / nx;
    const int nb[4] = {k - nx, k - 1, k + 1, k + nx};
    const int ok[4] = {j > 0, i > 0, i < nx - 1, j < ny - 1};
    for (int m = 0; m < 4; ++m)
      if (ok[m] && !reached[nb[m]] && phi[nb[m]] > 0.0f) reached[nb[m]] = 1, queue[tail++] = nb[m];
  }
  for (size_t k = 0; k < n; ++k) enclosed[k] = phi[k] > 0.0f && !reached[k];
  free(reached);
  free(queue);
}

/* A new nx x ny field of random rectangles of inside (-1), thin outside (0.5)
 * and open outside (5) cells over a background of one of the three. */
static lsm_grid *random_field(int nx, int ny, uint64_t *seed) {
  static const float values[3] = {-1.0f, 0.5f, 5.0f};
  lsm_grid *g = NULL;
  assert_int_equal(lsm_grid_create(nx, ny, 1.0f, 1.0f, &g, NULL), LSM_OK);
  const float background = values[lsm_test_rand(seed) % 3];
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i < g->nx; ++i) LSM_AT(g, i, j) = background;
  const int rects = (int)(lsm_test_rand(seed) % 8);
  for (int r = 0; r < rects; ++r) {
    const int i0 = (int)(lsm_test_rand(seed) % (uint64_t)g->nx);
    const int j0 = (int)(lsm_test_rand(seed) % (uint64_t)g->ny);
    const int w = 1 + (int)(lsm_test_rand(seed) % 12), h = 1 + (int)(lsm_test_rand(seed) % 12);
    const float v = values[lsm_test_rand(seed) % 3];
    for (int j = j0; j < j0 + h && j < g->ny; ++j)
      for (int i = i0; i < i0 + w && i < g->nx; ++i) LSM_AT(g, i, j) = v;
  }
  return g;
}

static void copy_field(const lsm_grid *g, float *out) {
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i < g->nx; ++i) out[j * g->nx + i] = LSM_AT(g, i, j);
}

/* lsm_pinholes_find on random pairs of fields, near and touching the
 * borders, equals the whole-image flood: the cells enclosed in the slice
 * outside there (phi_a > 0: a's, else b's). */
static void test_find_equals_whole_image_flood(void **state) {
  (void)state;
  uint64_t seed = 12345u;
  lsm_err err;
  lsm_err_clear(&err);
  for (int trial = 0; trial < 400; ++trial) {
    const int nx = 1 + (int)(lsm_test_rand(&seed) % 24), ny = 1 + (int)(lsm_test_rand(&seed) % 24);
    lsm_grid *a = random_field(nx, ny, &seed), *b = random_field(nx, ny, &seed);
    const size_t n = (size_t)nx * (size_t)ny;
    float *fa = malloc(n * sizeof *fa), *fb = malloc(n * sizeof *fb);
    uint8_t *ea = malloc(n), *eb = malloc(n);
    assert_true(fa && fb && ea && eb);
    copy_field(a, fa);
    copy_field(b, fb);
    enclosed_by_flood(fa, nx, ny, 2.0f, ea);
    enclosed_by_flood(fb, nx, ny, 2.0f, eb);
    size_t expected = 0;
    for (size_t k = 0; k < n; ++k) expected += (size_t)ea[k] + (size_t)eb[k];
    uint8_t *pinhole = NULL;
    assert_int_equal(lsm_pinholes_find(a, b, 2.0f, &pinhole, &err), LSM_OK);
    assert_int_equal(pinhole != NULL, expected > 0);
    for (size_t k = 0; pinhole && k < n; ++k)
      assert_int_equal(pinhole[k], fa[k] > 0.0f ? ea[k] : eb[k]);
    free(pinhole);
    free(fa);
    free(fb);
    free(ea);
    free(eb);
    lsm_grid_destroy(&a);
    lsm_grid_destroy(&b);
  }
}

/* lsm_mask_has_hole on random masks: a hole is an outside cell the
 * whole-image flood from the border does not reach. */
static void test_has_hole_equals_whole_image_flood(void **state) {
  (void)state;
  uint64_t seed = 777u;
  lsm_err err;
  lsm_err_clear(&err);
  for (int trial = 0; trial < 400; ++trial) {
    const int nx = 1 + (int)(lsm_test_rand(&seed) % 24), ny = 1 + (int)(lsm_test_rand(&seed) % 24);
    lsm_grid *g = random_field(nx, ny, &seed);
    const size_t n = (size_t)nx * (size_t)ny;
    lsm_mask m;
    assert_int_equal(lsm_mask_create(nx, ny, &m, &err), LSM_OK);
    float *f = malloc(n * sizeof *f);
    uint8_t *enclosed = malloc(n);
    int32_t *cls = malloc(n * sizeof *cls), *queue = malloc(n * sizeof *queue);
    assert_true(f && enclosed && cls && queue);
    copy_field(g, f);
    for (size_t k = 0; k < n; ++k) {
      m.pixels[k] = f[k] <= 0.0f;
      f[k] = f[k] <= 0.0f ? -1.0f : 1.0f; /* a mask: no cell is open by itself */
    }
    enclosed_by_flood(f, nx, ny, 2.0f, enclosed);
    int any = 0;
    for (size_t k = 0; k < n; ++k) any |= enclosed[k];
    assert_int_equal(lsm_mask_has_hole(&m, cls, queue), any);
    free(f);
    free(enclosed);
    free(cls);
    free(queue);
    lsm_mask_free(&m);
    lsm_grid_destroy(&g);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_find_equals_whole_image_flood),
      cmocka_unit_test(test_has_hole_equals_whole_image_flood),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
