/* lsm_backend: where the grid work of a morph runs, behind ops its driver cannot see through.
 *
 * A backend is a table of ops and a context opened once per run (for OpenCL: platform, device,
 * context and the built program).  For each pair the driver (lsm_fields.c, for lsm_morph) asks
 * it for a state holding phi, phi_target and scratch fields, and calls the per-stage and
 * per-sweep ops below; the Runge–Kutta tableau, the reinitialisation loop and the CFL step are
 * written once, in the driver.  As in SUNDIALS' N_Vector, some ops are required (never NULL)
 * and some optional (NULL where absent: the driver then refuses what needs them).
 *
 * Backends are chosen by name from a const table (lsm_backend_open): "c", the reference
 * (solver/pde/lsm_backend_c.c), and "opencl" (kernels/opencl/).  Their per-cell code is
 * shared (kernels/), so they give the same numbers.  What only one backend knows (its device,
 * an OpenCL program's build time) it reports as facts (ops.facts), which run.json prints.
 *
 * Cell ops act on every interior cell until the optional band ops (the narrow band,
 * lsm_band.h) restrict them to the band's cells; the ops keep their meaning over that set.
 */
#ifndef LSM_BACKEND_H
#define LSM_BACKEND_H

#include <stdio.h>

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/pde/lsm_band.h"
#include "solver/pde/lsm_particles.h"
#include "solver/pde/lsm_scheme.h"

struct lsm_motion_device; /* solver/motion/lsm_motion.h: where a registration runs */

/* The fields of a pair state that ops name; phi_target is fixed at creation. */
typedef enum lsm_field {
  LSM_FIELD_PHI,    /* the morph's working field */
  LSM_FIELD_STAGE1, /* Runge–Kutta stage, and the reinitialisation iterate */
  LSM_FIELD_STAGE2, /* the second Runge–Kutta stage (RK3) */
  LSM_FIELD_PHI0,   /* phi at the start of a reinitialisation (created by its first copy) */
  LSM_FIELD_COUNT
} lsm_field;

/* A fact a backend reports about itself: one field of run.json's "backend" object. */
typedef enum lsm_fact_kind { LSM_FACT_TEXT, LSM_FACT_NUMBER, LSM_FACT_FLAG } lsm_fact_kind;
typedef struct lsm_backend_fact {
  const char *key;   /* the run.json field name */
  lsm_fact_kind kind;
  const char *text;  /* LSM_FACT_TEXT: valid while the backend is open */
  double number;     /* LSM_FACT_NUMBER */
  int flag;          /* LSM_FACT_FLAG */
} lsm_backend_fact;
#define LSM_BACKEND_FACTS_MAX 16

typedef struct lsm_backend_ops {
  /* ---- required ------------------------------------------------------------------------
   * Run-wide: the facts, first the run.json contract "device" (text), "build_seconds"
   * (number) and "kernel_cache_hit" (flag), in this order; returns how many (<= max). */
  int (*facts)(const void *ctx, lsm_backend_fact *facts, int max);
  void (*close)(void *ctx); /* frees the context (NULL is fine) */
  /* A pair state: phi = phi_source, the target phi_target (same size; ghosts included). */
  lsm_status (*create)(void *ctx, const lsm_grid *phi_source, const lsm_grid *phi_target,
                       int threads, void **state, lsm_err *err);
  void (*destroy)(void *state); /* NULL is fine */
  /* Zero-gradient extension of a field into its ghost ring (lsm_grid_fill_ghosts). */
  lsm_status (*fill_ghosts)(void *state, lsm_field field, lsm_err *err);
  /* dst = src, ghosts included. */
  lsm_status (*copy)(void *state, lsm_field dst, lsm_field src, lsm_err *err);
  /* Exchanges two fields (no copy). */
  void (*swap)(void *state, lsm_field a, lsm_field b);
  /* One Shu–Osher stage out = c0 u0 + c1 (in - dt Hhat(in)) with the scheme's Hamiltonian;
   * in's ghosts are filled; out may be u0, never in. */
  lsm_status (*stage)(void *state, lsm_scheme scheme, lsm_field out, lsm_field u0,
                      lsm_field in, float c0, float c1, float dt, lsm_err *err);
  /* The largest CFL rate of the scheme over the cells of phi (ghosts filled;
   * kernels/lsm_cell.h, lsm_cfl_rate_of). */
  lsm_status (*max_rate)(void *state, lsm_scheme scheme, float *rate, lsm_err *err);
  /* ||phi - phi_target||_2 over the interior (physical units); finite wherever the exact sum
   * is.  Sums that decide when a pair stops are taken by the driver from read_phi. */
  lsm_status (*residual)(void *state, double *norm, lsm_err *err);
  /* One Russo–Smereka pseudo-time step out <- in, with LSM_FIELD_PHI0 the field at the start
   * (ghosts of in and phi0 filled); dtau = 0.5 min(dx, dy). */
  lsm_status (*reinit_sweep)(void *state, lsm_field out, lsm_field in, lsm_err *err);
  /* phi on the host, read-only, valid until the next op on the state: the backend's own grid
   * where phi lives on the host, else a copy this call downloads (ghosts as they are). */
  lsm_status (*read_phi)(void *state, const lsm_grid **phi, lsm_err *err);
  /* Replaces phi with a host grid of the state's size (ghosts included). */
  lsm_status (*upload)(void *state, const lsm_grid *phi, lsm_err *err);
  /* ---- optional: particles (--method pls) -------------------------------------------------
   * pls_load: replaces the state's particle set with a copy of `set` (all live), e.g. once
   * per pair after seeding and after each reseeding; radius_adjust as in lsm_pls_opts.
   * pls_stage: the particles' share of a Runge–Kutta stage whose input is `in`
   * (lsm_pls_stage; stage k of `stages`, from 0).  pls_correct: lsm_pls_correct without the
   * reseeding, on the state's phi, counted into *stats as lsm_pls_count_correction counts;
   * its result does not depend on the particle order. */
  lsm_status (*pls_load)(void *state, const lsm_pls_view *set, int radius_adjust,
                         lsm_err *err);
  lsm_status (*pls_stage)(void *state, lsm_field in, float c0, float c1, float dt, int stage,
                          int stages, lsm_err *err);
  lsm_status (*pls_correct)(void *state, lsm_pls_stats *stats, lsm_err *err);
  /* ---- optional: the narrow band (all or none) --------------------------------------------
   * band_set: from now on stage, max_rate, residual and reinit_sweep act on the cells of the
   * band's runs only, and fill_rim on its rim (lists' arrays stay valid until the next
   * band_set or destroy; the enter lists are not read).  band_write: field[cells[q]] =
   * values[q].  fill_rim: field at each rim cell = lsm_relaxed(phi_target, its amplitude, g). */
  lsm_status (*band_set)(void *state, const lsm_band_lists *lists, lsm_err *err);
  lsm_status (*band_write)(void *state, lsm_field field, const int32_t *cells,
                           const float *values, size_t n, lsm_err *err);
  lsm_status (*fill_rim)(void *state, lsm_field field, float g, lsm_err *err);
  /* ---- optional: the correspondence field (--motion field) ---------------------------------
   * motion: *dev = this backend as the runner of the registration's levels (run-wide, on
   * ctx; solver/motion/lsm_motion.h).  Absent: the registration runs on the host. */
  void (*motion)(void *ctx, struct lsm_motion_device *dev);
} lsm_backend_ops;

