/* The correspondence field (--motion field; solver/motion, solver/recon/lsm_moving):
 * the registration recovers a translation both ways, its exponentials invert each other,
 * identical slices give the zero field and then exactly the plain morph, and a thin
 * ellipse turning 40 degrees per gap is carried across the gap whole where the morph in
 * place lets it shrink.  Per part (rule field-parts, solver/recon/lsm_pairing): a pair is
 * registered only where some part moved off itself, a part appearing beside a still body
 * leaves the run exactly the plain morph's, and a still body beside a tube that jumps past
 * it stays where the morph in place leaves it while the tube is carried.  --motion auto
 * (solver/recon/lsm_choose): the turning ellipse takes the field in every pair, chosen by
 * leaving its slices out; a disc growing in place, or a stack of two, runs as in place. */
#include "tests/lsm_test.h"

#include "solver/base/lsm_grid.h"
#include "solver/motion/lsm_motion.h"
#include "solver/recon/lsm_pairing.h"
#include "solver/recon/lsm_stack.h"
#include "solver/sdf/lsm_sdf.h"

/* An ellipse of half axes r (along angle t, radians) and q (0: a disc of radius r). */
typedef struct disc {
  double cx, cy, r, q, t;
} disc;

/* Paints d into m: over it (or 0) or, with `add`, added to it (r = 0: nothing). */
static void paint_on(const disc *d, int add, lsm_mask *m) {
  const double q = d->q > 0.0 ? d->q : d->r, c = cos(d->t), s = sin(d->t);
  for (int y = 0; y < m->height; ++y)
    for (int x = 0; x < m->width; ++x) {
      const double u = x - d->cx, v = y - d->cy, along = c * u + s * v, across = -s * u + c * v;
      const uint8_t in = d->r > 0.0 && along * along / (d->r * d->r) + across * across / (q * q) <= 1.0;
      uint8_t *p = &m->pixels[(size_t)y * m->width + x];
      *p = add ? (uint8_t)(*p | in) : in;
    }
}

static void paint(const disc *d, lsm_mask *m) { paint_on(d, 0, m); }

static lsm_grid *disc_phi(int w, int h, disc d) {
  lsm_err err;
  lsm_err_clear(&err);
  lsm_mask m;
  assert_int_equal(lsm_mask_create(w, h, &m, &err), LSM_OK);
  paint(&d, &m);
  lsm_grid *g = NULL;
  assert_int_equal(lsm_grid_create(w, h, 1.0f, 1.0f, &g, &err), LSM_OK);
  assert_int_equal(lsm_sdf_from_mask(&m, g, &err), LSM_OK);
  lsm_mask_free(&m);
  return g;
}

static lsm_motion_field *registered(const lsm_grid *a, const lsm_grid *b) {
  lsm_motion_params p;
  lsm_motion_params_default(&p);
  lsm_err err;
  lsm_err_clear(&err);
  lsm_motion_field *f = NULL;
  assert_int_equal(lsm_motion_register(a, b, &p, 2, &f, &err), LSM_OK);
  return f;
}

/* The displacement of exp(t w) at (x, y). */
static void exp_at(const lsm_motion_field *f, double t, float x, float y, float *dx, float *dy) {
  lsm_err err;
  lsm_err_clear(&err);
  lsm_motion_map m, scratch;
  assert_int_equal(lsm_motion_map_create(f, &m, &err), LSM_OK);
  assert_int_equal(lsm_motion_map_create(f, &scratch, &err), LSM_OK);
  lsm_motion_exp(f, t, &m, &scratch, 2);
  lsm_motion_map_at(&m, x, y, dx, dy);
  lsm_motion_map_free(&m);
  lsm_motion_map_free(&scratch);
}

/* A disc (radius 10) moved by (10, 4): exp(w) carries A's centre to B's and exp(-w) back,
 * within a pixel; exp(w/2) carries it half way. */
