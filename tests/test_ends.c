/* Tests of the end rule (solver/recon/lsm_ends.h): how an object ends in a gap
 * whose far side is an empty slice.  Sections are discs; the area of a
 * result is its count of cells with phi <= 0. */
#include "tests/lsm_test_mask.h"

#include "solver/base/lsm_flood.h"
#include "solver/recon/lsm_ends.h"
#include "solver/sdf/lsm_sdf.h"

#define SIZE 96
#define PI 3.14159265358979323846

typedef struct disc {
  double cx, cy, r;
} disc;

/* phi of the union of n discs on a SIZE x SIZE grid of unit cells. */
static lsm_grid *discs_phi(const disc *d, int n) {
  lsm_mask m = lsm_test_mask(SIZE, SIZE);
  for (int k = 0; k < n; ++k) lsm_test_paint_disc(&m, d[k].cx, d[k].cy, d[k].r);
  lsm_grid *phi = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_grid_create(SIZE, SIZE, 1.0f, 1.0f, &phi, &err), LSM_OK);
  assert_int_equal(lsm_sdf_from_mask(&m, phi, &err), LSM_OK);
  lsm_mask_free(&m);
  return phi;
}

static double inside_cells(const lsm_grid *phi, int x0, int x1) {
  double n = 0.0;
  for (int j = 0; j < phi->ny; ++j)
    for (int i = x0; i < x1; ++i) n += LSM_AT(phi, i, j) <= 0.0f;
  return n;
}

static double area(const lsm_grid *phi) { return inside_cells(phi, 0, phi->nx); }

/* The end at sigma, for F (N beyond it, or NULL, h_beyond away; M beyond N,
 * or NULL, h_farther from N) over a gap of height H: a new grid (the caller
 * destroys it). */
static lsm_grid *end_at_m(const lsm_grid *full, const lsm_grid *beyond, double h_beyond,
                          const lsm_grid *farther, double h_farther, double H,
                          lsm_end_profile profile, double sigma) {
  lsm_err err;
  lsm_err_clear(&err);
  lsm_end *end = NULL;
  lsm_grid *work = NULL;
  assert_int_equal(
      lsm_end_create(full, beyond, h_beyond, farther, h_farther, H, profile, NULL, &end, &err),
      LSM_OK);
  assert_int_equal(lsm_grid_clone(full, &work, &err), LSM_OK);
  lsm_end_at(end, sigma, work);
  lsm_end_destroy(&end);
  assert_null(end);
  return work;
}

static lsm_grid *end_at(const lsm_grid *full, const lsm_grid *beyond, double h_beyond, double H,
                        lsm_end_profile profile, double sigma) {
  return end_at_m(full, beyond, h_beyond, NULL, 0.0, H, profile, sigma);
}

static double end_area(const lsm_grid *full, const lsm_grid *beyond, double h_beyond, double H,
                       lsm_end_profile profile, double sigma) {
  lsm_grid *work = end_at(full, beyond, h_beyond, H, profile, sigma);
  const double a = area(work);
  lsm_grid_destroy(&work);
  return a;
}

/* R is the section's largest depth, -min phi (a disc's radius, less the
 * distance from its centre to the nearest cell centre), at least half a cell. */
static void test_depth(void **state) {
  (void)state;
  const disc d = {47.0, 47.0, 20.0};
  lsm_grid *phi = discs_phi(&d, 1);
  assert_close(lsm_end_depth(phi), -lsm_grid_min(phi), 1e-6);
  assert_close(lsm_end_depth(phi), 20.0, 0.5);
  lsm_grid_fill(phi, 0.1f);
  assert_close(lsm_end_depth(phi), 0.5, 1e-9);
  lsm_grid_destroy(&phi);
}

/* Linear profile: a uniform erosion of the disc (effective radius r, largest
 * depth R) by R (1 - sqrt(1 - 2 sigma)) for ls (a paraboloid cap: the area
 * falls about linearly to nothing at mid-gap), by R sigma / (1 - sigma) for
 * the blend (the zero set of (1 - sigma) phi + sigma R); nothing is left
 * from mid-gap on. */
