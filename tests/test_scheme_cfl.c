/* The morph solver in time: the CFL step (per-cell rates, flat phi, unequal
 * spacing), monotonicity of the schemes under it, the Euler / RK2 / RK3
 * integrators against each other and against a fine-step reference, and the
 * concentric circle morph against its analytic front with a convergence
 * check (upwind, Roe-Fix, WENO5).
 *
 * Reference facts (solver/README.md, sections 2 and 4):
 *   phi_t + F |grad phi| = 0,  F = phi - phi_target.
 *   For concentric circles phi_0 = |x| - r1, phi_T = |x| - r2, F = r2 - r1 is
 *   constant in space, phi stays a signed distance function, and the front is
 *   exactly r(t) = r2 + (r1 - r2) e^{-t}. */
#include "tests/lsm_test_scheme.h"

#include "kernels/lsm_cell.h"
#include "solver/base/lsm_grid.h"
#include "solver/pde/lsm_fields.h"
#include "solver/pde/lsm_morph.h"
#include "solver/pde/lsm_scheme.h"
#include "solver/sdf/lsm_sdf.h"
#include "solver/base/lsm_status.h"

/* One step of the integrator on phi, and `iterations` reinitialisation steps,
 * on the C backend through lsm_fields (as lsm_morph runs them). */
static void step_c(lsm_grid *phi, const lsm_grid *tgt, lsm_scheme scheme, lsm_time time, float dt) {
  lsm_fields *f = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_fields_create(NULL, phi, tgt, 1, &f, &err), LSM_OK);
  assert_int_equal(lsm_fields_step(f, scheme, time, dt, &err), LSM_OK);
  assert_int_equal(lsm_fields_download(f, phi, &err), LSM_OK);
  lsm_fields_destroy(&f);
}

/* ------------------------------------------------------------------------ */
/* CFL                                                                       */

