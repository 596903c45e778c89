/* lsm_metrics: how close a reconstructed slice is to the truth.
 * Used by `lsmorph score` and the validation suite. */
#ifndef LSM_METRICS_H
#define LSM_METRICS_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"

typedef struct lsm_slice_score {
  double dice;         /* 2|A∩B| / (|A|+|B|); 1 when both are empty */
  double hd95;         /* 95th percentile of the symmetric boundary distances (pixel widths) */
  double hd_max;       /* Hausdorff distance between boundaries (pixel widths) */
  double mean_surface; /* mean symmetric boundary distance (pixel widths) */
  size_t area_result, area_truth;
  int comparable;      /* 0 when exactly one of the two is empty (distances undefined) */
} lsm_slice_score;

/* Boundary pixels: inside pixels with a 4-neighbour outside (or on the image
 * border).  Distances are between boundary pixel centres, in pixel widths
 * (the step from column to column); row_step is the step from row to row in
 * those units (1 for square pixels; pixel height / pixel width).
 * When dist is non-NULL, every boundary-to-boundary distance (both directions)
 * is appended to the growable array *dist (*n used, *cap allocated); when
 * exactly one of the two slices is empty, each boundary pixel of the other is
 * appended with the penalty max(width, height * row_step). */
lsm_status lsm_score_slice(const lsm_mask *result, const lsm_mask *truth, double row_step,
                           lsm_slice_score *out, double **dist, size_t *n, size_t *cap,
                           lsm_err *err);

/* q-quantile (0..1, nearest rank) of values (sorted in place). */
double lsm_quantile(double *values, size_t n, double q);

#endif
