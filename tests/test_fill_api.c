/* Tests of solver/fill (the label boxes against whole slices, threads) and of
 * liblsmorph's public functions (solver/api/lsmorph.h). */
#include "lsm_test.h"

#include "solver/api/lsmorph.h"
#include "solver/fill/lsm_fill.h"

enum { NX = 96, NY = 88, NZ = 33 };

/* Labels on physical coordinates (1 x 1 x 2): a disc moving diagonally 3 px a
 * slice (its pairs are aligned), two discs drifting apart (moving parts), a
 * turning ellipse, touching a fixed block. */
static uint8_t *scene(void) {
  uint8_t *v = calloc((size_t)NX * NY * NZ, 1);
  for (int k = 2; k < NZ - 2; ++k)
    for (int j = 0; j < NY; ++j)
      for (int i = 0; i < NX; ++i) {
        uint8_t *p = v + ((size_t)k * NY + (size_t)j) * NX + (size_t)i;
        const double t = (k - 2) / (double)(NZ - 5);
        const double mx = 12 + 60 * t, my = 10 + 20 * t;
        const double a = 1.4 * t, ex = 60, ey = 62;
        const double u = (i - ex) * cos(a) + (j - ey) * sin(a), w = -(i - ex) * sin(a) + (j - ey) * cos(a);
        if ((i - mx) * (i - mx) + (j - my) * (j - my) < 64) *p = 1;
        else if ((i - 30 + 10 * t) * (i - 30 + 10 * t) + (j - 70) * (j - 70) < 16 ||
                 (i - 40 - 10 * t) * (i - 40 - 10 * t) + (j - 70) * (j - 70) < 16) *p = 2;
        else if (u * u / 196.0 + w * w / 36.0 < 1) *p = 3;
        else if (i >= 74 && i < 90 && j >= 50 && j < 80) *p = 4;
      }
  return v;
}

static void drawn_every(uint8_t *v, int step) {
  for (int k = 0; k < NZ; ++k)
    if (k % step) memset(v + (size_t)k * NX * NY, 0, (size_t)NX * NY);
}

static void fill_motion(uint8_t *v, int whole, int threads, lsm_motion_mode motion) {
  lsm_voxels vox = {{NX, NY, NZ}, LSM_VOXEL_U8, v, {1.0, 1.0, 2.0}};
  lsm_fill_opts o;
  lsm_fill_opts_default(&o);
  o.stack.motion = motion;
  o.whole_slices = whole;
  o.threads = threads;
  lsm_err err;
  lsm_err_clear(&err);
  lsm_fill_plan *plan = NULL;
  if (lsm_fill_plan_make(&vox, &o, &plan, &err) != LSM_OK) fail_msg("%s", err.msg);
  assert_int_equal(plan->axis, 2);
  assert_true(plan->gap_slices > 0);
  lsm_fill_stats stats;
  if (lsm_fill_run(plan, &vox, &o, &stats, &err) != LSM_OK) fail_msg("%s", err.msg);
  assert_int_equal(stats.runs, 4);
  lsm_fill_plan_free(&plan);
}

static void fill_with(uint8_t *v, int whole, int threads) { /* the default */
  fill_motion(v, whole, threads, LSM_MOTION_AUTO);
}

/* A label's box plus the margin gives the whole slice's result: voxel for voxel in place
 * (--motion none: the morph inside the box sees what it would see on the whole slice);
 * with the field (--motion field, and auto where it takes it) but for a thousandth of the
 * voxels, its node grid and smoothing following the canvas. */
