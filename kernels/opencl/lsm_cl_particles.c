#include "kernels/opencl/lsm_cl_particles.h"

#include <stdint.h>
#include <stdlib.h>

#include "kernels/lsm_particle_cell.h"

/* The counters of lsm_pcl_detect / lsm_pcl_apply (morph.cl), in this order. */
enum { PCL_N_ESCAPED, PCL_N_STRAY, PCL_N_REMOVED, PCL_N_LIVE, PCL_N_CORRECTED, PCL_N_COUNT };

struct lsm_cl_particles {
  /* per particle: x, y, Runge–Kutta base x0, y0, radius, sign (char), state (uchar);
   * pcap allocated, pn in use */
  cl_mem px, py, px0, py0, pradius, psign, pstate;
  /* per node: the stage's node field (float4), the phi_plus / phi_minus keys; the
   * correction's counters */
  cl_mem vel, plus, minus, counters;
  size_t pcap;
  cl_int pn;
  long long live; /* particles not yet removed (strays included) */
  int radius_adjust;
  size_t local; /* particle kernels' work-group size */
  float inv_2dx, inv_2dy, far, rmin, rmax; /* as lsm_pls_create computes them */
};

void lsm_cl_pls_destroy(lsm_cl_particles *p) {
  if (!p) return;
  cl_mem *mems[] = {&p->px,  &p->py,  &p->px0,   &p->py0,  &p->pradius, &p->psign,
                    &p->pstate, &p->vel, &p->plus, &p->minus, &p->counters};
  for (size_t k = 0; k < sizeof mems / sizeof *mems; ++k)
    if (*mems[k]) clReleaseMemObject(*mems[k]);
  free(p);
}

/* (Re)allocation of a particle buffer of `bytes` (the old one, if any, released). */
static lsm_status pcl_buffer(lsm_cl_grid *g, cl_mem *buf, size_t bytes, lsm_err *err) {
  if (*buf) clReleaseMemObject(*buf);
  *buf = NULL;
  return lsm_cl_buffer(g, bytes, buf, err);
}

static lsm_status fill_uint(lsm_cl_grid *g, cl_mem buf, cl_uint value, size_t count,
                            lsm_err *err) {
  LSM_CL_TRY(g->c->name, "clEnqueueFillBuffer",
             clEnqueueFillBuffer(g->queue, buf, &value, sizeof value, 0, count * sizeof value, 0,
                                 NULL, NULL));
  return LSM_OK;
}

static lsm_status create(lsm_cl_grid *g, lsm_cl_particles **out, lsm_err *err) {
  lsm_cl_particles *p = calloc(1, sizeof *p);
  if (!p) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "OpenCL: cannot allocate the particles");
  p->inv_2dx = 0.5f / g->dx;
  p->inv_2dy = 0.5f / g->dy;
  p->far = lsm_pcl_far(g->dx, g->dy);
  p->rmin = lsm_pcl_rmin(g->dx, g->dy);
  p->rmax = lsm_pcl_rmax(g->dx, g->dy);
  /* 1D groups of 128, fewer if the device says so */
  p->local = 128;
  while (p->local > 1 && (p->local > g->c->max_group || p->local > g->c->max_items[0]))
    p->local /= 2;
  const size_t nodes = (size_t)g->nx * (size_t)g->ny;
  lsm_status st = pcl_buffer(g, &p->vel, nodes * 4 * sizeof(float), err);
  if (st == LSM_OK) st = pcl_buffer(g, &p->plus, nodes * sizeof(cl_uint), err);
  if (st == LSM_OK) st = pcl_buffer(g, &p->minus, nodes * sizeof(cl_uint), err);
  /* the accumulators' "no particle" keys (morph.cl: LSM_PCL_KEY_NONE_*);
   * lsm_pcl_apply restores them after each correction */
  if (st == LSM_OK) st = fill_uint(g, p->plus, 0u, nodes, err);
  if (st == LSM_OK) st = fill_uint(g, p->minus, 0xFFFFFFFFu, nodes, err);
  if (st == LSM_OK) st = pcl_buffer(g, &p->counters, PCL_N_COUNT * sizeof(cl_int), err);
  if (st != LSM_OK) {
    lsm_cl_pls_destroy(p);
    return st;
  }
  *out = p;
  return LSM_OK;
}

