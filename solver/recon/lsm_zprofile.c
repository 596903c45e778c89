/* lsm_zprofile: the monotone cubic z-profile (see the header). */
#include "solver/recon/lsm_zprofile.h"

#include <math.h>

#include "kernels/lsm_cell.h"
#include "solver/recon/lsm_ends.h"
#include "solver/recon/lsm_pchip.h"

/* Per pixel, from the secants of the gap and of the intervals beyond A and B:
 *   - a non-empty neighbour: the centred (Fritsch-Carlson) slope;
 *   - where the data end on one side (no neighbour, or an empty one): the
 *     non-centred three-point slope through the interval beyond the other
 *     side (rule edge-slope), an empty slice there counting as that side's
 *     section eroded by its largest depth R (rule empty-eroded), else the
 *     gap's secant;
 *   - next to an empty neighbour only shrinking toward the end, 0 where the
 *     section grows toward it (rule end-slope-shrink): the widest part of an
 *     object between its last two slices is flat there.
 * The end gap itself continues with the secant (lsm_ends), so the surface
 * has a crease at the last section where the two differ. */
lsm_status lsm_zprofile_slopes(const lsm_window *w, double H, const lsm_grid *phi_a,
                               const lsm_grid *phi_b, lsm_grid *const beyond[2],
                               const lsm_rules *rules, lsm_grid **slope_a, lsm_grid **slope_b,
                               lsm_err *err) {
  const int edge = lsm_rule_on(rules, LSM_RULE_EDGE_SLOPE);
  const int eroded = edge && lsm_rule_on(rules, LSM_RULE_EMPTY_ERODED);
  const int shrink = lsm_rule_on(rules, LSM_RULE_END_SLOPE_SHRINK);
  /* Lengths in units of the gap H: a slope is stored times H (phi per gap),
   * the size of phi's own differences whatever the pixel size and spacing. */
  lsm_grid *outer[2] = {NULL, NULL}; /* phi differences beyond A (A - prev) and B (next - B) */
  int end[2] = {0, 0};               /* that neighbour is an empty slice */
  double end_secant[2] = {0.0, 0.0}, h_outer[2] = {1.0, 1.0}; /* per gap, in gaps */
  LSM_TRY(lsm_grid_clone(phi_a, slope_a, err));
  LSM_TRY(lsm_grid_clone(phi_a, slope_b, err));
  lsm_status st = LSM_OK;
  for (int side = 0; side < 2 && st == LSM_OK; ++side) {
    const int k = side ? 3 : 0, kf = side ? 2 : 1; /* the neighbour, and A or B */
    if (!w->s[k] || !w->s[k]->loaded) continue;
    const lsm_grid *own = side ? phi_b : phi_a;
    h_outer[side] = fabs(w->z[k] - w->z[kf]) / H;
    if (w->s[k]->empty) {
      const double R = lsm_end_depth(own);
      end[side] = 1;
      end_secant[side] = (side ? R : -R) / h_outer[side];
      continue;
    }
    lsm_grid *diff = outer[side] = beyond[side]; /* the neighbour's phi, made a difference */
    for (int j = 0; j < diff->ny; ++j)
      for (int i = 0; i < diff->nx; ++i) {
        float *v = &LSM_AT(diff, i, j);
        *v = side ? *v - LSM_AT(own, i, j) : LSM_AT(own, i, j) - *v;
      }
  }
  for (int side = 0; side < 2 && st == LSM_OK; ++side) {
    lsm_grid *m = side ? *slope_b : *slope_a;
    const int other = 1 - side;
    for (int j = 0; j < m->ny; ++j)
      for (int i = 0; i < m->nx; ++i) {
        const double d = (double)LSM_AT(phi_b, i, j) - (double)LSM_AT(phi_a, i, j);
        double slope;
        if (outer[side]) /* a slice on both sides: the centred slope */
          slope = side ? lsm_pchip_slope(1.0, h_outer[1], d, LSM_AT(outer[1], i, j) / h_outer[1])
                       : lsm_pchip_slope(h_outer[0], 1.0, LSM_AT(outer[0], i, j) / h_outer[0], d);
        else {
          /* the data end on this side (no slice beyond it, or an empty one) */
          slope = outer[other] && edge
                      ? lsm_pchip_edge_slope(1.0, h_outer[other], d,
                                             LSM_AT(outer[other], i, j) / h_outer[other])
                  : end[other] && eroded
                      ? lsm_pchip_edge_slope(1.0, h_outer[other], d, end_secant[other])
                      : d;
          if (end[side] && shrink) slope = side ? fmax(slope, 0.0) : fmin(slope, 0.0);
        }
        LSM_AT(m, i, j) = (float)slope; /* at most 3 |d| */
      }
  }
  return st;
}

/* The cubic's departure from the linear interpolant,
 *   Phi_cubic(s) - Phi_linear(s) = H [h10(s) (m_A - delta) + h11(s) (m_B - delta)],
 * delta = (phi_B - phi_A) / H (slopes held times H): it vanishes at s = 0 and
 * 1, where its s-slope makes the z-slope of the result the PCHIP slope, the
 * same on both sides of a slice.  The cubic alone never leaves the range of
 * its two slices; added to the morph's departure it can, so the sum is kept
 * within it (rule cubic-range). */
void lsm_zprofile_add_cubic(const lsm_grid *phi_a, const lsm_grid *phi_b, const lsm_grid *slope_a,
                            const lsm_grid *slope_b, double s, const lsm_rules *rules,
                            lsm_grid *field) {
  if (!slope_a) return;
  const int bounded = lsm_rule_on(rules, LSM_RULE_CUBIC_RANGE);
  double h00, h10, h01, h11;
  lsm_hermite_basis(s, &h00, &h10, &h01, &h11);
  const float c10 = (float)h10, c11 = (float)h11; /* slopes are per gap (times H) */
  for (int j = 0; j < field->ny; ++j) {
    const float *pa = &LSM_AT(phi_a, 0, j), *pb = &LSM_AT(phi_b, 0, j);
    const float *ma = &LSM_AT(slope_a, 0, j), *mb = &LSM_AT(slope_b, 0, j);
    float *o = &LSM_AT(field, 0, j);
    for (int i = 0; i < field->nx; ++i) {
      const float d = pb[i] - pa[i];
      const float v = o[i] + (c10 * (ma[i] - d) + c11 * (mb[i] - d)); /* a sum symmetric in A, B */
      o[i] = bounded ? lsm_minf(lsm_maxf(v, lsm_minf(pa[i], pb[i])), lsm_maxf(pa[i], pb[i])) : v;
    }
  }
}

/* The discrete morph's error relative to the distance still to go grows like
 * t e^-t, so read at t(s) = -ln(1 - s) its slope has a logarithmic
 * singularity at the slices; omega vanishes with zero slope there and is 1 at
 * mid-gap, where the morph matters. */
void lsm_zprofile_weight(const lsm_grid *phi_a, const lsm_grid *phi_b, double s_gap, lsm_grid *field) {
  const float s = (float)s_gap, omega = 16.0f * s * s * (1.0f - s) * (1.0f - s);
  for (int j = 0; j < field->ny; ++j) {
    const float *a = &LSM_AT(phi_a, 0, j), *b = &LSM_AT(phi_b, 0, j);
    float *o = &LSM_AT(field, 0, j);
    for (int i = 0; i < field->nx; ++i) {
      const float lin = (1.0f - s) * a[i] + s * b[i];
      o[i] = lin + omega * (o[i] - lin);
    }
  }
}
