/* lsm_choose: --motion auto's choice for one pair, made on the stack's own slices.
 *
 * Whether the correspondence field or the in-place morph serves a gap better cannot be
 * seen in the gap, but it can be tried where the answer is known: each end slice of the
 * pair that has input slices on both sides is left out and reconstructed from the (up to)
 * four nearest others, once with --motion field and once with --motion none; the pair
 * takes the field when it predicted each left-out slice better, missing fewer of its pixels
 * (leave-one-out; solver/README.md §9).  No constant: a tie, a slice the field predicted no
 * better, or no slice to leave out keeps the pair in place.
 */
#ifndef LSM_CHOOSE_H
#define LSM_CHOOSE_H

#include <stddef.h>

#include "solver/base/lsm_status.h"
#include "solver/recon/lsm_stack.h"

typedef struct lsm_choice {
  int field;                 /* 1: the pair takes the field */
  int tests;                 /* slices left out (0, 1 or 2) */
  int field_better;          /* of those, the slices the field predicted better */
  long long missed_field;    /* pixels the field's predictions got wrong, over the tests */
  long long missed_in_place; /* the same in place */
} lsm_choice;

/* Whether input slice j of src can be left out: it has slices on both sides, and predicting
 * it writes no more output slices than the run (options o) does over the same heights. */
int lsm_choose_can_leave_out(const lsm_slice_source *src, size_t j, const lsm_stack_opts *o);

struct lsm_flows;

/* Slice j of src (width x height slices) left out and predicted from the up to four
 * nearest others with --motion field and with --motion none: the pixels each prediction
 * got wrong.  o: the run's options (their motion is ignored); threads for each run; run:
 * the run's fields (lsm_flows), which the predictions borrow for the pairs they share. */
lsm_status lsm_choose_left_out(const lsm_slice_source *src, size_t j, int width, int height,
                               const lsm_stack_opts *o, int threads, struct lsm_flows *run,
                               long long *missed_field, long long *missed_in_place,
                               lsm_err *err);

/* The choice from the tests of a pair's end slices, added up in *c (field set here): the
 * field when it predicted every slice left out better. */
void lsm_choose_decide(lsm_choice *c);

#endif
