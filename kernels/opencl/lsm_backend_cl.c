/* OpenCL backend: the grid work of a morph on an OpenCL device.
 *
 * The context (lsm_backend.ctx) holds the platform, device, OpenCL context
 * and the program built from kernels/morph.cl with kernels/lsm_cell.h spliced
 * in (embedded at build time as a byte array, $(BUILD)/gen/lsm_kernels.h).
 * Each pair state has its own queue, kernels and buffers: phi, phi_target,
 * two integrator scratch grids, the reinitialisation snapshot phi0 (on first
 * use) and the small array of per-work-group partial results.  Fields stay
 * on the device for the whole pair; the host reads only the partial results
 * of the CFL and residual reductions, and the whole phi when asked
 * (download).
 *
 * The host enqueues the same stage sequence as lsm_step_hooked (Euler, RK2,
 * RK3 with the Shu–Osher coefficients) and the same reinitialisation loop as
 * lsm_reinit_run, with ghost fills before each stage; floats throughout, and
 * the program is built without contraction or relaxed maths (and with
 * correctly rounded divide and sqrt when the device offers it), so results
 * track the C path.  The blend of the two morphs of a gap runs on the host.
 *
 * Particles (--method pls, the optional ops pls_load / pls_correct): the set
 * seeded on the host is copied to the device once per pair (and after each
 * host reseeding); each stage then builds the node field F, grad phi and
 * advects every particle, each correction removes flagged particles, detects
 * escaped ones and corrects phi, all on the device with the per-particle code
 * of kernels/lsm_particle_cell.h.  The host reads back five counters per
 * correction.  Removed particles are kept with a dead state, not compacted.
 *
 * The program is built from source at every open: the OpenCL implementations'
 * own caches (PoCL's, NVIDIA's) serve repeated builds (kernels/README.md). */
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "kernels/lsm_particle_cell.h"
#include "lsm_kernels.h" /* lsm_kernel_source[]: morph.cl + the headers, NUL-terminated */
#include "solver/pde/lsm_backend.h"

/* ---- errors ------------------------------------------------------------------------ */

