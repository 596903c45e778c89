/* lsm_label_score: score of two label volumes (lsm_label_score.h says what). */
#include "solver/app/lsm_label_score.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/lsm_io.h"
#include "io/lsm_labels.h"
#include "solver/app/lsm_fill_cmd.h"
#include "solver/app/lsm_metrics.h"
#include "solver/sdf/lsm_sdf.h"

int lsm_label_score_wanted(int argc, char **argv) {
  if (argc < 2 || strcmp(argv[1], "score") != 0) return 0;
  int names = 0;
  for (int i = 2; i < argc; ++i) {
    if (argv[i][0] == '-') { /* its value, when given apart, is not a name */
      if (!strchr(argv[i], '=') && (strcmp(argv[i], "--axis") == 0 ||
                                    strcmp(argv[i], "--slices") == 0 ||
                                    strcmp(argv[i], "--labels") == 0))
        ++i;
      continue;
    }
    if (!lsm_labels_is_volume_name(argv[i])) return 0;
    names++;
  }
  return names >= 1;
}

typedef struct score_args {
  const char *truth, *result;
  int axis;            /* -1: from the note */
  long long *slices, *labels;
  size_t n_slices, n_labels;
  int recorded;        /* the slices come from OUT's lsmorph_fill record */
} score_args;

static lsm_status parse_score(int argc, char **argv, score_args *a, lsm_err *err) {
  memset(a, 0, sizeof *a);
  a->axis = -1;
  for (int i = 2; i < argc; ++i) {
    const char *arg = argv[i];
    const char *eq = strchr(arg, '=');
    char name[32];
    snprintf(name, sizeof name, "%.*s", eq ? (int)(eq - arg) : (int)strlen(arg), arg);
    const int valued = strcmp(name, "--axis") == 0 || strcmp(name, "--slices") == 0 ||
                       strcmp(name, "--labels") == 0;
    const char *value = eq ? eq + 1 : NULL;
    if (arg[0] != '-') {
      if (!a->truth) a->truth = arg;
      else if (!a->result) a->result = arg;
      else return lsm_fail(err, LSM_ERR_USAGE, NULL, "score: unexpected argument '%s'", arg);
      continue;
    }
    if (!valued)
      return lsm_fail(err, LSM_ERR_USAGE, NULL,
                      "score: unknown option '%s' for label volumes (--axis, --slices, --labels)",
                      arg);
    if (!value && (value = i + 1 < argc ? argv[++i] : NULL) == NULL)
      return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s needs a value", name);
    if (strcmp(name, "--axis") == 0) {
      if (strlen(value) != 1 || !strchr("ijk", value[0]))
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "--axis: '%s' is not one of i, j, k", value);
      a->axis = value[0] - 'i';
    } else if (strcmp(name, "--slices") == 0) {
      free(a->slices);
      LSM_TRY(lsm_fill_parse_list("--slices", value, 0, &a->slices, &a->n_slices, err));
    } else {
      free(a->labels);
      LSM_TRY(lsm_fill_parse_list("--labels", value, 1, &a->labels, &a->n_labels, err));
    }
  }
  if (!a->truth || !a->result)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "score: needs TRUTH and OUT (two label volumes)");
  return LSM_OK;
}

static int cmp_ll(const void *x, const void *y) {
  const long long a = *(const long long *)x, b = *(const long long *)y;
  return (a > b) - (a < b);
}

/* Sorts and drops repeats. */
static void sort_unique(long long *v, size_t *n) {
  qsort(v, *n, sizeof *v, cmp_ll);
  size_t m = 0;
  for (size_t k = 0; k < *n; ++k)
    if (m == 0 || v[m - 1] != v[k]) v[m++] = v[k];
  *n = m;
}

