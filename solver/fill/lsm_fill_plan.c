/* lsm_fill_plan: what a fill will do, read off the volume in two passes: the
 * whole volume once (its labels, and which slices along each axis hold one),
 * then the drawn slices (each label's sections: where its stack starts and
 * ends, and the box it is cropped to). */
#include "solver/fill/fill_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void lsm_fill_opts_default(lsm_fill_opts *o) {
  memset(o, 0, sizeof *o);
  o->axis = -1;
  lsm_stack_opts_default(&o->stack);
}

int lsm_fill_default_axis(const double spacing[3]) {
  int axis = 0;
  for (int a = 1; a < 3; ++a) /* the last on ties (within float noise) */
    if (spacing[a] >= spacing[axis] * (1.0 - 1e-6)) axis = a;
  return axis;
}

void fill_geometry_of(const lsm_voxels *v, int axis, fill_geometry *g) {
  static const int in_plane[3][2] = {{1, 2}, {0, 2}, {0, 1}};
  g->axis = axis;
  g->u = in_plane[axis][0];
  g->v = in_plane[axis][1];
  g->stride[0] = 1;
  g->stride[1] = v->n[0];
  g->stride[2] = v->n[0] * v->n[1];
  g->width = v->n[g->u];
  g->height = v->n[g->v];
  g->slices = v->n[axis];
}

/* ---- the distinct values of a volume (open addressing) -------------------------------- */

#define VALUES_MAX ((size_t)1 << 20)

typedef struct value_set {
  int64_t *key;
  uint8_t *used;
  size_t cap, count;
} value_set;

static size_t slot_of(int64_t key, size_t cap) {
  uint64_t h = (uint64_t)key * 0x9E3779B97F4A7C15ull;
  return (size_t)(h >> 20) & (cap - 1);
}

static lsm_status value_set_add(value_set *s, int64_t key, lsm_err *err) {
  if (2 * (s->count + 1) > s->cap) { /* keep the load at most one half */
    if (s->count >= VALUES_MAX)
      return lsm_fail(err, LSM_ERR_INPUT, NULL,
                      "more than %zu distinct values: not a label map", VALUES_MAX);
    value_set grown = {NULL, NULL, s->cap ? 2 * s->cap : 64, 0};
    grown.key = malloc(grown.cap * sizeof *grown.key);
    grown.used = calloc(grown.cap, 1);
    if (!grown.key || !grown.used) {
      free(grown.key);
      free(grown.used);
      return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the label table");
    }
    for (size_t k = 0; k < s->cap; ++k)
      if (s->used[k]) {
        size_t at = slot_of(s->key[k], grown.cap);
        while (grown.used[at]) at = (at + 1) & (grown.cap - 1);
        grown.used[at] = 1;
        grown.key[at] = s->key[k];
        grown.count++;
      }
    free(s->key);
    free(s->used);
    *s = grown;
  }
  size_t at = slot_of(key, s->cap);
  while (s->used[at]) {
    if (s->key[at] == key) return LSM_OK;
    at = (at + 1) & (s->cap - 1);
  }
  s->used[at] = 1;
  s->key[at] = key;
  s->count++;
  return LSM_OK;
}

static int cmp_i64(const void *a, const void *b) {
  const int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return (x > y) - (x < y);
}

static int cmp_size(const void *a, const void *b) {
  const size_t x = *(const size_t *)a, y = *(const size_t *)b;
  return (x > y) - (x < y);
}

/* The index of value in sorted[0 .. n), or -1. */
static long find_i64(const int64_t *sorted, size_t n, int64_t value) {
  size_t lo = 0, hi = n;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (sorted[mid] < value) lo = mid + 1; else hi = mid;
  }
  return lo < n && sorted[lo] == value ? (long)lo : -1;
}

int fill_is_label(const lsm_fill_plan *plan, int64_t value) {
  const fill_internal *in = plan->internal;
  if (in->every_label) return value != 0;
  return value != 0 && find_i64(plan->labels, plan->n_labels, value) >= 0;
}