/* rate = |F| max over (p, q) in {dxm, dxp} x {dym, dyp} of (|p|/dx + |q|/dy)/|(p,q)|. */
static void test_cfl(void **state) {
  (void)state;
  double dt;
  /* phi = x, dx = dy = 1, F = 2: p = 1, q = 0 -> rate = 2 * 1 -> dt = cfl / 2. */
  lsm_grid *phi = new_grid(16, 12, 1.0f, 1.0f), *tgt = new_grid(16, 12, 1.0f, 1.0f);
  fill_linear(phi, 1.0, 0.0, 0.0);
  fill_linear(tgt, 1.0, 0.0, -2.0);
  lsm_cfl_dt(phi, tgt, LSM_SCHEME_UPWIND, 0.75, 1, &dt);
  assert_close(dt, 0.75 / 2.0, 1e-6);
  lsm_cfl_dt(phi, tgt, LSM_SCHEME_UPWIND, 0.5, 2, &dt);
  assert_close(dt, 0.5 / 2.0, 1e-6);
  /* F = -2: same |F|. */
  fill_linear(tgt, 1.0, 0.0, 2.0);
  lsm_cfl_dt(phi, tgt, LSM_SCHEME_UPWIND, 0.75, 1, &dt);
  assert_close(dt, 0.75 / 2.0, 1e-6);
  /* phi == phi_target: no motion, dt = +inf. */
  lsm_grid_copy(tgt, phi);
  lsm_cfl_dt(phi, tgt, LSM_SCHEME_UPWIND, 0.75, 1, &dt);
  assert_true(isinf(dt) && dt > 0);
  lsm_grid_destroy(&phi);
  lsm_grid_destroy(&tgt);

  /* dx = dy = 0.5, phi = x: p = 1, rate = 2 / 0.5 = 4 -> dt = cfl / 4. */
  phi = new_grid(16, 12, 0.5f, 0.5f);
  tgt = new_grid(16, 12, 0.5f, 0.5f);
  fill_linear(phi, 1.0, 0.0, 0.0);
  fill_linear(tgt, 1.0, 0.0, -2.0);
  lsm_cfl_dt(phi, tgt, LSM_SCHEME_UPWIND, 0.75, 1, &dt);
  assert_close(dt, 0.75 / 4.0, 1e-6);
  lsm_grid_destroy(&phi);
  lsm_grid_destroy(&tgt);

  /* Anisotropic dx = 0.5, dy = 1, F = 2: the upwind rate is the bound over
   * all directions, |F| sqrt(1/dx^2 + 1/dy^2) = 2 sqrt 5, whatever phi's
   * gradient (the step is fixed from phi_0 and the front may turn; the
   * pairwise rate, (|p|/dx + |q|/dy)/|(p,q)|, stays the per-cell form it
   * bounds: 3/sqrt 2 for phi = x + y, 2 for x, 1 for y). */
  phi = new_grid(16, 12, 0.5f, 1.0f);
  tgt = new_grid(16, 12, 0.5f, 1.0f);
  const double axes[3][2] = {{1.0, 1.0}, {1.0, 0.0}, {0.0, 1.0}};
  for (int k = 0; k < 3; ++k) {
    fill_linear(phi, axes[k][0], axes[k][1], 0.0);
    fill_linear(tgt, axes[k][0], axes[k][1], -2.0);
    lsm_cfl_dt(phi, tgt, LSM_SCHEME_UPWIND, 0.75, 1, &dt);
    assert_close(dt, 0.75 / (2.0 * sqrt(5.0)), 1e-6);
  }
  assert_close(lsm_cfl_rate(2.0f, 1.0f, 1.0f, 1.0f, 1.0f, 2.0f, 1.0f), 2.0 * 3.0 / sqrt(2.0), 1e-5);
  assert_close(lsm_cfl_rate_of(0, 2.0f, 1.0f, 1.0f, 1.0f, 1.0f, 2.0f, 1.0f), 2.0 * sqrt(5.0), 1e-5);
  /* a flat cell still has rate 0 */
  assert_close(lsm_cfl_rate_of(0, 2.0f, 0.0f, 0.0f, 0.0f, 0.0f, 2.0f, 1.0f), 0.0, 0.0);
  lsm_grid_destroy(&phi);
  lsm_grid_destroy(&tgt);

  /* Per-cell rate on a kink: p in {-1, 1}, q in {0.5, 2}, dx = dy = 1, F = -3:
   * max over the four of (|p| + |q|)/|(p,q)| = (1 + 1... ) -> (1, 2): 3/sqrt5,
   * (1, 0.5): 1.5/sqrt1.25 = 1.3416; 3/sqrt5 = 1.3416 too; both equal. */
  assert_close(lsm_cfl_rate(-3.0f, -1.0f, 1.0f, 0.5f, 2.0f, 1.0f, 1.0f), 3.0 * 3.0 / sqrt(5.0),
               1e-5);
  /* Diagonal: (1,1) gives the maximum sqrt 2. */
  assert_close(lsm_cfl_rate(1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f), sqrt(2.0), 1e-6);
  /* Zero gradient: rate 0. */
  assert_close(lsm_cfl_rate(5.0f, 0.0f, 0.0f, 0.0f, 0.0f, 1.0f, 1.0f), 0.0, 0.0);
}

/* The upwind step under the CFL step of §3.4 is monotone for cfl <= 1: phi
 * never leaves the range of its previous values (the PDE's maximum
 * principle).  A one-cell peak and a one-cell pit, F = phi - 0 = +-1 there:
 * the sum form of Osher and Sethian took the peak to 1 - 0.75 * 2 / sqrt 2 =
 * -0.06 at cfl 0.75, below every neighbour. */
