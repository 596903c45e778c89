#include "solver/pde/lsm_morph.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct lsm_morph {
  lsm_morph_opts opts;
  const lsm_backend_ops *ops;
  void *state;           /* the backend's per-pair fields */
  lsm_grid *phi_target;  /* host copy of the target */
  lsm_grid *phi_host;    /* host mirror of phi for device backends */
  int host_stale;        /* phi_host is older than the device's phi */
  lsm_particles *pls;    /* the host set: seeded here; stepped here unless pls_device */
  int pls_device;        /* particles run on the backend (its pls_load / pls_correct) */
  lsm_pls_stats pls_stats; /* ... and then their counters, kept here */
  long long pls_live;    /* ... and how many particles the backend holds */
  lsm_err err;           /* why the last lsm_morph_phi failed */
  double dt, time, cp, residual;
  int iterations;
};

void lsm_morph_opts_default(lsm_morph_opts *opts) {
  memset(opts, 0, sizeof *opts);
  opts->scheme = LSM_SCHEME_UPWIND;
  opts->time = LSM_TIME_EULER;
  opts->cfl = 0.75;
  opts->reinit_every = 0;
  opts->reinit_iters = 10;
  opts->threads = 1;
  opts->track_cp = 1;
  opts->particles = 0;
  lsm_pls_opts_default(&opts->pls);
  opts->backend = NULL;
  opts->stop = NULL;
}

void lsm_morph_destroy(lsm_morph **morph) {
  if (!morph || !*morph) return;
  lsm_morph *m = *morph;
  if (m->ops && m->state) m->ops->destroy(&m->state);
  lsm_grid_destroy(&m->phi_target);
  lsm_grid_destroy(&m->phi_host);
  lsm_pls_destroy(&m->pls);
  free(m);
  *morph = NULL;
}

/* ||phi - phi_target||_2 over the grid.  Where CP decides when a pair stops
 * (track_cp: the per-iteration mode), it is summed on the host exactly as the
 * C backend sums it, so every backend stops at the same step (a device's float
 * reduction differs in the last bits, enough to flip CP <= --tol); the
 * per-iteration output downloads phi every step anyway.  Else the backend's
 * own reduction. */