static const char *cl_error_name(cl_int code) {
  switch (code) {
#define LSM_CL_ERR(name) \
  case name:             \
    return #name;
    LSM_CL_ERR(CL_SUCCESS)
    LSM_CL_ERR(CL_DEVICE_NOT_FOUND)
    LSM_CL_ERR(CL_DEVICE_NOT_AVAILABLE)
    LSM_CL_ERR(CL_COMPILER_NOT_AVAILABLE)
    LSM_CL_ERR(CL_MEM_OBJECT_ALLOCATION_FAILURE)
    LSM_CL_ERR(CL_OUT_OF_RESOURCES)
    LSM_CL_ERR(CL_OUT_OF_HOST_MEMORY)
    LSM_CL_ERR(CL_PROFILING_INFO_NOT_AVAILABLE)
    LSM_CL_ERR(CL_MEM_COPY_OVERLAP)
    LSM_CL_ERR(CL_IMAGE_FORMAT_MISMATCH)
    LSM_CL_ERR(CL_IMAGE_FORMAT_NOT_SUPPORTED)
    LSM_CL_ERR(CL_BUILD_PROGRAM_FAILURE)
    LSM_CL_ERR(CL_MAP_FAILURE)
    LSM_CL_ERR(CL_MISALIGNED_SUB_BUFFER_OFFSET)
    LSM_CL_ERR(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
    LSM_CL_ERR(CL_COMPILE_PROGRAM_FAILURE)
    LSM_CL_ERR(CL_LINKER_NOT_AVAILABLE)
    LSM_CL_ERR(CL_LINK_PROGRAM_FAILURE)
    LSM_CL_ERR(CL_DEVICE_PARTITION_FAILED)
    LSM_CL_ERR(CL_KERNEL_ARG_INFO_NOT_AVAILABLE)
    LSM_CL_ERR(CL_INVALID_VALUE)
    LSM_CL_ERR(CL_INVALID_DEVICE_TYPE)
    LSM_CL_ERR(CL_INVALID_PLATFORM)
    LSM_CL_ERR(CL_INVALID_DEVICE)
    LSM_CL_ERR(CL_INVALID_CONTEXT)
    LSM_CL_ERR(CL_INVALID_QUEUE_PROPERTIES)
    LSM_CL_ERR(CL_INVALID_COMMAND_QUEUE)
    LSM_CL_ERR(CL_INVALID_HOST_PTR)
    LSM_CL_ERR(CL_INVALID_MEM_OBJECT)
    LSM_CL_ERR(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR)
    LSM_CL_ERR(CL_INVALID_IMAGE_SIZE)
    LSM_CL_ERR(CL_INVALID_SAMPLER)
    LSM_CL_ERR(CL_INVALID_BINARY)
    LSM_CL_ERR(CL_INVALID_BUILD_OPTIONS)
    LSM_CL_ERR(CL_INVALID_PROGRAM)
    LSM_CL_ERR(CL_INVALID_PROGRAM_EXECUTABLE)
    LSM_CL_ERR(CL_INVALID_KERNEL_NAME)
    LSM_CL_ERR(CL_INVALID_KERNEL_DEFINITION)
    LSM_CL_ERR(CL_INVALID_KERNEL)
    LSM_CL_ERR(CL_INVALID_ARG_INDEX)
    LSM_CL_ERR(CL_INVALID_ARG_VALUE)
    LSM_CL_ERR(CL_INVALID_ARG_SIZE)
    LSM_CL_ERR(CL_INVALID_KERNEL_ARGS)
    LSM_CL_ERR(CL_INVALID_WORK_DIMENSION)
    LSM_CL_ERR(CL_INVALID_WORK_GROUP_SIZE)
    LSM_CL_ERR(CL_INVALID_WORK_ITEM_SIZE)
    LSM_CL_ERR(CL_INVALID_GLOBAL_OFFSET)
    LSM_CL_ERR(CL_INVALID_EVENT_WAIT_LIST)
    LSM_CL_ERR(CL_INVALID_EVENT)
    LSM_CL_ERR(CL_INVALID_OPERATION)
    LSM_CL_ERR(CL_INVALID_GL_OBJECT)
    LSM_CL_ERR(CL_INVALID_BUFFER_SIZE)
    LSM_CL_ERR(CL_INVALID_MIP_LEVEL)
    LSM_CL_ERR(CL_INVALID_GLOBAL_WORK_SIZE)
    LSM_CL_ERR(CL_INVALID_PROPERTY)
    LSM_CL_ERR(CL_INVALID_IMAGE_DESCRIPTOR)
    LSM_CL_ERR(CL_INVALID_COMPILER_OPTIONS)
    LSM_CL_ERR(CL_INVALID_LINKER_OPTIONS)
    LSM_CL_ERR(CL_INVALID_DEVICE_PARTITION_COUNT)
#undef LSM_CL_ERR
  case -1001:
    return "CL_PLATFORM_NOT_FOUND_KHR";
  default:
    return "unknown OpenCL error";
  }
}

/* The status an OpenCL error maps to: running out of device or host memory is
 * LSM_ERR_NOMEM, anything else a failure of the OpenCL implementation. */
static lsm_status cl_status_of(cl_int code) {
  return code == CL_MEM_OBJECT_ALLOCATION_FAILURE || code == CL_OUT_OF_RESOURCES ||
                 code == CL_OUT_OF_HOST_MEMORY
             ? LSM_ERR_NOMEM
             : LSM_ERR_INTERNAL;
}

/* "OpenCL: <device>: <call> failed: <error name>" */
static lsm_status cl_fail(lsm_err *err, const char *device, const char *call, cl_int code) {
  return lsm_fail(err, cl_status_of(code), NULL, "OpenCL: %s: %s failed: %s (%d)", device, call,
                  cl_error_name(code), (int)code);
}

/* Evaluates a call returning cl_int; on failure records the message and returns
 * the status from the enclosing function.  Needs `err` and a device name. */
#define CL_TRY(device, call_name, expr)                                \
  do {                                                                 \
    cl_int lsm_cl_e_ = (expr);                                         \
    if (lsm_cl_e_ != CL_SUCCESS) return cl_fail(err, device, call_name, lsm_cl_e_); \
  } while (0)

static double now_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- device enumeration ---------------------------------------------------------------- */

typedef struct cl_dev_ref {
  cl_platform_id platform;
  cl_device_id device;
} cl_dev_ref;

/* Every device of every platform, in platform order: the indices of
 * `lsmorph devices` and --device. */
static lsm_status cl_enumerate(cl_dev_ref **out, cl_uint *count, lsm_err *err) {
  *out = NULL;
  *count = 0;
  cl_uint nplat = 0;
  cl_int e = clGetPlatformIDs(0, NULL, &nplat);
  if (e == -1001 /* CL_PLATFORM_NOT_FOUND_KHR */ || (e == CL_SUCCESS && nplat == 0))
    return lsm_fail(err, LSM_ERR_UNSUPPORTED, NULL,
                    "OpenCL: no platform found (install an OpenCL driver, e.g. the Debian "
                    "package pocl-opencl-icd, or use --backend c)");
  if (e != CL_SUCCESS) return cl_fail(err, "no device", "clGetPlatformIDs", e);
  cl_platform_id *plats = calloc(nplat, sizeof *plats);
  if (!plats) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: cannot allocate the platform list");
  e = clGetPlatformIDs(nplat, plats, NULL);
  if (e != CL_SUCCESS) {
    free(plats);
    return cl_fail(err, "no device", "clGetPlatformIDs", e);
  }
  cl_dev_ref *refs = NULL;
  cl_uint n = 0;
  lsm_status st = LSM_OK;
  for (cl_uint p = 0; p < nplat && st == LSM_OK; ++p) {
    cl_uint nd = 0;
    e = clGetDeviceIDs(plats[p], CL_DEVICE_TYPE_ALL, 0, NULL, &nd);
    if (e == CL_DEVICE_NOT_FOUND) continue;
    if (e != CL_SUCCESS) { /* a platform skipped would renumber the devices after it */
      st = cl_fail(err, "no device", "clGetDeviceIDs", e);
      break;
    }
    if (nd == 0) continue;
    cl_device_id *devs = calloc(nd, sizeof *devs);
    cl_dev_ref *grown = realloc(refs, (size_t)(n + nd) * sizeof *refs);
    if (grown) refs = grown;
    if (!devs || !grown) {
      free(devs);
      st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: cannot allocate the device list");
      break;
    }
    e = clGetDeviceIDs(plats[p], CL_DEVICE_TYPE_ALL, nd, devs, NULL);
    if (e != CL_SUCCESS) {
      free(devs);
      st = cl_fail(err, "no device", "clGetDeviceIDs", e);
      break;
    }
    for (cl_uint d = 0; d < nd; ++d) {
      refs[n].platform = plats[p];
      refs[n].device = devs[d];
      n++;
    }
    free(devs);
  }
  free(plats);
  if (st != LSM_OK) {
    free(refs);
    return st;
  }
  if (n == 0) {
    free(refs);
    return lsm_fail(err, LSM_ERR_UNSUPPORTED, NULL,
                    "OpenCL: %u platform%s but no device found (use --backend c; PoCL drops its "
                    "CPU device when it cannot write its kernel cache: set POCL_CACHE_DIR to a "
                    "writable folder)",
                    nplat, nplat == 1 ? "" : "s");
  }
  *out = refs;
  *count = n;
  return LSM_OK;
}

/* A string property ("?" when the query fails). */
static void device_str(cl_device_id d, cl_device_info what, char *buf, size_t size) {
  if (clGetDeviceInfo(d, what, size, buf, NULL) != CL_SUCCESS) snprintf(buf, size, "?");
  buf[size - 1] = '\0';
}

static void platform_str(cl_platform_id p, cl_platform_info what, char *buf, size_t size) {
  if (clGetPlatformInfo(p, what, size, buf, NULL) != CL_SUCCESS) snprintf(buf, size, "?");
  buf[size - 1] = '\0';
}

static const char *device_type_name(cl_device_type t) {
  if (t & CL_DEVICE_TYPE_GPU) return "GPU";
  if (t & CL_DEVICE_TYPE_CPU) return "CPU";
  if (t & CL_DEVICE_TYPE_ACCELERATOR) return "accelerator";
  return "other";
}

/* The device taken without --device: the first GPU listed, else the first. */
static cl_uint default_device(const cl_dev_ref *refs, cl_uint n) {
  for (cl_uint k = 0; k < n; ++k) {
    cl_device_type t = 0;
    if (clGetDeviceInfo(refs[k].device, CL_DEVICE_TYPE, sizeof t, &t, NULL) == CL_SUCCESS &&
        (t & CL_DEVICE_TYPE_GPU))
      return k;
  }
  return 0;
}

lsm_status lsm_backend_cl_list(FILE *f, lsm_err *err) {
  cl_dev_ref *refs = NULL;
  cl_uint n = 0;
  LSM_TRY(cl_enumerate(&refs, &n, err));
  const cl_uint taken = default_device(refs, n);
  fprintf(f, "OpenCL devices (--device N; without it, the default):\n");
  for (cl_uint k = 0; k < n; ++k) {
    char name[256], plat[256], version[256], driver[128];
    cl_device_type type = 0;
    cl_uint units = 0;
    cl_ulong mem = 0;
    device_str(refs[k].device, CL_DEVICE_NAME, name, sizeof name);
    device_str(refs[k].device, CL_DEVICE_VERSION, version, sizeof version);
    device_str(refs[k].device, CL_DRIVER_VERSION, driver, sizeof driver);
    platform_str(refs[k].platform, CL_PLATFORM_NAME, plat, sizeof plat);
    /* A failed query prints as unknown rather than failing the list. */
    const int has_type =
        clGetDeviceInfo(refs[k].device, CL_DEVICE_TYPE, sizeof type, &type, NULL) == CL_SUCCESS;
    const int has_units = clGetDeviceInfo(refs[k].device, CL_DEVICE_MAX_COMPUTE_UNITS,
                                          sizeof units, &units, NULL) == CL_SUCCESS;
    const int has_mem = clGetDeviceInfo(refs[k].device, CL_DEVICE_GLOBAL_MEM_SIZE, sizeof mem,
                                        &mem, NULL) == CL_SUCCESS;
    fprintf(f, "  %u: %s (%s)%s\n     type %s, ", k, name, plat, k == taken ? ", the default" : "",
            has_type ? device_type_name(type) : "unknown");
    if (has_units)
      fprintf(f, "%u compute unit%s, ", units, units == 1 ? "" : "s");
    else
      fprintf(f, "? compute units, ");
    if (has_mem)
      fprintf(f, "%.0f MiB global memory, ", (double)mem / (1024.0 * 1024.0));
    else
      fprintf(f, "? MiB global memory, ");
    fprintf(f, "%s, driver %s\n", version, driver);
  }
  free(refs);
  return LSM_OK;
}

/* ---- the run-wide context -------------------------------------------------------------- */

typedef struct cl_ctx {
  cl_platform_id platform;
  cl_device_id device;
  cl_context context;
  cl_program program;
  char name[256];           /* "<device name> (<platform name>)" */
  int cpu;                  /* a CPU device (PoCL): reductions in runs, serial combine */
  size_t local_max;         /* cell kernels' work-group width limit (one row segment) */
  size_t red_local[2];      /* reductions' work-group, a power of two in all */
  int red_run;              /* cells per work-item and row in the reductions */
  size_t max_group;         /* CL_DEVICE_MAX_WORK_GROUP_SIZE, lowered to the smallest
                               CL_KERNEL_WORK_GROUP_SIZE of our kernels (registers, local
                               memory: a GPU may take fewer work-items per group for a
                               kernel than for the device) */
  size_t max_items[3];      /* CL_DEVICE_MAX_WORK_ITEM_SIZES, first three dimensions */
  cl_ulong max_alloc, global_mem;
} cl_ctx;

static void cl_close_ctx(void **vctx) {
  if (!vctx || !*vctx) return;
  cl_ctx *c = *vctx;
  if (c->program) clReleaseProgram(c->program);
  if (c->context) clReleaseContext(c->context);
  free(c);
  *vctx = NULL;
}

/* ---- building the program ----------------------------------------------------------------- */

/* clBuildProgram; on failure the message carries the (truncated) build log. */
static lsm_status build_program(cl_ctx *c, cl_program prog, const char *options, lsm_err *err) {
  cl_int e = clBuildProgram(prog, 1, &c->device, options, NULL, NULL);
  if (e == CL_SUCCESS) return LSM_OK;
  size_t n = 0;
  char *log = NULL;
  if (clGetProgramBuildInfo(prog, c->device, CL_PROGRAM_BUILD_LOG, 0, NULL, &n) == CL_SUCCESS &&
      n > 0 && (log = malloc(n + 1)) != NULL) {
    if (clGetProgramBuildInfo(prog, c->device, CL_PROGRAM_BUILD_LOG, n, log, NULL) != CL_SUCCESS)
      n = 0;
    log[n] = '\0';
  }
  const size_t keep = 600;
  lsm_status st = lsm_fail(err, e == CL_BUILD_PROGRAM_FAILURE ? LSM_ERR_INTERNAL : cl_status_of(e),
                           NULL, "OpenCL: %s: clBuildProgram failed: %s (%d); build log%s:\n%.*s",
                           c->name, cl_error_name(e), (int)e,
                           log && strlen(log) > keep ? " (truncated)" : "", (int)keep,
                           log && log[0] ? log : "(empty)");
  free(log);
  return st;
}

static lsm_status program_from_source(cl_ctx *c, const char *options, lsm_err *err) {
  const char *src = (const char *)lsm_kernel_source;
  const size_t len = sizeof lsm_kernel_source - 1;
  cl_int e;
  c->program = clCreateProgramWithSource(c->context, 1, &src, &len, &e);
  if (e != CL_SUCCESS) {
    c->program = NULL;
    return cl_fail(err, c->name, "clCreateProgramWithSource", e);
  }
  return build_program(c, c->program, options, err);
}

/* ---- opening ------------------------------------------------------------------------------ */

static const lsm_backend_ops cl_ops;

/* The kernels of morph.cl, created per pair (cl_state). */
enum {
  K_GHOSTS,
  K_UPWIND,
  K_ROEFIX,
  K_WENO5,
  K_CFL,
  K_RESIDUAL,
  K_REINIT,
  K_PCL_VELOCITY,
  K_PCL_ADVECT,
  K_PCL_DETECT,
  K_PCL_APPLY,
  K_PCL_RADIUS,
  K_COUNT
};
static const char *const kernel_names[K_COUNT] = {
    "lsm_fill_ghosts",  "lsm_stage_upwind", "lsm_stage_roefix", "lsm_stage_weno5", "lsm_cfl_partial",
    "lsm_residual_partial", "lsm_reinit_step", "lsm_pcl_velocity", "lsm_pcl_advect",
    "lsm_pcl_detect",   "lsm_pcl_apply",    "lsm_pcl_adjust_radius"};

/* Lowers c->max_group to the smallest CL_KERNEL_WORK_GROUP_SIZE of the
 * kernels: a GPU can take fewer work-items per group for a kernel that uses
 * many registers than CL_DEVICE_MAX_WORK_GROUP_SIZE says, and a launch past
 * it fails with CL_INVALID_WORK_GROUP_SIZE. */
static lsm_status kernel_group_limit(cl_ctx *c, lsm_err *err) {
  for (int k = 0; k < K_COUNT; ++k) {
    cl_int e;
    cl_kernel kernel = clCreateKernel(c->program, kernel_names[k], &e);
    char call[64];
    snprintf(call, sizeof call, "clCreateKernel(%s)", kernel_names[k]);
    if (e != CL_SUCCESS) return cl_fail(err, c->name, call, e);
    size_t limit = 0;
    e = clGetKernelWorkGroupInfo(kernel, c->device, CL_KERNEL_WORK_GROUP_SIZE, sizeof limit, &limit,
                                 NULL);
    clReleaseKernel(kernel);
    if (e != CL_SUCCESS) return cl_fail(err, c->name, "clGetKernelWorkGroupInfo", e);
    if (limit > 0 && limit < c->max_group) c->max_group = limit;
  }
  return LSM_OK;
}

/* Work-group shapes.  Cell kernels: one row segment of up to 256 work-items
 * (LSMORPH_CL_LOCAL=W overrides the 256, for experiments).  Reductions: on
 * CPUs 8 x 1 work-items each covering runs of 128 cells of a row (plain
 * loops, the residual eight lanes at a time); elsewhere 64 x 4 work-items of
 * one cell each (neighbours read neighbours); halved until the device takes
 * them. */
static void pick_local(cl_ctx *c) {
  c->local_max = 256;
  const char *env = getenv("LSMORPH_CL_LOCAL");
  if (env) {
    unsigned w = 0;
    if (sscanf(env, "%u", &w) == 1 && w > 0 && w <= 4096) c->local_max = w;
  }
  while (c->local_max > 1 && (c->local_max > c->max_items[0] || c->local_max > c->max_group))
    c->local_max /= 2;
  size_t rx = c->cpu ? 8 : 64, ry = c->cpu ? 1 : 4;
  while (rx * ry > c->max_group || rx > c->max_items[0] || ry > c->max_items[1]) {
    if (ry > 1)
      ry /= 2;
    else
      rx /= 2;
  }
  c->red_local[0] = rx;
  c->red_local[1] = ry;
  c->red_run = c->cpu ? 128 : 1;
}

lsm_status lsm_backend_cl_open(int device, lsm_backend *b, lsm_err *err) {
  cl_dev_ref *refs = NULL;
  cl_uint n = 0;
  LSM_TRY(cl_enumerate(&refs, &n, err));
  int pick = device;
  if (device < 0) {
    pick = (int)default_device(refs, n);
  } else if ((cl_uint)device >= n) {
    free(refs);
    return lsm_fail(err, LSM_ERR_INPUT, NULL,
                    "OpenCL: device %d does not exist: %u device%s found (indices 0 to %u; "
                    "see 'lsmorph devices')",
                    device, n, n == 1 ? "" : "s", n - 1);
  }
  cl_ctx *c = calloc(1, sizeof *c);
  if (!c) {
    free(refs);
    return lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: cannot allocate the backend context");
  }
  c->platform = refs[pick].platform;
  c->device = refs[pick].device;
  free(refs);
  char dev[256], plat[256];
  device_str(c->device, CL_DEVICE_NAME, dev, sizeof dev);
  platform_str(c->platform, CL_PLATFORM_NAME, plat, sizeof plat);
  snprintf(c->name, sizeof c->name, "%.120s (%.120s)", dev, plat);

  lsm_status st = LSM_OK;
  cl_int e = CL_SUCCESS;
  cl_device_fp_config fp = 0;
  cl_device_type type = 0;
  size_t items[64] = {0}; /* CL_DEVICE_MAX_WORK_ITEM_SIZES: one per dimension (>= 3) */
  cl_bool available = CL_FALSE, compiler = CL_FALSE;
  if ((e = clGetDeviceInfo(c->device, CL_DEVICE_AVAILABLE, sizeof available, &available, NULL)) ||
      (e = clGetDeviceInfo(c->device, CL_DEVICE_COMPILER_AVAILABLE, sizeof compiler, &compiler, NULL)) ||
      (e = clGetDeviceInfo(c->device, CL_DEVICE_SINGLE_FP_CONFIG, sizeof fp, &fp, NULL)) ||
      (e = clGetDeviceInfo(c->device, CL_DEVICE_TYPE, sizeof type, &type, NULL)) ||
      (e = clGetDeviceInfo(c->device, CL_DEVICE_MAX_WORK_GROUP_SIZE, sizeof c->max_group, &c->max_group, NULL)) ||
      (e = clGetDeviceInfo(c->device, CL_DEVICE_MAX_WORK_ITEM_SIZES, sizeof items, items, NULL)) ||
      (e = clGetDeviceInfo(c->device, CL_DEVICE_MAX_MEM_ALLOC_SIZE, sizeof c->max_alloc, &c->max_alloc, NULL)) ||
      (e = clGetDeviceInfo(c->device, CL_DEVICE_GLOBAL_MEM_SIZE, sizeof c->global_mem, &c->global_mem, NULL)))
    st = cl_fail(err, c->name, "clGetDeviceInfo", e);
  memcpy(c->max_items, items, sizeof c->max_items);
  if (st == LSM_OK && !available)
    st = lsm_fail(err, LSM_ERR_UNSUPPORTED, NULL, "OpenCL: %s: the device is not available", c->name);
  if (st == LSM_OK && !compiler)
    st = lsm_fail(err, LSM_ERR_UNSUPPORTED, NULL, "OpenCL: %s: the device has no OpenCL C compiler",
                  c->name);
  if (st == LSM_OK) {
    cl_context_properties props[] = {CL_CONTEXT_PLATFORM, (cl_context_properties)c->platform, 0};
    c->context = clCreateContext(props, 1, &c->device, NULL, NULL, &e);
    if (e != CL_SUCCESS) {
      c->context = NULL;
      st = cl_fail(err, c->name, "clCreateContext", e);
    }
  }
  if (st == LSM_OK) {
    c->cpu = (type & CL_DEVICE_TYPE_CPU) != 0;
    char options[256];
    snprintf(options, sizeof options, "-cl-std=CL1.2 -DLSM_GHOST=%d%s%s", LSM_GHOST,
             (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) ? " -cl-fp32-correctly-rounded-divide-sqrt"
                                                        : "",
             c->cpu ? " -DLSM_CL_SERIAL_COMBINE" : "");
    const double t0 = now_seconds();
    st = program_from_source(c, options, err);
    b->build_seconds = now_seconds() - t0;
    b->kernel_cache_hit = 0; /* no cache of our own: the driver's (PoCL's, NVIDIA's) serves */
  }
  if (st == LSM_OK) st = kernel_group_limit(c, err);
  if (st == LSM_OK) pick_local(c);
  if (st != LSM_OK) {
    void *p = c;
    cl_close_ctx(&p);
    return st;
  }
  b->ops = &cl_ops;
  b->ctx = c;
  b->close_ctx = cl_close_ctx;
  snprintf(b->device, sizeof b->device, "%s", c->name);
  return LSM_OK;
}

/* ---- per-pair state ------------------------------------------------------------------------- */

/* The counters of lsm_pcl_detect / lsm_pcl_apply (morph.cl), in this order. */
enum { PCL_N_ESCAPED, PCL_N_STRAY, PCL_N_REMOVED, PCL_N_LIVE, PCL_N_CORRECTED, PCL_N_COUNT };

typedef struct cl_state {
  cl_ctx *c;
  cl_command_queue queue;
  cl_kernel k[K_COUNT];
  cl_mem phi, target, s1, s2, phi0; /* phi0: on first reinit */
  cl_mem partial;                   /* one float per reduction work-group */
  float *partial_host;
  size_t npartial;
  /* particles (pls_load): per particle x, y, RK base x0, y0, radius, sign
   * (char), state (uchar); pcap allocated, pn in use.  Per node (on the first
   * load): the stage's node field (float4), the phi_plus / phi_minus keys;
   * and the correction's counters. */
  cl_mem px, py, px0, py0, pradius, psign, pstate;
  cl_mem vel, plus, minus, counters;
  size_t pcap;
  cl_int pn;
  int radius_adjust;
  size_t plocal;  /* particle kernels' work-group size */
  float inv_2dx, inv_2dy, far, rmin, rmax;
  int nx, ny;
  cl_int stride;
  float dx, dy;
  size_t bytes;        /* one grid, ghosts included */
  size_t local[2];     /* cell kernels' work-group: a row segment (LX, 1) */
  size_t global[2];    /* cell kernels' NDRange: nx rounded up to LX, ny */
  size_t red_global[2];
  size_t ghost_global; /* ring cells, rounded up */
} cl_state;

static void cl_destroy(void **vs) {
  if (!vs || !*vs) return;
  cl_state *s = *vs;
  if (s->queue) clFinish(s->queue);
  for (int k = 0; k < K_COUNT; ++k)
    if (s->k[k]) clReleaseKernel(s->k[k]);
  cl_mem *mems[] = {&s->phi,   &s->target, &s->s1,      &s->s2,    &s->phi0,
                    &s->partial, &s->px,   &s->py,      &s->px0,   &s->py0,
                    &s->pradius, &s->psign, &s->pstate, &s->vel,   &s->plus,
                    &s->minus,   &s->counters};
  for (size_t k = 0; k < sizeof mems / sizeof *mems; ++k)
    if (*mems[k]) clReleaseMemObject(*mems[k]);
  if (s->queue) clReleaseCommandQueue(s->queue);
  free(s->partial_host);
  free(s);
  *vs = NULL;
}

static size_t round_up(size_t n, size_t m) { return m ? (n + m - 1) / m * m : n; }

static lsm_status new_buffer(cl_state *s, size_t bytes, cl_mem *out, lsm_err *err) {
  cl_int e;
  *out = clCreateBuffer(s->c->context, CL_MEM_READ_WRITE, bytes, NULL, &e);
  if (e == CL_SUCCESS) return LSM_OK;
  *out = NULL;
  if (e == CL_MEM_OBJECT_ALLOCATION_FAILURE || e == CL_OUT_OF_RESOURCES ||
      e == CL_OUT_OF_HOST_MEMORY || e == CL_INVALID_BUFFER_SIZE)
    return lsm_fail(err, LSM_ERR_NOMEM, NULL,
                    "OpenCL: %s: out of device memory for a %dx%d grid (a buffer of %.1f MiB): "
                    "clCreateBuffer failed: %s (%d)",
                    s->c->name, s->nx, s->ny, (double)bytes / (1024.0 * 1024.0),
                    cl_error_name(e), (int)e);
  return cl_fail(err, s->c->name, "clCreateBuffer", e);
}

/* Blocking write of a whole host grid (ghosts included) into a buffer. */
static lsm_status write_grid(cl_state *s, cl_mem buf, const lsm_grid *g, lsm_err *err) {
  CL_TRY(s->c->name, "clEnqueueWriteBuffer",
         clEnqueueWriteBuffer(s->queue, buf, CL_TRUE, 0, s->bytes, g->base, 0, NULL, NULL));
  return LSM_OK;
}

static lsm_status set_arg(cl_state *s, cl_kernel k, cl_uint index, size_t size, const void *value,
                          lsm_err *err) {
  CL_TRY(s->c->name, "clSetKernelArg", clSetKernelArg(k, index, size, value));
  return LSM_OK;
}

#define ARG(kernel, index, value) LSM_TRY(set_arg(s, kernel, index, sizeof(value), &(value), err))

static lsm_status run_2d(cl_state *s, cl_kernel k, const size_t *global, const size_t *local,
                         lsm_err *err) {
  CL_TRY(s->c->name, "clEnqueueNDRangeKernel",
         clEnqueueNDRangeKernel(s->queue, k, 2, NULL, global, local, 0, NULL, NULL));
  return LSM_OK;
}

/* Zero-gradient ghost fill of a buffer (lsm_grid_fill_ghosts). */
static lsm_status fill_ghosts(cl_state *s, cl_mem g, lsm_err *err) {
  cl_kernel k = s->k[K_GHOSTS];
  ARG(k, 0, g);
  ARG(k, 1, s->nx);
  ARG(k, 2, s->ny);
  ARG(k, 3, s->stride);
  const size_t local = 64;
  CL_TRY(s->c->name, "clEnqueueNDRangeKernel",
         clEnqueueNDRangeKernel(s->queue, k, 1, NULL, &s->ghost_global,
                                local <= s->c->max_group ? &local : NULL, 0, NULL, NULL));
  return LSM_OK;
}

static lsm_status cl_create(void *vctx, const lsm_grid *src, const lsm_grid *tgt, int threads,
                            void **state, lsm_err *err) {
  (void)threads; /* the device runs its own threads */
  *state = NULL;
  cl_ctx *c = vctx;
  if (src->nx != tgt->nx || src->ny != tgt->ny || src->stride != tgt->stride ||
      src->ghost != LSM_GHOST || tgt->ghost != LSM_GHOST)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "OpenCL: source and target grids differ in size");
  const size_t rows = (size_t)src->ny + 2u * LSM_GHOST;
  size_t floats, bytes;
  if (!lsm_size_mul(rows, (size_t)src->stride, &floats) ||
      !lsm_size_mul(floats, sizeof(float), &bytes) || src->stride > INT32_MAX ||
      floats > (size_t)INT32_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "OpenCL: %s: a %dx%d grid is too large", c->name,
                    src->nx, src->ny);
  if (bytes > c->max_alloc || 4.0 * (double)bytes > (double)c->global_mem)
    return lsm_fail(err, LSM_ERR_NOMEM, NULL,
                    "OpenCL: %s: out of device memory: a %dx%d grid needs 4 buffers of %.1f MiB "
                    "(device: %.0f MiB global memory, at most %.0f MiB per buffer)",
                    c->name, src->nx, src->ny, (double)bytes / 1048576.0,
                    (double)c->global_mem / 1048576.0, (double)c->max_alloc / 1048576.0);
  cl_state *s = calloc(1, sizeof *s);
  if (!s) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: cannot allocate the backend state");
  s->c = c;
  s->nx = src->nx;
  s->ny = src->ny;
  s->stride = (cl_int)src->stride;
  s->dx = src->dx;
  s->dy = src->dy;
  s->bytes = bytes;
  /* particle constants, computed as lsm_pls_create computes them */
  s->inv_2dx = 0.5f / s->dx;
  s->inv_2dy = 0.5f / s->dy;
  s->far = lsm_pcl_far(s->dx, s->dy);
  s->rmin = lsm_pcl_rmin(s->dx, s->dy);
  s->rmax = lsm_pcl_rmax(s->dx, s->dy);
  /* particle kernels: 1D groups of 128, fewer if the device says so */
  s->plocal = 128;
  while (s->plocal > 1 && (s->plocal > c->max_group || s->plocal > c->max_items[0]))
    s->plocal /= 2;
  /* Cell kernels: row segments of LX work-items, LX a power of two from 8 up
   * to local_max, no wider than the row needs.  (Taller groups run several
   * times slower on PoCL: its work-item loops vectorise along rows.) */
  size_t lx = 8;
  while (lx < c->local_max && lx < (size_t)s->nx) lx *= 2;
  while (lx > 1 && lx > c->local_max) lx /= 2;
  s->local[0] = lx;
  s->local[1] = 1;
  s->global[0] = round_up((size_t)s->nx, lx);
  s->global[1] = (size_t)s->ny;
  /* Reductions: whole groups across the width (runs of red_run cells per
   * work-item); down the height at most enough groups for ~1024 partial
   * results (work-items then loop over rows). */
  const size_t runs = ((size_t)s->nx + (size_t)c->red_run - 1) / (size_t)c->red_run;
  s->red_global[0] = round_up(runs, c->red_local[0]);
  const size_t groups_x = s->red_global[0] / c->red_local[0];
  size_t groups_y = ((size_t)s->ny + c->red_local[1] - 1) / c->red_local[1];
  size_t cap_y = 1024 / groups_x;
  if (cap_y < 1) cap_y = 1;
  if (groups_y > cap_y) groups_y = cap_y;
  s->red_global[1] = groups_y * c->red_local[1];
  s->npartial = groups_x * groups_y;
  s->ghost_global = round_up(2u * LSM_GHOST * ((size_t)s->ny + (size_t)s->stride), 64);

  lsm_status st = LSM_OK;
  cl_int e;
  s->queue = clCreateCommandQueue(c->context, c->device, 0, &e);
  if (e != CL_SUCCESS) {
    s->queue = NULL;
    st = cl_fail(err, c->name, "clCreateCommandQueue", e);
  }
  for (int k = 0; k < K_COUNT && st == LSM_OK; ++k) {
    s->k[k] = clCreateKernel(c->program, kernel_names[k], &e);
    if (e != CL_SUCCESS) {
      s->k[k] = NULL;
      char call[64];
      snprintf(call, sizeof call, "clCreateKernel(%s)", kernel_names[k]);
      st = cl_fail(err, c->name, call, e);
    }
  }
  if (st == LSM_OK && !(s->partial_host = calloc(s->npartial, sizeof(float))))
    st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: cannot allocate the reduction results");
  if (st == LSM_OK) st = new_buffer(s, bytes, &s->phi, err);
  if (st == LSM_OK) st = new_buffer(s, bytes, &s->target, err);
  if (st == LSM_OK) st = new_buffer(s, bytes, &s->s1, err);
  if (st == LSM_OK) st = new_buffer(s, bytes, &s->s2, err);
  if (st == LSM_OK) st = new_buffer(s, s->npartial * sizeof(float), &s->partial, err);
  if (st == LSM_OK) st = write_grid(s, s->phi, src, err);
  if (st == LSM_OK) st = write_grid(s, s->target, tgt, err);
  if (st == LSM_OK) st = fill_ghosts(s, s->target, err);
  if (st != LSM_OK) {
    void *p = s;
    cl_destroy(&p);
    return st;
  }
  *state = s;
  return LSM_OK;
}

