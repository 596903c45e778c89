/* lsm_fill: the runs.  One stack run per label (lsm_fill.h): its source cuts
 * the label's masks out of the drawn slices, its sink writes the label into
 * the gap slices where it is the deepest label so far.
 *
 * The box of a label is the box of its drawn sections plus a margin.  A
 * gap's output never leaves the union of its two sections where the pair
 * stays in place (the profile keeps phi within [min(phi_A, phi_B),
 * max(phi_A, phi_B)], lsm_stack.h), and the signed distances inside the box
 * are the ones of the whole slice: every pixel's nearest pixel of the other
 * side lies in the box or on the ring just around it.  A pair aligned by its
 * centroids (--align) moves the morph of its two centred sections along the
 * centroid path, between the two centroids, so the shape stays within the
 * box widened by the centroid step |c_B - c_A| along each axis; an object
 * ending next to an empty slice keeps moving at the last pair's centroid
 * velocity, for at most the longest gap.  The margin is therefore 2 pixels
 * (the ring, and the bilinear resampling of a shifted field) plus the
 * largest centroid step between consecutive sections, scaled by the longest
 * gap over that pair's gap where that is more than 1. */
#include "solver/fill/fill_internal.h"

#include <math.h>
#include <omp.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>

#include "solver/sdf/lsm_sdf.h"

#define LOCK_STRIPES 64

typedef struct fill_shared {
  const lsm_fill_plan *plan;
  const fill_internal *in;
  lsm_voxels *vol;
  uint16_t *depth;        /* per gap slice, per pixel of the slice: 0 unclaimed, else 1 + depth */
  double quantum;         /* depth per step of `depth`: 1/256 of the smaller pixel side */
  omp_lock_t lock[LOCK_STRIPES];
  omp_lock_t progress_lock;
  const lsm_progress *progress;
  size_t done, total;
  int failed;             /* read and written atomically */
  const volatile sig_atomic_t *stop;
  int whole_slices;
} fill_shared;

typedef struct label_task {
  fill_shared *sh;
  const fill_label *lab;
  size_t x0, y0;          /* the box's corner in the slice */
  int width, height;
  size_t count;           /* drawn slices in its stack */
  double *z;
  double cost;
} label_task;

static int failed(fill_shared *sh) {
  int f;
#pragma omp atomic read
  f = sh->failed;
  return f || (sh->stop && *sh->stop);
}

/* The label's mask on drawn slice drawn[first + index], in the box. */
static void cut_mask(const label_task *t, size_t index, uint8_t *pixels) {
  const fill_shared *sh = t->sh;
  const fill_geometry *g = &sh->in->geo;
  const size_t s = sh->plan->drawn[t->lab->first + index];
  const size_t base = s * g->stride[g->axis];
  const int64_t value = t->lab->value;
  const size_t su = g->stride[g->u];
  LSM_VOXEL_INT_SWITCH(sh->vol->type, {
    const T *p = (const T *)sh->vol->data;
    for (int y = 0; y < t->height; ++y) {
      const T *row = p + base + (t->y0 + (size_t)y) * g->stride[g->v] + t->x0 * su;
      uint8_t *out = pixels + (size_t)y * (size_t)t->width;
      for (int x = 0; x < t->width; ++x) out[x] = (int64_t)row[(size_t)x * su] == value;
    }
  })
}

static lsm_status task_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
  label_task *t = ctx;
  if (failed(t->sh)) return lsm_fail(err, LSM_ERR_INTERRUPTED, NULL, "interrupted");
  LSM_TRY(lsm_mask_create(t->width, t->height, out, err));
  cut_mask(t, index, out->pixels);
  return LSM_OK;
}

/* A gap slice of the label: each pixel where phi < 0 takes the label if it is
 * deeper there than the label the voxel has (equal: the lower value). */
