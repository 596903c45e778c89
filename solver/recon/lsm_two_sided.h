/* lsm_two_sided: the two-sided level-set morph of a gap whose slices are
 * both non-empty.
 *
 * The forward morph A -> B is used where it retreats (inside A), the reverse
 * morph B -> A at 1 - s where B retreats (inside B), joined by the union of
 * the two insides, or of the two outsides where an outside is thin; a
 * slice's pinholes take the blend (lsm_pinholes).  With the cubic profile
 * the result gets the spline's shape (lsm_zprofile).
 */
#ifndef LSM_TWO_SIDED_H
#define LSM_TWO_SIDED_H

#include "solver/base/lsm_status.h"
#include "solver/pde/lsm_morph.h"
#include "solver/recon/lsm_emit.h"
#include "solver/recon/lsm_gap.h"
#include "solver/recon/lsm_stack.h"

/* Emits the gap's output slices at heights zs (fractions fs, n of them). */
lsm_status lsm_two_sided_run(lsm_run *r, lsm_gap *g, const double *zs, const double *fs,
                             size_t n, lsm_pair_stats *ps, lsm_err *err);

/* Adds a morph's particle counters to the pair's (m may be NULL). */
void lsm_pair_stats_add_pls(lsm_pair_stats *ps, const lsm_morph *m);

#endif