static lsm_status write(lsm_cl_grid *g, cl_mem buf, size_t bytes, const void *src, lsm_err *err) {
  LSM_CL_TRY(g->c->name, "clEnqueueWriteBuffer",
             clEnqueueWriteBuffer(g->queue, buf, CL_FALSE, 0, bytes, src, 0, NULL, NULL));
  return LSM_OK;
}

lsm_status lsm_cl_pls_load(lsm_cl_particles **pp, lsm_cl_grid *g, const lsm_pls_view *set,
                           int radius_adjust, lsm_err *err) {
  if (set->n > (size_t)INT32_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "OpenCL: %s: %zu particles are too many",
                    g->c->name, set->n);
  if (set->n > 0 && (g->nx < 2 || g->ny < 2))
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "OpenCL: particles on a %dx%d grid", g->nx,
                    g->ny);
  if (!*pp) LSM_TRY(create(g, pp, err));
  lsm_cl_particles *p = *pp;
  const size_t n = set->n;
  if (n > p->pcap || !p->px) {
    const size_t cap = n > 0 ? n : 1, fb = cap * sizeof(float);
    p->pcap = 0;
    cl_mem *floats[] = {&p->px, &p->py, &p->px0, &p->py0, &p->pradius};
    for (size_t k = 0; k < sizeof floats / sizeof *floats; ++k)
      LSM_TRY(pcl_buffer(g, floats[k], fb, err));
    LSM_TRY(pcl_buffer(g, &p->psign, cap, err));
    LSM_TRY(pcl_buffer(g, &p->pstate, cap, err));
    p->pcap = cap;
  }
  p->pn = 0;
  if (n > 0) {
    const size_t fb = n * sizeof(float);
    LSM_TRY(write(g, p->px, fb, set->x, err));
    LSM_TRY(write(g, p->py, fb, set->y, err));
    LSM_TRY(write(g, p->pradius, fb, set->radius, err));
    LSM_TRY(write(g, p->psign, n, set->sign, err));
    const cl_uchar live = 0; /* morph.cl: LSM_PCL_LIVE */
    LSM_CL_TRY(g->c->name, "clEnqueueFillBuffer",
               clEnqueueFillBuffer(g->queue, p->pstate, &live, 1, 0, n, 0, NULL, NULL));
  }
  /* The set may change once this returns: wait for the copies. */
  LSM_CL_TRY(g->c->name, "clFinish", clFinish(g->queue));
  p->pn = (cl_int)n;
  p->live = (long long)n;
  p->radius_adjust = radius_adjust;
  return LSM_OK;
}

lsm_status lsm_cl_pls_stage(lsm_cl_particles *p, lsm_cl_grid *g, lsm_field in, float c0,
                            float c1, float dt, int first, lsm_err *err) {
  if (p->pn == 0) return LSM_OK;
  const float inv_dx = 1.0f / g->dx, inv_dy = 1.0f / g->dy;
  cl_kernel k = g->k[LSM_CL_K_PCL_VELOCITY];
  const lsm_cl_arg vel[] = {LSM_CL_ARG(p->vel),    LSM_CL_ARG(g->field[in]), LSM_CL_ARG(g->target),
                            LSM_CL_ARG(g->nx),     LSM_CL_ARG(g->ny),        LSM_CL_ARG(g->stride),
                            LSM_CL_ARG(inv_dx),    LSM_CL_ARG(inv_dy),       LSM_CL_ARG(p->inv_2dx),
                            LSM_CL_ARG(p->inv_2dy)};
  LSM_TRY(lsm_cl_args(g, k, 0, vel, 10, err));
  LSM_TRY(lsm_cl_run_cells(g, k, err));
  /* the step's first stage records the positions as the Runge–Kutta base */
  const cl_int save_base = first;
  k = g->k[LSM_CL_K_PCL_ADVECT];
  const lsm_cl_arg adv[] = {LSM_CL_ARG(p->px),     LSM_CL_ARG(p->py),  LSM_CL_ARG(p->px0),
                            LSM_CL_ARG(p->py0),    LSM_CL_ARG(p->pstate), LSM_CL_ARG(p->pn),
                            LSM_CL_ARG(p->vel),    LSM_CL_ARG(g->nx),  LSM_CL_ARG(g->ny),
                            LSM_CL_ARG(inv_dx),    LSM_CL_ARG(inv_dy), LSM_CL_ARG(c0),
                            LSM_CL_ARG(c1),        LSM_CL_ARG(dt),     LSM_CL_ARG(save_base)};
  LSM_TRY(lsm_cl_args(g, k, 0, adv, 15, err));
  return lsm_cl_run_1d(g, k, (size_t)p->pn, p->local, err);
}

