/* Signed-distance reinitialisation and the morph object that drives the
 * solver: reinitialisation on a steep circle, cell by cell by hand, one
 * pseudo-time step on a grid and at tiny pixel sizes; the fraction -> time
 * map; the morph's fixed CFL step and its landing on t, the per-iteration
 * stopping quantity CP by hand, the step after a reinitialisation, a step of
 * zero and identical slices at rest. */
#include "tests/lsm_test_scheme.h"

#include "kernels/lsm_cell.h"
#include "solver/base/lsm_grid.h"
#include "solver/pde/lsm_fields.h"
#include "solver/pde/lsm_morph.h"
#include "solver/pde/lsm_scheme.h"
#include "solver/base/lsm_status.h"

/* `iterations` reinitialisation steps of phi on the C backend through
 * lsm_fields (as lsm_morph runs them). */
static void reinit_c(lsm_grid *phi, int iterations) {
  lsm_fields *f = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_fields_create(NULL, phi, phi, 1, &f, &err), LSM_OK);
  assert_int_equal(lsm_fields_reinit(f, iterations, &err), LSM_OK);
  assert_int_equal(lsm_fields_download(f, phi, &err), LSM_OK);
  lsm_fields_destroy(&f);
}

static double max_abs_diff(const lsm_grid *a, const lsm_grid *b) {
  double m = 0.0;
  for (int j = 0; j < a->ny; ++j)
    for (int i = 0; i < a->nx; ++i) m = fmax(m, fabs((double)LSM_AT(a, i, j) - LSM_AT(b, i, j)));
  return m;
}

/* ------------------------------------------------------------------------ */
/* reinitialisation                                                          */

/* phi = 3 (|x| - r): |grad phi| = 3.  After 40 iterations (band ~ 20 px)
 * |grad phi| is within 0.1 of 1 within 4 px of the front, and the front has
 * not moved (< 0.1 px). */
static void test_reinit(void **state) {
  (void)state;
  const int n = 64;
  const double r = 15.3;
  lsm_grid *phi = new_grid(n, n, 1.0f, 1.0f);
  fill_circle(phi, 0.4, -0.3, r, 3.0);
  double dev0;
  const double r_before = front_radius(phi, 0.4, -0.3, r, &dev0, NULL);
  reinit_c(phi, 40);
  double dev1;
  const double r_after = front_radius(phi, 0.4, -0.3, r, &dev1, NULL);
  print_message("reinit: front radius %.4f -> %.4f (max deviation %.4f -> %.4f)\n", r_before,
                r_after, dev0, dev1);
  assert_close(r_after, r_before, 0.1);
  assert_true(dev1 < dev0 + 0.1);
  double worst = 0.0, worst_val = 0.0;
  int cells = 0;
  for (int j = 1; j + 1 < n; ++j)
    for (int i = 1; i + 1 < n; ++i) {
      const double d = hypot(cx_of(phi, i) - 0.4, cy_of(phi, j) + 0.3) - r;
      if (fabs(d) > 4.0) continue;
      const double gx = (LSM_AT(phi, i + 1, j) - LSM_AT(phi, i - 1, j)) / 2.0;
      const double gy = (LSM_AT(phi, i, j + 1) - LSM_AT(phi, i, j - 1)) / 2.0;
      const double g = hypot(gx, gy);
      if (fabs(g - 1.0) > worst) worst = fabs(g - 1.0), worst_val = g;
      ++cells;
      /* And phi itself is the signed distance there. */
      assert_close(LSM_AT(phi, i, j), d, 0.25);
    }
  print_message("reinit: |grad phi| worst %.4f over %d cells in the 4 px band\n", worst_val,
                cells);
  assert_true(cells > 400);
  assert_true(worst < 0.1);
  /* Zero iterations: nothing changes. */
  lsm_grid *copy = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_grid_clone(phi, &copy, &err), LSM_OK);
  reinit_c(phi, 0);
  assert_close(max_abs_diff(phi, copy), 0.0, 0.0);
  lsm_grid_destroy(&copy);
  lsm_grid_destroy(&phi);
}

