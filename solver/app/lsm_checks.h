/* lsm_checks: what reconstruct checks before any work, so that a run that
 * cannot succeed fails at once: the heights, the slice sizes, and the
 * resource limits (--max-pixels, --max-voxels, the working grids, NIfTI's
 * 16-bit sizes, the estimate of memory and disk against --max-memory and
 * what is free).  OUT_DIR is checked by lsm_out_dir. */
#ifndef LSM_CHECKS_H
#define LSM_CHECKS_H

#include <stddef.h>
#include <stdint.h>

#include "solver/app/lsm_cli.h"
#include "solver/app/lsm_inputs.h"
#include "solver/base/lsm_status.h"

/* Checks the heights z (src->count of them) and every slice header (PNG IHDR,
 * TIFF size: all slices one size) against the options' limits; sizes are
 * computed in 64-bit or double arithmetic, so nothing wraps around.  On
 * success *width x *height is the slice size. */
lsm_status lsm_check_inputs(const lsm_cli *cli, const lsm_slice_files *src, const double *z,
                            int *width, int *height, lsm_err *err);

/* The memory and disk the run is estimated to need (the model and its
 * measurements: lsm_checks.c, validation/measurements/limits.md), checked
 * before any work: refused (LSM_ERR_LIMIT) with the numbers when the memory
 * is more than --max-memory, or than what is available (MemAvailable, less
 * in a cgroup that allows less), or when what is sure to be written (the
 * uncompressed volumes, a block per slice PNG) is more than the free space
 * of folder, where the temporary folder goes.  Sets cli->stack.held_max:
 * what a gap may hold for its turn (per-iteration's count is known only
 * then). */
lsm_status lsm_check_resources(lsm_cli *cli, const lsm_slice_files *src, const double *z, int w,
                               int h, const char *folder, lsm_err *err);

/* What `lsmorph fill` will need beyond the volume it has read. */
typedef struct lsm_fill_need {
  double gap_voxels;  /* voxels of the slices to fill */
  int width, height;  /* a slice across the axis */
  size_t most;        /* slices of the longest gap */
  int threads;
  double out_bytes;   /* the output file, uncompressed (0: compressed, not known ahead) */
  int field;          /* the correspondence field may be registered (--motion field, auto) */
} lsm_fill_need;

/* The same estimate for fill, before the work: memory against --max-memory
 * (max_memory, 0: what is available), the output against the free space of
 * folder (where it is written).  *canvas_max: the most cells a gap's working
 * canvas may have within that memory (0: no limit; lsm_stack_opts.canvas_max). */
lsm_status lsm_check_fill_resources(uint64_t max_memory, const lsm_fill_need *need,
                                    const char *labels_path, const char *folder,
                                    double *canvas_max, lsm_err *err);

/* Bytes of memory this process may still take: MemAvailable, or less where
 * its cgroup allows less; 0 where the system does not say. */
double lsm_memory_available(void);

#endif
