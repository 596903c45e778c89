/* lsm_gap_run: the output slices of one gap.
 *
 * By what the two slices hold: both empty (nothing), one empty (the object
 * ends inside the gap: lsm_ends), both full (the blend, or the two-sided
 * morph: lsm_two_sided); each output slice then goes through lsm_emit.
 * Per-iteration mode (the design document's) emits every solver iteration.
 */
#ifndef LSM_GAP_RUN_H
#define LSM_GAP_RUN_H

#include "solver/base/lsm_status.h"
#include "solver/recon/lsm_emit.h"
#include "solver/recon/lsm_slice.h"
#include "solver/recon/lsm_stack.h"

/* Default mode, the gap between w->s[1] and w->s[2]: the output heights zs
 * (fractions fs of the gap, n of them) strictly inside it. */
lsm_status lsm_gap_run(lsm_run *r, const lsm_window *w, const double *zs, const double *fs,
                       size_t n, lsm_pair_stats *ps, lsm_err *err);

/* Per-iteration mode, one gap: runs to convergence once to count the
 * iterations k, then again emitting iterate n at height
 * linspace(z_A, z_B, k + 2)[n]. */
lsm_status lsm_gap_run_iterations(lsm_run *r, const lsm_window *w, lsm_pair_stats *ps,
                                  lsm_err *err);

#endif
