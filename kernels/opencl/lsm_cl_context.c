/* The OpenCL backend's run-wide context: errors, devices, the program.
 *
 * Enumerates the platforms' devices (the indices of `lsmorph devices` and --device), opens
 * one with its OpenCL context, and builds the program from kernels/morph.cl with the kernels/
 * headers spliced in (embedded at build time: $(BUILD)/gen/lsm_kernels.h) without contraction
 * or relaxed maths (and with correctly rounded divide and sqrt where the device offers it), so
 * results track the C path.  The program is built from source at every open: the OpenCL
 * implementations' own caches (PoCL's, NVIDIA's) serve repeated builds (kernels/README.md). */
#include "kernels/opencl/lsm_cl_context.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "solver/base/lsm_clock.h"
#include "solver/base/lsm_grid.h" /* LSM_GHOST */
#include "solver/pde/lsm_band.h"  /* LSM_BAND_SEGMENT */
#include "lsm_kernels.h" /* lsm_kernel_source[]: morph.cl + the headers, NUL-terminated */

/* ---- errors ------------------------------------------------------------------------ */

const char *lsm_cl_error_name(cl_int code) {
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
lsm_status lsm_cl_status_of(cl_int code) {
  return code == CL_MEM_OBJECT_ALLOCATION_FAILURE || code == CL_OUT_OF_RESOURCES ||
                 code == CL_OUT_OF_HOST_MEMORY
             ? LSM_ERR_NOMEM
             : LSM_ERR_INTERNAL;
}

/* "OpenCL: <device>: <call> failed: <error name>" */
lsm_status lsm_cl_fail(lsm_err *err, const char *device, const char *call, cl_int code) {
  return lsm_fail(err, lsm_cl_status_of(code), NULL, "OpenCL: %s: %s failed: %s (%d)", device, call,
                  lsm_cl_error_name(code), (int)code);
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
  if (e != CL_SUCCESS) return lsm_cl_fail(err, "no device", "clGetPlatformIDs", e);
  cl_platform_id *plats = calloc(nplat, sizeof *plats);
  if (!plats) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: cannot allocate the platform list");
  e = clGetPlatformIDs(nplat, plats, NULL);
  if (e != CL_SUCCESS) {
    free(plats);
    return lsm_cl_fail(err, "no device", "clGetPlatformIDs", e);
  }
  cl_dev_ref *refs = NULL;
  cl_uint n = 0;
  lsm_status st = LSM_OK;
  for (cl_uint p = 0; p < nplat && st == LSM_OK; ++p) {
    cl_uint nd = 0;
    e = clGetDeviceIDs(plats[p], CL_DEVICE_TYPE_ALL, 0, NULL, &nd);
    if (e == CL_DEVICE_NOT_FOUND) continue;
    if (e != CL_SUCCESS) { /* a platform skipped would renumber the devices after it */
      st = lsm_cl_fail(err, "no device", "clGetDeviceIDs", e);
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
      st = lsm_cl_fail(err, "no device", "clGetDeviceIDs", e);
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

lsm_status lsm_cl_list_devices(FILE *f, lsm_err *err) {
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

void lsm_cl_context_close(void *ctx) {
  lsm_cl_ctx *c = ctx;
  if (!c) return;
  if (c->program) clReleaseProgram(c->program);
  if (c->context) clReleaseContext(c->context);
  free(c);
}

/* ---- building the program ----------------------------------------------------------------- */

/* clBuildProgram; on failure the message carries the (truncated) build log. */
static lsm_status build_program(lsm_cl_ctx *c, cl_program prog, const char *options, lsm_err *err) {
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
  lsm_status st = lsm_fail(err, e == CL_BUILD_PROGRAM_FAILURE ? LSM_ERR_INTERNAL : lsm_cl_status_of(e),
                           NULL, "OpenCL: %s: clBuildProgram failed: %s (%d); build log%s:\n%.*s",
                           c->name, lsm_cl_error_name(e), (int)e,
                           log && strlen(log) > keep ? " (truncated)" : "", (int)keep,
                           log && log[0] ? log : "(empty)");
  free(log);
  return st;
}

static lsm_status program_from_source(lsm_cl_ctx *c, const char *options, lsm_err *err) {
  const char *src = (const char *)lsm_kernel_source;
  const size_t len = sizeof lsm_kernel_source - 1;
  cl_int e;
  c->program = clCreateProgramWithSource(c->context, 1, &src, &len, &e);
  if (e != CL_SUCCESS) {
    c->program = NULL;
    return lsm_cl_fail(err, c->name, "clCreateProgramWithSource", e);
  }
  return build_program(c, c->program, options, err);
}

const char *const lsm_cl_kernel_names[LSM_CL_K_COUNT] = {
    "lsm_fill_ghosts",  "lsm_stage_upwind", "lsm_stage_roefix", "lsm_stage_weno5", "lsm_cfl_partial",
    "lsm_residual_partial", "lsm_reinit_step", "lsm_pcl_velocity", "lsm_pcl_advect",
    "lsm_pcl_detect",   "lsm_pcl_apply",    "lsm_pcl_adjust_radius", "lsm_band_stage_upwind",
    "lsm_band_stage_roefix", "lsm_band_stage_weno5", "lsm_band_cfl_partial",
    "lsm_band_residual_partial", "lsm_band_reinit_step", "lsm_band_fill_rim", "lsm_band_write"};

/* Lowers c->max_group to the smallest CL_KERNEL_WORK_GROUP_SIZE of the
 * kernels: a GPU can take fewer work-items per group for a kernel that uses
 * many registers than CL_DEVICE_MAX_WORK_GROUP_SIZE says, and a launch past
 * it fails with CL_INVALID_WORK_GROUP_SIZE. */
static lsm_status kernel_group_limit(lsm_cl_ctx *c, lsm_err *err) {
  for (int k = 0; k < LSM_CL_K_COUNT; ++k) {
    cl_int e;
    cl_kernel kernel = clCreateKernel(c->program, lsm_cl_kernel_names[k], &e);
    char call[64];
    snprintf(call, sizeof call, "clCreateKernel(%s)", lsm_cl_kernel_names[k]);
    if (e != CL_SUCCESS) return lsm_cl_fail(err, c->name, call, e);
    size_t limit = 0;
    e = clGetKernelWorkGroupInfo(kernel, c->device, CL_KERNEL_WORK_GROUP_SIZE, sizeof limit, &limit,
                                 NULL);
    clReleaseKernel(kernel);
    if (e != CL_SUCCESS) return lsm_cl_fail(err, c->name, "clGetKernelWorkGroupInfo", e);
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
static void pick_local(lsm_cl_ctx *c) {
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

/* ---- opening ------------------------------------------------------------------------------ */

lsm_status lsm_cl_context_open(int device, void **ctx, lsm_err *err) {
  *ctx = NULL;
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
  lsm_cl_ctx *c = calloc(1, sizeof *c);
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
    st = lsm_cl_fail(err, c->name, "clGetDeviceInfo", e);
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
      st = lsm_cl_fail(err, c->name, "clCreateContext", e);
    }
  }
  if (st == LSM_OK) {
    c->cpu = (type & CL_DEVICE_TYPE_CPU) != 0;
    char options[256];
    snprintf(options, sizeof options, "-cl-std=CL1.2 -DLSM_GHOST=%d -DLSM_BAND_SEGMENT=%d%s%s",
             LSM_GHOST, LSM_BAND_SEGMENT,
             (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) ? " -cl-fp32-correctly-rounded-divide-sqrt"
                                                        : "",
             c->cpu ? " -DLSM_CL_SERIAL_COMBINE" : "");
    const double t0 = lsm_clock_seconds();
    st = program_from_source(c, options, err);
    c->build_seconds = lsm_clock_seconds() - t0;
  }
  if (st == LSM_OK) st = kernel_group_limit(c, err);
  if (st == LSM_OK) pick_local(c);
  if (st != LSM_OK) {
    lsm_cl_context_close(c);
    return st;
  }
  *ctx = c;
  return LSM_OK;
}

