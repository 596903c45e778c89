/* lsm_unmatched: parts with no counterpart (see the header). */
#include "solver/recon/lsm_unmatched.h"

#include <math.h>
#include <stdlib.h>

#include "solver/base/lsm_grid.h"

/* What cap_unmatched learns about one component. */
typedef struct unmatched_stats {
  float depth;        /* its largest depth */
  float gap_to_other; /* the smallest phi of the other side over its inside */
  int matched;        /* it overlaps the other side's inside */
  int32_t area;       /* its cells inside */
  int branch;         /* one piece, on the slice beyond, with a larger matched component */
} unmatched_stats;

/* Marks the components of x that are branches: a component of {phi_before
 * <= 0} (the slice beyond x, away from the gap) that overlaps it also
 * overlaps a larger matched component of x.  label_x: x's components, labels
 * of phi_before's written to label_before. */
static void mark_branches(const lsm_grid *phi_x, const int32_t *label_x, const lsm_grid *phi_before,
                          int32_t *label_before, int32_t *queue, unmatched_stats *cs) {
  const int nx = phi_x->nx, ny = phi_x->ny;
  const int32_t count = lsm_grid_label_components(phi_before, 0.0f, label_before, queue);
  if (count <= 0) return;
  /* queue is free again: per component of phi_before's, the largest matched
   * component of x it overlaps (its area) */
  for (int32_t p = 0; p < count; ++p) queue[p] = 0;
  for (int pass = 0; pass < 2; ++pass)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const size_t at = (size_t)j * nx + i;
        const int32_t c = label_x[at], p = label_before[at];
        if (c < 0 || p < 0 || LSM_AT(phi_x, i, j) > 0.0f) continue;
        if (pass == 0 && cs[c].matched && cs[c].area > queue[p]) queue[p] = cs[c].area;
        if (pass == 1 && queue[p] > cs[c].area) cs[c].branch = 1;
      }
}

/* The halfway rule for components.  A connected component C of {phi_x <= 0}
 * (slightly dilated, by 2 cells, so a component's front band goes with it)
 * that does not overlap {phi_y <= 0}, and lies farther from it than its own
 * depth, has no counterpart on the other side: it ends there, like a whole
 * object next to an empty slice.  Inside C the
 * other side's field is lowered to the constant R_C (C's largest depth), so
 * the blend (1 - s) phi_x + s R_C closes C at mid-gap, and the morph erodes
 * it at speed R_C instead of pulling it toward far-away shapes (with the
 * distance to them as speed, a small component would vanish at once).
 * A branch is left alone: C that was one piece, on the slice beyond x
 * (phi_before; NULL if none, or with the linear profile, which reads only the
 * pair), with a larger matched component has just split
 * off a body that goes on, and it recedes toward that body's shapes on the
 * other side, as the interpolation makes it (atlas.py every 2nd slice:
 * pooled HD95 1.42 -> 1.35 px, the brainstem cut axially 3.61 -> 1.41 px;
 * with any matched component, not only a larger one, the bunny's body,
 * one piece on the slice beyond with a small part that goes on, vanished
 * too early: meshes.py bunny-z every 16th 0.9648 -> 0.9566). */
lsm_status lsm_cap_unmatched(const lsm_grid *phi_x, lsm_grid *phi_y, const lsm_grid *phi_before,
                             lsm_err *err) {
  const int nx = phi_x->nx, ny = phi_x->ny;
  const size_t n = (size_t)nx * (size_t)ny;
  const float grow = 2.0f * (phi_x->dx > phi_x->dy ? phi_x->dx : phi_x->dy);
  int32_t *label = lsm_alloc(n, sizeof *label, err, "component labels");
  int32_t *queue = label ? lsm_alloc(n, sizeof *queue, err, "component queue") : NULL;
  int32_t *label_before = queue && phi_before ? lsm_alloc(n, sizeof *label_before, err, "component labels")
                                              : NULL;
  if (!queue || (phi_before && !label_before)) {
    free(label);
    free(queue);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  const int32_t count = lsm_grid_label_components(phi_x, grow, label, queue);
  /* per component: its largest depth, whether it overlaps the other side's
   * inside, and how far the other side's nearest inside is (the smallest phi_y
   * over its inside) */
  unmatched_stats *cs = lsm_alloc((size_t)count + 1, sizeof *cs, err, "component depths");
  if (!cs) {
    free(label);
    free(queue);
    free(label_before);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  for (int32_t c = 0; c < count; ++c) cs[c] = (unmatched_stats){0.0f, INFINITY, 0, 0, 0};
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int32_t c = label[(size_t)j * nx + i];
      if (c < 0) continue;
      const float v = LSM_AT(phi_x, i, j), vy = LSM_AT(phi_y, i, j);
      if (-v > cs[c].depth) cs[c].depth = -v;
      if (v <= 0.0f) cs[c].area++;
      if (v <= 0.0f && vy <= 0.0f) cs[c].matched = 1;
      if (v <= 0.0f && vy < cs[c].gap_to_other) cs[c].gap_to_other = vy;
    }
  if (phi_before) mark_branches(phi_x, label, phi_before, label_before, queue, cs);
  free(queue);
  free(label_before);
  /* A component next to the other side's shapes (closer than its own depth)
   * branches off them: the interpolation already makes it appear or vanish by
   * mid-gap, from the right place. */
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int32_t c = label[(size_t)j * nx + i];
      if (c < 0 || cs[c].matched || cs[c].branch || !(cs[c].depth > 0.0f) ||
          !(cs[c].gap_to_other > cs[c].depth))
        continue;
      float *y = &LSM_AT(phi_y, i, j);
      if (*y > cs[c].depth) *y = cs[c].depth;
    }
  free(cs);
  free(label);
  lsm_grid_fill_ghosts(phi_y);
  return LSM_OK;
}