static void test_translation(void **state) {
  (void)state;
  lsm_grid *a = disc_phi(96, 96, (disc){40, 44, 10, 0, 0}), *b = disc_phi(96, 96, (disc){50, 48, 10, 0, 0});
  lsm_motion_field *f = registered(a, b);
  float dx, dy;
  exp_at(f, 1.0, 40, 44, &dx, &dy);
  print_message("exp(w) at A's centre: (%.2f, %.2f), exp(-w) at B's:", dx, dy);
  assert_close(dx, 10.0, 1.0);
  assert_close(dy, 4.0, 1.0);
  exp_at(f, -1.0, 50, 48, &dx, &dy);
  print_message(" (%.2f, %.2f)\n", dx, dy);
  assert_close(dx, -10.0, 1.0);
  assert_close(dy, -4.0, 1.0);
  exp_at(f, 0.5, 40, 44, &dx, &dy);
  assert_close(dx, 5.0, 1.0);
  assert_close(dy, 2.0, 1.0);
  assert_true(f->iterations > 0);
  assert_close(f->max_displacement, 10.8, 2.0);
  lsm_motion_field_destroy(&f);
  lsm_grid_destroy(&a);
  lsm_grid_destroy(&b);
}

/* exp(-w) after exp(w) is the identity (scaling and squaring of one field), within a
 * quarter pixel over the disc (the maps are bilinear between nodes 2 px apart). */
static void test_inverse(void **state) {
  (void)state;
  lsm_grid *a = disc_phi(96, 96, (disc){40, 44, 10, 0, 0}), *b = disc_phi(96, 96, (disc){52, 40, 8, 0, 0});
  lsm_motion_field *f = registered(a, b);
  lsm_err err;
  lsm_err_clear(&err);
  lsm_motion_map fwd, back, both, scratch;
  assert_int_equal(lsm_motion_map_create(f, &fwd, &err), LSM_OK);
  assert_int_equal(lsm_motion_map_create(f, &back, &err), LSM_OK);
  assert_int_equal(lsm_motion_map_create(f, &both, &err), LSM_OK);
  assert_int_equal(lsm_motion_map_create(f, &scratch, &err), LSM_OK);
  lsm_motion_exp(f, 1.0, &fwd, &scratch, 2);
  lsm_motion_exp(f, -1.0, &back, &scratch, 2);
  lsm_motion_compose(&fwd, &back, &both, 2);
  float most = 0.0f;
  for (int y = 34; y <= 54; y += 2)
    for (int x = 30; x <= 50; x += 2) {
      float dx, dy;
      lsm_motion_map_at(&both, (float)x, (float)y, &dx, &dy);
      most = fmaxf(most, hypotf(dx, dy));
    }
  print_message("|exp(-w) exp(w) - id| at most %.3f px\n", most);
  assert_true(most < 0.25f);
  lsm_motion_map_free(&fwd);
  lsm_motion_map_free(&back);
  lsm_motion_map_free(&both);
  lsm_motion_map_free(&scratch);
  lsm_motion_field_destroy(&f);
  lsm_grid_destroy(&a);
  lsm_grid_destroy(&b);
}

/* ---- whole stacks ---------------------------------------------------------------------- */

enum { SW = 96, SH = 64 };

typedef struct stack_ctx {
  const disc *d;
  const disc *also; /* a second shape per slice, or NULL */
  float *out; /* every output slice */
  double z[64];
  size_t n;
  double max_px; /* the first pair's largest displacement (run.json) */
} stack_ctx;

static lsm_status src_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
  const stack_ctx *c = ctx;
  LSM_TRY(lsm_mask_create(SW, SH, out, err));
  paint(&c->d[index], out);
  if (c->also) paint_on(&c->also[index], 1, out);
  return LSM_OK;
}

