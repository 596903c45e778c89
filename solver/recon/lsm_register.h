/* lsm_register: how far one binary slice has moved against the next.
 *
 * The translation of largest overlap between two masks, found coarse to fine:
 * an exhaustive search on a coverage pyramid level where the two shapes span
 * at most LSM_REGISTER_COARSE pixels, then a 3 x 3 refinement at every finer
 * level down to the pixels themselves.  `--align auto` uses it to tell a
 * shape that moved (the best shift follows the centroid) from one that
 * changed where it stands (a part grows or shrinks on one side: the centroid
 * moves, the best shift stays near zero).
 */
#ifndef LSM_REGISTER_H
#define LSM_REGISTER_H

#include <stddef.h>

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"

/* Longest side, in pixels of the coarsest level, of the box around both
 * shapes where the exhaustive search runs. */
#define LSM_REGISTER_COARSE 32

/* Pixels p inside a whose p + (dx, dy) lies inside b (same-size masks). */
size_t lsm_mask_overlap(const lsm_mask *a, const lsm_mask *b, int dx, int dy);

/* The whole-pixel shift (dx, dy) that maximises lsm_mask_overlap(a, b, dx, dy)
 * over the coarse-to-fine search above; of equal overlaps the shortest shift
 * wins.  a and b must have the same size; if either is empty the shift is
 * (0, 0).  Memory: coverage pyramids of both masks, about 2.7 bytes per
 * pixel in all.  Fails only when that memory cannot be had. */
lsm_status lsm_register_shift(const lsm_mask *a, const lsm_mask *b, int *dx, int *dy,
                              lsm_err *err);

#endif
