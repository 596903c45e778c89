/* lsm_ends: how an object ends inside a gap whose far side is an empty slice.
 *
 * F is the last non-empty section, sigma the fraction of the gap from F
 * (sigma = 0) to the empty slice (sigma = 1), H the gap's height.  F's
 * section is kept at most up to mid-gap, and in between the object is F
 * eroded; phi + e is the exact level-set solution of a uniform inward motion
 * by e, so no PDE is needed.
 *
 * Linear profile, ls and pls (LSM_END_PARABOLOID): a uniform erosion by a
 * depth that only the pair sees (lsm_end_cap_depth).  Blend (LSM_END_BLEND):
 * the textbook's halfway rule, (1 - sigma) phi_F + sigma R (the empty slice
 * counts as the constant R, F's largest depth).  Both end the object at
 * mid-gap (sigma >= 1/2 is empty).
 *
 * Cubic profile (LSM_END_TREND): the end continues what the slices N (beyond
 * F) and M (beyond N) say; each is a rule of lsm_rules.h (end-*):
 *   - shape: per cell phi_F + sigma H max(m, 0), m = (phi_F - phi_N) / h_N, the
 *     secant of the gap N -> F, held at F where the shape grows toward the end
 *     (nothing grows past the last slice), carried at most h_N past F;
 *   - parts: each 8-connected component of F ends on its own, with its areas
 *     A_F, A_N (N's components overlapping it, shared by overlap), A_M; a part
 *     mostly outside N is a flat end (a tail or thin part meeting a wide
 *     body), one mostly inside N narrows like N -> F, a share of each between;
 *     with no N (a lone section) every part is a flat end;
 *   - area: the part is eroded uniformly to the smallest of its caps: the flat
 *     share keeps A_F; the narrowing share follows the parabola through A_M,
 *     A_N, A_F (a smooth solid's section area is close to quadratic in z near
 *     its end), or with no M the line through A_N, A_F and the parabola
 *     through A_N, A_F and zero at the empty slice; past mid-gap every part is
 *     capped by a tip A_F (2 (1 - sigma))^p closing at the empty slice, p
 *     steeper where the part narrows; whatever closes it, a floor of a tip
 *     one power lower stays (a held-out slice left empty where the object
 *     still is costs the 95 % Hausdorff distance the image size).  Equally
 *     deep cells leave together, rounding the area down, unless that keeps
 *     less than half the cap.
 *   The tip, not mid-gap, because an object cut one slice beyond its end (the
 *   bunny's base) would lose half a gap; where the end lies in the gap is
 *   otherwise unknown.
 *
 * LSM_END_TREND_HALFWAY is the same without the tip: nothing past mid-gap.
 * The stack driver uses it (--ends auto) where more input slices lie beyond
 * the empty one (a scan that covers more than the object), the tip where the
 * empty slice is the outermost one (a stack cut one slice beyond the object).
 *
 * Usage: lsm_end_create once per gap, lsm_end_at for each output fraction,
 * lsm_end_destroy.  Grids hold phi with negative inside, in one frame.
 * Measurements behind each choice: validation/measurements/rules.md. */
#ifndef LSM_ENDS_H
#define LSM_ENDS_H

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/recon/lsm_rules.h"

typedef enum lsm_end_profile {
  LSM_END_PARABOLOID, /* linear z-profile, ls and pls: radius R sqrt(1 - 2 sigma) */
  LSM_END_BLEND,      /* linear z-profile, blend: the zero set of (1 - sigma) phi + sigma R */
  LSM_END_TREND,      /* cubic z-profile: the trend of N -> F, area caps, per part */
  LSM_END_TREND_HALFWAY /* the same, but nothing past mid-gap: no tip (--ends halfway) */
} lsm_end_profile;

typedef struct lsm_end lsm_end;

/* The largest depth R of a non-empty section's field, -min phi (at least
 * half a cell): the constant an empty slice stands for next to it. */
double lsm_end_depth(const lsm_grid *phi);

/* The same over the window of nx x ny cells from (x0, y0) only: a slice's own
 * image on a working canvas, whose margin is no part of the slice. */
double lsm_end_depth_in(const lsm_grid *phi, int x0, int y0, int nx, int ny);

/* Erosion depth at fraction sigma of the end gap with the paraboloid, R the
 * section's largest depth: R (1 - sqrt(1 - 2 sigma)); past R from sigma = 1/2
 * (nothing left: R by a millionth of R and of the cell size dx). */
double lsm_end_cap_depth(double R, double sigma, double dx);

/* Whether profile is one of the cubic (trend) profiles, which read N and M. */
int lsm_end_profile_is_trend(lsm_end_profile profile);

/* Prepares the end of F's section (full, F's phi) in a gap of height H.
 * beyond: N's phi in F's frame and grid shape, or NULL (no slice beyond F, or
 * one that is empty); h_beyond: |z_N - z_F| (ignored without N).  farther:
 * M's phi, the slice beyond N, likewise, or NULL; h_farther: |z_M - z_N|
 * (ignored without N and M).  Only the trend profiles read beyond and
 * farther.  rules: NULL for the defaults.
 * full and rules must stay alive and unchanged until lsm_end_destroy; beyond
 * and farther may be freed on return. */
lsm_status lsm_end_create(const lsm_grid *full, const lsm_grid *beyond, double h_beyond,
                          const lsm_grid *farther, double h_farther, double H,
                          lsm_end_profile profile, const lsm_rules *rules, lsm_end **out,
                          lsm_err *err);

/* work (F's grid shape) := the object's phi at fraction sigma in [0, 1] of the
 * gap from F to the empty slice. */
void lsm_end_at(lsm_end *end, double sigma, lsm_grid *work);

/* The linear profiles' R (lsm_end_create takes lsm_end_depth of the whole
 * grid): set it to F's depth over its own image (lsm_end_depth_in). */
void lsm_end_set_depth(lsm_end *end, double R);

void lsm_end_destroy(lsm_end **end);

#endif
