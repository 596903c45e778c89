/* fill_internal: what lsm_fill_plan.c hands lsm_fill.c (private to the two). */
#ifndef FILL_INTERNAL_H
#define FILL_INTERNAL_H

#include "solver/fill/lsm_fill.h"

/* The in-plane axes of a slice across `axis`: u along a row, v down a column
 * (i, j across k; i, k across j; j, k across i), and each axis's stride in
 * the volume. */
typedef struct fill_geometry {
  int axis, u, v;
  size_t stride[3];
  size_t width, height; /* n[u], n[v] */
  size_t slices;        /* n[axis] */
} fill_geometry;

void fill_geometry_of(const lsm_voxels *v, int axis, fill_geometry *g);

/* A label to fill. */
typedef struct fill_label {
  int64_t value;
  int present;           /* on some drawn slice */
  size_t first, last;    /* its stack: drawn[first] .. drawn[last], the drawn slice before
                            its first section to the one after its last (clipped) */
  size_t box[4];         /* u0, u1, v0, v1 (inclusive) of its drawn sections */
} fill_label;

typedef struct fill_internal {
  fill_geometry geo;
  fill_label *label;     /* plan->n_labels of them, in plan->labels' order */
  int every_label;       /* every non-zero value is filled */
} fill_internal;

/* Whether value is one of the plan's labels (sorted). */
int fill_is_label(const lsm_fill_plan *plan, int64_t value);

/* Where slice s (a gap slice) is among the gap slices, 0-based. */
size_t fill_gap_index(const lsm_fill_plan *plan, size_t s);

#endif