/* Runs a reduction kernel (args from index `first_local` on: __local scratch,
 * partial) and reads the partial results (blocking). */
static lsm_status reduce(cl_state *s, cl_kernel k, cl_uint first_local, lsm_err *err) {
  const size_t local_bytes = s->c->red_local[0] * s->c->red_local[1] * sizeof(float);
  LSM_TRY(set_arg(s, k, first_local, local_bytes, NULL, err));
  ARG(k, first_local + 1, s->partial);
  LSM_TRY(run_2d(s, k, s->red_global, s->c->red_local, err));
  CL_TRY(s->c->name, "clEnqueueReadBuffer",
         clEnqueueReadBuffer(s->queue, s->partial, CL_TRUE, 0, s->npartial * sizeof(float),
                             s->partial_host, 0, NULL, NULL));
  return LSM_OK;
}

static lsm_status cl_cfl_dt(void *vs, lsm_scheme scheme, double cfl, double *dt, lsm_err *err) {
  cl_state *s = vs;
  const float inv_dx = 1.0f / s->dx, inv_dy = 1.0f / s->dy;
  LSM_TRY(fill_ghosts(s, s->phi, err));
  cl_kernel k = s->k[K_CFL];
  ARG(k, 0, s->phi);
  ARG(k, 1, s->target);
  ARG(k, 2, s->nx);
  ARG(k, 3, s->ny);
  ARG(k, 4, s->stride);
  ARG(k, 5, s->c->red_run);
  ARG(k, 6, inv_dx);
  ARG(k, 7, inv_dy);
  const cl_int roefix = scheme == LSM_SCHEME_ROEFIX;
  ARG(k, 8, roefix);
  LSM_TRY(reduce(s, k, 9, err));
  float rate = 0.0f;
  for (size_t q = 0; q < s->npartial; ++q)
    rate = s->partial_host[q] > rate ? s->partial_host[q] : rate;
  *dt = rate > 0.0f ? cfl / (double)rate : INFINITY;
  return LSM_OK;
}