size_t fill_gap_index(const lsm_fill_plan *plan, size_t s) {
  /* drawn slices in (drawn[0], s]: the count of drawn entries <= s, less one */
  size_t lo = 0, hi = plan->n_drawn;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (plan->drawn[mid] <= s) lo = mid + 1; else hi = mid;
  }
  return (s - plan->drawn[0]) - (lo - 1) - 1;
}

/* Row (j, k) of v as int64 values. */
static void read_row(const lsm_voxels *v, size_t j, size_t k, int64_t *row) {
  const size_t n = v->n[0], base = (k * v->n[1] + j) * n;
#define ROW(T)                                                                  \
  do {                                                                          \
    const T *p = (const T *)v->data + base;                                     \
    for (size_t i = 0; i < n; ++i) row[i] = (int64_t)p[i];                      \
  } while (0)
  switch (v->type) {
  case LSM_VOXEL_U8: ROW(uint8_t); break;
  case LSM_VOXEL_I8: ROW(int8_t); break;
  case LSM_VOXEL_U16: ROW(uint16_t); break;
  case LSM_VOXEL_I16: ROW(int16_t); break;
  case LSM_VOXEL_U32: ROW(uint32_t); break;
  case LSM_VOXEL_I32: ROW(int32_t); break;
  case LSM_VOXEL_I64: ROW(int64_t); break;
  default:
    for (size_t i = 0; i < n; ++i) row[i] = lsm_voxel_get_int(v, base + i);
  }
#undef ROW
}

/* ---- pass 1: the labels, and the slices along each axis that hold one ------------------ */

typedef struct scan {
  uint8_t *holds[3];   /* holds[a][s]: slice s across axis a holds a label to fill */
  value_set values;    /* every distinct non-zero value */
  uint8_t *asked_seen; /* per label asked for: seen in the volume */
} scan;

static lsm_status scan_volume(const lsm_voxels *v, const int64_t *asked, size_t n_asked,
                              scan *sc, lsm_err *err) {
  int64_t *row = lsm_alloc(v->n[0], sizeof *row, err, "row");
  if (!row) return err ? err->status : LSM_ERR_NOMEM;
  lsm_status st = LSM_OK;
  for (size_t k = 0; st == LSM_OK && k < v->n[2]; ++k)
    for (size_t j = 0; st == LSM_OK && j < v->n[1]; ++j) {
      read_row(v, j, k, row);
      int64_t last = 0;
      int last_fill = 0, any = 0;
      for (size_t i = 0; i < v->n[0]; ++i) {
        const int64_t x = row[i];
        if (x == 0) continue;
        if (x != last || !any) {
          last = x;
          if (asked) {
            const long at = find_i64(asked, n_asked, x);
            last_fill = at >= 0;
            if (at >= 0) sc->asked_seen[at] = 1;
          } else {
            last_fill = 1;
          }
          if ((st = value_set_add(&sc->values, x, err)) != LSM_OK) break;
        }
        any = 1;
        if (last_fill) {
          sc->holds[0][i] = 1;
          sc->holds[1][j] = 1;
          sc->holds[2][k] = 1;
        }
      }
    }
  free(row);
  return st;
}

/* The drawn slices found along a: those holding a label, and one typical step
 * (the median step between them) beyond the first and the last, where the
 * volume has it.  drawn holds n + 2 entries. */
