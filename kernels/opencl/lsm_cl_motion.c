/* lsm_cl_motion: the registration's levels on an OpenCL device (see the header). */
#include "kernels/opencl/lsm_cl_motion.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "kernels/opencl/lsm_cl_grid.h" /* lsm_cl_arg */

enum { MK_ROW_MAX, MK_SCALE, MK_SQUARE, MK_WARP, MK_DEMONS, MK_BLUR, MK_ADD, MK_COUNT };
static const char *const kernel_names[MK_COUNT] = {
    "lsm_motion_row_max", "lsm_motion_scale", "lsm_motion_square_k", "lsm_motion_warp_k",
    "lsm_motion_demons_k", "lsm_motion_blur_k", "lsm_motion_add"};

/* The level's buffers: the planes of lsm_motion.c's host loop, r^2 and the active flags
 * (R2C, two planes), the rows' largest norms and the two Gaussians' taps. */
enum { B_A, B_B, B_WX, B_WY, B_UX, B_UY, B_TX, B_TY, B_PX, B_PY, B_MX, B_MY, B_SX, B_SY,
       B_WA, B_WB, B_R2C, B_ROWS, B_KU, B_KW, B_COUNT };
#define TAPS_MAX (2 * 64 + 1) /* lsm_motion.c's Gaussians: radius at most 64 */

typedef struct cl_level {
  lsm_cl_ctx *c;
  cl_command_queue queue;
  cl_kernel k[MK_COUNT];
  cl_mem m[B_COUNT];
  float *r2c, *rows; /* host copies of R2C and ROWS */
  cl_int nx, ny, n;
  size_t global[2], local[2], global1, local1;
  int shaped; /* local[] given (else the implementation picks) */
} cl_level;

static size_t round_up(size_t n, size_t m) { return (n + m - 1) / m * m; }

static void level_release(cl_level *L) {
  if (L->queue) clFinish(L->queue);
  for (int k = 0; k < MK_COUNT; ++k)
    if (L->k[k]) clReleaseKernel(L->k[k]);
  for (int b = 0; b < B_COUNT; ++b)
    if (L->m[b]) clReleaseMemObject(L->m[b]);
  if (L->queue) clReleaseCommandQueue(L->queue);
  free(L->r2c);
  free(L->rows);
}

static lsm_status args(cl_level *L, cl_kernel k, const lsm_cl_arg *a, int n, lsm_err *err) {
  for (int q = 0; q < n; ++q)
    LSM_CL_TRY(L->c->name, "clSetKernelArg", clSetKernelArg(k, (cl_uint)q, a[q].size, a[q].value));
  return LSM_OK;
}

/* Runs k over the nodes (2D) or, with dims 1, over n items. */
static lsm_status launch(cl_level *L, cl_kernel k, int dims, size_t n, lsm_err *err) {
  const size_t global1 = round_up(n, L->local1);
  const cl_int e = dims == 2
                       ? clEnqueueNDRangeKernel(L->queue, k, 2, NULL, L->global,
                                                L->shaped ? L->local : NULL, 0, NULL, NULL)
                       : clEnqueueNDRangeKernel(L->queue, k, 1, NULL, &global1,
                                                L->shaped ? &L->local1 : NULL, 0, NULL, NULL);
  if (e != CL_SUCCESS) return lsm_cl_fail(err, L->c->name, "clEnqueueNDRangeKernel", e);
  return LSM_OK;
}

static lsm_status write_buf(cl_level *L, cl_mem b, const void *host, size_t bytes, lsm_err *err) {
  LSM_CL_TRY(L->c->name, "clEnqueueWriteBuffer",
             clEnqueueWriteBuffer(L->queue, b, CL_TRUE, 0, bytes, host, 0, NULL, NULL));
  return LSM_OK;
}

static lsm_status read_buf(cl_level *L, cl_mem b, void *host, size_t bytes, lsm_err *err) {
  LSM_CL_TRY(L->c->name, "clEnqueueReadBuffer",
             clEnqueueReadBuffer(L->queue, b, CL_TRUE, 0, bytes, host, 0, NULL, NULL));
  return LSM_OK;
}

