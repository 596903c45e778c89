/* lsm_frame: alignment frames (see the header). */
#include "solver/recon/lsm_frame.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "solver/recon/lsm_pchip.h"
#include "solver/recon/lsm_register.h"

/* Halves round upward: rounding half away from zero (lround) would put two
 * shapes 16 px apart at offsets -7.5 and 8.5 px from the centre 17 px apart
 * in the aligned frame. */
int lsm_pixel_shift(double offset) { return (int)floor(offset + 0.5); }

/* --align auto: hull alignment for the pair a, b only when its shape moved
 * rather than changed (rules align-*): the centroid shift must make the two
 * overlap more than in place, and the translation of largest overlap must
 * make them alike, or somewhat alike where they barely touch in place.  A
 * centroid moves too where a part grows out on one side; a small section
 * inside a large one fits it at many shifts: in neither does the shift
 * explain the difference. */
static lsm_status resolve_align(lsm_align asked, const lsm_slice *a, const lsm_slice *b, int width,
                                int height, const lsm_rules *rules, lsm_align *align,
                                lsm_err *err) {
  *align = asked;
  if (asked != LSM_ALIGN_AUTO) return LSM_OK;
  *align = LSM_ALIGN_NONE;
  if (a->empty || b->empty || !lsm_rule_on(rules, LSM_RULE_ALIGN_AUTO)) return LSM_OK;
  const double cx = 0.5 * (width - 1), cy = 0.5 * (height - 1);
  const int dx = lsm_pixel_shift(b->cx - cx) - lsm_pixel_shift(a->cx - cx);
  const int dy = lsm_pixel_shift(b->cy - cy) - lsm_pixel_shift(a->cy - cy);
  if (dx == 0 && dy == 0) return LSM_OK;
  const size_t in_place = lsm_mask_overlap(&a->filled, &b->filled, 0, 0);
  const size_t area_a = lsm_mask_count(&a->filled), area_b = lsm_mask_count(&b->filled);
  const size_t area = area_a + area_b;
  if (lsm_rule_on(rules, LSM_RULE_ALIGN_CENTROID_GAIN) &&
      lsm_mask_overlap(&a->filled, &b->filled, dx, dy) <= in_place)
    return LSM_OK;
  int tx, ty;
  LSM_TRY(lsm_register_shift(&a->filled, &b->filled, &tx, &ty, err));
  const double iou = (double)in_place / (double)(area - in_place);
  const size_t smaller = area_a < area_b ? area_a : area_b;
  const size_t moved = lsm_mask_overlap(&a->filled, &b->filled, tx, ty);
  const double iou_moved = (double)moved / (double)(area - moved);
  const int apart = lsm_rule_on(rules, LSM_RULE_ALIGN_APART) &&
                    (double)in_place < rules->align_apart_overlap * (double)smaller &&
                    iou_moved >= rules->align_apart_iou;
  const int alike = lsm_rule_on(rules, LSM_RULE_ALIGN_ALIKE) &&
                    iou_moved >= rules->align_alike_iou &&
                    iou_moved >= rules->align_alike_gain * iou;
  if (apart || alike) *align = LSM_ALIGN_HULL;
  return LSM_OK;
}

