/* lsm_api: liblsmorph's public functions (solver/api/lsmorph.h) over the
 * solver's rooms: options by name, in-memory slice sources and sinks, status
 * codes and messages. */
#include "solver/api/lsmorph.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "solver/base/lsm_status.h"
#include "solver/base/lsm_voxels.h"
#include "solver/fill/lsm_fill.h"
#include "solver/pde/lsm_backend.h"
#include "solver/recon/lsm_stack.h"

/* The public codes are lsm_status's values. */
_Static_assert(LSMORPH_ERR_INTERNAL == (int)LSM_ERR_INTERNAL, "status codes out of step");
_Static_assert(LSMORPH_INT64 == (int)LSM_VOXEL_I64, "voxel types out of step");

const char *lsmorph_status_name(int status) { return lsm_status_name((lsm_status)status); }
const char *lsmorph_version(void) { return LSMORPH_VERSION; }

void lsmorph_options_default(lsmorph_options *o) {
  memset(o, 0, sizeof *o);
  o->size = sizeof *o;
  o->cfl = 0.75;
  o->max_iter = 100000;
  o->reinit_iters = 10;
  o->particles_per_cell = 16;
  o->seed = 20130101u;
  o->device = -1;
}

/* Hands err's message to the caller's buffer and returns its status. */
static int finish(lsm_status st, const lsm_err *err, char *message, size_t size) {
  if (message && size) snprintf(message, size, "%s", st == LSM_OK ? "" : err->msg);
  return (int)st;
}

#define ENUM_OPTION(field, from_name, target, what, names)                        \
  do {                                                                             \
    if (o->field) {                                                                \
      const int v_ = (int)from_name(o->field);                                     \
      if (v_ < 0)                                                                  \
        return lsm_fail(err, LSM_ERR_USAGE, NULL, what ": '%s' is not one of " names, o->field); \
      target = v_;                                                                 \
    }                                                                              \
  } while (0)

/* The stack options and backend the public options ask for; ends_given: the
 * caller chose the end rule. */
static lsm_status stack_options(const lsmorph_options *o, lsm_stack_opts *so, int *ends_given,
                                int *threads, const char **backend, lsm_err *err) {
  lsm_stack_opts_default(so);
  *ends_given = 0;
  *threads = 0;
  *backend = "c";
  if (!o) return LSM_OK;
  if (o->size != sizeof *o)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "options: fill them with lsmorph_options_default");
  int v = 0;
  ENUM_OPTION(method, lsm_method_from_name, v, "method", "ls, pls, blend");
  if (o->method) so->method = (lsm_method)v;
  ENUM_OPTION(interp, lsm_interp_from_name, v, "interp", "linear, cubic");
  if (o->interp) so->interp = (lsm_interp)v;
  ENUM_OPTION(ends, lsm_end_rule_from_name, v, "ends", "tip, halfway, auto");
  if (o->ends) so->ends = (lsm_end_rule)v;
  *ends_given = o->ends != NULL;
  ENUM_OPTION(align, lsm_align_from_name, v, "align", "hull, none, auto");
  if (o->align) so->align = (lsm_align)v;
  ENUM_OPTION(motion, lsm_motion_from_name, v, "motion", "auto, field, none");
  if (o->motion) so->motion = (lsm_motion_mode)v;
  ENUM_OPTION(scheme, lsm_scheme_from_name, v, "scheme", "upwind, roe-fix, weno5");
  if (o->scheme) so->morph.scheme = (lsm_scheme)v;
  ENUM_OPTION(time, lsm_time_from_name, v, "time", "euler, rk2, rk3");
  if (o->time) so->morph.time = (lsm_time)v;
  if (o->backend) *backend = o->backend; /* lsm_backend_open checks the name */
  if (!(o->cfl > 0.0) || !isfinite(o->cfl))
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "cfl: %g must be positive", o->cfl);
  if (o->max_iter < 1 || o->reinit_every < 0 || o->reinit_iters < 1 || o->reinit_iters > 100000 ||
      o->particles_per_cell < 2 || o->particles_per_cell > 256 || o->threads < 0 ||
      o->threads > 4096)
    return lsm_fail(err, LSM_ERR_USAGE, NULL,
                    "options: max_iter >= 1, reinit_every >= 0, reinit_iters 1 .. 100000, "
                    "particles_per_cell 2 .. 256, threads 0 .. 4096");
  so->morph.cfl = o->cfl;
  so->max_iter = o->max_iter;
  so->morph.reinit_every = o->reinit_every;
  so->morph.reinit_iters = o->reinit_iters;
  so->morph.pls.particles_per_cell = o->particles_per_cell;
  so->morph.pls.seed = o->seed;
  *threads = o->threads;
  return LSM_OK;
}