/* Queue, kernels, buffers and host copies for a level of nx x ny nodes. */
static lsm_status level_open(cl_level *L, lsm_cl_ctx *c, int nx, int ny, lsm_err *err) {
  memset(L, 0, sizeof *L);
  L->c = c;
  const size_t n = (size_t)nx * (size_t)ny;
  if (nx < 1 || ny < 1 || n > (size_t)INT32_MAX / 2)
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "OpenCL: %s: a registration grid of %dx%d nodes is "
                    "too large", c->name, nx, ny);
  L->nx = nx;
  L->ny = ny;
  L->n = (cl_int)n;
  L->shaped = c->max_group >= 64 && c->max_items[0] >= 16 && c->max_items[1] >= 4;
  cl_int e;
  L->queue = clCreateCommandQueue(c->context, c->device, 0, &e);
  if (e != CL_SUCCESS) {
    L->queue = NULL;
    return lsm_cl_fail(err, c->name, "clCreateCommandQueue", e);
  }
  for (int k = 0; k < MK_COUNT; ++k) {
    L->k[k] = clCreateKernel(c->program, kernel_names[k], &e);
    if (e != CL_SUCCESS) {
      L->k[k] = NULL;
      char call[64];
      snprintf(call, sizeof call, "clCreateKernel(%s)", kernel_names[k]);
      return lsm_cl_fail(err, c->name, call, e);
    }
    size_t limit = 0; /* a kernel may take fewer work-items per group than the device */
    LSM_CL_TRY(c->name, "clGetKernelWorkGroupInfo",
               clGetKernelWorkGroupInfo(L->k[k], c->device, CL_KERNEL_WORK_GROUP_SIZE,
                                        sizeof limit, &limit, NULL));
    if (limit > 0 && limit < 64) L->shaped = 0;
  }
  /* groups of 16 x 4 (64 in 1D), the NDRange rounded up to them; else the runtime's */
  L->local[0] = 16;
  L->local[1] = 4;
  L->global[0] = L->shaped ? round_up((size_t)nx, 16) : (size_t)nx;
  L->global[1] = L->shaped ? round_up((size_t)ny, 4) : (size_t)ny;
  L->local1 = L->shaped ? 64 : 1;
  for (int b = 0; b < B_COUNT; ++b) {
    const size_t floats = b == B_R2C ? 2 * n : b == B_ROWS ? (size_t)ny
                          : b == B_KU || b == B_KW ? TAPS_MAX : n;
    L->m[b] = clCreateBuffer(c->context, CL_MEM_READ_WRITE, floats * sizeof(float), NULL, &e);
    if (e != CL_SUCCESS) {
      L->m[b] = NULL;
      if (e == CL_MEM_OBJECT_ALLOCATION_FAILURE || e == CL_OUT_OF_RESOURCES ||
          e == CL_OUT_OF_HOST_MEMORY || e == CL_INVALID_BUFFER_SIZE)
        return lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: %s: out of device memory for the "
                        "registration (%dx%d nodes): clCreateBuffer failed: %s (%d)", c->name,
                        nx, ny, lsm_cl_error_name(e), (int)e);
      return lsm_cl_fail(err, c->name, "clCreateBuffer", e);
    }
  }
  L->r2c = lsm_alloc(n, 2 * sizeof(float), err, "registration mismatch");
  L->rows = lsm_alloc((size_t)ny, sizeof(float), err, "registration norms");
  if (!L->r2c || !L->rows) return err ? err->status : LSM_ERR_NOMEM;
  return LSM_OK;
}

/* exp(t w) into buffers (dx, dy) by scaling and squaring (lsm_motion.c's exp_planes): the
 * squarings from the rows' largest norms, then d = scale w and K squarings, ping-ponging
 * with (SX, SY); the result's buffers are renamed into (dx, dy), never copied. */
