#include "kernels/opencl/lsm_cl_grid.h"

#include "kernels/lsm_cell.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static size_t round_up(size_t n, size_t m) { return m ? (n + m - 1) / m * m : n; }

lsm_status lsm_cl_buffer(lsm_cl_grid *g, size_t bytes, cl_mem *out, lsm_err *err) {
  cl_int e;
  *out = clCreateBuffer(g->c->context, CL_MEM_READ_WRITE, bytes, NULL, &e);
  if (e == CL_SUCCESS) return LSM_OK;
  *out = NULL;
  if (e == CL_MEM_OBJECT_ALLOCATION_FAILURE || e == CL_OUT_OF_RESOURCES ||
      e == CL_OUT_OF_HOST_MEMORY || e == CL_INVALID_BUFFER_SIZE)
    return lsm_fail(err, LSM_ERR_NOMEM, NULL,
                    "OpenCL: %s: out of device memory for a %dx%d grid (a buffer of %.1f MiB): "
                    "clCreateBuffer failed: %s (%d)",
                    g->c->name, g->nx, g->ny, (double)bytes / (1024.0 * 1024.0),
                    lsm_cl_error_name(e), (int)e);
  return lsm_cl_fail(err, g->c->name, "clCreateBuffer", e);
}

lsm_status lsm_cl_args(lsm_cl_grid *g, cl_kernel k, int first, const lsm_cl_arg *args, int n,
                       lsm_err *err) {
  for (int a = 0; a < n; ++a)
    LSM_CL_TRY(g->c->name, "clSetKernelArg",
               clSetKernelArg(k, (cl_uint)(first + a), args[a].size, args[a].value));
  return LSM_OK;
}

static lsm_status run_2d(lsm_cl_grid *g, cl_kernel k, const size_t *global, const size_t *local,
                         lsm_err *err) {
  LSM_CL_TRY(g->c->name, "clEnqueueNDRangeKernel",
             clEnqueueNDRangeKernel(g->queue, k, 2, NULL, global, local, 0, NULL, NULL));
  return LSM_OK;
}

lsm_status lsm_cl_run_cells(lsm_cl_grid *g, cl_kernel k, lsm_err *err) {
  return run_2d(g, k, g->global, g->local, err);
}

lsm_status lsm_cl_run_1d(lsm_cl_grid *g, cl_kernel k, size_t n, size_t local, lsm_err *err) {
  const size_t global = round_up(n, local);
  LSM_CL_TRY(g->c->name, "clEnqueueNDRangeKernel",
             clEnqueueNDRangeKernel(g->queue, k, 1, NULL, &global, &local, 0, NULL, NULL));
  return LSM_OK;
}

/* Blocking write of a whole host grid (ghosts included) into a buffer. */
static lsm_status write_grid(lsm_cl_grid *g, cl_mem buf, const lsm_grid *h, lsm_err *err) {
  LSM_CL_TRY(g->c->name, "clEnqueueWriteBuffer",
             clEnqueueWriteBuffer(g->queue, buf, CL_TRUE, 0, g->bytes, h->base, 0, NULL, NULL));
  return LSM_OK;
}

static lsm_status read_grid(lsm_cl_grid *g, cl_mem buf, lsm_grid *h, lsm_err *err) {
  LSM_CL_TRY(g->c->name, "clEnqueueReadBuffer",
             clEnqueueReadBuffer(g->queue, buf, CL_TRUE, 0, g->bytes, h->base, 0, NULL, NULL));
  return LSM_OK;
}

/* Zero-gradient ghost fill of a buffer (lsm_grid_fill_ghosts): one work-item per ghost cell. */
static lsm_status fill_ghosts(lsm_cl_grid *g, cl_mem buf, lsm_err *err) {
  cl_kernel k = g->k[LSM_CL_K_GHOSTS];
  const lsm_cl_arg args[] = {LSM_CL_ARG(buf), LSM_CL_ARG(g->nx), LSM_CL_ARG(g->ny),
                             LSM_CL_ARG(g->stride)};
  LSM_TRY(lsm_cl_args(g, k, 0, args, 4, err));
  const size_t local = 64;
  LSM_CL_TRY(g->c->name, "clEnqueueNDRangeKernel",
             clEnqueueNDRangeKernel(g->queue, k, 1, NULL, &g->ghost_global,
                                    local <= g->c->max_group ? &local : NULL, 0, NULL, NULL));
  return LSM_OK;
}

