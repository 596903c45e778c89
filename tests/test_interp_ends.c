/* Tests of the z-profile where the object ends: the slope at a last section
 * beside an end (a ball cut beside its ends, an object of two sections, next
 * to an empty slice), and where an object ends between slices with default
 * options and with --ends.  Slices come from an in-memory source; output
 * slices are recorded by an in-memory sink (tests/lsm_test_interp.h). */
#include "tests/lsm_test_interp.h"

/* The interior side of a last section (the object ends in the gap beyond
 * it) takes the three-point slope, as at the first input slice: a rounded
 * solid's radius profile is curved there, and the gap's secant (the rule
 * before) drew the sections between too small.  A ball of radius 25 centred
 * at z = 30, cut every 16 units with empty slices at z = 0 and 64 (sections
 * of radius 20.7, 24.9 and 17.3): the section halfway through each interior
 * gap, z = 24 and 40, has the ball's radius (24.3 and 22.9) within 0.5 px
 * with ls and blend; with the secant it was about 1 px small at z = 24. */
/* Radius of a ball of radius R centred at z = centre at height z (0 outside it). */
static double ball_radius(double R, double centre, double z) {
  const double h = z - centre;
  return R * R - h * h > 0 ? sqrt(R * R - h * h) : 0.0;
}

/* A ball of radius R centred at z = centre cut every 16 units from z = 0 (n
 * sections), run with ls (method 0) or blend (1) at dz = 1 into rec. */
static void run_cut_ball(double R, double centre, size_t n, int size, int method, record *rec) {
  double z[8], radius[8];
  assert_true(n <= 8);
  for (size_t k = 0; k < n; ++k) {
    z[k] = 16.0 * (double)k;
    radius[k] = ball_radius(R, centre, z[k]);
  }
  disc_source src = {size, radius, NULL};
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  o.method = method ? LSM_METHOD_BLEND : LSM_METHOD_LS;
  o.dz = 1.0;
  run_stack(&src, z, n, &o, rec);
}

/* The radius of the disc with the area of the output slice at height z. */
static double radius_at(const record *rec, double z) {
  return sqrt((double)slice_inside(rec, slice_at(rec, z), NULL) / acos(-1.0));
}

static void test_ball_beside_ends(void **state) {
  (void)state;
  for (int method = 0; method < 2; ++method) {
    record rec = {0};
    run_cut_ball(25.0, 30.0, 5, 80, method, &rec);
    const double at[2] = {24.0, 40.0};
    for (int k = 0; k < 2; ++k) {
      const double r = radius_at(&rec, at[k]), truth = ball_radius(25.0, 30.0, at[k]);
      print_message("%s, z = %g: radius %.2f, the ball's %.2f\n", method ? "blend" : "ls", at[k], r,
                    truth);
      assert_true(fabs(r - truth) < 0.5);
    }
    record_free(&rec);
  }
}

/* An object with two sections, each a last section: the slope at the
 * smaller one takes the three-point slope through the empty slice beyond the
 * larger one, counted as that section eroded by its largest depth (as at the
 * first or last input slice).  A ball of radius 20 centred at z = 26, cut
 * every 16 units (empty at z = 0 and 48, radii 17.3 and 19.1 at 16 and 32):
 * halfway, at z = 24, the ball's radius is 19.9, above both sections (its
 * equator lies between them), which no monotone profile passes; the
 * section there has an area-equivalent radius of 19.1 with ls and blend (18.3
 * with the secant, the slope when there was no third section). */
static void test_two_sections(void **state) {
  (void)state;
  for (int method = 0; method < 2; ++method) {
    record rec = {0};
    run_cut_ball(20.0, 26.0, 4, 64, method, &rec);
    const double r = radius_at(&rec, 24.0);
    print_message("%s, z = 24: radius %.2f (sections 17.32 and 19.08, the ball's 19.90)\n",
                  method ? "blend" : "ls", r);
    assert_true(r > 18.7 && r < 19.9);
    record_free(&rec);
  }
}

/* Next to an empty slice the slope at the last section is the one the end
 * gap continues with: 0 where the section grows toward the end.  Radii 20 at
 * z = 8 and 16 at z = 16 (the widest part between them, the object ending
 * below z = 8): the section just past z = 8 keeps its area (the secant would
 * shrink it straight toward z = 16, about 5 % of the area by z = 9).  The
 * same stack upside down (the empty slice above) gives the same areas at
 * every distance from F: the rule is symmetric in z. */
