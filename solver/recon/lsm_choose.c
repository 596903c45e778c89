/* lsm_choose: leave-one-out choice of the field (see the header). */
#include "solver/recon/lsm_choose.h"

#include <math.h>
#include <stdlib.h>

#include "solver/recon/lsm_flows.h"
#include "solver/recon/lsm_slice.h"

/* The input slices of src without the left-out one: the up to four nearest. */
typedef struct sub_source {
  const lsm_slice_source *parent;
  size_t index[4];
  double z[4];
  size_t count;
} sub_source;

static lsm_status sub_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
  const sub_source *s = ctx;
  return s->parent->load(s->parent->ctx, s->index[index], out, err);
}

static const char *sub_name(void *ctx, size_t index) {
  const sub_source *s = ctx;
  return s->parent->name ? s->parent->name(s->parent->ctx, s->index[index]) : NULL;
}

/* Counts the pixels where the output slice at height z differs from the left-out slice. */
typedef struct miss_sink {
  const lsm_mask *truth;
  double z, eps;
  long long missed;
  int seen;
} miss_sink;

static lsm_status miss_emit(void *ctx, const float *phi, int width, int height, double z,
                            long input_index, lsm_err *err) {
  (void)err;
  miss_sink *m = ctx;
  if (input_index >= 0 || fabs(z - m->z) > m->eps) return LSM_OK;
  const size_t cells = (size_t)width * (size_t)height;
  long long missed = 0;
  for (size_t i = 0; i < cells; ++i) missed += (phi[i] < 0.0f) != (m->truth->pixels[i] != 0);
  m->missed = missed;
  m->seen = 1;
  return LSM_OK;
}

/* The up to four nearest slices around j, without it. */
static sub_source window(const lsm_slice_source *src, size_t j) {
  sub_source sub = {.parent = src};
  for (size_t k = j >= 2 ? j - 2 : 0; k <= j + 2 && k < src->count; ++k)
    if (k != j) {
      sub.index[sub.count] = k;
      sub.z[sub.count] = src->z[k];
      sub.count++;
    }
  return sub;
}

/* The output step of the run predicting slice j: from the first slice kept through the
 * left-out height, so that with even spacing no output lies inside the other gaps, which are
 * then not morphed. */
static double window_dz(const lsm_slice_source *src, size_t j, const sub_source *sub) {
  return src->z[j] - sub->z[0];
}

/* Slice j of src left out and predicted with `motion`: the pixels missed. */
static lsm_status predict(const lsm_slice_source *src, size_t j, const lsm_mask *truth, int width,
                          int height, const lsm_stack_opts *o, lsm_motion_mode motion,
                          int threads, lsm_flows *run, long long *missed, lsm_err *err) {
  sub_source sub = window(src, j);
  const lsm_slice_source source = {&sub, sub.count, sub.z, sub_load, sub_name};
  const lsm_flows_lender lender = {run, sub.index, sub.count};
  lsm_stack_opts so = *o;
  so.motion = motion;
  so.lender = run ? &lender : NULL;
  so.dz = window_dz(src, j, &sub);
  so.transport = NULL;
  so.morph.threads = threads;
  const double span = src->z[j + 1] - src->z[j - 1];
  miss_sink m = {truth, src->z[j], 1e-6 * span, 0, 0};
  const lsm_slice_sink sink = {&m, miss_emit};
  lsm_pair_stats stats[3];
  LSM_TRY(lsm_stack_run(&source, width, height, &so, &sink, stats, NULL, err));
  if (!m.seen) return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "leave-one-out: no slice at %g", m.z);
  *missed = m.missed;
  return LSM_OK;
}

int lsm_choose_can_leave_out(const lsm_slice_source *src, size_t j, const lsm_stack_opts *o) {
  if (j == 0 || j + 1 >= src->count) return 0;
  /* uneven heights can make that step finer than the run's own: then the prediction would
   * write more slices than the run does over the same heights (a step of 0.001 between
   * slices 1000 apart, a million), and the slice is not left out */
  const sub_source sub = window(src, j);
  const size_t asked = lsm_stack_output_count(sub.z, sub.count, window_dz(src, j, &sub));
  return asked <= lsm_stack_output_count(sub.z, sub.count, lsm_stack_output_dz(o));
}

lsm_status lsm_choose_left_out(const lsm_slice_source *src, size_t j, int width, int height,
                               const lsm_stack_opts *o, int threads, lsm_flows *run,
                               long long *missed_field, long long *missed_in_place,
                               lsm_err *err) {
  if (!lsm_choose_can_leave_out(src, j, o))
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "leave-one-out: slice %zu has no two sides", j);
  lsm_slice left_out;
  LSM_TRY(lsm_slice_load(src, j, width, height, o->input, &left_out, err));
  lsm_status st = predict(src, j, &left_out.filled, width, height, o, LSM_MOTION_FIELD, threads,
                          run, missed_field, err);
  if (st == LSM_OK)
    st = predict(src, j, &left_out.filled, width, height, o, LSM_MOTION_NONE, threads, NULL,
                 missed_in_place, err);
  lsm_slice_free(&left_out);
  return st;
}

void lsm_choose_decide(lsm_choice *c) {
  c->field = c->tests > 0 && c->field_better == c->tests;
}
