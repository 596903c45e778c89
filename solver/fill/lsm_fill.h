/* lsm_fill: fills the slices between the drawn slices of a label volume, every
 * label at once, with the stack driver (solver/recon/lsm_stack.h).
 *
 * The slices are taken across one index axis (the slice axis).  The drawn
 * slices are the ones given, else every slice holding a label to fill plus one
 * typical step (the median step between those slices) beyond the first and
 * the last, taken as drawn empty where the volume has it, so that every object
 * ends there.  A label absent from a drawn slice is absent there.  The slices
 * strictly between the first and the last drawn slice that are not drawn are
 * the gaps: their voxels of the labels filled are replaced, everything else
 * (drawn slices, other labels, slices outside the drawn range) is kept as it
 * is, so the drawn slices come back exactly.
 *
 * Each label is one stack run: its masks on the drawn slices from the one
 * before its first appearance to the one after its last, cropped to the box
 * of its drawn sections plus a margin (lsm_fill.c says why the margin suffices),
 * pixel sizes and slice heights from the volume's spacing, one output slice
 * per volume slice.  Labels run side by side (one thread each) when there
 * are at least as many as threads, else one after another with the stack
 * driver's threads over their gaps.
 *
 * One label per voxel.  Each run gives phi_l, the interpolated signed
 * distance of label l (negative inside).  A voxel of a gap slice gets the
 * label whose phi_l is the most negative there, if any phi_l < 0: for regions
 * that partition the plane their signed distances satisfy phi_l < 0 <= phi_m
 * inside l, so the rule returns the partition exactly on the drawn slices,
 * and where two interpolated regions overlap it splits the overlap along
 * phi_l = phi_m, the set of points equally deep in both: at a touching
 * interface, where phi_l = -phi_m, that is the interface itself.  It is the
 * rule of multi-label shape-based interpolation and needs no parameter.  The
 * depth -phi_l is kept per voxel of the gaps in 16 bits (1/256 of the
 * smaller pixel side, to 255 pixels deep); equal depths go to the lower
 * label value, so the result does not depend on the order the labels finish
 * in nor on the thread count.
 *
 * Memory: the volume (filled in place), 2 bytes per voxel of the gap slices,
 * and the working grids of the gaps in flight (one label's box each).
 */
#ifndef LSM_FILL_H
#define LSM_FILL_H

#include <stddef.h>
#include <stdint.h>

#include "solver/base/lsm_status.h"
#include "solver/base/lsm_voxels.h"
#include "solver/recon/lsm_stack.h"

typedef struct lsm_fill_opts {
  int axis;               /* 0, 1, 2 (i, j, k); -1: the axis of the largest spacing, the
                             last on ties */
  const size_t *slices;   /* the drawn slices (any order, repeats allowed); NULL: found */
  size_t n_slices;
  const int64_t *labels;  /* the labels to fill; NULL: every non-zero value */
  size_t n_labels;
  /* method, interp, ends, align, morph (scheme, time, cfl, ..., backend, stop flag);
   * pixel sizes, dz and per_iteration are set by lsm_fill_run */
  lsm_stack_opts stack;
  int ends_given;         /* stack.ends chosen by the caller; else halfway (lsm_fill.c) */
  int threads;            /* 0: all cores */
  const lsm_progress *progress; /* may be NULL; called from one thread at a time */
  int whole_slices;       /* each label on whole slices, not its box (tests of the box) */
} lsm_fill_opts;

void lsm_fill_opts_default(lsm_fill_opts *o);

/* The axis the default picks for these spacings. */
int lsm_fill_default_axis(const double spacing[3]);

/* What a fill will do, decided from the volume before any work. */
typedef struct lsm_fill_plan {
  int axis;
  size_t *drawn;          /* the drawn slices, increasing */
  size_t n_drawn;
  size_t n_found;         /* without opts.slices: the slices holding a label */
  size_t step;            /* without opts.slices: the typical step between them (0: one slice) */
  size_t added[2];        /* the slices added beyond the first and last (SIZE_MAX: none) */
  size_t gap_slices;      /* slices to fill */
  int other_axis;         /* an axis across which the labels lie on separate slices (blank
                             slices between), -1 if none: the hint when this one has none */
  int64_t *labels;        /* the labels filled, increasing */
  size_t n_labels;
  size_t n_values;        /* distinct non-zero values in the volume */
  int64_t *absent;        /* labels filled that no drawn slice holds (their voxels in the
                             gaps are removed) */
  size_t n_absent;
  void *internal;
} lsm_fill_plan;

/* Checks the volume and the options and plans the fill.  Errors (exit 1 in
 * the CLI): an integer volume is needed; a slice or label asked for that the
 * volume has not; fewer than two drawn slices along the axis (the message
 * names another axis along which the labels lie on separate slices, if one
 * does).  gap_slices 0 is not an error: nothing to fill. */
lsm_status lsm_fill_plan_make(const lsm_voxels *v, const lsm_fill_opts *o, lsm_fill_plan **out,
                              lsm_err *err);
void lsm_fill_plan_free(lsm_fill_plan **p);

/* What the runs did. */
typedef struct lsm_fill_stats {
  size_t runs;            /* stack runs (labels with a drawn section) */
  size_t voxels_filled;   /* gap voxels given a label */
  long long iterations;   /* solver steps, all runs */
  double solver_seconds;  /* the morphs' time, summed over the gaps (thread time) */
  double seconds;         /* wall clock of the runs */
  size_t box_cells_max;   /* the largest box, in cells of a slice */
  long long motion_tried; /* --motion auto: gaps tried by leaving their slices out, all runs */
  long long motion_field; /* gaps that followed the correspondence field, all runs */
  int threads;
} lsm_fill_stats;

/* Fills v in place as planned (v must be the volume the plan was made of). */
lsm_status lsm_fill_run(const lsm_fill_plan *plan, lsm_voxels *v, const lsm_fill_opts *o,
                        lsm_fill_stats *stats, lsm_err *err);

#endif