static void test_box_is_whole(void **state) {
  (void)state;
  const size_t n = (size_t)NX * NY * NZ;
  uint8_t *a = scene(), *b;
  drawn_every(a, 4);
  b = malloc(n);
  const lsm_motion_mode modes[3] = {LSM_MOTION_NONE, LSM_MOTION_FIELD, LSM_MOTION_AUTO};
  for (int m = 0; m < 3; ++m) {
    const lsm_motion_mode motion = modes[m];
    const int field = motion != LSM_MOTION_NONE;
    uint8_t *fresh = scene();
    drawn_every(fresh, 4);
    memcpy(a, fresh, n);
    memcpy(b, fresh, n);
    free(fresh);
    fill_motion(a, 0, 2, motion);
    fill_motion(b, 1, 2, motion);
    size_t differ = 0;
    for (size_t k = 0; k < n; ++k) differ += a[k] != b[k];
    print_message("%s: %zu voxels differ between the boxes and whole slices\n",
                  lsm_motion_name(motion), differ);
    if (field ? differ > n / 1000 : differ > 0)
      fail_msg("%zu voxels differ between the boxes and whole slices", differ);
  }
  /* and the thread count changes nothing (a: auto's boxes on 2 threads) */
  uint8_t *fresh = scene();
  memcpy(b, fresh, n);
  free(fresh);
  drawn_every(b, 4);
  fill_motion(b, 0, 1, LSM_MOTION_AUTO);
  assert_memory_equal(a, b, n);
  free(a);
  free(b);
}

/* lsmorph_fill gives lsm_fill's volume; a C-ordered view (k, j, i) with the
 * axis and spacing turned gives the same voxels. */
static void test_public_fill(void **state) {
  (void)state;
  const size_t n = (size_t)NX * NY * NZ;
  uint8_t *a = scene(), *b = malloc(n);
  drawn_every(a, 4);
  memcpy(b, a, n);
  fill_with(a, 0, 0);
  lsmorph_options o;
  lsmorph_options_default(&o);
  char msg[256];
  size_t filled = 0;
  const size_t sizes[3] = {NX, NY, NZ};
  const double spacing[3] = {1.0, 1.0, 2.0};
  assert_int_equal(lsmorph_fill(b, LSMORPH_UINT8, sizes, spacing, -1, NULL, 0, NULL, 0, &o,
                                &filled, msg, sizeof msg),
                   LSMORPH_OK);
  assert_int_equal(filled, 24); /* 0, 4, ..., 32 drawn: 33 - 9 */
  assert_memory_equal(a, b, n);
  o.method = "bogus";
  assert_int_equal(lsmorph_fill(b, LSMORPH_UINT8, sizes, spacing, -1, NULL, 0, NULL, 0, &o, NULL,
                                msg, sizeof msg),
                   LSMORPH_ERR_USAGE);
  assert_non_null(strstr(msg, "method: 'bogus' is not one of"));
  assert_string_equal(lsmorph_status_name(LSMORPH_ERR_USAGE), "usage error");
  free(a);
  free(b);
}

/* lsmorph_reconstruct: a disc growing between two masks, as the stack driver
 * gives it: one slice per dz, the input slices' signed distances at the ends. */
static void test_public_reconstruct(void **state) {
  (void)state;
  enum { W = 40, H = 30 };
  uint8_t masks[2][H][W];
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i) {
      masks[0][j][i] = (i - 20) * (i - 20) + (j - 15) * (j - 15) < 25;
      masks[1][j][i] = (i - 20) * (i - 20) + (j - 15) * (j - 15) < 100;
    }
  const double z[2] = {0.0, 4.0};
  const size_t count = lsmorph_reconstruct_count(z, 2, 1.0);
  assert_int_equal(count, 5);
  float *out = malloc(count * W * H * sizeof *out);
  char msg[256];
  assert_int_equal(lsmorph_reconstruct(&masks[0][0][0], 2, W, H, z, 1.0, 1.0, 1.0, NULL, out, count,
                                       msg, sizeof msg),
                   LSMORPH_OK);
  /* the centre is inside everywhere; a point at radius 7 is outside at the first
   * slice and inside at the last */
  for (size_t k = 0; k < count; ++k) assert_true(out[k * W * H + 15 * W + 20] < 0.0f);
  assert_true(out[15 * W + 27] > 0.0f);
  assert_true(out[4 * W * H + 15 * W + 27] < 0.0f);
  assert_int_equal(lsmorph_reconstruct(&masks[0][0][0], 2, W, H, z, 1.0, 1.0, 1.0, NULL, out, 3,
                                       msg, sizeof msg),
                   LSMORPH_ERR_USAGE);
  free(out);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_box_is_whole),
      cmocka_unit_test(test_public_fill),
      cmocka_unit_test(test_public_reconstruct),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