static void find_drawn(const uint8_t *holds, size_t n, lsm_fill_plan *p, size_t *steps) {
  size_t count = 0;
  for (size_t s = 0; s < n; ++s)
    if (holds[s]) p->drawn[count++] = s;
  p->n_found = count;
  p->added[0] = p->added[1] = SIZE_MAX;
  p->step = 0;
  if (count >= 2) {
    for (size_t k = 0; k + 1 < count; ++k) steps[k] = p->drawn[k + 1] - p->drawn[k];
    qsort(steps, count - 1, sizeof *steps, cmp_size);
    p->step = steps[(count - 2) / 2]; /* the lower median */
  }
  if (count >= 1 && p->step > 0) {
    const size_t first = p->drawn[0], last = p->drawn[count - 1];
    if (first >= p->step) p->added[0] = first - p->step;
    if (last + p->step < n) p->added[1] = last + p->step;
  }
  size_t m = 0;
  if (p->added[0] != SIZE_MAX) {
    memmove(p->drawn + 1, p->drawn, count * sizeof *p->drawn);
    p->drawn[0] = p->added[0];
    m = 1;
  }
  m += count;
  if (p->added[1] != SIZE_MAX) p->drawn[m++] = p->added[1];
  p->n_drawn = m;
}

/* An axis other than `axis` along which the labels lie on separate slices
 * (blank slices between slices holding one), or -1. */
static int other_axis(const scan *sc, const lsm_voxels *v, int axis) {
  for (int b = 2; b >= 0; --b) {
    if (b == axis) continue;
    size_t first = SIZE_MAX, last = 0, count = 0;
    for (size_t s = 0; s < v->n[b]; ++s)
      if (sc->holds[b][s]) {
        if (first == SIZE_MAX) first = s;
        last = s;
        count++;
      }
    if (count >= 2 && last - first + 1 > count) return b;
  }
  return -1;
}

/* ---- pass 2: each label's sections on the drawn slices ---------------------------------- */

static void scan_drawn(const lsm_voxels *v, lsm_fill_plan *p) {
  fill_internal *in = p->internal;
  const fill_geometry *g = &in->geo;
  for (size_t l = 0; l < p->n_labels; ++l) {
    in->label[l].value = p->labels[l];
    in->label[l].box[0] = in->label[l].box[2] = SIZE_MAX;
  }
  for (size_t d = 0; d < p->n_drawn; ++d) {
    const size_t base = p->drawn[d] * g->stride[g->axis];
    int64_t last = 0;
    long at = -1;
    for (size_t y = 0; y < g->height; ++y)
      for (size_t x = 0; x < g->width; ++x) {
        const int64_t value = lsm_voxel_get_int(v, base + x * g->stride[g->u] + y * g->stride[g->v]);
        if (value == 0) continue;
        if (value != last || at < 0) {
          last = value;
          at = find_i64(p->labels, p->n_labels, value);
        }
        if (at < 0) continue;
        fill_label *lab = &in->label[at];
        if (!lab->present) lab->first = d;
        lab->present = 1;
        lab->last = d;
        if (lab->box[0] == SIZE_MAX || x < lab->box[0]) lab->box[0] = x;
        if (lab->box[0] == SIZE_MAX || x > lab->box[1]) lab->box[1] = x;
        if (lab->box[2] == SIZE_MAX || y < lab->box[2]) lab->box[2] = y;
        if (lab->box[2] == SIZE_MAX || y > lab->box[3]) lab->box[3] = y;
      }
  }
  for (size_t l = 0; l < p->n_labels; ++l) { /* one drawn slice beyond each end */
    fill_label *lab = &in->label[l];
    if (!lab->present) continue;
    if (lab->first > 0) lab->first--;
    if (lab->last + 1 < p->n_drawn) lab->last++;
  }
}

void lsm_fill_plan_free(lsm_fill_plan **p) {
  if (!p || !*p) return;
  fill_internal *in = (*p)->internal;
  if (in) free(in->label);
  free(in);
  free((*p)->drawn);
  free((*p)->labels);
  free((*p)->absent);
  free(*p);
  *p = NULL;
}

static const char axis_name[3] = {'i', 'j', 'k'};

