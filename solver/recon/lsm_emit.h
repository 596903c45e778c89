/* lsm_emit: one run of the stack driver, and its output slices on their way
 * to the sink.
 *
 * lsm_run holds what every gap of a run shares (the source, the options, the
 * sink and progress) and what one task owns (its output slice buffer and
 * scratch).  lsm_emit hands the output slice to the sink: a gap's slice
 * first loses the parts beyond those its slices allow (lsm_specks), gets its
 * pinholes filled (lsm_pinholes) and its zero ties broken.
 */
#ifndef LSM_EMIT_H
#define LSM_EMIT_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/pde/lsm_morph.h"
#include "solver/recon/lsm_pinholes.h"
#include "solver/recon/lsm_slice.h"
#include "solver/recon/lsm_specks.h"
#include "solver/recon/lsm_stack.h"

typedef struct lsm_run {
  const lsm_slice_source *src;
  const lsm_stack_opts *opts;
  const lsm_slice_sink *sink;
  const lsm_progress *progress;
  int width, height;
  lsm_morph_opts morph;  /* the morph options of this run (particles, CP tracking) */
  float *out;            /* one output slice */
  lsm_grid *image_phi;   /* an input slice's phi in the image frame */
  size_t done, total;
  int gap_workers;       /* gaps run at once (default mode) */
  lsm_pinhole_fill *fill; /* set while a gap whose slices have no hole emits */
  const lsm_specks *specks; /* set while a gap between two non-empty slices emits (ls, pls) */
  struct lsm_flows *flows; /* the pairs' fields (--motion field), shared by the tasks */
} lsm_run;

/* LSM_ERR_INTERRUPTED once the run's stop flag (morph.stop) is set: the
 * loops of a gap poll it per slice, and the solver per step. */
lsm_status lsm_run_check_stop(const lsm_run *r, lsm_err *err);

/* Hands r->out, the output slice at height z, to the sink (input_index: the
 * input slice it reproduces, or -1 for an interpolated slice); first checks
 * the stop flag. */
lsm_status lsm_emit(lsm_run *r, double z, long input_index, lsm_err *err);

/* Emits input slice s (index `index`) at height z: its own phi. */
lsm_status lsm_emit_input(lsm_run *r, const lsm_slice *s, size_t index, double z, lsm_err *err);


#endif
