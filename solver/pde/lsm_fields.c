#include "solver/pde/lsm_fields.h"

#include <stdlib.h>

struct lsm_fields {
  const char *name; /* the backend's */
  const lsm_backend_ops *ops;
  void *state;
  int particles; /* a set is loaded: it takes every stage */
};

/* One stage of a tableau: out = c0 u0 + c1 (in - dt L(in)). */
typedef struct rk_stage {
  lsm_field out, u0, in;
  float c0, c1;
} rk_stage;

/* A Shu–Osher tableau; `result` holds the step's result, swapped into phi when it is
 * another field (Euler computes into a scratch field: in and out must differ). */
typedef struct rk_tableau {
  int stages;
  rk_stage stage[3];
  lsm_field result;
} rk_tableau;

#define PHI LSM_FIELD_PHI
#define S1 LSM_FIELD_STAGE1
#define S2 LSM_FIELD_STAGE2

/* Euler: phi - dt L(phi).  RK2 (Heun): phi1 = phi - dt L(phi), phi = 1/2 phi + 1/2 (phi1 - dt
 * L(phi1)).  RK3: phi1 as RK2, phi2 = 3/4 phi + 1/4 (phi1 - dt L(phi1)), phi = 1/3 phi + 2/3
 * (phi2 - dt L(phi2)). */
static const rk_tableau tableaux[LSM_TIME_COUNT] = {
    [LSM_TIME_EULER] = {1, {{S1, PHI, PHI, 0.0f, 1.0f}}, S1},
    [LSM_TIME_RK2] = {2, {{S1, PHI, PHI, 0.0f, 1.0f}, {PHI, PHI, S1, 0.5f, 0.5f}}, PHI},
    [LSM_TIME_RK3] = {3,
                      {{S1, PHI, PHI, 0.0f, 1.0f},
                       {S2, PHI, S1, 0.75f, 0.25f},
                       {PHI, PHI, S2, 1.0f / 3.0f, 2.0f / 3.0f}},
                      PHI},
};

lsm_status lsm_fields_create(const lsm_backend *backend, const lsm_grid *phi_source,
                             const lsm_grid *phi_target, int threads, lsm_fields **out,
                             lsm_err *err) {
  *out = NULL;
  if (phi_source->nx != phi_target->nx || phi_source->ny != phi_target->ny)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "fields: source and target sizes differ");
  lsm_fields *f = calloc(1, sizeof *f);
  if (!f) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate a pair's fields");
  f->name = backend ? backend->name : "c";
  f->ops = backend ? backend->entry->ops : lsm_backend_c_entry.ops;
  lsm_status st = f->ops->create(backend ? backend->ctx : NULL, phi_source, phi_target,
                                 threads < 1 ? 1 : threads, &f->state, err);
  if (st != LSM_OK) {
    free(f);
    return st;
  }
  *out = f;
  return LSM_OK;
}

void lsm_fields_destroy(lsm_fields **fields) {
  if (!fields || !*fields) return;
  (*fields)->ops->destroy((*fields)->state);
  free(*fields);
  *fields = NULL;
}

const char *lsm_fields_backend_name(const lsm_fields *f) { return f->name; }

lsm_status lsm_fields_cfl_dt(lsm_fields *f, lsm_scheme scheme, double cfl, double *dt,
                             lsm_err *err) {
  float rate = 0.0f;
  LSM_TRY(f->ops->fill_ghosts(f->state, LSM_FIELD_PHI, err));
  LSM_TRY(f->ops->max_rate(f->state, scheme, &rate, err));
  *dt = lsm_cfl_step(cfl, rate);
  return LSM_OK;
}

lsm_status lsm_fields_step(lsm_fields *f, lsm_scheme scheme, lsm_time time, float dt,
                           lsm_err *err) {
  const rk_tableau *t = &tableaux[time >= 0 && time < LSM_TIME_COUNT ? time : LSM_TIME_EULER];
  for (int k = 0; k < t->stages; ++k) {
    const rk_stage *s = &t->stage[k];
    LSM_TRY(f->ops->fill_ghosts(f->state, s->in, err));
    if (f->particles)
      LSM_TRY(f->ops->pls_stage(f->state, s->in, s->c0, s->c1, dt, k, t->stages, err));
    LSM_TRY(f->ops->stage(f->state, scheme, s->out, s->u0, s->in, s->c0, s->c1, dt, err));
  }
  if (t->result != LSM_FIELD_PHI) f->ops->swap(f->state, LSM_FIELD_PHI, t->result);
  return LSM_OK;
}

lsm_status lsm_fields_reinit(lsm_fields *f, int iterations, lsm_err *err) {
  if (iterations <= 0) return LSM_OK;
  LSM_TRY(f->ops->fill_ghosts(f->state, LSM_FIELD_PHI, err));
  LSM_TRY(f->ops->copy(f->state, LSM_FIELD_PHI0, LSM_FIELD_PHI, err));
  for (int it = 0; it < iterations; ++it) {
    LSM_TRY(f->ops->fill_ghosts(f->state, LSM_FIELD_PHI, err));
    LSM_TRY(f->ops->reinit_sweep(f->state, LSM_FIELD_STAGE1, LSM_FIELD_PHI, err));
    f->ops->swap(f->state, LSM_FIELD_PHI, LSM_FIELD_STAGE1);
  }
  return f->ops->fill_ghosts(f->state, LSM_FIELD_PHI, err);
}

lsm_status lsm_fields_residual(lsm_fields *f, double *norm, lsm_err *err) {
  return f->ops->residual(f->state, norm, err);
}

lsm_status lsm_fields_phi(lsm_fields *f, const lsm_grid **phi, lsm_err *err) {
  *phi = NULL;
  LSM_TRY(f->ops->fill_ghosts(f->state, LSM_FIELD_PHI, err));
  return f->ops->read_phi(f->state, phi, err);
}

lsm_status lsm_fields_download(lsm_fields *f, lsm_grid *phi, lsm_err *err) {
  const lsm_grid *now;
  LSM_TRY(lsm_fields_phi(f, &now, err));
  if (phi->nx != now->nx || phi->ny != now->ny)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "fields: host grid %dx%d, phi %dx%d", phi->nx,
                    phi->ny, now->nx, now->ny);
  lsm_grid_copy(phi, now);
  return LSM_OK;
}

lsm_status lsm_fields_upload(lsm_fields *f, const lsm_grid *phi, lsm_err *err) {
  return f->ops->upload(f->state, phi, err);
}

int lsm_fields_has_particles(const lsm_fields *f) {
  return f->ops->pls_load && f->ops->pls_stage && f->ops->pls_correct;
}

lsm_status lsm_fields_pls_load(lsm_fields *f, const lsm_pls_view *set, int radius_adjust,
                               lsm_err *err) {
  if (!lsm_fields_has_particles(f))
    return lsm_fail(err, LSM_ERR_UNSUPPORTED, NULL,
                    "--method pls: the %s backend cannot run particles", f->name);
  LSM_TRY(f->ops->pls_load(f->state, set, radius_adjust, err));
  f->particles = 1;
  return LSM_OK;
}

lsm_status lsm_fields_pls_correct(lsm_fields *f, lsm_pls_stats *stats, lsm_err *err) {
  if (!f->particles)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "particles: no set loaded on the %s backend",
                    f->name);
  return f->ops->pls_correct(f->state, stats, err);
}