static lsm_status sink_emit(void *ctx, const float *phi, int width, int height, double z,
                            long input_index, lsm_err *err) {
  (void)err;
  (void)input_index;
  stack_ctx *c = ctx;
  assert_int_equal(width * height, SW * SH);
  assert_true(c->n < 64);
  memcpy(c->out + c->n * SW * SH, phi, sizeof(float) * SW * SH);
  c->z[c->n++] = z;
  return LSM_OK;
}

/* Runs slices d (and c->also, set by the caller or NULL) with options o on 2 threads; stats
 * (count - 1 of them) gets each pair's. */
static void run_opts(const disc *d, const double *z, size_t count, lsm_stack_opts o, stack_ctx *c,
                     lsm_pair_stats *stats) {
  o.morph.threads = 2;
  c->d = d;
  c->n = 0;
  c->out = malloc(sizeof(float) * SW * SH * 64);
  assert_non_null(c->out);
  lsm_slice_source src = {c, count, z, src_load, NULL};
  lsm_slice_sink sink = {c, sink_emit};
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_stack_run(&src, SW, SH, &o, &sink, stats, NULL, &err), LSM_OK);
  c->max_px = stats[0].motion_max_px;
}

/* Runs slices d (and c->also) with default options but --align none, --motion motion and,
 * with whole, the rule field-parts off. */
static void run_rules(const disc *d, const double *z, size_t count, lsm_motion_mode motion,
                      int whole, stack_ctx *c) {
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  o.align = LSM_ALIGN_NONE;
  o.motion = motion;
  if (whole) o.rules.off |= (uint64_t)1 << LSM_RULE_FIELD_PARTS;
  lsm_pair_stats stats[8];
  run_opts(d, z, count, o, c, stats);
}

static void run(const disc *d, const double *z, size_t count, lsm_motion_mode motion,
                stack_ctx *c) {
  c->also = NULL;
  run_rules(d, z, count, motion, 0, c);
}

/* Two runs gave the same slices, float for float; both freed. */
static void same_and_free(stack_ctx *a, stack_ctx *b) {
  assert_int_equal(a->n, b->n);
  assert_memory_equal(a->out, b->out, sizeof(float) * SW * SH * a->n);
  free(a->out);
  free(b->out);
}

/* Slices that do not move: the field is zero and the output is the plain morph's, float for
 * float. */
static void test_still_is_plain(void **state) {
  (void)state;
  const disc d[3] = {{40, 30, 12, 0, 0}, {40, 30, 12, 0, 0}, {40, 30, 12, 0, 0}};
  const double z[3] = {0, 6, 12};
  stack_ctx field, none;
  run(d, z, 3, LSM_MOTION_FIELD, &field);
  run(d, z, 3, LSM_MOTION_NONE, &none);
  same_and_free(&field, &none);
}

/* Dice of output slice k against shape d. */
static double dice_at(const stack_ctx *c, size_t k, const disc *d) {
  lsm_err err;
  lsm_err_clear(&err);
  lsm_mask m;
  assert_int_equal(lsm_mask_create(SW, SH, &m, &err), LSM_OK);
  paint(d, &m);
  double both = 0.0, sum = 0.0;
  for (size_t p = 0; p < (size_t)SW * SH; ++p) {
    const int in = c->out[k * SW * SH + p] <= 0.0f;
    both += in && m.pixels[p];
    sum += in + m.pixels[p];
  }
  lsm_mask_free(&m);
  return 2.0 * both / sum;
}

/* The inside's area and centroid column of output slice k. */
static double area_at(const stack_ctx *c, size_t k, double *cx) {
  double area = 0.0, sx = 0.0;
  for (int y = 0; y < SH; ++y)
    for (int x = 0; x < SW; ++x)
      if (c->out[k * SW * SH + (size_t)y * SW + x] <= 0.0f) {
        area += 1.0;
        sx += x;
      }
  *cx = area > 0.0 ? sx / area : -1.0;
  return area;
}

