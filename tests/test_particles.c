/* Tests for solver/pde/lsm_particles.c and kernels/lsm_particle_cell.h: seeding
 * (Algorithm 3.2), attraction and radii, advection with the front
 * (dt * F * N per step for Euler, RK2, RK3), the escaped-particle correction
 * of Algorithm 3.3 against hand-computed values, removal of particles that
 * leave the domain, reseeding and radius adjustment, and bit-identical results
 * for 1 and 2 threads; lsm_morph's particles (through the backend's particle
 * ops) equal to this module driven directly. */
#include "tests/lsm_test.h"

#include "kernels/lsm_particle_cell.h"
#include "solver/base/lsm_grid.h"
#include "solver/pde/lsm_morph.h"
#include "solver/pde/lsm_particles.h"
#include "solver/pde/lsm_scheme.h"
#include "solver/base/lsm_status.h"

/* ------------------------------------------------------------------------ */
/* helpers                                                                   */

static lsm_grid *new_grid(int w, int h, float dx, float dy) {
  lsm_grid *g = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_grid_create(w, h, dx, dy, &g, &err), LSM_OK);
  return g;
}

/* Signed distance to a disc (negative inside), physical units, centre in cells. */
static void fill_disc(lsm_grid *g, double cx, double cy, double radius) {
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i < g->nx; ++i) {
      double ex = (i - cx) * g->dx, ey = (j - cy) * g->dy;
      LSM_AT(g, i, j) = (float)(sqrt(ex * ex + ey * ey) - radius);
    }
  lsm_grid_fill_ghosts(g);
}

static double disc_sdf(const lsm_grid *g, double x, double y, double cx, double cy,
                       double radius) {
  double ex = (x - cx) * g->dx, ey = (y - cy) * g->dy;
  return sqrt(ex * ex + ey * ey) - radius;
}

/* Independent bilinear interpolation (double) at cell coordinates. */
static double bilinear(const lsm_grid *g, double x, double y) {
  int i = (int)floor(x), j = (int)floor(y);
  if (i > g->nx - 2) i = g->nx - 2;
  if (j > g->ny - 2) j = g->ny - 2;
  if (i < 0) i = 0;
  if (j < 0) j = 0;
  double fx = x - i, fy = y - j;
  return (1 - fy) * ((1 - fx) * LSM_AT(g, i, j) + fx * LSM_AT(g, i + 1, j)) +
         fy * ((1 - fx) * LSM_AT(g, i, j + 1) + fx * LSM_AT(g, i + 1, j + 1));
}

static lsm_particles *new_pls(const lsm_grid *phi, const lsm_pls_opts *o) {
  lsm_particles *p = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = lsm_pls_create(phi, o, &p, &err);
  if (st != LSM_OK) fail_msg("lsm_pls_create: %s", err.msg);
  assert_non_null(p);
  return p;
}

/* lsm_pls_stage, which must succeed. */
static void stage(lsm_particles *p, const lsm_grid *in, const lsm_grid *target, float c0, float c1,
                  float dt) {
  lsm_err err;
  lsm_err_clear(&err);
  if (lsm_pls_stage(p, in, target, c0, c1, dt, &err) != LSM_OK) fail_msg("lsm_pls_stage: %s", err.msg);
}

