/* Tests of solver/pde/lsm_particles.c and kernels/lsm_particle_cell.h, one
 * operation at a time: seeding (Algorithm 3.2), attraction and radii,
 * advection with the front (dt * F * N per step for Euler, RK2, RK3), the
 * escaped-particle correction of Algorithm 3.3 against hand-computed values,
 * removal of particles that leave the domain, and the kernel header's pure
 * per-corner maths. */
#include "tests/lsm_test_particles.h"

#include "kernels/lsm_particle_cell.h"
#include "solver/base/lsm_grid.h"
#include "solver/pde/lsm_particles.h"
#include "solver/base/lsm_status.h"

static double disc_sdf(const lsm_grid *g, double x, double y, double cx, double cy,
                       double radius) {
  double ex = (x - cx) * g->dx, ey = (y - cy) * g->dy;
  return sqrt(ex * ex + ey * ey) - radius;
}

static void set_particles(lsm_particles *p, size_t n, const float *x, const float *y,
                          const int8_t *s, const float *r) {
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = lsm_pls_set(p, n, x, y, s, r, &err);
  if (st != LSM_OK) fail_msg("lsm_pls_set: %s", err.msg);
}

static long long count_band_cells(const lsm_grid *phi, float band) {
  long long cells = 0;
  for (int j = 0; j < phi->ny - 1; ++j)
    for (int i = 0; i < phi->nx - 1; ++i) {
      int in = 0;
      for (int b = 0; b < 2; ++b)
        for (int a = 0; a < 2; ++a) in |= fabsf(LSM_AT(phi, i + a, j + b)) < band;
      cells += in;
    }
  return cells;
}

/* ------------------------------------------------------------------------ */
/* seeding                                                                   */

/* Without attraction: every band cell holds exactly particles_per_cell
 * particles inside it, ceil(n/2) positive; no other cell holds any. */
static void test_seeding_per_cell(void **state) {
  (void)state;
  const int nx = 40, ny = 36, ppcs[2] = {16, 7};
  const float dx = 1.0f, dy = 0.75f, band = 3.0f * 1.0f;
  lsm_grid *phi = new_grid(nx, ny, dx, dy);
  fill_disc(phi, 19.3, 17.6, 8.0);
  for (int t = 0; t < 2; ++t) {
    const int ppc = ppcs[t];
    lsm_pls_opts o;
    lsm_pls_opts_default(&o);
    o.particles_per_cell = ppc;
    o.skip_attraction = 1;
    lsm_particles *p = new_pls(phi, &o);
    lsm_pls_view v = lsm_pls_view_get(p);
    int *count = calloc((size_t)nx * ny, sizeof *count), *pos = calloc((size_t)nx * ny, sizeof *pos);
    assert_non_null(count);
    assert_non_null(pos);
    for (size_t k = 0; k < v.n; ++k) {
      int i = (int)floorf(v.x[k]), j = (int)floorf(v.y[k]);
      assert_true(i >= 0 && i < nx - 1 && j >= 0 && j < ny - 1);
      assert_true(v.sign[k] == 1 || v.sign[k] == -1);
      count[j * nx + i]++;
      pos[j * nx + i] += v.sign[k] > 0;
    }
    long long cells = 0;
    for (int j = 0; j < ny - 1; ++j)
      for (int i = 0; i < nx - 1; ++i) {
        int in = 0;
        for (int b = 0; b < 2; ++b)
          for (int a = 0; a < 2; ++a) in |= fabsf(LSM_AT(phi, i + a, j + b)) < band;
        cells += in;
        assert_int_equal(count[j * nx + i], in ? ppc : 0);
        assert_int_equal(pos[j * nx + i], in ? (ppc + 1) / 2 : 0);
      }
    assert_true(cells > 100);
    const lsm_pls_stats *s = lsm_pls_stats_get(p);
    assert_int_equal(s->band_cells, cells);
    assert_int_equal(s->seeded, cells * ppc);
    assert_int_equal(s->discarded, 0);
    assert_int_equal((long long)lsm_pls_count(p), cells * ppc);
    free(count);
    free(pos);
    lsm_pls_destroy(&p);
    assert_null(p);
  }
  lsm_grid_destroy(&phi);
}

/* With attraction on a disc: count = ppc * band cells - discarded, >= 95 % of
 * the seeded particles kept, and >= 95 % of the kept ones inside their band
 * measured against the exact disc distance (not the module's interpolation). */