static void test_schemes_monotone(void **state) {
  (void)state;
  const float cfls[] = {0.75f, 0.99f};
  for (size_t c = 0; c < 2; ++c)
    for (int sign = -1; sign <= 1; sign += 2) {
      lsm_grid *phi = new_grid(9, 9, 1.0f, 1.0f), *tgt = new_grid(9, 9, 1.0f, 1.0f);
      lsm_grid *out = new_grid(9, 9, 1.0f, 1.0f);
      LSM_AT(phi, 4, 4) = (float)sign;
      double dt;
      lsm_cfl_dt(phi, tgt, LSM_SCHEME_UPWIND, cfls[c], 1, &dt);
      lsm_scheme_stage(LSM_SCHEME_UPWIND, out, phi, phi, tgt, 0.0f, 1.0f, (float)dt, 1);
      const double v = LSM_AT(out, 4, 4);
      if (!(sign > 0 ? v >= 0.0 && v <= 1.0 : v <= 0.0 && v >= -1.0))
        fail_msg("cfl %g, peak %+d: %g left [min, max] of the old values", cfls[c], sign, v);
      lsm_grid_destroy(&phi);
      lsm_grid_destroy(&tgt);
      lsm_grid_destroy(&out);
    }
  /* Both schemes: 1-px stripes into a small disc (masks, 40 x 40), the step
   * fixed from phi_0 as the morph fixes it, cfl 0.9, 200 Euler steps.  Roe-Fix
   * with the pairwise rate of the document's reading of §3.4 went from 0.5
   * to 35 at cfl 0.8 and to NaN at 0.85. */
  for (int sch = 0; sch < 2; ++sch) {
    const lsm_scheme scheme = sch ? LSM_SCHEME_ROEFIX : LSM_SCHEME_UPWIND;
    const int n = 40;
    lsm_mask stripes, disc;
    lsm_err err;
    lsm_err_clear(&err);
    assert_int_equal(lsm_mask_create(n, n, &stripes, &err), LSM_OK);
    assert_int_equal(lsm_mask_create(n, n, &disc, &err), LSM_OK);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        stripes.pixels[j * n + i] = i % 2 == 0;
        disc.pixels[j * n + i] = hypot(j - 32.0, i - 13.0) < 4.7;
      }
    lsm_grid *phi = new_grid(n, n, 1.0f, 1.0f), *tgt = new_grid(n, n, 1.0f, 1.0f);
    lsm_grid *out = new_grid(n, n, 1.0f, 1.0f);
    assert_int_equal(lsm_sdf_from_mask(&stripes, phi, &err), LSM_OK);
    assert_int_equal(lsm_sdf_from_mask(&disc, tgt, &err), LSM_OK);
    const float lo = lsm_grid_min(phi), hi = lsm_grid_max(phi);
    double dt;
    lsm_cfl_dt(phi, tgt, scheme, 0.9, 1, &dt);
    for (int step = 0; step < 200; ++step) {
      lsm_grid_fill_ghosts(phi);
      lsm_scheme_stage(scheme, out, phi, phi, tgt, 0.0f, 1.0f, (float)dt, 1);
      lsm_grid *t = phi;
      phi = out;
      out = t;
      if (!(lsm_grid_min(phi) >= lo - 1e-5f && lsm_grid_max(phi) <= hi + 1e-5f))
        fail_msg("%s, step %d: phi in [%g, %g], left [%g, %g]", lsm_scheme_name(scheme), step,
                 lsm_grid_min(phi), lsm_grid_max(phi), lo, hi);
    }
    lsm_mask_free(&stripes);
    lsm_mask_free(&disc);
    lsm_grid_destroy(&phi);
    lsm_grid_destroy(&tgt);
    lsm_grid_destroy(&out);
  }
}

/* A flat phi (an empty slice's constant far value) cannot move whatever F:
 * both schemes' CFL rates are 0 there, so the step is infinite (the morph is
 * at rest).  Roe-Fix's rate |F| (1/dx + 1/dy) counted F = 1e6 there and took
 * steps of 1e-6 until --max-iter. */
static void test_cfl_flat_phi(void **state) {
  (void)state;
  lsm_grid *phi = new_grid(30, 30, 1.0f, 1.0f), *tgt = new_grid(30, 30, 1.0f, 1.0f);
  for (int j = 0; j < 30; ++j)
    for (int i = 0; i < 30; ++i) LSM_AT(phi, i, j) = 1e6f;
  fill_circle(tgt, 0.0, 0.0, 6.0, 1.0);
  for (int sch = 0; sch < LSM_SCHEME_COUNT; ++sch) {
    const lsm_scheme scheme = (lsm_scheme)sch;
    double dt = 0.0;
    lsm_cfl_dt(phi, tgt, scheme, 0.75, 1, &dt);
    if (!isinf(dt)) fail_msg("%s: dt %g on a flat phi", lsm_scheme_name(scheme), dt);
  }
  lsm_grid_destroy(&phi);
  lsm_grid_destroy(&tgt);
}

