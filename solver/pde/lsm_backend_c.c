/* The C backend, the reference: fields on the host, the cell loops of lsm_scheme.c and
 * lsm_reinit.c (OpenMP over rows), particles through lsm_particles.c. */
#include <stdlib.h>
#include <string.h>

#include "solver/pde/lsm_backend.h"
#include "kernels/lsm_cell.h"
#include "solver/pde/lsm_reinit.h"

typedef struct c_ctx {
  char device[64]; /* "C (2 threads)" */
} c_ctx;

typedef struct c_state {
  lsm_grid *field[LSM_FIELD_COUNT]; /* phi0 created by its first copy */
  lsm_grid *phi_target;
  lsm_particles *pls; /* the loaded particle set (pls_load) */
  int radius_adjust;
  int threads;
  lsm_runs band;          /* the narrow band's cells (band_set), ... */
  const lsm_runs *cells;  /* ... which the cell ops sweep: &band, or NULL for every cell */
  const int32_t *rim;     /* the rim (fill_rim) */
  const float *rim_amplitude;
  size_t rim_cells;
} c_state;

static lsm_status c_open(int device, int threads, void **ctx, lsm_err *err) {
  (void)device;
  c_ctx *c = calloc(1, sizeof *c);
  if (!c) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the C backend");
  snprintf(c->device, sizeof c->device, "C (%d thread%s)", threads, threads == 1 ? "" : "s");
  *ctx = c;
  return LSM_OK;
}

static void c_close(void *ctx) { free(ctx); }

/* Nothing is built: build_seconds 0. */
static int c_facts(const void *ctx, lsm_backend_fact *facts, int max) {
  const c_ctx *c = ctx;
  return lsm_backend_contract_facts(facts, max, c ? c->device : "C", 0.0);
}

static void c_destroy(void *state) {
  c_state *s = state;
  if (!s) return;
  for (int f = 0; f < LSM_FIELD_COUNT; ++f) lsm_grid_destroy(&s->field[f]);
  lsm_grid_destroy(&s->phi_target);
  lsm_pls_destroy(&s->pls);
  free(s);
}

static lsm_status c_create(void *ctx, const lsm_grid *phi_source, const lsm_grid *phi_target,
                           int threads, void **state, lsm_err *err) {
  (void)ctx;
  *state = NULL;
  c_state *s = calloc(1, sizeof *s);
  if (!s) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the C backend state");
  s->threads = threads < 1 ? 1 : threads;
  const lsm_grid *g = phi_source;
  lsm_status st = lsm_grid_clone(phi_source, &s->field[LSM_FIELD_PHI], err);
  if (st == LSM_OK) st = lsm_grid_clone(phi_target, &s->phi_target, err);
  if (st == LSM_OK) st = lsm_grid_create(g->nx, g->ny, g->dx, g->dy, &s->field[LSM_FIELD_STAGE1], err);
  if (st == LSM_OK) st = lsm_grid_create(g->nx, g->ny, g->dx, g->dy, &s->field[LSM_FIELD_STAGE2], err);
  if (st != LSM_OK) {
    c_destroy(s);
    return st;
  }
  lsm_grid_fill_ghosts(s->phi_target);
  *state = s;
  return LSM_OK;
}

static lsm_status c_fill_ghosts(void *state, lsm_field f, lsm_err *err) {
  (void)err;
  lsm_grid_fill_ghosts(((c_state *)state)->field[f]);
  return LSM_OK;
}

static lsm_status c_copy(void *state, lsm_field dst, lsm_field src, lsm_err *err) {
  c_state *s = state;
  if (!s->field[dst]) return lsm_grid_clone(s->field[src], &s->field[dst], err);
  lsm_grid_copy(s->field[dst], s->field[src]);
  return LSM_OK;
}

/* The buffers change places, the grids stay (a phi read through read_phi stays phi). */
static void c_swap(void *state, lsm_field a, lsm_field b) {
  c_state *s = state;
  lsm_grid_swap(s->field[a], s->field[b]);
}

static lsm_status c_stage(void *state, lsm_scheme scheme, lsm_field out, lsm_field u0,
                          lsm_field in, float c0, float c1, float dt, lsm_err *err) {
  (void)err;
  c_state *s = state;
  lsm_scheme_stage_on(scheme, s->field[out], s->field[u0], s->field[in], s->phi_target, c0, c1,
                      dt, s->cells, s->threads);
  return LSM_OK;
}

static lsm_status c_max_rate(void *state, lsm_scheme scheme, float *rate, lsm_err *err) {
  (void)err;
  c_state *s = state;
  *rate = lsm_cfl_max_rate_on(s->field[LSM_FIELD_PHI], s->phi_target, scheme, s->cells,
                              s->threads);
  return LSM_OK;
}