static lsm_status task_emit(void *ctx, const float *phi, int width, int height, double z,
                            long input_index, lsm_err *err) {
  label_task *t = ctx;
  fill_shared *sh = t->sh;
  if (failed(sh)) return lsm_fail(err, LSM_ERR_INTERRUPTED, NULL, "interrupted");
  if (input_index >= 0) return LSM_OK; /* a drawn slice: kept as it is */
  const fill_geometry *g = &sh->in->geo;
  const double spacing = sh->vol->spacing[g->axis];
  const double at = nearbyint(z / spacing);
  if (!(at >= (double)sh->plan->drawn[0]) || !(at <= (double)sh->plan->drawn[sh->plan->n_drawn - 1]))
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "an output slice at %g lies off the volume", z);
  const size_t s = (size_t)at;
  const size_t gap = fill_gap_index(sh->plan, s);
  uint16_t *depth = sh->depth + gap * g->width * g->height;
  const size_t base = s * g->stride[g->axis];
  const int64_t value = t->lab->value;
  const double per = 1.0 / sh->quantum;
  omp_lock_t *lock = &sh->lock[gap % LOCK_STRIPES];
  omp_set_lock(lock);
  LSM_VOXEL_INT_SWITCH(sh->vol->type, {
    T *vol = (T *)sh->vol->data;
    for (int y = 0; y < height; ++y) {
      const size_t py = t->y0 + (size_t)y;
      for (int x = 0; x < width; ++x) {
        const float f = phi[(size_t)y * (size_t)width + (size_t)x];
        if (!(f < 0.0f)) continue;
        const size_t px = t->x0 + (size_t)x, p = py * g->width + px;
        const size_t voxel = base + px * g->stride[g->u] + py * g->stride[g->v];
        const double deep = -(double)f * per;
        const uint16_t q = (uint16_t)(1 + (deep >= 65534.0 ? 65534 : (unsigned)deep));
        if (depth[p] == 0) {
          if (vol[voxel] != 0) continue; /* a label kept as it is */
        } else if (q < depth[p] || (q == depth[p] && value > (int64_t)vol[voxel])) {
          continue;
        }
        depth[p] = q;
        vol[voxel] = (T)value;
      }
    }
  })
  omp_unset_lock(lock);
  if (sh->progress && sh->progress->update) {
    omp_set_lock(&sh->progress_lock);
    sh->done++;
    sh->progress->update(sh->progress->ctx, sh->done, sh->total, 0, 0);
    omp_unset_lock(&sh->progress_lock);
  }
  return LSM_OK;
}

/* The label's box: its sections' box widened by the margin of the file
 * comment, within the slice. */
static lsm_status task_box(label_task *t, lsm_err *err) {
  const fill_shared *sh = t->sh;
  const fill_geometry *g = &sh->in->geo;
  const fill_label *lab = t->lab;
  t->x0 = lab->box[0];
  t->y0 = lab->box[2];
  t->width = (int)(lab->box[1] - lab->box[0] + 1);
  t->height = (int)(lab->box[3] - lab->box[2] + 1);
  lsm_mask m;
  LSM_TRY(lsm_mask_create(t->width, t->height, &m, err));
  const size_t *drawn = sh->plan->drawn + lab->first;
  double longest = 0.0, step[2] = {0.0, 0.0}, prev[2] = {0.0, 0.0};
  size_t prev_at = SIZE_MAX;
  for (size_t k = 0; k + 1 < t->count; ++k)
    longest = fmax(longest, (double)(drawn[k + 1] - drawn[k]));
  for (size_t k = 0; k < t->count; ++k) {
    cut_mask(t, k, m.pixels);
    double c[2];
    const int hull = lsm_hull_centroid(&m, &c[0], &c[1]);
    if (hull < 0) {
      lsm_mask_free(&m);
      return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the convex hull");
    }
    if (hull == 0) {
      prev_at = SIZE_MAX;
      continue;
    }
    if (prev_at != SIZE_MAX) {
      const double scale = fmax(1.0, longest / (double)(drawn[k] - drawn[prev_at]));
      for (int a = 0; a < 2; ++a) step[a] = fmax(step[a], fabs(c[a] - prev[a]) * scale);
    }
    prev[0] = c[0];
    prev[1] = c[1];
    prev_at = k;
  }
  lsm_mask_free(&m);
  if (sh->whole_slices) {
    t->x0 = t->y0 = 0;
    t->width = (int)g->width;
    t->height = (int)g->height;
    return LSM_OK;
  }
  const size_t margin[2] = {2 + (size_t)ceil(step[0]), 2 + (size_t)ceil(step[1])};
  size_t x0 = t->x0 > margin[0] ? t->x0 - margin[0] : 0;
  size_t y0 = t->y0 > margin[1] ? t->y0 - margin[1] : 0;
  size_t x1 = lab->box[1] + margin[0] < g->width ? lab->box[1] + margin[0] : g->width - 1;
  size_t y1 = lab->box[3] + margin[1] < g->height ? lab->box[3] + margin[1] : g->height - 1;
  /* sides of the slice's parity: an aligned pair is shifted by whole pixels
   * from its centroid to the canvas centre, and the centres of a box and of
   * the slice then lie alike on the pixel grid, so the box's pixels are moved
   * as the slice's are */
  if ((x1 - x0 + 1) % 2 != g->width % 2) {
    if (x1 + 1 < g->width) ++x1; else --x0;
  }
  if ((y1 - y0 + 1) % 2 != g->height % 2) {
    if (y1 + 1 < g->height) ++y1; else --y0;
  }
  t->x0 = x0;
  t->y0 = y0;
  t->width = (int)(x1 - x0 + 1);
  t->height = (int)(y1 - y0 + 1);
  return LSM_OK;
}