/* Unequal spacing, the step fixed from phi_0 as the morph fixes it: an
 * 8-row band (its gradient along the coarse axis y, where the pairwise rate
 * is |F| / dy) morphing into a small disc in a corner; once the front turns,
 * the rate grows up to |F| sqrt(1/dx^2 + 1/dy^2).  With the pairwise rate
 * alone the upwind morph went non-finite at step 39 (dx = 1, dy = 4); with
 * the direction-free bound it stays within its slices' range, either way
 * round. */
static void test_upwind_unequal_spacing(void **state) {
  (void)state;
  const int n = 48;
  const float spacing[2][2] = {{1.0f, 4.0f}, {4.0f, 1.0f}};
  for (int c = 0; c < 2; ++c) {
    lsm_mask band, corner;
    lsm_err err;
    lsm_err_clear(&err);
    assert_int_equal(lsm_mask_create(n, n, &band, &err), LSM_OK);
    assert_int_equal(lsm_mask_create(n, n, &corner, &err), LSM_OK);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int along = c == 0 ? j : i; /* across the band: the coarse axis */
        band.pixels[j * n + i] = along >= 20 && along < 28;
        corner.pixels[j * n + i] = hypot(i - 5.0, j - 5.0) < 4.0;
      }
    lsm_grid *src = new_grid(n, n, spacing[c][0], spacing[c][1]);
    lsm_grid *tgt = new_grid(n, n, spacing[c][0], spacing[c][1]);
    assert_int_equal(lsm_sdf_from_mask(&band, src, &err), LSM_OK);
    assert_int_equal(lsm_sdf_from_mask(&corner, tgt, &err), LSM_OK);
    const float lo = fminf(lsm_grid_min(src), lsm_grid_min(tgt));
    const float hi = fmaxf(lsm_grid_max(src), lsm_grid_max(tgt));
    lsm_morph_opts o;
    lsm_morph_opts_default(&o);
    o.scheme = LSM_SCHEME_UPWIND;
    lsm_morph *m = NULL;
    assert_int_equal(lsm_morph_create(src, tgt, &o, &m, &err), LSM_OK);
    for (int step = 0; step < 600; ++step) {
      assert_int_equal(lsm_morph_step(m, INFINITY, &err), LSM_OK);
      const lsm_grid *phi = lsm_morph_phi(m);
      const float mn = lsm_grid_min(phi), mx = lsm_grid_max(phi);
      if (!(mn >= lo - 1e-3f && mx <= hi + 1e-3f))
        fail_msg("dx %g, dy %g, step %d: phi in [%g, %g], left [%g, %g]", spacing[c][0],
                 spacing[c][1], step, mn, mx, lo, hi);
    }
    lsm_morph_destroy(&m);
    lsm_mask_free(&band);
    lsm_mask_free(&corner);
    lsm_grid_destroy(&src);
    lsm_grid_destroy(&tgt);
  }
}

/* ------------------------------------------------------------------------ */
/* integrators                                                               */

/* One step from the circle SDF r1 = 20 toward r2 = 10 (F = -10 everywhere).
 * Away from the centre the upwind gradient is G ~ 1 and the semi-discrete
 * problem is the linear ODE u' = -G u for u = phi - phi_T, so
 *   Euler:  phi - dt F G
 *   RK2:    phi - dt F G + dt^2 F G^2 / 2      (+ O(dt^3): G varies in space)
 *   RK3:    phi - dt F G + dt^2 F G^2 / 2 - dt^3 F G^3 / 6.
 * So |Euler - RK2| = dt^2 |F| G^2 / 2 (halving dt divides it by 4) and
 * |RK2 - RK3| = O(dt^3) (divided by 8). */
