/* Numerical tests of the morph solver: per-cell Hamiltonians (upwind,
 * Roe-Fix branches), CFL step, one grid stage, the integrators, the concentric
 * circle morph against its analytic solution (with a convergence check),
 * reinitialisation, and the fraction -> time map.
 *
 * Reference facts (solver/README.md, sections 2 and 4):
 *   phi_t + F |grad phi| = 0,  F = phi - phi_target.
 *   For concentric circles phi_0 = |x| - r1, phi_T = |x| - r2, F = r2 - r1 is
 *   constant in space, phi stays a signed distance function, and the front is
 *   exactly r(t) = r2 + (r1 - r2) e^{-t}. */
#include "tests/lsm_test.h"

#include "kernels/lsm_cell.h"
#include "solver/base/lsm_grid.h"
#include "solver/pde/lsm_fields.h"
#include "solver/pde/lsm_morph.h"
#include "solver/pde/lsm_scheme.h"
#include "solver/sdf/lsm_sdf.h"
#include "solver/base/lsm_status.h"

/* ------------------------------------------------------------------------ */
/* helpers                                                                   */

static lsm_grid *new_grid(int nx, int ny, float dx, float dy) {
  lsm_grid *g = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_grid_create(nx, ny, dx, dy, &g, &err), LSM_OK);
  assert_non_null(g);
  return g;
}

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

static void reinit_c(lsm_grid *phi, int iterations) {
  lsm_fields *f = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_fields_create(NULL, phi, phi, 1, &f, &err), LSM_OK);
  assert_int_equal(lsm_fields_reinit(f, iterations, &err), LSM_OK);
  assert_int_equal(lsm_fields_download(f, phi, &err), LSM_OK);
  lsm_fields_destroy(&f);
}

/* Physical coordinates of cell centres, the grid centred on the origin. */
static double cx_of(const lsm_grid *g, int i) { return (i + 0.5) * g->dx - 0.5 * g->nx * g->dx; }
static double cy_of(const lsm_grid *g, int j) { return (j + 0.5) * g->dy - 0.5 * g->ny * g->dy; }

/* phi = scale * (|x - c| - r), analytic (not through the EDT). */
static void fill_circle(lsm_grid *g, double x0, double y0, double r, double scale) {
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i < g->nx; ++i)
      LSM_AT(g, i, j) = (float)(scale * (hypot(cx_of(g, i) - x0, cy_of(g, j) - y0) - r));
  lsm_grid_fill_ghosts(g);
}

/* phi = a x + b y + off. */
static void fill_linear(lsm_grid *g, double a, double b, double off) {
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i < g->nx; ++i)
      LSM_AT(g, i, j) = (float)(a * cx_of(g, i) + b * cy_of(g, j) + off);
  lsm_grid_fill_ghosts(g);
}

/* Zero crossings of phi along every grid row and column, located by linear
 * interpolation between the two cells that straddle it.  Returns the mean
 * distance of the crossings from (x0, y0) and, in *maxdev, the largest
 * |distance - r_ref|; *count gets the number of crossings. */
static double front_radius(const lsm_grid *g, double x0, double y0, double r_ref, double *maxdev,
                           int *count) {
  double sum = 0.0, dev = 0.0;
  int n = 0;
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i + 1 < g->nx; ++i) {
      const double a = LSM_AT(g, i, j), b = LSM_AT(g, i + 1, j);
      if ((a <= 0.0) == (b <= 0.0)) continue;
      const double x = cx_of(g, i) + g->dx * a / (a - b), y = cy_of(g, j);
      const double r = hypot(x - x0, y - y0);
      sum += r;
      dev = fmax(dev, fabs(r - r_ref));
      ++n;
    }
  for (int i = 0; i < g->nx; ++i)
    for (int j = 0; j + 1 < g->ny; ++j) {
      const double a = LSM_AT(g, i, j), b = LSM_AT(g, i, j + 1);
      if ((a <= 0.0) == (b <= 0.0)) continue;
      const double x = cx_of(g, i), y = cy_of(g, j) + g->dy * a / (a - b);
      const double r = hypot(x - x0, y - y0);
      sum += r;
      dev = fmax(dev, fabs(r - r_ref));
      ++n;
    }
  if (maxdev) *maxdev = dev;
  if (count) *count = n;
  assert_true(n > 0);
  return sum / n;
}

static double max_abs_diff(const lsm_grid *a, const lsm_grid *b) {
  double m = 0.0;
  for (int j = 0; j < a->ny; ++j)
    for (int i = 0; i < a->nx; ++i) m = fmax(m, fabs((double)LSM_AT(a, i, j) - LSM_AT(b, i, j)));
  return m;
}

static double urand(uint64_t *s, double lo, double hi) {
  return lo + (hi - lo) * (double)(lsm_test_rand(s) >> 11) * (1.0 / 9007199254740992.0);
}

/* ------------------------------------------------------------------------ */
/* upwind Hamiltonian                                                         */

/* Linear phi: both one-sided differences equal, so every upwind selection
 * gives |grad phi| = sqrt(a^2 + b^2) and H = F sqrt(a^2 + b^2). */
