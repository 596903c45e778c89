#include "solver/pde/lsm_morph.h"

#include "solver/pde/lsm_fields.h"

#include "kernels/lsm_cell.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct lsm_morph {
  lsm_morph_opts opts;
  lsm_fields *fields;     /* phi, phi_target and scratch on the backend */
  lsm_grid *phi_target;   /* host copy of the target */
  const lsm_grid *phi;    /* phi on the host (lsm_morph_phi), when not stale */
  int host_stale;         /* the backend's phi changed since */
  lsm_particles *seeds;   /* particles: the host set that seeds and reseeds ... */
  lsm_pls_stats pls_stats; /* ... and the counters of the set the backend steps */
  lsm_err err;            /* why the last lsm_morph_phi failed */
  double dt, time, cp, residual;
  int iterations;
  int still; /* phi_source == phi_target: nothing moves, not even outside the band */
};

void lsm_morph_opts_default(lsm_morph_opts *opts) {
  /* the rest 0 / NULL: no reinitialisation, no particles, the C backend, no stop flag; the
   * narrow band on */
  static const lsm_morph_opts defaults = {.scheme = LSM_SCHEME_UPWIND,
                                          .time = LSM_TIME_EULER,
                                          .cfl = 0.75,
                                          .reinit_iters = 10,
                                          .threads = 1,
                                          .track_cp = 1,
                                          .band = 1};
  *opts = defaults;
  lsm_pls_opts_default(&opts->pls);
}

void lsm_morph_destroy(lsm_morph **morph) {
  if (!morph || !*morph) return;
  lsm_morph *m = *morph;
  lsm_fields_destroy(&m->fields);
  lsm_grid_destroy(&m->phi_target);
  lsm_pls_destroy(&m->seeds);
  free(m);
  *morph = NULL;
}

/* ||phi - phi_target||_2 over the grid.  Where CP decides when a pair stops
 * (track_cp: the per-iteration mode, and the step that lands on a slice), it
 * is summed on the host from the downloaded phi, so every backend stops at
 * the same step (a device's float reduction differs in the last bits, enough
 * to flip CP <= --tol); else the backend's own sum. */
static lsm_status morph_residual(lsm_morph *m, double *residual, lsm_err *err) {
  if (!m->opts.track_cp) return lsm_fields_residual(m->fields, residual, err);
  const lsm_grid *phi = lsm_morph_phi(m);
  if (!phi) return lsm_fail(err, m->err.status, NULL, "%s", m->err.msg);
  *residual = lsm_grid_diff_norm(phi, m->phi_target, m->opts.threads);
  return LSM_OK;
}

/* The CFL step of phi now; with the band (whose cells outside relax as a distance does,
 * phi - phi_target times 1 - dt each step, without a CFL bound of their own) at most 1, so
 * that factor never turns negative (solver/README.md §4). */
static lsm_status band_dt(lsm_morph *m, lsm_err *err) {
  double dt;
  LSM_TRY(lsm_fields_cfl_dt(m->fields, m->opts.scheme, m->opts.cfl, &dt, err));
  if (lsm_fields_banded(m->fields) && !(dt <= 1.0) && !m->still) dt = 1.0;
  m->dt = dt;
  return LSM_OK;
}

/* Whether two grids hold the same interior values. */
static int same_interior(const lsm_grid *a, const lsm_grid *b) {
  for (int j = 0; j < a->ny; ++j)
    if (memcmp(&LSM_AT(a, 0, j), &LSM_AT(b, 0, j), (size_t)a->nx * sizeof(float)) != 0) return 0;
  return 1;
}

/* Loads the seeding set's particles onto the backend. */
static lsm_status pls_load(lsm_morph *m, lsm_err *err) {
  const lsm_pls_view set = lsm_pls_view_get(m->seeds);
  return lsm_fields_pls_load(m->fields, &set, m->opts.pls.radius_adjust, err);
}

