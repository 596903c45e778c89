/* lsm_preview: the 3D picture drawn as the slices arrive (heights expected)
 * is the one drawn at the end, byte for byte, also when the slices span
 * more or fewer heights than expected; it shows the object where it is; odd
 * volumes (one slice, one column, all inside) draw without harm. */
#include "lsm_test.h"

#include <png.h>
#include <unistd.h>

#include "io/lsm_io.h"
#include "io/lsm_preview.h"

/* A ball of radius 0.35 * nx at the middle, rising with z. */
static void ball(float *phi, int nx, int ny, int k, int nz) {
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double x = i - 0.5 * nx, y = j - 0.5 * ny - 0.1 * k, z = k - 0.5 * nz;
      phi[j * nx + i] = (float)(sqrt(x * x + y * y + z * z) - 0.35 * nx);
    }
}

static void all_inside(float *phi, int nx, int ny, int k, int nz) {
  (void)k, (void)nz;
  for (int q = 0; q < nx * ny; ++q) phi[q] = -2.0f;
}

typedef void (*shape_fn)(float *phi, int nx, int ny, int k, int nz);

/* Writes the pictures of nz slices 1.5 apart from z = 2, the heights told
 * ahead as [2, z_last] unless z_last is NaN. */
static void draw(const char *dir, const char *tag, shape_fn shape, int nx, int ny, int nz,
                 double z_last) {
  lsm_preview *p = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_preview_open(nx, ny, 0.8, 1.0, 1.5, &p, &err), LSM_OK);
  if (!isnan(z_last)) assert_int_equal(lsm_preview_expect(p, 2.0, z_last, &err), LSM_OK);
  float *phi = malloc(sizeof *phi * (size_t)nx * (size_t)ny);
  assert_non_null(phi);
  for (int k = 0; k < nz; ++k) {
    shape(phi, nx, ny, k, nz);
    assert_int_equal(lsm_preview_add_slice(p, phi, 2.0 + 1.5 * k, k % 4 == 0 ? k : -1, &err), LSM_OK);
  }
  free(phi);
  char montage[256], render[256];
  snprintf(montage, sizeof montage, "%s/%s-montage.png", dir, tag);
  snprintf(render, sizeof render, "%s/%s-render.png", dir, tag);
  if (lsm_preview_write(p, montage, render, &err) != LSM_OK) fail_msg("%s: %s", tag, err.msg);
  lsm_preview_free(&p);
}

static int same_file(const char *dir, const char *a, const char *b) {
  char pa[256], pb[256];
  snprintf(pa, sizeof pa, "%s/%s-render.png", dir, a);
  snprintf(pb, sizeof pb, "%s/%s-render.png", dir, b);
  FILE *fa = fopen(pa, "rb"), *fb = fopen(pb, "rb");
  assert_non_null(fa);
  assert_non_null(fb);
  int same = 1, ca, cb;
  do {
    ca = fgetc(fa);
    cb = fgetc(fb);
    same &= ca == cb;
  } while (same && ca != EOF);
  fclose(fa);
  fclose(fb);
  return same;
}

/* The picture's pixel (x, y) as RGB, and its size. */
static void pixel(const char *path, int fx, int fy, int rgb[3], int *w, int *h) {
  png_image im;
  memset(&im, 0, sizeof im);
  im.version = PNG_IMAGE_VERSION;
  assert_true(png_image_begin_read_from_file(&im, path));
  im.format = PNG_FORMAT_RGB;
  uint8_t *px = malloc(PNG_IMAGE_SIZE(im));
  assert_non_null(px);
  assert_true(png_image_finish_read(&im, NULL, px, 0, NULL));
  *w = (int)im.width;
  *h = (int)im.height;
  const int x = fx * *w / 100, y = fy * *h / 100;
  for (int c = 0; c < 3; ++c) rgb[c] = px[3 * ((size_t)y * im.width + (size_t)x) + (size_t)c];
  free(px);
}

static void test_incremental_equals_final(void **state) {
  (void)state;
  char dir[] = "/tmp/lsm_test_preview_XXXXXX";
  assert_non_null(mkdtemp(dir));
  const int nz = 40;
  const double z_last = 2.0 + 1.5 * (nz - 1);
  draw(dir, "end", ball, 48, 40, nz, NAN);
  draw(dir, "ahead", ball, 48, 40, nz, z_last);
  assert_true(same_file(dir, "end", "ahead"));
  /* the last slice a little short of the heights told: the same picture */
  draw(dir, "short", ball, 48, 40, nz, z_last + 1.0);
  draw(dir, "longer", ball, 48, 40, nz, z_last - 20.0); /* more than told: drawn at the end */
  assert_true(same_file(dir, "end", "longer"));
  /* the ball shows in the middle; the corner is background (grey, a little blue) */
  char path[256];
  snprintf(path, sizeof path, "%s/short-render.png", dir);
  int mid[3], corner[3], w, h;
  pixel(path, 50, 50, mid, &w, &h);
  pixel(path, 2, 2, corner, &w, &h);
  assert_true(w >= 64 && h >= 64);
  assert_true(mid[0] - mid[2] > 12);                            /* the surface's warm colour */
  assert_true(corner[2] - corner[0] >= 3 && corner[2] - corner[0] <= 5); /* the background */
  const char *tags[] = {"end", "ahead", "short", "longer"};
  for (int t = 0; t < 4; ++t)
    for (int kind = 0; kind < 2; ++kind) {
      snprintf(path, sizeof path, "%s/%s-%s.png", dir, tags[t], kind ? "render" : "montage");
      unlink(path);
    }
  rmdir(dir);
}

static void test_odd_volumes(void **state) {
  (void)state;
  char dir[] = "/tmp/lsm_test_preview_XXXXXX";
  assert_non_null(mkdtemp(dir));
  const struct {
    const char *tag;
    shape_fn shape;
    int nx, ny, nz;
  } odd[] = {{"one-slice", ball, 30, 20, 1},   {"one-column", ball, 1, 25, 12},
             {"two-by-two", ball, 2, 2, 2},     {"all-inside", all_inside, 20, 16, 9},
             {"many", ball, 12, 10, 300}}; /* more planes than kept: the step doubles */
  for (size_t q = 0; q < sizeof odd / sizeof odd[0]; ++q) {
    draw(dir, odd[q].tag, odd[q].shape, odd[q].nx, odd[q].ny, odd[q].nz,
         2.0 + 1.5 * (odd[q].nz - 1));
    char path[256];
    for (int kind = 0; kind < 2; ++kind) {
      snprintf(path, sizeof path, "%s/%s-%s.png", dir, odd[q].tag, kind ? "render" : "montage");
      assert_int_equal(access(path, F_OK), 0);
      unlink(path);
    }
  }
  rmdir(dir);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_incremental_equals_final),
      cmocka_unit_test(test_odd_volumes),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