static void test_end_neighbour_flat(void **state) {
  (void)state;
  const double z[3] = {0.0, 8.0, 16.0}, radius[3] = {0.0, 20.0, 16.0};
  const double mirrored[3] = {16.0, 20.0, 0.0}; /* the same with the empty slice above */
  size_t areas[2][2][9]; /* [up][method][units from F]: the rule is symmetric in z */
  for (int up = 0; up < 2; ++up) {
    disc_source src = {96, up ? mirrored : radius, NULL};
    /* heights from the full section toward the narrower one */
    const double zf = 8.0, z1 = up ? 7.0 : 9.0, z4 = up ? 4.0 : 12.0, zn = up ? 0.0 : 16.0;
    for (int method = 0; method < 2; ++method) {
      lsm_stack_opts o;
      lsm_stack_opts_default(&o);
      o.method = method ? LSM_METHOD_BLEND : LSM_METHOD_LS;
      o.dz = 1.0;
      record rec = {0};
      run_stack(&src, z, 3, &o, &rec);
      const size_t a8 = slice_inside(&rec, slice_at(&rec, zf), NULL);
      const size_t a9 = slice_inside(&rec, slice_at(&rec, z1), NULL);
      const size_t a12 = slice_inside(&rec, slice_at(&rec, z4), NULL);
      const size_t a16 = slice_inside(&rec, slice_at(&rec, zn), NULL);
      print_message("%s, empty slice %s: area at 0, 1, 4, 8 units from F: %zu %zu %zu %zu\n",
                    method ? "blend" : "ls", up ? "above" : "below", a8, a9, a12, a16);
      assert_true((double)a9 >= 0.98 * (double)a8);
      assert_true(a9 <= a8 && a12 < a9 && a16 < a12); /* and no overshoot */
      for (int t = 0; t <= 8; ++t)
        areas[up][method][t] = slice_inside(&rec, slice_at(&rec, up ? 8.0 - t : 8.0 + t), NULL);
      record_free(&rec);
    }
  }
  for (int method = 0; method < 2; ++method)
    for (int t = 0; t <= 8; ++t)
      if (areas[0][method][t] != areas[1][method][t])
        fail_msg("%s, %d units from F: area %zu with the empty slice below, %zu above",
                 method ? "blend" : "ls", t, areas[0][method][t], areas[1][method][t]);
}

/* Where the object ends (default options, cubic): an empty slice at z = 0,
 * the last non-empty one F at z = 8, the slice N beyond it at z = 16 and,
 * where a third section is given, M at z = 24.
 *   flat end (F = N = M, a cylinder): F's section, whole, up to mid-gap; from there a tip
 *     whose radius shrinks linearly to 0 at the empty slice (a cone), area
 *     A_F (2 (1 - sigma))^2 at fraction sigma of the way from F; an end that
 *     narrows toward the empty slice closes faster, A_F (2 (1 - sigma))^3;
 *   paraboloid end (areas of N and F on a line that reaches 0 at z = 4): the
 *     area at z = 6 at most the line's, A_F / 2, and not far below it; past
 *     z = 4 a tenth of the cone's tip;
 *   no slice beyond F (a lone section): a flat end;
 *   moving end (N and F do not overlap): the section keeps moving at the
 *     centroid velocity of N -> F, 2 px per unit z;
 *   two sections only (F = N, no M): the area follows the parabola through
 *     the areas of N and F and zero at the empty slice, 5/8 of F's at mid-gap. */