static lsm_status cl_residual(void *vs, double *norm, lsm_err *err) {
  cl_state *s = vs;
  cl_kernel k = s->k[K_RESIDUAL];
  ARG(k, 0, s->phi);
  ARG(k, 1, s->target);
  ARG(k, 2, s->nx);
  ARG(k, 3, s->ny);
  ARG(k, 4, s->stride);
  ARG(k, 5, s->c->red_run);
  LSM_TRY(reduce(s, k, 6, err));
  double total = 0.0;
  for (size_t q = 0; q < s->npartial; ++q) total += (double)s->partial_host[q];
  *norm = sqrt(total);
  return LSM_OK;
}

/* ---- particles ------------------------------------------------------------------------ */

static lsm_status run_1d(cl_state *s, cl_kernel k, size_t n, lsm_err *err) {
  const size_t global = round_up(n, s->plocal);
  CL_TRY(s->c->name, "clEnqueueNDRangeKernel",
         clEnqueueNDRangeKernel(s->queue, k, 1, NULL, &global, &s->plocal, 0, NULL, NULL));
  return LSM_OK;
}

/* The particles' share of a stage whose input is `in` (lsm_pls_stage): the
 * node field from `in`, then every particle advected; first: the step's
 * first stage (records the Runge–Kutta base). */