static lsm_status morph_residual(lsm_morph *m, double *residual, lsm_err *err) {
  if (!m->opts.track_cp || m->ops->host_phi(m->state)) {
    LSM_TRY(m->ops->residual(m->state, residual, err));
    /* a device sums in float, which overflows where lengths are near 1e18
     * or more (allowed up to 1e30): then the host's sum in double */
    if (isfinite(*residual) || m->ops->host_phi(m->state)) return LSM_OK;
  }
  const lsm_grid *phi = lsm_morph_phi(m);
  if (!phi) return lsm_fail(err, m->err.status, NULL, "%s", m->err.msg);
  *residual = lsm_grid_diff_norm(phi, m->phi_target, m->opts.threads);
  return LSM_OK;
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
  m->ops = opts->backend ? opts->backend->ops : lsm_backend_c_ops();
  lsm_status st = m->ops->create(opts->backend ? opts->backend->ctx : NULL, phi_source,
                                 phi_target, m->opts.threads, &m->state, err);
  if (st == LSM_OK) st = lsm_grid_clone(phi_target, &m->phi_target, err);
  if (st == LSM_OK && !m->ops->host_phi(m->state))
    st = lsm_grid_clone(phi_source, &m->phi_host, err);
  if (st == LSM_OK && opts->particles) {
    /* Particles on the backend when it has the particle ops, else through the
     * stage hook on the host phi; seeded on the host either way. */
    m->pls_device = m->ops->pls_load && m->ops->pls_correct;
    if (!m->pls_device && !m->ops->host_phi(m->state))
      st = lsm_fail(err, LSM_ERR_UNSUPPORTED, NULL,
                    "--method pls: the %s backend cannot run particles (use --backend c)",
                    m->ops->name);
  }
  if (st == LSM_OK && opts->particles) {
    lsm_pls_opts po = opts->pls;
    po.threads = m->opts.threads;
    st = lsm_pls_create(phi_source, &po, &m->pls, err);
  }
  if (st == LSM_OK && m->pls_device) {
    const lsm_pls_view set = lsm_pls_view_get(m->pls);
    st = m->ops->pls_load(m->state, &set, opts->pls.radius_adjust, err);
    m->pls_stats = *lsm_pls_stats_get(m->pls);
    m->pls_live = (long long)set.n;
  }
  if (st == LSM_OK) st = m->ops->cfl_dt(m->state, opts->scheme, opts->cfl, &m->dt, err);
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

/* Reseeding of a set that runs on the backend, on the host: phi comes down,
 * the host set seeds its next generation on it (the same particles as the C
 * path's reseeding at this step), and the new set goes up.  The backend's set
 * still holds the strays its last correction found (the C path removes them
 * as it reseeds and counts them as left the domain): `strays` of the live. */
static lsm_status device_reseed(lsm_morph *m, long long strays, lsm_err *err) {
  LSM_TRY(m->ops->download(m->state, m->phi_host, err));
  const lsm_pls_stats before = *lsm_pls_stats_get(m->pls);
  LSM_TRY(lsm_pls_reseed(m->pls, m->phi_host, err));
  const lsm_pls_stats *after = lsm_pls_stats_get(m->pls);
  lsm_pls_stats *q = &m->pls_stats;
  q->left_domain += strays;
  q->reseed_dropped += m->pls_live - strays;
  q->reseeds++;
  q->seeded += after->seeded - before.seeded;
  q->discarded += after->discarded - before.discarded;
  q->band_cells = after->band_cells;
  const lsm_pls_view set = lsm_pls_view_get(m->pls);
  LSM_TRY(m->ops->pls_load(m->state, &set, m->opts.pls.radius_adjust, err));
  m->pls_live = (long long)set.n;
  return LSM_OK;
}

/* lsm_pls_correct for a set on the backend: the correction there, the
 * counters here (as lsm_pls_correct counts), reseeding on the host. */
static lsm_status device_correct(lsm_morph *m, lsm_err *err) {
  lsm_pls_counts c;
  LSM_TRY(m->ops->pls_correct(m->state, &c, err));
  lsm_pls_stats *q = &m->pls_stats;
  q->left_domain += c.removed;
  q->stray += c.stray;
  q->escaped_last = c.escaped;
  q->corrected_last = c.corrected;
  q->escaped_total += c.escaped;
  q->corrected_total += c.corrected;
  q->steps++;
  m->pls_live -= c.removed;
  if (c.live != m->pls_live)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL,
                    "particles: the %s backend holds %lld live particles, %lld expected",
                    m->ops->name, c.live, m->pls_live);
  if (m->opts.pls.reseed_every > 0 && q->steps % m->opts.pls.reseed_every == 0)
    LSM_TRY(device_reseed(m, c.stray, err));
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
  /* Particles on the host ride the stage hook; on a backend with particle
   * ops, step advects the loaded set itself. */
  lsm_stage_hook hook = {m->pls, lsm_pls_stage_hook};
  const int host_pls = m->pls && !m->pls_device;
  if (host_pls) lsm_pls_begin_step(m->pls, lsm_time_stages(m->opts.time));
  LSM_TRY(m->ops->step(m->state, m->opts.scheme, m->opts.time, (float)dt, host_pls ? &hook : NULL,
                       err));
  m->iterations++;
  m->time += dt;
  m->host_stale = 1;
  /* Particles repair phi where they escaped (Alg. 3.3): on the host phi (C
   * backend) or on the backend's. */
  if (host_pls) LSM_TRY(lsm_pls_correct(m->pls, m->ops->host_phi(m->state), err));
  if (m->pls_device) LSM_TRY(device_correct(m, err));
  if (m->opts.reinit_every > 0 && m->iterations % m->opts.reinit_every == 0) {
    LSM_TRY(m->ops->reinit(m->state, m->opts.reinit_iters, err));
    /* The step was fixed from phi_0 (the design document's rule); a
     * reinitialised phi can move faster (steeper where it was flat, farther
     * from phi_target where it was clamped), so the CFL bound is taken again
     * and the step only ever shrinks. */
    double dt_now;
    LSM_TRY(m->ops->cfl_dt(m->state, m->opts.scheme, m->opts.cfl, &dt_now, err));
    if (dt_now < m->dt) m->dt = dt_now;
    if (!(m->dt > 0.0))
      return lsm_fail(err, LSM_ERR_NUMERIC, NULL,
                      "iteration %d: the CFL time step after reinitialisation is %g",
                      m->iterations, m->dt);
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
  lsm_grid *live = m->ops->host_phi(m->state);
  if (live) return live;
  if (m->host_stale) {
    lsm_err_clear(&m->err);
    if (m->ops->download(m->state, m->phi_host, &m->err) != LSM_OK) return NULL;
    m->host_stale = 0;
  }
  return m->phi_host;
}

const lsm_grid *lsm_morph_target(const lsm_morph *m) { return m->phi_target; }
const lsm_err *lsm_morph_error(const lsm_morph *m) { return &m->err; }
const lsm_pls_stats *lsm_morph_pls_stats(const lsm_morph *m) {
  if (!m->pls) return NULL;
  return m->pls_device ? &m->pls_stats : lsm_pls_stats_get(m->pls);
}
double lsm_morph_time(const lsm_morph *m) { return m->time; }
double lsm_morph_dt(const lsm_morph *m) { return m->dt; }
int lsm_morph_iterations(const lsm_morph *m) { return m->iterations; }
double lsm_morph_cp(const lsm_morph *m) { return m->cp; }
double lsm_morph_residual(const lsm_morph *m) { return m->residual; }

double lsm_morph_time_of_fraction(double s) {
  if (s <= 0.0) return 0.0;
  if (s >= 1.0) return INFINITY;
  return -log1p(-s);
}