static void test_linear_profiles(void **state) {
  (void)state;
  const disc d = {47.5, 47.5, 30.0};
  lsm_grid *phi = discs_phi(&d, 1);
  const double R = lsm_end_depth(phi), a0 = area(phi), r = sqrt(a0 / PI);
  for (double sigma = 0.1; sigma < 0.45; sigma += 0.1) {
    const double r_ls = r - R * (1.0 - sqrt(1.0 - 2.0 * sigma));
    const double r_blend = r - R * sigma / (1.0 - sigma);
    const double ls = end_area(phi, NULL, 0.0, 8.0, LSM_END_PARABOLOID, sigma);
    const double blend = end_area(phi, NULL, 0.0, 8.0, LSM_END_BLEND, sigma);
    print_message("sigma %.1f: ls %.0f (%.0f), blend %.0f (%.0f)\n", sigma, ls, PI * r_ls * r_ls,
                  blend, PI * r_blend * r_blend);
    assert_close(sqrt(ls / PI), r_ls, 0.5);
    assert_close(sqrt(blend / PI), r_blend, 0.5);
  }
  for (double sigma = 0.5; sigma <= 1.0; sigma += 0.25) {
    assert_true(end_area(phi, NULL, 0.0, 8.0, LSM_END_PARABOLOID, sigma) == 0.0);
    assert_true(end_area(phi, NULL, 0.0, 8.0, LSM_END_BLEND, sigma) == 0.0);
  }
  lsm_grid_destroy(&phi);
}

/* Cubic profile, nothing beyond F (a lone section): a flat end, whole up to
 * mid-gap, then closing like a cone, A_F (2 (1 - sigma))^2, to nothing at the
 * empty slice (above a tenth of the tip one power lower, which it keeps). */
static void test_flat_end(void **state) {
  (void)state;
  const disc d = {47.5, 47.5, 20.0};
  lsm_grid *phi = discs_phi(&d, 1);
  const double a0 = area(phi);
  assert_true(end_area(phi, NULL, 0.0, 8.0, LSM_END_TREND, 0.25) == a0);
  assert_true(end_area(phi, NULL, 0.0, 8.0, LSM_END_TREND, 0.5) == a0);
  for (double sigma = 0.625; sigma < 0.95; sigma += 0.125) {
    const double a = end_area(phi, NULL, 0.0, 8.0, LSM_END_TREND, sigma);
    const double tip = 2.0 * (1.0 - sigma);
    const double cap = a0 * tip * tip;
    print_message("sigma %.3f: %.0f cells, cap %.0f\n", sigma, a, cap);
    assert_true(cap > 0.1 * a0 * tip);
    assert_true(a <= cap);
    assert_true(a >= 0.9 * cap);
  }
  assert_true(end_area(phi, NULL, 0.0, 8.0, LSM_END_TREND, 1.0) == 0.0);
  lsm_grid_destroy(&phi);
}

/* The parabola through the areas of N (h before F), F and zero at the empty
 * slice (H past F), at z past F. */
static double two_section_parabola(double a_n, double a_f, double h, double H, double z) {
  const double d1 = (a_f - a_n) / h, d2 = -a_f / H;
  return a_f + d1 * z + (d2 - d1) / (H + h) * z * (z + h);
}

/* Cubic profile, F narrower than N (a rounded end), no slice beyond N: the
 * area follows the line through N's and F's areas or, where it lies lower,
 * the parabola through them and zero at the empty slice, and past mid-gap
 * also the narrowing tip, A_F (2 (1 - sigma))^3, keeping at least a tenth of
 * a cone's tip, A_F (2 (1 - sigma))^2 / 10. */
