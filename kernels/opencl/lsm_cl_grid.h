/* lsm_cl_grid: one pair's fields on an OpenCL device and the grid ops on them.
 *
 * A state has its own queue, kernels and buffers: the fields of lsm_backend.h (phi, two
 * Runge–Kutta scratch grids, phi0 on the first reinitialisation), phi_target, and the small
 * array of per-work-group partial results.  Fields stay on the device for the whole pair; the
 * host reads only the partial results of the CFL and residual reductions, and phi when asked.
 * Each op enqueues the kernels of morph.cl that do its job (ghost fill, stage, reduction,
 * reinitialisation sweep) with the per-cell code of kernels/.
 */
#ifndef LSM_CL_GRID_H
#define LSM_CL_GRID_H

#include "kernels/opencl/lsm_cl_context.h"
#include "solver/base/lsm_grid.h"
#include "solver/pde/lsm_backend.h"

typedef struct lsm_cl_grid {
  lsm_cl_ctx *c;
  cl_command_queue queue;
  cl_kernel k[LSM_CL_K_COUNT];
  cl_mem field[LSM_FIELD_COUNT];
  cl_mem target;
  cl_mem partial; /* one float per reduction work-group */
  float *partial_host;
  size_t npartial;
  lsm_grid *host;        /* phi read to the host (read_phi) */
  lsm_grid *host_target; /* phi_target there, for the residual's sum in double */
  int threads;
  int nx, ny;
  cl_int stride;
  float dx, dy;
  size_t bytes;        /* one grid, ghosts included */
  size_t local[2];     /* cell kernels' work-group: a row segment (LX, 1) */
  size_t global[2];    /* cell kernels' NDRange: nx rounded up to LX, ny */
  size_t red_global[2];
  size_t ghost_global; /* ring cells, rounded up */
  struct lsm_cl_band *band; /* the narrow band (lsm_cl_band.c), once set; NULL: every cell */
} lsm_cl_grid;

/* The grid ops of lsm_backend_ops on a state (see there). */
lsm_status lsm_cl_grid_create(lsm_cl_ctx *c, const lsm_grid *phi_source, const lsm_grid *phi_target,
                              int threads, lsm_cl_grid **out, lsm_err *err);
void lsm_cl_grid_destroy(lsm_cl_grid *g);
lsm_status lsm_cl_grid_fill_ghosts(lsm_cl_grid *g, lsm_field f, lsm_err *err);
lsm_status lsm_cl_grid_copy(lsm_cl_grid *g, lsm_field dst, lsm_field src, lsm_err *err);
void lsm_cl_grid_swap(lsm_cl_grid *g, lsm_field a, lsm_field b);
lsm_status lsm_cl_grid_stage(lsm_cl_grid *g, lsm_scheme scheme, lsm_field out, lsm_field u0,
                             lsm_field in, float c0, float c1, float dt, lsm_err *err);
lsm_status lsm_cl_grid_max_rate(lsm_cl_grid *g, lsm_scheme scheme, float *rate, lsm_err *err);
lsm_status lsm_cl_grid_residual(lsm_cl_grid *g, double *norm, lsm_err *err);
lsm_status lsm_cl_grid_reinit_sweep(lsm_cl_grid *g, lsm_field out, lsm_field in, lsm_err *err);
lsm_status lsm_cl_grid_read_phi(lsm_cl_grid *g, const lsm_grid **phi, lsm_err *err);
lsm_status lsm_cl_grid_upload(lsm_cl_grid *g, const lsm_grid *phi, lsm_err *err);
/* phi_target read to the host once (g->host_target), for sums in double there. */
lsm_status lsm_cl_grid_host_target(lsm_cl_grid *g, lsm_err *err);

/* ---- the narrow band (lsm_cl_band.c): the band ops, and the cell ops on the band ---- */
lsm_status lsm_cl_band_set(lsm_cl_grid *g, const lsm_band_lists *lists, lsm_err *err);
lsm_status lsm_cl_band_write(lsm_cl_grid *g, lsm_field field, const int32_t *cells,
                             const float *values, size_t n, lsm_err *err);
lsm_status lsm_cl_band_fill_rim(lsm_cl_grid *g, lsm_field field, float g_relax, lsm_err *err);
void lsm_cl_band_destroy(lsm_cl_grid *g);
lsm_status lsm_cl_band_stage(lsm_cl_grid *g, lsm_scheme scheme, lsm_field out, lsm_field u0,
                             lsm_field in, float c0, float c1, float dt, lsm_err *err);
lsm_status lsm_cl_band_max_rate(lsm_cl_grid *g, lsm_scheme scheme, float *rate, lsm_err *err);
lsm_status lsm_cl_band_residual(lsm_cl_grid *g, double *norm, lsm_err *err);
lsm_status lsm_cl_band_reinit_sweep(lsm_cl_grid *g, lsm_field out, lsm_field in, lsm_err *err);

/* ---- for the kernels of other modules (particles, band) ---- */

/* A kernel argument: LSM_CL_ARG(value) for a variable, {bytes, NULL} for __local memory. */
typedef struct lsm_cl_arg {
  size_t size;
  const void *value;
} lsm_cl_arg;
#define LSM_CL_ARG(v) {sizeof(v), &(v)}
/* Sets arguments first .. first + n - 1 of kernel k. */
lsm_status lsm_cl_args(lsm_cl_grid *g, cl_kernel k, int first, const lsm_cl_arg *args, int n,
                       lsm_err *err);
/* Enqueues k over the cells (2D, the cell kernels' shape) or over n items in 1D groups of
 * `local`. */
lsm_status lsm_cl_run_cells(lsm_cl_grid *g, cl_kernel k, lsm_err *err);
lsm_status lsm_cl_run_1d(lsm_cl_grid *g, cl_kernel k, size_t n, size_t local, lsm_err *err);
/* A device buffer of `bytes` (out of memory: a message naming the grid). */
lsm_status lsm_cl_buffer(lsm_cl_grid *g, size_t bytes, cl_mem *out, lsm_err *err);

#endif
