/* lsm_schedule: the gaps of a run as tasks, and their output in stack order.
 *
 * Default mode: the regular output grid split by gap; each gap loads its own
 * window of input slices and runs start to end (lsm_gap_run).  Gaps run one
 * at a time with the threads inside each, or side by side (small slices, or
 * a device backend), each buffering its slices until an ordered block hands
 * them to the sink; or spread over MPI ranks (lsm_gap_transport), rank 0
 * writing.  The output is the same byte for byte whichever way.
 * Per-iteration mode: gap by gap, or over ranks.
 */
#ifndef LSM_SCHEDULE_H
#define LSM_SCHEDULE_H

#include <stddef.h>

#include "solver/base/lsm_status.h"
#include "solver/recon/lsm_emit.h"
#include "solver/recon/lsm_stack.h"

/* The regular output grid of the default mode: heights z0 + k dz.  Output
 * height k is input slice i when its offset k dz from z0 lies within eps of
 * the input's offset z_i - z0: a millionth of dz, or of the closest pair of
 * input heights where they are closer still (a gap thinner than eps would
 * otherwise give its first output height to the wrong slice).  Offsets, not
 * heights, are compared, so that a large z0 costs no precision, and the same
 * two tests below decide the slice count, each gap's share and which
 * heights are input slices. */
typedef struct lsm_output_grid {
  double z0, dz, eps;
} lsm_output_grid;

lsm_output_grid lsm_output_grid_of(const double *z, size_t count, double dz);
/* Output height k lies below input height z by more than eps. */
int lsm_output_below(const lsm_output_grid *g, size_t k, double z);
/* Output height k lies no higher than eps above input height z. */
int lsm_output_not_above(const lsm_output_grid *g, size_t k, double z);

/* How many gaps of the default mode run at once for width x height slices,
 * gaps gaps, the largest with most_slices output slices (the run's own
 * choice; the estimate of memory before any work makes it too). */
int lsm_schedule_gap_workers(const lsm_stack_opts *o, int width, int height, size_t gaps,
                             size_t most_slices);

/* Runs every gap of r (set up by lsm_stack_run) and emits the whole stack. */
lsm_status lsm_schedule_run(lsm_run *r, lsm_pair_stats *stats, lsm_err *err);

#endif
