/* lsm_gap: the working fields of one gap.
 *
 * phi_A and phi_B on the gap's padded canvas (lsm_frame), each slice centred
 * by its own shift; the parts that moved between them, taken out and moved
 * on their own (lsm_parts); the parts with no counterpart, capped
 * (lsm_unmatched); and for the cubic profile the per-pixel slopes
 * (lsm_zprofile).  Where one side is empty it stands for the constant the
 * halfway rule gives it.
 */
#ifndef LSM_GAP_H
#define LSM_GAP_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/recon/lsm_flows.h"
#include "solver/recon/lsm_frame.h"
#include "solver/recon/lsm_moving.h"
#include "solver/recon/lsm_parts.h"
#include "solver/recon/lsm_slice.h"
#include "solver/recon/lsm_stack.h"

typedef struct lsm_gap {
  lsm_frame f;
  lsm_grid *phi_a, *phi_b;
  lsm_grid *slope_a, *slope_b; /* cubic: H dphi/dz at A and B (NULL for linear) */
  /* parts that moved (lsm_parts): each pair's phi on a window of the image
   * around the part (origin part_ax, part_ay / part_bx, part_by), and the
   * shift from A's part to B's; phi_a and phi_b then hold the rest */
  int parts;
  lsm_grid *part_a[LSM_PARTS_MAX], *part_b[LSM_PARTS_MAX];
  int part_ax[LSM_PARTS_MAX], part_ay[LSM_PARTS_MAX], part_bx[LSM_PARTS_MAX], part_by[LSM_PARTS_MAX];
  double part_dx[LSM_PARTS_MAX], part_dy[LSM_PARTS_MAX];
  int rest_empty; /* every part of both slices moved: the rest is empty */
  /* --motion field: phi_a, phi_b (and the neighbours read by the rules and the slopes) in
   * the mid frame of the gap's field; each output slice carried to its place (lsm_moving) */
  lsm_choice choice; /* whether the pair takes the field (lsm_flows_choice; 0 without flows) */
  int moving;
  lsm_moving mv;
  lsm_grid *carried; /* an output slice carried to its fraction, on the canvas */
} lsm_gap;

/* Sets up the gap between w->s[1] (A) and w->s[2] (B) of width x height
 * slices; flows: the run's fields (NULL: in place), threads for their maps.  On failure
 * nothing is left to free. */
lsm_status lsm_gap_setup(const lsm_stack_opts *o, int width, int height, const lsm_window *w,
                         lsm_flows *flows, int threads, lsm_gap *g, lsm_err *err);

/* The output slice at fraction s from the gap's working result `mix` (canvas): carried to
 * its place in the moving frame (mix is then scratch), else mix itself. */
const lsm_grid *lsm_gap_carry(lsm_gap *g, double s, lsm_grid *mix);
void lsm_gap_free(lsm_gap *g);

/* Adds the moving parts to an output slice at fraction s (union: min). */
void lsm_gap_paste_parts(const lsm_gap *g, double s, float *out);

#endif