static lsm_status pcl_stage(cl_state *s, cl_mem in, float c0, float c1, float dt, int first,
                            lsm_err *err) {
  const float inv_dx = 1.0f / s->dx, inv_dy = 1.0f / s->dy;
  cl_kernel k = s->k[K_PCL_VELOCITY];
  ARG(k, 0, s->vel);
  ARG(k, 1, in);
  ARG(k, 2, s->target);
  ARG(k, 3, s->nx);
  ARG(k, 4, s->ny);
  ARG(k, 5, s->stride);
  ARG(k, 6, inv_dx);
  ARG(k, 7, inv_dy);
  ARG(k, 8, s->inv_2dx);
  ARG(k, 9, s->inv_2dy);
  LSM_TRY(run_2d(s, k, s->global, s->local, err));
  const cl_int save_base = first;
  k = s->k[K_PCL_ADVECT];
  ARG(k, 0, s->px);
  ARG(k, 1, s->py);
  ARG(k, 2, s->px0);
  ARG(k, 3, s->py0);
  ARG(k, 4, s->pstate);
  ARG(k, 5, s->pn);
  ARG(k, 6, s->vel);
  ARG(k, 7, s->nx);
  ARG(k, 8, s->ny);
  ARG(k, 9, inv_dx);
  ARG(k, 10, inv_dy);
  ARG(k, 11, c0);
  ARG(k, 12, c1);
  ARG(k, 13, dt);
  ARG(k, 14, save_base);
  return run_1d(s, k, (size_t)s->pn, err);
}

