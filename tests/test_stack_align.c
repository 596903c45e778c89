/* The stack driver's alignment and rules (tests/lsm_test_stack.h for the
 * bench): --align of disjoint slices, --align auto where it must leave a pair
 * in place (growth, a small section inside or apart from a large one), parts
 * moving apart (lsm_parts), and rules switched off falling back to what the
 * rules table says. */
#include "tests/lsm_test_stack.h"

/* ------------------------------------------------------------------------ */
/* alignment                                                                 */

/* Disc r = 10 at (25, 50) at z = 0 and the same disc at (75, 50) at z = 7.
 * align hull: both are moved to the centre (identical there: no motion), and
 * slice z is moved back by the linear interpolation of the two shifts, so it is
 * one disc centred at (25 + 50 z / 7, 50) (fractional shifts: bilinear).
 * align none: the discs do not overlap; the morph alone would erode the left
 * disc in place and grow the right one late in the gap (the object absent in
 * the middle, as the blend's zero set of (1 - s) phi_A + s phi_B, whose
 * minimum is 50 s - 10 at the left centre, is empty for 0.2 < s < 0.8), but
 * the two discs are a moving part (lsm_parts) and travel (observed: one
 * component per slice).  test_parts_apart checks that rule; here only the
 * exact endpoints and a clean run are asserted. */
static void test_align(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {disc(25, C, 10)}}, {1, {disc(75, C, 10)}}};
  const double z[2] = {0, 7};
  lsm_stack_opts o;
  run r;
  /* hull, and auto (which must choose hull here: moving A onto B's centroid
   * takes the overlap from 0 to the whole disc). */
  for (int mode = 0; mode < 2; ++mode) {
    default_opts(&o);
    o.motion = LSM_MOTION_NONE; /* --align auto acts with --motion none */
    o.align = mode ? LSM_ALIGN_AUTO : LSM_ALIGN_HULL;
    assert_int_equal(run_stack(&r, W, H, 0, defs, z, 2, &o), LSM_OK);
    assert_int_equal(r.sink.n, 8);
    check_exact_input(&r, 0, 0);
    check_exact_input(&r, 7, 1);
    const size_t a0 = area(r.sink.s[0].phi, W, H);
    double worst = 0;
    for (size_t k = 1; k < 7; ++k) {
      double cx[8], cy[8];
      const float *phi = r.sink.s[k].phi;
      assert_int_equal(components(phi, W, H, 1, 1, 0, cx, cy), 1);
      const double ex = 25.0 + 50.0 * k / 7.0, ey = C;
      const double d = hypot(cx[0] - ex, cy[0] - ey);
      worst = fmax(worst, d);
      if (d > 1.5)
        fail_msg("z = %zu: centroid (%.2f, %.2f), expected (%.2f, %.2f)", k, cx[0], cy[0], ex,
                 ey);
      /* Same disc: the area stays within a perimeter's worth of pixels. */
      const double ak = (double)area(phi, W, H);
      assert_true(fabs(ak - (double)a0) <= 2.0 * PI * 10.0);
    }
    print_message("align %s: worst centroid offset %.3f px\n", lsm_align_name(o.align), worst);
    sink_free(&r.sink);
  }

  o.align = LSM_ALIGN_NONE;
  assert_int_equal(run_stack(&r, W, H, 0, defs, z, 2, &o), LSM_OK);
  assert_int_equal(r.sink.n, 8);
  check_exact_input(&r, 0, 0);
  check_exact_input(&r, 7, 1);
  char text[64] = "";
  for (size_t k = 0; k < 8; ++k) {
    double cx[8], cy[8];
    const int n = components(r.sink.s[k].phi, W, H, 1, 1, 0, cx, cy);
    sprintf(text + strlen(text), " %d", n);
    for (int q = 0; q < n && q < 8; ++q) assert_true(isfinite(cx[q]) && isfinite(cy[q]));
  }
  print_message("align none: components per slice%s\n", text);
  sink_free(&r.sink);
}

/* Runs a two-slice stack (z = 0 and z_b, one output slice per unit) with
 * --align auto, none and hull, and counts the cells of the intermediate slices
 * where auto, and hull, differ from none. */
static void align_modes_differ(const slice_def defs[2], double z_b, size_t *differ_auto,
                               size_t *differ_hull) {
  const double z[2] = {0, z_b};
  const size_t n = (size_t)z_b + 1;
  lsm_stack_opts o;
  run by_mode[3];
  const lsm_align modes[3] = {LSM_ALIGN_AUTO, LSM_ALIGN_NONE, LSM_ALIGN_HULL};
  for (int m = 0; m < 3; ++m) {
    default_opts(&o);
    o.align = modes[m];
    assert_int_equal(run_stack(&by_mode[m], W, H, 0, defs, z, 2, &o), LSM_OK);
    assert_int_equal(by_mode[m].sink.n, n);
  }
  *differ_auto = *differ_hull = 0;
  for (size_t k = 1; k + 1 < n; ++k)
    for (int p = 0; p < W * H; ++p) {
      *differ_auto += by_mode[0].sink.s[k].phi[p] != by_mode[1].sink.s[k].phi[p];
      *differ_hull += by_mode[2].sink.s[k].phi[p] != by_mode[1].sink.s[k].phi[p];
    }
  for (int m = 0; m < 3; ++m) sink_free(&by_mode[m].sink);
}