static void test_attraction_disc(void **state) {
  (void)state;
  const float dxs[2] = {1.0f, 0.5f}, dys[2] = {1.0f, 0.8f};
  for (int t = 0; t < 2; ++t) {
    const int nx = 64, ny = 60;
    const float dx = dxs[t], dy = dys[t];
    const double cx = 31.4, cy = 29.2, R = 12.0 * fmin(dx, dy);
    lsm_grid *phi = new_grid(nx, ny, dx, dy);
    fill_disc(phi, cx, cy, R);
    lsm_pls_opts o;
    lsm_pls_opts_default(&o);
    lsm_particles *p = new_pls(phi, &o);
    const lsm_pls_stats *s = lsm_pls_stats_get(p);
    long long cells = count_band_cells(phi, 3.0f * fmaxf(dx, dy));
    assert_int_equal(s->band_cells, cells);
    assert_int_equal(s->seeded, 16 * cells);
    assert_int_equal((long long)lsm_pls_count(p), 16 * cells - s->discarded);
    assert_true((double)lsm_pls_count(p) >= 0.95 * (double)s->seeded);
    const double vmin = 0.1 * fmin(dx, dy), vmax = 3.0 * fmax(dx, dy);
    lsm_pls_view v = lsm_pls_view_get(p);
    size_t good = 0, npos = 0;
    for (size_t k = 0; k < v.n; ++k) {
      double d = v.sign[k] * disc_sdf(phi, v.x[k], v.y[k], cx, cy, R);
      good += d >= vmin && d <= vmax;
      npos += v.sign[k] > 0;
      /* by the module's own interpolation every kept particle is in its band */
      double b = v.sign[k] * bilinear(phi, v.x[k], v.y[k]);
      assert_true(b >= vmin - 1e-5 && b <= vmax + 1e-5);
    }
    assert_true((double)good >= 0.95 * (double)v.n);
    /* roughly balanced signs after attraction */
    assert_true(npos > v.n / 3 && npos < 2 * v.n / 3);
    lsm_pls_destroy(&p);
    lsm_grid_destroy(&phi);
  }
}

/* On a linear field with unit physical gradient, phi = (x - 20) dx or
 * phi = (y - 15) dy, one attraction step p + (phi_goal - phi(p)) N (converted
 * to cells per axis) lands exactly on phi_goal, well inside the domain, so
 * nothing is discarded.  Particles are stored cell by cell, slot by slot, so
 * the test recomputes every goal from the documented counter-based draw and
 * checks phi(p) against it. */
static void test_attraction_linear_exact(void **state) {
  (void)state;
  const int nx = 40, ny = 30, ppc = 16;
  const float dx = 0.25f, dy = 0.5f;
  const double vmin = 0.1 * 0.25, vmax = 3.0 * 0.5;
  lsm_grid *phi = new_grid(nx, ny, dx, dy);
  for (int axis = 0; axis < 2; ++axis) {
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        LSM_AT(phi, i, j) = axis == 0 ? (float)(i - 20) * dx : (float)(j - 15) * dy;
    lsm_pls_opts o;
    lsm_pls_opts_default(&o);
    lsm_particles *p = new_pls(phi, &o);
    const lsm_pls_stats *st = lsm_pls_stats_get(p);
    assert_int_equal(st->discarded, 0);
    lsm_pls_view v = lsm_pls_view_get(p);
    assert_int_equal((long long)v.n, ppc * st->band_cells);
    size_t k = 0;
    for (int j = 0; j < ny - 1; ++j)
      for (int i = 0; i < nx - 1; ++i) {
        int in = 0;
        for (int b = 0; b < 2; ++b)
          for (int a = 0; a < 2; ++a) in |= fabsf(LSM_AT(phi, i + a, j + b)) < 1.5f;
        if (!in) continue;
        for (int q = 0; q < ppc; ++q, ++k) {
          int s = q < ppc / 2 ? 1 : -1;
          assert_int_equal(v.sign[k], s);
          double u = lsm_pcl_uniform(o.seed, 0, (uint64_t)j * nx + i, (uint64_t)q, 2);
          double goal = s * (vmin + u * (vmax - vmin));
          assert_close(bilinear(phi, v.x[k], v.y[k]), goal, 1e-5);
          /* the move is along N only */
          if (axis == 0) assert_true(v.y[k] >= j && v.y[k] < j + 1);
          else assert_true(v.x[k] >= i && v.x[k] < i + 1);
        }
      }
    assert_int_equal(k, v.n);
    assert_true(k > 1000);
    lsm_pls_destroy(&p);
  }
  lsm_grid_destroy(&phi);
}

