/* lsm_sdf: from binary slices to signed distance functions.
 *
 * Exact Euclidean distance transform (Felzenszwalb & Huttenlocher 2012, linear
 * time, separable) and the two ways lsmorph turns a slice into phi:
 *
 *  mask input     phi < 0 inside.  For a pixel outside, phi = d - 0.5 where d is
 *                 the distance to the nearest inside pixel centre; inside,
 *                 phi = -(d - 0.5) with d the distance to the nearest outside
 *                 pixel centre.  The zero level lies halfway between inside
 *                 and outside pixel centres (exact for straight edges).
 *  outline input  the document's input (§3.3): thin closed 8-connected contours.
 *                 phi = +-(distance to the nearest contour pixel centre), 0 on
 *                 the contour; the sign comes from the parity of the number of
 *                 contours crossed from the image border (nested contours,
 *                 holes and islands in holes).
 *
 * Distances are in physical units: pixel spacing dx (columns) and dy (rows).
 */
#ifndef LSM_SDF_H
#define LSM_SDF_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"

/* Squared Euclidean distance, in pixel units, from every pixel centre to the
 * nearest pixel with feature[k] != 0, with anisotropic weights: distance^2 =
 * (dx*di)^2 + (dy*dj)^2.  Where there is no feature pixel at all the result is
 * +INFINITY.  out has width*height doubles. */
lsm_status lsm_edt_squared(const uint8_t *feature, int width, int height, double dx,
                           double dy, double *out, lsm_err *err);

/* The same along one line of n samples `spacing` apart: out[q] = min over p of
 * (spacing (q - p))^2 + f[p] (f +INFINITY where there is no feature; out
 * +INFINITY when there is none at all).  Scratch: v holds n ints, z n + 1
 * doubles.  (A 3D transform is the 2D one per slice, then this across them.) */
void lsm_edt_squared_1d(const double *f, int n, double spacing, double *out, int *v, double *z);

/* Fills the inside of outline contours by parity: out->pixels = 1 for pixels
 * enclosed by an odd number of contours and for contour pixels themselves
 * (so a filled disc includes its outline).  The background is found with
 * 4-connectivity, contours are 8-connected. */
lsm_status lsm_outline_fill(const lsm_mask *outline, lsm_mask *filled, lsm_err *err);

/* Signed distance of a mask (see above) into the interior of phi, which must
 * be mask->width x mask->height (the grid's dx, dy are the pixel size).  An
 * empty mask gives +LSM_SDF_FAR dx everywhere; a full mask -LSM_SDF_FAR dx. */
lsm_status lsm_sdf_from_mask(const lsm_mask *mask, lsm_grid *phi, lsm_err *err);

/* Signed distance of an outline slice (see above) into phi. */
lsm_status lsm_sdf_from_outline(const lsm_mask *outline, lsm_grid *phi, lsm_err *err);

/* |phi| assigned to cells when a slice has no boundary (empty or full), in
 * cells: the field holds LSM_SDF_FAR times the grid's dx. */
#define LSM_SDF_FAR 1.0e6f

/* Centroid (cx, cy) in pixel coordinates (column, row; pixel centres at
 * integers) of the convex hull of the pixel centres with mask != 0 (area
 * centroid of the hull polygon; degenerate hulls — one pixel, a segment —
 * give the centroid of their points).  Returns 0 for an empty mask, 1 otherwise,
 * -1 (cx, cy NaN) when its scratch memory cannot be allocated. */
int lsm_hull_centroid(const lsm_mask *mask, double *cx, double *cy);

#endif