/* The drawn slices and labels from OUT's note "axis=k drawn=0,4 labels=1,2". */
static lsm_status from_note(const char *note, const char *path, score_args *a, lsm_err *err) {
  const char *axis = strstr(note, "axis="), *drawn = strstr(note, "drawn="),
             *labels = strstr(note, "labels=");
  if (!axis || !drawn || !strchr("ijk", axis[5]) || !axis[5] || (axis[6] && axis[6] != ' '))
    return lsm_fail(err, LSM_ERR_INPUT, path, "its lsmorph_fill record is damaged: '%.80s'", note);
  lsm_status st = LSM_OK;
  if (a->axis < 0) a->axis = axis[5] - 'i';
  char list[1 << 12];
  if (!a->slices) {
    const size_t n = strcspn(drawn + 6, " ");
    char *copy = malloc(n + 1);
    if (!copy) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot read the record");
    memcpy(copy, drawn + 6, n);
    copy[n] = '\0';
    st = lsm_fill_parse_list("drawn", copy, 0, &a->slices, &a->n_slices, err);
    free(copy);
    a->recorded = st == LSM_OK;
  }
  if (st == LSM_OK && !a->labels && labels) {
    const size_t n = strcspn(labels + 7, " ");
    if (n > 0 && n < sizeof list) {
      memcpy(list, labels + 7, n);
      list[n] = '\0';
      st = lsm_fill_parse_list("labels", list, 1, &a->labels, &a->n_labels, err);
    }
  }
  if (st == LSM_OK || st == LSM_ERR_NOMEM) return st;
  /* the list parser's usage message, about the file's record */
  char what[LSM_ERR_MSG_MAX];
  snprintf(what, sizeof what, "%s", err ? err->msg : "");
  if (err) lsm_err_clear(err);
  return lsm_fail(err, LSM_ERR_INPUT, path, "its lsmorph_fill record is damaged: %.300s", what);
}

typedef struct label_score {
  long long label;
  double inter, truth, result;     /* voxels on the slices scored */
  size_t lo[3], hi[3];             /* the box of the label on both sides */
  int seen;
  double *dist;                    /* boundary distances, both ways (physical) */
  size_t n;
} label_score;

static void print_number(double v) { lsm_json_number(stdout, v); }

/* The scored volumes and where the slices lie. */
typedef struct score_space {
  const lsm_voxels *t, *r;
  int axis;
  size_t stride[3];
  const uint8_t *scored;           /* per slice across axis: scored (held out) */
} score_space;

/* Whether voxel (i, j, k) of v holds label and has a 6-neighbour that does
 * not (or lies on the volume's border): on the label's surface. */
static int on_surface(const lsm_voxels *v, const size_t *stride, const size_t ijk[3],
                      long long label) {
  const size_t at = ijk[0] + ijk[1] * stride[1] + ijk[2] * stride[2];
  if (lsm_voxel_get_int(v, at) != label) return 0;
  for (int a = 0; a < 3; ++a) {
    if (ijk[a] == 0 || ijk[a] + 1 == v->n[a]) return 1;
    if (lsm_voxel_get_int(v, at - stride[a]) != label || lsm_voxel_get_int(v, at + stride[a]) != label)
      return 1;
  }
  return 0;
}

/* Squared distance (physical, 3D) from every voxel of the label's box to the
 * nearest surface voxel of `from`: the 2D transform on each slice across the
 * axis, then the 1D one across the slices.  d holds the box's voxels, u, v
 * the in-plane axes; scratch as lsm_edt_squared_1d needs for the longest side. */
static lsm_status surface_distance(const score_space *sp, const lsm_voxels *from, const label_score *sc,
                                   int u, int v, double *d, uint8_t *mask, double *line, double *lout,
                                   int *iv, double *z, lsm_err *err) {
  const int a = sp->axis;
  const size_t nu = sc->hi[u] - sc->lo[u] + 1, nv = sc->hi[v] - sc->lo[v] + 1,
               na = sc->hi[a] - sc->lo[a] + 1, plane = nu * nv;
  for (size_t s = 0; s < na; ++s) {
    for (size_t y = 0; y < nv; ++y)
      for (size_t x = 0; x < nu; ++x) {
        size_t ijk[3];
        ijk[a] = sc->lo[a] + s;
        ijk[u] = sc->lo[u] + x;
        ijk[v] = sc->lo[v] + y;
        mask[y * nu + x] = (uint8_t)on_surface(from, sp->stride, ijk, sc->label);
      }
    LSM_TRY(lsm_edt_squared(mask, (int)nu, (int)nv, from->spacing[u], from->spacing[v],
                            d + s * plane, err));
  }
  for (size_t q = 0; q < plane; ++q) {
    for (size_t s = 0; s < na; ++s) line[s] = d[s * plane + q];
    lsm_edt_squared_1d(line, (int)na, from->spacing[a], lout, iv, z);
    for (size_t s = 0; s < na; ++s) d[s * plane + q] = lout[s];
  }
  return LSM_OK;
}