/* Every radius is clamp(s phi(p), r_min, r_max). */
static void test_radius_clamp(void **state) {
  (void)state;
  const float dx = 0.6f, dy = 0.9f;
  const double rmin = 0.1 * 0.6, rmax = 0.5 * 0.6;
  lsm_grid *phi = new_grid(50, 40, dx, dy);
  fill_disc(phi, 24.5, 19.5, 7.0);
  for (int skip = 0; skip < 2; ++skip) {
    lsm_pls_opts o;
    lsm_pls_opts_default(&o);
    o.skip_attraction = skip;
    lsm_particles *p = new_pls(phi, &o);
    lsm_pls_view v = lsm_pls_view_get(p);
    assert_true(v.n > 1000);
    int at_min = 0, at_max = 0, between = 0;
    for (size_t k = 0; k < v.n; ++k) {
      double r = v.radius[k];
      assert_true(r >= rmin - 1e-7 && r <= rmax + 1e-7);
      double sp = v.sign[k] * bilinear(phi, v.x[k], v.y[k]);
      double want = sp > rmax ? rmax : (sp < rmin ? rmin : sp);
      assert_close(r, want, 1e-5);
      at_min += r <= rmin + 1e-7;
      at_max += r >= rmax - 1e-7;
      between += r > rmin + 1e-7 && r < rmax - 1e-7;
    }
    assert_true(at_max > 0);
    assert_true(between > 0);
    if (skip) assert_true(at_min > 0); /* wrong-side particles get r_min */
    lsm_pls_destroy(&p);
  }
  lsm_grid_destroy(&phi);
}

/* ------------------------------------------------------------------------ */
/* advection                                                                 */

/* phi = (x - 3) dx (or (y - 3) dy): N = (1,0) (or (0,1)); phi_target = phi - c:
 * F = c.  One step moves by dt c / dx cells along N, for Euler, RK2 and RK3. */
static void test_uniform_field(void **state) {
  (void)state;
  const int nx = 40, ny = 30;
  const float dx = 0.5f, dy = 2.0f, c = 1.5f, dt = 0.4f;
  lsm_grid *phi = new_grid(nx, ny, dx, dy), *target = new_grid(nx, ny, dx, dy);
  for (int axis = 0; axis < 2; ++axis) {
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        float v = axis == 0 ? (float)(i - 3) * dx : (float)(j - 3) * dy;
        LSM_AT(phi, i, j) = v;
        LSM_AT(target, i, j) = v - c;
      }
    lsm_pls_opts o;
    lsm_pls_opts_default(&o);
    lsm_particles *p = new_pls(phi, &o);
    float x[4] = {3.0f, 7.25f, 10.5f, 0.6f}, y[4] = {4.0f, 11.75f, 0.3f, 7.9f};
    float r[4] = {0.1f, 0.1f, 0.1f, 0.1f};
    int8_t s[4] = {1, -1, 1, -1};
    const float shift = axis == 0 ? dt * c / dx : dt * c / dy; /* cells */
    /* Euler, RK2, RK3 */
    static const float coef[3][3][2] = {{{0.0f, 1.0f}},
                                        {{0.0f, 1.0f}, {0.5f, 0.5f}},
                                        {{0.0f, 1.0f}, {0.75f, 0.25f}, {1.0f / 3.0f, 2.0f / 3.0f}}};
    for (int scheme = 0; scheme < 3; ++scheme) {
      set_particles(p, 4, x, y, s, r);
      for (int step = 0; step < 2; ++step) {
        lsm_pls_begin_step(p, scheme + 1);
        for (int st = 0; st <= scheme; ++st)
          stage(p, phi, target, coef[scheme][st][0], coef[scheme][st][1], dt);
      }
      lsm_pls_view v = lsm_pls_view_get(p);
      assert_int_equal(v.n, 4);
      for (int k = 0; k < 4; ++k) {
        float ex = axis == 0 ? x[k] + 2 * shift : x[k];
        float ey = axis == 1 ? y[k] + 2 * shift : y[k];
        assert_close(v.x[k], ex, 2e-5);
        assert_close(v.y[k], ey, 2e-5);
      }
    }
    /* a single Euler stage, checked on its own */
    set_particles(p, 4, x, y, s, r);
    lsm_pls_begin_step(p, 1);
    stage(p, phi, target, 0.0f, 1.0f, dt);
    lsm_pls_view v = lsm_pls_view_get(p);
    for (int k = 0; k < 4; ++k) {
      assert_close(axis == 0 ? v.x[k] - x[k] : v.y[k] - y[k], shift, 1e-5);
      assert_close(axis == 0 ? v.y[k] - y[k] : v.x[k] - x[k], 0.0, 1e-6);
    }
    lsm_pls_destroy(&p);
  }
  lsm_grid_destroy(&phi);
  lsm_grid_destroy(&target);
}