static void correct(lsm_particles *p, lsm_grid *phi) {
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = lsm_pls_correct(p, phi, &err);
  if (st != LSM_OK) fail_msg("lsm_pls_correct: %s", err.msg);
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

/* ------------------------------------------------------------------------ */
/* full sequences                                                            */

/* Stand-in for a grid step (the scheme is not linked here): the exact
 * relaxation phi <- phi_T + (phi - phi_T) e^{-dt}, plus a small deterministic
 * ripple so that the particles have something to correct. */
static void fake_step(lsm_grid *phi, const lsm_grid *target, float dt, int n) {
  const float a = expf(-dt);
  for (int j = 0; j < phi->ny; ++j)
    for (int i = 0; i < phi->nx; ++i) {
      float v = LSM_AT(target, i, j) + (LSM_AT(phi, i, j) - LSM_AT(target, i, j)) * a;
      v += 0.08f * phi->dx * sinf(0.9f * (float)i + 0.5f * (float)n) * cosf(0.7f * (float)j);
      LSM_AT(phi, i, j) = v;
    }
  lsm_grid_fill_ghosts(phi);
}

typedef struct run_result {
  lsm_grid *phi;
  size_t n;
  float *x, *y, *r;
  int8_t *s;
  lsm_pls_stats stats;
} run_result;

/* Steps particles against a stand-in grid evolution.  edge: the target lies partly outside
 * the grid, so particles leave the domain. */
static run_result run_sequence_ex(int threads, int rk3, int reseed, int adjust, int steps,
                                  int edge) {
  const int N = 160;
  lsm_grid *phi = new_grid(N, N, 1.0f, 1.0f), *target = new_grid(N, N, 1.0f, 1.0f);
  lsm_grid *mid = new_grid(N, N, 1.0f, 1.0f);
  fill_disc(phi, 80.3, 79.6, 50.0);
  if (edge)
    fill_disc(target, 30.0, 83.0, 45.0);
  else
    fill_disc(target, 74.0, 83.0, 38.0);
  lsm_pls_opts o;
  lsm_pls_opts_default(&o);
  o.threads = threads;
  o.reseed_every = reseed;
  o.radius_adjust = adjust;
  lsm_particles *p = new_pls(phi, &o);
  const float dt = 0.3f;
  for (int n = 0; n < steps; ++n) {
    lsm_pls_begin_step(p, rk3 ? 3 : 1);
    if (rk3) {
      /* the particle stages of RK3 against stand-in stage fields */
      stage(p, phi, target, 0.0f, 1.0f, dt);
      lsm_grid_copy(mid, phi);
      fake_step(mid, target, dt, n);
      stage(p, mid, target, 0.75f, 0.25f, dt);
      stage(p, mid, target, 1.0f / 3.0f, 2.0f / 3.0f, dt);
    } else {
      stage(p, phi, target, 0.0f, 1.0f, dt);
    }
    fake_step(phi, target, dt, n);
    correct(p, phi);
  }
  run_result res;
  lsm_pls_view v = lsm_pls_view_get(p);
  res.phi = phi;
  res.n = v.n;
  res.x = malloc(v.n * sizeof(float) + 1);
  res.y = malloc(v.n * sizeof(float) + 1);
  res.r = malloc(v.n * sizeof(float) + 1);
  res.s = malloc(v.n + 1);
  assert_true(res.x && res.y && res.r && res.s);
  memcpy(res.x, v.x, v.n * sizeof(float));
  memcpy(res.y, v.y, v.n * sizeof(float));
  memcpy(res.r, v.radius, v.n * sizeof(float));
  memcpy(res.s, v.sign, v.n);
  res.stats = *lsm_pls_stats_get(p);
  lsm_pls_destroy(&p);
  lsm_grid_destroy(&target);
  lsm_grid_destroy(&mid);
  return res;
}

static run_result run_sequence(int threads, int rk3, int reseed, int adjust, int steps) {
  return run_sequence_ex(threads, rk3, reseed, adjust, steps, 0);
}

static void free_result(run_result *r) {
  lsm_grid_destroy(&r->phi);
  free(r->x);
  free(r->y);
  free(r->r);
  free(r->s);
}

static void assert_same(const run_result *a, const run_result *b) {
  assert_int_equal(a->n, b->n);
  assert_memory_equal(a->x, b->x, a->n * sizeof(float));
  assert_memory_equal(a->y, b->y, a->n * sizeof(float));
  assert_memory_equal(a->r, b->r, a->n * sizeof(float));
  assert_memory_equal(a->s, b->s, a->n);
  size_t bytes = (size_t)(a->phi->ny + 2 * a->phi->ghost) * (size_t)a->phi->stride * sizeof(float);
  assert_memory_equal(a->phi->base, b->phi->base, bytes);
  assert_memory_equal(&a->stats, &b->stats, sizeof a->stats);
}

/* seed + advect + correct on a disc: bit-identical for 1 and 2 threads (and 3,
 * with RK3 stages, reseeding and radius adjustment). */
static void test_determinism_threads(void **state) {
  (void)state;
  run_result a = run_sequence(1, 0, 0, 0, 12), b = run_sequence(2, 0, 0, 0, 12);
  /* enough particles for the parallel loops to actually run in parallel */
  assert_true(a.stats.seeded >= LSM_PLS_MIN_PARALLEL);
  assert_true(a.n >= (size_t)LSM_PLS_MIN_PARALLEL);
  assert_true(a.stats.escaped_total > 0);
  assert_true(a.stats.corrected_total > 0);
  assert_same(&a, &b);
  free_result(&a);
  free_result(&b);
  a = run_sequence(1, 1, 4, 1, 10);
  b = run_sequence(3, 1, 4, 1, 10);
  assert_true(a.stats.reseeds == 2);
  assert_same(&a, &b);
  free_result(&a);
  free_result(&b);
}

/* lsm_morph's particles (seeded on the host, stepped and corrected through the
 * C backend's particle ops, reseeded by the morph) against this module driven
 * directly, each Runge–Kutta stage's particles before its grid stage and
 * lsm_pls_correct (with its own reseeding) after the step: the same phi, bit
 * for bit, and the same counters.  Euler and RK3, reseeding, radius
 * adjustment, strays, 1 and 2 threads. */
static void test_morph_equals_direct_particles(void **state) {
  (void)state;
  const int cases[][4] = {/* time, reseed, adjust, threads */
                          {LSM_TIME_EULER, 0, 0, 1}, {LSM_TIME_RK3, 0, 0, 1},
                          {LSM_TIME_RK2, 4, 1, 2},   {LSM_TIME_EULER, 3, 0, 2},
                          {LSM_TIME_EULER, 55, 0, 1}}; /* strays before the reseeding */
  static const float coef[3][3][2] = {{{0.0f, 1.0f}},
                                      {{0.0f, 1.0f}, {0.5f, 0.5f}},
                                      {{0.0f, 1.0f}, {0.75f, 0.25f}, {1.0f / 3.0f, 2.0f / 3.0f}}};
  const int N = 96, steps = 60;
  long long removed = 0; /* strays and particles that left the domain, over the cases */
  for (size_t c = 0; c < sizeof cases / sizeof *cases; ++c) {
    const int *q = cases[c];
    const lsm_time time = (lsm_time)q[0];
    lsm_grid *phi = new_grid(N, N, 1.0f, 1.0f), *target = new_grid(N, N, 1.0f, 1.0f);
    lsm_grid *s1 = new_grid(N, N, 1.0f, 1.0f), *s2 = new_grid(N, N, 1.0f, 1.0f);
    /* a box (particles escape at its corners) into a disc past the right edge */
    for (int j = 0; j < N; ++j)
      for (int i = 0; i < N; ++i) {
        const double qx = fabs(i - 38.3) - 21.0, qy = fabs(j - 47.6) - 28.0;
        const double out = hypot(qx > 0 ? qx : 0, qy > 0 ? qy : 0);
        LSM_AT(phi, i, j) = (float)(qx > 0 || qy > 0 ? out : (qx > qy ? qx : qy));
      }
    lsm_grid_fill_ghosts(phi);
    fill_disc(target, 78.0, 43.0, 34.0);
    lsm_morph_opts mo;
    lsm_morph_opts_default(&mo);
    mo.time = time;
    mo.particles = 1;
    mo.threads = q[3];
    mo.pls.reseed_every = q[1];
    mo.pls.radius_adjust = q[2];
    mo.band = 0; /* the direct loop below sweeps every cell */
    lsm_morph *m = NULL;
    lsm_err err;
    lsm_err_clear(&err);
    assert_int_equal(lsm_morph_create(phi, target, &mo, &m, &err), LSM_OK);
    lsm_pls_opts po = mo.pls;
    po.threads = q[3];
    lsm_particles *p = new_pls(phi, &po);
    const float dt = (float)lsm_morph_dt(m);
    const int stages = lsm_time_stages(time);
    for (int n = 0; n < steps; ++n) {
      assert_int_equal(lsm_morph_step(m, INFINITY, &err), LSM_OK);
      lsm_pls_begin_step(p, stages);
      lsm_grid *out[3] = {s1, time == LSM_TIME_RK2 ? phi : s2, phi};
      lsm_grid *in[3] = {phi, s1, s2};
      for (int k = 0; k < stages; ++k) {
        lsm_grid_fill_ghosts(in[k]);
        stage(p, in[k], target, coef[stages - 1][k][0], coef[stages - 1][k][1], dt);
        lsm_scheme_stage(LSM_SCHEME_UPWIND, out[k], phi, in[k], target, coef[stages - 1][k][0],
                         coef[stages - 1][k][1], dt, q[3]);
      }
      if (time == LSM_TIME_EULER) lsm_grid_swap(phi, s1);
      correct(p, phi);
    }
    const lsm_grid *got = lsm_morph_phi(m);
    assert_non_null(got);
    for (int j = 0; j < N; ++j)
      assert_memory_equal(&LSM_AT(got, 0, j), &LSM_AT(phi, 0, j), (size_t)N * sizeof(float));
    const lsm_pls_stats *a = lsm_morph_pls_stats(m), *b = lsm_pls_stats_get(p);
    print_message("pls: %s reseed %d adjust %d threads %d: seeded %lld, left %lld, strays %lld, "
                  "escaped %lld, corrected %lld, reseeds %d\n", lsm_time_name(time), q[1], q[2],
                  q[3], b->seeded, b->left_domain, b->stray, b->escaped_total, b->corrected_total,
                  b->reseeds);
    assert_memory_equal(a, b, sizeof *a);
    assert_true(b->escaped_total > 0 && b->corrected_total > 0);
    removed += b->left_domain;
    if (q[1]) assert_int_equal(b->reseeds, steps / q[1]);
    lsm_morph_destroy(&m);
    lsm_pls_destroy(&p);
    lsm_grid_destroy(&phi);
    lsm_grid_destroy(&target);
    lsm_grid_destroy(&s1);
    lsm_grid_destroy(&s2);
  }
  assert_true(removed > 0);
}

/* Reseeding and radius adjustment keep the bookkeeping consistent:
 * count = seeded - discarded - left_domain - reseed_dropped, radii in range,
 * and a reseed puts back a freshly seeded band of the current phi. */
static void test_reseed_and_adjust(void **state) {
  (void)state;
  run_result a = run_sequence(1, 0, 3, 1, 7);
  const lsm_pls_stats *s = &a.stats;
  assert_int_equal(s->steps, 7);
  assert_int_equal(s->reseeds, 2);
  assert_int_equal((long long)a.n, s->seeded - s->discarded - s->left_domain - s->reseed_dropped);
  assert_true(s->reseed_dropped > 0);
  for (size_t k = 0; k < a.n; ++k) assert_true(a.r[k] >= 0.1f - 1e-7f && a.r[k] <= 0.5f + 1e-7f);
  /* radius adjustment: particles on their side have r = clamp(s phi(p)) of the
   * final phi (the run ended right after a correction without reseed at 7) */
  int checked = 0;
  for (size_t k = 0; k < a.n; ++k) {
    double ph = bilinear(a.phi, a.x[k], a.y[k]);
    if (ph * a.s[k] > 0.0) {
      double sp = a.s[k] * ph, want = sp > 0.5 ? 0.5 : (sp < 0.1 ? 0.1 : sp);
      assert_close(a.r[k], want, 1e-5);
      ++checked;
    }
  }
  assert_true(checked > 1000);
  free_result(&a);

  /* reseeding at every step on an unchanged phi reproduces the same count */
  lsm_grid *phi = new_grid(60, 60, 1.0f, 1.0f);
  fill_disc(phi, 30.0, 30.0, 15.0);
  lsm_pls_opts o;
  lsm_pls_opts_default(&o);
  o.reseed_every = 1;
  lsm_particles *p = new_pls(phi, &o);
  const long long band = lsm_pls_stats_get(p)->band_cells;
  lsm_pls_begin_step(p, 1);
  stage(p, phi, phi, 0.0f, 1.0f, 0.1f); /* F = 0: nothing moves */
  correct(p, phi);
  const lsm_pls_stats *st = lsm_pls_stats_get(p);
  assert_int_equal(st->reseeds, 1);
  assert_int_equal(st->band_cells, band);
  assert_int_equal(st->seeded, 2 * 16 * band);
  assert_int_equal((long long)lsm_pls_count(p),
                   st->seeded - st->discarded - st->left_domain - st->reseed_dropped);
  assert_true((double)lsm_pls_count(p) >= 0.95 * 16.0 * (double)band);
  lsm_pls_destroy(&p);
  lsm_grid_destroy(&phi);
}

/* Particles that escaped too far (strays) are removed as having left the
 * domain, also when a reseed follows in the same correction: with or without
 * reseeding, every stray is counted in left_domain (run.json's "discarded"
 * relies on it), none in reseed_dropped. */
static void test_strays_counted_with_reseed(void **state) {
  (void)state;
  for (int reseed = 0; reseed <= 1; ++reseed) {
    lsm_grid *phi = new_grid(40, 40, 1.0f, 1.0f), *moved = new_grid(40, 40, 1.0f, 1.0f);
    fill_disc(phi, 20.0, 20.0, 8.0);
    fill_disc(moved, 20.0, 20.0, 11.0); /* the front jumps 3 px out */
    lsm_pls_opts o;
    lsm_pls_opts_default(&o);
    o.reseed_every = reseed;
    lsm_particles *p = new_pls(phi, &o);
    correct(p, moved);
    correct(p, moved); /* without reseeding the strays leave at this one */
    const lsm_pls_stats *st = lsm_pls_stats_get(p);
    if (!(st->stray > 0 && st->stray == st->left_domain))
      fail_msg("reseed_every %d: %lld strays, %lld left the domain", reseed, st->stray,
               st->left_domain);
    assert_int_equal((long long)lsm_pls_count(p),
                     st->seeded - st->discarded - st->left_domain - st->reseed_dropped);
    lsm_pls_destroy(&p);
    lsm_grid_destroy(&phi);
    lsm_grid_destroy(&moved);
  }
}

/* Bad options are errors; tiny grids give an empty set. */
static void test_options_and_edges(void **state) {
  (void)state;
  lsm_grid *phi = new_grid(8, 8, 1.0f, 1.0f);
  fill_disc(phi, 4, 4, 2);
  lsm_pls_opts o;
  lsm_pls_opts_default(&o);
  assert_int_equal(o.particles_per_cell, 16);
  assert_int_equal(o.reseed_every, 0);
  assert_int_equal(o.radius_adjust, 0);
  assert_true(o.seed == LSM_PLS_DEFAULT_SEED);
  lsm_particles *p = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  o.particles_per_cell = 0;
  assert_int_equal(lsm_pls_create(phi, &o, &p, &err), LSM_ERR_USAGE);
  assert_null(p);
  assert_true(strstr(err.msg, "particles per cell") != NULL);
  lsm_pls_opts_default(&o);
  o.reseed_every = -1;
  lsm_err_clear(&err);
  assert_int_equal(lsm_pls_create(phi, &o, &p, &err), LSM_ERR_USAGE);
  /* correcting a grid of another size is refused */
  assert_int_equal(lsm_pls_create(phi, NULL, &p, &err), LSM_OK);
  lsm_grid *other = new_grid(9, 8, 1.0f, 1.0f);
  lsm_err_clear(&err);
  assert_int_equal(lsm_pls_correct(p, other, &err), LSM_ERR_INTERNAL);
  assert_int_equal(lsm_pls_stats_get(p)->steps, 0);
  lsm_grid_destroy(&other);
  lsm_pls_destroy(&p);
  lsm_grid_destroy(&phi);

  phi = new_grid(1, 5, 1.0f, 1.0f);
  lsm_err_clear(&err);
  assert_int_equal(lsm_pls_create(phi, NULL, &p, &err), LSM_OK);
  assert_int_equal(lsm_pls_count(p), 0);
  lsm_pls_begin_step(p, 1);
  stage(p, phi, phi, 0.0f, 1.0f, 1.0f);
  assert_int_equal(lsm_pls_correct(p, phi, &err), LSM_OK);
  lsm_pls_destroy(&p);
  lsm_pls_destroy(&p); /* NULL is fine */
  lsm_grid_destroy(&phi);
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
      cmocka_unit_test(test_determinism_threads),
      cmocka_unit_test(test_morph_equals_direct_particles),
      cmocka_unit_test(test_reseed_and_adjust),
      cmocka_unit_test(test_strays_counted_with_reseed),
      cmocka_unit_test(test_options_and_edges),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
