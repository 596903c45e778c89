/* lsm_unmatched: parts with no counterpart (see the header). */
#include "solver/recon/lsm_unmatched.h"

#include <math.h>
#include <stdlib.h>

#include "solver/base/lsm_grid.h"

/* What lsm_cap_unmatched learns about one component. */
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

/* The halfway rule for components (rule unmatched).  A component C of
 * {phi_x <= 0}, dilated by unmatched_grow_px so its front band goes with it,
 * that overlaps nothing of {phi_y <= 0} and lies farther from it than its
 * own depth ends like a whole object next to an empty slice: inside C, phi_y
 * is lowered to C's largest depth R_C, so the blend closes C at mid-gap and
 * the morph erodes it at speed R_C, not pulled toward far shapes.  Nearer
 * than its depth (rule unmatched-near) it branches off them as it is; a
 * branch of a larger body (rule branches) recedes toward the body. */
lsm_status lsm_cap_unmatched(const lsm_grid *phi_x, lsm_grid *phi_y, const lsm_grid *phi_before,
                             const lsm_rules *rules, lsm_err *err) {
  if (!rules) rules = lsm_rules_defaults();
  if (!lsm_rule_on(rules, LSM_RULE_BRANCHES)) phi_before = NULL;
  const int near = lsm_rule_on(rules, LSM_RULE_UNMATCHED_NEAR);
  const int nx = phi_x->nx, ny = phi_x->ny;
  const size_t n = (size_t)nx * (size_t)ny;
  const float grow =
      (float)rules->unmatched_grow_px * (phi_x->dx > phi_x->dy ? phi_x->dx : phi_x->dy);
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
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int32_t c = label[(size_t)j * nx + i];
      if (c < 0 || cs[c].matched || cs[c].branch || !(cs[c].depth > 0.0f) ||
          (near && !(cs[c].gap_to_other > cs[c].depth)))
        continue;
      float *y = &LSM_AT(phi_y, i, j);
      if (*y > cs[c].depth) *y = cs[c].depth;
    }
  free(cs);
  free(label);
  lsm_grid_fill_ghosts(phi_y);
  return LSM_OK;
}