/* The distances of `to`'s surface voxels on the scored slices to the surface
 * of the other side (d, from surface_distance), appended to sc->dist; a side
 * without the label has no surface: *missing is set. */
static lsm_status collect(const score_space *sp, const lsm_voxels *to, label_score *sc, int u, int v,
                          const double *d, size_t *cap, int *missing, lsm_err *err) {
  const int a = sp->axis;
  const size_t nu = sc->hi[u] - sc->lo[u] + 1, nv = sc->hi[v] - sc->lo[v] + 1,
               na = sc->hi[a] - sc->lo[a] + 1, plane = nu * nv;
  for (size_t s = 0; s < na; ++s) {
    if (!sp->scored[sc->lo[a] + s]) continue;
    for (size_t q = 0; q < plane; ++q) {
      size_t ijk[3];
      ijk[a] = sc->lo[a] + s;
      ijk[u] = sc->lo[u] + q % nu;
      ijk[v] = sc->lo[v] + q / nu;
      if (!on_surface(to, sp->stride, ijk, sc->label)) continue;
      const double dd = d[s * plane + q];
      if (isinf(dd)) {
        *missing = 1;
        continue;
      }
      if (sc->n == *cap) {
        *cap = *cap ? 2 * *cap : 1024;
        double *grown = realloc(sc->dist, *cap * sizeof *grown);
        if (!grown) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot grow the distance list");
        sc->dist = grown;
      }
      sc->dist[sc->n++] = sqrt(dd);
    }
  }
  return LSM_OK;
}

/* One label's distances, both ways; *missing: one side lacks the label. */
static lsm_status label_distances(const score_space *sp, label_score *sc, int *missing, lsm_err *err) {
  static const int in_plane[3][2] = {{1, 2}, {0, 2}, {0, 1}};
  const int a = sp->axis, u = in_plane[a][0], v = in_plane[a][1];
  for (int k = 0; k < 3; ++k) { /* a voxel around, for the surface's outer side */
    if (sc->lo[k] > 0) sc->lo[k]--;
    if (sc->hi[k] + 1 < sp->t->n[k]) sc->hi[k]++;
  }
  const size_t nu = sc->hi[u] - sc->lo[u] + 1, nv = sc->hi[v] - sc->lo[v] + 1,
               na = sc->hi[a] - sc->lo[a] + 1;
  size_t cells = 0, cap = 0;
  if (!lsm_size_mul3(nu, nv, na, &cells) || nu > INT32_MAX / 2 || nv > INT32_MAX / 2 || na > INT32_MAX / 2)
    return lsm_fail(err, LSM_ERR_LIMIT, NULL, "label %lld: its box is too large", sc->label);
  double *d = lsm_alloc(cells, sizeof *d, err, "distances");
  uint8_t *mask = d ? lsm_alloc(nu * nv, 1, err, "surface") : NULL;
  double *line = mask ? lsm_alloc(2 * na + 1, sizeof *line, err, "distances") : NULL;
  double *z = line ? lsm_alloc(na + 1, sizeof *z, err, "distances") : NULL;
  int *iv = z ? lsm_alloc(na, sizeof *iv, err, "distances") : NULL;
  lsm_status st = iv ? LSM_OK : (err ? err->status : LSM_ERR_NOMEM);
  *missing = 0;
  if (st == LSM_OK) st = surface_distance(sp, sp->r, sc, u, v, d, mask, line, line + na, iv, z, err);
  if (st == LSM_OK) st = collect(sp, sp->t, sc, u, v, d, &cap, missing, err);
  if (st == LSM_OK) st = surface_distance(sp, sp->t, sc, u, v, d, mask, line, line + na, iv, z, err);
  if (st == LSM_OK) st = collect(sp, sp->r, sc, u, v, d, &cap, missing, err);
  free(d);
  free(mask);
  free(line);
  free(z);
  free(iv);
  return st;
}