static void test_narrowing_end(void **state) {
  (void)state;
  const disc f = {47.5, 47.5, 20.0}, n = {47.5, 47.5, 24.0};
  lsm_grid *phi_f = discs_phi(&f, 1), *phi_n = discs_phi(&n, 1);
  const double a_f = area(phi_f), a_n = area(phi_n), h = 8.0, H = 8.0;
  for (double sigma = 0.125; sigma < 0.95; sigma += 0.125) {
    const double a = end_area(phi_f, phi_n, h, H, LSM_END_TREND, sigma);
    const double line = a_f - sigma * H * (a_n - a_f) / h;
    const double parabola = two_section_parabola(a_n, a_f, h, H, sigma * H);
    const double t = fmin(1.0, 2.0 * (1.0 - sigma));
    const double tip = a_f * t * t * t;
    const double cap = fmax(fmin(fmin(line, parabola), tip), 0.1 * a_f * t * t);
    print_message("sigma %.3f: %.0f cells, line %.0f, parabola %.0f, tip %.0f\n", sigma, a, line,
                  parabola, tip);
    assert_true(a <= cap + 1e-9);
    assert_true(a >= cap - 0.05 * a_f);
  }
  lsm_grid_destroy(&phi_f);
  lsm_grid_destroy(&phi_n);
}

/* The sections of a ball of radius 40 at z = -4 (M), 12 (N) and 28 (F), the
 * empty slice at 44: the area of a ball's section is quadratic in z, so the
 * parabola through the areas of M, N and F follows the ball's own end,
 * pi (40^2 - z^2).  Without M, the parabola through N, F and zero at the
 * empty slice closes at z = 44, not at the ball's z = 40, and keeps more. */
static void test_rounded_end(void **state) {
  (void)state;
  const double radius = 40.0, zm = -4.0, zn = 12.0, zf = 28.0, H = 16.0;
  const disc m = {47.5, 47.5, sqrt(radius * radius - zm * zm)},
             n = {47.5, 47.5, sqrt(radius * radius - zn * zn)},
             f = {47.5, 47.5, sqrt(radius * radius - zf * zf)};
  lsm_grid *phi_m = discs_phi(&m, 1), *phi_n = discs_phi(&n, 1), *phi_f = discs_phi(&f, 1);
  for (double sigma = 0.25; sigma <= 0.5; sigma += 0.125) {
    const double z = zf + sigma * H, ball = PI * (radius * radius - z * z);
    lsm_grid *work = end_at_m(phi_f, phi_n, zf - zn, phi_m, zn - zm, H, LSM_END_TREND, sigma);
    const double a = area(work);
    const double line = end_area(phi_f, phi_n, zf - zn, H, LSM_END_TREND, sigma);
    const double two = two_section_parabola(PI * n.r * n.r, PI * f.r * f.r, zf - zn, H, z - zf);
    print_message("sigma %.3f: %.0f cells, ball %.0f, without M %.0f (parabola %.0f)\n", sigma, a,
                  ball, line, two);
    assert_true(fabs(a - ball) <= 0.05 * ball + 20.0);
    assert_true(line > ball + 0.05 * PI * f.r * f.r);
    assert_true(fabs(line - two) <= 0.05 * two + 20.0);
    lsm_grid_destroy(&work);
  }
  lsm_grid_destroy(&phi_m);
  lsm_grid_destroy(&phi_n);
  lsm_grid_destroy(&phi_f);
}

/* Two sections only (N, F, nothing beyond N), F as wide as N or wider: the
 * area follows the parabola through the areas of N and F and zero at the
 * empty slice (a cylinder crossed by two sections: A_F (1 - sigma / 2 -
 * sigma^2 / 2) with h = H), never above F's, and past mid-gap a cone's tip,
 * A_F (2 (1 - sigma))^2, keeping a tenth of A_F 2 (1 - sigma). */