/* The per-cell reinitialisation step by hand (kernels/lsm_cell.h, Russo &
 * Smereka 2000).  test_reinit above checks only the state 40 iterations on,
 * which is reached whatever the relaxation rate and however |grad phi0| is
 * estimated; here one step of each branch on stencils where every term of the
 * documented formulas decides the value:
 *   interface cell (phi0 changes sign towards a 4-neighbour):
 *     out = phi - (dtau/h) (sgn(phi0) |phi| - D),   D = phi0 / g,
 *     g = max(|central gradient of phi0|, |r0 - phi0|/dx, |phi0 - l0|/dx,
 *             |u0 - phi0|/dy, |phi0 - d0|/dy, 1e-6);
 *   far cell: out = phi - dtau sgn(phi0) (G - 1), G the Godunov gradient upwind
 *     by sgn(phi0), per axis the larger square (as lsm_upwind_hamiltonian):
 *     s > 0: max(max(dxm,0)^2, min(dxp,0)^2) + (y),
 *     s < 0: max(min(dxm,0)^2, max(dxp,0)^2) + (y). */
static void test_reinit_cell_by_hand(void **state) {
  (void)state;
  /* |grad phi0| estimate.  Each case makes a different term the largest; with
   * dtau = h and phi = phi0 > 0 the step lands on D exactly
   * (out = phi0 - (phi0 - D) = D), so the value is D = phi0 / g.
   * r0 one-sided (the audit's case): central (1.5 - -0.1)/2 = 0.8, one-sided
   * |1.5 - 0.2| = 1.3 and |0.2 - -0.1| = 0.3, y flat: g = 1.3 (the central
   * estimate alone would give D = 0.25, 1.6 times too far from the front). */
  assert_close(lsm_reinit_cell(0.2f, 0.2f, -0.1f, 1.5f, 0.2f, 0.2f, 0, 0, 0, 0, 1, 1, 1, 1),
               0.2 / 1.3, 1e-6);
  /* l0 one-sided, the mirror image: g = |0.2 - 1.5| = 1.3. */
  assert_close(lsm_reinit_cell(0.2f, 0.2f, 1.5f, -0.1f, 0.2f, 0.2f, 0, 0, 0, 0, 1, 1, 1, 1),
               0.2 / 1.3, 1e-6);
  /* u0 one-sided on dy = 2 (inv_dy 0.5; h = min(dx, dy) = 1): central
   * (3 - -0.1)/2/2 = 0.775, |3 - 0.2|/2 = 1.4, |0.2 - -0.1|/2 = 0.15: g = 1.4.
   * (Taking 1/dx for the y slopes would give 2.8.) */
  assert_close(lsm_reinit_cell(0.2f, 0.2f, 0.2f, 0.2f, -0.1f, 3.0f, 0, 0, 0, 0, 1, 0.5f, 1, 1),
               0.2 / 1.4, 1e-6);
  /* d0 one-sided, the mirror image. */
  assert_close(lsm_reinit_cell(0.2f, 0.2f, 0.2f, 0.2f, 3.0f, -0.1f, 0, 0, 0, 0, 1, 0.5f, 1, 1),
               0.2 / 1.4, 1e-6);
  /* The central gradient largest: (0.9 - -0.8)/2 = 0.85, (1 - -0.6)/2 = 0.8,
   * g = sqrt(0.85^2 + 0.8^2) = 1.16726 > every one-sided slope (0.7, 1.0,
   * 0.8, 0.8). */
  assert_close(lsm_reinit_cell(0.2f, 0.2f, -0.8f, 0.9f, -0.6f, 1.0f, 0, 0, 0, 0, 1, 1, 1, 1),
               0.2 / sqrt(0.85 * 0.85 + 0.8 * 0.8), 1e-6);

  /* Relaxation rate: the driver's step dtau = h/2 (lsm_reinit.h), so one
   * step goes half the way from sgn(phi0)|phi| to D.  phi0 = -0.3 inside, on
   * dx = 0.5, dy = 1 (h = 0.5, dtau = 0.25): l0 = 0.4 outside, r0 = -0.5;
   * central |-0.5 - 0.4|/2/0.5 = 0.9, |phi0 - l0|/dx = 1.4, |r0 - phi0|/dx =
   * 0.4: g = 1.4, D = -0.3/1.4 = -0.2142857.
   *   phi = -0.45: out = -0.45 - 0.5 (-0.45 + 0.2142857) = -0.3321429
   *   phi = +0.1 (on the wrong side): s|phi| = -0.1,
   *         out = 0.1 - 0.5 (-0.1 + 0.2142857) = 0.0428571 */
  const double D = -0.3 / 1.4;
  assert_close(lsm_reinit_cell(-0.45f, -0.3f, 0.4f, -0.5f, -0.3f, -0.3f, 0, 0, 0, 0, 2, 1, 0.5f,
                               0.25f),
               -0.45 - 0.5 * (-0.45 - D), 1e-6);
  assert_close(lsm_reinit_cell(0.1f, -0.3f, 0.4f, -0.5f, -0.3f, -0.3f, 0, 0, 0, 0, 2, 1, 0.5f,
                               0.25f),
               0.1 - 0.5 * (-0.1 - D), 1e-6);

  /* Godunov gradient, far cells.  s > 0 on a ridge in x (dxm = 0.6 > 0 >
   * dxp = -0.8): both sides upwind, G = max(0.6^2, 0.8^2)^(1/2) = 0.8 (the
   * sum of squares would give 1.0). */
  assert_close(lsm_godunov_grad(1.0f, 0.6f, -0.8f, 0.0f, 0.0f), 0.8, 1e-6);
  /* s > 0, linear 0.3 in x (only dxm upwind) and a ridge in y (1.2, -0.5):
   * G^2 = 0.3^2 + max(1.2^2, 0.5^2) = 1.53. */
  assert_close(lsm_godunov_grad(1.0f, 0.3f, 0.3f, 1.2f, -0.5f), sqrt(1.53), 1e-6);
  /* s < 0 in a valley in both axes (dxm = -0.5, dxp = 1.2; dym = -0.9,
   * dyp = 0.4): G^2 = max(0.25, 1.44) + max(0.81, 0.16) = 2.25. */
  assert_close(lsm_godunov_grad(-1.0f, -0.5f, 1.2f, -0.9f, 0.4f), 1.5, 1e-6);
  /* The other way round nothing is upwind: s > 0 in a valley, s < 0 on a
   * ridge, G = 0. */
  assert_close(lsm_godunov_grad(1.0f, -0.5f, 1.2f, -0.9f, 0.4f), 0.0, 0.0);
  assert_close(lsm_godunov_grad(-1.0f, 0.6f, -0.8f, 1.2f, -0.5f), 0.0, 0.0);
  /* The far-cell step on the x ridge: phi = phi0 = 2, all neighbours
   * positive, dtau = 0.5: out = 2 - 0.5 (0.8 - 1) = 2.1. */
  assert_close(lsm_reinit_cell(2.0f, 2.0f, 1.4f, 1.2f, 2.0f, 2.0f, 0.6f, -0.8f, 0, 0, 1, 1, 1,
                               0.5f),
               2.1, 1e-6);
  /* ... and in the valley inside: phi = phi0 = -2, out = -2 + 0.5 (1.5 - 1). */
  assert_close(lsm_reinit_cell(-2.0f, -2.0f, -1.5f, -0.8f, -1.1f, -1.6f, -0.5f, 1.2f, -0.9f, 0.4f,
                               1, 1, 1, 0.5f),
               -1.75, 1e-6);
}