/* Runs fn between opening the backend and closing it, on `threads` threads
 * for the loops without their own count (restored after). */
typedef struct run_env {
  lsm_backend *backend;
  int threads, previous;
} run_env;

static lsm_status env_begin(run_env *e, const char *kind, int device, int threads,
                            lsm_err *err) {
  e->previous = omp_get_max_threads();
  e->threads = threads > 0 ? threads : omp_get_num_procs();
  omp_set_num_threads(e->threads);
  e->backend = NULL;
  return lsm_backend_open(kind, device, e->threads, &e->backend, err);
}

static void env_end(run_env *e) {
  lsm_backend_close(&e->backend);
  omp_set_num_threads(e->previous);
}

int lsmorph_fill(void *labels, lsmorph_dtype dtype, const size_t n[3], const double spacing[3],
                 int axis, const size_t *slices, size_t n_slices, const int64_t *fill_labels,
                 size_t n_labels, const lsmorph_options *options, size_t *filled, char *message,
                 size_t message_size) {
  lsm_err err;
  lsm_err_clear(&err);
  if (filled) *filled = 0;
  if (!labels || !n || !spacing || (int)dtype < 0 || dtype > LSMORPH_INT64 || axis < -1 || axis > 2)
    return finish(lsm_fail(&err, LSM_ERR_USAGE, NULL,
                           "fill: labels, a voxel type, the sizes and the spacing are needed, "
                           "and an axis of -1, 0, 1 or 2"),
                  &err, message, message_size);
  lsm_voxels v = {{n[0], n[1], n[2]}, (lsm_voxel_type)dtype, labels,
                  {spacing[0], spacing[1], spacing[2]}};
  for (int a = 0; a < 3; ++a)
    if (!(spacing[a] > 0.0) || !isfinite(spacing[a]))
      return finish(lsm_fail(&err, LSM_ERR_USAGE, NULL, "fill: spacing %g along %c is not a "
                             "length", spacing[a], "ijk"[a]), &err, message, message_size);
  lsm_fill_opts o;
  lsm_fill_opts_default(&o);
  o.axis = axis;
  o.slices = slices;
  o.n_slices = slices ? n_slices : 0;
  o.labels = fill_labels;
  o.n_labels = fill_labels ? n_labels : 0;
  const char *kind = "c";
  lsm_status st = stack_options(options, &o.stack, &o.ends_given, &o.threads, &kind, &err);
  run_env env;
  memset(&env, 0, sizeof env);
  lsm_fill_plan *plan = NULL;
  if (st == LSM_OK) st = lsm_fill_plan_make(&v, &o, &plan, &err);
  if (st == LSM_OK && plan->gap_slices > 0) {
    st = env_begin(&env, kind, options ? options->device : -1, o.threads, &err);
    o.threads = env.threads;
    o.stack.morph.backend = env.backend;
    lsm_fill_stats stats;
    if (st == LSM_OK) st = lsm_fill_run(plan, &v, &o, &stats, &err);
    env_end(&env);
  }
  if (st == LSM_OK && filled) *filled = plan->gap_slices;
  lsm_fill_plan_free(&plan);
  return finish(st, &err, message, message_size);
}

size_t lsmorph_reconstruct_count(const double *z, size_t count, double dz) {
  if (!z || count < 2 || !(dz > 0.0)) return 0;
  return lsm_stack_output_count(z, count, dz);
}