lsm_status lsm_fill_plan_make(const lsm_voxels *v, const lsm_fill_opts *o, lsm_fill_plan **out,
                              lsm_err *err) {
  *out = NULL;
  if (!lsm_voxel_is_integer(v->type))
    return lsm_fail(err, LSM_ERR_INPUT, NULL,
                    "the volume holds %s values: labels are integers (convert it first)",
                    lsm_voxel_type_name(v->type));
  for (int a = 0; a < 3; ++a) /* lengths the floats of the run hold */
    if (!lsm_length_in_range(v->spacing[a]) || !lsm_length_in_range(v->spacing[a] * (double)v->n[a]))
      return lsm_fail(err, LSM_ERR_INPUT, NULL,
                      "the voxel spacing along %c is %g, and %zu voxels span %g: outside %g to "
                      "%g (lengths are held as floats; write the volume in a unit that brings "
                      "them into range)",
                      axis_name[a], v->spacing[a], v->n[a], v->spacing[a] * (double)v->n[a],
                      LSM_LENGTH_MIN, LSM_LENGTH_MAX);
  size_t count = 0;
  LSM_TRY(lsm_voxels_count(v->n, v->type, &count, NULL, err));
  const int axis = o->axis >= 0 && o->axis < 3 ? o->axis : lsm_fill_default_axis(v->spacing);
  lsm_fill_plan *p = calloc(1, sizeof *p);
  fill_internal *in = calloc(1, sizeof *in);
  scan sc;
  memset(&sc, 0, sizeof sc);
  int64_t *asked = NULL;
  size_t n_asked = 0;
  lsm_status st = p && in ? LSM_OK : lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot plan the fill");
  if (st == LSM_OK) {
    p->internal = in;
    p->axis = axis;
    fill_geometry_of(v, axis, &in->geo);
    if (in->geo.width > (size_t)1 << 24 || in->geo.height > (size_t)1 << 24 ||
        in->geo.width * in->geo.height > (size_t)LSM_GRID_CELLS_MAX)
      st = lsm_fail(err, LSM_ERR_LIMIT, NULL,
                    "slices of %zu x %zu voxels across %c: more than a working grid holds",
                    in->geo.width, in->geo.height, axis_name[axis]);
  }
  if (st == LSM_OK && o->labels) { /* the labels asked for, sorted, once each */
    asked = lsm_alloc(o->n_labels ? o->n_labels : 1, sizeof *asked, err, "labels");
    if (!asked) st = err ? err->status : LSM_ERR_NOMEM;
    for (size_t k = 0; st == LSM_OK && k < o->n_labels; ++k) {
      if (o->labels[k] == 0)
        st = lsm_fail(err, LSM_ERR_USAGE, NULL, "--labels: 0 is the background, not a label");
      asked[k] = o->labels[k];
    }
    if (st == LSM_OK) {
      qsort(asked, o->n_labels, sizeof *asked, cmp_i64);
      for (size_t k = 0; k < o->n_labels; ++k)
        if (n_asked == 0 || asked[n_asked - 1] != asked[k]) asked[n_asked++] = asked[k];
    }
  }
  for (int a = 0; st == LSM_OK && a < 3; ++a) {
    sc.holds[a] = calloc(v->n[a], 1);
    if (!sc.holds[a]) st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the slice table");
  }
  if (st == LSM_OK && asked) {
    sc.asked_seen = calloc(n_asked, 1);
    if (!sc.asked_seen) st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the label table");
  }
  if (st == LSM_OK) st = scan_volume(v, asked, n_asked, &sc, err);
  if (st == LSM_OK) p->n_values = sc.values.count;
  for (size_t k = 0; st == LSM_OK && asked && k < n_asked; ++k)
    if (!sc.asked_seen[k])
      st = lsm_fail(err, LSM_ERR_INPUT, NULL, "--labels: %lld is not in the volume",
                    (long long)asked[k]);
  /* the labels filled, increasing */
  if (st == LSM_OK) {
    in->every_label = asked == NULL;
    if (asked) {
      p->labels = asked;
      p->n_labels = n_asked;
      asked = NULL;
    } else {
      p->labels = lsm_alloc(sc.values.count ? sc.values.count : 1, sizeof *p->labels, err, "labels");
      if (!p->labels) st = err ? err->status : LSM_ERR_NOMEM;
      for (size_t k = 0; st == LSM_OK && k < sc.values.cap; ++k)
        if (sc.values.used[k]) p->labels[p->n_labels++] = sc.values.key[k];
      if (st == LSM_OK) qsort(p->labels, p->n_labels, sizeof *p->labels, cmp_i64);
    }
  }
  /* the drawn slices */
  const size_t n = v->n[axis];
  size_t *steps = NULL;
  if (st == LSM_OK) {
    p->drawn = lsm_alloc((o->slices ? o->n_slices : n) + 2, sizeof *p->drawn, err, "slice list");
    steps = lsm_alloc(n + 2, sizeof *steps, err, "slice list");
    if (!p->drawn || !steps) st = err ? err->status : LSM_ERR_NOMEM;
  }
  if (st == LSM_OK && o->slices) {
    for (size_t k = 0; st == LSM_OK && k < o->n_slices; ++k) {
      if (o->slices[k] >= n)
        st = lsm_fail(err, LSM_ERR_USAGE, NULL,
                      "--slices: %zu is past the last slice across %c (0 .. %zu)", o->slices[k],
                      axis_name[axis], n - 1);
      p->drawn[k] = o->slices[k];
    }
    if (st == LSM_OK) {
      qsort(p->drawn, o->n_slices, sizeof *p->drawn, cmp_size);
      for (size_t k = 0; k < o->n_slices; ++k)
        if (p->n_drawn == 0 || p->drawn[p->n_drawn - 1] != p->drawn[k])
          p->drawn[p->n_drawn++] = p->drawn[k];
      p->added[0] = p->added[1] = SIZE_MAX;
    }
  } else if (st == LSM_OK) {
    find_drawn(sc.holds[axis], n, p, steps);
  }
  free(steps);
  if (st == LSM_OK) p->other_axis = other_axis(&sc, v, axis);
  if (st == LSM_OK && p->n_drawn < 2) {
    const int b = p->other_axis;
    char hint[160] = "";
    if (b >= 0 && !o->slices)
      snprintf(hint, sizeof hint, "; across %c the labels lie on separate slices: --axis %c",
               axis_name[b], axis_name[b]);
    if (o->slices)
      st = lsm_fail(err, LSM_ERR_INPUT, NULL,
                    "--slices gives %zu drawn slice%s: at least two are needed to fill between",
                    p->n_drawn, p->n_drawn == 1 ? "" : "s");
    else if (p->n_found == 0)
      st = lsm_fail(err, LSM_ERR_INPUT, NULL, "no slice holds a label to fill: nothing to fill");
    else
      st = lsm_fail(err, LSM_ERR_INPUT, NULL,
                    "across %c only slice %zu holds labels: at least two drawn slices are needed "
                    "to fill between%s",
                    axis_name[axis], p->drawn[0], hint);
  }
  if (st == LSM_OK) {
    p->gap_slices = p->drawn[p->n_drawn - 1] - p->drawn[0] + 1 - p->n_drawn;
    in->label = calloc(p->n_labels ? p->n_labels : 1, sizeof *in->label);
    p->absent = lsm_alloc(p->n_labels ? p->n_labels : 1, sizeof *p->absent, err, "labels");
    if (!in->label || !p->absent) st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot plan the fill");
  }
  if (st == LSM_OK) {
    scan_drawn(v, p);
    for (size_t l = 0; l < p->n_labels; ++l)
      if (!in->label[l].present) p->absent[p->n_absent++] = p->labels[l];
  }
  for (int a = 0; a < 3; ++a) free(sc.holds[a]);
  free(sc.values.key);
  free(sc.values.used);
  free(sc.asked_seen);
  free(asked);
  if (st != LSM_OK) {
    lsm_fill_plan_free(&p);
    return st;
  }
  *out = p;
  return LSM_OK;
}