static void test_two_section_end(void **state) {
  (void)state;
  const disc f = {47.5, 47.5, 20.0}, wider = {47.5, 47.5, 20.0}, narrower = {47.5, 47.5, 16.0};
  lsm_grid *phi_f = discs_phi(&f, 1), *phi_same = discs_phi(&wider, 1);
  lsm_grid *phi_n = discs_phi(&narrower, 1);
  const double a_f = area(phi_f), h = 8.0, H = 8.0;
  const lsm_grid *beyond[2] = {phi_same, phi_n};
  for (int t = 0; t < 2; ++t) {
    const double a_n = area(beyond[t]);
    for (double sigma = 0.125; sigma < 0.95; sigma += 0.125) {
      const double a = end_area(phi_f, beyond[t], h, H, LSM_END_TREND, sigma);
      const double parabola = two_section_parabola(a_n, a_f, h, H, sigma * H);
      const double frac = fmin(1.0, 2.0 * (1.0 - sigma));
      const double tip = a_f * frac * frac; /* p = 2: no narrowing */
      const double cap = fmax(fmin(fmin(parabola, tip), a_f), 0.1 * a_f * frac);
      print_message("A_N %.0f, sigma %.3f: %.0f cells, parabola %.0f, tip %.0f\n", a_n, sigma, a,
                    parabola, tip);
      assert_true(a <= cap + 1e-9);
      /* (the erosion keeps or drops whole rings of cells tied in phi) */
      assert_true(a >= cap - 0.05 * a_f);
    }
    /* the cylinder: 1 - sigma / 2 - sigma^2 / 2 of F at mid-gap, 5/8 */
    if (t == 0)
      assert_close(end_area(phi_f, phi_same, h, H, LSM_END_TREND, 0.5), 0.625 * a_f, 0.05 * a_f);
  }
  lsm_grid_destroy(&phi_f);
  lsm_grid_destroy(&phi_same);
  lsm_grid_destroy(&phi_n);
}

/* A part half inside N (a share between 40 % and 60 %: weight w of it narrows
 * like N -> F, the rest is a flat end): up to mid-gap its area follows
 * (1 - w) A_F + w min(line, parabola), the line through A_N and A_F and the
 * parabola through them and zero at the empty slice taken for the narrowing
 * share alone, w A_F + w sigma H (A_F - A_N) / h for the line. */
static void test_half_nested_end(void **state) {
  (void)state;
  const disc f = {35.0, 47.5, 16.0}, n = {57.5, 47.5, 24.0};
  lsm_grid *phi_f = discs_phi(&f, 1), *phi_n = discs_phi(&n, 1);
  const double a_f = area(phi_f), a_n = area(phi_n), h = 8.0, H = 8.0;
  double nested = 0.0;
  for (int j = 0; j < SIZE; ++j)
    for (int i = 0; i < SIZE; ++i)
      nested += LSM_AT(phi_f, i, j) <= 0.0f && LSM_AT(phi_n, i, j) <= 0.0f;
  const double w = (nested / a_f - 0.4) / 0.2;
  print_message("share inside N %.3f, weight %.3f\n", nested / a_f, w);
  assert_true(w > 0.25 && w < 0.75);
  for (double sigma = 0.125; sigma <= 0.5; sigma += 0.125) {
    const double a = end_area(phi_f, phi_n, h, H, LSM_END_TREND, sigma);
    const double line = a_f - sigma * H * (a_n - a_f) / h;
    const double parabola = fmax(two_section_parabola(a_n, a_f, h, H, sigma * H), 0.0);
    const double cap = (1.0 - w) * a_f + w * fmin(line, parabola);
    print_message("sigma %.3f: %.0f cells, cap %.0f (line %.0f, parabola %.0f)\n", sigma, a, cap,
                  line, parabola);
    assert_true(a <= cap + 1e-9);
    assert_true(a >= cap - 0.05 * a_f);
  }
  lsm_grid_destroy(&phi_f);
  lsm_grid_destroy(&phi_n);
}

/* M does not change an end that keeps its size (a cylinder: M, N and F the
 * same disc) or one that widens toward it ever faster (a cone's base): the
 * parabola then lies above F's area, and the flat end stays whole up to
 * mid-gap. */
static void test_flat_end_with_m(void **state) {
  (void)state;
  const disc same = {47.5, 47.5, 20.0}, m = {47.5, 47.5, 12.0}, n = {47.5, 47.5, 16.0};
  lsm_grid *phi_same = discs_phi(&same, 1), *phi_m = discs_phi(&m, 1), *phi_n = discs_phi(&n, 1);
  const double a0 = area(phi_same);
  for (double sigma = 0.125; sigma < 0.95; sigma += 0.125) {
    lsm_grid *cyl = end_at_m(phi_same, phi_same, 8.0, phi_same, 8.0, 8.0, LSM_END_TREND, sigma);
    lsm_grid *cone = end_at_m(phi_same, phi_n, 8.0, phi_m, 8.0, 8.0, LSM_END_TREND, sigma);
    const double flat = end_area(phi_same, NULL, 0.0, 8.0, LSM_END_TREND, sigma);
    assert_true(area(cyl) == flat);
    assert_true(area(cone) == flat);
    if (sigma <= 0.5) assert_true(flat == a0);
    lsm_grid_destroy(&cyl);
    lsm_grid_destroy(&cone);
  }
  lsm_grid_destroy(&phi_same);
  lsm_grid_destroy(&phi_m);
  lsm_grid_destroy(&phi_n);
}

