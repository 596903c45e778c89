/* Tests of solver/pde/lsm_particles.c over whole sequences of steps:
 * bit-identical results for 1, 2 and 3 threads (Euler and RK3 stages,
 * reseeding, radius adjustment), lsm_morph's particles (through the backend's
 * particle ops) equal to this module driven directly, consistent bookkeeping
 * with reseeding and radius adjustment, strays counted as having left the
 * domain, and bad options and tiny grids. */
#include "tests/lsm_test_particles.h"

#include "solver/base/lsm_grid.h"
#include "solver/pde/lsm_morph.h"
#include "solver/pde/lsm_particles.h"
#include "solver/pde/lsm_scheme.h"
#include "solver/base/lsm_status.h"

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
      cmocka_unit_test(test_determinism_threads),
      cmocka_unit_test(test_morph_equals_direct_particles),
      cmocka_unit_test(test_reseed_and_adjust),
      cmocka_unit_test(test_strays_counted_with_reseed),
      cmocka_unit_test(test_options_and_edges),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