/* One row of the table of backends. */
typedef struct lsm_backend_entry {
  int host_threads;          /* 1: the cell loops run on the host's threads */
  /* Opens the run-wide context; device: an index of list_devices (-1: the default). */
  lsm_status (*open)(int device, int threads, void **ctx, lsm_err *err);
  /* Optional: prints the devices with their indices. */
  lsm_status (*list_devices)(FILE *f, lsm_err *err);
  const lsm_backend_ops *ops;
} lsm_backend_entry;

/* The table of backends, X(name, row): --backend NAME and run.json's backend.name; the C
 * reference first.  lsm_backend.c builds the table from it, the command line its names
 * (LSM_BACKEND_NAME, then "auto"). */
#define LSM_BACKEND_TABLE(X)                                                   \
  X("c", lsm_backend_c_entry)           /* solver/pde/lsm_backend_c.c */      \
  X("opencl", lsm_backend_opencl_entry) /* kernels/opencl/lsm_backend_cl.c */
#define LSM_BACKEND_NAME(name, row) name,
#define LSM_BACKEND_ROW_DECL(name, row) extern const lsm_backend_entry row;
LSM_BACKEND_TABLE(LSM_BACKEND_ROW_DECL)

/* An open backend: read it through the functions below. */
typedef struct lsm_backend {
  const char *name;
  const lsm_backend_entry *entry;
  void *ctx;                      /* the backend's run-wide context, owned */
  char fallback[LSM_ERR_MSG_MAX]; /* "auto" on the reference: why no other opened */
} lsm_backend;

/* The row named `name`, or NULL. */
const lsm_backend_entry *lsm_backend_find(const char *name);
/* "c, opencl, auto": the names lsm_backend_open takes. */
void lsm_backend_names(char *buf, size_t size);

/* Opens the backend named `name`, or with "auto" the first of the others in table order that
 * opens, else the reference (fallback then says why the last one failed).  device: the
 * device index of that backend's list (-1: its default).  Errors: LSM_ERR_USAGE for an
 * unknown name; an opening's own (no OpenCL platform, a missing device, a build error). */
lsm_status lsm_backend_open(const char *name, int device, int threads, lsm_backend **out,
                            lsm_err *err);
void lsm_backend_close(lsm_backend **backend);

const char *lsm_backend_name(const lsm_backend *backend);
/* Why "auto" runs on the reference ("" otherwise). */
const char *lsm_backend_fallback(const lsm_backend *backend);
/* 1 when the backend's cell loops run on the host's threads (the reference). */
int lsm_backend_host_threads(const lsm_backend *backend);
/* The backend's facts (ops.facts); lsm_backend_device: the "device" fact's text. */
int lsm_backend_facts(const lsm_backend *backend, lsm_backend_fact *facts, int max);
const char *lsm_backend_device(const lsm_backend *backend);

/* Fills *dev with where the backend runs the correspondence field's registration and
 * returns 1; 0 (dev untouched) where it has no motion op or backend is NULL: the host. */
int lsm_backend_motion(const lsm_backend *backend, struct lsm_motion_device *dev);

/* For a backend's facts op: the run.json contract's three facts, device (text), build_seconds
 * (the kernel program's build) and kernel_cache_hit (false: lsmorph keeps no kernel cache),
 * into facts[0 .. max); returns how many. */
int lsm_backend_contract_facts(lsm_backend_fact *facts, int max, const char *device,
                               double build_seconds);

/* Prints the devices of every backend that has them; LSM_ERR_UNSUPPORTED (with a message)
 * when none can list any. */
lsm_status lsm_backend_list_devices(FILE *f, lsm_err *err);

#endif