/* The two volumes must lie on one grid (voxel i of one where voxel i of the
 * other is): their index-to-world maps agree within a thousandth of the
 * smallest voxel spacing (NIfTI keeps them as floats). */
static lsm_status check_same_grid(const lsm_label_file *t, const lsm_label_file *r,
                                  const char *result, const char *truth, lsm_err *err) {
  double mt[3][4], mr[3][4];
  lsm_labels_affine(t, mt);
  lsm_labels_affine(r, mr);
  const double *sp = lsm_labels_voxels((lsm_label_file *)t)->spacing;
  double tol = sp[0];
  for (int a = 1; a < 3; ++a) tol = sp[a] < tol ? sp[a] : tol;
  tol *= 1e-3;
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 3; ++row) {
      /* a column's difference times the voxels along it: the far corner's shift */
      const double reach = c < 3 ? (double)lsm_labels_voxels((lsm_label_file *)t)->n[c] : 1.0;
      if (!(fabs(mt[row][c] - mr[row][c]) * reach <= tol))
        return lsm_fail(err, LSM_ERR_INPUT, result,
                        "not on %s's grid: the same voxel counts, but its %s%s is (%g, %g, %g) "
                        "in LPS, and %s's (%g, %g, %g); score volumes on one grid (resample one "
                        "onto the other with nearest neighbour)",
                        truth, c < 3 ? "voxel step along " : "origin",
                        c < 3 ? (const char[]){"ijk"[c], '\0'} : "", mr[0][c], mr[1][c],
                        mr[2][c], truth, mt[0][c], mt[1][c], mt[2][c]);
    }
  return LSM_OK;
}