static void test_object_ends(void **state) {
  (void)state;
  const double z[4] = {0.0, 8.0, 16.0, 24.0};
  const double r_flat[4] = {0.0, 20.0, 20.0, 20.0};
  const double r_para[3] = {0.0, 10.0, sqrt(300.0)};
  const double r_moving[4] = {0.0, 8.0, 8.0, 8.0}, cx_moving[4] = {0.0, 40.0, 56.0, 72.0};
  const double r_bulge[4] = {0.0, 20.0, 22.0, 24.0}; /* narrows by 21 % in area toward the end */
  struct {
    const char *name;
    const double *radius, *cx;
    size_t slices;
    double tip_power; /* 0: the area line closes the end by mid-gap */
  } cases[] = {{"flat", r_flat, NULL, 4, 2.0},
               {"paraboloid", r_para, NULL, 3, 0.0},
               {"no slice beyond", r_flat, NULL, 2, 2.0}, /* a lone section: a flat end */
               {"moving", r_moving, cx_moving, 4, 2.0},
               {"narrowing slowly", r_bulge, NULL, 4, 3.0}};
  for (size_t t = 0; t < sizeof cases / sizeof cases[0]; ++t) {
    disc_source src = {96, cases[t].radius, cases[t].cx};
    lsm_stack_opts o;
    lsm_stack_opts_default(&o);
    o.dz = 1.0;
    /* the moving end keeps moving with --align auto's frame (rule end-moves-on), which acts
     * with --motion none; the field does not carry an end */
    o.motion = LSM_MOTION_NONE;
    record rec = {0};
    run_stack(&src, z, cases[t].slices, &o, &rec);
    const size_t area_f = slice_inside(&rec, slice_at(&rec, 8.0), NULL);
    assert_int_equal(slice_inside(&rec, slice_at(&rec, 0.0), NULL), 0); /* the empty input */
    const double p = cases[t].tip_power;
    if (p > 0.0) { /* the tip past mid-gap: area A_F (zz / 4)^p, p = 2 (a cone)
                    * for an end that does not narrow, 3 for one that does */
      for (double zz = 1.0; zz <= 4.0; zz += 1.0) {
        const double tip = (double)area_f * pow(zz / 4.0, p);
        const size_t a = slice_inside(&rec, slice_at(&rec, zz), NULL);
        print_message("end %s: area at z = %.0f: %zu (tip %.1f)\n", cases[t].name, zz, a, tip);
        assert_true((double)a <= tip && (double)a >= 0.85 * tip - 4.0);
      }
    } else { /* narrowing fast: the area line closes the end by mid-gap; what
              * is left past it is a tenth of the cone's tip, A_F (zz / 4)^2 / 10
              * (give or take a ring of tied pixels), never nothing */
      for (double zz = 1.0; zz <= 3.0; zz += 1.0) {
        const double tenth = 0.1 * (double)area_f * pow(zz / 4.0, 2.0);
        const size_t a = slice_inside(&rec, slice_at(&rec, zz), NULL);
        print_message("end %s: area at z = %.0f: %zu (a tenth of the tip %.1f)\n", cases[t].name,
                      zz, a, tenth);
        assert_true(a >= 1 && fabs((double)a - tenth) <= 8.0);
      }
      assert_true(slice_inside(&rec, slice_at(&rec, 4.0), NULL) <= 0.1 * (double)area_f + 8.0);
    }
    double cx6 = 0.0;
    const size_t area5 = slice_inside(&rec, slice_at(&rec, 5.0), NULL);
    const size_t area6 = slice_inside(&rec, slice_at(&rec, 6.0), &cx6);
    const size_t area7 = slice_inside(&rec, slice_at(&rec, 7.0), NULL);
    print_message("end %s: area at z = 8, 7, 6, 5: %zu %zu %zu %zu, centroid x at 6: %.2f\n",
                  cases[t].name, area_f, area7, area6, area5, cx6);
    if (p == 2.0) { /* not narrowing: whole up to mid-gap */
      assert_int_equal(area5, area_f);
      assert_int_equal(area6, area_f);
      assert_int_equal(area7, area_f);
    } else { /* at most the line through the areas of N and F or, with M (the
              * slice beyond N), the parabola through the areas of M, N and F
              * instead, and not far below it */
      const double a_n = (double)slice_inside(&rec, slice_at(&rec, 16.0), NULL);
      const int has_m = cases[t].slices == 4;
      const double a_m = has_m ? (double)slice_inside(&rec, slice_at(&rec, 24.0), NULL) : 0.0;
      for (double zz = 5.0; zz <= 7.0; zz += 1.0) {
        const double d = 8.0 - zz, d1 = ((double)area_f - a_n) / 8.0, d0 = (a_n - a_m) / 8.0;
        const double cap = has_m ? (double)area_f + d1 * d + (d1 - d0) / 16.0 * d * (d + 8.0)
                                 : (double)area_f + d1 * d;
        const size_t a = slice_inside(&rec, slice_at(&rec, zz), NULL);
        print_message("end %s: area at z = %.0f: %zu (cap %.1f)\n", cases[t].name, zz, a, cap);
        assert_true((double)a <= cap && (double)a >= 0.85 * cap - 4.0);
      }
    }
    if (t == 3) assert_true(fabs(cx6 - 36.0) <= 0.5); /* 40 - 2 px per unit z * 2 */
    record_free(&rec);
  }
  {
    disc_source src = {96, r_flat, NULL};
    lsm_stack_opts o;
    lsm_stack_opts_default(&o);
    o.dz = 1.0;
    record rec = {0};
    run_stack(&src, z, 3, &o, &rec);
    const double area_f = (double)slice_inside(&rec, slice_at(&rec, 8.0), NULL);
    const double area4 = (double)slice_inside(&rec, slice_at(&rec, 4.0), NULL);
    print_message("end two sections: area at z = 4: %.0f (5/8 of F %.0f)\n", area4,
                  0.625 * area_f);
    assert_true(fabs(area4 - 0.625 * area_f) <= 0.05 * area_f);
    record_free(&rec);
  }
  /* Uneven gaps: N -> F moves 16 px in 1 unit, the end gap is 400 units long.
   * The extrapolated end stops at the image border (x = 0) instead of 6400 px
   * away, so the canvas stays bounded; at a quarter of the gap the centroid
   * is a quarter of the way from 40 to 0; the shape trend measured over 1
   * unit is not multiplied by 100. */
  const double z_long[4] = {0.0, 400.0, 401.0, 402.0};
  const double cx_long[4] = {0.0, 40.0, 56.0, 72.0};
  disc_source src = {96, r_moving, cx_long};
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  o.dz = 1.0;
  o.motion = LSM_MOTION_NONE; /* end-moves-on, as above */
  record rec = {0};
  run_stack(&src, z_long, 4, &o, &rec);
  double cx300 = 0.0;
  const size_t area300 = slice_inside(&rec, slice_at(&rec, 300.0), &cx300);
  print_message("end moving, long gap: area at z = 300: %zu, centroid x %.2f\n", area300, cx300);
  /* whole, but for the pixel by which the whole-pixel shifts of N and F
   * disagree (centroids 8.5 and -7.5 px from the centre, rounded apart) */
  assert_true((double)area300 >= 0.9 * (double)slice_inside(&rec, slice_at(&rec, 400.0), NULL));
  assert_true(fabs(cx300 - 30.0) <= 0.5);
  record_free(&rec);
}

