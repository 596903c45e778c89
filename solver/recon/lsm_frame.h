/* lsm_frame: alignment, and the working frame of a gap.
 *
 * Alignment (§3.2, §3.9 of the design document): each slice of a pair is
 * shifted by whole pixels so the centroid of the convex hull of its
 * foreground sits at the image centre, on a canvas padded so nothing is
 * clipped; an intermediate slice at fraction s is shifted back along the
 * path between the two slices' shifts (a straight segment, or with the cubic
 * profile the monotone cubic through the neighbouring slices' centroids),
 * with bilinear resampling of phi.  --align auto aligns a pair only when its
 * shape moved (the tests in lsm_frame.c); where the object ends in a gap, the
 * end keeps moving with the aligned pair beyond it.
 */
#ifndef LSM_FRAME_H
#define LSM_FRAME_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/recon/lsm_slice.h"
#include "solver/recon/lsm_stack.h"

typedef struct lsm_frame {
  int width, height;     /* image size */
  int pad;               /* canvas margin on the left and right */
  int pad_y;             /* canvas margin above and below */
  int dx[4], dy[4];      /* whole-pixel shifts (centroid - centre) of prev, A, B, next */
  double H;              /* height of the gap, z_B - z_A */
  double mx[2], my[2];   /* slopes of the shift path at A and B, per unit z */
  float clamp;           /* |phi| written out is at most this */
  int aligned;           /* the pair is aligned (hull, asked or chosen by auto) */
  int end_aligned;       /* where the object ends: the pair beyond the full slice is aligned */
} lsm_frame;

/* A centroid offset from the image centre rounded to whole pixels. */
int lsm_pixel_shift(double offset);

/* The frame of the gap between w->s[1] (A) and w->s[2] (B): whether it is
 * aligned (asked: the --align mode), each slice's shift, the shift path's
 * slopes and the canvas margins.  rules: NULL for the defaults. */
lsm_status lsm_frame_setup(lsm_frame *f, const lsm_window *w, lsm_align asked, lsm_interp interp,
                           int width, int height, double pixel_dx, double pixel_dy,
                           const lsm_rules *rules, lsm_err *err);

/* Writes the slice at fraction s from the working field into out (width x
 * height), undoing the alignment shift. */
void lsm_frame_extract(const lsm_frame *f, const lsm_grid *work, double s, float *out);

#endif
