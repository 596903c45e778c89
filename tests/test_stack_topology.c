/* The stack driver's topology (tests/lsm_test_stack.h for the bench): discs
 * that merge and split, the parts of a last section ending each its own way,
 * an end that moves on, thin features of the outside (notches, pinholes, a
 * band across the image border), merging balls without pinholes, a branch
 * that recedes, and shapes that vanish and appear next to empty slices. */
#include "tests/lsm_test_stack.h"

/* ------------------------------------------------------------------------ */
/* topology                                                                  */

/* Two discs merge into one.  A: discs r = 6 at x = 32, 68 (a 24 px gap: the
 * neck point (50, 50) is 12 px outside A); B: one disc r = 25 at the centre,
 * covering both (the neck is 25 px deep inside it).  While phi relaxes like
 * a distance function, phi(s) at the neck ~ (1 - s) 12 + s (-25) (exact for
 * the blend), so the neck closes near s = 12/37 = 0.32: at z = 1 (s = 0.1)
 * there are 2 components (phi ~ +8 there), at z = 9 one (phi ~ -21).  The
 * count never goes back up.  Split is the same pair in reverse order. */
static void test_merge_split(void **state) {
  (void)state;
  const slice_def two = {2, {disc(32, C, 6), disc(68, C, 6)}};
  const slice_def one = {1, {disc(C, C, 25)}};
  const double z[2] = {0, 10};
  int c[16];
  char text[32];
  for (int method = 0; method < 2; ++method) {
    lsm_stack_opts o;
    default_opts(&o);
    o.method = method ? LSM_METHOD_BLEND : LSM_METHOD_LS;
    const slice_def merge[2] = {two, one}, split[2] = {one, two};
    run r;
    assert_int_equal(run_stack(&r, W, H, 0, merge, z, 2, &o), LSM_OK);
    assert_int_equal(r.sink.n, 11);
    counts(&r, c, text);
    print_message("merge (%s): components %s\n", lsm_method_name(o.method), text);
    assert_int_equal(c[0], 2);
    assert_int_equal(c[1], 2);
    assert_int_equal(c[9], 1);
    assert_int_equal(c[10], 1);
    for (int k = 1; k <= 10; ++k) {
      assert_true(c[k] == 1 || c[k] == 2);
      assert_true(c[k] <= c[k - 1]);
    }
    /* The area grows monotonically from two small discs to the big one. */
    for (int k = 1; k <= 10; ++k)
      assert_true(area(r.sink.s[k].phi, W, H) >= area(r.sink.s[k - 1].phi, W, H));
    sink_free(&r.sink);

    assert_int_equal(run_stack(&r, W, H, 0, split, z, 2, &o), LSM_OK);
    counts(&r, c, text);
    print_message("split (%s): components %s\n", lsm_method_name(o.method), text);
    assert_int_equal(c[0], 1);
    assert_int_equal(c[1], 1);
    assert_int_equal(c[9], 2);
    assert_int_equal(c[10], 2);
    for (int k = 1; k <= 10; ++k) {
      assert_true(c[k] == 1 || c[k] == 2);
      assert_true(c[k] >= c[k - 1]);
    }
    for (int k = 1; k <= 10; ++k)
      assert_true(area(r.sink.s[k].phi, W, H) <= area(r.sink.s[k - 1].phi, W, H));
    sink_free(&r.sink);
  }
}

/* Where an object ends, each part of its last section ends its own way.  At
 * z = 8: a disc r = 10 at x = 30 that narrows (at z = 16 it is r = sqrt(300),
 * so the line through its two areas reaches 0 at z = 4), and a disc r = 8 at
 * x = 75 that nothing at z = 16 continues (a lone part: a flat end); z = 0 is
 * empty.  Cubic profile (the default): the lone disc stays whole up to
 * mid-gap (z = 5, 6, 7), the narrowing one follows its own area line.  One
 * area line for the whole section (the rule before) took the narrowing of
 * the left disc for the whole section, and the right one lost its cells. */
