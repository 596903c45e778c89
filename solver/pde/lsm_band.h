/* lsm_band: the narrow band of a pair morph, kept on the host (solver/README.md §4, "The
 * narrow band").
 *
 * The band holds the cells the morph updates: every cell within `travel + reach` cells
 * (4-neighbour steps) of the kept levels L = {|phi| <= level} and of every sign change, widened
 * to whole aligned row segments of LSM_BAND_SEGMENT cells, so that the cell loops of both
 * backends run over the same contiguous runs.  The rim (cells within `reach` of the band,
 * outside it) is what the band's stencils read across its edge.  A cell outside the band
 * holds phi = phi_target + a g: its amplitude a (phi_source - phi_target to begin with, the
 * band's value relaxed back when the band leaves it) times g, the integrator's relaxation
 * factor of a cell where phi is a distance (lsm_fields tracks g).  A cell enters the band
 * when the band reaches it, or when that value comes within `level` of zero (nucleation):
 * lsm_band_next_g says at which g the next one does.
 */
#ifndef LSM_BAND_H
#define LSM_BAND_H

#include <stddef.h>
#include <stdint.h>

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/pde/lsm_scheme.h"

/* The band's cell loops run over aligned row segments of this many cells (the C sweeps'
 * vectors, the OpenCL work-items of a segment). */
#define LSM_BAND_SEGMENT 8

/* The band's widths (solver/README.md §4, "The narrow band"). */
typedef struct lsm_band_params {
  float level; /* the levels kept, |phi| <= level (physical units) */
  int reach;   /* the scheme's stencil reach (cells) */
  int travel;  /* cells a level may move between rebuilds */
} lsm_band_params;

/* The widths for a scheme on cells dx x dy. */
void lsm_band_params_of(lsm_scheme scheme, float dx, float dy, lsm_band_params *params);
/* Cells the scheme's stencil reads on each side along an axis (1, Roe-Fix 4, WENO5 3). */
int lsm_scheme_reach(lsm_scheme scheme);

typedef struct lsm_band lsm_band;

/* What the backend needs after a (re)build; valid until the next rebuild or destroy.  Cell
 * offsets are from cell (0, 0) of a grid laid out as phi (j stride + i). */
typedef struct lsm_band_lists {
  const int32_t *run_start, *run_length; /* the band: runs of cells along rows, row-major */
  size_t runs;
  size_t cells;                          /* cells in the runs */
  const int32_t *rim;                    /* the rim's cells, row-major, and their amplitudes */
  const float *rim_amplitude;
  size_t rim_cells;
  const int32_t *enter;                  /* cells that entered the band, and their values */
  const float *enter_value;
  size_t entered;
  int edge;                              /* the band's stencils reach the ghost ring */
} lsm_band_lists;

/* The band of phi_source (its ghosts filled), relaxing towards phi_target (same size,
 * borrowed: it must outlive the band). */
lsm_status lsm_band_create(const lsm_grid *phi_source, const lsm_grid *phi_target,
                           const lsm_band_params *params, lsm_band **out, lsm_err *err);
void lsm_band_destroy(lsm_band **band);

/* Rebuilds the band around phi at relaxation factor g: phi's band cells hold the morph, its
 * rim and ghost cells their values (the backend's fill_rim, fill_ghosts).  Cells leaving the band keep their value as amplitude
 * (phi - phi_target) / g; cells entering take phi_target + a g (lists.enter). */
lsm_status lsm_band_rebuild(lsm_band *band, const lsm_grid *phi, double g, lsm_err *err);

lsm_band_lists lsm_band_get(const lsm_band *band);

/* The largest |phi - phi_target| on the band when it was built: no level in it moves faster
 * until the next rebuild (solver/README.md §4). */
float lsm_band_speed(const lsm_band *band);
/* The largest |phi - phi_target| of the cells that entered the band at the last rebuild. */
float lsm_band_enter_speed(const lsm_band *band);

/* The relaxation factor at or below which a cell outside the band comes within the kept
 * levels (a front may appear there: rebuild); 0 when none will. */
double lsm_band_next_g(const lsm_band *band);

/* out = phi on the band, phi_target + a g elsewhere (interior; ghosts are not touched). */
void lsm_band_materialize(const lsm_band *band, const lsm_grid *phi, double g, lsm_grid *out,
                          int threads);

/* Multiplies every amplitude by factor (the driver rescales g when it grows small). */
void lsm_band_rescale(lsm_band *band, double factor);

#endif