/* A pair auto must leave unaligned: auto gives exactly --align none's slices,
 * while hull gives others (so the case is one where alignment matters). */
static void assert_auto_leaves_in_place(const char *what, const slice_def defs[2], double z_b) {
  size_t differ_auto, differ_hull;
  align_modes_differ(defs, z_b, &differ_auto, &differ_hull);
  print_message("%s: cells differing from none: auto %zu, hull %zu\n", what, differ_auto,
                differ_hull);
  assert_int_equal(differ_auto, 0);
  assert_true(differ_hull > 0);
}

/* --align auto when a part grows out of a shape that stays: a disc (r = 12)
 * becomes a bar (9 px wide) reaching from it to the right edge.  The hull
 * centroid moves ~35 px right and moving the disc by that much would overlap
 * the bar more than in place (so a centroid-only rule would align), but the
 * translation of largest overlap is only ~8 px (the disc just inside the bar):
 * nothing moved, and auto must morph in place, exactly as --align none. */
static void test_align_auto_growth(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {disc(20, C, 12)}}, {2, {disc(20, C, 4), rect(16, 46, 95, 54, 0)}}};
  assert_auto_leaves_in_place("growth", defs, 6);
}

/* --align auto when a small section meets a large, different one: a disc
 * (r = 6) at x = 30 becomes a disc (r = 22) at x = 72 with a bar (5 px wide)
 * reaching left to x = 28, which covers about half of the small disc in place
 * (a narrow part of an organ or a mesh next to its wide body).  The centroid
 * moves ~38 px; the small disc fits whole only inside the large one, about 20
 * px away, nearer the centroid difference than no shift, so the centroid and
 * registration tests alone would align.  But at that shift the two are not
 * alike (IoU ~0.07: one is a small part of the other), so nothing moved and
 * auto must morph in place, exactly as --align none. */
static void test_align_auto_inside(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {disc(30, C, 6)}}, {2, {disc(72, C, 22), rect(28, 48, 72, 52, 0)}}};
  assert_auto_leaves_in_place("inside", defs, 8);
}

/* --align auto when a small section lies apart from a large, different one:
 * a disc (r = 5) at (18, 18) and, on the next slice, a disc (r = 22) at
 * (66, 66), touching nothing in place (one part of an object ends while
 * another begins).  The centroid moves (48, 48) px and the small disc fits
 * whole inside the large one around that shift, so the centroid and
 * registration tests align, and the two barely touch in place.  But at the
 * best shift they are not alike (IoU ~0.05 < 1/4): nothing moved, and auto
 * must morph in place, exactly as --align none. */
static void test_align_auto_apart_unlike(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {disc(18, 18, 5)}}, {1, {disc(66, 66, 22)}}};
  assert_auto_leaves_in_place("apart, unlike", defs, 8);
}

/* Parts moving apart (lsm_parts): two discs r = 5 at x = 40 and 60 (z = 0)
 * are at x = 20 and 80 at z = 8.  Neither overlaps itself across the gap and
 * the slice's centroid stays, so alignment cannot help; each disc must
 * travel its own straight line (centroid within 1 px of 40 - 2.5 z and
 * 60 + 2.5 z) and keep its area, for ls and pls, cubic and linear.  Blend
 * stays the classic baseline. */
static void test_parts_apart(void **state) {
  (void)state;
  const slice_def defs[2] = {{2, {disc(40, C, 5), disc(60, C, 5)}},
                             {2, {disc(20, C, 5), disc(80, C, 5)}}};
  const double z[2] = {0, 8};
  for (int variant = 0; variant < 3; ++variant) {
    lsm_stack_opts o;
    default_opts(&o);
    o.motion = LSM_MOTION_NONE; /* the moving-parts rule acts with --motion none */
    if (variant == 1) o.interp = LSM_INTERP_LINEAR;
    if (variant == 2) o.method = LSM_METHOD_PLS;
    run r;
    assert_int_equal(run_stack(&r, W, H, 0, defs, z, 2, &o), LSM_OK);
    assert_int_equal(r.sink.n, 9);
    check_exact_input(&r, 0, 0);
    check_exact_input(&r, 8, 1);
    const double a0 = (double)area(r.sink.s[0].phi, W, H);
    double worst = 0.0;
    for (size_t k = 1; k < 8; ++k) {
      double cx[8], cy[8];
      const float *phi = r.sink.s[k].phi;
      const int n = components(phi, W, H, 1, 1, 0, cx, cy);
      if (n != 2) fail_msg("z = %zu: %d components (want 2)", k, n);
      const double left = cx[0] < cx[1] ? cx[0] : cx[1], right = cx[0] < cx[1] ? cx[1] : cx[0];
      const double el = 40.0 - 2.5 * (double)k, er = 60.0 + 2.5 * (double)k;
      worst = fmax(worst, fmax(fabs(left - el), fabs(right - er)));
      worst = fmax(worst, fmax(fabs(cy[0] - C), fabs(cy[1] - C)));
      assert_true(fabs((double)area(phi, W, H) - a0) <= 2.0 * 2.0 * PI * 5.0);
    }
    print_message("parts apart (%s, %s): worst centroid offset %.3f px\n",
                  lsm_method_name(o.method), lsm_interp_name(o.interp), worst);
    assert_true(worst <= 1.0);
    sink_free(&r.sink);
  }
}

