/* lsm_stack: the stack driver's public face (see the header): option names
 * and defaults, the output grid's size, and lsm_stack_run, which checks its
 * input and hands the run to lsm_schedule. */
#include "solver/recon/lsm_stack.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "solver/recon/lsm_emit.h"
#include "solver/recon/lsm_schedule.h"

/* ---- names ------------------------------------------------------------------------ */

LSM_NAME_FUNCTIONS(lsm_method, LSM_METHOD_LIST, lsm_method_name, lsm_method_from_name)
LSM_NAME_FUNCTIONS(lsm_input_kind, LSM_INPUT_LIST, lsm_input_name, lsm_input_from_name)
LSM_NAME_FUNCTIONS(lsm_align, LSM_ALIGN_LIST, lsm_align_name, lsm_align_from_name)
LSM_NAME_FUNCTIONS(lsm_motion_mode, LSM_MOTION_LIST, lsm_motion_name, lsm_motion_from_name)
LSM_NAME_FUNCTIONS(lsm_interp, LSM_INTERP_LIST, lsm_interp_name, lsm_interp_from_name)
LSM_NAME_FUNCTIONS(lsm_end_rule, LSM_ENDS_LIST, lsm_end_rule_name, lsm_end_rule_from_name)

void lsm_stack_opts_default(lsm_stack_opts *opts) {
  *opts = (lsm_stack_opts){.method = LSM_METHOD_LS, .input = LSM_INPUT_MASK,
                           .align = LSM_ALIGN_AUTO, .motion = LSM_MOTION_AUTO,
                           .interp = LSM_INTERP_CUBIC, .ends = LSM_ENDS_AUTO, .pixel_dx = 1.0,
                           .pixel_dy = 1.0, .dz = 0.0 /* the pixel size */, .tol = 0.25,
                           .max_iter = 100000};
  lsm_morph_opts_default(&opts->morph);
  lsm_rules_default(&opts->rules);
}

const char *lsm_stack_field_excluded_by(const lsm_stack_opts *opts) {
  return opts->per_iteration                ? "--per-iteration"
         : opts->align == LSM_ALIGN_HULL     ? "--align hull"
         : opts->method == LSM_METHOD_BLEND ? "--method blend"
                                            : NULL;
}

void lsm_stack_opts_resolve(lsm_stack_opts *opts) {
  if (opts->per_iteration) opts->interp = LSM_INTERP_LINEAR;
  /* the field is for ls and pls in default mode: blend stays the textbook, --per-iteration
   * and --align hull the document's modes (the command line refuses --motion field there) */
  if (opts->motion != LSM_MOTION_NONE && lsm_stack_field_excluded_by(opts))
    opts->motion = LSM_MOTION_NONE;
  /* the field replaces --align auto's alignment (auto: in the pairs that take it) */
  if (opts->motion == LSM_MOTION_FIELD && opts->align == LSM_ALIGN_AUTO) opts->align = LSM_ALIGN_NONE;
  if (opts->interp == LSM_INTERP_LINEAR) opts->ends = LSM_ENDS_HALFWAY;
}

double lsm_stack_output_dz(const lsm_stack_opts *opts) {
  return opts->dz > 0.0 ? opts->dz : fmin(opts->pixel_dx, opts->pixel_dy);
}

size_t lsm_stack_output_count(const double *z, size_t count, double dz) {
  if (count == 0 || !(dz > 0.0)) return 0;
  const lsm_output_grid g = lsm_output_grid_of(z, count, dz);
  const double span = z[count - 1] - z[0];
  const double n0 = floor((span + g.eps) / dz);
  if (!(n0 >= 0.0)) return 0;
  /* not reached by callers that first check lsm_output_step_resolved (lsm_stack_run, the
   * CLI): a step of at least 8 units in the last place of the heights gives at most
   * about 6e14 slices */
  if (n0 >= (double)LSM_OUTPUT_COUNT_MAX / 2) return LSM_OUTPUT_COUNT_MAX;
  /* the division rounds: settle n by the test the gaps use */
  size_t n = (size_t)n0;
  while (lsm_output_not_above(&g, n + 1, z[count - 1])) ++n;
  while (n > 0 && !lsm_output_not_above(&g, n, z[count - 1])) --n;
  return n + 1;
}

