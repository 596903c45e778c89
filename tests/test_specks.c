/* A new part grows as one piece (rule one-piece, solver/recon/lsm_specks):
 * the parts allowed between two slices (their overlap groups), the smallest
 * parts dropped beyond them, and the design document's Candlestick (two feet
 * -> one stem -> two arms -> three candles), whose third candle the morph
 * used to grow out of specks: no output slice may have more parts than the
 * larger count of its gap's two slices. */
#include "tests/lsm_test.h"

#include "solver/base/lsm_grid.h"
#include "solver/recon/lsm_specks.h"
#include "solver/recon/lsm_stack.h"

typedef struct circle {
  double cx, cy, r;
} circle;

typedef struct slice_def {
  int n;
  circle c[3];
} slice_def;

/* pixel centres within r of the centre (the rule of examples/gen_synthetic.c) */
static void paint(const slice_def *d, lsm_mask *m) {
  for (int y = 0; y < m->height; ++y)
    for (int x = 0; x < m->width; ++x) {
      uint8_t v = 0;
      for (int k = 0; k < d->n; ++k) {
        const double u = x - d->c[k].cx, w = y - d->c[k].cy;
        v |= (uint8_t)(u * u + w * w <= d->c[k].r * d->c[k].r);
      }
      m->pixels[(size_t)y * m->width + x] = v;
    }
}

/* Contour pixels (inside with a 4-neighbour outside) of the same discs. */
static void paint_outline(const slice_def *d, lsm_mask *m) {
  lsm_mask full;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_mask_create(m->width, m->height, &full, &err), LSM_OK);
  memset(m->pixels, 0, (size_t)m->width * m->height);
  for (int k = 0; k < d->n; ++k) {
    const slice_def one = {1, {d->c[k]}};
    paint(&one, &full);
    for (int y = 0; y < m->height; ++y)
      for (int x = 0; x < m->width; ++x) {
        const uint8_t *p = full.pixels + (size_t)y * m->width + x;
        if (!*p) continue;
        const int edge = x == 0 || y == 0 || x == m->width - 1 || y == m->height - 1 || !p[-1] ||
                         !p[1] || !p[-m->width] || !p[m->width];
        if (edge) m->pixels[(size_t)y * m->width + x] = 1;
      }
  }
  lsm_mask_free(&full);
}

static const slice_def CANDLESTICK[4] = {
    {2, {{25.5, 34.5, 21}, {73.5, 34.5, 21}}},
    {1, {{49.5, 34.5, 30}}},
    {2, {{27.5, 34.5, 19}, {71.5, 34.5, 19}}},
    {3, {{17.5, 34.5, 14}, {49.5, 34.5, 14}, {81.5, 34.5, 14}}},
};
static const double CANDLE_Z[4] = {0, 50, 100, 200};
enum { CW = 100, CH = 70 };

typedef struct source_ctx {
  int outline;
} source_ctx;

static lsm_status src_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
  const source_ctx *c = ctx;
  LSM_TRY(lsm_mask_create(CW, CH, out, err));
  if (c->outline) paint_outline(&CANDLESTICK[index], out);
  else paint(&CANDLESTICK[index], out);
  return LSM_OK;
}

/* Per output slice: its height and its parts (8-connected, phi <= 0). */
typedef struct sink_ctx {
  double z[256];
  int parts[256];
  size_t n;
  int32_t label[CW * CH], queue[CW * CH];
} sink_ctx;

static int parts_of(const float *phi, int32_t *label, int32_t *queue) {
  lsm_mask m;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_mask_create(CW, CH, &m, &err), LSM_OK);
  for (size_t k = 0; k < (size_t)CW * CH; ++k) m.pixels[k] = phi[k] <= 0.0f;
  int allowed = 0; /* the parts of one mask: its groups against an empty mask */
  lsm_mask none;
  assert_int_equal(lsm_mask_create(CW, CH, &none, &err), LSM_OK);
  assert_int_equal(lsm_specks_allowed(&m, &none, 0, 0, label, queue, &allowed, &err), LSM_OK);
  lsm_mask_free(&none);
  lsm_mask_free(&m);
  return allowed;
}

static lsm_status sink_emit(void *ctx, const float *phi, int width, int height, double z,
                            long input_index, lsm_err *err) {
  (void)err;
  (void)input_index;
  sink_ctx *c = ctx;
  assert_int_equal(width, CW);
  assert_int_equal(height, CH);
  assert_true(c->n < 256);
  c->z[c->n] = z;
  c->parts[c->n] = parts_of(phi, c->label, c->queue);
  c->n++;
  return LSM_OK;
}