/* Rules switched off (lsm_rules.h) fall back to what the table says: moving
 * parts morph in place, the morph's pinholes stay, the canvas margin is
 * background, a moved pair is not aligned.  And with every rule off at once
 * a stack with ends, parts and a merge still runs. */
static void switch_off(lsm_stack_opts *o, const char *names) {
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_rules_switch_off(&o->rules, names, &err), LSM_OK);
}

/* The first gap's statistics of a two-slice stack, with the rule `off`
 * switched off (NULL: the defaults). */
static lsm_pair_stats first_gap(const slice_def defs[2], const char *off) {
  const double z2[2] = {0, 8};
  lsm_stack_opts o;
  default_opts(&o);
  o.motion = LSM_MOTION_NONE; /* the rules below act in place */
  if (off) switch_off(&o, off);
  run r;
  assert_int_equal(run_stack(&r, W, H, 0, defs, z2, 2, &o), LSM_OK);
  sink_free(&r.sink);
  return r.stats[0];
}

static void test_rules_off(void **state) {
  (void)state;
  const double z2[2] = {0, 8};
  lsm_stack_opts o;
  run r;
  /* moving-parts: two discs moving apart */
  const slice_def apart[2] = {{2, {disc(40, C, 5), disc(60, C, 5)}},
                              {2, {disc(20, C, 5), disc(80, C, 5)}}};
  assert_int_equal(first_gap(apart, NULL).moving_parts, 2);
  assert_int_equal(first_gap(apart, "moving-parts").moving_parts, 0);
  /* align-auto: a disc that moved by more than its width */
  const slice_def moved[2] = {{1, {disc(30, C, 10)}}, {1, {disc(70, C, 10)}}};
  assert_int_equal(first_gap(moved, NULL).aligned, 1);
  assert_int_equal(first_gap(moved, "align-auto").aligned, 0);
  /* border-extension: a band across the image lags at its border columns */
  const slice_def band[2] = {{1, {rect(0, 45, W - 1, 55, 0)}}, {1, {rect(0, 40, W - 1, 60, 0)}}};
  default_opts(&o);
  switch_off(&o, "border-extension");
  assert_int_equal(run_stack(&r, W, H, 0, band, z2, 2, &o), LSM_OK);
  int lagging = 0;
  for (int y = 0; y < H; ++y) {
    const float *phi = r.sink.s[4].phi;
    lagging += (phi[y * W] <= 0.0f) != (phi[y * W + W / 2] <= 0.0f);
  }
  assert_true(lagging > 0);
  sink_free(&r.sink);
  /* pinhole-fill: two balls merging (test_merge_no_pinholes) keep holes */
  enum { N = BALLS_N, SIDE = BALLS_SIDE };
  slice_def balls[N];
  double z[N];
  merging_balls(balls, z);
  default_opts(&o);
  switch_off(&o, "pinhole-fill");
  assert_int_equal(run_stack(&r, SIDE, SIDE, 0, balls, z, N, &o), LSM_OK);
  int total = 0;
  for (size_t k = 0; k < r.sink.n; ++k) total += holes(r.sink.s[k].phi, SIDE, SIDE);
  print_message("rules off: pinhole-fill off leaves %d holes\n", total);
  assert_true(total > 0);
  sink_free(&r.sink);
  /* every rule off, for each method */
  for (int m = 0; m < 3; ++m) {
    default_opts(&o);
    o.method = m == 0 ? LSM_METHOD_LS : m == 1 ? LSM_METHOD_PLS : LSM_METHOD_BLEND;
    o.rules.off = ~(uint64_t)0;
    assert_int_equal(run_stack(&r, SIDE, SIDE, 0, balls, z, N, &o), LSM_OK);
    assert_int_equal(r.sink.n, 57);
    sink_free(&r.sink);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_align),
      cmocka_unit_test(test_align_auto_growth),
      cmocka_unit_test(test_align_auto_inside),
      cmocka_unit_test(test_align_auto_apart_unlike),
      cmocka_unit_test(test_parts_apart),
      cmocka_unit_test(test_rules_off),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