void lsm_cl_grid_destroy(lsm_cl_grid *g) {
  if (!g) return;
  if (g->queue) clFinish(g->queue);
  lsm_cl_band_destroy(g);
  for (int k = 0; k < LSM_CL_K_COUNT; ++k)
    if (g->k[k]) clReleaseKernel(g->k[k]);
  for (int f = 0; f < LSM_FIELD_COUNT; ++f)
    if (g->field[f]) clReleaseMemObject(g->field[f]);
  if (g->target) clReleaseMemObject(g->target);
  if (g->partial) clReleaseMemObject(g->partial);
  if (g->queue) clReleaseCommandQueue(g->queue);
  lsm_grid_destroy(&g->host);
  lsm_grid_destroy(&g->host_target);
  free(g->partial_host);
  free(g);
}

/* Work-group shapes.  Cell kernels: row segments of LX work-items, LX a power of two from 8
 * up to local_max, no wider than the row needs (PoCL's work-item loops vectorise along
 * rows: taller groups are slower).  Reductions: whole groups across the width
 * (runs of red_run cells per work-item); down the height at most enough groups for ~1024
 * partial results (work-items then loop over rows). */
static void shapes(lsm_cl_grid *g) {
  const lsm_cl_ctx *c = g->c;
  size_t lx = 8;
  while (lx < c->local_max && lx < (size_t)g->nx) lx *= 2;
  while (lx > 1 && lx > c->local_max) lx /= 2;
  g->local[0] = lx;
  g->local[1] = 1;
  g->global[0] = round_up((size_t)g->nx, lx);
  g->global[1] = (size_t)g->ny;
  const size_t runs = ((size_t)g->nx + (size_t)c->red_run - 1) / (size_t)c->red_run;
  g->red_global[0] = round_up(runs, c->red_local[0]);
  const size_t groups_x = g->red_global[0] / c->red_local[0];
  size_t groups_y = ((size_t)g->ny + c->red_local[1] - 1) / c->red_local[1];
  size_t cap_y = 1024 / groups_x;
  if (cap_y < 1) cap_y = 1;
  if (groups_y > cap_y) groups_y = cap_y;
  g->red_global[1] = groups_y * c->red_local[1];
  g->npartial = groups_x * groups_y;
  g->ghost_global = round_up(2u * LSM_GHOST * ((size_t)g->ny + (size_t)g->stride), 64);
}

lsm_status lsm_cl_grid_create(lsm_cl_ctx *c, const lsm_grid *src, const lsm_grid *tgt,
                              int threads, lsm_cl_grid **out, lsm_err *err) {
  *out = NULL;
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
  lsm_cl_grid *g = calloc(1, sizeof *g);
  if (!g) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: cannot allocate the backend state");
  g->c = c;
  g->threads = threads;
  g->nx = src->nx;
  g->ny = src->ny;
  g->stride = (cl_int)src->stride;
  g->dx = src->dx;
  g->dy = src->dy;
  g->bytes = bytes;
  shapes(g);

  lsm_status st = LSM_OK;
  cl_int e;
  g->queue = clCreateCommandQueue(c->context, c->device, 0, &e);
  if (e != CL_SUCCESS) {
    g->queue = NULL;
    st = lsm_cl_fail(err, c->name, "clCreateCommandQueue", e);
  }
  for (int k = 0; k < LSM_CL_K_COUNT && st == LSM_OK; ++k) {
    g->k[k] = clCreateKernel(c->program, lsm_cl_kernel_names[k], &e);
    if (e != CL_SUCCESS) {
      g->k[k] = NULL;
      char call[64];
      snprintf(call, sizeof call, "clCreateKernel(%s)", lsm_cl_kernel_names[k]);
      st = lsm_cl_fail(err, c->name, call, e);
    }
  }
  if (st == LSM_OK && !(g->partial_host = calloc(g->npartial, sizeof(float))))
    st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: cannot allocate the reduction results");
  if (st == LSM_OK) st = lsm_cl_buffer(g, bytes, &g->field[LSM_FIELD_PHI], err);
  if (st == LSM_OK) st = lsm_cl_buffer(g, bytes, &g->target, err);
  if (st == LSM_OK) st = lsm_cl_buffer(g, bytes, &g->field[LSM_FIELD_STAGE1], err);
  if (st == LSM_OK) st = lsm_cl_buffer(g, bytes, &g->field[LSM_FIELD_STAGE2], err);
  if (st == LSM_OK) st = lsm_cl_buffer(g, g->npartial * sizeof(float), &g->partial, err);
  if (st == LSM_OK) st = lsm_grid_create(g->nx, g->ny, g->dx, g->dy, &g->host, err);
  /* the scratch fields start at zero, as the C backend's (the narrow band leaves cells of
   * them unwritten, which nothing reads) */
  const cl_float zero = 0.0f;
  for (int f = LSM_FIELD_STAGE1; st == LSM_OK && f <= LSM_FIELD_STAGE2; ++f) {
    const cl_int e2 = clEnqueueFillBuffer(g->queue, g->field[f], &zero, sizeof zero, 0, bytes, 0,
                                          NULL, NULL);
    if (e2 != CL_SUCCESS) st = lsm_cl_fail(err, c->name, "clEnqueueFillBuffer", e2);
  }
  if (st == LSM_OK) st = write_grid(g, g->field[LSM_FIELD_PHI], src, err);
  if (st == LSM_OK) st = write_grid(g, g->target, tgt, err);
  if (st == LSM_OK) st = fill_ghosts(g, g->target, err);
  if (st != LSM_OK) {
    lsm_cl_grid_destroy(g);
    return st;
  }
  *out = g;
  return LSM_OK;
}

