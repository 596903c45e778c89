/* lsm_cl_particles: the particle level set of one pair on an OpenCL device (--method pls).
 *
 * The set seeded on the host is copied to the device (load); every Runge–Kutta stage then
 * builds the node field F, grad phi of its input and advects every particle, and every
 * correction removes flagged particles, detects escaped ones and corrects phi, all with the
 * per-particle code of kernels/lsm_particle_cell.h.  The host reads back five counters per
 * correction.  Removed particles are kept with a dead state, not compacted.
 */
#ifndef LSM_CL_PARTICLES_H
#define LSM_CL_PARTICLES_H

#include "kernels/opencl/lsm_cl_grid.h"
#include "solver/pde/lsm_particles.h"

typedef struct lsm_cl_particles lsm_cl_particles;

/* The particle ops of lsm_backend_ops on grid g's fields; *p is created by the first load. */
lsm_status lsm_cl_pls_load(lsm_cl_particles **p, lsm_cl_grid *g, const lsm_pls_view *set,
                           int radius_adjust, lsm_err *err);
lsm_status lsm_cl_pls_stage(lsm_cl_particles *p, lsm_cl_grid *g, lsm_field in, float c0, float c1,
                            float dt, int first, lsm_err *err);
lsm_status lsm_cl_pls_correct(lsm_cl_particles *p, lsm_cl_grid *g, lsm_pls_stats *stats,
                              lsm_err *err);
void lsm_cl_pls_destroy(lsm_cl_particles *p);

#endif
