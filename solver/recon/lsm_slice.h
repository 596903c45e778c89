/* lsm_slice: the input slices of a gap, as the stack driver holds them, and
 * their signed distances on a working canvas.
 *
 * An lsm_slice is one input slice as read (an outline or a mask), its filled
 * region and the centroid of that region's convex hull.  An lsm_window is the
 * four input slices around a gap (prev, A, B, next), which the cubic z-profile
 * reads, and M beyond them where the object ends in the gap (lsm_ends).
 */
#ifndef LSM_SLICE_H
#define LSM_SLICE_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/recon/lsm_stack.h"

typedef struct lsm_slice {
  lsm_mask raw;    /* as read: outline or mask */
  lsm_mask filled; /* the region (== raw for mask input) */
  int empty;
  double cx, cy;   /* hull centroid (pixels) */
  int loaded;
} lsm_slice;

/* Loads input slice `index` of src (width x height, as the first slice). */
lsm_status lsm_slice_load(const lsm_slice_source *src, size_t index, int width, int height,
                          lsm_input_kind input, lsm_slice *s, lsm_err *err);
void lsm_slice_free(lsm_slice *s);

/* phi of a mask (or outline) placed on phi's canvas with its pixel (0,0) at
 * cell (ox, oy).  border: a mask touching the image border goes on across it
 * into the canvas margin (the border is not the object's boundary). */
lsm_status lsm_mask_phi(const lsm_mask *m, lsm_input_kind input, int border, int ox, int oy,
                        lsm_grid *phi, lsm_err *err);
/* The same for a loaded slice (its raw mask), as the options say. */
lsm_status lsm_slice_phi(const lsm_slice *s, const lsm_stack_opts *o, int ox, int oy, lsm_grid *phi,
                         lsm_err *err);

/* The four input slices around a gap: prev, A, B, next (prev/next may be
 * absent) with their heights. */
typedef struct lsm_window {
  const lsm_slice *s[4];
  double z[4];
  const lsm_slice *farther; /* M, the slice beyond the next one past a gap where the object
                             * ends (cubic; NULL elsewhere or at the stack's end) */
  double z_farther;
  int at_start, at_end; /* A is the first input slice, B the last (whether or not loaded) */
  size_t gap;           /* the gap's index (A's input index) */
} lsm_window;

/* A neighbour takes part in the spline only if it exists and is not empty. */
int lsm_window_usable(const lsm_window *w, int k);

#endif
