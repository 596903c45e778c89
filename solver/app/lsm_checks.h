/* lsm_checks: what reconstruct checks before any work, so that a run that
 * cannot succeed fails at once: the heights, the slice sizes, and the
 * resource limits (--max-pixels, --max-voxels, the working grids, NIfTI's
 * 16-bit sizes).  OUT_DIR is checked by lsm_out_dir. */
#ifndef LSM_CHECKS_H
#define LSM_CHECKS_H

#include "solver/app/lsm_cli.h"
#include "solver/app/lsm_inputs.h"
#include "solver/base/lsm_status.h"

/* Checks the heights z (src->count of them) and every slice header (PNG IHDR,
 * TIFF size: all slices one size) against the options' limits; sizes are
 * computed in 64-bit or double arithmetic, so nothing wraps around.  On
 * success *width x *height is the slice size. */
lsm_status lsm_check_inputs(const lsm_cli *cli, const lsm_slice_files *src, const double *z,
                            int *width, int *height, lsm_err *err);

#endif