static void test_integrators_agree(void **state) {
  (void)state;
  const int n = 64;
  lsm_grid *phi0 = new_grid(n, n, 1.0f, 1.0f), *tgt = new_grid(n, n, 1.0f, 1.0f);
  fill_circle(phi0, 0, 0, 20.0, 1.0);
  fill_circle(tgt, 0, 0, 10.0, 1.0);
  lsm_grid *e = NULL, *r2 = NULL, *r3 = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  double d12[2], d23[2];
  const float dts[2] = {0.04f, 0.02f};
  for (int s = 0; s < 2; ++s) {
    for (int sc = 0; sc < 2; ++sc) {
      const lsm_scheme scheme = sc ? LSM_SCHEME_ROEFIX : LSM_SCHEME_UPWIND;
      assert_int_equal(lsm_grid_clone(phi0, &e, &err), LSM_OK);
      assert_int_equal(lsm_grid_clone(phi0, &r2, &err), LSM_OK);
      assert_int_equal(lsm_grid_clone(phi0, &r3, &err), LSM_OK);
      step_c(e, tgt, scheme, LSM_TIME_EULER, dts[s]);
      step_c(r2, tgt, scheme, LSM_TIME_RK2, dts[s]);
      step_c(r3, tgt, scheme, LSM_TIME_RK3, dts[s]);
      /* Compare in an annulus 12 <= |x| <= 28 (smooth, away from the centre
       * kink and the boundary). */
      double m12 = 0, m23 = 0, m12min = INFINITY;
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const double rr = hypot(cx_of(phi0, i), cy_of(phi0, j));
          if (rr < 12 || rr > 28) continue;
          const double a = fabs((double)LSM_AT(e, i, j) - LSM_AT(r2, i, j));
          m12 = fmax(m12, a);
          m12min = fmin(m12min, a);
          m23 = fmax(m23, fabs((double)LSM_AT(r2, i, j) - LSM_AT(r3, i, j)));
        }
      /* dt^2 |F| G^2 / 2 with G in [0.85, 1.05] (one-sided differences of
       * a circle of radius >= 12 with dx = 1). */
      const double ref = 0.5 * dts[s] * dts[s] * 10.0;
      assert_true(m12 <= ref * 1.05 * 1.05 * 1.01);
      assert_true(m12min >= ref * 0.85 * 0.85 * 0.99);
      assert_true(m23 <= 0.2 * ref);
      if (sc == 0) d12[s] = m12, d23[s] = m23;
      lsm_grid_destroy(&e);
      lsm_grid_destroy(&r2);
      lsm_grid_destroy(&r3);
    }
  }
  /* Second-order agreement: halving dt divides Euler-RK2 by ~4. */
  assert_true(d12[0] / d12[1] > 3.5 && d12[0] / d12[1] < 4.5);
  /* RK2-RK3 is O(dt^3): halving dt divides it by 8 asymptotically; the values
   * are ~1e-4 and ~1e-5, so allow float round-off (values ~30: ulp 2e-6). */
  assert_true(d23[1] <= d23[0] / 4.0 + 2e-6);
  lsm_grid_destroy(&phi0);
  lsm_grid_destroy(&tgt);
}

/* ------------------------------------------------------------------------ */
/* concentric circles: analytic front                                        */

typedef struct circle_run {
  double err[3]; /* |front - exact| at t = 0.5, 1, 2 */
} circle_run;

static const double circle_times[3] = {0.5, 1.0, 2.0};

/* A square grid of side L = 64 (physical), n cells, centred. */
static circle_run run_circles(int n, double r1, double r2, lsm_scheme scheme, lsm_time time,
                              double cfl) {
  const float dx = (float)(64.0 / n);
  lsm_grid *src = new_grid(n, n, dx, dx), *tgt = new_grid(n, n, dx, dx);
  fill_circle(src, 0, 0, r1, 1.0);
  fill_circle(tgt, 0, 0, r2, 1.0);
  lsm_morph_opts o;
  lsm_morph_opts_default(&o);
  o.scheme = scheme;
  o.time = time;
  o.cfl = cfl;
  o.threads = 2;
  lsm_morph *m = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_morph_create(src, tgt, &o, &m, &err), LSM_OK);
  circle_run out;
  for (int k = 0; k < 3; ++k) {
    const double t = circle_times[k];
    assert_int_equal(lsm_morph_advance_to(m, t, 1000000, &err), LSM_OK);
    assert_close(lsm_morph_time(m), t, 1e-9);
    const double exact = r2 + (r1 - r2) * exp(-t);
    const double r = front_radius(lsm_morph_phi(m), 0, 0, exact, NULL, NULL);
    out.err[k] = fabs(r - exact);
  }
  lsm_morph_destroy(&m);
  lsm_grid_destroy(&src);
  lsm_grid_destroy(&tgt);
  return out;
}

