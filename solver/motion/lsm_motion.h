/* lsm_motion: the correspondence field of a slice pair, and its maps.
 *
 * Between two slices A and B (signed distances on a gap's canvas) a stationary velocity
 * field w from a symmetric, diffeomorphic registration: log-domain symmetric demons on the
 * two distances clipped to a band, coarse to fine (solver/README.md §9).  The point of A at
 * p moves along the flow of w and reaches B at exp(w)(p) after one unit of time (the whole
 * gap); the mid frame, where the morph runs, is exp(w/2).  The field lives on a node grid
 * coarser than the pixels (it is smooth on the scale of its smoothing); its maps
 * (exponentials, compositions) are computed there and read at the pixels bilinearly.
 *
 * The per-node arithmetic is kernels/lsm_motion_cell.h, which the OpenCL path shares.
 */
#ifndef LSM_MOTION_H
#define LSM_MOTION_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"

#define LSM_MOTION_LEVELS_MAX 4

/* One pyramid level of the registration, as lsm_motion_register hands it to where it runs:
 * node grids of nx x ny floats, row-major.  Each iteration: P = exp(w/2), M = exp(-w/2),
 * a' = A(M), b' = B(P), the demons update u (lsm_motion_demons) smoothed with ku, w += u,
 * w smoothed with kw; the level stops after `iterations` or where lsm_motion_level_stops
 * says so. */
typedef struct lsm_motion_level {
  int nx, ny;
  float hx, hy, clip;     /* node spacing (physical), the distances' clip */
  const float *a, *b;     /* the two slices' distances at the nodes, clipped */
  float *wx, *wy;         /* the field: in, the start (upsampled); out, the result */
  const float *ku, *kw;   /* Gaussian taps of the update's and the field's smoothing */
  int ru, rw;             /* their radii (0: no smoothing) */
  int iterations;         /* at most (<= LSM_MOTION_ITERATIONS_MAX) */
  int stop_window;
  double stop_drop;
} lsm_motion_level;
#define LSM_MOTION_ITERATIONS_MAX 512

/* Where the levels run: a backend's device (kernels/opencl/lsm_cl_motion.c), given by the
 * backend's optional `motion` op (lsm_backend_motion).  run_level NULL: on the host. */
typedef struct lsm_motion_device {
  void *ctx;
  /* Runs lv's iterations (the same numbers as the host's; lv->wx, wy updated); *taken:
   * how many. */
  lsm_status (*run_level)(void *ctx, const lsm_motion_level *lv, int *taken, lsm_err *err);
} lsm_motion_device;

/* The registration's constants (lsm_motion_params_default; their derivations and
 * ablations: solver/README.md §9, validation/measurements/motion.md). */
typedef struct lsm_motion_params {
  int levels;                            /* pyramid levels, coarse to fine */
  int step[LSM_MOTION_LEVELS_MAX];       /* node spacing of each level, pixels */
  int iterations[LSM_MOTION_LEVELS_MAX]; /* most iterations of each level */
  double clip_nodes;      /* distances clipped to +- this many node spacings of the level */
  double sigma_update_px; /* Gaussian smoothing of each update (fluid-like), pixels */
  double sigma_field_px;  /* Gaussian smoothing of the field after each update, pixels */
  int stop_window;        /* a level stops when the mean squared mismatch fell by less */
  double stop_drop;       /* than stop_drop (a share) over the last stop_window iterations */
  lsm_motion_device device; /* where the levels run (default: zeroed, the host) */
} lsm_motion_params;

void lsm_motion_params_default(lsm_motion_params *p);

/* A stationary velocity field on a node grid over a canvas of cnx x cny cells: node (I, J)
 * at canvas cell (I step, J step); components in node units per gap. */
typedef struct lsm_motion_field {
  int nx, ny, step;
  int cnx, cny;
  float *vx, *vy;
  /* what the registration did (run.json) */
  int iterations;          /* at all levels */
  double seconds;          /* its wall time */
  double max_displacement; /* largest |exp(w)(p) - p| over the nodes, pixels */
} lsm_motion_field;

/* Registers phi_b to phi_a (two grids of the same size and spacing, physical units):
 * *out = the field w with exp(w) taking A's points to B's.  Slices with no boundary (an
 * empty or full slice: phi beyond the band everywhere) give w = 0.  threads: for the
 * node loops (the result does not depend on it). */
lsm_status lsm_motion_register(const lsm_grid *phi_a, const lsm_grid *phi_b,
                               const lsm_motion_params *p, int threads, lsm_motion_field **out,
                               lsm_err *err);
/* Shared by the host and the devices (the decisions, taken on the host in double):
 * lsm_motion_squarings: K, the squarings of exp(t v) whose largest lsm_motion_norm2 over
 * the nodes is most2 (each of the 2^K steps within half a node); *scale = t / 2^K.
 * lsm_motion_mismatch: the sum of r2 and of the active flags c over the nodes, each row in
 * double, then the rows in order (the same for any thread count or work-group shape).
 * lsm_motion_level_stops: records iteration it's mean squared mismatch in history; 1 when
 * the level stops there (no active node, or a drop below stop_drop over stop_window). */
int lsm_motion_squarings(float most2, float t, float *scale);
void lsm_motion_mismatch(const float *r2, const float *c, int nx, int ny, double *sum,
                         double *count);
int lsm_motion_level_stops(const lsm_motion_level *lv, double *history, int it, double sum,
                           double count);

/* A zero field over the canvas of phi (the identity maps). */
lsm_status lsm_motion_field_zero(const lsm_grid *phi, int step, lsm_motion_field **out,
                                 lsm_err *err);
/* A copy of f. */
lsm_status lsm_motion_field_clone(const lsm_motion_field *f, lsm_motion_field **out,
                                  lsm_err *err);
void lsm_motion_field_destroy(lsm_motion_field **f);

/* A map x -> x + d(x) on a field's node grid (d in node units). */
typedef struct lsm_motion_map {
  int nx, ny, step;
  float *dx, *dy;
} lsm_motion_map;

lsm_status lsm_motion_map_create(const lsm_motion_field *f, lsm_motion_map *m, lsm_err *err);
void lsm_motion_map_free(lsm_motion_map *m);
/* *m = exp(t w), by scaling and squaring (w / 2^K with K the smallest keeping every node's
 * step within half a node, then K squarings).  scratch: a map of the same grid. */
void lsm_motion_exp(const lsm_motion_field *f, double t, lsm_motion_map *m,
                    lsm_motion_map *scratch, int threads);
/* out = second after first: x -> x + d1(x) + d2(x + d1(x)); out may not alias the others. */
void lsm_motion_compose(const lsm_motion_map *first, const lsm_motion_map *second,
                        lsm_motion_map *out, int threads);
/* The displacement of m at canvas cell (x, y), in cells (bilinear between nodes). */
void lsm_motion_map_at(const lsm_motion_map *m, float x, float y, float *dx, float *dy);
/* dst(x) = src(x + m(x)) over the interior of dst (same size as src), bilinear, clamped to
 * src's interior; ghosts filled. */
void lsm_motion_pull(const lsm_grid *src, const lsm_motion_map *m, lsm_grid *dst, int threads);
/* The velocity of f at canvas cell (x, y), cells per gap. */
void lsm_motion_velocity_at(const lsm_motion_field *f, float x, float y, float *vx, float *vy);

#endif