lsm_status lsm_cl_grid_fill_ghosts(lsm_cl_grid *g, lsm_field f, lsm_err *err) {
  return fill_ghosts(g, g->field[f], err);
}

lsm_status lsm_cl_grid_copy(lsm_cl_grid *g, lsm_field dst, lsm_field src, lsm_err *err) {
  if (!g->field[dst]) LSM_TRY(lsm_cl_buffer(g, g->bytes, &g->field[dst], err));
  LSM_CL_TRY(g->c->name, "clEnqueueCopyBuffer",
             clEnqueueCopyBuffer(g->queue, g->field[src], g->field[dst], 0, 0, g->bytes, 0, NULL,
                                 NULL));
  return LSM_OK;
}

void lsm_cl_grid_swap(lsm_cl_grid *g, lsm_field a, lsm_field b) {
  cl_mem t = g->field[a];
  g->field[a] = g->field[b];
  g->field[b] = t;
}

lsm_status lsm_cl_grid_stage(lsm_cl_grid *g, lsm_scheme scheme, lsm_field out, lsm_field u0,
                             lsm_field in, float c0, float c1, float dt, lsm_err *err) {
  if (g->band) return lsm_cl_band_stage(g, scheme, out, u0, in, c0, c1, dt, err);
  const float inv_dx = 1.0f / g->dx, inv_dy = 1.0f / g->dy;
  cl_kernel k = g->k[scheme == LSM_SCHEME_ROEFIX  ? LSM_CL_K_ROEFIX
                     : scheme == LSM_SCHEME_WENO5 ? LSM_CL_K_WENO5
                                                  : LSM_CL_K_UPWIND];
  const lsm_cl_arg args[] = {LSM_CL_ARG(g->field[out]), LSM_CL_ARG(g->field[u0]),
                             LSM_CL_ARG(g->field[in]),  LSM_CL_ARG(g->target),
                             LSM_CL_ARG(g->nx),         LSM_CL_ARG(g->ny),
                             LSM_CL_ARG(g->stride),     LSM_CL_ARG(inv_dx),
                             LSM_CL_ARG(inv_dy),        LSM_CL_ARG(c0),
                             LSM_CL_ARG(c1),            LSM_CL_ARG(dt)};
  LSM_TRY(lsm_cl_args(g, k, 0, args, 12, err));
  LSM_TRY(lsm_cl_run_cells(g, k, err));
  LSM_CL_TRY(g->c->name, "clFlush", clFlush(g->queue));
  return LSM_OK;
}

/* Runs a reduction kernel whose arguments before `nargs` are set (then: __local scratch,
 * partial) and reads the partial results (blocking). */
static lsm_status reduce(lsm_cl_grid *g, cl_kernel k, const lsm_cl_arg *args, int nargs,
                         lsm_err *err) {
  const lsm_cl_arg out[] = {{g->c->red_local[0] * g->c->red_local[1] * sizeof(float), NULL},
                           LSM_CL_ARG(g->partial)};
  LSM_TRY(lsm_cl_args(g, k, 0, args, nargs, err));
  LSM_TRY(lsm_cl_args(g, k, nargs, out, 2, err));
  LSM_TRY(run_2d(g, k, g->red_global, g->c->red_local, err));
  LSM_CL_TRY(g->c->name, "clEnqueueReadBuffer",
             clEnqueueReadBuffer(g->queue, g->partial, CL_TRUE, 0, g->npartial * sizeof(float),
                                 g->partial_host, 0, NULL, NULL));
  return LSM_OK;
}