/* One pseudo-time step of the reinitialisation on a whole grid, every cell by hand.
 * phi0 = 3 (|x - c| - r), a slab in x (flat in y), dx = 0.5, dy = 1, c on the
 * centre of column 7 of 15, r = 2.15: with k = i - 7, phi0 = 1.5 |k| - 6.45
 * (-6.45, -4.95, -3.45, -1.95, -0.45 | 1.05, 2.55, 4.05 for |k| = 0..7).
 * h = min(dx, dy) = 0.5, dtau = h/2 = 0.25.
 *   |k| = 4, 5 (interface): g = 3 (central and one-sided alike), D = phi0/3,
 *     the distance; out = phi0 - (1/2)(phi0 - D) = (2/3) phi0: half way.
 *   k = 0, the valley at the centre (s < 0, dxm = -3, dxp = 3): G = 3 (a sum
 *     of squares would give 3 sqrt 2), out = phi0 - 0.25 (-1)(3 - 1) = phi0 + 0.5.
 *   other cells (linear, G = 3; the zero-gradient ghosts at |k| = 7 are on
 *     the downwind side): out = phi0 - 0.25 s (3 - 1) = phi0 - 0.5 s. */
static void test_reinit_one_step(void **state) {
  (void)state;
  const int nx = 15, ny = 3;
  lsm_grid *phi = new_grid(nx, ny, 0.5f, 1.0f);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) LSM_AT(phi, i, j) = (float)(1.5 * abs(i - 7) - 6.45);
  reinit_c(phi, 1);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int k = abs(i - 7);
      const double phi0 = 1.5 * k - 6.45;
      double want;
      if (k == 4 || k == 5)
        want = phi0 * 2.0 / 3.0;
      else
        want = phi0 - 0.5 * (phi0 > 0 ? 1.0 : -1.0);
      /* float arithmetic on values up to 6.45: a few ulp */
      assert_close(LSM_AT(phi, i, j), want, 1e-5);
    }
  lsm_grid_destroy(&phi);
}