/* The sign convention: a particle on the zero level of a disc of radius 10
 * whose target is the concentric disc of radius 6 (phi_target = +4 there,
 * F = -4) moves INWARD by dt * 4; towards a disc of radius 14 it moves outward. */
static void test_velocity_sign(void **state) {
  (void)state;
  const int n = 48;
  const double cx = 23.5, cy = 23.5;
  const float dt = 0.05f;
  lsm_grid *phi = new_grid(n, n, 1.0f, 1.0f), *target = new_grid(n, n, 1.0f, 1.0f);
  fill_disc(phi, cx, cy, 10.0);
  const double radii[2] = {6.0, 14.0};
  for (int t = 0; t < 2; ++t) {
    fill_disc(target, cx, cy, radii[t]);
    lsm_pls_opts o;
    lsm_pls_opts_default(&o);
    lsm_particles *p = new_pls(phi, &o);
    const double ang[3] = {0.0, 0.7, 2.2};
    float x[3], y[3], r[3] = {0.1f, 0.1f, 0.1f};
    int8_t s[3] = {1, -1, 1};
    for (int k = 0; k < 3; ++k) {
      x[k] = (float)(cx + 10.0 * cos(ang[k]));
      y[k] = (float)(cy + 10.0 * sin(ang[k]));
    }
    set_particles(p, 3, x, y, s, r);
    lsm_pls_begin_step(p, 1);
    stage(p, phi, target, 0.0f, 1.0f, dt);
    lsm_pls_view v = lsm_pls_view_get(p);
    for (int k = 0; k < 3; ++k) {
      double rad = hypot(v.x[k] - cx, v.y[k] - cy);
      double want = 10.0 + dt * (radii[t] - 10.0); /* F = -(radius_t - 10) along N */
      assert_close(rad, want, 0.02);
      /* and the move is radial */
      double a0 = atan2(y[k] - cy, x[k] - cx), a1 = atan2(v.y[k] - cy, v.x[k] - cx);
      assert_close(a1, a0, 0.01);
    }
    lsm_pls_destroy(&p);
  }
  lsm_grid_destroy(&phi);
  lsm_grid_destroy(&target);
}

/* A particle pushed out of the domain is removed at the next correction. */
static void test_left_domain(void **state) {
  (void)state;
  const int nx = 20, ny = 20;
  lsm_grid *phi = new_grid(nx, ny, 1.0f, 1.0f), *target = new_grid(nx, ny, 1.0f, 1.0f);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      LSM_AT(phi, i, j) = (float)(i - 10);
      LSM_AT(target, i, j) = (float)(i - 10) - 2.0f; /* F = 2, N = (1,0) */
    }
  lsm_pls_opts o;
  lsm_pls_opts_default(&o);
  o.skip_attraction = 1;
  lsm_particles *p = new_pls(phi, &o);
  const long long before = (long long)lsm_pls_count(p);
  float x[3] = {18.5f, 5.0f, 12.0f}, y[3] = {3.0f, 4.0f, 5.0f}, r[3] = {0.5f, 0.5f, 0.5f};
  int8_t s[3] = {1, -1, 1};
  set_particles(p, 3, x, y, s, r);
  lsm_pls_begin_step(p, 1);
  stage(p, phi, target, 0.0f, 1.0f, 0.5f); /* moves by 1 cell: 18.5 -> 19.5 > 19 */
  correct(p, phi);
  lsm_pls_view v = lsm_pls_view_get(p);
  assert_int_equal(v.n, 2);
  assert_close(v.x[0], 6.0, 1e-5);
  assert_close(v.x[1], 13.0, 1e-5);
  const lsm_pls_stats *st = lsm_pls_stats_get(p);
  assert_int_equal(st->left_domain, 1);
  assert_int_equal(st->steps, 1);
  assert_true(before > 0);
  lsm_pls_destroy(&p);
  lsm_grid_destroy(&phi);
  lsm_grid_destroy(&target);
}

