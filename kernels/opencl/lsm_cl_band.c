/* lsm_cl_band: the narrow band on an OpenCL device (the band ops of lsm_backend.h, and the
 * cell ops restricted to the band's cells).
 *
 * The host's band (solver/pde/lsm_band.c) hands over its runs; they go to the device as row
 * segments of LSM_BAND_SEGMENT cells (buffer offsets and lengths), one work-item a cell, with
 * the rim's cells and amplitudes.  The kernels (morph.cl, lsm_band_*) run the per-cell code of
 * the full-grid ones on those cells only, so both backends update the same cells with the same
 * arithmetic. */
#include "kernels/opencl/lsm_cl_grid.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "kernels/lsm_cell.h"

typedef struct lsm_cl_band {
  cl_mem seg, rim, rim_amp, partial, cells, values; /* device buffers, grown as needed */
  size_t seg_cap, rim_cap, amp_cap, partial_cap, cells_cap, values_cap; /* capacities */
  int32_t *seg_host;                                /* the segments on the host */
  size_t seg_host_cap;
  float *partial_host;
  size_t nseg, nrim;
  size_t local; /* work-group size: a power of two */
} lsm_cl_band;

static size_t round_up(size_t n, size_t m) { return (n + m - 1) / m * m; }

void lsm_cl_band_destroy(lsm_cl_grid *g) {
  lsm_cl_band *b = g->band;
  if (!b) return;
  cl_mem m[] = {b->seg, b->rim, b->rim_amp, b->partial, b->cells, b->values};
  for (size_t q = 0; q < sizeof m / sizeof m[0]; ++q)
    if (m[q]) clReleaseMemObject(m[q]);
  free(b->seg_host);
  free(b->partial_host);
  free(b);
  g->band = NULL;
}

/* A device buffer of at least `need` elements of `size` bytes (at least one). */
static lsm_status grow(lsm_cl_grid *g, cl_mem *buf, size_t *cap, size_t need, size_t size,
                       lsm_err *err) {
  if (need < 1) need = 1;
  if (*buf && *cap >= need) return LSM_OK;
  size_t n = *cap ? *cap : 1024;
  while (n < need) n *= 2;
  if (*buf) clReleaseMemObject(*buf);
  *buf = NULL;
  *cap = 0;
  LSM_TRY(lsm_cl_buffer(g, n * size, buf, err));
  *cap = n;
  return LSM_OK;
}

static lsm_status upload(lsm_cl_grid *g, cl_mem buf, const void *data, size_t bytes,
                         lsm_err *err) {
  if (!bytes) return LSM_OK;
  LSM_CL_TRY(g->c->name, "clEnqueueWriteBuffer",
             clEnqueueWriteBuffer(g->queue, buf, CL_TRUE, 0, bytes, data, 0, NULL, NULL));
  return LSM_OK;
}

/* The buffer offset of the cell at offset k from cell (0, 0). */
static cl_int device_offset(const lsm_cl_grid *g, int32_t k) {
  return (cl_int)(k + (ptrdiff_t)LSM_GHOST * g->stride + LSM_GHOST);
}

lsm_status lsm_cl_band_set(lsm_cl_grid *g, const lsm_band_lists *l, lsm_err *err) {
  if (!g->band) {
    if (!(g->band = calloc(1, sizeof *g->band)))
      return lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: cannot allocate the narrow band");
    size_t local = 64;
    while (local > 1 && local > g->c->max_group) local /= 2;
    g->band->local = local;
  }
  lsm_cl_band *b = g->band;
  size_t nseg = 0;
  for (size_t r = 0; r < l->runs; ++r)
    nseg += ((size_t)l->run_length[r] + LSM_BAND_SEGMENT - 1) / LSM_BAND_SEGMENT;
  if (nseg * 2 > b->seg_host_cap) {
    free(b->seg_host);
    b->seg_host_cap = 0;
    if (!(b->seg_host = malloc(nseg * 2 * sizeof *b->seg_host)))
      return lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: cannot allocate the narrow band");
    b->seg_host_cap = nseg * 2;
  }
  size_t q = 0;
  for (size_t r = 0; r < l->runs; ++r)
    for (int32_t o = 0; o < l->run_length[r]; o += LSM_BAND_SEGMENT) {
      const int32_t left = l->run_length[r] - o;
      b->seg_host[2 * q] = device_offset(g, l->run_start[r] + o);
      b->seg_host[2 * q + 1] = left < LSM_BAND_SEGMENT ? left : LSM_BAND_SEGMENT;
      q++;
    }
  b->nseg = nseg;
  LSM_TRY(grow(g, &b->seg, &b->seg_cap, 2 * nseg, sizeof(cl_int), err));
  LSM_TRY(upload(g, b->seg, b->seg_host, 2 * nseg * sizeof(cl_int), err));
  /* the rim, as buffer offsets */
  b->nrim = l->rim_cells;
  LSM_TRY(grow(g, &b->rim, &b->rim_cap, b->nrim, sizeof(cl_int), err));
  LSM_TRY(grow(g, &b->rim_amp, &b->amp_cap, b->nrim, sizeof(float), err));
  int32_t *offsets = b->nrim ? malloc(b->nrim * sizeof *offsets) : NULL;
  if (b->nrim && !offsets) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: narrow band rim");
  for (size_t k = 0; k < b->nrim; ++k) offsets[k] = device_offset(g, l->rim[k]);
  lsm_status st = upload(g, b->rim, offsets, b->nrim * sizeof(cl_int), err);
  free(offsets);
  LSM_TRY(st);
  return upload(g, b->rim_amp, l->rim_amplitude, b->nrim * sizeof(float), err);
}