/* The same circle at a pixel size of 1e-25 (the options allow down to
 * 1e-30): the front stays put.  Interface cells were found by the sign of
 * phi0 * neighbour, which underflowed to 0 there, and the far-cell update
 * moved the front by 0.4 px. */
static void test_reinit_tiny_pixels(void **state) {
  (void)state;
  const int n = 64;
  const double h = 1e-25, r = 15.3;
  lsm_grid *phi = new_grid(n, n, (float)h, (float)h);
  fill_circle(phi, 0.4 * h, -0.3 * h, r * h, 3.0);
  const double r_before = front_radius(phi, 0.4 * h, -0.3 * h, r * h, NULL, NULL) / h;
  reinit_c(phi, 40);
  const double r_after = front_radius(phi, 0.4 * h, -0.3 * h, r * h, NULL, NULL) / h;
  print_message("reinit at pixel size 1e-25: front radius %.4f -> %.4f px\n", r_before, r_after);
  assert_close(r_after, r_before, 0.1);
  lsm_grid_destroy(&phi);
}

/* ------------------------------------------------------------------------ */
/* fraction -> time                                                          */

static void test_time_of_fraction(void **state) {
  (void)state;
  assert_close(lsm_morph_time_of_fraction(0.0), 0.0, 0.0);
  assert_close(lsm_morph_time_of_fraction(0.5), log(2.0), 1e-15);
  assert_close(lsm_morph_time_of_fraction(0.75), log(4.0), 1e-14);
  assert_close(lsm_morph_time_of_fraction(0.9), log(10.0), 1e-13);
  assert_close(lsm_morph_time_of_fraction(1e-9), 1e-9, 1e-17);
  double prev = -1.0;
  for (int k = 0; k < 1000; ++k) {
    const double t = lsm_morph_time_of_fraction(k / 1000.0);
    assert_true(t > prev);
    /* Inverse: 1 - e^{-t} = s. */
    assert_close(-expm1(-t), k / 1000.0, 1e-12);
    prev = t;
  }
  const double t1 = lsm_morph_time_of_fraction(1.0);
  assert_true(isinf(t1) && t1 > 0);
}

/* ------------------------------------------------------------------------ */
/* morph object                                                               */

