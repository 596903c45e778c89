/* lsm_morph: the level-set metamorphosis of one slice pair (solver/README.md §2, §4).
 *
 * A morph owns the pair's fields on a backend (lsm_fields: phi, starting as
 * phi_source, the target phi_target and the scratch) and advances
 *     phi_t + (phi - phi_target) |grad phi| = 0
 * with a fixed step dt = cfl / max(|H1|/dx + |H2|/dy) computed once from
 * phi_source; with reinitialisation the bound is taken again after each one,
 * and dt shrinks if it must.  With the narrow band (opts.band) only the band's
 * cells are updated and the maximum is the band's, taken again at each
 * rebuild (dt only shrinks, and stays <= 1).  With particles it seeds them on the host and
 * has the backend step and correct them.  The pair and stack drivers decide
 * when to stop and what to keep; the morph only steps.
 */
#ifndef LSM_MORPH_H
#define LSM_MORPH_H

#include <signal.h>

#include "solver/pde/lsm_backend.h"
#include "solver/base/lsm_grid.h"
#include "solver/pde/lsm_particles.h"
#include "solver/pde/lsm_scheme.h"
#include "solver/base/lsm_status.h"

typedef struct lsm_morph_opts {
  lsm_scheme scheme;  /* spatial scheme (default upwind) */
  lsm_time time;      /* integrator (default euler) */
  double cfl;         /* CFL number (default 0.75, §3.4) */
  int reinit_every;   /* reinitialise every N steps; 0 = never (the document) */
  int reinit_iters;   /* pseudo-time iterations per reinitialisation (default 10) */
  int threads;        /* OpenMP threads for the cell loops (>= 1) */
  int track_cp;       /* compute CP after every step (per-iteration mode); otherwise the
                         residual is checked every 16 steps, for NaN/Inf detection */
  int particles;      /* 1: particle level set correction (Enright et al. 2002) */
  lsm_pls_opts pls;   /* particle options (lsm_pls_opts_default) */
  const lsm_backend *backend; /* where the grid work runs; NULL = the C backend */
  int band;           /* 1: the narrow band (the default; solver/README.md §4): only cells near
                         the front are updated, dt from the band's speeds; 0: every cell */
  /* When not NULL: lsm_morph_advance_to stops with LSM_ERR_INTERRUPTED before
   * any step once *stop is non-zero (a signal handler's flag), so a long gap
   * does not run to its end after Ctrl-C. */
  const volatile sig_atomic_t *stop;
} lsm_morph_opts;

void lsm_morph_opts_default(lsm_morph_opts *opts);

typedef struct lsm_morph lsm_morph;

/* Copies phi_source and phi_target (same size) and computes dt. */
lsm_status lsm_morph_create(const lsm_grid *phi_source, const lsm_grid *phi_target,
                            const lsm_morph_opts *opts, lsm_morph **out, lsm_err *err);
void lsm_morph_destroy(lsm_morph **morph);

/* One step of size min(dt, max_dt).  Updates the iteration count, the time and
 * the convergence measure CP (§3.7).  Fails with LSM_ERR_NUMERIC when phi
 * stops being finite. */
lsm_status lsm_morph_step(lsm_morph *morph, double max_dt, lsm_err *err);

/* Steps until the time reaches t (the last step shortened to land on t
 * exactly), or max_iter steps in all have been taken (then returns LSM_OK with
 * the time short of t: check lsm_morph_time).  A morph at rest (dt infinite:
 * nothing can move) reaches t at once, with no step. */
lsm_status lsm_morph_advance_to(lsm_morph *morph, double t, int max_iter, lsm_err *err);

/* The current phi on the host (downloaded from the device when the backend
 * keeps it there).  NULL if the download failed: lsm_morph_error tells why. */
const lsm_grid *lsm_morph_phi(lsm_morph *morph);
const lsm_grid *lsm_morph_target(const lsm_morph *morph);
const lsm_err *lsm_morph_error(const lsm_morph *morph);
/* Particle statistics, or NULL without particles. */
const lsm_pls_stats *lsm_morph_pls_stats(const lsm_morph *morph);
double lsm_morph_time(const lsm_morph *morph);
double lsm_morph_dt(const lsm_morph *morph);
int lsm_morph_iterations(const lsm_morph *morph);
/* CP of the last step: | ||phi^n - phi_T||_2 - ||phi^{n-1} - phi_T||_2 |
 * (Frobenius norms over the grid, physical units); +INFINITY before a step. */
double lsm_morph_cp(const lsm_morph *morph);
/* ||phi - phi_T||_2 now. */
double lsm_morph_residual(const lsm_morph *morph);
/* Cell updates so far (cells swept by each stage, summed), and whether the band is on. */
long long lsm_morph_cell_updates(const lsm_morph *morph);
/* Cells of the grid (the full grid's cells per stage). */
long long lsm_morph_grid_cells(const lsm_morph *morph);
int lsm_morph_banded(const lsm_morph *morph);

/* Morph time at which a pair is a fraction s in [0, 1) of the way:
 *   t(s) = -ln(1 - s).
 * While phi stays a signed distance function the morph relaxes exponentially,
 * phi(t) = phi_T + (phi_0 - phi_T) e^{-t}, so concentric circles r1 -> r2 have
 * front radius r2 + (r1 - r2)(1 - s): straight cone walls, uniform in z. */
double lsm_morph_time_of_fraction(double s);

#endif
