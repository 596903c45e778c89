/* lsm_fields: one pair's fields on a backend, and the time stepping written once.
 *
 * The Shu–Osher Runge–Kutta tableaux, the reinitialisation loop and the CFL step live here and
 * nowhere else; each calls the backend's per-stage and per-sweep ops (lsm_backend.h), so the
 * C reference and OpenCL run the same sequence of stages, ghost fills and sweeps.  lsm_morph
 * drives a pair through this; tests and benchmarks may too.
 */
#ifndef LSM_FIELDS_H
#define LSM_FIELDS_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/pde/lsm_backend.h"
#include "solver/pde/lsm_band.h"
#include "solver/pde/lsm_particles.h"
#include "solver/pde/lsm_scheme.h"

typedef struct lsm_fields lsm_fields;

/* phi = phi_source and the target phi_target (same size) on `backend` (NULL: the C
 * reference); threads: the host threads of the C cell loops. */
lsm_status lsm_fields_create(const lsm_backend *backend, const lsm_grid *phi_source,
                             const lsm_grid *phi_target, int threads, lsm_fields **out,
                             lsm_err *err);
void lsm_fields_destroy(lsm_fields **fields);
const char *lsm_fields_backend_name(const lsm_fields *fields);

/* dt = cfl / (the scheme's largest CFL rate over phi) (solver/README.md §4); +INFINITY when
 * the rate is 0 everywhere (phi == phi_target, or phi flat). */
lsm_status lsm_fields_cfl_dt(lsm_fields *fields, lsm_scheme scheme, double cfl, double *dt,
                             lsm_err *err);

/* One step of size dt: the stages of `time` (TVD Runge–Kutta, Shu & Osher 1988), each after
 * a ghost fill of its input; a loaded particle set takes each stage too. */
lsm_status lsm_fields_step(lsm_fields *fields, lsm_scheme scheme, lsm_time time, float dt,
                           lsm_err *err);

/* `iterations` Russo–Smereka pseudo-time steps (dtau = 0.5 min(dx, dy)) on phi in place. */
lsm_status lsm_fields_reinit(lsm_fields *fields, int iterations, lsm_err *err);

/* ||phi - phi_target||_2 as the backend sums it (lsm_backend_ops.residual). */
lsm_status lsm_fields_residual(lsm_fields *fields, double *norm, lsm_err *err);

/* phi on the host, its ghosts filled: read-only, valid until the next call on the fields
 * (a download where the backend keeps phi elsewhere). */
lsm_status lsm_fields_phi(lsm_fields *fields, const lsm_grid **phi, lsm_err *err);
/* The same copied into a host grid of the same size; and a host grid as the new phi. */
lsm_status lsm_fields_download(lsm_fields *fields, lsm_grid *phi, lsm_err *err);
lsm_status lsm_fields_upload(lsm_fields *fields, const lsm_grid *phi, lsm_err *err);

/* Particles (the backend's optional ops): 1 when it has them.  A loaded set (lsm_fields_pls_load,
 * a copy) takes every stage of lsm_fields_step; lsm_fields_pls_correct corrects phi with it
 * (no reseeding: the caller reseeds on the host and loads the new set). */
int lsm_fields_has_particles(const lsm_fields *fields);
lsm_status lsm_fields_pls_load(lsm_fields *fields, const lsm_pls_view *set, int radius_adjust,
                               lsm_err *err);
lsm_status lsm_fields_pls_correct(lsm_fields *fields, lsm_pls_stats *stats, lsm_err *err);

/* Exchanges two fields (the backend's swap). */
void lsm_fields_swap(lsm_fields *fields, lsm_field a, lsm_field b);

/* The narrow band (the backend's optional band ops; lsm_band.h).  lsm_fields_band_start: from
 * now on the cell ops run on the band around phi's kept levels (phi_target, which must stay
 * valid while the band runs, is where the cells outside it relax to); lsm_fields_phi then
 * returns phi with the cells outside the band filled.  lsm_fields_band_maintain, after each
 * step and its corrections: rebuilds the band every params->every steps, or sooner where a
 * front may appear (*rebuilt = 1: the CFL rate may have changed). */
int lsm_fields_has_band(const lsm_fields *fields);
lsm_status lsm_fields_band_start(lsm_fields *fields, const lsm_grid *phi_target,
                                 const lsm_band_params *params, lsm_err *err);
lsm_status lsm_fields_band_maintain(lsm_fields *fields, int *rebuilt, lsm_err *err);
int lsm_fields_banded(const lsm_fields *fields);
/* The largest |phi - phi_target| of the cells the last rebuild took into the band. */
float lsm_fields_band_enter_speed(const lsm_fields *fields);
/* Cell updates of the stages so far (cells swept x stages); the cells a stage sweeps now. */
long long lsm_fields_cell_updates(const lsm_fields *fields);
long long lsm_fields_cells(const lsm_fields *fields);

#endif
