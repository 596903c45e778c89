/* lsm_flows: the correspondence field of every pair of a run, each computed once.
 *
 * Gap i reads the field of its own pair (i, i + 1) and, for the cubic profile, those of the
 * pairs beside it (i - 1, i) and (i + 1, i + 2): each field serves up to three gaps, which
 * may run at once on different threads.  The first to ask computes it (under the pair's
 * lock); a field is freed once every gap of this process that could read it has finished,
 * so at most a few fields per gap in flight are held.  With MPI each process keeps its own.
 */
#ifndef LSM_FLOWS_H
#define LSM_FLOWS_H

#include <stddef.h>

#include "solver/base/lsm_status.h"
#include "solver/motion/lsm_motion.h"
#include "solver/recon/lsm_choose.h"
#include "solver/recon/lsm_slice.h"
#include "solver/recon/lsm_stack.h"

typedef struct lsm_flows lsm_flows;

/* --motion auto's predictions (lsm_choose) are runs of their own on some of the run's slices:
 * slice k of a prediction is the run's slice index[k], and a pair of it that is a pair of the
 * run (index[k + 1] == index[k] + 1) borrows a copy of the run's field, computing it there
 * when the run will still read it. */
typedef struct lsm_flows_lender {
  lsm_flows *flows;
  const size_t *index;
  size_t count;
} lsm_flows_lender;

/* The cache of the stack src (its count - 1 pairs), whose gaps g with g % size == rank run
 * here.  src is kept for --motion auto's choices (lsm_choose); lender: NULL, or the run a
 * prediction borrows fields from; progress: NULL, or the run's, told when a pair is tried. */
lsm_status lsm_flows_create(const lsm_slice_source *src, int rank, int size,
                            const lsm_flows_lender *lender, const lsm_progress *progress,
                            lsm_flows **out, lsm_err *err);
void lsm_flows_destroy(lsm_flows **flows);

/* The margin of the canvas the fields are computed on (an unaligned gap's). */
#define LSM_FLOWS_PAD 2

/* The field of pair `pair`, a and b its two slices (loaded), on the canvas of an unaligned
 * gap (width + 2 LSM_FLOWS_PAD by height + 2 LSM_FLOWS_PAD); computed on first use with
 * `threads` threads, weighed per part (lsm_pairing, rule field-parts).  *field is NULL
 * where no part takes it.  With --motion auto a pair chosen in place still has its field:
 * the gaps beside it that take theirs carry their neighbours along it.  Valid until the gaps that read it
 * are done. */
lsm_status lsm_flows_get(lsm_flows *flows, size_t pair, const lsm_slice *a, const lsm_slice *b,
                         const lsm_stack_opts *o, int width, int height, int threads,
                         const lsm_motion_field **field, lsm_err *err);

/* Whether pair `pair` (its slices a and b, loaded) takes the field: with --motion field
 * always; with --motion auto the leave-one-out choice, made on the first call and kept.
 * When this call made it from the two slices' phi on the fields' canvas (LSM_FLOWS_PAD
 * cells around the image, unshifted), it hands them over in *phi_a and *phi_b (the caller
 * destroys them; NULL otherwise, and phi_a, phi_b may be NULL). */
lsm_status lsm_flows_choice(lsm_flows *flows, size_t pair, const lsm_slice *a, const lsm_slice *b,
                            const lsm_stack_opts *o, int width, int height, int threads,
                            lsm_choice *choice, lsm_grid **phi_a, lsm_grid **phi_b,
                            lsm_err *err);

/* Gap `gap` has finished (also on failure): fields nobody here will read again are freed. */
void lsm_flows_gap_done(lsm_flows *flows, size_t gap);

/* The registration's constants of a run (the rules table's motion_* constants). */
void lsm_flows_params(const lsm_stack_opts *o, lsm_motion_params *p);

#endif