lsm_status lsm_cl_band_write(lsm_cl_grid *g, lsm_field field, const int32_t *cells,
                             const float *values, size_t n, lsm_err *err) {
  lsm_cl_band *b = g->band;
  if (!b || !g->field[field]) return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "band: no such field");
  if (!n) return LSM_OK;
  LSM_TRY(grow(g, &b->cells, &b->cells_cap, n, sizeof(cl_int), err));
  LSM_TRY(grow(g, &b->values, &b->values_cap, n, sizeof(float), err));
  int32_t *offsets = malloc(n * sizeof *offsets);
  if (!offsets) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: narrow band cells");
  for (size_t k = 0; k < n; ++k) offsets[k] = device_offset(g, cells[k]);
  lsm_status st = upload(g, b->cells, offsets, n * sizeof(cl_int), err);
  free(offsets);
  LSM_TRY(st);
  LSM_TRY(upload(g, b->values, values, n * sizeof(float), err));
  const cl_int count = (cl_int)n;
  cl_kernel k = g->k[LSM_CL_K_BAND_WRITE];
  const lsm_cl_arg args[] = {LSM_CL_ARG(g->field[field]), LSM_CL_ARG(b->cells),
                             LSM_CL_ARG(b->values), LSM_CL_ARG(count)};
  LSM_TRY(lsm_cl_args(g, k, 0, args, 4, err));
  return lsm_cl_run_1d(g, k, n, b->local, err);
}

lsm_status lsm_cl_band_fill_rim(lsm_cl_grid *g, lsm_field field, float g_relax, lsm_err *err) {
  lsm_cl_band *b = g->band;
  if (!b || !g->field[field]) return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "band: no such field");
  if (!b->nrim) return LSM_OK;
  const cl_int count = (cl_int)b->nrim;
  cl_kernel k = g->k[LSM_CL_K_BAND_RIM];
  const lsm_cl_arg args[] = {LSM_CL_ARG(g->field[field]), LSM_CL_ARG(g->target),
                             LSM_CL_ARG(b->rim), LSM_CL_ARG(b->rim_amp), LSM_CL_ARG(count),
                             LSM_CL_ARG(g_relax)};
  LSM_TRY(lsm_cl_args(g, k, 0, args, 6, err));
  return lsm_cl_run_1d(g, k, b->nrim, b->local, err);
}

/* Runs kernel k over the band's cells (its arguments set). */
static lsm_status run_band(lsm_cl_grid *g, cl_kernel k, lsm_err *err) {
  const lsm_cl_band *b = g->band;
  if (!b->nseg) return LSM_OK;
  LSM_TRY(lsm_cl_run_1d(g, k, b->nseg * LSM_BAND_SEGMENT, b->local, err));
  LSM_CL_TRY(g->c->name, "clFlush", clFlush(g->queue));
  return LSM_OK;
}

lsm_status lsm_cl_band_stage(lsm_cl_grid *g, lsm_scheme scheme, lsm_field out, lsm_field u0,
                             lsm_field in, float c0, float c1, float dt, lsm_err *err) {
  const lsm_cl_band *b = g->band;
  const float inv_dx = 1.0f / g->dx, inv_dy = 1.0f / g->dy;
  const cl_int nseg = (cl_int)b->nseg;
  cl_kernel k = g->k[scheme == LSM_SCHEME_ROEFIX  ? LSM_CL_K_BAND_ROEFIX
                     : scheme == LSM_SCHEME_WENO5 ? LSM_CL_K_BAND_WENO5
                                                  : LSM_CL_K_BAND_UPWIND];
  const lsm_cl_arg args[] = {LSM_CL_ARG(g->field[out]), LSM_CL_ARG(g->field[u0]),
                             LSM_CL_ARG(g->field[in]),  LSM_CL_ARG(g->target),
                             LSM_CL_ARG(b->seg),        LSM_CL_ARG(nseg),
                             LSM_CL_ARG(g->stride),     LSM_CL_ARG(inv_dx),
                             LSM_CL_ARG(inv_dy),        LSM_CL_ARG(c0),
                             LSM_CL_ARG(c1),            LSM_CL_ARG(dt)};
  LSM_TRY(lsm_cl_args(g, k, 0, args, 12, err));
  return run_band(g, k, err);
}

