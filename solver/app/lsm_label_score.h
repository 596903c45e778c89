/* lsm_label_score: `lsmorph score TRUTH OUT` for two label volumes (a full
 * segmentation and a fill of some of its slices): per label and overall, Dice,
 * the 95 % Hausdorff distance and the mean surface distance, in the volumes'
 * physical units, on the slices that were not drawn.
 *
 * The drawn slices and the slice axis are read from OUT's header (lsmorph fill
 * records them), or given with --slices and --axis.  The slices scored are the
 * ones strictly between the first and the last drawn slice that are not drawn.
 * Per label: Dice pooled over them, 2 |T n R| / (|T| + |R|); the distances
 * are in-plane, between the label's boundary pixels on each slice (4-connected
 * boundary, as `score` of PNG stacks), pooled over the slices: HD95 is their
 * 95th percentile, a slice holding the label on one side only counting each
 * of its boundary pixels at the slice's larger physical side; the mean surface
 * distance is their mean over the slices holding the label on both sides.
 * "mean" averages the labels; "dice_pooled" pools all labels' voxels. */
#ifndef LSM_LABEL_SCORE_H
#define LSM_LABEL_SCORE_H

#include "solver/base/lsm_status.h"

/* Whether argv is `score` of two label volumes (names ending .nii, .nii.gz,
 * .nrrd, .nhdr). */
int lsm_label_score_wanted(int argc, char **argv);

/* Parses and runs it, printing one JSON object on stdout. */
lsm_status lsm_label_score_main(int argc, char **argv, lsm_err *err);

#endif