lsm_status lsm_cl_pls_correct(lsm_cl_particles *p, lsm_cl_grid *g, lsm_pls_stats *stats,
                              lsm_err *err) {
  if (p->pn == 0) {
    lsm_pls_count_correction(stats, 0, 0, 0, 0);
    return LSM_OK;
  }
  LSM_TRY(fill_uint(g, p->counters, 0u, PCL_N_COUNT, err));
  /* arguments 0-9 of the detection and radius kernels: the particles, their count, and
   * phi with its size and row stride */
  const lsm_cl_arg pcl[] = {LSM_CL_ARG(p->px),     LSM_CL_ARG(p->py),
                            LSM_CL_ARG(p->psign),  LSM_CL_ARG(p->pradius),
                            LSM_CL_ARG(p->pstate), LSM_CL_ARG(p->pn),
                            LSM_CL_ARG(g->field[LSM_FIELD_PHI]), LSM_CL_ARG(g->nx),
                            LSM_CL_ARG(g->ny),     LSM_CL_ARG(g->stride),
                            LSM_CL_ARG(g->dx),     LSM_CL_ARG(g->dy),
                            LSM_CL_ARG(p->far),    LSM_CL_ARG(p->plus),
                            LSM_CL_ARG(p->minus),  LSM_CL_ARG(p->counters),
                            {p->local * sizeof(cl_int), NULL}};
  cl_kernel k = g->k[LSM_CL_K_PCL_DETECT];
  LSM_TRY(lsm_cl_args(g, k, 0, pcl, 17, err));
  LSM_TRY(lsm_cl_run_1d(g, k, (size_t)p->pn, p->local, err));
  k = g->k[LSM_CL_K_PCL_APPLY];
  const lsm_cl_arg apply[] = {LSM_CL_ARG(g->field[LSM_FIELD_PHI]), LSM_CL_ARG(g->nx),
                              LSM_CL_ARG(g->ny), LSM_CL_ARG(g->stride), LSM_CL_ARG(p->plus),
                              LSM_CL_ARG(p->minus), LSM_CL_ARG(p->counters)};
  LSM_TRY(lsm_cl_args(g, k, 0, apply, 7, err));
  LSM_TRY(lsm_cl_run_cells(g, k, err));
  if (p->radius_adjust) {
    k = g->k[LSM_CL_K_PCL_RADIUS];
    const lsm_cl_arg radius[] = {LSM_CL_ARG(p->rmin), LSM_CL_ARG(p->rmax)};
    LSM_TRY(lsm_cl_args(g, k, 0, pcl, 10, err));
    LSM_TRY(lsm_cl_args(g, k, 10, radius, 2, err));
    LSM_TRY(lsm_cl_run_1d(g, k, (size_t)p->pn, p->local, err));
  }
  cl_int c[PCL_N_COUNT];
  LSM_CL_TRY(g->c->name, "clEnqueueReadBuffer",
             clEnqueueReadBuffer(g->queue, p->counters, CL_TRUE, 0, sizeof c, c, 0, NULL, NULL));
  p->live -= c[PCL_N_REMOVED];
  if (c[PCL_N_LIVE] != p->live)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL,
                    "particles: %s holds %d live particles, %lld expected", g->c->name,
                    (int)c[PCL_N_LIVE], p->live);
  lsm_pls_count_correction(stats, c[PCL_N_REMOVED], c[PCL_N_STRAY], c[PCL_N_ESCAPED],
                           c[PCL_N_CORRECTED]);
  return LSM_OK;
}