/* A thin ellipse (half axes 16 and 3) turning 40 degrees per gap: with the field every
 * slice in the gaps keeps its area within a fifth and the slice at mid-gap matches the
 * ellipse turned 20 degrees (Dice > 0.9), better than in place (none: the moving-parts rule
 * only translates); the field moves the tips (their chord is 2 16 sin(20 deg) = 11 px) by
 * more than the ellipse's width. */
static void test_turning(void **state) {
  (void)state;
  const double deg = 3.14159265358979323846 / 180.0;
  const disc d[3] = {{48, 32, 16, 3, 0.0}, {48, 32, 16, 3, 40 * deg}, {48, 32, 16, 3, 80 * deg}};
  const double z[3] = {0, 8, 16};
  stack_ctx field, none;
  run(d, z, 3, LSM_MOTION_FIELD, &field);
  run(d, z, 3, LSM_MOTION_NONE, &none);
  double cx;
  const double a0 = area_at(&field, 0, &cx);
  double least = a0;
  for (size_t k = 1; k < field.n; ++k) least = fmin(least, area_at(&field, k, &cx));
  const disc mid = {48, 32, 16, 3, 20 * deg};
  const double d_field = dice_at(&field, 4, &mid), d_none = dice_at(&none, 4, &mid);
  print_message("mid-gap Dice: field %.3f, none %.3f; least area %.0f of %.0f; largest "
                "displacement %.1f px\n", d_field, d_none, least, a0, field.max_px);
  assert_true(least > 0.8 * a0);
  assert_true(d_field > 0.9);
  assert_true(d_field > d_none + 0.05);
  assert_true(field.max_px > 6.0);
  assert_true(none.max_px == 0.0);
  free(field.out);
  free(none.out);
}

/* ---- --motion auto (solver/recon/lsm_choose) ------------------------------------------- */

/* Runs slices d with default options but --motion motion; stats gets each pair's. */
static void run_default(const disc *d, const double *z, size_t count, lsm_motion_mode motion,
                        stack_ctx *c, lsm_pair_stats *stats) {
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  o.motion = motion;
  c->also = NULL;
  run_opts(d, z, count, o, c, stats);
}

/* A thin ellipse turning 40 degrees per gap, five slices 8 apart. */
static void turning_ellipse(disc d[5], double z[5]) {
  const double deg = 3.14159265358979323846 / 180.0;
  for (int k = 0; k < 5; ++k) {
    d[k] = (disc){48, 32, 16, 3, 40 * k * deg};
    z[k] = 8 * k;
  }
}

/* The thin ellipse turning 40 degrees per gap over five slices: leaving each inner slice
 * out, the field predicts it better than the morph in place, so every pair takes the field
 * and the run is --motion field's, float for float. */
static void test_auto_turning(void **state) {
  (void)state;
  disc d[5];
  double z[5];
  turning_ellipse(d, z);
  stack_ctx autoc, field;
  lsm_pair_stats sa[4], sf[4];
  run_default(d, z, 5, LSM_MOTION_AUTO, &autoc, sa);
  run_default(d, z, 5, LSM_MOTION_FIELD, &field, sf);
  for (int p = 0; p < 4; ++p) {
    print_message("pair %d: left out %d, missed %lld with the field, %lld in place\n", p,
                  sa[p].motion_tests, sa[p].motion_missed_field, sa[p].motion_missed_in_place);
    assert_int_equal(sa[p].motion_tests, p == 0 || p == 3 ? 1 : 2);
    assert_true(sa[p].motion_missed_field < sa[p].motion_missed_in_place);
    assert_int_equal(sa[p].motion_field, 1);
  }
  same_and_free(&autoc, &field);
}

/* The run's progress hears of each pair auto tries, once, before the pair writes anything:
 * all four pairs of the turning ellipse; none with --motion none. */
typedef struct tried_log {
  int calls, seen[4];
  size_t pairs;
} tried_log;

static void count_update(void *ctx, size_t done, size_t total, size_t pair, size_t pairs) {
  (void)ctx, (void)done, (void)total, (void)pair, (void)pairs;
}