lsm_status lsm_cl_grid_max_rate(lsm_cl_grid *g, lsm_scheme scheme, float *rate, lsm_err *err) {
  if (g->band) return lsm_cl_band_max_rate(g, scheme, rate, err);
  const float inv_dx = 1.0f / g->dx, inv_dy = 1.0f / g->dy;
  const cl_int roefix = scheme == LSM_SCHEME_ROEFIX;
  const lsm_cl_arg args[] = {LSM_CL_ARG(g->field[LSM_FIELD_PHI]), LSM_CL_ARG(g->target),
                             LSM_CL_ARG(g->nx),     LSM_CL_ARG(g->ny),
                             LSM_CL_ARG(g->stride), LSM_CL_ARG(g->c->red_run),
                             LSM_CL_ARG(inv_dx),    LSM_CL_ARG(inv_dy),
                             LSM_CL_ARG(roefix)};
  LSM_TRY(reduce(g, g->k[LSM_CL_K_CFL], args, 9, err));
  float r = 0.0f;
  for (size_t q = 0; q < g->npartial; ++q) r = g->partial_host[q] > r ? g->partial_host[q] : r;
  *rate = r;
  return LSM_OK;
}

/* The device sums in float (partial sums added in double here), which overflows where
 * lengths are near 1e18 or more (allowed up to 1e30): then the host's sum in double. */
lsm_status lsm_cl_grid_residual(lsm_cl_grid *g, double *norm, lsm_err *err) {
  if (g->band) return lsm_cl_band_residual(g, norm, err);
  const lsm_cl_arg args[] = {LSM_CL_ARG(g->field[LSM_FIELD_PHI]), LSM_CL_ARG(g->target),
                             LSM_CL_ARG(g->nx), LSM_CL_ARG(g->ny), LSM_CL_ARG(g->stride),
                             LSM_CL_ARG(g->c->red_run)};
  LSM_TRY(reduce(g, g->k[LSM_CL_K_RESIDUAL], args, 6, err));
  double total = 0.0;
  for (size_t q = 0; q < g->npartial; ++q) total += (double)g->partial_host[q];
  *norm = sqrt(total);
  if (isfinite(*norm)) return LSM_OK;
  LSM_TRY(lsm_cl_grid_host_target(g, err));
  LSM_TRY(read_grid(g, g->field[LSM_FIELD_PHI], g->host, err));
  *norm = lsm_grid_diff_norm(g->host, g->host_target, g->threads);
  return LSM_OK;
}

lsm_status lsm_cl_grid_host_target(lsm_cl_grid *g, lsm_err *err) {
  if (g->host_target) return LSM_OK;
  LSM_TRY(lsm_grid_create(g->nx, g->ny, g->dx, g->dy, &g->host_target, err));
  return read_grid(g, g->target, g->host_target, err);
}

lsm_status lsm_cl_grid_reinit_sweep(lsm_cl_grid *g, lsm_field out, lsm_field in, lsm_err *err) {
  if (!g->field[LSM_FIELD_PHI0])
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "reinitialisation: phi0 was not taken");
  if (g->band) return lsm_cl_band_reinit_sweep(g, out, in, err);
  const float inv_dx = 1.0f / g->dx, inv_dy = 1.0f / g->dy;
  const float h = lsm_reinit_h(g->dx, g->dy), dtau = lsm_reinit_dtau(h);
  cl_kernel k = g->k[LSM_CL_K_REINIT];
  const lsm_cl_arg args[] = {LSM_CL_ARG(g->field[out]), LSM_CL_ARG(g->field[in]),
                             LSM_CL_ARG(g->field[LSM_FIELD_PHI0]), LSM_CL_ARG(g->nx),
                             LSM_CL_ARG(g->ny), LSM_CL_ARG(g->stride), LSM_CL_ARG(inv_dx),
                             LSM_CL_ARG(inv_dy), LSM_CL_ARG(h), LSM_CL_ARG(dtau)};
  LSM_TRY(lsm_cl_args(g, k, 0, args, 10, err));
  LSM_TRY(lsm_cl_run_cells(g, k, err));
  LSM_CL_TRY(g->c->name, "clFlush", clFlush(g->queue));
  return LSM_OK;
}

static lsm_status check_size(const lsm_cl_grid *g, const lsm_grid *h, lsm_err *err) {
  if (h->nx != g->nx || h->ny != g->ny || h->stride != g->stride || h->ghost != LSM_GHOST)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL,
                    "OpenCL: host grid %dx%d differs from the device's %dx%d", h->nx, h->ny,
                    g->nx, g->ny);
  return LSM_OK;
}

lsm_status lsm_cl_grid_read_phi(lsm_cl_grid *g, const lsm_grid **phi, lsm_err *err) {
  LSM_TRY(read_grid(g, g->field[LSM_FIELD_PHI], g->host, err));
  *phi = g->host;
  return LSM_OK;
}

lsm_status lsm_cl_grid_upload(lsm_cl_grid *g, const lsm_grid *phi, lsm_err *err) {
  LSM_TRY(check_size(g, phi, err));
  return write_grid(g, g->field[LSM_FIELD_PHI], phi, err);
}
