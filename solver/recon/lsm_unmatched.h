/* lsm_unmatched: parts of one slice with no counterpart in the other.
 *
 * A connected part of phi_x's inside that overlaps nothing of phi_y's and
 * lies farther from it than its own depth R ends near mid-gap, like a whole
 * object next to an empty slice: inside it phi_y is lowered to R.  A branch
 * (one piece, on the slice beyond x, with a larger part that goes on) keeps
 * the plain interpolation and recedes toward that body.
 */
#ifndef LSM_UNMATCHED_H
#define LSM_UNMATCHED_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/recon/lsm_rules.h"

/* Lowers phi_y inside the unmatched parts of phi_x (see above).  phi_before:
 * the slice beyond x, away from the gap, in x's frame, or NULL (no such
 * slice, or the linear profile).  rules: NULL for the defaults. */
lsm_status lsm_cap_unmatched(const lsm_grid *phi_x, lsm_grid *phi_y, const lsm_grid *phi_before,
                             const lsm_rules *rules, lsm_err *err);

#endif
