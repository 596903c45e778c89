/* lsm_backend: where the grid work of a morph runs.
 *
 * A backend is an ops table plus a context opened once per run (for OpenCL:
 * platform, device, context, queue and the built program).  A morph asks the
 * backend for a per-pair state holding phi, phi_target and scratch, then
 * drives it through the ops: the pair and stack drivers never know which
 * backend runs.  The C backend (solver/pde/lsm_backend_c.c) is the reference; the
 * OpenCL backend (kernels/opencl/lsm_backend_cl.c) runs the same per-cell code
 * (kernels/lsm_cell.h) on a device, with the fields resident on the device
 * for the whole pair.
 *
 * Particles (--method pls).  The driver seeds them on the host
 * (solver/pde/lsm_particles.c).  A backend that keeps phi on the host (C) runs
 * them there through the stage hook of `step`; a backend with the optional
 * particle ops (OpenCL) takes a copy of the seeded set (pls_load) and then
 * advects, detects and corrects on the device, with the same per-particle
 * code (kernels/lsm_particle_cell.h).
 */
#ifndef LSM_BACKEND_H
#define LSM_BACKEND_H

#include <stdio.h>

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_names.h"
#include "solver/pde/lsm_particles.h"
#include "solver/pde/lsm_scheme.h"
#include "solver/base/lsm_status.h"

/* Add new items at the end (lsm_names.h). */
#define LSM_BACKEND_LIST(X)                                                     \
  X(LSM_BACKEND_C, "c")           /* scalar C path, OpenMP threads */           \
  X(LSM_BACKEND_OPENCL, "opencl") /* OpenCL device (PoCL on CPUs, GPUs) */      \
  X(LSM_BACKEND_AUTO, "auto")     /* OpenCL when a device is present, else C */
LSM_ENUM(lsm_backend_kind, LSM_BACKEND, LSM_BACKEND_LIST, lsm_backend_kind_name,
         lsm_backend_kind_from_name);


/* What one particle correction on a backend did (lsm_backend_ops.pls_correct);
 * the driver adds these to its lsm_pls_stats as lsm_pls_correct would. */
typedef struct lsm_pls_counts {
  long long removed;   /* removed first: left the domain in this step's stages, or
                          strays flagged by the previous correction */
  long long stray;     /* escaped by more than 1.5 max(dx,dy): flagged, removed by
                          the next correction (lsm_pls_stats.stray) */
  long long escaped;   /* escaped particles that corrected phi */
  long long corrected; /* grid values changed */
  long long live;      /* particles in the set after detection, strays included */
} lsm_pls_counts;

typedef struct lsm_backend_ops {
  const char *name;
  /* Per-pair state: copies phi_source and phi_target (same size, ghosts included). */
  lsm_status (*create)(void *ctx, const lsm_grid *phi_source, const lsm_grid *phi_target,
                       int threads, void **state, lsm_err *err);
  /* dt = cfl / max(|H1|/dx + |H2|/dy) on the current phi (METHOD.md §3.4). */
  lsm_status (*cfl_dt)(void *state, lsm_scheme scheme, double cfl, double *dt, lsm_err *err);
  /* One step of size dt with the scheme and integrator; hook (may be NULL)
   * sees each stage's input field (backends that cannot, return
   * LSM_ERR_UNSUPPORTED when hook is not NULL). */
  lsm_status (*step)(void *state, lsm_scheme scheme, lsm_time time, float dt,
                     const lsm_stage_hook *hook, lsm_err *err);
  /* Russo–Smereka reinitialisation, `iterations` pseudo-time steps. */
  lsm_status (*reinit)(void *state, int iterations, lsm_err *err);
  /* ||phi - phi_target||_2 over the interior (physical units). */
  lsm_status (*residual)(void *state, double *norm, lsm_err *err);
  /* Copies phi (interior and ghosts) into a host grid of the same size. */
  lsm_status (*download)(void *state, lsm_grid *phi, lsm_err *err);
  /* Replaces phi with a host grid of the same size (after a host-side correction). */
  lsm_status (*upload)(void *state, const lsm_grid *phi, lsm_err *err);
  /* The live host grid of phi when the backend keeps it on the host, else NULL. */
  lsm_grid *(*host_phi)(void *state);
  void (*destroy)(void **state);
  /* ---- optional: particles on the backend (NULL where absent) ----
   * pls_load: replaces the backend's particle set with a copy of `set` (all
   * live; positions as lsm_pls_view gives them), e.g. once per pair after
   * lsm_pls_create and after each host reseeding.  radius_adjust: the
   * lsm_pls_opts option.  While a non-empty set is loaded, `step` (with a NULL
   * hook) advects it at every stage exactly as lsm_pls_stage does.
   * pls_correct: lsm_pls_correct without the reseeding, on the backend's phi:
   * removal of flagged particles, detection, strays, the correction of phi
   * (Eq. 3.23-3.26), the radius adjustment; *counts says what it did.  The
   * result does not depend on the particle order. */
  lsm_status (*pls_load)(void *state, const lsm_pls_view *set, int radius_adjust, lsm_err *err);
  lsm_status (*pls_correct)(void *state, lsm_pls_counts *counts, lsm_err *err);
} lsm_backend_ops;

typedef struct lsm_backend {
  const lsm_backend_ops *ops;
  void *ctx;               /* backend-wide context, owned */
  void (*close_ctx)(void **ctx);
  char device[256];        /* what runs: "C (2 threads)", "pthread-AMD EPYC ... (PoCL)" */
  double build_seconds;    /* OpenCL program build (or cache load) time */
  int kernel_cache_hit;    /* 1 if the program came from the kernel cache */
  char fallback[LSM_ERR_MSG_MAX]; /* AUTO on C: why OpenCL could not be opened ("" otherwise) */
} lsm_backend;

/* The C backend: always available, never fails. */
const lsm_backend_ops *lsm_backend_c_ops(void);

/* Opens a backend.  kind AUTO picks OpenCL when a device can be opened and
 * C otherwise (the reason in fallback).  device is the OpenCL device index as listed by
 * lsm_backend_list_devices (-1: the first GPU, else the first device).
 * Failures (no OpenCL platform, build errors) name the device and the cause. */
lsm_status lsm_backend_open(lsm_backend_kind kind, int device, int threads, lsm_backend **out,
                            lsm_err *err);
void lsm_backend_close(lsm_backend **backend);

/* Prints the OpenCL platforms and devices with their indices; returns
 * LSM_ERR_UNSUPPORTED (with a message) when OpenCL is not available. */
lsm_status lsm_backend_list_devices(FILE *f, lsm_err *err);

/* ---- OpenCL entry points (kernels/opencl/lsm_backend_cl.c) ---- */
lsm_status lsm_backend_cl_open(int device, lsm_backend *backend, lsm_err *err);
lsm_status lsm_backend_cl_list(FILE *f, lsm_err *err);

#endif