static lsm_status c_residual(void *state, double *norm, lsm_err *err) {
  (void)err;
  c_state *s = state;
  *norm = lsm_grid_diff_norm_on(s->field[LSM_FIELD_PHI], s->phi_target, s->cells, s->threads);
  return LSM_OK;
}

static lsm_status c_reinit_sweep(void *state, lsm_field out, lsm_field in, lsm_err *err) {
  c_state *s = state;
  if (!s->field[LSM_FIELD_PHI0])
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "reinitialisation: phi0 was not taken");
  lsm_reinit_sweep_on(s->field[out], s->field[in], s->field[LSM_FIELD_PHI0], s->cells,
                      s->threads);
  return LSM_OK;
}

static lsm_status c_read_phi(void *state, const lsm_grid **phi, lsm_err *err) {
  (void)err;
  *phi = ((c_state *)state)->field[LSM_FIELD_PHI];
  return LSM_OK;
}

static lsm_status c_upload(void *state, const lsm_grid *phi, lsm_err *err) {
  c_state *s = state;
  lsm_grid *now = s->field[LSM_FIELD_PHI];
  if (phi->nx != now->nx || phi->ny != now->ny)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "C backend: host grid %dx%d differs from %dx%d",
                    phi->nx, phi->ny, now->nx, now->ny);
  lsm_grid_copy(now, phi);
  return LSM_OK;
}

/* ---- particles: a copy of the driver's set, stepped by lsm_particles.c ---------------- */

static lsm_status c_pls_load(void *state, const lsm_pls_view *set, int radius_adjust,
                             lsm_err *err) {
  c_state *s = state;
  if (s->pls && s->radius_adjust != radius_adjust) lsm_pls_destroy(&s->pls);
  if (!s->pls) {
    lsm_pls_opts o;
    lsm_pls_opts_default(&o);
    o.threads = s->threads;
    o.radius_adjust = radius_adjust;
    LSM_TRY(lsm_pls_create_empty(s->field[LSM_FIELD_PHI], &o, &s->pls, err));
    s->radius_adjust = radius_adjust;
  }
  return lsm_pls_set(s->pls, set->n, set->x, set->y, set->sign, set->radius, err);
}

static lsm_status c_pls_stage(void *state, lsm_field in, float c0, float c1, float dt,
                              int stage, int stages, lsm_err *err) {
  c_state *s = state;
  if (stage == 0) lsm_pls_begin_step(s->pls, stages);
  return lsm_pls_stage(s->pls, s->field[in], s->phi_target, c0, c1, dt, err);
}

static lsm_status c_pls_correct(void *state, lsm_pls_stats *stats, lsm_err *err) {
  c_state *s = state;
  return lsm_pls_correct_into(s->pls, s->field[LSM_FIELD_PHI], stats, err);
}

/* ---- the narrow band: the driver's lists, borrowed ---------------------------------------- */

static lsm_status c_band_set(void *state, const lsm_band_lists *lists, lsm_err *err) {
  (void)err;
  c_state *s = state;
  s->band = (lsm_runs){lists->run_start, lists->run_length, lists->runs, lists->cells};
  s->cells = &s->band;
  s->rim = lists->rim;
  s->rim_amplitude = lists->rim_amplitude;
  s->rim_cells = lists->rim_cells;
  return LSM_OK;
}

static lsm_status c_band_write(void *state, lsm_field field, const int32_t *cells,
                               const float *values, size_t n, lsm_err *err) {
  c_state *s = state;
  if (!s->field[field]) return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "band: no such field");
  float *d = s->field[field]->data;
  for (size_t q = 0; q < n; ++q) d[cells[q]] = values[q];
  return LSM_OK;
}

static lsm_status c_fill_rim(void *state, lsm_field field, float g, lsm_err *err) {
  c_state *s = state;
  if (!s->field[field]) return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "band: no such field");
  float *d = s->field[field]->data;
  const float *t = s->phi_target->data;
  for (size_t q = 0; q < s->rim_cells; ++q)
    d[s->rim[q]] = lsm_relaxed(t[s->rim[q]], s->rim_amplitude[q], g);
  return LSM_OK;
}

static const lsm_backend_ops c_ops = {
    .facts = c_facts,
    .close = c_close,
    .create = c_create,
    .destroy = c_destroy,
    .fill_ghosts = c_fill_ghosts,
    .copy = c_copy,
    .swap = c_swap,
    .stage = c_stage,
    .max_rate = c_max_rate,
    .residual = c_residual,
    .reinit_sweep = c_reinit_sweep,
    .read_phi = c_read_phi,
    .upload = c_upload,
    .pls_load = c_pls_load,
    .pls_stage = c_pls_stage,
    .pls_correct = c_pls_correct,
    .band_set = c_band_set,
    .band_write = c_band_write,
    .fill_rim = c_fill_rim,
};

const lsm_backend_entry lsm_backend_c_entry = {
    .host_threads = 1, .open = c_open, .list_devices = NULL, .ops = &c_ops};