static void test_upwind_linear(void **state) {
  (void)state;
  const float ab[][2] = {{0.6f, 0.8f}, {-0.6f, 0.8f}, {0.6f, -0.8f}, {-3.0f, -4.0f},
                         {1.0f, 0.0f}, {0.0f, -2.5f}, {0.0f, 0.0f}};
  const float Fs[] = {2.0f, 0.5f, -1.5f, -7.0f};
  for (size_t k = 0; k < sizeof ab / sizeof ab[0]; ++k)
    for (size_t f = 0; f < sizeof Fs / sizeof Fs[0]; ++f) {
      const float a = ab[k][0], b = ab[k][1], F = Fs[f];
      const double want = F * sqrt((double)a * a + (double)b * b);
      assert_close(lsm_upwind_hamiltonian(F, a, a, b, b), want, 1e-6 * (1 + fabs(want)));
    }
  /* F = 0: no motion whatever the gradient. */
  assert_close(lsm_upwind_hamiltonian(0.0f, -1.0f, 2.0f, 3.0f, -4.0f), 0.0, 0.0);
}

/* Kinks.  Godunov (Rouy–Tourin), per axis the larger upwind slope:
 *   F > 0: |grad|^2 = max(max(dxm,0)^2, min(dxp,0)^2) + the same in y
 *   F < 0: |grad|^2 = max(min(dxm,0)^2, max(dxp,0)^2) + the same in y
 * V-shaped minimum in x (dxm < 0 < dxp), flat in y:
 *   F > 0 (phi decreasing, the minimum is an outflow point): every term is 0,
 *         so the upwind gradient is 0 and H = 0.
 *   F < 0: both sides are upwind, |grad|^2 = max(dxm^2, dxp^2) (Osher and
 *         Sethian's 1988 sum dxm^2 + dxp^2 would move the kink faster than
 *         the steeper side's characteristic: not monotone).
 * A Λ-shaped maximum (dxm > 0 > dxp) is the mirror image. */
static void test_upwind_kinks(void **state) {
  (void)state;
  /* V minimum, asymmetric slopes. */
  const float dxm = -1.5f, dxp = 0.5f;
  assert_close(lsm_upwind_hamiltonian(2.0f, dxm, dxp, 0.0f, 0.0f), 0.0, 0.0);
  const double vneg = lsm_upwind_hamiltonian(-2.0f, dxm, dxp, 0.0f, 0.0f);
  assert_close(vneg, -2.0 * 1.5, 1e-6);
  /* Λ maximum: the mirror image. */
  assert_close(lsm_upwind_hamiltonian(-2.0f, 1.5f, -0.5f, 0.0f, 0.0f), 0.0, 0.0);
  assert_close(lsm_upwind_hamiltonian(2.0f, 1.5f, -0.5f, 0.0f, 0.0f), 2.0 * 1.5, 1e-6);
  assert_close(lsm_upwind_hamiltonian(2.0f, 0.5f, -1.5f, 0.0f, 0.0f), 2.0 * 1.5, 1e-6);
  /* V in x, linear in y (slope 0.75): F > 0 keeps only the y part. */
  assert_close(lsm_upwind_hamiltonian(3.0f, dxm, dxp, 0.75f, 0.75f), 3.0 * 0.75, 1e-6);
  assert_close(lsm_upwind_hamiltonian(-3.0f, dxm, dxp, 0.75f, 0.75f),
               -3.0 * sqrt(1.5 * 1.5 + 0.75 * 0.75), 1e-6);
  /* Cone minimum (centre of a disc's SDF, dx = dy = 1): V in both axes. */
  assert_close(lsm_upwind_hamiltonian(1.0f, -1.0f, 1.0f, -1.0f, 1.0f), 0.0, 0.0);
  assert_close(lsm_upwind_hamiltonian(-1.0f, -1.0f, 1.0f, -1.0f, 1.0f), -sqrt(2.0), 1e-6);
  /* One-sided slope choice away from kinks: phi increasing in x with different
   * slopes on each side: F > 0 takes the backward difference, F < 0 the forward. */
  assert_close(lsm_upwind_hamiltonian(1.0f, 0.5f, 2.0f, 0.0f, 0.0f), 0.5, 1e-6);
  assert_close(lsm_upwind_hamiltonian(-1.0f, 0.5f, 2.0f, 0.0f, 0.0f), -2.0, 1e-6);
  /* Decreasing in x: F > 0 takes the forward difference, F < 0 the backward. */
  assert_close(lsm_upwind_hamiltonian(1.0f, -0.5f, -2.0f, 0.0f, 0.0f), 2.0, 1e-6);
  assert_close(lsm_upwind_hamiltonian(-1.0f, -0.5f, -2.0f, 0.0f, 0.0f), -0.5, 1e-6);
}

/* ------------------------------------------------------------------------ */
/* one grid stage with constant F                                           */

/* phi = a x + b y (+ offset), phi_target = phi - c, so F = c everywhere and
 * every interior stencil is linear: out = phi - dt c sqrt(a^2 + b^2).  The
 * boundary cells see the zero-gradient ghosts and are excluded (1 cell for
 * upwind; Roe-Fix too, its narrow sets are one-signed for linear data). */