static double max3(const double *v) { return fmax(v[0], fmax(v[1], v[2])); }

/* The measurement itself: the mean crossing radius of the exact SDF is the
 * radius (linear interpolation of a circle SDF along grid lines is accurate
 * to O(dx^2 / r)). */
static void test_front_measure(void **state) {
  (void)state;
  lsm_grid *g = new_grid(64, 64, 1.0f, 1.0f);
  for (double r = 10.0; r <= 25.0; r += 2.5) {
    fill_circle(g, 0, 0, r, 1.0);
    double dev;
    int n;
    assert_close(front_radius(g, 0, 0, r, &dev, &n), r, 0.02);
    assert_true(dev < 0.1);
    /* about 8 r crossings: 2 on each of the ~2r rows and ~2r columns */
    assert_true(n >= 8 * r - 8 && n <= 8 * r + 8);
  }
  lsm_grid_destroy(&g);
}

static void check_circle_convergence(lsm_scheme scheme, double r1, double r2) {
  const circle_run c1 = run_circles(64, r1, r2, scheme, LSM_TIME_EULER, 0.75);
  const circle_run c2 = run_circles(128, r1, r2, scheme, LSM_TIME_EULER, 0.75);
  print_message("circle %s %g->%g: dx=1 err %.4f %.4f %.4f | dx=0.5 err %.4f %.4f %.4f | "
                "ratio %.2f\n",
                lsm_scheme_name(scheme), r1, r2, c1.err[0], c1.err[1], c1.err[2], c2.err[0],
                c2.err[1], c2.err[2], max3(c1.err) / max3(c2.err));
  for (int k = 0; k < 3; ++k) {
    assert_true(c1.err[k] < 0.5);
    assert_true(c2.err[k] < 0.5);
  }
  /* First order: halving dx must cut the worst error by a clear factor. */
  assert_true(max3(c2.err) * 1.5 <= max3(c1.err));
}

static void test_circles_upwind(void **state) {
  (void)state;
  check_circle_convergence(LSM_SCHEME_UPWIND, 20.0, 10.0); /* shrink */
  check_circle_convergence(LSM_SCHEME_UPWIND, 10.0, 20.0); /* grow */
}

static void test_circles_roefix(void **state) {
  (void)state;
  check_circle_convergence(LSM_SCHEME_ROEFIX, 20.0, 10.0);
  check_circle_convergence(LSM_SCHEME_ROEFIX, 10.0, 20.0);
}

/* Concentric circles with WENO5 and RK3, dx = 2, 1, 1/2: the front error
 * falls at least like dx^1.7 (the front is located by linear interpolation
 * between cells, itself second order, so no more than about 2 shows), and at
 * dx = 1/2 it is a tenth of upwind's or less. */
static void test_circles_weno5(void **state) {
  (void)state;
  for (int c = 0; c < 2; ++c) {
    const double r1 = c ? 10.0 : 20.0, r2 = c ? 20.0 : 10.0;
    const circle_run w32 = run_circles(32, r1, r2, LSM_SCHEME_WENO5, LSM_TIME_RK3, 0.75);
    const circle_run w64 = run_circles(64, r1, r2, LSM_SCHEME_WENO5, LSM_TIME_RK3, 0.75);
    const circle_run w128 = run_circles(128, r1, r2, LSM_SCHEME_WENO5, LSM_TIME_RK3, 0.75);
    const circle_run u128 = run_circles(128, r1, r2, LSM_SCHEME_UPWIND, LSM_TIME_RK3, 0.75);
    const double o1 = log2(max3(w32.err) / max3(w64.err)), o2 = log2(max3(w64.err) / max3(w128.err));
    print_message("circle weno5/rk3 %g->%g: worst error %.2e %.2e %.2e (orders %.2f %.2f), "
                  "upwind/rk3 at dx=0.5 %.2e\n",
                  r1, r2, max3(w32.err), max3(w64.err), max3(w128.err), o1, o2, max3(u128.err));
    assert_true(o1 >= 1.7 && o2 >= 1.7);
    assert_true(max3(w128.err) <= 0.1 * max3(u128.err));
  }
}