static void test_end_parts(void **state) {
  (void)state;
  const slice_def defs[3] = {{0, {{0}}},
                             {2, {disc(30, C, 10), disc(75, C, 8)}},
                             {1, {disc(30, C, sqrt(300.0))}}};
  const double z[3] = {0, 8, 16};
  lsm_stack_opts o;
  default_opts(&o);
  run r;
  assert_int_equal(run_stack(&r, W, H, 0, defs, z, 3, &o), LSM_OK);
  assert_int_equal(r.sink.n, 17);
  size_t left[17], right[17];
  for (int k = 0; k <= 16; ++k) {
    left[k] = right[k] = 0;
    for (int p = 0; p < W * H; ++p)
      if (r.sink.s[k].phi[p] <= 0.0f) ++*(p % W < 52 ? &left[k] : &right[k]);
  }
  print_message("end parts: left (narrowing) at z = 4..8: %zu %zu %zu %zu %zu; right (lone): %zu %zu %zu %zu %zu\n",
                left[4], left[5], left[6], left[7], left[8], right[4], right[5], right[6], right[7], right[8]);
  assert_int_equal(right[16], 0);
  for (int k = 5; k <= 7; ++k) {
    assert_int_equal(right[k], right[8]);
    const double line = (double)left[8] - (8.0 - k) * ((double)left[16] - (double)left[8]) / 8.0;
    assert_true((double)left[k] <= line && (double)left[k] >= 0.85 * line - 4.0);
  }
  /* past the left disc's line (z = 4) a tenth of its cone tip is left; the
   * lone disc's tip, a cone's, A_F (3 / 4)^2 at z = 3, is far larger */
  const double tenth = 0.1 * (double)left[8] * pow(3.0 / 4.0, 2.0);
  assert_true(left[3] >= 1 && fabs((double)left[3] - tenth) <= 8.0);
  const double cone = (double)right[8] * pow(3.0 / 4.0, 2.0);
  assert_true((double)right[3] <= cone && (double)right[3] >= 0.85 * cone - 4.0);
  assert_true((double)right[3] > 2.0 * tenth);
  sink_free(&r.sink);
}

/* ------------------------------------------------------------------------ */
/* an end that moves on                                                      */

/* A disc drifting 2 px per unit z (an oblique vessel) and ending in the last
 * gap: with --align auto the end keeps moving along the drift, and run.json's
 * "aligned" says so for that gap as for the others. */
static void test_end_moves_on(void **state) {
  (void)state;
  const slice_def defs[5] = {{1, {disc(20, C, 5)}}, {1, {disc(36, C, 5)}}, {1, {disc(52, C, 5)}},
                             {1, {disc(68, C, 5)}}, {0, {{0}}}};
  const double z[5] = {0, 8, 16, 24, 32};
  lsm_stack_opts o;
  default_opts(&o);
  o.motion = LSM_MOTION_NONE; /* --align auto's rules act with --motion none */
  run r;
  assert_int_equal(run_stack(&r, W, H, 0, defs, z, 5, &o), LSM_OK);
  assert_int_equal(r.sink.n, 33);
  for (int k = 0; k < 4; ++k)
    if (!r.stats[k].aligned) fail_msg("gap %d: aligned = 0", k + 1);
  double cx[8], cy[8];
  assert_int_equal(components(r.sink.s[27].phi, W, H, 1, 1, 0, cx, cy), 1);
  print_message("end moves on: centroid at z = 27: %.1f (the last section's 68, the drift's 74)\n",
                cx[0]);
  assert_true(fabs(cx[0] - 74.0) <= 1.0);
  sink_free(&r.sink);
}

/* ------------------------------------------------------------------------ */
/* thin features of the outside move like those of the inside                */