static void check_constant_speed(lsm_scheme scheme, double a, double b, double c, float dx,
                                 float dy) {
  const int nx = 24, ny = 19;
  lsm_grid *phi = new_grid(nx, ny, dx, dy), *tgt = new_grid(nx, ny, dx, dy);
  lsm_grid *out = new_grid(nx, ny, dx, dy);
  fill_linear(phi, a, b, 0.3);
  fill_linear(tgt, a, b, 0.3 - c);
  const float dt = 0.05f;
  lsm_scheme_stage(scheme, out, phi, phi, tgt, 0.0f, 1.0f, dt, 1);
  const double g = sqrt(a * a + b * b);
  int checked = 0;
  for (int j = 1; j + 1 < ny; ++j)
    for (int i = 1; i + 1 < nx; ++i) {
      /* F is computed in float as phi - (phi - c): allow its rounding. */
      const double want = LSM_AT(phi, i, j) - dt * c * g;
      assert_close(LSM_AT(out, i, j), want, 2e-5 * (1.0 + fabs(want)));
      ++checked;
    }
  assert_int_equal(checked, (nx - 2) * (ny - 2));
  /* Shu–Osher combination: out = c0 u0 + c1 (in - dt H). */
  lsm_scheme_stage(scheme, out, tgt, phi, tgt, 0.25f, 0.75f, dt, 1);
  for (int j = 1; j + 1 < ny; ++j)
    for (int i = 1; i + 1 < nx; ++i) {
      const double want =
          0.25 * LSM_AT(tgt, i, j) + 0.75 * (LSM_AT(phi, i, j) - dt * c * g);
      assert_close(LSM_AT(out, i, j), want, 2e-5 * (1.0 + fabs(want)));
    }
  lsm_grid_destroy(&phi);
  lsm_grid_destroy(&tgt);
  lsm_grid_destroy(&out);
}