static void count_trying(void *ctx, size_t pair, size_t pairs) {
  tried_log *t = ctx;
#pragma omp critical(test_tried_log)
  {
    t->calls++;
    if (pair < 4) t->seen[pair]++;
    t->pairs = pairs;
  }
}

static void test_auto_tells_progress(void **state) {
  (void)state;
  disc d[5];
  double z[5];
  turning_ellipse(d, z);
  for (int motion = 0; motion < 2; ++motion) {
    tried_log t = {0, {0}, 0};
    const lsm_progress progress = {&t, count_update, count_trying};
    lsm_stack_opts o;
    lsm_stack_opts_default(&o);
    o.motion = motion ? LSM_MOTION_AUTO : LSM_MOTION_NONE;
    o.morph.threads = 2;
    stack_ctx c = {0};
    c.d = d;
    c.out = malloc(sizeof(float) * SW * SH * 64);
    assert_non_null(c.out);
    lsm_slice_source src = {&c, 5, z, src_load, NULL};
    lsm_slice_sink sink = {&c, sink_emit};
    lsm_pair_stats stats[4];
    lsm_err err;
    lsm_err_clear(&err);
    assert_int_equal(lsm_stack_run(&src, SW, SH, &o, &sink, stats, &progress, &err), LSM_OK);
    free(c.out);
    assert_int_equal(t.calls, motion ? 4 : 0);
    for (int p = 0; motion && p < 4; ++p) assert_int_equal(t.seen[p], 1);
    if (motion) assert_int_equal(t.pairs, 4);
  }
}

/* Where no part moved off itself (a disc growing in place) nothing is left out and the run
 * is --motion none's, float for float; a pair with no slice to leave out (a stack of two, a
 * disc jumping past its width) stays in place too. */
static void test_auto_in_place(void **state) {
  (void)state;
  const disc grow[4] = {{40, 30, 8, 0, 0}, {41, 30, 10, 0, 0}, {42, 31, 12, 0, 0},
                        {42, 32, 14, 0, 0}};
  const disc jump[2] = {{20, 30, 6, 0, 0}, {60, 34, 6, 0, 0}};
  const double z[4] = {0, 6, 12, 18};
  for (int t = 0; t < 2; ++t) {
    const disc *d = t ? jump : grow;
    const size_t count = t ? 2 : 4;
    stack_ctx autoc, none;
    lsm_pair_stats sa[3], sn[3];
    run_default(d, z, count, LSM_MOTION_AUTO, &autoc, sa);
    run_default(d, z, count, LSM_MOTION_NONE, &none, sn);
    for (size_t p = 0; p + 1 < count; ++p) {
      assert_int_equal(sa[p].motion_tests, 0);
      assert_int_equal(sa[p].motion_field, 0);
    }
    same_and_free(&autoc, &none);
  }
}

/* Heights 0, 1e-9, 10, 11 (a disc jumping along): predicting slice 2 (at 1e-9) from the
 * others would take output steps of 1e-9, ten billion slices where the run writes twelve
 * (the run failed for memory), so it is not left out; the run goes through. */
static void test_auto_uneven(void **state) {
  (void)state;
  const disc d[4] = {{16, 32, 6, 0, 0}, {36, 32, 6, 0, 0}, {56, 32, 6, 0, 0}, {76, 32, 6, 0, 0}};
  const double z[4] = {0, 1e-9, 10, 11};
  stack_ctx c;
  lsm_pair_stats st[3];
  memset(st, 0, sizeof st);
  run_default(d, z, 4, LSM_MOTION_AUTO, &c, st);
  assert_int_equal(c.n, 12);
  for (int p = 0; p < 3; ++p) assert_true(st[p].motion_tests <= 1);
  free(c.out);
}

/* The default is auto, which keeps --align auto for the pairs it leaves in place; the
 * field, asked for everywhere, is for ls and pls in default mode (--align auto becomes none);
 * blend (the textbook), --per-iteration and --align hull run in place, under auto too. */
