/* lsm_specks: an output slice has no more parts than its gap's slices allow.
 *
 * Between two non-empty slices A and B, the parts (8-connected components)
 * of A and of B that overlap, in the gap's frame, form groups; a group with
 * m parts of A and n of B is one structure that merges or splits, and an
 * interpolation of it has no evidence for more than max(m, n) parts at any
 * height (a part of A alone vanishes, one of B alone appears: a group of its
 * own).  The morph's fronts can break that: where a new part of B grows
 * between parts of A, its thin ridges cross A's and leave specks for many
 * slices before it appears (the design document's Candlestick).  An output
 * slice with more parts than the groups allow keeps the largest and drops the
 * rest (phi -> -phi there), rule one-piece.
 */
#ifndef LSM_SPECKS_H
#define LSM_SPECKS_H

#include <stdint.h>

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"

/* What lsm_specks_drop needs of a gap: the parts allowed, and scratch of
 * width x height cells each. */
typedef struct lsm_specks {
  int allowed;
  int32_t *label, *queue;
} lsm_specks;

/* The parts an output slice of the gap between masks a and b may have: the
 * sum over the overlap groups of the larger of their two counts.  B's pixel
 * (x, y) lies on A's pixel (x - shift_x, y - shift_y) in the gap's frame.
 * label and queue hold width x height cells.  *allowed is set on success. */
lsm_status lsm_specks_allowed(const lsm_mask *a, const lsm_mask *b, int shift_x, int shift_y,
                              int32_t *label, int32_t *queue, int *allowed, lsm_err *err);

/* Drops the smallest parts of out (width x height, inside phi <= 0) beyond
 * s->allowed: their phi changes sign (a zero becomes a millionth of `pixel`
 * above).  Of parts of equal size the later in row-major order goes first. */
lsm_status lsm_specks_drop(const lsm_specks *s, int width, int height, double pixel, float *out,
                           lsm_err *err);

#endif
