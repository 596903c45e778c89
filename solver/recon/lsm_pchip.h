/* lsm_pchip: the slopes of a monotone piecewise cubic Hermite interpolant
 * (PCHIP, Fritsch & Carlson 1980; Fritsch & Butland 1984) and the cubic
 * Hermite basis, pure functions.  The z-profile through the slices
 * (lsm_zprofile) and the centroid path of aligned pairs (lsm_frame) use them. */
#ifndef LSM_PCHIP_H
#define LSM_PCHIP_H

#include <math.h>

/* Both strictly positive or both strictly negative (signs compared, not
 * multiplied, so no product can under- or overflow). */
static inline int lsm_same_sign(double a, double b) {
  return (a > 0.0 && b > 0.0) || (a < 0.0 && b < 0.0);
}

/* Fritsch–Carlson slope at a knot between intervals of lengths h0, h1 with
 * secants d0, d1 (the weighted harmonic mean of Fritsch & Butland, as in
 * Moler's pchip): zero at a local extremum, so the Hermite cubic stays within
 * the range of its two knots — no overshoot.  At most 3 min(|d0|, |d1|).
 * Homogeneous: scaling h0, h1 by c scales the slope by 1/c, so callers pass
 * lengths in units of the gap (its slope times H, the size of phi itself),
 * and nothing depends on the ratio of pixel size to slice spacing. */
static inline double lsm_pchip_slope(double h0, double h1, double d0, double d1) {
  if (!lsm_same_sign(d0, d1)) return 0.0;
  const double hs = h0 + h1, w1 = (2.0 * h1 + h0) / hs, w2 = (h1 + 2.0 * h0) / hs;
  return (w1 + w2) / (w1 / d0 + w2 / d1);
}

/* PCHIP slope at the end of the data (scipy's non-centred three-point
 * formula, shape preserving): h0, d0 the last interval and its secant, h1, d1
 * the one before it.  At most 3 |d0|; homogeneous as lsm_pchip_slope. */
static inline double lsm_pchip_edge_slope(double h0, double h1, double d0, double d1) {
  const double hs = h0 + h1, m = ((2.0 * h0 + h1) / hs) * d0 - (h0 / hs) * d1;
  if (!lsm_same_sign(m, d0)) return 0.0;
  if (lsm_same_sign(d0, -d1) && fabs(m) > 3.0 * fabs(d0)) return 3.0 * d0;
  return m;
}

/* Cubic Hermite basis on s in [0, 1]. */
static inline void lsm_hermite_basis(double s, double *h00, double *h10, double *h01,
                                     double *h11) {
  const double s2 = s * s, s3 = s2 * s;
  *h00 = 2 * s3 - 3 * s2 + 1;
  *h10 = s3 - 2 * s2 + s;
  *h01 = -2 * s3 + 3 * s2;
  *h11 = s3 - s2;
}

#endif