/* --ends: the flat end of test_object_ends (a cylinder crossed by three
 * sections, an empty slice at z = 0).  halfway: the same as tip from F down
 * to mid-gap, whole, and nothing past it, where tip keeps its tip.  auto (the
 * default): tip where the empty slice is the first input slice, as here;
 * halfway when another empty slice lies below it (z = -8: a scan that
 * covers more than the object). */
static void test_object_ends_halfway(void **state) {
  (void)state;
  const double z[5] = {-8.0, 0.0, 8.0, 16.0, 24.0};
  const double r_flat[5] = {0.0, 0.0, 20.0, 20.0, 20.0};
  disc_source cut = {96, r_flat + 1, NULL}, scan = {96, r_flat, NULL};
  record tip = {0}, halfway = {0}, auto_cut = {0}, auto_scan = {0};
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  assert_int_equal(o.ends, LSM_ENDS_AUTO);
  o.dz = 1.0;
  run_stack(&cut, z + 1, 4, &o, &auto_cut);
  run_stack(&scan, z, 5, &o, &auto_scan);
  o.ends = LSM_ENDS_TIP;
  run_stack(&cut, z + 1, 4, &o, &tip);
  o.ends = LSM_ENDS_HALFWAY;
  run_stack(&cut, z + 1, 4, &o, &halfway);
  const size_t area_f = slice_inside(&halfway, slice_at(&halfway, 8.0), NULL);
  for (double zz = 1.0; zz <= 8.0; zz += 1.0) {
    const size_t a = slice_inside(&halfway, slice_at(&halfway, zz), NULL);
    const size_t a_tip = slice_inside(&tip, slice_at(&tip, zz), NULL);
    print_message("end halfway: area at z = %.0f: %zu (tip rule %zu)\n", zz, a, a_tip);
    if (zz < 4.0) {
      assert_int_equal(a, 0);
      assert_true(a_tip > 0);
    } else {
      assert_int_equal(a, area_f);
      assert_int_equal(a, a_tip);
    }
    assert_int_equal(slice_inside(&auto_cut, slice_at(&auto_cut, zz), NULL), a_tip);
    assert_int_equal(slice_inside(&auto_scan, slice_at(&auto_scan, zz), NULL), a);
  }
  record_free(&tip);
  record_free(&halfway);
  record_free(&auto_cut);
  record_free(&auto_scan);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_object_ends),
      cmocka_unit_test(test_object_ends_halfway),
      cmocka_unit_test(test_end_neighbour_flat),
      cmocka_unit_test(test_ball_beside_ends),
      cmocka_unit_test(test_two_sections),
  };
  return cmocka_run_group_tests_name("interp_ends", tests, NULL, NULL);
}