/* The last inside pixel's column along row y, from x_from rightward (-1: none). */
static int last_inside(const float *phi, int w, int y, int x_from) {
  int last = -1;
  for (int x = x_from; x < w; ++x)
    if (phi[(size_t)y * w + x] <= 0.0f) last = x;
  return last;
}

/* The morph equation is unchanged under phi -> -phi, so a notch 3 px wide
 * cut into a disc that deepens from 4 to 20 px (a sulcus) should open as
 * fast as a bar 3 px wide on a disc lengthens from 4 to 20 px.  The
 * two-sided join was made for the bar (the union of the two insides); at
 * cells less than two cells outside one slice and deeper inside the other it
 * joins the outsides instead, and the notch keeps up with the bar. */
static void test_thin_outside(void **state) {
  (void)state;
  const double z[2] = {0.0, 8.0};
  /* notch: disc centre (40, 50), r 30 (right edge at x = 70), cut by the
   * strict inside of a rect (rows 49..51) from x = 67 or 51 outward */
  const slice_def notch[2] = {{2, {disc(40, 50, 30), rect(66, 48, 100, 52, 1)}},
                              {2, {disc(40, 50, 30), rect(50, 48, 100, 52, 1)}}};
  /* bar: disc centre (40, 50), r 20, rows 49..51 from x = 40 to 64 or 80 */
  const slice_def bar[2] = {{2, {disc(40, 50, 20), rect(40, 49, 64, 51, 0)}},
                            {2, {disc(40, 50, 20), rect(40, 49, 80, 51, 0)}}};
  lsm_stack_opts o;
  default_opts(&o);
  o.dz = 1.0;
  run rn, rb;
  assert_int_equal(run_stack(&rn, W, H, 0, notch, z, 2, &o), LSM_OK);
  assert_int_equal(run_stack(&rb, W, H, 0, bar, z, 2, &o), LSM_OK);
  for (size_t k = 1; k < 8; ++k) {
    const int depth = 70 - last_inside(rn.sink.s[k].phi, W, 50, 40);
    const int length = last_inside(rb.sink.s[k].phi, W, 50, 40) - 60;
    print_message("z %zu: notch depth %d px, bar length %d px (both 4 -> 20)\n", k, depth, length);
    if (k >= 5) assert_true(depth >= length);
  }
  sink_free(&rn.sink);
  sink_free(&rb.sink);
}

/* A pinhole: an oblique sulcus cuts each section as a hole of a pixel or two
 * that moves from slice to slice.  Here a 2x2 hole inside a disc moves 2 px
 * every 2 units of z (x = 38..39, 40..41, 42..43, 44..45 at z = 0, 2, 4, 6;
 * rows 50..51), so half-way between two slices (z = 1, 3, 5) the truth's
 * hole is the 2x2 cells at x = 39..40, 41..42, 43..44: cells where the two
 * slices tie (+1/2 outside one, -1/2 inside the other).  The morph of so
 * small a hole is numerical diffusion; the union of the two insides left 2
 * of the 4 cells at z = 1 and 5.  At a pinhole's cells the profile is the
 * monotone cubic of the signed distances, which follows the hole. */
/* The image border is not the object's boundary: a band across the whole
 * image, 11 rows thick and then 21, is the same in every column of every
 * output slice, its two border columns included (a margin of background
 * around the image made them lag: 11 -> 13 rows where the band was 17 rows
 * thick inside).  For ls and blend. */