static lsm_status device_exp(cl_level *L, float t, int dx, int dy, lsm_err *err) {
  const lsm_cl_arg rm[] = {LSM_CL_ARG(L->m[B_WX]), LSM_CL_ARG(L->m[B_WY]), LSM_CL_ARG(L->nx),
                           LSM_CL_ARG(L->ny), LSM_CL_ARG(t), LSM_CL_ARG(L->m[B_ROWS])};
  LSM_TRY(args(L, L->k[MK_ROW_MAX], rm, 6, err));
  LSM_TRY(launch(L, L->k[MK_ROW_MAX], 1, (size_t)L->ny, err));
  LSM_TRY(read_buf(L, L->m[B_ROWS], L->rows, (size_t)L->ny * sizeof(float), err));
  float most = 0.0f;
  for (int j = 0; j < L->ny; ++j)
    if (L->rows[j] > most) most = L->rows[j];
  float scale;
  const int K = lsm_motion_squarings(most, t, &scale);
  const lsm_cl_arg sc[] = {LSM_CL_ARG(L->m[dx]), LSM_CL_ARG(L->m[dy]), LSM_CL_ARG(L->m[B_WX]),
                           LSM_CL_ARG(L->m[B_WY]), LSM_CL_ARG(L->n), LSM_CL_ARG(scale)};
  LSM_TRY(args(L, L->k[MK_SCALE], sc, 6, err));
  LSM_TRY(launch(L, L->k[MK_SCALE], 1, (size_t)L->n, err));
  int a[2] = {dx, dy}, b[2] = {B_SX, B_SY};
  for (int q = 0; q < K; ++q) {
    const lsm_cl_arg sq[] = {LSM_CL_ARG(L->m[b[0]]), LSM_CL_ARG(L->m[b[1]]),
                             LSM_CL_ARG(L->m[a[0]]), LSM_CL_ARG(L->m[a[1]]), LSM_CL_ARG(L->nx),
                             LSM_CL_ARG(L->ny)};
    LSM_TRY(args(L, L->k[MK_SQUARE], sq, 6, err));
    LSM_TRY(launch(L, L->k[MK_SQUARE], 2, 0, err));
    for (int c = 0; c < 2; ++c) {
      const int t2 = a[c];
      a[c] = b[c];
      b[c] = t2;
    }
  }
  if (a[0] != dx) /* the result is in the scratch buffers: exchange the names */
    for (int c = 0; c < 2; ++c) {
      cl_mem m = L->m[a[c]];
      L->m[a[c]] = L->m[b[c]];
      L->m[b[c]] = m;
    }
  return LSM_OK;
}

/* Both components of a field smoothed in place: along x into (TX, TY), back along y. */
static lsm_status device_blur(cl_level *L, int fx, int fy, int kern, int radius, lsm_err *err) {
  if (radius == 0) return LSM_OK;
  for (int axis = 0; axis < 2; ++axis) {
    const int ox = axis == 0 ? B_TX : fx, oy = axis == 0 ? B_TY : fy;
    const int ix = axis == 0 ? fx : B_TX, iy = axis == 0 ? fy : B_TY;
    const cl_int ax = axis, rad = radius;
    const lsm_cl_arg bl[] = {LSM_CL_ARG(L->m[ox]), LSM_CL_ARG(L->m[oy]), LSM_CL_ARG(L->m[ix]),
                             LSM_CL_ARG(L->m[iy]), LSM_CL_ARG(L->nx),    LSM_CL_ARG(L->ny),
                             LSM_CL_ARG(ax),       LSM_CL_ARG(L->m[kern]), LSM_CL_ARG(rad)};
    LSM_TRY(args(L, L->k[MK_BLUR], bl, 9, err));
    LSM_TRY(launch(L, L->k[MK_BLUR], 2, 0, err));
  }
  return LSM_OK;
}