/* The morph's fixed dt is the CFL step of phi_source; advance_to lands on t. */
static void test_morph_dt_and_landing(void **state) {
  (void)state;
  lsm_grid *src = new_grid(32, 32, 1.0f, 1.0f), *tgt = new_grid(32, 32, 1.0f, 1.0f);
  fill_circle(src, 0, 0, 10.0, 1.0);
  fill_circle(tgt, 0, 0, 6.0, 1.0);
  lsm_morph_opts o;
  lsm_morph_opts_default(&o);
  lsm_morph *m = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_morph_create(src, tgt, &o, &m, &err), LSM_OK);
  double dt;
  lsm_cfl_dt(src, tgt, LSM_SCHEME_UPWIND, 0.75, 1, &dt);
  assert_close(lsm_morph_dt(m), dt, 1e-12);
  /* |F| = 4, rate <= 4 sqrt 2 -> dt >= 0.75 / (4 sqrt 2). */
  /* (float arithmetic: relative 1e-6) */
  assert_true(dt >= 0.75 / (4.0 * sqrt(2.0)) * (1 - 1e-6) && dt <= 0.75 / 4.0 * (1 + 1e-6));
  assert_true(isinf(lsm_morph_cp(m)));
  assert_close(lsm_morph_residual(m), lsm_grid_diff_norm(src, tgt, 1), 1e-9);
  /* ||phi_0 - phi_T|| = 4 * 32 (F = -4 on all 1024 cells). */
  assert_close(lsm_morph_residual(m), 4.0 * 32.0, 1e-3);
  const double t = 2.5 * dt;
  assert_int_equal(lsm_morph_advance_to(m, t, 100, &err), LSM_OK);
  assert_int_equal(lsm_morph_iterations(m), 3);
  assert_close(lsm_morph_time(m), t, 1e-12);
  assert_true(lsm_morph_cp(m) > 0 && isfinite(lsm_morph_cp(m)));
  /* max_iter stops short. */
  assert_int_equal(lsm_morph_advance_to(m, 100.0, 5, &err), LSM_OK);
  assert_int_equal(lsm_morph_iterations(m), 5);
  assert_true(lsm_morph_time(m) < 100.0);
  lsm_morph_destroy(&m);
  lsm_grid_destroy(&src);
  lsm_grid_destroy(&tgt);
}

/* ||a - b||_2 over every interior cell, summed serially in double: the
 * definition, not lsm_grid_diff_norm's lane-split sum. */
static double norm_diff_by_def(const lsm_grid *a, const lsm_grid *b) {
  double s = 0.0;
  for (int j = 0; j < a->ny; ++j)
    for (int i = 0; i < a->nx; ++i) {
      const double d = (double)LSM_AT(a, i, j) - (double)LSM_AT(b, i, j);
      s += d * d;
    }
  return sqrt(s);
}

/* CP, the per-iteration stopping quantity (lsm_morph.h, solver/README.md section 12):
 *   CP = | ||phi^n - phi_T|| - ||phi^(n-1) - phi_T|| |
 * over all cells of the working grid, phi in physical units, no area weight.
 * The norms are taken here from lsm_morph_phi after each step; a CP scaled or
 * taken over part of the grid would stop per-iteration runs at another
 * iteration (the stack's test_per_iteration only sees CP <= tol, the loop's
 * own exit condition).  Anisotropic cells (dx = 0.5, dy = 1) so that an area
 * weight dx dy would show as well. */
static void test_morph_cp_by_hand(void **state) {
  (void)state;
  lsm_grid *src = new_grid(40, 20, 0.5f, 1.0f), *tgt = new_grid(40, 20, 0.5f, 1.0f);
  fill_circle(src, 0.3, 0, 7.0, 1.0);
  fill_circle(tgt, 0.3, 0, 4.0, 1.0);
  lsm_morph_opts o;
  lsm_morph_opts_default(&o);
  o.track_cp = 1;
  lsm_morph *m = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_morph_create(src, tgt, &o, &m, &err), LSM_OK);
  double prev = norm_diff_by_def(src, tgt);
  assert_close(lsm_morph_residual(m), prev, 1e-12 * prev);
  for (int n = 1; n <= 12; ++n) {
    assert_int_equal(lsm_morph_step(m, INFINITY, &err), LSM_OK);
    const lsm_grid *phi = lsm_morph_phi(m);
    assert_non_null(phi);
    const double now = norm_diff_by_def(phi, tgt);
    /* Both sums are exact to about 1e-16 relative (800 squares in double):
     * 1e-12 of the norm leaves CP itself (about dt times the norm, 5 %)
     * checked to 2e-11 relative. */
    assert_close(lsm_morph_residual(m), now, 1e-12 * now);
    assert_close(lsm_morph_cp(m), fabs(now - prev), 1e-12 * prev);
    /* the residual shrinks by a few per cent a step: CP is no rounding residue */
    assert_true(lsm_morph_cp(m) > 0.01 * now);
    prev = now;
  }
  lsm_morph_destroy(&m);
  lsm_grid_destroy(&src);
  lsm_grid_destroy(&tgt);
}