static void test_border_band(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {rect(0, 45, W - 1, 55, 0)}}, {1, {rect(0, 40, W - 1, 60, 0)}}};
  const double z[2] = {0, 8};
  for (int method = 0; method < 2; ++method) {
    lsm_stack_opts o;
    default_opts(&o);
    o.method = method ? LSM_METHOD_BLEND : LSM_METHOD_LS;
    run r;
    assert_int_equal(run_stack(&r, W, H, 0, defs, z, 2, &o), LSM_OK);
    assert_int_equal(r.sink.n, 9);
    for (size_t k = 0; k < r.sink.n; ++k) {
      const float *phi = r.sink.s[k].phi;
      int rows = 0;
      for (int y = 0; y < H; ++y) {
        const float middle = phi[y * W + W / 2];
        rows += middle <= 0.0f;
        for (int x = 0; x < W; ++x)
          if (fabsf(phi[y * W + x] - middle) > 1e-5f)
            fail_msg("%s slice %zu: phi(%d, %d) = %g, %g in the middle column",
                     method ? "blend" : "ls", k, x, y, phi[y * W + x], middle);
      }
      print_message("%s z = %g: %d rows\n", method ? "blend" : "ls", r.sink.s[k].z, rows);
      assert_true(rows >= 11 && rows <= 21);
    }
    sink_free(&r.sink);
  }
}

static void test_pinhole(void **state) {
  (void)state;
  const double z[4] = {0.0, 2.0, 4.0, 6.0};
  slice_def defs[4]; /* holes cut by the strict insides of the rects */
  for (int k = 0; k < 4; ++k) {
    defs[k].n = 2;
    defs[k].s[0] = disc(C, C, 30);
    defs[k].s[1] = rect(37 + 2 * k, 49, 40 + 2 * k, 52, 1);
  }
  lsm_stack_opts o;
  default_opts(&o);
  o.dz = 1.0;
  for (int m = 0; m < 2; ++m) {
    o.method = m ? LSM_METHOD_PLS : LSM_METHOD_LS;
    run r;
    assert_int_equal(run_stack(&r, W, H, 0, defs, z, 4, &o), LSM_OK);
    assert_int_equal(r.sink.n, 7);
    for (int k = 1; k <= 5; k += 2) {
      const float *mid = r.sink.s[k].phi;
      const int x0 = 38 + k; /* the truth's hole: x0, x0 + 1; rows 50, 51 */
      size_t outside = 0, misplaced = 0;
      for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
          if ((i - C) * (i - C) + (j - C) * (j - C) <= 25.0 * 25.0 && mid[(size_t)j * W + i] > 0.0f) {
            ++outside;
            misplaced += !(i >= x0 && i <= x0 + 1 && j >= 50 && j <= 51);
          }
      print_message("pinhole (%s) z = %d: %zu outside cells, %zu of them off the truth's hole\n",
                    lsm_method_name(o.method), k, outside, misplaced);
      assert_int_equal(outside, 4);
      assert_int_equal(misplaced, 0);
    }
    sink_free(&r.sink);
  }
}

/* Two balls of radius 20 (centres (46, 63.5, 26) and (82, 63.5, 40)) cut
 * every 8th unit: their sections merge between z = 24 and z = 32 and split
 * again between 32 and 40.  The outside between them (a ridge of phi in the
 * morph) sank below zero unevenly and left holes of one or two pixels on
 * the neck (6 in all, at z = 27, 36 and 37); no section has a hole and
 * neither has the truth.  Every output slice must be free of holes. */

static void test_merge_no_pinholes(void **state) {
  (void)state;
  enum { N = BALLS_N, SIDE = BALLS_SIDE };
  slice_def defs[N];
  double z[N];
  merging_balls(defs, z);
  for (int m = 0; m < 2; ++m) {
    lsm_stack_opts o;
    default_opts(&o);
    o.interp = m ? LSM_INTERP_LINEAR : LSM_INTERP_CUBIC;
    run r;
    assert_int_equal(run_stack(&r, SIDE, SIDE, 0, defs, z, N, &o), LSM_OK);
    assert_int_equal(r.sink.n, 57);
    int total = 0;
    size_t beyond = 0;
    for (size_t k = 0; k < r.sink.n; ++k) {
      const int h = holes(r.sink.s[k].phi, SIDE, SIDE);
      if (h) print_message("merge (%s): %d holes at z = %g\n", lsm_interp_name(o.interp), h, r.sink.s[k].z);
      total += h;
      /* and the filled cells, as every other, within the range of the
       * slices around them (gaps between two non-empty slices) */
      const size_t below = k - k % 8, above = below + 8;
      if (k % 8 == 0 || defs[below / 8].n == 0 || defs[above / 8].n == 0) continue;
      const float *pa = r.sink.s[below].phi, *pb = r.sink.s[above].phi, *p = r.sink.s[k].phi;
      for (int c = 0; c < SIDE * SIDE; ++c)
        beyond += p[c] < fminf(pa[c], pb[c]) - 1e-4f || p[c] > fmaxf(pa[c], pb[c]) + 1e-4f;
    }
    assert_int_equal(total, 0);
    assert_int_equal(beyond, 0);
    sink_free(&r.sink);
  }
}