/* The iterations of lsm_motion.c's run_level, kernel for loop. */
static lsm_status level_run(cl_level *L, const lsm_motion_level *lv, int *taken, lsm_err *err) {
  const size_t plane = (size_t)L->n * sizeof(float);
  LSM_TRY(write_buf(L, L->m[B_A], lv->a, plane, err));
  LSM_TRY(write_buf(L, L->m[B_B], lv->b, plane, err));
  LSM_TRY(write_buf(L, L->m[B_WX], lv->wx, plane, err));
  LSM_TRY(write_buf(L, L->m[B_WY], lv->wy, plane, err));
  LSM_TRY(write_buf(L, L->m[B_KU], lv->ku, (size_t)(2 * lv->ru + 1) * sizeof(float), err));
  LSM_TRY(write_buf(L, L->m[B_KW], lv->kw, (size_t)(2 * lv->rw + 1) * sizeof(float), err));
  double history[LSM_MOTION_ITERATIONS_MAX];
  const int most = lv->iterations < LSM_MOTION_ITERATIONS_MAX ? lv->iterations
                                                               : LSM_MOTION_ITERATIONS_MAX;
  int it = 0;
  for (; it < most; ++it) {
    LSM_TRY(device_exp(L, 0.5f, B_PX, B_PY, err));
    LSM_TRY(device_exp(L, -0.5f, B_MX, B_MY, err));
    const lsm_cl_arg wp[] = {LSM_CL_ARG(L->m[B_WA]), LSM_CL_ARG(L->m[B_WB]),
                             LSM_CL_ARG(L->m[B_A]),  LSM_CL_ARG(L->m[B_B]),
                             LSM_CL_ARG(L->m[B_MX]), LSM_CL_ARG(L->m[B_MY]),
                             LSM_CL_ARG(L->m[B_PX]), LSM_CL_ARG(L->m[B_PY]),
                             LSM_CL_ARG(L->nx),      LSM_CL_ARG(L->ny)};
    LSM_TRY(args(L, L->k[MK_WARP], wp, 10, err));
    LSM_TRY(launch(L, L->k[MK_WARP], 2, 0, err));
    const lsm_cl_arg dm[] = {LSM_CL_ARG(L->m[B_UX]), LSM_CL_ARG(L->m[B_UY]),
                             LSM_CL_ARG(L->m[B_R2C]), LSM_CL_ARG(L->m[B_WA]),
                             LSM_CL_ARG(L->m[B_WB]), LSM_CL_ARG(L->nx),
                             LSM_CL_ARG(L->ny),      LSM_CL_ARG(lv->hx),
                             LSM_CL_ARG(lv->hy),     LSM_CL_ARG(lv->clip)};
    LSM_TRY(args(L, L->k[MK_DEMONS], dm, 10, err));
    LSM_TRY(launch(L, L->k[MK_DEMONS], 2, 0, err));
    LSM_TRY(read_buf(L, L->m[B_R2C], L->r2c, 2 * plane, err));
    double sum, count;
    lsm_motion_mismatch(L->r2c, L->r2c + L->n, L->nx, L->ny, &sum, &count);
    if (lsm_motion_level_stops(lv, history, it, sum, count)) break;
    LSM_TRY(device_blur(L, B_UX, B_UY, B_KU, lv->ru, err));
    const lsm_cl_arg ad[] = {LSM_CL_ARG(L->m[B_WX]), LSM_CL_ARG(L->m[B_WY]),
                             LSM_CL_ARG(L->m[B_UX]), LSM_CL_ARG(L->m[B_UY]), LSM_CL_ARG(L->n)};
    LSM_TRY(args(L, L->k[MK_ADD], ad, 5, err));
    LSM_TRY(launch(L, L->k[MK_ADD], 1, (size_t)L->n, err));
    LSM_TRY(device_blur(L, B_WX, B_WY, B_KW, lv->rw, err));
  }
  LSM_TRY(read_buf(L, L->m[B_WX], lv->wx, plane, err));
  LSM_TRY(read_buf(L, L->m[B_WY], lv->wy, plane, err));
  *taken = it;
  return LSM_OK;
}

lsm_status lsm_cl_motion_level(void *ctx, const lsm_motion_level *lv, int *taken, lsm_err *err) {
  *taken = 0;
  if (lv->ru < 0 || lv->rw < 0 || 2 * lv->ru + 1 > TAPS_MAX || 2 * lv->rw + 1 > TAPS_MAX)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "OpenCL: a registration smoothing wider than "
                    "%d taps", TAPS_MAX);
  cl_level L;
  lsm_status st = level_open(&L, ctx, lv->nx, lv->ny, err);
  if (st == LSM_OK) st = level_run(&L, lv, taken, err);
  level_release(&L);
  return st;
}

void lsm_cl_motion_device(lsm_cl_ctx *c, lsm_motion_device *dev) {
  dev->ctx = c;
  dev->run_level = lsm_cl_motion_level;
}
