/* lsm_moving: a gap in the moving frame of its correspondence field (--motion field).
 *
 * The gap's field w (lsm_flows) takes A's points to B's in one unit of time.  The gap's
 * work (the two-sided morph, the rules, the z-profile) runs in the mid frame, exp(w/2): A
 * pulled forward half way, A~ = phi_A(exp(-w/2)), B pulled back, B~ = phi_B(exp(w/2)), the
 * neighbours pulled along the composed fields of their own pairs.  An output slice at
 * fraction s is then
 *   phi_s = (1 - s) phi_A(exp(-s w)) + s phi_B(exp((1 - s) w)) + D_s(exp((1/2 - s) w)),
 * A carried forward to s and B back from 1 by the flow, plus the mid frame's departure
 * D_s = m_s - ((1 - s) A~ + s B~) of the mid-frame result m_s from its own blend, carried to
 * s.  For the blend D_s = 0 and phi_s is the blend of the two carried slices; with w = 0 it
 * is the gap's plain result (solver/README.md §9).
 */
#ifndef LSM_MOVING_H
#define LSM_MOVING_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/motion/lsm_motion.h"

typedef struct lsm_moving {
  const lsm_motion_field *w; /* the gap's field (not owned) */
  lsm_grid *raw_a, *raw_b;   /* phi_A, phi_B as the slices give them */
  lsm_grid *mid_a, *mid_b;   /* A~, B~ before any rule changes them */
  lsm_motion_map half_back, half_fwd, m1, m2, m3, scratch;
  /* the cubic path (lsm_moving_tangent): per mid-frame node, the tangent at A (0) and B (1)
   * less the flow's own velocity there, cells per gap; unset: the flow's path */
  lsm_motion_map bend[2];
  int bent[2];
  int threads;
} lsm_moving;

/* Pulls phi_a and phi_b (the gap's canvas fields) into the mid frame of w, in place,
 * keeping copies of both as they were and as pulled.  On failure nothing is left to free. */
lsm_status lsm_moving_setup(lsm_moving *mv, const lsm_motion_field *w, lsm_grid *phi_a,
                            lsm_grid *phi_b, int threads, lsm_err *err);
void lsm_moving_free(lsm_moving *mv);

/* Pulls a neighbour's phi (in place) into the mid frame along the composed fields: side 0
 * the slice before A, through exp(-w_beyond) after exp(-w/2); side 1 the slice after B,
 * through exp(w_beyond) after exp(w/2).  w_beyond: the field of the pair beyond. */
lsm_status lsm_moving_pull_neighbour(lsm_moving *mv, const lsm_motion_field *w_beyond, int side,
                                     lsm_grid *phi, lsm_err *err);

/* The path's tangent at A (side 0) or B (side 1) made C1 with the pair beyond: w_beyond its
 * field, H this gap's height and H_beyond the beyond pair's.  At A the tangent is the
 * three-point slope (H v_prev + H_prev v) / (H_prev + H) of the two pairs' velocities per
 * height at the point, and the path becomes the flow plus the Hermite terms
 * h10(s) (T_A - V_A) + h11(s) (T_B - V_B) (V the flow's own velocity per gap). */
lsm_status lsm_moving_tangent(lsm_moving *mv, const lsm_motion_field *w_beyond, int side,
                              double H, double H_beyond, lsm_err *err);

/* The slice at fraction s from the mid frame's result mid (canvas size): written to out
 * (canvas size, ghosts filled); mid is used as scratch. */
void lsm_moving_carry(lsm_moving *mv, double s, lsm_grid *mid, lsm_grid *out);

#endif