/* (Re)allocation of a particle buffer of `bytes` (the old one, if any, released). */
static lsm_status pcl_buffer(cl_state *s, cl_mem *buf, size_t bytes, lsm_err *err) {
  if (*buf) clReleaseMemObject(*buf);
  *buf = NULL;
  return new_buffer(s, bytes, buf, err);
}

static lsm_status fill_uint(cl_state *s, cl_mem buf, cl_uint value, size_t count, lsm_err *err) {
  CL_TRY(s->c->name, "clEnqueueFillBuffer",
         clEnqueueFillBuffer(s->queue, buf, &value, sizeof value, 0, count * sizeof value, 0,
                             NULL, NULL));
  return LSM_OK;
}

static lsm_status cl_pls_load(void *vs, const lsm_pls_view *set, int radius_adjust,
                              lsm_err *err) {
  cl_state *s = vs;
  if (set->n > (size_t)INT32_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "OpenCL: %s: %zu particles are too many", s->c->name,
                    set->n);
  if (set->n > 0 && (s->nx < 2 || s->ny < 2))
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "OpenCL: particles on a %dx%d grid", s->nx, s->ny);
  const size_t nodes = (size_t)s->nx * (size_t)s->ny;
  if (!s->counters) { /* the first load (or a retry after a failed one) */
    LSM_TRY(pcl_buffer(s, &s->vel, nodes * 4 * sizeof(float), err));
    LSM_TRY(pcl_buffer(s, &s->plus, nodes * sizeof(cl_uint), err));
    LSM_TRY(pcl_buffer(s, &s->minus, nodes * sizeof(cl_uint), err));
    /* the accumulators' "no particle" keys (morph.cl: LSM_PCL_KEY_NONE_*);
     * lsm_pcl_apply restores them after each correction */
    LSM_TRY(fill_uint(s, s->plus, 0u, nodes, err));
    LSM_TRY(fill_uint(s, s->minus, 0xFFFFFFFFu, nodes, err));
    LSM_TRY(pcl_buffer(s, &s->counters, PCL_N_COUNT * sizeof(cl_int), err));
  }
  const size_t n = set->n;
  if (n > s->pcap || !s->px) {
    const size_t cap = n > 0 ? n : 1, fb = cap * sizeof(float);
    s->pcap = 0;
    LSM_TRY(pcl_buffer(s, &s->px, fb, err));
    LSM_TRY(pcl_buffer(s, &s->py, fb, err));
    LSM_TRY(pcl_buffer(s, &s->px0, fb, err));
    LSM_TRY(pcl_buffer(s, &s->py0, fb, err));
    LSM_TRY(pcl_buffer(s, &s->pradius, fb, err));
    LSM_TRY(pcl_buffer(s, &s->psign, cap, err));
    LSM_TRY(pcl_buffer(s, &s->pstate, cap, err));
    s->pcap = cap;
  }
  s->pn = 0;
  if (n > 0) {
    const size_t fb = n * sizeof(float);
    CL_TRY(s->c->name, "clEnqueueWriteBuffer",
           clEnqueueWriteBuffer(s->queue, s->px, CL_FALSE, 0, fb, set->x, 0, NULL, NULL));
    CL_TRY(s->c->name, "clEnqueueWriteBuffer",
           clEnqueueWriteBuffer(s->queue, s->py, CL_FALSE, 0, fb, set->y, 0, NULL, NULL));
    CL_TRY(s->c->name, "clEnqueueWriteBuffer",
           clEnqueueWriteBuffer(s->queue, s->pradius, CL_FALSE, 0, fb, set->radius, 0, NULL, NULL));
    CL_TRY(s->c->name, "clEnqueueWriteBuffer",
           clEnqueueWriteBuffer(s->queue, s->psign, CL_FALSE, 0, n, set->sign, 0, NULL, NULL));
    const cl_uchar live = 0; /* morph.cl: LSM_PCL_LIVE */
    CL_TRY(s->c->name, "clEnqueueFillBuffer",
           clEnqueueFillBuffer(s->queue, s->pstate, &live, 1, 0, n, 0, NULL, NULL));
  }
  /* The set may change once this returns: wait for the copies. */
  CL_TRY(s->c->name, "clFinish", clFinish(s->queue));
  s->pn = (cl_int)n;
  s->radius_adjust = radius_adjust;
  return LSM_OK;
}

