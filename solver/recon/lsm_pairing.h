/* lsm_pairing: which parts of a slice pair take the correspondence field (rule field-parts).
 *
 * A field registered on a whole slice pair explains every mismatch by motion: where a
 * part appears, vanishes, splits or merges it drags the neighbouring outline toward it,
 * which the level-set morph in place handles better.  So the field is decided per part,
 * the parts being the 8-connected components of the two slices:
 *   - a pair of parts P (of A) and Q (of B) takes the field when, in place, P overlaps no
 *     part of B but Q and Q no part of A but P (they form a group of their own, or each is
 *     alone), the registered field makes them a group of their own too (P carried half way
 *     forward overlaps Q carried half way back and nothing else), and they moved or turned
 *     off themselves: alone in place, or each reaching at least R/2 outside the other, R
 *     the larger of their half-thicknesses (depths).  A disc of radius R moved by d reaches
 *     d outside itself on both sides, and moved by less than R/2 it blends in place with
 *     Dice above 0.98 (solver/README.md §9); a part that grows or shrinks in place reaches
 *     outside on one side only, one that turns (a thin section, a hinged wall) as far as
 *     its outline moves;
 *   - every other part (appearing, vanishing, splitting, merging, or overlapping its
 *     counterpart well) stays with the morph in place: the field is zero on it, rising to
 *     full over one node spacing beyond the nodes that carry it.
 * The test in place comes first: a pair where no part can take the field is not
 * registered at all.
 */
#ifndef LSM_PAIRING_H
#define LSM_PAIRING_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/motion/lsm_motion.h"

typedef struct lsm_pairing lsm_pairing;

/* The parts of masks a and b (the pair's slices, same size) and their groups in place;
 * phi_a, phi_b: their signed distances on the field's canvas, mask pixel (x, y) at cell
 * (x + pad, y + pad).  *needs: 1 when some part may take the field (the pair is worth
 * registering), else 0. */
lsm_status lsm_pairing_create(const lsm_mask *a, const lsm_mask *b, const lsm_grid *phi_a,
                              const lsm_grid *phi_b, int pad, lsm_pairing **out, int *needs,
                              lsm_err *err);
void lsm_pairing_destroy(lsm_pairing **p);

/* Weighs the pair's registered field w in place: zero on the parts that stay in place,
 * rising to full over one node spacing.  *taken: the parts (of both slices) that take the
 * field; when 0, w is zero everywhere.  w->max_displacement is updated. */
lsm_status lsm_pairing_weigh(const lsm_pairing *p, lsm_motion_field *w, int threads, int *taken,
                             lsm_err *err);

#endif
