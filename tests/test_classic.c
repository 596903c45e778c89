/* The classic baseline: `--method blend --interp linear --align none` is the
 * textbook shape-based interpolation (Raya & Udupa 1990).  Between two
 * non-empty slices every output slice is (1 - s) phi_A + s phi_B of the two
 * slices' signed distances; next to an empty slice the empty side counts as
 * the constant R, the full slice's largest depth (the halfway rule: the
 * object closes at mid-gap, and nothing is drawn from there on).  This test
 * computes that directly from the slices' signed distances (lsm_sdf, tested
 * in test_sdf) and asks the stack driver for the same floats, voxel for voxel:
 * no reconstruction rule may act in this mode. */
#include "tests/lsm_test.h"

#include "solver/base/lsm_grid.h"
#include "solver/recon/lsm_stack.h"
#include "solver/sdf/lsm_sdf.h"

typedef struct blob {
  double cx, cy, rx, ry; /* an axis-aligned ellipse (rx, ry > 0) or a box (rx, ry < 0) */
} blob;

typedef struct slice_def {
  int n;
  blob b[6];
} slice_def;

typedef struct stack_def {
  int width, height;
  size_t count;
  const slice_def *slices;
  const double *z; /* whole numbers from 0: the outputs fall on them (dz 1) */
} stack_def;

static int in_blob(const blob *b, int x, int y) {
  const double u = x - b->cx, v = y - b->cy;
  if (b->rx < 0) return fabs(u) <= -b->rx && fabs(v) <= -b->ry;
  return (u * u) / (b->rx * b->rx) + (v * v) / (b->ry * b->ry) <= 1.0;
}

static void paint(const slice_def *d, lsm_mask *m) {
  for (int y = 0; y < m->height; ++y)
    for (int x = 0; x < m->width; ++x) {
      uint8_t v = 0;
      for (int k = 0; k < d->n; ++k) v |= (uint8_t)in_blob(&d->b[k], x, y);
      m->pixels[(size_t)y * m->width + x] = v;
    }
}

static lsm_status src_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
  const stack_def *s = ctx;
  LSM_TRY(lsm_mask_create(s->width, s->height, out, err));
  paint(&s->slices[index], out);
  return LSM_OK;
}

typedef struct sink_ctx {
  float *phi; /* count x width x height */
  double *z;
  long *input;
  size_t n, cap, cells;
} sink_ctx;

static lsm_status sink_emit(void *ctx, const float *phi, int width, int height, double z,
                            long input_index, lsm_err *err) {
  (void)err;
  sink_ctx *c = ctx;
  assert_int_equal((size_t)width * (size_t)height, c->cells);
  assert_true(c->n < c->cap);
  memcpy(c->phi + c->n * c->cells, phi, c->cells * sizeof *phi);
  c->z[c->n] = z;
  c->input[c->n] = input_index;
  c->n++;
  return LSM_OK;
}

/* Signed distance of slice k on the image, and whether the slice is empty. */
static float *slice_phi(const stack_def *s, size_t k, int *empty) {
  lsm_err err;
  lsm_err_clear(&err);
  lsm_mask m;
  assert_int_equal(lsm_mask_create(s->width, s->height, &m, &err), LSM_OK);
  paint(&s->slices[k], &m);
  *empty = lsm_mask_count(&m) == 0;
  lsm_grid *g = NULL;
  assert_int_equal(lsm_grid_create(s->width, s->height, 1.0f, 1.0f, &g, &err), LSM_OK);
  assert_int_equal(lsm_sdf_from_mask(&m, g, &err), LSM_OK);
  float *phi = malloc((size_t)s->width * s->height * sizeof *phi);
  assert_non_null(phi);
  for (int y = 0; y < s->height; ++y)
    for (int x = 0; x < s->width; ++x) phi[(size_t)y * s->width + x] = LSM_AT(g, x, y);
  lsm_grid_destroy(&g);
  lsm_mask_free(&m);
  return phi;
}

