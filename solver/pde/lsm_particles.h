/* lsm_particles: the particle level set (PLS) correction of the morph
 * (solver/README.md §11; the design document's Algorithms 3.2 and 3.3,
 * Eq. 3.15–3.26; Enright, Fedkiw, Ferziger & Mitchell 2002).
 *
 * Marker particles are seeded in a band around the zero level of phi_0,
 * attracted to their side of it, advected with the front, and used after each
 * level-set step to repair phi where the grid has lost the interface.
 *
 * Units and coordinates.  Particle positions are CELL coordinates: x = column,
 * y = row, continuous, cell centres at integers, the domain is
 * [0, nx-1] x [0, ny-1].  phi, radii and distances are physical (dx, dy).
 *
 * Velocity convention.  The morph solves phi_t + F |grad phi| = 0 with
 * F = phi - phi_target and phi > 0 outside, so the front moves along the
 * outward normal N = grad phi / |grad phi| with normal speed F; a particle
 * rides along by dt * F * N (Eq. 3.20–3.21).  Where the source lies outside
 * the target (phi_target > 0 on phi's zero level) F < 0 and particles move
 * inward.
 *
 * Determinism.  Random numbers come from a counter-based hash of (seed,
 * seeding generation, cell, particle, draw) (kernels/lsm_particle_cell.h);
 * every per-particle loop writes only its own particle, compaction and the
 * grid correction run serially in particle order.  Results are bit-identical
 * for any thread count.
 *
 * Storage.  Structure of arrays (x, y, sign, radius, ...), one allocation per
 * array, grown geometrically only when a reseeding needs more room; discarded
 * particles are removed by in-order compaction.
 *
 * Typical step (see lsm_pls_stage for Runge–Kutta):
 *     lsm_pls_begin_step(p, stages);
 *     lsm_pls_stage(p, phi_n, target, 0, 1, dt, err); (same stages as the grid)
 *     ... grid step phi_n -> phi_{n+1} ...
 *     lsm_pls_correct(p, phi_{n+1}, err);
 */
#ifndef LSM_PARTICLES_H
#define LSM_PARTICLES_H

#include <stddef.h>
#include <stdint.h>

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"

typedef struct lsm_pls_opts {
  int particles_per_cell; /* default 16 (Alg. 3.2): ceil(n/2) positive, floor(n/2) negative */
  int reseed_every;       /* reseed every N corrections; 0 = never (default, the document) */
  int radius_adjust;      /* 1: reset radii after each correction (Enright et al.);
                             0 = off (default, the document) */
  uint64_t seed;          /* random seed (default LSM_PLS_DEFAULT_SEED) */
  int threads;            /* OpenMP threads (>= 1); 1 is used below LSM_PLS_MIN_PARALLEL particles */
  int skip_attraction;    /* 1: seed only (particles stay where drawn, radius from phi
                             there); for tests and diagnostics.  Default 0 */
} lsm_pls_opts;

#define LSM_PLS_DEFAULT_SEED 20130101u
/* Particle loops run on one thread below this many particles. */
#define LSM_PLS_MIN_PARALLEL 20000

/* Fills o with the defaults above (threads = 1, skip_attraction = 0). */
void lsm_pls_opts_default(lsm_pls_opts *o);

/* Counters, cumulative since lsm_pls_create unless named _last.  At any time
 * outside a step (i.e. not between lsm_pls_stage and lsm_pls_correct)
 *   lsm_pls_count() == seeded - discarded - left_domain - reseed_dropped. */
typedef struct lsm_pls_stats {
  long long seeded;          /* particles placed by all seedings (creation + reseedings) */
  long long discarded;       /* removed by attraction failure (still outside their band after 10 iterations) */
  long long left_domain;     /* removed because advection took them out of [0,nx-1]x[0,ny-1],
                                or because they escaped by more than 1.5 max(dx,dy) (see stray) */
  long long stray;           /* of those, escaped too far to mark the interface */
  long long reseed_dropped;  /* live particles removed when reseeding */
  long long escaped_total;   /* escaped particles found, summed over corrections */
  long long corrected_total; /* grid values changed by corrections, summed */
  long long escaped_last;    /* escaped particles in the last correction */
  long long corrected_last;  /* grid values changed by the last correction */
  long long band_cells;      /* grid cells seeded by the latest seeding */
  int steps;                 /* corrections done (one per level-set step) */
  int reseeds;               /* reseedings done (not counting creation) */
} lsm_pls_stats;