lsm_status lsm_morph_create(const lsm_grid *phi_source, const lsm_grid *phi_target,
                            const lsm_morph_opts *opts, lsm_morph **out, lsm_err *err) {
  *out = NULL;
  if (phi_source->nx != phi_target->nx || phi_source->ny != phi_target->ny)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "morph: source and target sizes differ");
  if (!(opts->cfl > 0.0) || !isfinite(opts->cfl))
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "CFL number %g must be positive", opts->cfl);
  lsm_morph *m = calloc(1, sizeof *m);
  if (!m) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate a morph");
  m->opts = *opts;
  if (m->opts.threads < 1) m->opts.threads = 1;
  lsm_status st =
      lsm_fields_create(opts->backend, phi_source, phi_target, m->opts.threads, &m->fields, err);
  if (st == LSM_OK) st = lsm_grid_clone(phi_target, &m->phi_target, err);
  if (st == LSM_OK && opts->particles && !lsm_fields_has_particles(m->fields))
    st = lsm_fail(err, LSM_ERR_UNSUPPORTED, NULL,
                  "--method pls: the %s backend cannot run particles (use --backend c)",
                  lsm_fields_backend_name(m->fields));
  if (st == LSM_OK && opts->particles) {
    /* seeded on the host, stepped and corrected by the backend */
    lsm_pls_opts po = opts->pls;
    po.threads = m->opts.threads;
    st = lsm_pls_create(phi_source, &po, &m->seeds, err);
    if (st == LSM_OK) st = pls_load(m, err);
    if (st == LSM_OK) m->pls_stats = *lsm_pls_stats_get(m->seeds);
  }
  if (st == LSM_OK && opts->band && lsm_fields_has_band(m->fields)) {
    m->still = same_interior(phi_source, phi_target);
    lsm_band_params bp;
    lsm_band_params_of(opts->scheme, phi_source->dx, phi_source->dy, &bp);
    st = lsm_fields_band_start(m->fields, m->phi_target, &bp, err);
  }
  if (st == LSM_OK) st = band_dt(m, err);
  /* a rate that overflowed a float gives a step of 0: no step could advance
   * the morph (lsm_morph_advance_to would never arrive) */
  if (st == LSM_OK && !(m->dt > 0.0))
    st = lsm_fail(err, LSM_ERR_NUMERIC, NULL,
                  "morph: the CFL time step is %g (speeds or gradients too large for floats)",
                  m->dt);
  if (st == LSM_OK) st = morph_residual(m, &m->residual, err);
  if (st == LSM_OK && !isfinite(m->residual))
    st = lsm_fail(err, LSM_ERR_NUMERIC, NULL, "morph: the initial fields are not finite");
  if (st != LSM_OK) {
    lsm_morph_destroy(&m);
    return st;
  }
  m->cp = INFINITY;
  *out = m;
  return LSM_OK;
}

/* The particles' correction after a step (on the backend), and every
 * reseed_every steps their reseeding on the host: phi comes down, the seeding
 * set seeds its next generation on it and the new set goes up.  The strays of
 * this correction are still in the backend's set: they count as having left
 * the domain, the others as dropped by the reseeding (as lsm_pls_reseed
 * counts). */
static lsm_status pls_correct(lsm_morph *m, lsm_err *err) {
  lsm_pls_stats *q = &m->pls_stats;
  const long long strays_before = q->stray;
  LSM_TRY(lsm_fields_pls_correct(m->fields, q, err));
  if (m->opts.pls.reseed_every <= 0 || q->steps % m->opts.pls.reseed_every != 0) return LSM_OK;
  const lsm_grid *phi = lsm_morph_phi(m);
  if (!phi) return lsm_fail(err, m->err.status, NULL, "%s", m->err.msg);
  q->left_domain += q->stray - strays_before;
  q->reseed_dropped += q->seeded - q->discarded - q->left_domain - q->reseed_dropped;
  q->reseeds++;
  const lsm_pls_stats before = *lsm_pls_stats_get(m->seeds);
  LSM_TRY(lsm_pls_reseed(m->seeds, phi, err));
  const lsm_pls_stats *after = lsm_pls_stats_get(m->seeds);
  q->seeded += after->seeded - before.seeded;
  q->discarded += after->discarded - before.discarded;
  q->band_cells = after->band_cells;
  return pls_load(m, err);
}

/* dt = min(dt, the CFL step of phi now). */
static lsm_status shrink_dt(lsm_morph *m, const char *after, lsm_err *err) {
  const double dt = m->dt;
  LSM_TRY(band_dt(m, err));
  if (dt < m->dt) m->dt = dt;
  if (!(m->dt > 0.0))
    return lsm_fail(err, LSM_ERR_NUMERIC, NULL, "iteration %d: the CFL time step after %s is %g",
                    m->iterations, after, m->dt);
  return LSM_OK;
}