/* The textbook's slice at height z into want; returns 0 where both slices of
 * its gap are empty or the slice is an empty input (nothing to draw: only the sign is compared). */
static int textbook(const stack_def *s, float *const *phi, const int *empty, double z,
                    float *want) {
  const size_t cells = (size_t)s->width * (size_t)s->height;
  size_t k = 0;
  while (k + 2 < s->count && s->z[k + 1] <= z) ++k;
  if (z == s->z[k] || z == s->z[k + 1]) {
    const size_t at = z == s->z[k] ? k : k + 1;
    memcpy(want, phi[at], cells * sizeof *want);
    return !empty[at];
  }
  const double s_ab = (z - s->z[k]) / (s->z[k + 1] - s->z[k]);
  if (empty[k] && empty[k + 1]) return 0;
  if (!empty[k] && !empty[k + 1]) {
    const float f = (float)s_ab;
    for (size_t c = 0; c < cells; ++c) want[c] = (1.0f - f) * phi[k][c] + f * phi[k + 1][c];
    return 1;
  }
  /* the halfway rule: the empty side is R, the full side's largest depth */
  const float *full = empty[k] ? phi[k + 1] : phi[k];
  const double sigma = empty[k] ? 1.0 - s_ab : s_ab; /* from the full slice */
  float least = 0.0f;
  for (size_t c = 0; c < cells; ++c) least = full[c] < least ? full[c] : least;
  const double R = fmax(-(double)least, 0.5);
  const float keep = (float)(1.0 - sigma), rise = (float)(sigma * R);
  for (size_t c = 0; c < cells; ++c) {
    want[c] = keep * full[c] + rise;
    /* from mid-gap on nothing is left (the deepest cell's tie at mid-gap too) */
    if (sigma >= 0.5 && !(want[c] > 0.0f)) want[c] = 1e-6f;
  }
  return 1;
}

/* Runs the stack in the classic mode and compares every output slice with
 * the textbook's. */
static void check_classic(const stack_def *s) {
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  o.method = LSM_METHOD_BLEND;
  o.interp = LSM_INTERP_LINEAR;
  o.align = LSM_ALIGN_NONE;
  o.morph.threads = 2;
  const size_t cells = (size_t)s->width * (size_t)s->height;
  const size_t outputs = (size_t)s->z[s->count - 1] + 1;
  sink_ctx c = {NULL, NULL, NULL, 0, outputs, cells};
  c.phi = malloc(outputs * cells * sizeof *c.phi);
  c.z = malloc(outputs * sizeof *c.z);
  c.input = malloc(outputs * sizeof *c.input);
  assert_true(c.phi && c.z && c.input);
  lsm_slice_source source = {(void *)s, s->count, s->z, src_load, NULL};
  lsm_slice_sink sink = {&c, sink_emit};
  lsm_pair_stats stats[16];
  lsm_err err;
  lsm_err_clear(&err);
  assert_true(s->count <= 16);
  assert_int_equal(lsm_stack_run(&source, s->width, s->height, &o, &sink, stats, NULL, &err),
                   LSM_OK);
  assert_int_equal(c.n, outputs);
  float *phi[16];
  int empty[16];
  for (size_t k = 0; k < s->count; ++k) phi[k] = slice_phi(s, k, &empty[k]);
  float *want = malloc(cells * sizeof *want);
  assert_non_null(want);
  size_t differ = 0, sides = 0, compared = 0;
  for (size_t n = 0; n < c.n; ++n) {
    assert_close(c.z[n], (double)n, 0.0);
    const float *got = c.phi + n * cells;
    const int drawn = textbook(s, phi, empty, c.z[n], want);
    for (size_t k = 0; k < cells; ++k) {
      compared++;
      if (!drawn) {
        sides += !(got[k] > 0.0f);
        continue;
      }
      /* an exact 0 is written a millionth of a pixel below (rule zero-ties:
       * the same inside for readers taking phi < 0 as inside) */
      const int same = want[k] == 0.0f ? got[k] <= 0.0f && got[k] >= -1e-6f : got[k] == want[k];
      const int side = (got[k] <= 0.0f) != (want[k] <= 0.0f);
      if (side && sides++ == 0)
        print_message("first side: z %g, cell (%zu, %zu): %.9g, textbook %.9g\n", c.z[n],
                      k % (size_t)s->width, k / (size_t)s->width, got[k], want[k]);
      if (!same && differ++ == 0)
        print_message("first difference: z %g, cell (%zu, %zu): %.9g, textbook %.9g\n", c.z[n],
                      k % (size_t)s->width, k / (size_t)s->width, got[k], want[k]);
    }
  }
  print_message("%zu voxels: %zu differ from the textbook, %zu on the other side of 0\n",
                compared, differ, sides);
  assert_int_equal(differ, 0);
  assert_int_equal(sides, 0);
  for (size_t k = 0; k < s->count; ++k) free(phi[k]);
  free(want);
  free(c.phi);
  free(c.z);
  free(c.input);
}