typedef struct lsm_particles lsm_particles;

/* Seeds particles on phi0 (Algorithm 3.2) and attracts them to their bands:
 *  - every grid cell (square between nodes (i,j)..(i+1,j+1)) with a corner at
 *    |phi0| < 3 max(dx,dy) gets o->particles_per_cell particles, uniformly at
 *    random in the cell, the first ceil(n/2) of sign +1, the rest -1;
 *  - each particle draws phi_goal uniform in [v_min, v_max] (s = +1) or
 *    [-v_max, -v_min] (s = -1), v_min = 0.1 min(dx,dy), v_max = 3 max(dx,dy),
 *    and iterates up to 10 times p <- p + lambda (phi_goal - phi(p)) N(p)
 *    (per axis divided by dx or dy), lambda = 1 halved while the new point
 *    leaves the domain (at most 30 halvings, then clamped); it stops after
 *    the first move that lands phi(p) in its band (at least one move is made,
 *    as in the document), and is discarded (stats.discarded) if none of the
 *    10 does;
 *  - radius r = clamp(s phi(p), r_min, r_max), r_min = 0.1 min(dx,dy),
 *    r_max = 0.5 min(dx,dy).
 * Particles are stored cell by cell in row-major cell order, slot order within
 * a cell; discarding keeps that order.  With o->skip_attraction the particles
 * stay where they were drawn (the radius is still clamp(s phi(p), ...)).
 * phi0's ghosts are not read.  o may be NULL (defaults).  A grid narrower than
 * 2 nodes in x or y has no cells: the set is created empty.
 * Errors: LSM_ERR_USAGE (particles_per_cell < 1 or > 1024, reseed_every < 0),
 * LSM_ERR_LIMIT, LSM_ERR_NOMEM. */
lsm_status lsm_pls_create(const lsm_grid *phi0, const lsm_pls_opts *o, lsm_particles **out,
                          lsm_err *err);

/* An empty set on a grid like `like` (the same checks as lsm_pls_create), to be
 * filled by lsm_pls_set: a backend's copy of a seeded set. */
lsm_status lsm_pls_create_empty(const lsm_grid *like, const lsm_pls_opts *o, lsm_particles **out,
                                lsm_err *err);

/* Frees the set and sets *p to NULL (NULL and *p == NULL are fine). */
void lsm_pls_destroy(lsm_particles **p);

/* Starts a level-set step of `stages` Runge–Kutta stages (Euler 1, RK2 2,
 * RK3 3).  Call once per step, before its first lsm_pls_stage.  With more
 * than one stage, the first stage saves the start positions as the base
 * x_u0 of the later ones; Euler needs no copy. */
void lsm_pls_begin_step(lsm_particles *p, int stages);

/* One Runge–Kutta stage, the particle twin of lsm_scheme_stage:
 *   x_out = c0 * x_u0 + c1 * (x_in + dt * F(x_in) N(x_in))
 * per particle, where x_in is the particle's current position (the result of
 * the previous stage, or the step's start), F = phi - phi_target and
 * N = grad phi/|grad phi| are interpolated from 'in' (the stage's INPUT
 * field, the same 'in' lsm_scheme_stage gets) and phi_target (N = (1,1)/sqrt2
 * where grad phi = 0), and the displacement is converted to cells (x by dx,
 * y by dy).  Call with the same c0, c1, dt as the grid stage:
 *   Euler: (0, 1);   RK2: (0, 1), (1/2, 1/2);   RK3: (0, 1), (3/4, 1/4), (1/3, 2/3).
 * A particle whose new position leaves the domain is clamped to it and marked;
 * lsm_pls_correct removes it (stats.left_domain).  Ghost cells are not read,
 * so this may run before or after the grid stage as long as 'in' still holds
 * the stage's input.  Errors: LSM_ERR_NOMEM (the grid-sized scratch, allocated
 * on first use). */