lsm_status lsm_cl_band_reinit_sweep(lsm_cl_grid *g, lsm_field out, lsm_field in, lsm_err *err) {
  const lsm_cl_band *b = g->band;
  const float inv_dx = 1.0f / g->dx, inv_dy = 1.0f / g->dy;
  const float h = lsm_reinit_h(g->dx, g->dy), dtau = lsm_reinit_dtau(h);
  const cl_int nseg = (cl_int)b->nseg;
  cl_kernel k = g->k[LSM_CL_K_BAND_REINIT];
  const lsm_cl_arg args[] = {LSM_CL_ARG(g->field[out]), LSM_CL_ARG(g->field[in]),
                             LSM_CL_ARG(g->field[LSM_FIELD_PHI0]), LSM_CL_ARG(b->seg),
                             LSM_CL_ARG(nseg), LSM_CL_ARG(g->stride), LSM_CL_ARG(inv_dx),
                             LSM_CL_ARG(inv_dy), LSM_CL_ARG(h), LSM_CL_ARG(dtau)};
  LSM_TRY(lsm_cl_args(g, k, 0, args, 10, err));
  return run_band(g, k, err);
}

/* A reduction over the band's cells: kernel k's first `nargs` arguments set here, then the
 * work-group scratch and the partial results, read back (blocking); *groups of them. */
static lsm_status reduce(lsm_cl_grid *g, cl_kernel k, const lsm_cl_arg *args, int nargs,
                         size_t *groups, lsm_err *err) {
  lsm_cl_band *b = g->band;
  const size_t global = round_up(b->nseg * LSM_BAND_SEGMENT, b->local);
  *groups = global / b->local;
  if (!*groups) return LSM_OK;
  const size_t cap = b->partial_cap;
  LSM_TRY(grow(g, &b->partial, &b->partial_cap, *groups, sizeof(float), err));
  if (b->partial_cap != cap || !b->partial_host) {
    free(b->partial_host);
    if (!(b->partial_host = malloc(b->partial_cap * sizeof(float))))
      return lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: narrow band partial results");
  }
  const lsm_cl_arg out[] = {{b->local * sizeof(float), NULL}, LSM_CL_ARG(b->partial)};
  LSM_TRY(lsm_cl_args(g, k, 0, args, nargs, err));
  LSM_TRY(lsm_cl_args(g, k, nargs, out, 2, err));
  LSM_TRY(lsm_cl_run_1d(g, k, b->nseg * LSM_BAND_SEGMENT, b->local, err));
  LSM_CL_TRY(g->c->name, "clEnqueueReadBuffer",
             clEnqueueReadBuffer(g->queue, b->partial, CL_TRUE, 0, *groups * sizeof(float),
                                 b->partial_host, 0, NULL, NULL));
  return LSM_OK;
}

lsm_status lsm_cl_band_max_rate(lsm_cl_grid *g, lsm_scheme scheme, float *rate, lsm_err *err) {
  const lsm_cl_band *b = g->band;
  const float inv_dx = 1.0f / g->dx, inv_dy = 1.0f / g->dy;
  const cl_int roefix = scheme == LSM_SCHEME_ROEFIX, nseg = (cl_int)b->nseg;
  const lsm_cl_arg args[] = {LSM_CL_ARG(g->field[LSM_FIELD_PHI]), LSM_CL_ARG(g->target),
                             LSM_CL_ARG(b->seg),    LSM_CL_ARG(nseg),
                             LSM_CL_ARG(g->stride), LSM_CL_ARG(inv_dx),
                             LSM_CL_ARG(inv_dy),    LSM_CL_ARG(roefix)};
  size_t groups;
  LSM_TRY(reduce(g, g->k[LSM_CL_K_BAND_CFL], args, 8, &groups, err));
  float r = 0.0f;
  for (size_t q = 0; q < groups; ++q) r = lsm_maxf(r, b->partial_host[q]);
  *rate = r;
  return LSM_OK;
}

lsm_status lsm_cl_band_residual(lsm_cl_grid *g, double *norm, lsm_err *err) {
  const lsm_cl_band *b = g->band;
  const cl_int nseg = (cl_int)b->nseg;
  const lsm_cl_arg args[] = {LSM_CL_ARG(g->field[LSM_FIELD_PHI]), LSM_CL_ARG(g->target),
                             LSM_CL_ARG(b->seg), LSM_CL_ARG(nseg)};
  size_t groups;
  LSM_TRY(reduce(g, g->k[LSM_CL_K_BAND_RESIDUAL], args, 4, &groups, err));
  double total = 0.0;
  for (size_t q = 0; q < groups; ++q) total += (double)b->partial_host[q];
  *norm = sqrt(total);
  if (isfinite(*norm)) return LSM_OK;
  /* the device's float sum overflowed (lengths near 1e18 and beyond): the host's in double */
  LSM_TRY(lsm_cl_grid_host_target(g, err));
  const lsm_grid *phi;
  LSM_TRY(lsm_cl_grid_read_phi(g, &phi, err));
  total = 0.0;
  for (size_t q = 0; q < b->nseg; ++q)
    for (int32_t i = 0; i < b->seg_host[2 * q + 1]; ++i) {
      const size_t k = (size_t)b->seg_host[2 * q] + (size_t)i;
      const double d = (double)phi->base[k] - (double)g->host_target->base[k];
      total += d * d;
    }
  *norm = sqrt(total);
  return LSM_OK;
}