/* Two discs merging into one (the blend's ridge leaves a pinhole there), an
 * object ending at an empty slice and starting again beyond it, parts of
 * unequal depth ending together, a box running across the image border. */
static void test_classic_shapes(void **state) {
  (void)state;
  const slice_def slices[] = {
      {2, {{20, 30, 9, 9}, {44, 30, 9, 9}}},
      {1, {{32, 30, 15, 11}}},
      {0, {{0, 0, 0, 0}}},
      {2, {{-4, 20, -10, -6}, {40, 40, 12, 8}}},
      {3, {{-2, 24, -9, -5}, {44, 38, 10, 10}, {12, 52, 3, 3}}},
      {0, {{0, 0, 0, 0}}},
  };
  const double z[] = {0, 8, 12, 20, 26, 31};
  const stack_def s = {64, 64, 6, slices, z};
  check_classic(&s);
  /* three discs around a gap, then one disc over them: the blend's ridge at
   * the gap's centre leaves a small hole for a few slices */
  const slice_def three[] = {
      {3, {{32, 20, 8, 8}, {21.6, 38, 8, 8}, {42.4, 38, 8, 8}}},
      {1, {{32, 32, 22, 22}}},
  };
  const double z3[] = {0, 16};
  const stack_def t = {64, 64, 2, three, z3};
  check_classic(&t);
}

/* Random unions of ellipses and boxes, some slices empty, uneven gaps. */
static void test_classic_random(void **state) {
  (void)state;
  uint64_t seed = 0x9e3779b97f4a7c15u;
  for (int trial = 0; trial < 4; ++trial) {
    slice_def slices[7];
    double z[7];
    double at = 0.0;
    for (int k = 0; k < 7; ++k) {
      z[k] = at;
      at += 2 + (double)(lsm_test_rand(&seed) % 9);
      const int n = (int)(lsm_test_rand(&seed) % 5); /* 0: an empty slice */
      slices[k].n = n;
      for (int b = 0; b < n; ++b) {
        const double cx = (double)(lsm_test_rand(&seed) % 72) - 4.0;
        const double cy = (double)(lsm_test_rand(&seed) % 56);
        const double rx = 2.0 + (double)(lsm_test_rand(&seed) % 14);
        const double ry = 2.0 + (double)(lsm_test_rand(&seed) % 10);
        const int box = lsm_test_rand(&seed) % 3 == 0;
        slices[k].b[b] = (blob){cx, cy, box ? -rx : rx, box ? -ry : ry};
      }
    }
    const stack_def s = {64, 56, 7, slices, z};
    check_classic(&s);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_classic_shapes),
      cmocka_unit_test(test_classic_random),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