/* After a reinitialisation the CFL step is taken again and may only shrink
 * (lsm_morph.h).  The rate is |F| (|p|/dx + |q|/dy) / |(p, q)|, F = phi -
 * phi_T (kernels/lsm_cell.h): the gradient's direction enters, not its size,
 * so a steeper phi moves faster through F.  With phi_T = 0 everywhere F is phi
 * itself, and a field made 5 times steeper by the reinitialisation has a CFL
 * step 5 times smaller.
 *   phi0 = 0.2 (x - 0.25) on 8 x 3 unit cells (x = -3.5 .. 3.5, flat in y):
 *     rate = max |F| = 0.2 * 3.75 = 0.75 at x = -3.5, dt0 = 0.75 / 0.75 = 1.
 *   Step 1: phi1 = phi0 - dt0 F |grad phi0| = phi0 (1 - 0.2) (F = 0 at the
 *     front, which stays at 0.25); the reinitialisation makes it x - 0.25,
 *     rate 3.75, dt = 0.75 / 3.75 = 0.2.  It runs 30 iterations here: the
 *     default 10 leave the far cells short (-3.59 at x = -3.5: the far
 *     update converges to the distance only geometrically), after 30 they
 *     are within 1e-5 of it (1e-4 allowed), so the step is known by hand to
 *     3e-5 relative.
 * Without the new bound the second step would be 1: 5 times the stable one. */
static void test_morph_reinit_dt(void **state) {
  (void)state;
  lsm_grid *src = new_grid(8, 3, 1.0f, 1.0f), *tgt = new_grid(8, 3, 1.0f, 1.0f);
  lsm_grid_fill(tgt, 0.0f);
  lsm_grid_fill_ghosts(tgt);
  lsm_morph_opts o;
  lsm_morph_opts_default(&o);
  o.reinit_every = 1;
  o.reinit_iters = 30;
  lsm_err err;
  lsm_err_clear(&err);
  /* 0.2: the step shrinks; 3: reinitialising a 3x steeper field would allow a
   * 3x longer step, and dt must stay (rate 3 * 3.75 = 11.25, dt0 = 1/15). */
  const double scales[2] = {0.2, 3.0};
  for (int c = 0; c < 2; ++c) {
    const double a = scales[c];
    fill_linear(src, a, 0.0, -a * 0.25);
    lsm_morph *m = NULL;
    assert_int_equal(lsm_morph_create(src, tgt, &o, &m, &err), LSM_OK);
    const double dt0 = 0.75 / (a * 3.75);
    /* F and the rate in float: 1e-6 relative */
    assert_close(lsm_morph_dt(m), dt0, 1e-6 * dt0);
    assert_int_equal(lsm_morph_step(m, INFINITY, &err), LSM_OK);
    assert_close(lsm_morph_time(m), dt0, 1e-6 * dt0); /* step 1 took dt0 */
    lsm_grid *now = NULL;
    assert_int_equal(lsm_grid_clone(lsm_morph_phi(m), &now, &err), LSM_OK);
    /* the reinitialised field: x - 0.25 (the front did not move); the cells
     * farthest from the front are the last the reinitialisation reaches */
    double worst = 0.0;
    for (int i = 0; i < 8; ++i)
      worst = fmax(worst, fabs(LSM_AT(now, i, 1) - (cx_of(now, i) - 0.25)));
    print_message("reinit dt (phi0 = %g SDF): dt %.6f -> %.6f, |phi - (x - 0.25)| <= %.2g\n", a,
                  dt0, lsm_morph_dt(m), worst);
    assert_true(worst < 1e-4);
    double dt_re;
    lsm_cfl_dt(now, tgt, LSM_SCHEME_UPWIND, 0.75, 1, &dt_re);
    if (c == 0) {
      /* the step of the reinitialised field, to its last bit ... */
      assert_close(lsm_morph_dt(m), dt_re, 0.0);
      /* ... which is 0.75 / 3.75 up to the reinitialisation's 1e-4 at x = -3.5 */
      assert_close(lsm_morph_dt(m), 0.2, 0.2 * 1e-4 / 3.75 * 1.01);
      assert_true(lsm_morph_dt(m) < dt0 / 4.5);
    } else {
      assert_true(dt_re > 2.5 * dt0);
      assert_close(lsm_morph_dt(m), dt0, 1e-6 * dt0);
    }
    /* the next step is that step */
    const double t1 = lsm_morph_time(m), dt1 = lsm_morph_dt(m);
    assert_int_equal(lsm_morph_step(m, INFINITY, &err), LSM_OK);
    assert_close(lsm_morph_time(m), t1 + dt1, 1e-12);
    lsm_grid_destroy(&now);
    lsm_morph_destroy(&m);
  }
  lsm_grid_destroy(&src);
  lsm_grid_destroy(&tgt);
}

