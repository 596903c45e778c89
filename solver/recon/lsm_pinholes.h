/* lsm_pinholes: holes thinner than two pixels, in the slices of a gap and in
 * its output slices.
 *
 * A pinhole of a slice (a closed outside component everywhere thinner than
 * two pixels) fits neither rule of the two-sided morph, so the morph blends
 * the two slices there (lsm_pinholes_find).  Between two slices without any
 * hole, an output slice's hole of a few pixels, each thin and inside one of
 * the two slices, was made by the morph where two parts merge, and is filled
 * (lsm_pinholes_fill).
 */
#ifndef LSM_PINHOLES_H
#define LSM_PINHOLES_H

#include <stdint.h>

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/recon/lsm_slice.h"
#include "solver/recon/lsm_stack.h"

/* What lsm_pinholes_fill needs of a gap: its two slices, scratch of width x
 * height cells, and the slices' phi in the image frame (computed at the
 * first pinhole). */
typedef struct lsm_pinhole_fill {
  const lsm_slice *a, *b;
  int32_t *cls, *queue;
  lsm_grid *phi_a, *phi_b;
} lsm_pinhole_fill;

/* Whether a slice's region has a hole: an outside component that does not
 * reach the image border.  cls and queue hold width x height cells. */
int lsm_mask_has_hole(const lsm_mask *m, int32_t *cls, int32_t *queue);

/* Fills the pinholes of out, an output slice (width x height) of the gap
 * between f->a and f->b: holes of at most o->rules.pinhole_fill_cells cells,
 * each within pinhole_fill_thin_px of the inside and inside f->a or f->b. */
lsm_status lsm_pinholes_fill(lsm_pinhole_fill *f, const lsm_stack_opts *o, int width, int height,
                             float *out, lsm_err *err);

/* The pinhole cells of a gap (lsm_two_sided), a pinhole being everywhere
 * less than thin_px pixels from the inside: *pinhole[k] = 1 where the cell is
 * outside phi_a and in one of phi_a's pinholes, or inside phi_a and in one of
 * phi_b's; *pinhole stays NULL when neither slice has one. */
lsm_status lsm_pinholes_find(const lsm_grid *phi_a, const lsm_grid *phi_b, float thin_px,
                             uint8_t **pinhole, lsm_err *err);

#endif