/* ------------------------------------------------------------------------ */
/* correction                                                                */

/* Eq. 3.23 by hand. */
static double hand_phi_p(int s, double r, double phi_v, double ox, double oy, double dx,
                         double dy) {
  double d = sqrt(ox * dx * ox * dx + oy * dy * oy * dy);
  return phi_v <= 0.0 ? s * r - d : s * r + d;
}

/* phi = (x - 3.5) dx with dx = 0.5, dy = 1: interface between columns 3 and 4.
 * Particles (cell coordinates, sign, radius):
 *   A (2.25, 4.5) +, r 0.1: phi -0.625, escaped; cell (2,4), all corners phi <= 0.
 *   B (4.6, 2.3)  -, r 0.2: phi +0.55, escaped; cell (4,2), all corners phi > 0.
 *   C (3.2, 6.5)  +, r 0.1: phi -0.15, escaped; cell (3,6), straddles.
 *   D (3.8, 6.2)  -, r 0.1: phi +0.15, escaped; cell (3,6) too (plus and minus meet).
 *   E (5.5, 5.5)  +, r 0.3: phi +1.0, right side, not escaped.
 *   F (3.3, 1.5)  +, r 0.2: phi -0.1, wrong side but |phi| <= r, not escaped.
 * Expected corner values are computed here from Eq. 3.23–3.26. */
static void test_correction_by_hand(void **state) {
  (void)state;
  const int nx = 9, ny = 9;
  const double dx = 0.5, dy = 1.0;
  lsm_grid *phi = new_grid(nx, ny, (float)dx, (float)dy);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) LSM_AT(phi, i, j) = (float)((i - 3.5) * dx);
  lsm_grid_fill_ghosts(phi);
  lsm_pls_opts o;
  lsm_pls_opts_default(&o);
  lsm_particles *p = new_pls(phi, &o);
  float x[6] = {2.25f, 4.6f, 3.2f, 3.8f, 5.5f, 3.3f}, y[6] = {4.5f, 2.3f, 6.5f, 6.2f, 5.5f, 1.5f};
  int8_t s[6] = {1, -1, 1, -1, 1, 1};
  float r[6] = {0.1f, 0.2f, 0.1f, 0.1f, 0.3f, 0.2f};
  set_particles(p, 6, x, y, s, r);

  /* expected: start with plus = minus = phi at every node */
  double plus[9][9], minus[9][9], orig[9][9];
  int touched[9][9];
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      orig[j][i] = plus[j][i] = minus[j][i] = LSM_AT(phi, i, j);
      touched[j][i] = 0;
    }
  const int escaped_ids[4] = {0, 1, 2, 3};
  for (int e = 0; e < 4; ++e) {
    int k = escaped_ids[e];
    int ci = (int)floor(x[k]), cj = (int)floor(y[k]);
    for (int b = 0; b < 2; ++b)
      for (int a = 0; a < 2; ++a) {
        int vi = ci + a, vj = cj + b;
        double v = hand_phi_p(s[k], r[k], orig[vj][vi], vi - (double)x[k], vj - (double)y[k], dx, dy);
        if (s[k] > 0)
          plus[vj][vi] = fmax(plus[vj][vi], v);
        else
          minus[vj][vi] = fmin(minus[vj][vi], v);
        touched[vj][vi] = 1;
      }
  }
  correct(p, phi);

  int changed = 0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      double want = orig[j][i];
      if (touched[j][i]) want = fabs(plus[j][i]) <= fabs(minus[j][i]) ? plus[j][i] : minus[j][i];
      assert_close(LSM_AT(phi, i, j), want, 2e-6);
      changed += fabs(want - orig[j][i]) > 1e-6;
    }
  /* spot values, worked out on paper:
   * A at corner (2,4): d = sqrt(0.125^2 + 0.5^2), phi_p = 0.1 - d = -0.41539 > -0.75 */
  assert_close(LSM_AT(phi, 2, 4), 0.1 - sqrt(0.125 * 0.125 + 0.25), 2e-6);
  /* A at corner (3,4): phi_p = 0.1 - 0.625 = -0.525 < -0.25: phi_plus stays -0.25 */
  assert_close(LSM_AT(phi, 3, 4), -0.25, 1e-7);
  /* B at corner (5,2) (phi 0.75 > 0): phi_p = -0.2 + d, d = sqrt(0.2^2 + 0.3^2) */
  assert_close(LSM_AT(phi, 5, 2), -0.2 + sqrt(0.04 + 0.09), 2e-6);
  /* ghosts follow the corrected interior */
  assert_close(LSM_AT(phi, -1, 4), LSM_AT(phi, 0, 4), 0.0);

  const lsm_pls_stats *st = lsm_pls_stats_get(p);
  assert_int_equal(st->escaped_last, 4);
  assert_int_equal(st->escaped_total, 4);
  assert_int_equal(st->corrected_last, changed);
  assert_true(changed >= 4);
  assert_int_equal(lsm_pls_count(p), 6); /* escaped particles are kept */
  lsm_pls_destroy(&p);
  lsm_grid_destroy(&phi);
}

