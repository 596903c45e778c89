#include "lsm_morph.h"

#include <math.h>
#include <stdlib.h>

#include "lsm_reinit.h"

struct lsm_morph {
  lsm_morph_opts opts;
  lsm_grid *phi, *phi_target;
  lsm_stepper *stepper;
  lsm_reinit *reinit;
  double dt, time, cp, residual;
  int iterations;
};

void lsm_morph_opts_default(lsm_morph_opts *opts) {
  opts->scheme = LSM_SCHEME_UPWIND;
  opts->time = LSM_TIME_EULER;
  opts->cfl = 0.75;
  opts->reinit_every = 0;
  opts->reinit_iters = 10;
  opts->threads = 1;
}

void lsm_morph_destroy(lsm_morph **morph) {
  if (!morph || !*morph) return;
  lsm_morph *m = *morph;
  lsm_grid_destroy(&m->phi);
  lsm_grid_destroy(&m->phi_target);
  lsm_stepper_destroy(&m->stepper);
  lsm_reinit_destroy(&m->reinit);
  free(m);
  *morph = NULL;
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
  lsm_status status = lsm_grid_clone(phi_source, &m->phi, err);
  if (status == LSM_OK) status = lsm_grid_clone(phi_target, &m->phi_target, err);
  if (status == LSM_OK) status = lsm_stepper_create(phi_source, &m->stepper, err);
  if (status == LSM_OK && opts->reinit_every > 0)
    status = lsm_reinit_create(phi_source, &m->reinit, err);
  if (status != LSM_OK) {
    lsm_morph_destroy(&m);
    return status;
  }
  lsm_grid_fill_ghosts(m->phi_target);
  lsm_cfl_dt(m->phi, m->phi_target, opts->cfl, m->opts.threads, &m->dt);
  m->residual = lsm_grid_diff_norm(m->phi, m->phi_target, m->opts.threads);
  m->cp = INFINITY;
  if (!isfinite(m->residual)) {
    lsm_morph_destroy(&m);
    return lsm_fail(err, LSM_ERR_NUMERIC, NULL, "morph: the initial fields are not finite");
  }
  *out = m;
  return LSM_OK;
}

lsm_status lsm_morph_step(lsm_morph *m, double max_dt, lsm_err *err) {
  double dt = m->dt < max_dt ? m->dt : max_dt;
  if (!(dt > 0.0)) return LSM_OK;
  lsm_step(m->stepper, m->opts.scheme, m->opts.time, m->phi, m->phi_target, (float)dt,
           m->opts.threads);
  m->iterations++;
  m->time += dt;
  if (m->reinit && m->iterations % m->opts.reinit_every == 0)
    lsm_reinit_run(m->reinit, m->phi, m->opts.reinit_iters, m->opts.threads);
  double residual = lsm_grid_diff_norm(m->phi, m->phi_target, m->opts.threads);
  if (!isfinite(residual))
    return lsm_fail(err, LSM_ERR_NUMERIC, NULL,
                    "iteration %d: phi is no longer finite (dt %g, CFL %g)", m->iterations, dt,
                    m->opts.cfl);
  m->cp = fabs(residual - m->residual);
  m->residual = residual;
  return LSM_OK;
}

lsm_status lsm_morph_advance_to(lsm_morph *m, double t, int max_iter, lsm_err *err) {
  /* A relative slack keeps round-off from adding a vanishing extra step. */
  while (m->time < t * (1.0 - 1e-12) && m->iterations < max_iter)
    LSM_TRY(lsm_morph_step(m, t - m->time, err));
  return LSM_OK;
}

const lsm_grid *lsm_morph_phi(const lsm_morph *m) { return m->phi; }
const lsm_grid *lsm_morph_target(const lsm_morph *m) { return m->phi_target; }
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