lsm_status lsm_morph_step(lsm_morph *m, double max_dt, lsm_err *err) {
  double dt = m->dt < max_dt ? m->dt : max_dt;
  if (!(dt > 0.0)) return LSM_OK;
  if (!isfinite(dt)) {
    /* Nothing can move (phi == phi_target, or phi has no gradient anywhere):
     * the morph is at rest. */
    m->cp = 0.0;
    return LSM_OK;
  }
  LSM_TRY(lsm_fields_step(m->fields, m->opts.scheme, m->opts.time, (float)dt, err));
  m->iterations++;
  m->time += dt;
  m->host_stale = 1;
  /* Particles repair phi where they escaped (Alg. 3.3). */
  if (m->seeds) LSM_TRY(pls_correct(m, err));
  if (m->opts.reinit_every > 0 && m->iterations % m->opts.reinit_every == 0) {
    LSM_TRY(lsm_fields_reinit(m->fields, m->opts.reinit_iters, err));
    m->host_stale = 1;
    /* The step was fixed from phi_0 (the design document's rule); a
     * reinitialised phi can move faster (steeper where it was flat, farther
     * from phi_target where it was clamped), so the CFL bound is taken again
     * and the step only ever shrinks. */
    LSM_TRY(shrink_dt(m, "reinitialisation", err));
  }
  int rebuilt = 0;
  LSM_TRY(lsm_fields_band_maintain(m->fields, &rebuilt, err));
  if (rebuilt) {
    /* cells the band took in may move faster: each one's rate is bounded by its speed
     * whatever its gradient (kernels/lsm_cell.h) */
    const lsm_grid *t = m->phi_target;
    const float rate = lsm_cfl_rate_bound(m->opts.scheme == LSM_SCHEME_ROEFIX,
                                          lsm_fields_band_enter_speed(m->fields), 1.0f / t->dx,
                                          1.0f / t->dy);
    const double entered = lsm_cfl_step(m->opts.cfl, rate);
    if (entered < m->dt) m->dt = entered;
  }
  if (m->opts.track_cp || m->iterations % 16 == 0) {
    double residual;
    LSM_TRY(morph_residual(m, &residual, err));
    if (!isfinite(residual))
      return lsm_fail(err, LSM_ERR_NUMERIC, NULL,
                      "iteration %d: phi is no longer finite (dt %g, CFL %g)", m->iterations, dt,
                      m->opts.cfl);
    m->cp = fabs(residual - m->residual);
    m->residual = residual;
  }
  return LSM_OK;
}

lsm_status lsm_morph_advance_to(lsm_morph *m, double t, int max_iter, lsm_err *err) {
  if (!isfinite(m->dt)) {
    /* At rest (phi == phi_target, or no gradient anywhere): phi stays as it
     * is for all time, so any time is reached without a step. */
    if (m->time < t) m->time = t;
    m->cp = 0.0;
    return LSM_OK;
  }
  /* A relative slack keeps round-off from adding a vanishing extra step. */
  while (m->time < t * (1.0 - 1e-12) && m->iterations < max_iter) {
    if (m->opts.stop && *m->opts.stop)
      return lsm_fail(err, LSM_ERR_INTERRUPTED, NULL, "interrupted at iteration %d", m->iterations);
    const int last = m->time + m->dt >= t * (1.0 - 1e-12) || m->iterations + 1 >= max_iter;
    if (last && !m->opts.track_cp) {
      /* Without per-step tracking, CP is still measured on the step that
       * lands on t: the residual just before it and just after it, both
       * taken as tracking takes them (on a device backend the host's sum in
       * double, not the device's in float: CP is their difference) */
      m->opts.track_cp = 1;
      lsm_status st = morph_residual(m, &m->residual, err);
      if (st == LSM_OK) st = lsm_morph_step(m, t - m->time, err);
      m->opts.track_cp = 0;
      LSM_TRY(st);
    } else {
      LSM_TRY(lsm_morph_step(m, t - m->time, err));
    }
  }
  return LSM_OK;
}

const lsm_grid *lsm_morph_phi(lsm_morph *m) {
  if (m->host_stale || !m->phi) {
    lsm_err_clear(&m->err);
    if (lsm_fields_phi(m->fields, &m->phi, &m->err) != LSM_OK) return NULL;
    m->host_stale = 0;
  }
  return m->phi;
}

const lsm_grid *lsm_morph_target(const lsm_morph *m) { return m->phi_target; }
const lsm_err *lsm_morph_error(const lsm_morph *m) { return &m->err; }
const lsm_pls_stats *lsm_morph_pls_stats(const lsm_morph *m) {
  return m->seeds ? &m->pls_stats : NULL;
}
double lsm_morph_time(const lsm_morph *m) { return m->time; }
double lsm_morph_dt(const lsm_morph *m) { return m->dt; }
int lsm_morph_iterations(const lsm_morph *m) { return m->iterations; }
double lsm_morph_cp(const lsm_morph *m) { return m->cp; }
double lsm_morph_residual(const lsm_morph *m) { return m->residual; }
long long lsm_morph_cell_updates(const lsm_morph *m) { return lsm_fields_cell_updates(m->fields); }
long long lsm_morph_grid_cells(const lsm_morph *m) {
  return (long long)m->phi_target->nx * m->phi_target->ny;
}
int lsm_morph_banded(const lsm_morph *m) { return lsm_fields_banded(m->fields); }

double lsm_morph_time_of_fraction(double s) {
  if (s <= 0.0) return 0.0;
  if (s >= 1.0) return INFINITY;
  return -log1p(-s);
}
