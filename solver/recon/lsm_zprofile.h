/* lsm_zprofile: the monotone cubic z-profile (--interp cubic) through the
 * four nearest slices, per pixel.
 *
 * Per pixel, the PCHIP slopes m_A, m_B of phi in z at A and B come from the
 * neighbouring slices (lsm_zprofile_slopes).  An output slice at fraction s
 * is the linear interpolant (blend) or the morph, plus the cubic's departure
 * from the straight line (lsm_zprofile_add_cubic); for the morph, the
 * morph's own departure from the straight line is first weighted by omega(s)
 * (lsm_zprofile_weight), so the profile is C1 across slices.
 */
#ifndef LSM_ZPROFILE_H
#define LSM_ZPROFILE_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/recon/lsm_rules.h"
#include "solver/recon/lsm_slice.h"

/* The per-pixel slopes at A and B of the gap w (height H, fields phi_a,
 * phi_b) times H, into *slope_a and *slope_b (allocated; the caller frees
 * them, also on failure).  beyond[0], beyond[1]: phi of the non-empty
 * neighbours prev and next in A's and B's frame, or NULL; they are
 * overwritten.  rules: NULL for the defaults. */
lsm_status lsm_zprofile_slopes(const lsm_window *w, double H, const lsm_grid *phi_a,
                               const lsm_grid *phi_b, lsm_grid *const beyond[2],
                               const lsm_rules *rules, lsm_grid **slope_a, lsm_grid **slope_b,
                               lsm_err *err);

/* field := field + the cubic's departure from the linear interpolant at s,
 * kept within the range of phi_a and phi_b (rule cubic-range); nothing when
 * slope_a is NULL. */
void lsm_zprofile_add_cubic(const lsm_grid *phi_a, const lsm_grid *phi_b, const lsm_grid *slope_a,
                            const lsm_grid *slope_b, double s, const lsm_rules *rules,
                            lsm_grid *field);

/* field := lin + omega(s) (field - lin), lin = (1 - s) phi_a + s phi_b,
 * omega(s) = 16 s^2 (1 - s)^2: the morph's departure from the straight line,
 * weighted so that it vanishes with zero slope at both slices. */
void lsm_zprofile_weight(const lsm_grid *phi_a, const lsm_grid *phi_b, double s, lsm_grid *field);

#endif