/* However fast the line of the areas closes an end (N nearly five times F:
 * the line reaches zero at sigma 0.26, and the per-cell trend, N's disc 12
 * cells wider, takes the whole disc by sigma 0.7), it keeps a tenth of its
 * tip, A_F (2 (1 - sigma))^2 / 10 cells, up to the empty slice: no section
 * where the object may still be is left empty. */
static void test_tip_floor(void **state) {
  (void)state;
  const disc f = {47.5, 47.5, 10.0}, n = {47.5, 47.5, 22.0};
  lsm_grid *phi_f = discs_phi(&f, 1), *phi_n = discs_phi(&n, 1);
  const double a_f = area(phi_f);
  for (double sigma = 0.375; sigma < 0.95; sigma += 0.125) {
    const double a = end_area(phi_f, phi_n, 8.0, 8.0, LSM_END_TREND, sigma);
    const double floor_cells = 0.1 * a_f * pow(fmin(1.0, 2.0 * (1.0 - sigma)), 2.0);
    print_message("sigma %.3f: %.0f cells, a tenth of the tip %.1f\n", sigma, a, floor_cells);
    /* the floor, give or take the cells tied with the last one kept (rings
     * of 4 or 8 cells around the disc's centre), and never nothing */
    assert_true(a >= 1.0);
    assert_true(fabs(a - floor_cells) <= 8.0);
  }
  lsm_grid_destroy(&phi_f);
  lsm_grid_destroy(&phi_n);
}

/* --ends halfway: the same end as the tip rule up to mid-gap (a lone flat
 * section, and a rounded end whose cells the floor keeps), nothing past it,
 * where the tip rule still holds cells up to the empty slice. */
static void test_halfway_end(void **state) {
  (void)state;
  const disc f = {47.5, 47.5, 10.0}, n = {47.5, 47.5, 22.0};
  lsm_grid *phi_f = discs_phi(&f, 1), *phi_n = discs_phi(&n, 1);
  for (int with_n = 0; with_n < 2; ++with_n) {
    const lsm_grid *beyond = with_n ? phi_n : NULL;
    const double h = with_n ? 8.0 : 0.0;
    for (double sigma = 0.125; sigma <= 0.5; sigma += 0.125)
      assert_true(end_area(phi_f, beyond, h, 8.0, LSM_END_TREND_HALFWAY, sigma) ==
                  end_area(phi_f, beyond, h, 8.0, LSM_END_TREND, sigma));
    for (double sigma = 0.625; sigma < 0.95; sigma += 0.125) {
      assert_true(end_area(phi_f, beyond, h, 8.0, LSM_END_TREND_HALFWAY, sigma) == 0.0);
      assert_true(end_area(phi_f, beyond, h, 8.0, LSM_END_TREND, sigma) >= 1.0);
    }
  }
  assert_true(lsm_end_profile_is_trend(LSM_END_TREND_HALFWAY));
  assert_false(lsm_end_profile_is_trend(LSM_END_PARABOLOID));
  lsm_grid_destroy(&phi_f);
  lsm_grid_destroy(&phi_n);
}

/* A small section does not vanish by rounding: the signed distance of a
 * 5-cell plus has its four arms tied, so a uniform erosion keeps 5 cells or
 * 1.  Narrowing from a 3 x 3 square N, its target falls from 5 cells by
 * about half a cell per eighth of the gap; the arms stay while the target
 * is nearer 5 than 1 (the floor, 1 cell, would be less than half of it),
 * and the end closes to its centre when the target nears 1. */