static void test_stage_constant_speed(void **state) {
  (void)state;
  for (int s = 0; s < 2; ++s) {
    const lsm_scheme scheme = s ? LSM_SCHEME_ROEFIX : LSM_SCHEME_UPWIND;
    check_constant_speed(scheme, 0.7, 0.0, 2.0, 1.0f, 1.0f);   /* linear in x, F > 0 */
    check_constant_speed(scheme, -1.3, 0.0, 2.0, 1.0f, 1.0f);  /* decreasing, F > 0 */
    check_constant_speed(scheme, 0.7, 0.0, -1.5, 1.0f, 1.0f);  /* F < 0 */
    check_constant_speed(scheme, -1.3, 0.0, -1.5, 0.5f, 0.5f); /* F < 0, dx = 0.5 */
    check_constant_speed(scheme, 0.6, -0.8, 3.0, 0.5f, 1.25f); /* oblique, anisotropic */
    check_constant_speed(scheme, -0.6, 0.8, -3.0, 1.0f, 0.5f);
  }
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

/* ------------------------------------------------------------------------ */
/* Roe-Fix                                                                   */

/* Algorithm 3.1 (Roe-Fix: solver/README.md, section 4) written out directly, in double.
 * Returns Hhat; *branch gets the LSM_ROEFIX_* code. */
static void signs_h1(double F, const double *P, int np, const double *Q, int nq, int *pos,
                     int *neg, double *mx) {
  *pos = *neg = 0;
  *mx = 0.0;
  for (int a = 0; a < np; ++a)
    for (int b = 0; b < nq; ++b) {
      const double g = sqrt(P[a] * P[a] + Q[b] * Q[b]);
      const double h = g > 0 ? F * P[a] / g : 0.0;
      if (h > 0) *pos = 1;
      if (h < 0) *neg = 1;
      *mx = fmax(*mx, fabs(h));
    }
}

static double roefix_reference(double F, const float *xm, const float *xp, const float *ym,
                               const float *yp, int *branch) {
  const double Ix[2] = {xm[3], xp[3]}, Iy[2] = {ym[3], yp[3]};
  double Ixw[14], Iyw[14];
  for (int k = 0; k < 7; ++k) {
    Ixw[2 * k] = xm[k];
    Ixw[2 * k + 1] = xp[k];
    Iyw[2 * k] = ym[k];
    Iyw[2 * k + 1] = yp[k];
  }
  int p1, n1, p2, n2;
  double m1, m2;
  signs_h1(F, Ix, 2, Iy, 2, &p1, &n1, &m1); /* H1 = F p/|.| over I_x x I_y */
  signs_h1(F, Iy, 2, Ix, 2, &p2, &n2, &m2); /* H2 = F q/|.| over I_x x I_y */
  double px, py, ax = 0.0, ay = 0.0;
  if (!(p1 && n1) && !(p2 && n2)) {
    px = p1 ? Ix[0] : Ix[1];
    py = p2 ? Iy[0] : Iy[1];
    *branch = LSM_ROEFIX_UPWIND;
  } else {
    signs_h1(F, Ix, 2, Iyw, 14, &p1, &n1, &m1); /* H1 over I_x x I_y_new */
    signs_h1(F, Iy, 2, Ixw, 14, &p2, &n2, &m2); /* H2 over I_x_new x I_y */
    const int one1 = !(p1 && n1), one2 = !(p2 && n2);
    if (one1 && !one2) {
      px = p1 ? Ix[0] : Ix[1];
      py = 0.5 * (Iy[0] + Iy[1]);
      ay = m2;
      *branch = LSM_ROEFIX_LLF_Y;
    } else if (!one1 && one2) {
      px = 0.5 * (Ix[0] + Ix[1]);
      py = p2 ? Iy[0] : Iy[1];
      ax = m1;
      *branch = LSM_ROEFIX_LLF_X;
    } else {
      /* For H = F|grad|, sign(H1) = sign(F p) whatever q is, so widening in y
       * cannot make H1 one-signed: "neither" is the only case left. */
      assert_true(!one1 && !one2);
      px = 0.5 * (Ix[0] + Ix[1]);
      py = 0.5 * (Iy[0] + Iy[1]);
      ax = m1;
      ay = m2;
      *branch = LSM_ROEFIX_LLF_XY;
    }
  }
  return F * sqrt(px * px + py * py) - ax * 0.5 * (Ix[1] - Ix[0]) - ay * 0.5 * (Iy[1] - Iy[0]);
}

static void fill7(float *v, float value) {
  for (int k = 0; k < 7; ++k) v[k] = value;
}

/* Hand-built stencils for each branch, Hhat computed by hand. */
static void test_roefix_branches(void **state) {
  (void)state;
  float xm[7], xp[7], ym[7], yp[7];
  int br = -1;
  double h;

  /* 1. UPWIND, smooth but not linear: all p > 0, all q > 0.
   *    F = 2 > 0: H1, H2 > 0 -> phi_x* = xm = 0.5, phi_y* = ym = 0.2.
   *    Hhat = 2 sqrt(0.25 + 0.04). */
  fill7(xm, 9.0f), fill7(xp, -9.0f), fill7(ym, 9.0f), fill7(yp, -9.0f); /* never read */
  xm[3] = 0.5f, xp[3] = 1.0f, ym[3] = 0.2f, yp[3] = 0.4f;
  h = lsm_roefix_hamiltonian_ex(2.0f, xm, xp, ym, yp, &br);
  assert_int_equal(br, LSM_ROEFIX_UPWIND);
  assert_close(h, 2.0 * sqrt(0.29), 1e-6);
  /*    F = -2: H1, H2 < 0 -> phi_x* = xp = 1, phi_y* = yp = 0.4. */
  h = lsm_roefix_hamiltonian_ex(-2.0f, xm, xp, ym, yp, &br);
  assert_int_equal(br, LSM_ROEFIX_UPWIND);
  assert_close(h, -2.0 * sqrt(1.16), 1e-6);
  /*    Zero differences count as one-signed: p = 0 on one side. */
  xm[3] = 0.0f, xp[3] = 0.8f, ym[3] = 0.6f, yp[3] = 0.6f;
  h = lsm_roefix_hamiltonian_ex(1.0f, xm, xp, ym, yp, &br);
  assert_int_equal(br, LSM_ROEFIX_UPWIND);
  /*    H1 >= 0 over the set and positive somewhere -> phi_x* = xm = 0. */
  assert_close(h, 0.6, 1e-6);

  /* 2. LLF_X: V minimum in x (xm = -1, xp = 1), q > 0 everywhere (H2 one-signed),
   *    F = 1.  Widened I_y_new = {0.5 at the centre, 0.1 .. 2.0 elsewhere}.
   *    phi_x* = mean = 0, phi_y* = ym = 0.5 (H2 > 0),
   *    alpha_x = max |p|/|(p,q)| over p in {-1,1}, q in I_y_new = 1/sqrt(1 + 0.1^2)
   *    (smallest |q| = 0.1),
   *    Hhat = 1 * sqrt(0 + 0.25) - alpha_x (1 - (-1))/2 = 0.5 - 1/sqrt(1.01). */
  fill7(xm, 0.3f), fill7(xp, 0.3f);
  const float qs[7] = {2.0f, 0.7f, 0.1f, 0.5f, 1.1f, 0.9f, 1.5f};
  for (int k = 0; k < 7; ++k) ym[k] = qs[k], yp[k] = qs[k] + 0.05f;
  xm[3] = -1.0f, xp[3] = 1.0f, ym[3] = 0.5f, yp[3] = 0.5f;
  h = lsm_roefix_hamiltonian_ex(1.0f, xm, xp, ym, yp, &br);
  assert_int_equal(br, LSM_ROEFIX_LLF_X);
  assert_close(h, 0.5 - 1.0 / sqrt(1.01), 1e-6);

  /* 3. LLF_Y: the transpose, with F = 2: xm = xp = 0.5, ym = -1, yp = 1,
   *    smallest |p| in I_x_new is 0.1 -> alpha_y = 2/sqrt(1.01),
   *    phi_x* = xm = 0.5 (H1 > 0), phi_y* = 0,
   *    Hhat = 2 * 0.5 - alpha_y (1 - (-1))/2 = 1 - 2/sqrt(1.01). */
  fill7(ym, 0.3f), fill7(yp, 0.3f);
  for (int k = 0; k < 7; ++k) xm[k] = qs[k], xp[k] = qs[k] + 0.05f;
  xm[3] = 0.5f, xp[3] = 0.5f, ym[3] = -1.0f, yp[3] = 1.0f;
  h = lsm_roefix_hamiltonian_ex(2.0f, xm, xp, ym, yp, &br);
  assert_int_equal(br, LSM_ROEFIX_LLF_Y);
  assert_close(h, 1.0 - 2.0 / sqrt(1.01), 1e-6);

  /* 4. LLF_XY: F = -1.5, xm = -1, xp = 2 (V in x), ym = 1, yp = -0.5 (Λ in y).
   *    Both H1 and H2 change sign.  phi_x* = 0.5, phi_y* = 0.25.
   *    I_y_new: {1, -0.5} and the others with smallest |q| = 0.25 ->
   *      alpha_x = 1.5 * 2 / sqrt(4 + 0.0625)  (p = 2, q = 0.25);
   *    I_x_new: {-1, 2} and the others with smallest |p| = 0.5 ->
   *      alpha_y = 1.5 * 1 / sqrt(0.25 + 1)     (p = 0.5, q = 1).
   *    Hhat = -1.5 sqrt(0.25 + 0.0625) - alpha_x (2 - (-1))/2 - alpha_y (-0.5 - 1)/2. */
  {
    const float xo[7] = {0.9f, -1.2f, 0.5f, 0.0f, 1.7f, -0.6f, 3.0f};
    const float yo[7] = {0.6f, -0.8f, 1.4f, 0.0f, -0.25f, 0.3f, -2.0f};
    for (int k = 0; k < 7; ++k) xm[k] = xo[k], xp[k] = -xo[k], ym[k] = yo[k], yp[k] = -yo[k];
    xm[3] = -1.0f, xp[3] = 2.0f, ym[3] = 1.0f, yp[3] = -0.5f;
    const double ax = 1.5 * 2.0 / sqrt(4.0 + 0.0625), ay = 1.5 / sqrt(1.25);
    const double want = -1.5 * sqrt(0.3125) - ax * 1.5 - ay * (-0.75);
    h = lsm_roefix_hamiltonian_ex(-1.5f, xm, xp, ym, yp, &br);
    assert_int_equal(br, LSM_ROEFIX_LLF_XY);
    assert_close(h, want, 1e-5);
  }

  /* The wrapper returns the same value. */
  assert_close(lsm_roefix_hamiltonian(-1.5f, xm, xp, ym, yp), h, 0.0);
}

/* Random stencils: the kernel agrees with the reference implementation of the
 * algorithm above, branch and value, and every branch is visited. */
static void test_roefix_random_vs_reference(void **state) {
  (void)state;
  uint64_t rng = 0xC0FFEE123ull;
  int seen[4] = {0, 0, 0, 0};
  for (int c = 0; c < 20000; ++c) {
    float xm[7], xp[7], ym[7], yp[7];
    for (int k = 0; k < 7; ++k) {
      xm[k] = (float)urand(&rng, -2, 2);
      xp[k] = (float)urand(&rng, -2, 2);
      ym[k] = (float)urand(&rng, -2, 2);
      yp[k] = (float)urand(&rng, -2, 2);
    }
    if (c % 4 == 1) xp[3] = xm[3] * (float)urand(&rng, 0.1, 3.0); /* x one-signed */
    if (c % 4 == 2) yp[3] = ym[3] * (float)urand(&rng, 0.1, 3.0); /* y one-signed */
    const float F = (float)urand(&rng, -5, 5);
    int b1 = -1, b2 = -2;
    const double got = lsm_roefix_hamiltonian_ex(F, xm, xp, ym, yp, &b1);
    const double want = roefix_reference(F, xm, xp, ym, yp, &b2);
    assert_int_equal(b1, b2);
    assert_close(got, want, 2e-5 * (1.0 + fabs(want)));
    seen[b1]++;
  }
  for (int b = 0; b < 4; ++b) assert_true(seen[b] > 100);
}

/* Linear data (all differences equal): Roe-Fix is pure upwind and equals the
 * Godunov upwind Hamiltonian, F sqrt(a^2 + b^2). */
static void test_roefix_linear_equals_upwind(void **state) {
  (void)state;
  uint64_t rng = 42;
  for (int c = 0; c < 2000; ++c) {
    float xm[7], xp[7], ym[7], yp[7];
    const float a = (float)urand(&rng, -3, 3), b = (float)urand(&rng, -3, 3);
    const float F = (float)urand(&rng, -4, 4);
    fill7(xm, a), fill7(xp, a), fill7(ym, b), fill7(yp, b);
    int br = -1;
    const double r = lsm_roefix_hamiltonian_ex(F, xm, xp, ym, yp, &br);
    assert_int_equal(br, LSM_ROEFIX_UPWIND);
    assert_close(r, lsm_upwind_hamiltonian(F, a, a, b, b), 1e-5 * (1 + fabs(r)));
    assert_close(r, F * sqrt((double)a * a + (double)b * b), 1e-5 * (1 + fabs(r)));
  }
  /* And whole grid stages agree on a linear field (interior). */
  lsm_grid *phi = new_grid(20, 20, 1.0f, 1.0f), *tgt = new_grid(20, 20, 1.0f, 1.0f);
  lsm_grid *o1 = new_grid(20, 20, 1.0f, 1.0f), *o2 = new_grid(20, 20, 1.0f, 1.0f);
  fill_linear(phi, 0.3, -1.1, 0.0);
  fill_circle(tgt, 2.0, 3.0, 5.0, 1.0); /* F varies in space, sign too */
  lsm_scheme_stage(LSM_SCHEME_UPWIND, o1, phi, phi, tgt, 0.0f, 1.0f, 0.1f, 1);
  lsm_scheme_stage(LSM_SCHEME_ROEFIX, o2, phi, phi, tgt, 0.0f, 1.0f, 0.1f, 1);
  for (int j = 1; j < 19; ++j)
    for (int i = 1; i < 19; ++i) assert_close(LSM_AT(o1, i, j), LSM_AT(o2, i, j), 1e-5);
  lsm_grid_destroy(&phi);
  lsm_grid_destroy(&tgt);
  lsm_grid_destroy(&o1);
  lsm_grid_destroy(&o2);
}

/* The fields of the stage tests, nx x ny cells of dx x dy: phi the distance
 * to the union of two discs (kinks along the bisector and at the centres),
 * the target a third disc's, and an output grid. */
static void two_disc_fields(int nx, int ny, float dx, float dy, lsm_grid **phi, lsm_grid **tgt,
                            lsm_grid **out) {
  *phi = new_grid(nx, ny, dx, dy);
  *tgt = new_grid(nx, ny, dx, dy);
  *out = new_grid(nx, ny, dx, dy);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double x = cx_of(*phi, i), y = cy_of(*phi, j);
      LSM_AT(*phi, i, j) =
          (float)fmin(hypot(x - 5.2, y - 1.3) - 6.0, hypot(x + 7.9, y + 2.2) - 4.5);
      LSM_AT(*tgt, i, j) = (float)(hypot(x - 1.0, y + 0.7) - 9.0);
    }
}

