/* lsm_scheme: the schemes and integrators by name, and the C reference's sweeps over host
 * grids for the morph equation
 *
 *   phi_t + F |grad phi| = 0,   F = phi - phi_target         (solver/README.md §2, §4)
 *
 * Spatial schemes (numerical Hamiltonians, per cell in kernels/lsm_cell.h) and TVD
 * Runge–Kutta integrators (Shu & Osher 1988; their tableaux in lsm_fields.c) are chosen by
 * enums; a sweep dispatches once, outside its cell loop.  These sweeps are the C backend's
 * cell ops (lsm_backend_c.c).
 */
#ifndef LSM_SCHEME_H
#define LSM_SCHEME_H

#include <stdint.h>

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_names.h"
#include "solver/base/lsm_status.h"

/* Add new items at the end of each list (lsm_names.h). */
#define LSM_SCHEME_LIST(X)                                                      \
  X(LSM_SCHEME_UPWIND, "upwind")  /* first-order Godunov upwind */              \
  X(LSM_SCHEME_ROEFIX, "roe-fix") /* Roe-Fix, Algorithm 3.1 of the design document */ \
  X(LSM_SCHEME_WENO5, "weno5")    /* fifth-order HJ-WENO derivatives, Godunov Hamiltonian */
LSM_ENUM(lsm_scheme, LSM_SCHEME, LSM_SCHEME_LIST, lsm_scheme_name,
         lsm_scheme_from_name);

#define LSM_TIME_LIST(X)                                                        \
  X(LSM_TIME_EULER, "euler") /* forward Euler */                                \
  X(LSM_TIME_RK2, "rk2")     /* TVD Runge–Kutta 2 (Heun) */                     \
  X(LSM_TIME_RK3, "rk3")     /* TVD Runge–Kutta 3 (Shu–Osher) */
LSM_ENUM(lsm_time, LSM_TIME, LSM_TIME_LIST, lsm_time_name,
         lsm_time_from_name);

/* Number of Hamiltonian evaluations per cell and step (1, 2, 3). */
int lsm_time_stages(lsm_time time);

/* A set of cells as runs along rows: run q is the `length[q]` cells from offset `start[q]`
 * (from cell (0, 0); j stride + i), `cells` in all: the narrow band (lsm_band).  The sweeps
 * below take one, or NULL for every interior cell. */
typedef struct lsm_runs {
  const int32_t *start, *length;
  size_t n, cells;
} lsm_runs;

/* Run q of a sweep over runs (NULL: row q of g's interior): its count, first cell, length;
 * and the threads worth using (lsm_grid_threads by the cells swept). */
static inline ptrdiff_t lsm_runs_count(const lsm_grid *g, const lsm_runs *runs) {
  return runs ? (ptrdiff_t)runs->n : (ptrdiff_t)g->ny;
}
static inline ptrdiff_t lsm_runs_start(const lsm_grid *g, const lsm_runs *runs, ptrdiff_t q) {
  return runs ? (ptrdiff_t)runs->start[q] : q * g->stride;
}
static inline int lsm_runs_length(const lsm_grid *g, const lsm_runs *runs, ptrdiff_t q) {
  return runs ? (int)runs->length[q] : g->nx;
}
static inline int lsm_runs_threads(const lsm_grid *g, const lsm_runs *runs, int threads) {
  if (!runs) return lsm_grid_threads(g, threads);
  return runs->cells < 65536u || threads < 1 ? 1 : threads;
}

/* The CFL step (solver/README.md §4; kernels/lsm_cell.h, lsm_cfl_rate_of): the largest rate
 * of the scheme over the cells of phi (ghosts filled): upwind, |H1|/dx + |H2|/dy on the four
 * one-sided gradient combinations; Roe-Fix, |F| (1/dx + 1/dy), which bounds its
 * Lax–Friedrichs dissipation; WENO5, upwind's.  dt = cfl / rate, monotone for cfl <= 1
 * (upwind, Roe-Fix; WENO5 is not monotone); +INFINITY for a rate of 0 (phi == phi_target). */
float lsm_cfl_max_rate(const lsm_grid *phi, const lsm_grid *phi_target, lsm_scheme scheme,
                       int threads);
float lsm_cfl_max_rate_on(const lsm_grid *phi, const lsm_grid *phi_target, lsm_scheme scheme,
                          const lsm_runs *runs, int threads);
double lsm_cfl_step(double cfl, float rate);
/* Both on phi after filling its ghosts. */
void lsm_cfl_dt(lsm_grid *phi, const lsm_grid *phi_target, lsm_scheme scheme, double cfl,
                int threads, double *dt);

/* One Shu–Osher stage:  out = c0 * u0 + c1 * (in - dt * Hhat(in)), rows in parallel.
 * out may alias u0 (cell-wise), never in.  Fills in's ghosts. */
void lsm_scheme_stage(lsm_scheme scheme, lsm_grid *out, const lsm_grid *u0, lsm_grid *in,
                      const lsm_grid *phi_target, float c0, float c1, float dt, int threads);
/* The same on the cells of runs (NULL: every cell); in's ghosts as they are. */
void lsm_scheme_stage_on(lsm_scheme scheme, lsm_grid *out, const lsm_grid *u0, const lsm_grid *in,
                         const lsm_grid *phi_target, float c0, float c1, float dt,
                         const lsm_runs *runs, int threads);

/* ||a - b||_2 over the interior (Frobenius norm, physical units), summed in
 * double row by row and then in row order, so the value does not depend on
 * the thread count. */
double lsm_grid_diff_norm(const lsm_grid *a, const lsm_grid *b, int threads);
/* The same over the cells of runs (NULL: the interior), summed run by run in run order. */
double lsm_grid_diff_norm_on(const lsm_grid *a, const lsm_grid *b, const lsm_runs *runs,
                             int threads);

/* 1 if every interior value is finite. */
int lsm_grid_all_finite(const lsm_grid *g, int threads);

#endif
