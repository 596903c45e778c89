/* lsm_metrics: how close a reconstructed slice is to the truth.
 * Used by `lsmorph score` and the validation suite. */
#ifndef LSM_METRICS_H
#define LSM_METRICS_H

#include "lsm_grid.h"
#include "lsm_status.h"

typedef struct lsm_slice_score {
  double dice;         /* 2|A∩B| / (|A|+|B|); 1 when both are empty */
  double hd95;         /* 95th percentile of the symmetric boundary distances (pixels) */
  double hd_max;       /* Hausdorff distance between boundaries (pixels) */
  double mean_surface; /* mean symmetric boundary distance (pixels) */
  size_t area_result, area_truth;
  int comparable;      /* 0 when exactly one of the two is empty (distances undefined) */
} lsm_slice_score;

/* Boundary pixels: inside pixels with a 4-neighbour outside (or on the image
 * border).  Distances are between boundary pixel centres, in pixels. */
lsm_status lsm_score_slice(const lsm_mask *result, const lsm_mask *truth, lsm_slice_score *out,
                           lsm_err *err);

#endif
