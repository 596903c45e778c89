#include "solver/pde/lsm_fields.h"

#include <math.h>
#include <stdlib.h>

/* Below this relaxation factor the band's amplitudes are rescaled (g = 1 again), so that
 * phi_target + a g never needs a g near float's smallest normal numbers. */
#define BAND_G_RESCALE 1e-12

struct lsm_fields {
  const char *name; /* the backend's */
  const lsm_backend_ops *ops;
  void *state;
  int particles; /* a set is loaded: it takes every stage */
  int threads;
  long long cells;   /* cells each stage sweeps: the interior's, or the band's */
  long long updates; /* cell updates of the stages so far */
  /* the narrow band (NULL: every cell) */
  lsm_band *band;
  const lsm_grid *band_target; /* borrowed from the caller of lsm_fields_band_start */
  lsm_band_params band_params;
  float band_h;              /* the smaller cell side */
  int band_edge;             /* the band's stencils reach the ghost ring */
  double g[LSM_FIELD_COUNT]; /* each field's cells outside the band: target + amplitude g */
  double travel;             /* cells a level may have moved since the band was built */
  double step_travel;        /* ... in the last step */
  lsm_grid *view;            /* phi with the cells outside the band filled (lsm_fields_phi) */
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
  f->threads = threads < 1 ? 1 : threads;
  f->cells = (long long)phi_source->nx * phi_source->ny;
  for (int k = 0; k < LSM_FIELD_COUNT; ++k) f->g[k] = 1.0;
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
  lsm_band_destroy(&(*fields)->band);
  lsm_grid_destroy(&(*fields)->view);
  (*fields)->ops->destroy((*fields)->state);
  free(*fields);
  *fields = NULL;
}

const char *lsm_fields_backend_name(const lsm_fields *f) { return f->name; }

/* A field's cells around the band (its rim, then its ghost ring where the band's stencils
 * reach it), before it is read. */
static lsm_status fill_around(lsm_fields *f, lsm_field field, lsm_err *err) {
  if (!f->band) return f->ops->fill_ghosts(f->state, field, err);
  LSM_TRY(f->ops->fill_rim(f->state, field, (float)f->g[field], err));
  return f->band_edge ? f->ops->fill_ghosts(f->state, field, err) : LSM_OK;
}

lsm_status lsm_fields_cfl_dt(lsm_fields *f, lsm_scheme scheme, double cfl, double *dt,
                             lsm_err *err) {
  float rate = 0.0f;
  LSM_TRY(fill_around(f, LSM_FIELD_PHI, err));
  LSM_TRY(f->ops->max_rate(f->state, scheme, &rate, err));
  *dt = lsm_cfl_step(cfl, rate);
  return LSM_OK;
}

lsm_status lsm_fields_step(lsm_fields *f, lsm_scheme scheme, lsm_time time, float dt,
                           lsm_err *err) {
  const rk_tableau *t = &tableaux[time >= 0 && time < LSM_TIME_COUNT ? time : LSM_TIME_EULER];
  for (int k = 0; k < t->stages; ++k) {
    const rk_stage *s = &t->stage[k];
    LSM_TRY(fill_around(f, s->in, err));
    if (f->particles)
      LSM_TRY(f->ops->pls_stage(f->state, s->in, s->c0, s->c1, dt, k, t->stages, err));
    LSM_TRY(f->ops->stage(f->state, scheme, s->out, s->u0, s->in, s->c0, s->c1, dt, err));
    /* the stage on a cell where phi is a distance: phi - target times 1 - dt */
    f->g[s->out] = s->c0 * f->g[s->u0] + s->c1 * f->g[s->in] * (1.0 - (double)dt);
    f->updates += f->cells;
  }
  if (t->result != LSM_FIELD_PHI) lsm_fields_swap(f, LSM_FIELD_PHI, t->result);
  if (f->band) {
    /* a level moves with speed |phi - target| <= the band's largest, at most one cell a stage
     * (monotone schemes); sqrt 2: the band's widths count 4-neighbour steps */
    const double h = f->band_h, moved = 1.4142135623730951 * dt * lsm_band_speed(f->band) / h;
    f->step_travel = moved < t->stages ? moved : t->stages;
    f->travel += f->step_travel;
  }
  return LSM_OK;
}