lsm_status lsm_label_score_main(int argc, char **argv, lsm_err *err) {
  score_args a;
  lsm_status st = parse_score(argc, argv, &a, err);
  lsm_label_file *ft = NULL, *fr = NULL;
  if (st == LSM_OK) st = lsm_labels_read(a.truth, 0, &ft, err);
  if (st == LSM_OK) st = lsm_labels_read(a.result, 0, &fr, err);
  int converted = 0;
  if (st == LSM_OK) st = lsm_labels_to_integer(ft, &converted, err);
  if (st == LSM_OK) st = lsm_labels_to_integer(fr, &converted, err);
  const lsm_voxels *t = st == LSM_OK ? lsm_labels_voxels(ft) : NULL;
  const lsm_voxels *r = st == LSM_OK ? lsm_labels_voxels(fr) : NULL;
  if (st == LSM_OK && memcmp(t->n, r->n, sizeof t->n) != 0)
    st = lsm_fail(err, LSM_ERR_INPUT, a.result, "%zu x %zu x %zu voxels, but %s has %zu x %zu x %zu",
                  r->n[0], r->n[1], r->n[2], a.truth, t->n[0], t->n[1], t->n[2]);
  if (st == LSM_OK) st = check_same_grid(ft, fr, a.result, a.truth, err);
  if (st == LSM_OK && !a.slices) {
    const char *note = lsm_labels_note(fr, "lsmorph_fill");
    if (!note)
      st = lsm_fail(err, LSM_ERR_USAGE, a.result,
                    "does not record which slices were drawn (lsmorph fill records it): give "
                    "--slices LIST and --axis");
    else
      st = from_note(note, a.result, &a, err);
  } else if (st == LSM_OK && a.labels == NULL) {
    const char *note = lsm_labels_note(fr, "lsmorph_fill");
    if (note) st = from_note(note, a.result, &a, err);
  }
  if (st == LSM_OK && a.axis < 0) {
    a.axis = 0;
    for (int k = 1; k < 3; ++k)
      if (t->spacing[k] >= t->spacing[a.axis] * (1 - 1e-6)) a.axis = k;
  }
  if (st == LSM_OK) {
    sort_unique(a.slices, &a.n_slices);
    for (size_t k = 0; k < a.n_slices && st == LSM_OK; ++k)
      if (a.slices[k] < 0 || (size_t)a.slices[k] >= t->n[a.axis])
        st = a.recorded ? lsm_fail(err, LSM_ERR_INPUT, a.result,
                                   "its lsmorph_fill record names slice %lld, past the last slice "
                                   "across %c: the record is damaged, or not this volume's",
                                   a.slices[k], "ijk"[a.axis])
                        : lsm_fail(err, LSM_ERR_USAGE, NULL,
                                   "--slices: %lld is past the last slice across %c", a.slices[k],
                                   "ijk"[a.axis]);
    if (st == LSM_OK && a.n_slices < 2)
      st = a.recorded ? lsm_fail(err, LSM_ERR_INPUT, a.result,
                                 "its lsmorph_fill record names fewer than two drawn slices: the "
                                 "record is damaged; give --slices LIST and --axis")
                      : lsm_fail(err, LSM_ERR_USAGE, NULL,
                                 "at least two drawn slices are needed to score between");
  }
  const size_t stride[3] = {1, t ? t->n[0] : 0, t ? t->n[0] * t->n[1] : 0};
  /* the labels: given, recorded, else every value met on the scored slices */
  label_score *ls = NULL;
  size_t nl = 0;
  const size_t first = st == LSM_OK ? (size_t)a.slices[0] : 0;
  const size_t last = st == LSM_OK ? (size_t)a.slices[a.n_slices - 1] : 0;
  size_t held = 0;
  /* the scored slices */
  uint8_t *scored = st == LSM_OK ? calloc(t->n[a.axis], 1) : NULL;
  if (st == LSM_OK && !scored) st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot list the slices");
  size_t d = 0;
  for (size_t s = first + 1; st == LSM_OK && s < last; ++s) {
    while (d < a.n_slices && (size_t)a.slices[d] < s) ++d;
    if ((size_t)a.slices[d] != s) {
      scored[s] = 1;
      held++;
    }
  }
  if (st == LSM_OK && !a.labels) { /* every value met on them */
    size_t cap = 64;
    a.labels = malloc(cap * sizeof *a.labels);
    if (!a.labels) st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot list the labels");
    for (size_t k = 0, at = 0; st == LSM_OK && k < t->n[2]; ++k)
      for (size_t j = 0; st == LSM_OK && j < t->n[1]; ++j)
        for (size_t i = 0; i < t->n[0]; ++i, ++at) {
          const size_t ijk[3] = {i, j, k};
          if (!scored[ijk[a.axis]]) continue;
          const long long x[2] = {lsm_voxel_get_int(t, at), lsm_voxel_get_int(r, at)};
          for (int side = 0; side < 2; ++side) {
            if (!x[side] || (a.n_labels && a.labels[a.n_labels - 1] == x[side])) continue;
            if (a.n_labels == cap) {
              sort_unique(a.labels, &a.n_labels);
              if (a.n_labels > cap / 2) {
                long long *grown = cap < ((size_t)1 << 20) ? realloc(a.labels, 2 * cap * sizeof *grown) : NULL;
                if (!grown) {
                  st = lsm_fail(err, LSM_ERR_INPUT, NULL, "too many labels to score");
                  break;
                }
                a.labels = grown;
                cap *= 2;
              }
            }
            a.labels[a.n_labels++] = x[side];
          }
        }
  }
  if (st == LSM_OK) {
    sort_unique(a.labels, &a.n_labels);
    nl = a.n_labels;
    ls = calloc(nl ? nl : 1, sizeof *ls);
    if (!ls) st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the scores");
    for (size_t l = 0; ls && l < nl; ++l) ls[l].label = a.labels[l];
  }
  /* per label the voxels on the scored slices, and its box on both sides */
  for (size_t k = 0, at = 0; st == LSM_OK && k < t->n[2]; ++k)
    for (size_t j = 0; j < t->n[1]; ++j)
      for (size_t i = 0; i < t->n[0]; ++i, ++at) {
        const long long x[2] = {lsm_voxel_get_int(t, at), lsm_voxel_get_int(r, at)};
        if (!x[0] && !x[1]) continue;
        const size_t ijk[3] = {i, j, k};
        const int in_scored = scored[ijk[a.axis]];
        for (int side = 0; side < 2; ++side) {
          if (!x[side] || (side == 1 && x[1] == x[0])) continue;
          long long *hit = bsearch(&x[side], a.labels, nl, sizeof *a.labels, cmp_ll);
          if (!hit) continue;
          label_score *sc = &ls[hit - a.labels];
          for (int q = 0; q < 3; ++q) {
            if (!sc->seen || ijk[q] < sc->lo[q]) sc->lo[q] = ijk[q];
            if (!sc->seen || ijk[q] > sc->hi[q]) sc->hi[q] = ijk[q];
          }
          sc->seen = 1;
          if (in_scored) {
            const int both = x[0] == x[1];
            sc->truth += side == 0 || both;
            sc->result += side == 1 || both;
            sc->inter += both;
          }
        }
      }
  const score_space space = {t, r, a.axis, {stride[0], stride[1], stride[2]}, scored};
  int *missing = st == LSM_OK ? calloc(nl ? nl : 1, sizeof *missing) : NULL;
  if (st == LSM_OK && !missing) st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the scores");
  for (size_t l = 0; st == LSM_OK && l < nl; ++l)
    if (ls[l].seen) st = label_distances(&space, &ls[l], &missing[l], err);
  if (st == LSM_OK) {
    printf("{\"truth\": ");
    lsm_json_string(stdout, a.truth);
    printf(", \"result\": ");
    lsm_json_string(stdout, a.result);
    printf(", \"axis\": \"%c\", \"drawn\": %zu, \"held_out\": %zu, \"labels\": [", "ijk"[a.axis],
           a.n_slices, held);
    double dice = 0, hd = 0, msd = 0, inter = 0, size = 0;
    size_t n_hd = 0, n_msd = 0;
    for (size_t l = 0; l < nl; ++l) {
      label_score *sc = &ls[l];
      const double di = sc->truth + sc->result > 0 ? 2.0 * sc->inter / (sc->truth + sc->result) : 1.0;
      double total = 0.0;
      for (size_t k = 0; k < sc->n; ++k) total += sc->dist[k];
      const double ms = sc->n && !missing[l] ? total / (double)sc->n : NAN;
      const double h95 = sc->n && !missing[l] ? lsm_quantile(sc->dist, sc->n, 0.95) : NAN;
      printf("%s{\"label\": %lld, \"dice\": ", l ? ", " : "", sc->label);
      print_number(di);
      printf(", \"hd95\": ");
      print_number(h95);
      printf(", \"mean_surface\": ");
      print_number(ms);
      printf(", \"voxels_truth\": %.0f, \"voxels_result\": %.0f}", sc->truth, sc->result);
      dice += di;
      if (isfinite(h95)) { hd += h95; n_hd++; }
      if (isfinite(ms)) { msd += ms; n_msd++; }
      inter += sc->inter;
      size += sc->truth + sc->result;
    }
    printf("], \"mean\": {\"dice\": ");
    print_number(nl ? dice / (double)nl : NAN);
    printf(", \"hd95\": ");
    print_number(n_hd ? hd / (double)n_hd : NAN);
    printf(", \"mean_surface\": ");
    print_number(n_msd ? msd / (double)n_msd : NAN);
    printf("}, \"dice_pooled\": ");
    print_number(size > 0 ? 2.0 * inter / size : NAN);
    printf("}\n");
  }
  for (size_t l = 0; ls && l < nl; ++l) free(ls[l].dist);
  free(ls);
  free(scored);
  free(missing);
  free(a.slices);
  free(a.labels);
  lsm_labels_free(&ft);
  lsm_labels_free(&fr);
  return st;
}