/* Time accuracy.  Against a reference with a 20x smaller step (same grid,
 * so the spatial error cancels) RK3 at CFL 0.75 is closer than Euler at
 * CFL 0.75, whose time error is O(dt): the radius error of Euler at t is
 * (r1 - r2) e^{-t} t dt / 2 to first order (0.13 px at t = 1, dt = 0.053).
 * Against the exact solution, RK3 is not worse than Euler beyond the spatial
 * error's share (both have the same spatial error). */
static void test_integrators_circle(void **state) {
  (void)state;
  const double r1 = 20.0, r2 = 10.0;
  const circle_run e = run_circles(64, r1, r2, LSM_SCHEME_UPWIND, LSM_TIME_EULER, 0.75);
  const circle_run r2k = run_circles(64, r1, r2, LSM_SCHEME_UPWIND, LSM_TIME_RK2, 0.75);
  const circle_run r3 = run_circles(64, r1, r2, LSM_SCHEME_UPWIND, LSM_TIME_RK3, 0.75);
  print_message("circle vs exact: euler %.4f %.4f %.4f | rk2 %.4f %.4f %.4f | rk3 %.4f %.4f "
                "%.4f\n",
                e.err[0], e.err[1], e.err[2], r2k.err[0], r2k.err[1], r2k.err[2], r3.err[0],
                r3.err[1], r3.err[2]);
  for (int k = 0; k < 3; ++k) {
    assert_true(r3.err[k] < 0.5);
    assert_true(r2k.err[k] < 0.5);
  }
  assert_true(max3(r3.err) <= max3(e.err) + 1e-3);

  /* Time error alone: signed radii against a small-step reference. */
  const int n = 64;
  lsm_grid *src = new_grid(n, n, 1.0f, 1.0f), *tgt = new_grid(n, n, 1.0f, 1.0f);
  fill_circle(src, 0, 0, r1, 1.0);
  fill_circle(tgt, 0, 0, r2, 1.0);
  double rad[4];
  const lsm_time times[4] = {LSM_TIME_EULER, LSM_TIME_RK2, LSM_TIME_RK3, LSM_TIME_RK3};
  const double cfls[4] = {0.75, 0.75, 0.75, 0.0375};
  double dt_euler = 0;
  for (int k = 0; k < 4; ++k) {
    lsm_morph_opts o;
    lsm_morph_opts_default(&o);
    o.time = times[k];
    o.cfl = cfls[k];
    lsm_morph *m = NULL;
    lsm_err err;
    lsm_err_clear(&err);
    assert_int_equal(lsm_morph_create(src, tgt, &o, &m, &err), LSM_OK);
    if (k == 0) dt_euler = lsm_morph_dt(m);
    assert_int_equal(lsm_morph_advance_to(m, 1.0, 1000000, &err), LSM_OK);
    rad[k] = front_radius(lsm_morph_phi(m), 0, 0, 0, NULL, NULL);
    lsm_morph_destroy(&m);
  }
  const double te = fabs(rad[0] - rad[3]), t2 = fabs(rad[1] - rad[3]), t3 = fabs(rad[2] - rad[3]);
  print_message("time error at t=1 (dt %.4f): euler %.4f rk2 %.5f rk3 %.5f\n", dt_euler, te, t2,
                t3);
  /* Euler's predicted first-order error, within 40 %. */
  const double pred = (r1 - r2) * exp(-1.0) * 1.0 * dt_euler / 2.0;
  assert_true(te > 0.6 * pred && te < 1.4 * pred);
  assert_true(t2 < 0.25 * te);
  assert_true(t3 < 0.25 * te);
  lsm_grid_destroy(&src);
  lsm_grid_destroy(&tgt);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_cfl),
      cmocka_unit_test(test_schemes_monotone),
      cmocka_unit_test(test_cfl_flat_phi),
      cmocka_unit_test(test_upwind_unequal_spacing),
      cmocka_unit_test(test_integrators_agree),
      cmocka_unit_test(test_front_measure),
      cmocka_unit_test(test_circles_upwind),
      cmocka_unit_test(test_circles_roefix),
      cmocka_unit_test(test_circles_weno5),
      cmocka_unit_test(test_integrators_circle),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