/* Grid stages against per-cell references assembled here from the stencil
 * (checks the stencil gathering: offsets, strides, ghost cells, dx != dy).
 * Field: the distance to the union of two discs (kinks along the bisector
 * and at the centres), target a third disc, so every Roe-Fix branch occurs. */
static void test_stage_vs_cell_reference(void **state) {
  (void)state;
  const int nx = 40, ny = 33;
  const float dx = 0.8f, dy = 1.1f;
  lsm_grid *phi = NULL, *tgt = NULL, *out = NULL;
  two_disc_fields(nx, ny, dx, dy, &phi, &tgt, &out);
  const float dt = 0.07f;
  int seen[4] = {0, 0, 0, 0};
  for (int sc = 0; sc < 2; ++sc) {
    lsm_scheme_stage(sc ? LSM_SCHEME_ROEFIX : LSM_SCHEME_UPWIND, out, phi, phi, tgt, 0.0f, 1.0f,
                     dt, 2);
    lsm_grid_fill_ghosts(phi); /* zero-gradient, as the stage does */
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const double F = (double)LSM_AT(phi, i, j) - LSM_AT(tgt, i, j);
        double H;
        if (!sc) {
          H = lsm_upwind_hamiltonian((float)F, (LSM_AT(phi, i, j) - LSM_AT(phi, i - 1, j)) / dx,
                                     (LSM_AT(phi, i + 1, j) - LSM_AT(phi, i, j)) / dx,
                                     (LSM_AT(phi, i, j) - LSM_AT(phi, i, j - 1)) / dy,
                                     (LSM_AT(phi, i, j + 1) - LSM_AT(phi, i, j)) / dy);
        } else {
          float xm[7], xp[7], ym[7], yp[7];
          for (int k = 0; k < 7; ++k) {
            const int d = k - 3;
            xm[k] = (LSM_AT(phi, i + d, j) - LSM_AT(phi, i + d - 1, j)) / dx;
            xp[k] = (LSM_AT(phi, i + d + 1, j) - LSM_AT(phi, i + d, j)) / dx;
            ym[k] = (LSM_AT(phi, i, j + d) - LSM_AT(phi, i, j + d - 1)) / dy;
            yp[k] = (LSM_AT(phi, i, j + d + 1) - LSM_AT(phi, i, j + d)) / dy;
          }
          int br;
          H = roefix_reference(F, xm, xp, ym, yp, &br);
          seen[br]++;
        }
        const double want = LSM_AT(phi, i, j) - dt * H;
        if (fabs(LSM_AT(out, i, j) - want) > 2e-5 * (1.0 + fabs(want)))
          fail_msg("%s stage at cell (%d, %d): %.7g, reference %.7g", sc ? "roe-fix" : "upwind", i,
                   j, LSM_AT(out, i, j), want);
      }
  }
  for (int b = 0; b < 4; ++b) assert_true(seen[b] > 0);
  lsm_grid_destroy(&phi);
  lsm_grid_destroy(&tgt);
  lsm_grid_destroy(&out);
}