/* Inside cells with x >= x0 (the right-hand piece below). */
static size_t area_right_of(const float *phi, int w, int h, int x0) {
  size_t n = 0;
  for (int j = 0; j < h; ++j)
    for (int i = x0; i < w; ++i) n += phi[(size_t)j * w + i] <= 0.0f;
  return n;
}

/* A small piece of A (r 4 at x = 86) that B (z = 20) does not continue, next
 * to a body (r 15, then 10, at the centre) that goes on.  Where the slice
 * before A (z = 0) joins it to that body (a bar from the body to it), it is a
 * branch splitting off the body: it recedes toward the body's section on B
 * and is gone by z = 13.  Where it is its own piece at z = 0 too, it is an
 * object ending in the gap (the halfway rule): still there at z = 13. */
static void test_branch_recedes(void **state) {
  (void)state;
  const double z[3] = {0.0, 10.0, 20.0};
  const slice_def a = {2, {disc(C, C, 15), disc(86, C, 4)}}, b = {1, {disc(C, C, 10)}};
  const slice_def joined = {3, {disc(C, C, 20), rect(60, 46, 92, 54, 0), disc(86, C, 6)}};
  const slice_def apart = {2, {disc(C, C, 20), disc(86, C, 5)}};
  lsm_stack_opts o;
  default_opts(&o);
  o.dz = 1.0;
  for (int branch = 0; branch < 2; ++branch) {
    const slice_def defs[3] = {branch ? joined : apart, a, b};
    run r;
    assert_int_equal(run_stack(&r, W, H, 0, defs, z, 3, &o), LSM_OK);
    assert_int_equal(r.sink.n, 21);
    size_t piece[21];
    for (int k = 0; k <= 20; ++k) piece[k] = area_right_of(r.sink.s[k].phi, W, H, 78);
    print_message("%s: piece areas z = 10..20: %zu %zu %zu %zu %zu %zu %zu %zu %zu %zu %zu\n",
                  branch ? "branch" : "own piece", piece[10], piece[11], piece[12], piece[13], piece[14],
                  piece[15], piece[16], piece[17], piece[18], piece[19], piece[20]);
    assert_true(piece[10] > 40);
    if (branch) assert_int_equal(piece[13], 0);
    else assert_true(piece[13] > 0);
    for (int k = 18; k <= 20; ++k) assert_int_equal(piece[k], 0);
    sink_free(&r.sink);
  }
}

/* A disc next to an empty slice, with no slice beyond it (a lone section).
 * Linear profile: the object closes by mid-gap.  Vanishing (disc at z = 0,
 * empty at z = 10): areas strictly decrease while non-empty, the last
 * non-empty slice is at z <= 5, and the disc is still there just after the
 * input (z = 1).  Cubic profile: nothing tells how a lone section ends, so it
 * is a flat end: whole up to mid-gap, then a cone's tip to the empty slice,
 * A_F (2 (1 - z / 10))^2, non-empty up to z = 9.  Appearing
 * (the reverse): the mirror image. */
