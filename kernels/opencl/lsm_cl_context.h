/* lsm_cl_context: the OpenCL backend's run-wide context (platform, device, OpenCL context,
 * the built program, work-group shapes), its device list and its error messages. */
#ifndef LSM_CL_CONTEXT_H
#define LSM_CL_CONTEXT_H

#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>

#include <stdio.h>

#include "solver/base/lsm_status.h"

/* The kernels of morph.cl, created per pair state. */
enum {
  LSM_CL_K_GHOSTS,
  LSM_CL_K_UPWIND,
  LSM_CL_K_ROEFIX,
  LSM_CL_K_WENO5,
  LSM_CL_K_CFL,
  LSM_CL_K_RESIDUAL,
  LSM_CL_K_REINIT,
  LSM_CL_K_PCL_VELOCITY,
  LSM_CL_K_PCL_ADVECT,
  LSM_CL_K_PCL_DETECT,
  LSM_CL_K_PCL_APPLY,
  LSM_CL_K_PCL_RADIUS,
  LSM_CL_K_BAND_UPWIND,
  LSM_CL_K_BAND_ROEFIX,
  LSM_CL_K_BAND_WENO5,
  LSM_CL_K_BAND_CFL,
  LSM_CL_K_BAND_RESIDUAL,
  LSM_CL_K_BAND_REINIT,
  LSM_CL_K_BAND_RIM,
  LSM_CL_K_BAND_WRITE,
  LSM_CL_K_COUNT
};
extern const char *const lsm_cl_kernel_names[LSM_CL_K_COUNT];

typedef struct lsm_cl_ctx {
  cl_platform_id platform;
  cl_device_id device;
  cl_context context;
  cl_program program;
  char name[256];           /* "<device name> (<platform name>)" */
  double build_seconds;     /* the program build at open */
  int cpu;                  /* a CPU device (PoCL): reductions in runs, serial combine */
  size_t local_max;         /* cell kernels' work-group width limit (one row segment) */
  size_t red_local[2];      /* reductions' work-group, a power of two in all */
  int red_run;              /* cells per work-item and row in the reductions */
  size_t max_group;         /* CL_DEVICE_MAX_WORK_GROUP_SIZE, lowered to the smallest
                               CL_KERNEL_WORK_GROUP_SIZE of our kernels (a GPU may take fewer
                               work-items per group for a kernel than for the device) */
  size_t max_items[3];      /* CL_DEVICE_MAX_WORK_ITEM_SIZES, first three dimensions */
  cl_ulong max_alloc, global_mem;
} lsm_cl_ctx;

/* Opens device `device` of the list (-1: the first GPU, else the first device) and builds
 * the program; *ctx is an lsm_cl_ctx.  Failures (no platform, a missing device, a build
 * error with its log) name the device and the cause. */
lsm_status lsm_cl_context_open(int device, void **ctx, lsm_err *err);
void lsm_cl_context_close(void *ctx);

/* Prints every platform's devices with their indices, type, compute units and memory, and
 * marks the default; LSM_ERR_UNSUPPORTED (with a message) without an OpenCL platform. */
lsm_status lsm_cl_list_devices(FILE *f, lsm_err *err);

/* "CL_INVALID_VALUE", ...; the status an OpenCL error maps to (out of memory:
 * LSM_ERR_NOMEM, else LSM_ERR_INTERNAL); and the message "OpenCL: <device>: <call> failed:
 * <error name> (<code>)". */
const char *lsm_cl_error_name(cl_int code);
lsm_status lsm_cl_status_of(cl_int code);
lsm_status lsm_cl_fail(lsm_err *err, const char *device, const char *call, cl_int code);

/* Evaluates a call returning cl_int; on failure records the message and returns the status
 * from the enclosing function (which has `err`). */
#define LSM_CL_TRY(device, call_name, expr)                                          \
  do {                                                                               \
    cl_int lsm_cl_e_ = (expr);                                                       \
    if (lsm_cl_e_ != CL_SUCCESS) return lsm_cl_fail(err, device, call_name, lsm_cl_e_); \
  } while (0)

#endif