lsm_status lsm_fields_reinit(lsm_fields *f, int iterations, lsm_err *err) {
  if (iterations <= 0) return LSM_OK;
  LSM_TRY(fill_around(f, LSM_FIELD_PHI, err));
  LSM_TRY(f->ops->copy(f->state, LSM_FIELD_PHI0, LSM_FIELD_PHI, err));
  /* pseudo-time: the cells outside the band do not move */
  f->g[LSM_FIELD_PHI0] = f->g[LSM_FIELD_STAGE1] = f->g[LSM_FIELD_PHI];
  for (int it = 0; it < iterations; ++it) {
    LSM_TRY(fill_around(f, LSM_FIELD_PHI, err));
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
  if (!f->band) {
    LSM_TRY(f->ops->fill_ghosts(f->state, LSM_FIELD_PHI, err));
    return f->ops->read_phi(f->state, phi, err);
  }
  const lsm_grid *now;
  LSM_TRY(f->ops->read_phi(f->state, &now, err));
  if (!f->view) LSM_TRY(lsm_grid_clone(now, &f->view, err));
  lsm_band_materialize(f->band, now, f->g[LSM_FIELD_PHI], f->view, f->threads);
  lsm_grid_fill_ghosts(f->view);
  *phi = f->view;
  return LSM_OK;
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
  LSM_TRY(f->ops->upload(f->state, phi, err));
  /* the band starts again around the new phi */
  return f->band ? lsm_fields_band_start(f, f->band_target, &f->band_params, err) : LSM_OK;
}

void lsm_fields_swap(lsm_fields *f, lsm_field a, lsm_field b) {
  f->ops->swap(f->state, a, b);
  const double t = f->g[a];
  f->g[a] = f->g[b];
  f->g[b] = t;
}

long long lsm_fields_cell_updates(const lsm_fields *f) { return f->updates; }
long long lsm_fields_cells(const lsm_fields *f) { return f->cells; }
int lsm_fields_banded(const lsm_fields *f) { return f->band != NULL; }
float lsm_fields_band_enter_speed(const lsm_fields *f) {
  return f->band ? lsm_band_enter_speed(f->band) : 0.0f;
}

int lsm_fields_has_band(const lsm_fields *f) {
  return f->ops->band_set && f->ops->band_write && f->ops->fill_rim;
}

/* Hands the band's lists to the backend and writes the cells that entered it into phi. */
static lsm_status band_hand_over(lsm_fields *f, lsm_err *err) {
  const lsm_band_lists l = lsm_band_get(f->band);
  LSM_TRY(f->ops->band_set(f->state, &l, err));
  if (l.entered)
    LSM_TRY(f->ops->band_write(f->state, LSM_FIELD_PHI, l.enter, l.enter_value, l.entered, err));
  f->cells = (long long)l.cells;
  f->band_edge = l.edge;
  f->travel = 0.0;
  return LSM_OK;
}

lsm_status lsm_fields_band_start(lsm_fields *f, const lsm_grid *phi_target,
                                 const lsm_band_params *params, lsm_err *err) {
  if (!lsm_fields_has_band(f))
    return lsm_fail(err, LSM_ERR_UNSUPPORTED, NULL, "the %s backend has no narrow band", f->name);
  const lsm_grid *phi;
  LSM_TRY(f->ops->fill_ghosts(f->state, LSM_FIELD_PHI, err));
  LSM_TRY(f->ops->read_phi(f->state, &phi, err));
  lsm_band *band = NULL;
  LSM_TRY(lsm_band_create(phi, phi_target, params, &band, err));
  lsm_band_destroy(&f->band);
  f->band = band;
  f->band_target = phi_target;
  f->band_params = *params;
  f->band_h = phi->dx < phi->dy ? phi->dx : phi->dy;
  for (int k = 0; k < LSM_FIELD_COUNT; ++k) f->g[k] = 1.0;
  return band_hand_over(f, err);
}

lsm_status lsm_fields_band_maintain(lsm_fields *f, int *rebuilt, lsm_err *err) {
  *rebuilt = 0;
  if (!f->band) return LSM_OK;
  const double g = f->g[LSM_FIELD_PHI];
  /* the next step could carry a level past the band's margin, or a front may appear */
  if (f->travel + f->step_travel <= f->band_params.travel && g > lsm_band_next_g(f->band))
    return LSM_OK;
  const lsm_grid *phi;
  LSM_TRY(fill_around(f, LSM_FIELD_PHI, err));
  LSM_TRY(f->ops->read_phi(f->state, &phi, err));
  LSM_TRY(lsm_band_rebuild(f->band, phi, g, err));
  if (g < BAND_G_RESCALE) {
    lsm_band_rescale(f->band, g);
    for (int k = 0; k < LSM_FIELD_COUNT; ++k) f->g[k] /= g;
  }
  *rebuilt = 1;
  return band_hand_over(f, err);
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
