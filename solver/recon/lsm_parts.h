/* lsm_parts: parts of a slice that moved off their place by the next slice
 * (rule moving-parts).
 *
 * Two thin structures drifting apart (vessels after a bifurcation, the ears
 * of the bunny, the legs of a scanned figure) leave the slice's centroid in
 * place, so whole-slice alignment cannot follow them; a part that moves by
 * more than its own width overlaps nothing of itself on the other side, and
 * a morph in place would shrink it away and grow it again beside.
 * lsm_parts_moved finds such parts, pairs them, and gives the shift between
 * their centres; lsm_gap moves each pair along that shift.
 *
 * A part (an 8-connected component) of A and one of B are paired only when
 * all of these hold, so that nothing ambiguous moves:
 *   - neither overlaps any foreground of the other slice in place, and
 *     neither touches the image border;
 *   - each is the other's nearest component (centre to centre), and no other
 *     is as near (a tie does not tell which went where);
 *   - their areas are within a factor parts_area_ratio (rule parts-area).
 */
#ifndef LSM_PARTS_H
#define LSM_PARTS_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/recon/lsm_rules.h"

/* At most this many pairs are returned (the nearest first). */
#define LSM_PARTS_MAX 8

typedef struct lsm_part_move {
  lsm_mask part_a, part_b; /* the two parts, each alone on a mask of the slice's size */
  double dx, dy;           /* centre of part_b minus centre of part_a, pixels */
} lsm_part_move;

/* Fills moves[0 .. *count) (caller frees each with lsm_part_move_free).  a
 * and b must have the same size; rules: NULL for the defaults. */
lsm_status lsm_parts_moved(const lsm_mask *a, const lsm_mask *b, const lsm_rules *rules,
                           lsm_part_move *moves, int *count, lsm_err *err);
void lsm_part_move_free(lsm_part_move *move);

#endif