/* The pure per-corner maths of the kernel header. */
static void test_kernel_functions(void **state) {
  (void)state;
  assert_true(lsm_pcl_escaped(1, -0.5f, 0.2f));
  assert_false(lsm_pcl_escaped(1, -0.2f, 0.2f));
  assert_false(lsm_pcl_escaped(1, 0.5f, 0.2f));
  assert_true(lsm_pcl_escaped(-1, 0.5f, 0.2f));
  assert_false(lsm_pcl_escaped(-1, 0.0f, 0.0f));
  assert_close(lsm_pcl_corner_value(1, 0.3f, -1.0f, 0.5f), -0.2, 1e-7);
  assert_close(lsm_pcl_corner_value(1, 0.3f, 0.0f, 0.5f), -0.2, 1e-7);
  assert_close(lsm_pcl_corner_value(1, 0.3f, 1.0f, 0.5f), 0.8, 1e-7);
  assert_close(lsm_pcl_corner_value(-1, 0.3f, -1.0f, 0.5f), -0.8, 1e-7);
  assert_close(lsm_pcl_corner_value(-1, 0.3f, 1.0f, 0.5f), 0.2, 1e-7);
  assert_close(lsm_pcl_select(-0.2f, -0.5f), -0.2f, 0.0);
  assert_close(lsm_pcl_select(0.6f, -0.5f), -0.5, 0.0);
  assert_close(lsm_pcl_select(0.5f, -0.5f), 0.5, 0.0);
  assert_close(lsm_pcl_radius(1, 0.01f, 0.1f, 0.5f), 0.1f, 0.0);
  assert_close(lsm_pcl_radius(-1, -0.3f, 0.1f, 0.5f), 0.3, 1e-7);
  assert_close(lsm_pcl_radius(-1, -3.0f, 0.1f, 0.5f), 0.5, 0.0);
  assert_close(lsm_pcl_bilinear(1, 2, 3, 4, 0.25f, 0.5f), 1 + 0.25 + 1.0, 1e-7);
  float fx;
  assert_int_equal(lsm_pcl_locate(4.0f, 5, &fx), 3);
  assert_close(fx, 1.0, 0.0);
  assert_int_equal(lsm_pcl_locate(-2.0f, 5, &fx), 0);
  assert_close(fx, 0.0, 0.0);
  assert_true(lsm_pcl_seed_coord(100000, 0.99999994f) < 100001.0f);
  float nx_, ny_;
  lsm_pcl_normal(0.0f, 0.0f, &nx_, &ny_);
  assert_close(nx_, 1.0 / sqrt(2.0), 1e-7);
  assert_close(ny_, 1.0 / sqrt(2.0), 1e-7);
  /* counter-based draws: fixed, distinct, in [0, 1) */
  float u0 = lsm_pcl_uniform(1, 0, 5, 3, 0), u1 = lsm_pcl_uniform(1, 0, 5, 3, 1);
  assert_true(u0 >= 0.0f && u0 < 1.0f && u1 >= 0.0f && u1 < 1.0f && u0 != u1);
  assert_true(u0 == lsm_pcl_uniform(1, 0, 5, 3, 0));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_kernel_functions),
      cmocka_unit_test(test_seeding_per_cell),
      cmocka_unit_test(test_attraction_disc),
      cmocka_unit_test(test_attraction_linear_exact),
      cmocka_unit_test(test_radius_clamp),
      cmocka_unit_test(test_uniform_field),
      cmocka_unit_test(test_velocity_sign),
      cmocka_unit_test(test_left_domain),
      cmocka_unit_test(test_correction_by_hand),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