/* What one label's run adds to the fill's statistics. */
typedef struct task_counts {
  long long iterations, motion_tried, motion_field;
  double solver_seconds;
} task_counts;

/* One label's stack run, on `threads` threads. */
static lsm_status run_task(label_task *t, const lsm_fill_opts *o, int threads, task_counts *n,
                           lsm_err *err) {
  fill_shared *sh = t->sh;
  const fill_geometry *g = &sh->in->geo;
  LSM_TRY(task_box(t, err));
  lsm_stack_opts so = o->stack;
  so.pixel_dx = sh->vol->spacing[g->u];
  so.pixel_dy = sh->vol->spacing[g->v];
  so.dz = sh->vol->spacing[g->axis];
  so.per_iteration = 0;
  so.input = LSM_INPUT_MASK;
  so.transport = NULL;
  so.morph.threads = threads;
  if (!o->ends_given) so.ends = LSM_ENDS_HALFWAY;
  lsm_pair_stats *stats = lsm_alloc(t->count, sizeof *stats, err, "gap statistics");
  if (!stats) return err ? err->status : LSM_ERR_NOMEM;
  const lsm_slice_source source = {t, t->count, t->z, task_load, NULL};
  const lsm_slice_sink sink = {t, task_emit};
  const lsm_status st = lsm_stack_run(&source, t->width, t->height, &so, &sink, stats, NULL, err);
  for (size_t k = 0; st == LSM_OK && k + 1 < t->count; ++k) {
    n->iterations += stats[k].iterations;
    n->solver_seconds += stats[k].seconds;
    n->motion_tried += stats[k].motion_tests > 0;
    n->motion_field += stats[k].motion_field;
  }
  free(stats);
  return st;
}

static int cmp_cost(const void *a, const void *b) {
  const double x = ((const label_task *)a)->cost, y = ((const label_task *)b)->cost;
  return (x < y) - (x > y); /* the largest first */
}

/* Clears the labels to fill from the gap slices. */
static void clear_gaps(const lsm_fill_plan *plan, lsm_voxels *v, int threads) {
  const fill_internal *in = plan->internal;
  const fill_geometry *g = &in->geo;
  const size_t first = plan->drawn[0], last = plan->drawn[plan->n_drawn - 1];
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (size_t s = first + 1; s < last; ++s) {
    size_t lo = 0, hi = plan->n_drawn; /* skip drawn slices */
    while (lo < hi) {
      const size_t mid = lo + (hi - lo) / 2;
      if (plan->drawn[mid] < s) lo = mid + 1; else hi = mid;
    }
    if (lo < plan->n_drawn && plan->drawn[lo] == s) continue;
    const size_t base = s * g->stride[g->axis];
    for (size_t y = 0; y < g->height; ++y)
      for (size_t x = 0; x < g->width; ++x) {
        const size_t voxel = base + x * g->stride[g->u] + y * g->stride[g->v];
        if (fill_is_label(plan, lsm_voxel_get_int(v, voxel))) lsm_voxel_set_int(v, voxel, 0);
      }
  }
}