static void test_small_section(void **state) {
  (void)state;
  const disc f = {47.0, 47.0, 1.0}, n = {47.0, 47.0, 1.5};
  lsm_grid *phi_f = discs_phi(&f, 1), *phi_n = discs_phi(&n, 1);
  assert_true(area(phi_f) == 5.0);
  assert_true(area(phi_n) == 9.0);
  const double h = 8.0, H = 8.0;
  for (double sigma = 0.125; sigma <= 0.5; sigma += 0.125) {
    const double a = end_area(phi_f, phi_n, h, H, LSM_END_TREND, sigma);
    const double line = 5.0 - sigma * H * (9.0 - 5.0) / h;
    const double target = fmin(line, two_section_parabola(9.0, 5.0, h, H, sigma * H));
    print_message("sigma %.3f: %.0f cells, target %.2f\n", sigma, a, target);
    assert_true(a == (5.0 - target < target - 1.0 ? 5.0 : 1.0));
  }
  assert_true(end_area(phi_f, phi_n, h, H, LSM_END_TREND, 0.125) == 5.0);
  lsm_grid_destroy(&phi_f);
  lsm_grid_destroy(&phi_n);
}

/* Each part ends on its own: of two discs of F, the one inside N's wide disc
 * narrows with it; the one outside N grows out toward the end (a tail) and
 * is a flat end, whole up to mid-gap. */
static void test_parts_end_apart(void **state) {
  (void)state;
  const disc f[2] = {{28.0, 47.5, 12.0}, {78.0, 47.5, 8.0}}, n = {28.0, 47.5, 18.0};
  lsm_grid *phi_f = discs_phi(f, 2), *phi_n = discs_phi(&n, 1);
  const double body = inside_cells(phi_f, 0, 60), tail = inside_cells(phi_f, 60, SIZE);
  const double body_n = area(phi_n);
  lsm_grid *work = end_at(phi_f, phi_n, 8.0, 8.0, LSM_END_TREND, 0.375);
  const double body_end = inside_cells(work, 0, 60), tail_end = inside_cells(work, 60, SIZE);
  const double line = body - 0.375 * (body_n - body);
  print_message("body %.0f -> %.0f (line %.0f), tail %.0f -> %.0f\n", body, body_end, line,
                tail, tail_end);
  assert_true(tail_end == tail);
  assert_true(body_end <= line);
  assert_true(body_end >= line - 0.05 * body);
  lsm_grid_destroy(&work);
  lsm_grid_destroy(&phi_f);
  lsm_grid_destroy(&phi_n);
}

/* The per-cell trend of N -> F is carried at most h_N past F: with a slice
 * N only 1 below F and a gap of 16, an F that does not narrow in area (N
 * the same disc shifted, and M beyond it too, so that no parabola of the
 * areas caps the end) keeps moving by at most N -> F's step. */
static void test_trend_reach(void **state) {
  (void)state;
  const disc f = {50.5, 47.5, 20.0}, n = {49.5, 47.5, 20.0};
  lsm_grid *phi_f = discs_phi(&f, 1), *phi_n = discs_phi(&n, 1);
  lsm_grid *work = end_at_m(phi_f, phi_n, 1.0, phi_n, 1.0, 16.0, LSM_END_TREND, 0.5);
  /* per cell phi_F + min(sigma H, h_N) max(phi_F - phi_N, 0) / h_N: the
   * trailing side rises by at most one cell, never by sigma H = 8 */
  double worst = 0.0;
  for (int j = 0; j < SIZE; ++j)
    for (int i = 0; i < SIZE; ++i)
      worst = fmax(worst, LSM_AT(work, i, j) - LSM_AT(phi_f, i, j));
  print_message("largest rise %.3f cells\n", worst);
  assert_true(worst <= 1.0 + 1e-3);
  assert_true(worst >= 0.5);
  lsm_grid_destroy(&work);
  lsm_grid_destroy(&phi_f);
  lsm_grid_destroy(&phi_n);
}

/* The component labeller the end rule counts parts with: 8-connected
 * components of {phi <= level}, numbered in row-major order of their first
 * cell; the spread without phi gives every cell the label of the nearest
 * labelled cell (breadth-first, 8-neighbour steps). */