static void test_default(void **state) {
  (void)state;
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  assert_int_equal(o.motion, LSM_MOTION_AUTO);
  lsm_stack_opts_resolve(&o);
  assert_int_equal(o.motion, LSM_MOTION_AUTO);
  assert_int_equal(o.align, LSM_ALIGN_AUTO);
  o.motion = LSM_MOTION_NONE;
  lsm_stack_opts_resolve(&o);
  assert_int_equal(o.motion, LSM_MOTION_NONE);
  assert_int_equal(o.align, LSM_ALIGN_AUTO);
  o.motion = LSM_MOTION_FIELD;
  lsm_stack_opts_resolve(&o);
  assert_int_equal(o.motion, LSM_MOTION_FIELD);
  assert_int_equal(o.align, LSM_ALIGN_NONE);
  for (int k = 0; k < 6; ++k) {
    lsm_stack_opts_default(&o);
    o.motion = k < 3 ? LSM_MOTION_FIELD : LSM_MOTION_AUTO;
    if (k % 3 == 0) o.method = LSM_METHOD_BLEND;
    if (k % 3 == 1) o.per_iteration = 1;
    if (k % 3 == 2) o.align = LSM_ALIGN_HULL;
    lsm_stack_opts_resolve(&o);
    assert_int_equal(o.motion, LSM_MOTION_NONE);
    assert_int_equal(o.align, k % 3 == 2 ? LSM_ALIGN_HULL : LSM_ALIGN_AUTO);
  }
}

/* Whether lsm_pairing would register the pair of shapes a (+ a2) and b (+ b2). */
static int pairing_needs(const disc *a, const disc *a2, const disc *b, const disc *b2) {
  lsm_err err;
  lsm_err_clear(&err);
  lsm_mask ma, mb;
  assert_int_equal(lsm_mask_create(SW, SH, &ma, &err), LSM_OK);
  assert_int_equal(lsm_mask_create(SW, SH, &mb, &err), LSM_OK);
  paint(a, &ma);
  paint(b, &mb);
  if (a2) paint_on(a2, 1, &ma);
  if (b2) paint_on(b2, 1, &mb);
  lsm_grid *pa = NULL, *pb = NULL;
  assert_int_equal(lsm_grid_create(SW, SH, 1.0f, 1.0f, &pa, &err), LSM_OK);
  assert_int_equal(lsm_grid_create(SW, SH, 1.0f, 1.0f, &pb, &err), LSM_OK);
  assert_int_equal(lsm_sdf_from_mask(&ma, pa, &err), LSM_OK);
  assert_int_equal(lsm_sdf_from_mask(&mb, pb, &err), LSM_OK);
  lsm_pairing *p = NULL;
  int needs = -1;
  assert_int_equal(lsm_pairing_create(&ma, &mb, pa, pb, 0, &p, &needs, &err), LSM_OK);
  lsm_pairing_destroy(&p);
  lsm_grid_destroy(&pa);
  lsm_grid_destroy(&pb);
  lsm_mask_free(&ma);
  lsm_mask_free(&mb);
  return needs;
}

/* The test in place: a disc (radius 10) moved by 4 px (under half its radius) or growing
 * in place, or a part appearing beside it, needs no field; moved by 8 px, or a part
 * vanishing on one side while another appears on the other, does. */
static void test_pairing_needs(void **state) {
  (void)state;
  const disc at = {40, 32, 10, 0, 0}, near = {44, 32, 10, 0, 0}, far = {48, 32, 10, 0, 0};
  const disc grown = {40, 32, 16, 0, 0}, left = {12, 12, 4, 0, 0}, right = {80, 50, 4, 0, 0};
  assert_int_equal(pairing_needs(&at, NULL, &near, NULL), 0);
  assert_int_equal(pairing_needs(&at, NULL, &grown, NULL), 0);
  assert_int_equal(pairing_needs(&at, NULL, &at, &right), 0);
  assert_int_equal(pairing_needs(&at, &left, &at, NULL), 0);
  assert_int_equal(pairing_needs(&at, NULL, &far, NULL), 1);
  assert_int_equal(pairing_needs(&at, &left, &at, &right), 1);
}