/* At the apex of a cone (a cell at the centre of a disc's SDF: differences
 * -1 | +1 in both axes), F = -4:
 *   upwind (Godunov, F < 0): |grad|^2 = max(1, 1) + max(1, 1) -> H = -4 sqrt 2;
 *   Roe-Fix: both H1 and H2 change sign (LLF_XY), phi_x* = phi_y* = 0,
 *     alpha_x = alpha_y = |F| * 1/sqrt(1 + 1) (all other differences on the
 *     row and column are +-1), Hhat = -alpha_x - alpha_y = -4 sqrt 2. */
static void test_roefix_cone_apex(void **state) {
  (void)state;
  const int n = 32;
  lsm_grid *phi = new_grid(n, n, 1.0f, 1.0f), *tgt = new_grid(n, n, 1.0f, 1.0f);
  lsm_grid *out = new_grid(n, n, 1.0f, 1.0f);
  /* cx_of(16) = 0.5: the apex is cell (16, 16). */
  fill_circle(phi, 0.5, 0.5, 8.0, 1.0);
  fill_circle(tgt, 0.5, 0.5, 4.0, 1.0);
  const float dt = 0.1f;
  lsm_scheme_stage(LSM_SCHEME_UPWIND, out, phi, phi, tgt, 0.0f, 1.0f, dt, 1);
  assert_close(LSM_AT(out, 16, 16), -8.0 - dt * -4.0 * sqrt(2.0), 1e-5);
  lsm_scheme_stage(LSM_SCHEME_ROEFIX, out, phi, phi, tgt, 0.0f, 1.0f, dt, 1);
  assert_close(LSM_AT(out, 16, 16), -8.0 - dt * -4.0 * sqrt(2.0), 1e-5);
  lsm_grid_destroy(&phi);
  lsm_grid_destroy(&tgt);
  lsm_grid_destroy(&out);
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

/* ------------------------------------------------------------------------ */
/* fifth-order WENO                                                          */

/* The textbook form (Osher & Fedkiw 2003, eqs. 3.28-3.39), in double:
 * smoothness indicators with 13/12 and 1/4, eps = 1e-6 max v_k^2 + 1e-99,
 * weights 0.1, 0.6, 0.3. */
static double weno5_reference(const double v[5]) {
  const double p1 = v[0] / 3 - 7 * v[1] / 6 + 11 * v[2] / 6;
  const double p2 = -v[1] / 6 + 5 * v[2] / 6 + v[3] / 3;
  const double p3 = v[2] / 3 + 5 * v[3] / 6 - v[4] / 6;
  const double s1 = 13.0 / 12 * pow(v[0] - 2 * v[1] + v[2], 2) + 0.25 * pow(v[0] - 4 * v[1] + 3 * v[2], 2);
  const double s2 = 13.0 / 12 * pow(v[1] - 2 * v[2] + v[3], 2) + 0.25 * pow(v[1] - v[3], 2);
  const double s3 = 13.0 / 12 * pow(v[2] - 2 * v[3] + v[4], 2) + 0.25 * pow(3 * v[2] - 4 * v[3] + v[4], 2);
  double m = 0.0;
  for (int k = 0; k < 5; ++k) m = fmax(m, v[k] * v[k]);
  const double eps = 1e-6 * m + 1e-99;
  const double a1 = 0.1 / pow(s1 + eps, 2), a2 = 0.6 / pow(s2 + eps, 2), a3 = 0.3 / pow(s3 + eps, 2);
  return (a1 * p1 + a2 * p2 + a3 * p3) / (a1 + a2 + a3);
}

/* lsm_weno5 against the textbook form on random differences, smooth and
 * rough, at scales from 1e-30 to 1e30 (its indicators are taken of v / max
 * |v_k|, which must not change the weights), and 0 for all-zero input. */
static void test_weno5_reference(void **state) {
  (void)state;
  uint64_t seed = 0x5eed5eedULL;
  const double scales[5] = {1e-30, 1e-3, 1.0, 1e3, 1e30};
  double worst = 0.0;
  for (int trial = 0; trial < 20000; ++trial) {
    const double scale = scales[trial % 5];
    double v[5];
    float f[5];
    const int smooth = trial % 2;
    const double a = urand(&seed, -2, 2), b = urand(&seed, -0.5, 0.5);
    for (int k = 0; k < 5; ++k) {
      const double x = k - 2.0;
      v[k] = smooth ? a + b * x + urand(&seed, -1e-3, 1e-3) : urand(&seed, -2, 2);
      f[k] = (float)(scale * v[k]);
      v[k] = (double)f[k] / scale;
    }
    const double want = weno5_reference(v);
    const double got = lsm_weno5(f[0], f[1], f[2], f[3], f[4]) / scale;
    double vmax = 0.0;
    for (int k = 0; k < 5; ++k) vmax = fmax(vmax, fabs(v[k]));
    worst = fmax(worst, fabs(got - want) / vmax);
    if (fabs(got - want) > 2e-5 * vmax)
      fail_msg("trial %d (scale %g): %.9g, textbook %.9g", trial, scale, got, want);
  }
  print_message("weno5 against the textbook form: largest error %.2e of max |v|\n", worst);
  assert_true(lsm_weno5(0.0f, 0.0f, 0.0f, 0.0f, 0.0f) == 0.0f);
}

/* Every candidate is exact for a cubic phi, so phi_x^- and phi_x^+ are
 * its derivative; near a kink (phi = |x - 0.3|, the kink between two
 * cells) the candidates that cross it get almost no weight, so both
 * derivatives at the cell two cells from the kink are the smooth side's 1,
 * where the ideal (linear) weights are off by 6 %. */
static void test_weno5_derivatives(void **state) {
  (void)state;
  float phi[7], dd[6];
  const double xi = 0.7; /* the cell's x; cells at xi + k - 3, unit spacing */
  for (int k = 0; k < 7; ++k) {
    const double x = xi + k - 3;
    phi[k] = (float)(0.5 * x * x * x - 1.5 * x * x + 2.0 * x - 1.0);
  }
  for (int k = 0; k < 6; ++k) dd[k] = phi[k + 1] - phi[k];
  const double exact = 1.5 * xi * xi - 3.0 * xi + 2.0;
  const float minus = lsm_weno5(dd[0], dd[1], dd[2], dd[3], dd[4]);
  const float plus = lsm_weno5(dd[5], dd[4], dd[3], dd[2], dd[1]);
  print_message("cubic: phi_x^- %.7f, phi_x^+ %.7f, exact %.7f\n", minus, plus, exact);
  assert_close(minus, exact, 1e-5);
  assert_close(plus, exact, 1e-5);
  /* |x - 0.3| at cells x = 1.7 + k - 3: the kink between k = 1 and k = 2 */
  for (int k = 0; k < 7; ++k) phi[k] = (float)fabs(1.7 + k - 3 - 0.3);
  for (int k = 0; k < 6; ++k) dd[k] = phi[k + 1] - phi[k];
  const float kink_plus = lsm_weno5(dd[5], dd[4], dd[3], dd[2], dd[1]);
  const float kink_minus = lsm_weno5(dd[0], dd[1], dd[2], dd[3], dd[4]);
  const double linear = (0.1 * (2 * dd[5] - 7 * dd[4] + 11 * dd[3]) +
                         0.6 * (-dd[4] + 5 * dd[3] + 2 * dd[2]) + 0.3 * (2 * dd[3] + 5 * dd[2] - dd[1])) /
                        6.0;
  print_message("kink: phi_x^+ %.6f, phi_x^- %.6f (ideal weights: phi_x^+ %.6f)\n", kink_plus,
                kink_minus, linear);
  assert_close(kink_plus, 1.0, 1e-3);
  assert_close(kink_minus, 1.0, 1e-3);
  assert_true(fabs(linear - 1.0) > 0.05);
}

/* The stage gathers the WENO stencils right (offsets, strides, ghost
 * cells, dx != dy): against the textbook WENO derivatives in double and
 * the Godunov Hamiltonian, on the two-disc field of
 * test_stage_vs_cell_reference. */
static void test_weno5_stage_vs_reference(void **state) {
  (void)state;
  const int nx = 40, ny = 33;
  const float dx = 0.8f, dy = 1.1f;
  lsm_grid *phi = NULL, *tgt = NULL, *out = NULL;
  two_disc_fields(nx, ny, dx, dy, &phi, &tgt, &out);
  const float dt = 0.07f;
  lsm_scheme_stage(LSM_SCHEME_WENO5, out, phi, phi, tgt, 0.0f, 1.0f, dt, 2);
  lsm_grid_fill_ghosts(phi);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      double ex[6], ey[6], m[5], p[5], d[4];
      for (int k = 0; k < 6; ++k) {
        ex[k] = ((double)LSM_AT(phi, i + k - 2, j) - LSM_AT(phi, i + k - 3, j)) / dx;
        ey[k] = ((double)LSM_AT(phi, i, j + k - 2) - LSM_AT(phi, i, j + k - 3)) / dy;
      }
      for (int axis = 0; axis < 2; ++axis) {
        const double *e = axis ? ey : ex;
        for (int k = 0; k < 5; ++k) {
          m[k] = e[k];
          p[k] = e[5 - k];
        }
        d[2 * axis] = weno5_reference(m);
        d[2 * axis + 1] = weno5_reference(p);
      }
      const float F = LSM_AT(phi, i, j) - LSM_AT(tgt, i, j);
      const double H =
          lsm_upwind_hamiltonian(F, (float)d[0], (float)d[1], (float)d[2], (float)d[3]);
      const double want = LSM_AT(phi, i, j) - dt * H;
      if (fabs(LSM_AT(out, i, j) - want) > 2e-5 * (1.0 + fabs(want)))
        fail_msg("weno5 stage at cell (%d, %d): %.7g, reference %.7g", i, j, LSM_AT(out, i, j),
                 want);
    }
  lsm_grid_destroy(&phi);
  lsm_grid_destroy(&tgt);
  lsm_grid_destroy(&out);
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
      cmocka_unit_test(test_upwind_linear),
      cmocka_unit_test(test_upwind_kinks),
      cmocka_unit_test(test_stage_constant_speed),
      cmocka_unit_test(test_cfl),
      cmocka_unit_test(test_roefix_branches),
      cmocka_unit_test(test_roefix_random_vs_reference),
      cmocka_unit_test(test_roefix_linear_equals_upwind),
      cmocka_unit_test(test_stage_vs_cell_reference),
      cmocka_unit_test(test_roefix_cone_apex),
      cmocka_unit_test(test_schemes_monotone),
      cmocka_unit_test(test_cfl_flat_phi),
      cmocka_unit_test(test_upwind_unequal_spacing),
      cmocka_unit_test(test_integrators_agree),
      cmocka_unit_test(test_front_measure),
      cmocka_unit_test(test_circles_upwind),
      cmocka_unit_test(test_circles_roefix),
      cmocka_unit_test(test_weno5_reference),
      cmocka_unit_test(test_weno5_derivatives),
      cmocka_unit_test(test_weno5_stage_vs_reference),
      cmocka_unit_test(test_circles_weno5),
      cmocka_unit_test(test_integrators_circle),
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
