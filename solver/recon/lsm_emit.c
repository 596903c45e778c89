/* lsm_emit: output slices to the sink (see the header). */
#include "solver/recon/lsm_emit.h"

#include <math.h>

#include "solver/base/lsm_clock.h"
#include "solver/recon/lsm_frame.h"

/* A sample of exactly 0 lies on the surface and counts as inside (phi <= 0,
 * as the masks draw it); interpolating half-pixel distances makes whole rows
 * of such ties.  They leave a millionth of a pixel below zero (rule
 * zero-ties), so a reader taking phi < 0 as inside draws the same shape. */
static void break_zero_ties(float *phi, size_t cells, double pixel) {
  const float below = (float)(-1e-6 * pixel);
  for (size_t k = 0; k < cells; ++k)
    if (phi[k] == 0.0f) phi[k] = below;
}

lsm_status lsm_run_check_stop(const lsm_run *r, lsm_err *err) {
  if (r->morph.stop && *r->morph.stop)
    return lsm_fail(err, LSM_ERR_INTERRUPTED, NULL, "interrupted");
  return LSM_OK;
}

lsm_status lsm_emit(lsm_run *r, double z, long input_index, lsm_err *err) {
  LSM_TRY(lsm_run_check_stop(r, err)); /* every gap's slice loop, in every schedule */
  if (input_index < 0 && r->specks)
    LSM_TRY(lsm_specks_drop(r->specks, r->width, r->height, fmin(r->opts->pixel_dx, r->opts->pixel_dy),
                            r->out, err));
  if (input_index < 0 && r->fill) LSM_TRY(lsm_pinholes_fill(r->fill, r->opts, r->width, r->height, r->out, err));
  if (lsm_rule_on(&r->opts->rules, LSM_RULE_ZERO_TIES))
    break_zero_ties(r->out, (size_t)r->width * (size_t)r->height,
                    fmin(r->opts->pixel_dx, r->opts->pixel_dy));
  LSM_TRY(r->sink->emit(r->sink->ctx, r->out, r->width, r->height, z, input_index, err));
  r->done++;
  if (r->progress && r->progress->update)
    r->progress->update(r->progress->ctx, r->done, r->total,
                        input_index >= 0 ? (size_t)input_index : 0, r->src->count - 1);
  return LSM_OK;
}

lsm_status lsm_emit_input(lsm_run *r, const lsm_slice *s, size_t index, double z, lsm_err *err) {
  LSM_TRY(lsm_slice_phi(s, r->opts, 0, 0, r->image_phi, err));
  lsm_frame f;
  lsm_window w = {{NULL, s, s, NULL}, {0.0, 0.0, 1.0, 0.0}, NULL, 0.0, 0, 0, 0};
  LSM_TRY(lsm_frame_setup(&f, &w, LSM_ALIGN_NONE, LSM_INTERP_LINEAR, r->width, r->height,
                          r->opts->pixel_dx, r->opts->pixel_dy, &r->opts->rules, err));
  f.pad = 0;
  f.pad_y = 0;
  lsm_frame_extract(&f, r->image_phi, 0.0, r->out);
  return lsm_emit(r, z, (long)index, err);
}