static void test_vanish_appear(void **state) {
  (void)state;
  const slice_def full = {1, {disc(C, C, 15)}}, none = {0, {{0}}};
  const double z[2] = {0, 10};
  for (int variant = 0; variant < 4; ++variant) {
    lsm_stack_opts o;
    default_opts(&o);
    o.method = variant & 1 ? LSM_METHOD_BLEND : LSM_METHOD_LS;
    if (variant & 2) o.interp = LSM_INTERP_LINEAR;
    const slice_def vanish[2] = {full, none}, appear[2] = {none, full};
    run r;
    size_t a[11];
    assert_int_equal(run_stack(&r, W, H, 0, vanish, z, 2, &o), LSM_OK);
    assert_int_equal(r.sink.n, 11);
    check_exact_input(&r, 0, 0);
    int last = -1;
    for (int k = 0; k <= 10; ++k) {
      a[k] = area(r.sink.s[k].phi, W, H);
      if (a[k]) last = k;
    }
    print_message("vanish (%s, %s): areas %zu %zu %zu %zu %zu %zu ...\n",
                  lsm_method_name(o.method), lsm_interp_name(o.interp), a[0], a[1], a[2], a[3],
                  a[4], a[5]);
    const int cubic = o.interp == LSM_INTERP_CUBIC;
    if (cubic) {
      assert_int_equal(last, 9);
      for (int k = 1; k <= 5; ++k) assert_int_equal(a[k], a[0]);
      for (int k = 6; k <= 9; ++k) {
        const double tip = (double)a[0] * pow(2.0 * (1.0 - k / 10.0), 2.0);
        assert_true(a[k] < a[k - 1] && (double)a[k] <= tip && (double)a[k] >= 0.85 * tip - 4.0);
      }
    } else {
      assert_true(last >= 1 && last <= 5);
      for (int k = 1; k <= last; ++k) assert_true(a[k] < a[k - 1]);
    }
    for (int k = last + 1; k <= 10; ++k) assert_int_equal(a[k], 0);
    /* The empty input slice: everything outside. */
    assert_int_equal(r.sink.s[10].input_index, 1);
    for (int p = 0; p < W * H; ++p) assert_true(r.sink.s[10].phi[p] > 0.0f);
    /* What remains stays one disc around the centre. */
    for (int k = 1; k <= last; ++k) assert_int_equal(fg_components(r.sink.s[k].phi, W, H), 1);
    sink_free(&r.sink);

    assert_int_equal(run_stack(&r, W, H, 0, appear, z, 2, &o), LSM_OK);
    assert_int_equal(r.sink.n, 11);
    check_exact_input(&r, 10, 1);
    int first = 11;
    for (int k = 10; k >= 0; --k) {
      a[k] = area(r.sink.s[k].phi, W, H);
      if (a[k]) first = k;
    }
    print_message("appear (%s, %s): first non-empty z = %d\n", lsm_method_name(o.method),
                  lsm_interp_name(o.interp), first);
    if (cubic) {
      assert_int_equal(first, 1);
      for (int k = 1; k <= 4; ++k) assert_true(a[k] > 0 && a[k] < a[k + 1]);
      for (int k = 5; k <= 10; ++k) assert_int_equal(a[k], a[10]);
    } else {
      assert_true(first >= 5 && first <= 9);
      for (int k = first + 1; k <= 10; ++k) assert_true(a[k] > a[k - 1]);
    }
    for (int k = 0; k < first; ++k) assert_int_equal(a[k], 0);
    sink_free(&r.sink);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_merge_split),
      cmocka_unit_test(test_thin_outside),
      cmocka_unit_test(test_pinhole),
      cmocka_unit_test(test_merge_no_pinholes),
      cmocka_unit_test(test_border_band),
      cmocka_unit_test(test_end_moves_on),
      cmocka_unit_test(test_branch_recedes),
      cmocka_unit_test(test_end_parts),
      cmocka_unit_test(test_vanish_appear),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
