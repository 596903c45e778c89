/* lsm_flood: breadth-first floods and connected components on label images.
 *
 * A label image holds one int32 per cell of an nx x ny image, row-major.  A
 * flood spreads labels from queued cells to their 4- or 8-neighbours whose
 * label is `from` (the open cells); other values are walls.  Every breadth-
 * first search over cells in lsmorph runs through here: connected components
 * of grids and masks (lsm_grid, lsm_parts), the nearest-part regions of the
 * end rule (lsm_ends), enclosed outsides and pinholes (lsm_pinholes), the
 * contours and background of outline slices (lsm_sdf).
 */
#ifndef LSM_FLOOD_H
#define LSM_FLOOD_H

#include <stddef.h>
#include <stdint.h>

/* From the cells queue[0 .. tail), breadth first: each cell passes its label
 * to every neighbour (conn: 4 or 8) labelled `from`, which joins the queue.
 * Returns the new tail: queue[0 .. tail) are the seeds and every cell
 * reached.  Neighbours are visited row by row (the row above, left to right,
 * then the cell's own row, then the row below), so a cell reachable from two
 * labels takes the one queued first.  queue holds nx * ny cells. */
size_t lsm_flood(int32_t *label, int nx, int ny, int conn, int32_t from, int32_t *queue,
                 size_t tail);

/* The connected components (conn: 4 or 8) of the cells labelled `from`: the
 * component of the first such cell in row-major order gets label `first`,
 * the next one first + 1, and so on.  Returns how many there are.  queue
 * holds nx * ny cells. */
int32_t lsm_flood_components(int32_t *label, int nx, int ny, int conn, int32_t from, int32_t first,
                             int32_t *queue);

#endif