void lsm_gap_result_free(lsm_gap_result *b) {
  if (!b) return;
  free(b->phi);
  free(b->z);
  free(b->input);
  memset(b, 0, sizeof *b);
}

lsm_status lsm_stack_run(const lsm_slice_source *src, int width, int height,
                         const lsm_stack_opts *opts, const lsm_slice_sink *sink,
                         lsm_pair_stats *stats, const lsm_progress *progress, lsm_err *err) {
  if (src->count < 2)
    return lsm_fail(err, LSM_ERR_INPUT, NULL, "need at least two slices, got %zu", src->count);
  for (size_t i = 1; i < src->count; ++i) {
    const double h = src->z[i] - src->z[i - 1];
    if (!(h > 0.0))
      return lsm_fail(err, LSM_ERR_INPUT, NULL, "heights must increase strictly (slice %zu)", i + 1);
    if (!lsm_length_in_range(h))
      return lsm_fail(err, LSM_ERR_INPUT, NULL,
                      "slices %zu and %zu are %g apart, outside %g to %g (lengths are floats)", i,
                      i + 1, h, LSM_LENGTH_MIN, LSM_LENGTH_MAX);
  }
  if (!lsm_length_in_range(opts->pixel_dx) || !lsm_length_in_range(opts->pixel_dy))
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "pixel size %g x %g is outside %g to %g",
                    opts->pixel_dx, opts->pixel_dy, LSM_LENGTH_MIN, LSM_LENGTH_MAX);
  if (opts->dz > 0.0 && !lsm_length_in_range(opts->dz))
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "dz %g is outside %g to %g", opts->dz,
                    LSM_LENGTH_MIN, LSM_LENGTH_MAX);
  if (opts->per_iteration && opts->method == LSM_METHOD_BLEND)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "--per-iteration needs a solver method, not blend");
  const double dz = lsm_stack_output_dz(opts);
  const double z_mag = fmax(fabs(src->z[0]), fabs(src->z[src->count - 1]));
  for (size_t i = 1; opts->per_iteration && i < src->count; ++i)
    if (!lsm_output_step_resolved((src->z[i] - src->z[i - 1]) / ((double)opts->max_iter + 1.0),
                                  z_mag))
      return lsm_fail(err, LSM_ERR_INPUT, NULL,
                      "slices %zu and %zu are too close at heights near %g for %d distinct "
                      "per-iteration heights between them",
                      i, i + 1, z_mag, opts->max_iter);
  if (!opts->per_iteration && !lsm_output_step_resolved(dz, z_mag))
    return lsm_fail(err, LSM_ERR_INPUT, NULL,
                    "output step %g is too small for distinct heights near %g", dz, z_mag);
  lsm_stack_opts used = *opts;
  lsm_stack_opts_resolve(&used);
  opts = &used;

  lsm_run r = {.src = src, .opts = opts, .sink = sink, .progress = progress, .width = width,
               .height = height, .morph = opts->morph};
  r.morph.track_cp = opts->per_iteration; /* default mode: CP of each snapshot's last step */
  /* per-iteration mode's slices are the full grid's iterations, at its step (§12) */
  r.morph.band = opts->morph.band && !opts->per_iteration;
  r.morph.particles = opts->method == LSM_METHOD_PLS;
  r.out = lsm_alloc((size_t)width * (size_t)height, sizeof(float), err, "output slice");
  if (!r.out) return err ? err->status : LSM_ERR_NOMEM;
  lsm_status st = lsm_grid_create(width, height, (float)opts->pixel_dx, (float)opts->pixel_dy,
                                  &r.image_phi, err);
  if (st == LSM_OK) st = lsm_schedule_run(&r, stats, err);
  lsm_grid_destroy(&r.image_phi);
  free(r.out);
  return st;
}