/* A speed too large for floats (|F| / dx past 3.4e38): the CFL step is 0,
 * and no step could advance the morph; creating it fails with a numeric
 * error instead of a morph that never arrives. */
static void test_morph_step_zero(void **state) {
  (void)state;
  lsm_grid *src = new_grid(16, 16, 1e-3f, 1e-3f), *tgt = new_grid(16, 16, 1e-3f, 1e-3f);
  fill_linear(src, 1.0, 0.0, 0.0);
  fill_linear(tgt, 1.0, 0.0, -3e38);
  lsm_morph_opts o;
  lsm_morph_opts_default(&o);
  lsm_morph *m = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_morph_create(src, tgt, &o, &m, &err), LSM_ERR_NUMERIC);
  assert_null(m);
  assert_non_null(strstr(err.msg, "CFL time step"));
  lsm_grid_destroy(&src);
  lsm_grid_destroy(&tgt);
}

/* Identical slices: nothing can move (dt infinite), so every time is reached
 * at once, with no step, whatever max_iter allows. */
static void test_morph_at_rest(void **state) {
  (void)state;
  lsm_grid *src = new_grid(24, 24, 1.0f, 1.0f);
  fill_circle(src, 0, 0, 7.0, 1.0);
  lsm_morph_opts o;
  lsm_morph_opts_default(&o);
  lsm_morph *m = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_morph_create(src, src, &o, &m, &err), LSM_OK);
  assert_true(isinf(lsm_morph_dt(m)));
  const double times[] = {0.25, 0.7, 3.0};
  for (size_t k = 0; k < sizeof times / sizeof times[0]; ++k) {
    assert_int_equal(lsm_morph_advance_to(m, times[k], 1, &err), LSM_OK);
    assert_close(lsm_morph_time(m), times[k], 0.0);
  }
  assert_int_equal(lsm_morph_iterations(m), 0);
  assert_close(lsm_morph_cp(m), 0.0, 0.0);
  const lsm_grid *phi = lsm_morph_phi(m);
  assert_non_null(phi);
  assert_close(lsm_grid_diff_norm(phi, src, 1), 0.0, 0.0);
  lsm_morph_destroy(&m);
  lsm_grid_destroy(&src);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_reinit),
      cmocka_unit_test(test_reinit_tiny_pixels),
      cmocka_unit_test(test_reinit_cell_by_hand),
      cmocka_unit_test(test_reinit_one_step),
      cmocka_unit_test(test_morph_at_rest),
      cmocka_unit_test(test_morph_step_zero),
      cmocka_unit_test(test_time_of_fraction),
      cmocka_unit_test(test_morph_dt_and_landing),
      cmocka_unit_test(test_morph_cp_by_hand),
      cmocka_unit_test(test_morph_reinit_dt),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