/* Arguments 0-9 shared by the detection and radius kernels: the particle
 * arrays, their count, and phi with its size and row stride. */
static lsm_status particle_args(cl_state *s, cl_kernel k, lsm_err *err) {
  ARG(k, 0, s->px);
  ARG(k, 1, s->py);
  ARG(k, 2, s->psign);
  ARG(k, 3, s->pradius);
  ARG(k, 4, s->pstate);
  ARG(k, 5, s->pn);
  ARG(k, 6, s->phi);
  ARG(k, 7, s->nx);
  ARG(k, 8, s->ny);
  ARG(k, 9, s->stride);
  return LSM_OK;
}

static lsm_status cl_pls_correct(void *vs, lsm_pls_counts *counts, lsm_err *err) {
  cl_state *s = vs;
  memset(counts, 0, sizeof *counts);
  if (s->pn == 0) return LSM_OK;
  const cl_uint zero = 0;
  LSM_TRY(fill_uint(s, s->counters, zero, PCL_N_COUNT, err));
  cl_kernel k = s->k[K_PCL_DETECT];
  LSM_TRY(particle_args(s, k, err));
  ARG(k, 10, s->dx);
  ARG(k, 11, s->dy);
  ARG(k, 12, s->far);
  ARG(k, 13, s->plus);
  ARG(k, 14, s->minus);
  ARG(k, 15, s->counters);
  LSM_TRY(set_arg(s, k, 16, s->plocal * sizeof(cl_int), NULL, err));
  LSM_TRY(run_1d(s, k, (size_t)s->pn, err));
  k = s->k[K_PCL_APPLY];
  ARG(k, 0, s->phi);
  ARG(k, 1, s->nx);
  ARG(k, 2, s->ny);
  ARG(k, 3, s->stride);
  ARG(k, 4, s->plus);
  ARG(k, 5, s->minus);
  ARG(k, 6, s->counters);
  LSM_TRY(run_2d(s, k, s->global, s->local, err));
  if (s->radius_adjust) {
    k = s->k[K_PCL_RADIUS];
    LSM_TRY(particle_args(s, k, err));
    ARG(k, 10, s->rmin);
    ARG(k, 11, s->rmax);
    LSM_TRY(run_1d(s, k, (size_t)s->pn, err));
  }
  cl_int c[PCL_N_COUNT];
  CL_TRY(s->c->name, "clEnqueueReadBuffer",
         clEnqueueReadBuffer(s->queue, s->counters, CL_TRUE, 0, sizeof c, c, 0, NULL, NULL));
  counts->removed = c[PCL_N_REMOVED];
  counts->stray = c[PCL_N_STRAY];
  counts->escaped = c[PCL_N_ESCAPED];
  counts->corrected = c[PCL_N_CORRECTED];
  counts->live = c[PCL_N_LIVE];
  return LSM_OK;
}