lsm_status lsm_frame_setup(lsm_frame *f, const lsm_window *w, lsm_align asked, lsm_interp interp,
                           int width, int height, double pixel_dx, double pixel_dy,
                           const lsm_rules *rules, lsm_err *err) {
  memset(f, 0, sizeof *f);
  if (!rules) rules = lsm_rules_defaults();
  lsm_align align, end_align = LSM_ALIGN_NONE;
  LSM_TRY(resolve_align(asked, w->s[1], w->s[2], width, height, rules, &align, err));
  f->width = width;
  f->height = height;
  f->aligned = align == LSM_ALIGN_HULL;
  f->H = w->z[2] - w->z[1];
  const lsm_slice *a = w->s[1], *b = w->s[2];
  if (align == LSM_ALIGN_HULL && !(a->empty && b->empty)) {
    const double cx = 0.5 * (width - 1), cy = 0.5 * (height - 1);
    for (int k = 0; k < 4; ++k) {
      const lsm_slice *sk = w->s[k];
      if (k == 1 && a->empty) sk = b; /* an empty end sits with the full one (but see below) */
      if (k == 2 && b->empty) sk = a;
      if (!sk || !sk->loaded || sk->empty) continue;
      f->dx[k] = lsm_pixel_shift(sk->cx - cx);
      f->dy[k] = lsm_pixel_shift(sk->cy - cy);
    }
  }
  /* A gap where the object ends, cubic profile (rule end-moves-on): if the
   * pair beyond the full slice is aligned, the end keeps moving at that
   * pair's centroid velocity, and its shape is compared with the slice beyond
   * in that pair's frame.  (linear sees only the pair: the end stays put.) */
  const int ke = a->empty ? 1 : 2, kf = 3 - ke, kn = a->empty ? 3 : 0;
  if (interp == LSM_INTERP_CUBIC && a->empty != b->empty && asked != LSM_ALIGN_NONE &&
      lsm_window_usable(w, kn) && lsm_rule_on(rules, LSM_RULE_END_MOVES_ON))
    LSM_TRY(resolve_align(asked, w->s[kn], w->s[kf], width, height, rules, &end_align, err));
  f->end_aligned = end_align == LSM_ALIGN_HULL;
  if (end_align == LSM_ALIGN_HULL) {
    const double cx = 0.5 * (width - 1), cy = 0.5 * (height - 1);
    const lsm_slice *sf = w->s[kf], *sn = w->s[kn];
    const double vx = (sf->cx - sn->cx) / (w->z[kf] - w->z[kn]);
    const double vy = (sf->cy - sn->cy) / (w->z[kf] - w->z[kn]);
    const double he = w->z[ke] - w->z[kf];
    f->dx[kn] = lsm_pixel_shift(sn->cx - cx);
    f->dy[kn] = lsm_pixel_shift(sn->cy - cy);
    f->dx[kf] = lsm_pixel_shift(sf->cx - cx);
    f->dy[kf] = lsm_pixel_shift(sf->cy - cy);
    /* the extrapolated centroid stays on the image, which also keeps the
     * working canvas within its documented bound (--max-pixels) */
    f->dx[ke] = lsm_pixel_shift(fmin(fmax(sf->cx + he * vx, 0.0), width - 1.0) - cx);
    f->dy[ke] = lsm_pixel_shift(fmin(fmax(sf->cy + he * vy, 0.0), height - 1.0) - cy);
  }
  /* Slopes of the centroid path: secant (linear), or PCHIP through the
   * neighbouring slices' centroids (cubic; rule centroid-pchip). */
  const double sx = (f->dx[2] - f->dx[1]) / f->H, sy = (f->dy[2] - f->dy[1]) / f->H;
  f->mx[0] = f->mx[1] = sx;
  f->my[0] = f->my[1] = sy;
  if (interp == LSM_INTERP_CUBIC && align == LSM_ALIGN_HULL && !a->empty && !b->empty &&
      lsm_rule_on(rules, LSM_RULE_CENTROID_PCHIP)) {
    if (lsm_window_usable(w, 0)) {
      const double h0 = w->z[1] - w->z[0];
      f->mx[0] = lsm_pchip_slope(h0, f->H, (f->dx[1] - f->dx[0]) / h0, sx);
      f->my[0] = lsm_pchip_slope(h0, f->H, (f->dy[1] - f->dy[0]) / h0, sy);
    }
    if (lsm_window_usable(w, 3)) {
      const double h1 = w->z[3] - w->z[2];
      f->mx[1] = lsm_pchip_slope(f->H, h1, sx, (f->dx[3] - f->dx[2]) / h1);
      f->my[1] = lsm_pchip_slope(f->H, h1, sy, (f->dy[3] - f->dy[2]) / h1);
    }
  }
  int mx = 0, my = 0;
  for (int k = 0; k < 4; ++k) {
    if (abs(f->dx[k]) > mx) mx = abs(f->dx[k]);
    if (abs(f->dy[k]) > my) my = abs(f->dy[k]);
  }
  f->pad = mx + 2;
  f->pad_y = my + 2;
  f->clamp = (float)hypot(pixel_dx * width, pixel_dy * height);
  return LSM_OK;
}

/* The alignment shift at fraction s: the Hermite curve through the shifts of
 * A and B with the slopes above (a straight segment for linear). */
static void frame_shift(const lsm_frame *f, double s, double *shx, double *shy) {
  double h00, h10, h01, h11;
  lsm_hermite_basis(s, &h00, &h10, &h01, &h11);
  *shx = h00 * f->dx[1] + h10 * f->H * f->mx[0] + h01 * f->dx[2] + h11 * f->H * f->mx[1];
  *shy = h00 * f->dy[1] + h10 * f->H * f->my[0] + h01 * f->dy[2] + h11 * f->H * f->my[1];
}

/* Writes the slice at fraction s from the working field into out (width x
 * height), undoing the alignment shift. */
void lsm_frame_extract(const lsm_frame *f, const lsm_grid *work, double s, float *out) {
  double shx, shy;
  frame_shift(f, s, &shx, &shy);
  const double ox = f->pad - shx, oy = f->pad_y - shy;
  const int whole = ox == floor(ox) && oy == floor(oy);
  for (int y = 0; y < f->height; ++y)
    for (int x = 0; x < f->width; ++x) {
      float v = whole ? LSM_AT(work, x + (int)ox, y + (int)oy)
                      : lsm_grid_sample(work, x + ox, y + oy);
      if (v > f->clamp) v = f->clamp;
      if (v < -f->clamp) v = -f->clamp;
      out[(size_t)y * f->width + x] = v;
    }
}