/* The in-memory stack: masks in, phi out by slice index. */
typedef struct memory_stack {
  const uint8_t *masks;
  size_t width, height, count;
  float *out;
  size_t out_slices;
  double z0, dz;
} memory_stack;

static lsm_status memory_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
  const memory_stack *m = ctx;
  LSM_TRY(lsm_mask_create((int)m->width, (int)m->height, out, err));
  const uint8_t *src = m->masks + index * m->width * m->height;
  for (size_t k = 0; k < m->width * m->height; ++k) out->pixels[k] = src[k] != 0;
  return LSM_OK;
}

static lsm_status memory_emit(void *ctx, const float *phi, int width, int height, double z,
                              long input_index, lsm_err *err) {
  (void)input_index;
  memory_stack *m = ctx;
  const double at = nearbyint((z - m->z0) / m->dz);
  if (!(at >= 0.0) || !(at < (double)m->out_slices))
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "an output slice at %g lies past the output", z);
  memcpy(m->out + (size_t)at * m->width * m->height, phi,
         (size_t)width * (size_t)height * sizeof *phi);
  return LSM_OK;
}

int lsmorph_reconstruct(const uint8_t *masks, size_t count, size_t width, size_t height,
                        const double *z, double dx, double dy, double dz,
                        const lsmorph_options *options, float *out, size_t out_slices,
                        char *message, size_t message_size) {
  lsm_err err;
  lsm_err_clear(&err);
  if (!masks || !z || !out || count < 2 || width < 1 || height < 1 || width > (1u << 24) ||
      height > (1u << 24) || width * height > (size_t)LSM_GRID_CELLS_MAX)
    return finish(lsm_fail(&err, LSM_ERR_USAGE, NULL,
                           "reconstruct: at least two masks of 1 .. 2^24 pixels a side, their "
                           "heights and an output are needed"),
                  &err, message, message_size);
  if (!(dx > 0.0) || !isfinite(dx) || !(dy > 0.0) || !isfinite(dy))
    return finish(lsm_fail(&err, LSM_ERR_USAGE, NULL,
                           "reconstruct: the pixel size %g x %g is not two lengths", dx, dy),
                  &err, message, message_size);
  if (!isfinite(dz))
    return finish(lsm_fail(&err, LSM_ERR_USAGE, NULL,
                           "reconstruct: the output spacing dz %g is not a number (<= 0: the "
                           "smaller pixel side)", dz),
                  &err, message, message_size);
  lsm_stack_opts so;
  int ends_given = 0, threads = 0;
  const char *kind = "c";
  lsm_status st = stack_options(options, &so, &ends_given, &threads, &kind, &err);
  so.pixel_dx = dx;
  so.pixel_dy = dy;
  so.dz = dz > 0.0 ? dz : 0.0;
  const double step = lsm_stack_output_dz(&so);
  if (st == LSM_OK && out_slices != lsmorph_reconstruct_count(z, count, step))
    st = lsm_fail(&err, LSM_ERR_USAGE, NULL,
                  "reconstruct: the output holds %zu slices, lsmorph_reconstruct_count gives %zu",
                  out_slices, lsmorph_reconstruct_count(z, count, step));
  memory_stack m = {masks, width, height, count, out, out_slices, z[0], step};
  run_env env;
  memset(&env, 0, sizeof env);
  lsm_pair_stats *stats = st == LSM_OK ? lsm_alloc(count, sizeof *stats, &err, "statistics") : NULL;
  if (st == LSM_OK && !stats) st = err.status;
  if (st == LSM_OK) {
    st = env_begin(&env, kind, options ? options->device : -1, threads, &err);
    so.morph.threads = env.threads;
    so.morph.backend = env.backend;
    const lsm_slice_source source = {&m, count, z, memory_load, NULL};
    const lsm_slice_sink sink = {&m, memory_emit};
    if (st == LSM_OK)
      st = lsm_stack_run(&source, (int)width, (int)height, &so, &sink, stats, NULL, &err);
    env_end(&env);
  }
  free(stats);
  return finish(st, &err, message, message_size);
}