/* ---- steps -------------------------------------------------------------------------------- */

/* out = c0 u0 + c1 (in - dt Hhat(in)), after filling in's ghosts; a loaded
 * particle set takes the same stage first (it reads `in` only).  first: the
 * step's first stage. */
static lsm_status stage(cl_state *s, lsm_scheme scheme, cl_mem out, cl_mem u0, cl_mem in,
                        float c0, float c1, float dt, int first, lsm_err *err) {
  LSM_TRY(fill_ghosts(s, in, err));
  if (s->pn > 0) LSM_TRY(pcl_stage(s, in, c0, c1, dt, first, err));
  const float inv_dx = 1.0f / s->dx, inv_dy = 1.0f / s->dy;
  cl_kernel k = s->k[scheme == LSM_SCHEME_ROEFIX  ? K_ROEFIX
                     : scheme == LSM_SCHEME_WENO5 ? K_WENO5
                                                  : K_UPWIND];
  ARG(k, 0, out);
  ARG(k, 1, u0);
  ARG(k, 2, in);
  ARG(k, 3, s->target);
  ARG(k, 4, s->nx);
  ARG(k, 5, s->ny);
  ARG(k, 6, s->stride);
  ARG(k, 7, inv_dx);
  ARG(k, 8, inv_dy);
  ARG(k, 9, c0);
  ARG(k, 10, c1);
  ARG(k, 11, dt);
  return run_2d(s, k, s->global, s->local, err);
}

static void swap_mem(cl_mem *a, cl_mem *b) {
  cl_mem t = *a;
  *a = *b;
  *b = t;
}

static lsm_status cl_step(void *vs, lsm_scheme scheme, lsm_time time, float dt,
                          const lsm_stage_hook *hook, lsm_err *err) {
  cl_state *s = vs;
  if (hook)
    return lsm_fail(err, LSM_ERR_UNSUPPORTED, NULL,
                    "OpenCL: %s: no stage hooks (phi stays on the device); particles run "
                    "through pls_load and pls_correct",
                    s->c->name);
  switch (time) {
  case LSM_TIME_RK2:
    /* phi1 = phi - dt L(phi);  phi = 1/2 phi + 1/2 (phi1 - dt L(phi1)) */
    LSM_TRY(stage(s, scheme, s->s1, s->phi, s->phi, 0.0f, 1.0f, dt, 1, err));
    LSM_TRY(stage(s, scheme, s->phi, s->phi, s->s1, 0.5f, 0.5f, dt, 0, err));
    break;
  case LSM_TIME_RK3:
    /* phi1 = phi - dt L(phi); phi2 = 3/4 phi + 1/4 (phi1 - dt L(phi1));
     * phi = 1/3 phi + 2/3 (phi2 - dt L(phi2)) */
    LSM_TRY(stage(s, scheme, s->s1, s->phi, s->phi, 0.0f, 1.0f, dt, 1, err));
    LSM_TRY(stage(s, scheme, s->s2, s->phi, s->s1, 0.75f, 0.25f, dt, 0, err));
    LSM_TRY(stage(s, scheme, s->phi, s->phi, s->s2, 1.0f / 3.0f, 2.0f / 3.0f, dt, 0, err));
    break;
  default:
    /* phi = phi - dt L(phi), into the scratch grid, which then becomes phi. */
    LSM_TRY(stage(s, scheme, s->s1, s->phi, s->phi, 0.0f, 1.0f, dt, 1, err));
    swap_mem(&s->phi, &s->s1);
    break;
  }
  CL_TRY(s->c->name, "clFlush", clFlush(s->queue));
  return LSM_OK;
}

static lsm_status cl_reinit(void *vs, int iterations, lsm_err *err) {
  cl_state *s = vs;
  if (iterations <= 0) return LSM_OK;
  if (!s->phi0) LSM_TRY(new_buffer(s, s->bytes, &s->phi0, err));
  const float inv_dx = 1.0f / s->dx, inv_dy = 1.0f / s->dy;
  const float h = s->dx < s->dy ? s->dx : s->dy;
  const float dtau = 0.5f * h;
  LSM_TRY(fill_ghosts(s, s->phi, err));
  CL_TRY(s->c->name, "clEnqueueCopyBuffer",
         clEnqueueCopyBuffer(s->queue, s->phi, s->phi0, 0, 0, s->bytes, 0, NULL, NULL));
  cl_kernel k = s->k[K_REINIT];
  for (int it = 0; it < iterations; ++it) {
    LSM_TRY(fill_ghosts(s, s->phi, err));
    ARG(k, 0, s->s1);
    ARG(k, 1, s->phi);
    ARG(k, 2, s->phi0);
    ARG(k, 3, s->nx);
    ARG(k, 4, s->ny);
    ARG(k, 5, s->stride);
    ARG(k, 6, inv_dx);
    ARG(k, 7, inv_dy);
    ARG(k, 8, h);
    ARG(k, 9, dtau);
    LSM_TRY(run_2d(s, k, s->global, s->local, err));
    swap_mem(&s->phi, &s->s1);
  }
  LSM_TRY(fill_ghosts(s, s->phi, err));
  CL_TRY(s->c->name, "clFlush", clFlush(s->queue));
  return LSM_OK;
}

static lsm_status check_size(const cl_state *s, const lsm_grid *g, lsm_err *err) {
  if (g->nx != s->nx || g->ny != s->ny || g->stride != s->stride || g->ghost != LSM_GHOST)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "OpenCL: host grid %dx%d differs from the device's %dx%d",
                    g->nx, g->ny, s->nx, s->ny);
  return LSM_OK;
}

static lsm_status cl_download(void *vs, lsm_grid *phi, lsm_err *err) {
  cl_state *s = vs;
  LSM_TRY(check_size(s, phi, err));
  LSM_TRY(fill_ghosts(s, s->phi, err));
  CL_TRY(s->c->name, "clEnqueueReadBuffer",
         clEnqueueReadBuffer(s->queue, s->phi, CL_TRUE, 0, s->bytes, phi->base, 0, NULL, NULL));
  return LSM_OK;
}

static lsm_status cl_upload(void *vs, const lsm_grid *phi, lsm_err *err) {
  cl_state *s = vs;
  LSM_TRY(check_size(s, phi, err));
  return write_grid(s, s->phi, phi, err);
}

static lsm_grid *cl_host_phi(void *vs) {
  (void)vs;
  return NULL;
}

static const lsm_backend_ops cl_ops = {.name = "opencl",
                                       .create = cl_create,
                                       .cfl_dt = cl_cfl_dt,
                                       .step = cl_step,
                                       .reinit = cl_reinit,
                                       .residual = cl_residual,
                                       .download = cl_download,
                                       .upload = cl_upload,
                                       .host_phi = cl_host_phi,
                                       .destroy = cl_destroy,
                                       .pls_load = cl_pls_load,
                                       .pls_correct = cl_pls_correct};