lsm_status lsm_fill_run(const lsm_fill_plan *plan, lsm_voxels *v, const lsm_fill_opts *o,
                        lsm_fill_stats *stats, lsm_err *err) {
  memset(stats, 0, sizeof *stats);
  const fill_internal *in = plan->internal;
  const fill_geometry *g = &in->geo;
  const int threads = o->threads > 0 ? o->threads : omp_get_num_procs();
  stats->threads = threads;
  if (plan->gap_slices == 0) return LSM_OK;
  const double t0 = omp_get_wtime();
  fill_shared sh;
  memset(&sh, 0, sizeof sh);
  sh.plan = plan;
  sh.in = in;
  sh.vol = v;
  sh.quantum = fmin(v->spacing[g->u], v->spacing[g->v]) / 256.0;
  sh.progress = o->progress;
  sh.stop = o->stack.morph.stop;
  sh.whole_slices = o->whole_slices;
  size_t cells = 0;
  if (!lsm_size_mul3(plan->gap_slices, g->width, g->height, &cells))
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "the gap slices' size overflows");
  sh.depth = lsm_alloc(cells, sizeof *sh.depth, err, "label depths");
  label_task *task = lsm_alloc(plan->n_labels ? plan->n_labels : 1, sizeof *task, err, "labels");
  if (!sh.depth || !task) {
    free(sh.depth);
    free(task);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  memset(sh.depth, 0, cells * sizeof *sh.depth);
  /* found drawn slices are all the slices holding a label to fill: the gaps
   * hold none; given ones (--slices) may leave labels in the gaps, replaced here */
  if (o->slices) clear_gaps(plan, v, threads);
  /* one task per label with a drawn section, the costliest first */
  size_t tasks = 0;
  lsm_status st = LSM_OK;
  for (size_t l = 0; st == LSM_OK && l < plan->n_labels; ++l) {
    const fill_label *lab = &in->label[l];
    if (!lab->present) continue;
    label_task *t = &task[tasks++];
    memset(t, 0, sizeof *t);
    t->sh = &sh;
    t->lab = lab;
    t->count = lab->last - lab->first + 1;
    t->z = lsm_alloc(t->count, sizeof *t->z, err, "heights");
    if (!t->z) {
      st = err ? err->status : LSM_ERR_NOMEM;
      break;
    }
    for (size_t k = 0; k < t->count; ++k)
      t->z[k] = (double)plan->drawn[lab->first + k] * v->spacing[g->axis];
    const size_t span = plan->drawn[lab->last] - plan->drawn[lab->first];
    t->cost = (double)(lab->box[1] - lab->box[0] + 1) * (double)(lab->box[3] - lab->box[2] + 1) *
              (double)span;
    sh.total += span + 1 - t->count; /* its gap slices */
  }
  qsort(task, tasks, sizeof *task, cmp_cost);
  for (int k = 0; k < LOCK_STRIPES; ++k) omp_init_lock(&sh.lock[k]);
  omp_init_lock(&sh.progress_lock);
  /* labels side by side when there are enough of them, else the threads in each */
  const int side_by_side = threads > 1 && tasks >= (size_t)threads;
  lsm_status first_status = st;
  lsm_err first_err;
  lsm_err_clear(&first_err);
  long long iterations = 0, motion_tried = 0, motion_field = 0;
  double solver_seconds = 0.0;
  if (st == LSM_OK) {
#pragma omp parallel for num_threads(side_by_side ? threads : 1) schedule(dynamic, 1) \
    reduction(+ : iterations, solver_seconds, motion_tried, motion_field)
    for (size_t k = 0; k < tasks; ++k) {
      if (failed(&sh)) continue;
      lsm_err e;
      lsm_err_clear(&e);
      task_counts n = {0, 0, 0, 0.0};
      const lsm_status ts = run_task(&task[k], o, side_by_side ? 1 : threads, &n, &e);
      iterations += n.iterations;
      solver_seconds += n.solver_seconds;
      motion_tried += n.motion_tried;
      motion_field += n.motion_field;
      if (ts != LSM_OK) {
#pragma omp critical(lsm_fill_error)
        {
          /* the first failure that is not another run's echo of it */
          if (first_status == LSM_OK || first_status == LSM_ERR_INTERRUPTED) {
            first_status = ts;
            lsm_err_clear(&first_err);
            lsm_fail(&first_err, ts, NULL, "label %lld: %.900s", (long long)task[k].lab->value,
                     e.msg);
          }
        }
#pragma omp atomic write
        sh.failed = 1;
      }
    }
  }
  if (first_status == LSM_ERR_INTERRUPTED && sh.stop && *sh.stop)
    lsm_fail(err, LSM_ERR_INTERRUPTED, NULL, "interrupted");
  else if (first_status != LSM_OK && err && err->status == LSM_OK)
    *err = first_err;
  st = first_status;
  for (int k = 0; k < LOCK_STRIPES; ++k) omp_destroy_lock(&sh.lock[k]);
  omp_destroy_lock(&sh.progress_lock);
  if (st == LSM_OK) {
    stats->runs = tasks;
    stats->iterations = iterations;
    stats->solver_seconds = solver_seconds;
    stats->motion_tried = motion_tried;
    stats->motion_field = motion_field;
    for (size_t k = 0; k < cells; ++k) stats->voxels_filled += sh.depth[k] != 0;
    for (size_t k = 0; k < tasks; ++k) {
      const size_t box = (size_t)task[k].width * (size_t)task[k].height;
      if (box > stats->box_cells_max) stats->box_cells_max = box;
    }
  }
  for (size_t k = 0; k < tasks; ++k) free(task[k].z);
  free(task);
  free(sh.depth);
  stats->seconds = omp_get_wtime() - t0;
  return st;
}
