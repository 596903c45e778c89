/* The OpenCL backend: the ops of lsm_backend.h on an OpenCL device, a row of the table of
 * backends (lsm_backend_opencl_entry, declared in solver/pde/lsm_backend.h).
 *
 * The run-wide context is lsm_cl_context (device, program); a pair state is the grid's fields
 * (lsm_cl_grid) and, with --method pls, its particles (lsm_cl_particles); the registration of
 * --motion field runs its levels on the device (lsm_cl_motion). */
#include "kernels/opencl/lsm_cl_context.h"
#include "kernels/opencl/lsm_cl_grid.h"
#include "kernels/opencl/lsm_cl_motion.h"
#include "kernels/opencl/lsm_cl_particles.h"
#include "solver/pde/lsm_backend.h"

#include <stdlib.h>

typedef struct cl_pair {
  lsm_cl_grid *grid;
  lsm_cl_particles *particles; /* created by the first pls_load */
} cl_pair;

static lsm_status cl_open(int device, int threads, void **ctx, lsm_err *err) {
  (void)threads; /* the device runs its own */
  return lsm_cl_context_open(device, ctx, err);
}

static int cl_facts(const void *ctx, lsm_backend_fact *facts, int max) {
  const lsm_cl_ctx *c = ctx;
  return lsm_backend_contract_facts(facts, max, c->name, c->build_seconds);
}

static void cl_destroy(void *state) {
  cl_pair *s = state;
  if (!s) return;
  lsm_cl_pls_destroy(s->particles);
  lsm_cl_grid_destroy(s->grid);
  free(s);
}

static lsm_status cl_create(void *ctx, const lsm_grid *phi_source, const lsm_grid *phi_target,
                            int threads, void **state, lsm_err *err) {
  *state = NULL;
  cl_pair *s = calloc(1, sizeof *s);
  if (!s) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: cannot allocate the backend state");
  lsm_status st = lsm_cl_grid_create(ctx, phi_source, phi_target, threads, &s->grid, err);
  if (st != LSM_OK) {
    free(s);
    return st;
  }
  *state = s;
  return LSM_OK;
}

static lsm_status cl_fill_ghosts(void *state, lsm_field f, lsm_err *err) {
  return lsm_cl_grid_fill_ghosts(((cl_pair *)state)->grid, f, err);
}

static lsm_status cl_copy(void *state, lsm_field dst, lsm_field src, lsm_err *err) {
  return lsm_cl_grid_copy(((cl_pair *)state)->grid, dst, src, err);
}

static void cl_swap(void *state, lsm_field a, lsm_field b) {
  lsm_cl_grid_swap(((cl_pair *)state)->grid, a, b);
}

static lsm_status cl_stage(void *state, lsm_scheme scheme, lsm_field out, lsm_field u0,
                           lsm_field in, float c0, float c1, float dt, lsm_err *err) {
  return lsm_cl_grid_stage(((cl_pair *)state)->grid, scheme, out, u0, in, c0, c1, dt, err);
}

static lsm_status cl_max_rate(void *state, lsm_scheme scheme, float *rate, lsm_err *err) {
  return lsm_cl_grid_max_rate(((cl_pair *)state)->grid, scheme, rate, err);
}

static lsm_status cl_residual(void *state, double *norm, lsm_err *err) {
  return lsm_cl_grid_residual(((cl_pair *)state)->grid, norm, err);
}

static lsm_status cl_reinit_sweep(void *state, lsm_field out, lsm_field in, lsm_err *err) {
  return lsm_cl_grid_reinit_sweep(((cl_pair *)state)->grid, out, in, err);
}

static lsm_status cl_read_phi(void *state, const lsm_grid **phi, lsm_err *err) {
  return lsm_cl_grid_read_phi(((cl_pair *)state)->grid, phi, err);
}

static lsm_status cl_upload(void *state, const lsm_grid *phi, lsm_err *err) {
  return lsm_cl_grid_upload(((cl_pair *)state)->grid, phi, err);
}

static lsm_status cl_pls_load(void *state, const lsm_pls_view *set, int radius_adjust,
                              lsm_err *err) {
  cl_pair *s = state;
  return lsm_cl_pls_load(&s->particles, s->grid, set, radius_adjust, err);
}

static lsm_status cl_pls_stage(void *state, lsm_field in, float c0, float c1, float dt,
                               int stage, int stages, lsm_err *err) {
  (void)stages; /* the first stage records the base positions, whatever follows */
  cl_pair *s = state;
  return lsm_cl_pls_stage(s->particles, s->grid, in, c0, c1, dt, stage == 0, err);
}

static lsm_status cl_pls_correct(void *state, lsm_pls_stats *stats, lsm_err *err) {
  cl_pair *s = state;
  return lsm_cl_pls_correct(s->particles, s->grid, stats, err);
}

static lsm_status cl_band_set(void *state, const lsm_band_lists *lists, lsm_err *err) {
  return lsm_cl_band_set(((cl_pair *)state)->grid, lists, err);
}

static lsm_status cl_band_write(void *state, lsm_field field, const int32_t *cells,
                                const float *values, size_t n, lsm_err *err) {
  return lsm_cl_band_write(((cl_pair *)state)->grid, field, cells, values, n, err);
}

static lsm_status cl_fill_rim(void *state, lsm_field field, float g, lsm_err *err) {
  return lsm_cl_band_fill_rim(((cl_pair *)state)->grid, field, g, err);
}

static void cl_motion(void *ctx, struct lsm_motion_device *dev) {
  lsm_cl_motion_device(ctx, dev);
}

static const lsm_backend_ops cl_ops = {
    .facts = cl_facts,
    .close = lsm_cl_context_close,
    .create = cl_create,
    .destroy = cl_destroy,
    .fill_ghosts = cl_fill_ghosts,
    .copy = cl_copy,
    .swap = cl_swap,
    .stage = cl_stage,
    .max_rate = cl_max_rate,
    .residual = cl_residual,
    .reinit_sweep = cl_reinit_sweep,
    .read_phi = cl_read_phi,
    .upload = cl_upload,
    .pls_load = cl_pls_load,
    .pls_stage = cl_pls_stage,
    .pls_correct = cl_pls_correct,
    .band_set = cl_band_set,
    .band_write = cl_band_write,
    .fill_rim = cl_fill_rim,
    .motion = cl_motion,
};

const lsm_backend_entry lsm_backend_opencl_entry = {.host_threads = 0,
                                                    .open = cl_open,
                                                    .list_devices = lsm_cl_list_devices,
                                                    .ops = &cl_ops};
