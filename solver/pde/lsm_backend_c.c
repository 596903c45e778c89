/* The scalar C backend: the reference.  Fields live on the host; the cell
 * loops are in lsm_scheme.c and lsm_reinit.c (OpenMP over rows). */
#include <stdlib.h>
#include <string.h>

#include "solver/pde/lsm_backend.h"
#include "solver/pde/lsm_reinit.h"

typedef struct c_state {
  lsm_grid *phi, *phi_target;
  lsm_stepper *stepper;
  lsm_reinit *reinit; /* created on first use */
  int threads;
} c_state;

static void c_destroy(void **state) {
  if (!state || !*state) return;
  c_state *s = *state;
  lsm_grid_destroy(&s->phi);
  lsm_grid_destroy(&s->phi_target);
  lsm_stepper_destroy(&s->stepper);
  lsm_reinit_destroy(&s->reinit);
  free(s);
  *state = NULL;
}

static lsm_status c_create(void *ctx, const lsm_grid *phi_source, const lsm_grid *phi_target,
                           int threads, void **state, lsm_err *err) {
  (void)ctx;
  *state = NULL;
  c_state *s = calloc(1, sizeof *s);
  if (!s) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the C backend state");
  s->threads = threads < 1 ? 1 : threads;
  lsm_status st = lsm_grid_clone(phi_source, &s->phi, err);
  if (st == LSM_OK) st = lsm_grid_clone(phi_target, &s->phi_target, err);
  if (st == LSM_OK) st = lsm_stepper_create(phi_source, &s->stepper, err);
  if (st != LSM_OK) {
    void *p = s;
    c_destroy(&p);
    return st;
  }
  lsm_grid_fill_ghosts(s->phi_target);
  *state = s;
  return LSM_OK;
}

static lsm_status c_cfl_dt(void *state, lsm_scheme scheme, double cfl, double *dt,
                           lsm_err *err) {
  (void)err;
  c_state *s = state;
  lsm_cfl_dt(s->phi, s->phi_target, scheme, cfl, s->threads, dt);
  return LSM_OK;
}

static lsm_status c_step(void *state, lsm_scheme scheme, lsm_time time, float dt,
                         const lsm_stage_hook *hook, lsm_err *err) {
  (void)err;
  c_state *s = state;
  lsm_step_hooked(s->stepper, scheme, time, s->phi, s->phi_target, dt, s->threads, hook);
  return LSM_OK;
}

static lsm_status c_reinit(void *state, int iterations, lsm_err *err) {
  c_state *s = state;
  if (!s->reinit) LSM_TRY(lsm_reinit_create(s->phi, &s->reinit, err));
  lsm_reinit_run(s->reinit, s->phi, iterations, s->threads);
  return LSM_OK;
}

static lsm_status c_residual(void *state, double *norm, lsm_err *err) {
  (void)err;
  c_state *s = state;
  *norm = lsm_grid_diff_norm(s->phi, s->phi_target, s->threads);
  return LSM_OK;
}

static lsm_status c_download(void *state, lsm_grid *phi, lsm_err *err) {
  (void)err;
  c_state *s = state;
  if (phi != s->phi) lsm_grid_copy(phi, s->phi);
  return LSM_OK;
}

static lsm_status c_upload(void *state, const lsm_grid *phi, lsm_err *err) {
  (void)err;
  c_state *s = state;
  if (phi != s->phi) lsm_grid_copy(s->phi, phi);
  return LSM_OK;
}

static lsm_grid *c_host_phi(void *state) { return ((c_state *)state)->phi; }

/* Particles run on the host phi through the stage hook (solver/pde/lsm_particles.c):
 * no particle ops. */
static const lsm_backend_ops c_ops = {.name = "c",
                                      .create = c_create,
                                      .cfl_dt = c_cfl_dt,
                                      .step = c_step,
                                      .reinit = c_reinit,
                                      .residual = c_residual,
                                      .download = c_download,
                                      .upload = c_upload,
                                      .host_phi = c_host_phi,
                                      .destroy = c_destroy,
                                      .pls_load = NULL,
                                      .pls_correct = NULL};

const lsm_backend_ops *lsm_backend_c_ops(void) { return &c_ops; }

/* ---- opening a backend ---------------------------------------------------------- */

LSM_NAME_FUNCTIONS(lsm_backend_kind, LSM_BACKEND_LIST, lsm_backend_kind_name,
                   lsm_backend_kind_from_name)

lsm_status lsm_backend_open(lsm_backend_kind kind, int device, int threads, lsm_backend **out,
                            lsm_err *err) {
  *out = NULL;
  lsm_backend *b = calloc(1, sizeof *b);
  if (!b) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate a backend");
  if (kind == LSM_BACKEND_OPENCL || kind == LSM_BACKEND_AUTO) {
    lsm_err cl_err;
    lsm_err_clear(&cl_err);
    lsm_status st = lsm_backend_cl_open(device, b, &cl_err);
    if (st == LSM_OK) {
      *out = b;
      return LSM_OK;
    }
    if (kind == LSM_BACKEND_OPENCL) {
      free(b);
      return lsm_fail(err, st, NULL, "%s", cl_err.msg);
    }
    snprintf(b->fallback, sizeof b->fallback, "%s", cl_err.msg);
  }
  b->ops = lsm_backend_c_ops();
  snprintf(b->device, sizeof b->device, "C (%d thread%s)", threads, threads == 1 ? "" : "s");
  *out = b;
  return LSM_OK;
}

void lsm_backend_close(lsm_backend **backend) {
  if (!backend || !*backend) return;
  if ((*backend)->close_ctx) (*backend)->close_ctx(&(*backend)->ctx);
  free(*backend);
  *backend = NULL;
}

lsm_status lsm_backend_list_devices(FILE *f, lsm_err *err) { return lsm_backend_cl_list(f, err); }