/* A part appearing beside a still body: nothing is registered and the run is the plain
 * morph's, float for float. */
static void test_appearing_is_plain(void **state) {
  (void)state;
  const disc body[3] = {{30, 32, 14, 0, 0}, {30, 32, 14, 0, 0}, {30, 32, 14, 0, 0}};
  const disc lobe[3] = {{0, 0, 0, 0, 0}, {70, 30, 6, 0, 0}, {71, 31, 7, 0, 0}};
  const double z[3] = {0, 8, 16};
  stack_ctx field = {.also = lobe}, none = {.also = lobe};
  run_rules(body, z, 3, LSM_MOTION_FIELD, 0, &field);
  run_rules(body, z, 3, LSM_MOTION_NONE, 0, &none);
  assert_true(field.max_px == 0.0);
  same_and_free(&field, &none);
}

/* A still body (radius 14) and a tube (radius 4) jumping 12 px per gap past it: the tube
 * takes the field (carried whole: at mid-gap its area is within a fifth of the disc's),
 * the body stays in place: within 8 px of it every output cell has the sign the run with
 * no field gives it, but for a hundredth of the body's area. */
static void test_still_beside_moving(void **state) {
  (void)state;
  const disc body[3] = {{22, 32, 14, 0, 0}, {22, 32, 14, 0, 0}, {22, 32, 14, 0, 0}};
  const disc tube[3] = {{56, 32, 4, 0, 0}, {68, 32, 4, 0, 0}, {80, 32, 4, 0, 0}};
  const double z[3] = {0, 8, 16};
  stack_ctx field = {.also = tube}, none = {.also = tube};
  run_rules(body, z, 3, LSM_MOTION_FIELD, 0, &field);
  run_rules(body, z, 3, LSM_MOTION_NONE, 0, &none);
  assert_int_equal(field.n, none.n);
  double tube_area = 0.0, differ = 0.0;
  for (int y = 0; y < SH; ++y)
    for (int x = 0; x < SW; ++x) {
      const size_t k = 3 * (size_t)SW * SH + (size_t)y * SW + x; /* mid-gap of the first gap */
      if (x >= 48) tube_area += field.out[k] <= 0.0f;
      for (size_t q = 0; q < field.n && hypot(x - 22.0, y - 32.0) < 14.0 + 8.0; ++q) {
        const size_t c = q * SW * SH + (size_t)y * SW + x;
        differ += (field.out[c] <= 0.0f) != (none.out[c] <= 0.0f);
      }
    }
  const double disc_area = 3.14159265358979 * 16.0, body_area = 3.14159265358979 * 196.0;
  print_message("mid-gap tube area %.0f (disc %.0f); body cells that differ from in place: "
                "%.0f over %zu slices; largest displacement %.1f px\n", tube_area, disc_area,
                differ, field.n, field.max_px);
  assert_true(field.max_px > 6.0);
  assert_true(fabs(tube_area - disc_area) < 0.2 * disc_area);
  assert_true(differ <= 0.01 * body_area * (double)field.n);
  free(field.out);
  free(none.out);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_translation),
      cmocka_unit_test(test_inverse),
      cmocka_unit_test(test_still_is_plain),
      cmocka_unit_test(test_turning),
      cmocka_unit_test(test_default),
      cmocka_unit_test(test_auto_turning),
      cmocka_unit_test(test_auto_tells_progress),
      cmocka_unit_test(test_auto_in_place),
      cmocka_unit_test(test_auto_uneven),
      cmocka_unit_test(test_pairing_needs),
      cmocka_unit_test(test_appearing_is_plain),
      cmocka_unit_test(test_still_beside_moving),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