lsm_status lsm_pls_stage(lsm_particles *p, const lsm_grid *in, const lsm_grid *phi_target,
                         float c0, float c1, float dt, lsm_err *err);

/* After a level-set step: removes particles that left the domain, then the
 * correction of Algorithm 3.3 on phi in place (the document's smoothed
 * variant, Eq. 3.23–3.26):
 *  - a particle has escaped if sign(phi(p)) != s and |phi(p)| > r;
 *  - for each escaped particle and each corner v of its cell, with d = |v - p|
 *    physical: phi_p(v) = s r - d if phi(v) <= 0, s r + d otherwise;
 *    phi_plus(v) = max(phi_plus(v), phi_p(v)) for s = +1,
 *    phi_minus(v) = min(phi_minus(v), phi_p(v)) for s = -1 (both start as phi);
 *  - at every touched corner phi(v) = phi_plus(v) if |phi_plus| <= |phi_minus|,
 *    else phi_minus(v).
 * Then, per options, radius adjustment (particles on their own side get
 * r = clamp(s phi(p), r_min, r_max) on the corrected phi) and, every
 * reseed_every corrections, reseeding (all particles dropped and seeded again
 * on the corrected phi, as lsm_pls_create does).  Refills phi's ghosts.
 * phi must have the size of the grid the set was created on.
 * Errors: LSM_ERR_INTERNAL (phi's size differs from the seeding grid;
 * nothing is done), LSM_ERR_NOMEM / LSM_ERR_LIMIT when a reseeding cannot grow
 * the arrays (the set is then left empty, phi is corrected). */
lsm_status lsm_pls_correct(lsm_particles *p, lsm_grid *phi, lsm_err *err);

/* lsm_pls_correct without the reseeding, counted into *stats (the set's own
 * counters are left as they are): a backend's correction of a set whose
 * seeding its driver does. */
lsm_status lsm_pls_correct_into(lsm_particles *p, lsm_grid *phi, lsm_pls_stats *stats,
                                lsm_err *err);

/* How a correction counts (every backend's): `removed` particles left the
 * domain (in the step's stages, or strays flagged by the previous
 * correction), `strays` flagged now, `escaped` escaped ones corrected
 * `corrected` grid values; one step more. */
void lsm_pls_count_correction(lsm_pls_stats *stats, long long removed, long long strays,
                              long long escaped, long long corrected);

/* Drops every particle and seeds the next generation on phi (the reseeding
 * lsm_pls_correct does every reseed_every steps; also for a set whose
 * particles live on a backend).  Counts reseed_dropped and reseeds.
 * Errors: as lsm_pls_create (LSM_ERR_LIMIT, LSM_ERR_NOMEM), and
 * LSM_ERR_INTERNAL when phi is not the set's grid size. */
lsm_status lsm_pls_reseed(lsm_particles *p, const lsm_grid *phi, lsm_err *err);

/* Counters (valid until the set is destroyed). */
const lsm_pls_stats *lsm_pls_stats_get(const lsm_particles *p);

/* Number of particles now. */
size_t lsm_pls_count(const lsm_particles *p);

/* Read-only views of the particle arrays (lsm_pls_count entries each; valid
 * until the next call that changes the set): positions in cells, sign
 * (+1/-1), radius (physical).  For tests, output and plotting. */
typedef struct lsm_pls_view {
  size_t n;
  const float *x, *y, *radius;
  const int8_t *sign;
} lsm_pls_view;
lsm_pls_view lsm_pls_view_get(const lsm_particles *p);

/* Replaces the particle set with n given particles (positions in cells, signs
 * +1/-1, radii physical), clamping positions to the domain; the counters are
 * kept.  For tests and for restoring a saved state.
 * Errors: LSM_ERR_USAGE (a sign other than +-1, a non-finite value, n > 0 on
 * a grid with fewer than 2 nodes along x or y),
 * LSM_ERR_NOMEM, LSM_ERR_LIMIT. */
lsm_status lsm_pls_set(lsm_particles *p, size_t n, const float *x, const float *y,
                       const int8_t *sign, const float *radius, lsm_err *err);

#endif
