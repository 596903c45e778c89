/* lsm_cl_motion: the correspondence field's registration on an OpenCL device
 * (--backend opencl --motion field).
 *
 * lsm_motion_register (solver/motion) keeps the pyramid: it samples the two slices' distances
 * at each level's nodes, upsamples the coarser field and takes the final exponential on the
 * host; each level's iterations (lsm_motion_level) run here, with the kernels of
 * kernels/motion.cl over the per-node code of kernels/lsm_motion_cell.h.  A level has its own
 * queue, kernels and buffers (gaps register side by side); the host reads back per iteration
 * only the rows' largest norms (the squarings) and r^2 with the active flags (the stop test,
 * summed in double in the C path's order, so both stop at the same iteration).
 */
#ifndef LSM_CL_MOTION_H
#define LSM_CL_MOTION_H

#include "kernels/opencl/lsm_cl_context.h"
#include "solver/motion/lsm_motion.h"

/* *dev = the device c as lsm_motion_register's runner of levels (c must stay open). */
void lsm_cl_motion_device(lsm_cl_ctx *c, lsm_motion_device *dev);
/* One level's iterations on the device (lsm_motion_device.run_level; ctx an lsm_cl_ctx). */
lsm_status lsm_cl_motion_level(void *ctx, const lsm_motion_level *lv, int *taken, lsm_err *err);

#endif