static void test_label_components(void **state) {
  (void)state;
  lsm_grid *phi = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_grid_create(8, 4, 1.0f, 1.0f, &phi, &err), LSM_OK);
  lsm_grid_fill(phi, 1.0f);
  /* rows: "##......", "..#....#", "......1.", "#......." (1: phi = 0.5) */
  const int cells[][2] = {{0, 0}, {1, 0}, {2, 1}, {7, 1}, {0, 3}};
  for (size_t k = 0; k < sizeof cells / sizeof cells[0]; ++k)
    LSM_AT(phi, cells[k][0], cells[k][1]) = -1.0f;
  LSM_AT(phi, 6, 2) = 0.5f;
  int32_t label[32], queue[32];
  assert_int_equal(lsm_grid_label_components(phi, 0.0f, label, queue), 3);
  assert_int_equal(label[0], 0);
  assert_int_equal(label[1 * 8 + 2], 0); /* touches (1, 0) diagonally */
  assert_int_equal(label[1 * 8 + 7], 1);
  assert_int_equal(label[3 * 8 + 0], 2);
  assert_int_equal(label[2 * 8 + 6], -1);
  /* at level 0.5 the cell (6, 2) joins (7, 1) */
  assert_int_equal(lsm_grid_label_components(phi, 0.5f, label, queue), 3);
  assert_int_equal(label[2 * 8 + 6], 1);
  /* spread to every cell from the labelled ones */
  size_t tail = 0;
  for (int32_t k = 0; k < 32; ++k)
    if (label[k] >= 0) queue[tail++] = k;
  assert_int_equal(lsm_flood(label, 8, 4, 8, -1, queue, tail), 32);
  assert_int_equal(label[3 * 8 + 1], 2); /* next to (0, 3) */
  assert_int_equal(label[0 * 8 + 7], 1); /* next to (7, 1) */
  assert_int_equal(label[0 * 8 + 3], 0); /* next to (2, 1) */
  for (int k = 0; k < 32; ++k) assert_true(label[k] >= 0);
  lsm_grid_destroy(&phi);
}

/* lsm_flood's two connectivities on a 5 x 5 image whose walls (-2) run
 * along the anti-diagonal: 4-neighbour steps stay on their side of it, 8-
 * neighbour steps cross it diagonally; components count likewise. */
static void test_flood_connectivity(void **state) {
  (void)state;
  int32_t label[25], queue[25];
  for (int conn = 4; conn <= 8; conn += 4) {
    for (int k = 0; k < 25; ++k) label[k] = (k % 5) + (k / 5) == 4 ? -2 : -1;
    label[0] = 7;
    queue[0] = 0;
    const size_t reached = lsm_flood(label, 5, 5, conn, -1, queue, 1);
    assert_int_equal(reached, conn == 4 ? 10 : 20); /* the upper-left triangle, or every open cell */
    assert_int_equal(label[24], conn == 4 ? -1 : 7);
    assert_int_equal(label[4], -2);
    for (int k = 0; k < 25; ++k) label[k] = (k % 5) + (k / 5) == 4 ? -2 : -1;
    assert_int_equal(lsm_flood_components(label, 5, 5, conn, -1, 3, queue), conn == 4 ? 2 : 1);
    assert_int_equal(label[0], 3);
    assert_int_equal(label[24], conn == 4 ? 4 : 3);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_label_components),
      cmocka_unit_test(test_flood_connectivity),
      cmocka_unit_test(test_depth),
      cmocka_unit_test(test_linear_profiles),
      cmocka_unit_test(test_flat_end),
      cmocka_unit_test(test_narrowing_end),
      cmocka_unit_test(test_rounded_end),
      cmocka_unit_test(test_two_section_end),
      cmocka_unit_test(test_half_nested_end),
      cmocka_unit_test(test_tip_floor),
      cmocka_unit_test(test_small_section),
      cmocka_unit_test(test_halfway_end),
      cmocka_unit_test(test_flat_end_with_m),
      cmocka_unit_test(test_parts_end_apart),
      cmocka_unit_test(test_trend_reach),
  };
  return cmocka_run_group_tests_name("ends", tests, NULL, NULL);
}