/* The most parts of an output slice strictly inside each gap. */
static void candlestick(int outline, const char *off, int most[3]) {
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  o.input = outline ? LSM_INPUT_OUTLINE : LSM_INPUT_MASK;
  o.morph.threads = 2;
  lsm_err err;
  lsm_err_clear(&err);
  if (off) assert_int_equal(lsm_rules_switch_off(&o.rules, off, &err), LSM_OK);
  source_ctx src = {outline};
  static sink_ctx sink;
  memset(&sink, 0, sizeof sink);
  lsm_slice_source source = {&src, 4, CANDLE_Z, src_load, NULL};
  lsm_slice_sink out = {&sink, sink_emit};
  lsm_pair_stats stats[3];
  assert_int_equal(lsm_stack_run(&source, CW, CH, &o, &out, stats, NULL, &err), LSM_OK);
  assert_int_equal(sink.n, 201);
  most[0] = most[1] = most[2] = 0;
  for (size_t k = 0; k < sink.n; ++k)
    for (int g = 0; g < 3; ++g)
      if (sink.z[k] > CANDLE_Z[g] && sink.z[k] < CANDLE_Z[g + 1] && sink.parts[k] > most[g])
        most[g] = sink.parts[k];
}

/* Feet (2) -> stem (1) -> arms (2) -> candles (3): at most 2, 2 and 3 parts in
 * the three gaps, from masks and from the document's outlines. */
static void test_candlestick(void **state) {
  (void)state;
  for (int outline = 0; outline < 2; ++outline) {
    int most[3], before[3];
    candlestick(outline, NULL, most);
    candlestick(outline, "one-piece", before);
    print_message("%s: most parts per gap %d, %d, %d (without one-piece %d, %d, %d)\n",
                  outline ? "outlines" : "masks", most[0], most[1], most[2], before[0], before[1],
                  before[2]);
    assert_true(most[0] <= 2);
    assert_true(most[1] <= 2);
    assert_true(most[2] <= 3);
    assert_true(most[2] >= 1);
  }
}

static void make_mask(const slice_def *d, lsm_mask *m) {
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_mask_create(CW, CH, m, &err), LSM_OK);
  paint(d, m);
}

static int allowed_of(const slice_def *a, const slice_def *b, int sx, int sy) {
  lsm_mask ma, mb;
  make_mask(a, &ma);
  make_mask(b, &mb);
  static int32_t label[CW * CH], queue[CW * CH];
  lsm_err err;
  lsm_err_clear(&err);
  int allowed = -1;
  assert_int_equal(lsm_specks_allowed(&ma, &mb, sx, sy, label, queue, &allowed, &err), LSM_OK);
  lsm_mask_free(&ma);
  lsm_mask_free(&mb);
  return allowed;
}

/* Per overlap group the larger count: arms -> candles is one group of 2 and 3
 * (3); two discs apart, one moved off itself, the other in place: a group of
 * 1 and 1, and a part of each slice alone (3); the same moved back by the
 * frame's shift: two groups (2). */
static void test_allowed(void **state) {
  (void)state;
  assert_int_equal(allowed_of(&CANDLESTICK[2], &CANDLESTICK[3], 0, 0), 3);
  assert_int_equal(allowed_of(&CANDLESTICK[0], &CANDLESTICK[1], 0, 0), 2);
  const slice_def a = {2, {{15, 20, 6}, {60, 40, 6}}};
  const slice_def b = {2, {{15, 20, 6}, {80, 40, 6}}};
  assert_int_equal(allowed_of(&a, &b, 0, 0), 3);
  const slice_def b_shifted = {2, {{35, 20, 6}, {80, 40, 6}}};
  assert_int_equal(allowed_of(&a, &b_shifted, 20, 0), 2);
  const slice_def none = {0, {{0, 0, 0}}};
  assert_int_equal(allowed_of(&a, &none, 0, 0), 2);
}

/* Beyond the parts allowed the smallest go (phi changes sign there), the
 * larger stay untouched. */
static void test_drop(void **state) {
  (void)state;
  const slice_def d = {3, {{20, 20, 10}, {60, 20, 2}, {60, 50, 5}}};
  lsm_mask m;
  make_mask(&d, &m);
  float phi[CW * CH];
  for (size_t k = 0; k < (size_t)CW * CH; ++k) phi[k] = m.pixels[k] ? -0.5f : 0.5f;
  phi[20 * CW + 20] = 0.0f; /* a zero in the kept part stays */
  phi[20 * CW + 60] = 0.0f; /* and one in the dropped part leaves 0 */
  static int32_t label[CW * CH], queue[CW * CH];
  lsm_specks s = {2, label, queue};
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_specks_drop(&s, CW, CH, 1.0, phi, &err), LSM_OK);
  for (int y = 0; y < CH; ++y)
    for (int x = 0; x < CW; ++x) {
      const size_t k = (size_t)y * CW + x;
      const int small = (x - 60) * (x - 60) + (y - 20) * (y - 20) <= 4;
      if (small) assert_true(phi[k] > 0.0f);
      else if (m.pixels[k]) assert_true(phi[k] <= 0.0f);
      else assert_true(phi[k] == 0.5f);
    }
  lsm_mask_free(&m);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_allowed),
      cmocka_unit_test(test_drop),
      cmocka_unit_test(test_candlestick),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
