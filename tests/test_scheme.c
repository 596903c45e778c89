/* The morph solver's spatial schemes, cell by cell and stage by stage: the
 * upwind Hamiltonian (linear data, kinks), one grid stage at constant speed,
 * Roe-Fix (every branch by hand, random stencils against Algorithm 3.1
 * written out in double, the cone apex), the grid stages against per-cell
 * references assembled from the stencils, and fifth-order WENO (the textbook
 * form, exact derivatives of a cubic, the stage's stencil gathering).
 * Reference: solver/README.md, sections 2 and 4. */
#include "tests/lsm_test_scheme.h"

#include "kernels/lsm_cell.h"
#include "solver/base/lsm_grid.h"
#include "solver/pde/lsm_scheme.h"

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

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_upwind_linear),
      cmocka_unit_test(test_upwind_kinks),
      cmocka_unit_test(test_stage_constant_speed),
      cmocka_unit_test(test_roefix_branches),
      cmocka_unit_test(test_roefix_random_vs_reference),
      cmocka_unit_test(test_roefix_linear_equals_upwind),
      cmocka_unit_test(test_stage_vs_cell_reference),
      cmocka_unit_test(test_roefix_cone_apex),
      cmocka_unit_test(test_weno5_reference),
      cmocka_unit_test(test_weno5_derivatives),
      cmocka_unit_test(test_weno5_stage_vs_reference),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
