#include "solver/app/lsm_score.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "io/lsm_io.h"
#include "solver/app/lsm_inputs.h"
#include "solver/app/lsm_metrics.h"
#include "solver/sdf/lsm_sdf.h"

/* A result's run.json, read whole into *text (NUL-terminated), its path in
 * path; *text is NULL when there is none (slices written by another tool,
 * such as a reference).  One that is not JSON is an error: the result is
 * damaged.  Read as JSON, so a run.json saved again by another tool (other
 * spacing, other member order) reads alike. */
static lsm_status read_run_json(const char *result_dir, char path[4200], char **text,
                                lsm_err *err) {
  snprintf(path, 4200, "%s/run.json", result_dir);
  *text = NULL;
  struct stat info;
  if (stat(path, &info) != 0 && errno == ENOENT) return LSM_OK;
  size_t len = 0;
  LSM_TRY(lsm_read_file(path, (size_t)1 << 30, text, &len, err)); /* far above any run.json */
  size_t at = strlen(*text); /* a NUL byte is not JSON */
  if (at == len && lsm_json_find_number(*text, NULL, 0, NULL, &at) >= 0) return LSM_OK;
  free(*text);
  *text = NULL;
  return lsm_fail(err, LSM_ERR_INPUT, path, "not valid JSON (at byte %zu): the result is damaged",
                  at);
}

/* The step from row to row in pixel widths, the unit of score's distances:
 * options.pixel_size_y / options.pixel_size of a result's run.json (text), 1
 * for square pixels and where run.json does not say (text NULL: no run.json,
 * or one written before pixels could be other than square). */
static double result_row_step(const char *text) {
  static const char *const width_key[] = {"options", "pixel_size"};
  static const char *const height_key[] = {"options", "pixel_size_y"};
  double width = 0.0, height = 0.0;
  if (text && lsm_json_find_number(text, width_key, 2, &width, NULL) == 1 &&
      lsm_json_find_number(text, height_key, 2, &height, NULL) == 1 && width > 0.0 &&
      height > 0.0 && isfinite(height / width) && height / width > 0.0)
    return height / width;
  return 1.0;
}

/* Whether a result was made with --invert (options.invert of its run.json):
 * its truth is then dark inside, read as reconstruct read the inputs. */
static int result_inverted(const char *text) {
  static const char *const keys[] = {"options", "invert"};
  int invert = 0;
  return text && lsm_json_find_bool(text, keys, 2, &invert, NULL) == 1 && invert;
}

/* Whether a result was made from outlines (options.input "outline"): its
 * truth slices are then outlines too, filled by parity as its inputs were. */
static int result_from_outlines(const char *text) {
  static const char *const keys[] = {"options", "input"};
  const char *raw = NULL;
  size_t len = 0;
  return text && lsm_json_find_string(text, keys, 2, &raw, &len, NULL) == 1 && len == 7 &&
         memcmp(raw, "outline", 7) == 0;
}

/* The number of input slices a result was made from (input.slices of its
 * run.json, valid JSON); a run.json that does not say is an error. */
static lsm_status result_input_count(const char *text, const char *path, size_t *count,
                                     lsm_err *err) {
  static const char *const keys[] = {"input", "slices"};
  double n = 0.0;
  if (lsm_json_find_number(text, keys, 2, &n, NULL) != 1 ||
      !(n >= 1.0 && n <= 1e15 && n == floor(n)))
    return lsm_fail(err, LSM_ERR_INPUT, path,
                    "does not say how many input slices the result was made from (input.slices)");
  *count = (size_t)n;
  return LSM_OK;
}

/* Where a result's input slices lie among the n_truth truth slices
 * of truth_dir (0-based), from its run.json: the input heights (input.heights) are whole
 * output steps (options.dz) apart, the first input being truth slice first.
 * *pos is allocated, *n_pos entries: no more than the truth has slices. */
static lsm_status result_input_positions(const char *text, const char *path, size_t first,
                                         size_t n_truth, const char *truth_dir, size_t **pos, size_t *n_pos,
                                         lsm_err *err) {
  static const char *const heights_key[] = {"input", "heights"}, *const dz_key[] = {"options", "dz"};
  size_t n = 0;
  double dz = 0.0;
  *pos = NULL;
  *n_pos = 0;
  if (lsm_json_find_numbers(text, heights_key, 2, NULL, 0, &n, NULL) != 1 || n == 0)
    return lsm_fail(err, LSM_ERR_INPUT, path,
                    "does not give the input heights (input.heights): give --stride K");
  if (n > n_truth)
    return lsm_fail(err, LSM_ERR_INPUT, path,
                    "gives %zu input heights, more than the %zu truth slices: the result was "
                    "not made from slices of %s", n, n_truth, truth_dir);
  if (lsm_json_find_number(text, dz_key, 2, &dz, NULL) != 1 || !(dz > 0.0) || !isfinite(dz))
    return lsm_fail(err, LSM_ERR_INPUT, path,
                    "does not give the output step (options.dz): give --stride K");
  double *heights = lsm_alloc(n, sizeof *heights, err, "input heights");
  size_t *at = lsm_alloc(n, sizeof *at, err, "input positions");
  lsm_status st = heights && at ? LSM_OK : (err ? err->status : LSM_ERR_NOMEM);
  if (st == LSM_OK) lsm_json_find_numbers(text, heights_key, 2, heights, n, &n, NULL);
  for (size_t k = 0; st == LSM_OK && k < n; ++k) {
    const double steps = (heights[k] - heights[0]) / dz, whole = nearbyint(steps);
    if (!(fabs(steps - whole) <= 1e-6 * (1.0 + fabs(steps))) || whole > 1e9 ||
        (k > 0 && !(whole > (double)(at[k - 1] - first))))
      st = lsm_fail(err, LSM_ERR_INPUT, path,
                    "input slice %zu lies %.17g output steps (options.dz %.17g) above the first: "
                    "its inputs are not whole steps apart, so they are not slices of one truth "
                    "stack (score needs --dz equal to the truth's slice spacing)",
                    k + 1, steps, dz);
    else
      at[k] = first + (size_t)whole;
  }
  free(heights);
  if (st != LSM_OK) {
    free(at);
    return st;
  }
  *pos = at;
  *n_pos = n;
  return LSM_OK;
}

/* OUT_DIR must be a folder before its run.json is looked for: a missing one
 * is not a result without run.json (that asks for --stride). */
static lsm_status check_result_dir(const char *dir, lsm_err *err) {
  struct stat info;
  if (stat(dir, &info) != 0)
    return errno == ENOENT ? lsm_fail(err, LSM_ERR_INPUT, dir, "no such folder")
                           : lsm_fail(err, LSM_ERR_INPUT, dir, "cannot access folder: %s",
                                      strerror(errno));
  if (!S_ISDIR(info.st_mode))
    return lsm_fail(err, LSM_ERR_INPUT, dir,
                    "not a folder (score TRUTH_DIR OUT_DIR: OUT_DIR is reconstruct's output folder)");
  return LSM_OK;
}

/* Whether dir holds a run.json (a result folder given where the truth goes). */
static int is_dir_with_run_json(const char *dir) {
  char path[4200];
  struct stat info;
  snprintf(path, sizeof path, "%s/run.json", dir);
  return stat(path, &info) == 0 && S_ISREG(info.st_mode);
}

/* Whether two slice file names name the same slice: equal, or equal but for
 * a .png / .tif / .tiff extension (a truth kept as TIFF, inputs as PNG). */
static int same_slice_name(const char *a, const char *b) {
  if (strcmp(a, b) == 0) return 1;
  const char *da = strrchr(a, '.'), *db = strrchr(b, '.');
  if (!da || !db || da - a != db - b || strncmp(a, b, (size_t)(da - a)) != 0) return 0;
  return lsm_is_slice_image_name(a) && lsm_is_slice_image_name(b);
}

/* The truth slice (0-based) that a result's first input is by the file names
 * of its inputs (run.json's input.files): the truth slice of the first name,
 * when input i is named as truth slice first + offsets[i] is, for every one
 * of the n inputs (same_slice_name).  Returns 0 (nothing inferred) otherwise: inputs renamed,
 * from another stack, or a run.json without names. */
static int first_by_names(const char *text, char **truth, size_t n_truth, const size_t *offsets,
                          size_t n, size_t *first) {
  static const char *const files_key[] = {"input", "files"};
  size_t m = 0;
  if (n == 0 || lsm_json_find_strings(text, files_key, 2, NULL, NULL, 0, &m, NULL) != 1 || m != n)
    return 0;
  const char **raw = calloc(n, sizeof *raw);
  size_t *len = calloc(n, sizeof *len), longest = 0;
  char *name = NULL;
  int found = 0;
  if (raw && len) lsm_json_find_strings(text, files_key, 2, raw, len, n, &m, NULL);
  for (size_t i = 0; raw && len && i < n; ++i) longest = len[i] > longest ? len[i] : longest;
  if (raw && len) name = malloc(longest + 1);
  for (size_t i = 0; name && i < n; ++i) {
    if (lsm_json_unescape(raw[i], len[i], name) == (size_t)-1) break;
    if (i == 0) {
      for (size_t j = 0; j < n_truth && !found; ++j)
        if (same_slice_name(lsm_base_name(truth[j]), name)) {
          found = 1;
          *first = j;
        }
      if (!found) break;
    }
    if (*first + offsets[i] >= n_truth ||
        !same_slice_name(lsm_base_name(truth[*first + offsets[i]]), name)) {
      found = 0;
      break;
    }
  }
  free(name);
  free(len);
  free(raw);
  return found;
}

/* The truth slices that are a result's inputs (0-based, increasing): every
 * --stride-th from the first, or, with no --stride, where run.json's input
 * heights put them; the first is --first, else the truth slice named as the
 * first input when every input is named as its truth slice (first_by_names),
 * else the first truth slice.  *inputs: run.json's input count with
 * --stride, 0 without a run.json; from: " from slice N" where the inputs do
 * not start at the first truth slice; *row_step: the unit of the distances
 * (result_row_step), *invert and *outlines: whether it was made with --invert,
 * from outlines, all from the same run.json. */
static lsm_status score_kept(const lsm_cli *cli, char **truth, size_t n_truth, char from[64],
                             size_t **kept, size_t *n_kept, size_t *inputs, double *row_step,
                             int *invert, int *outlines, lsm_err *err) {
  const size_t k = (size_t)cli->stride;
  size_t first = cli->first > 0 ? (size_t)cli->first - 1 : 0;
  char path[4200], *text = NULL;
  LSM_TRY(check_result_dir(cli->result_dir, err));
  LSM_TRY(read_run_json(cli->result_dir, path, &text, err));
  lsm_status st = LSM_OK;
  size_t *offsets = NULL, n_offsets = 0; /* the inputs' truth slices less the first's */
  if (!k && !text) {
    st = lsm_fail(err, LSM_ERR_USAGE, cli->result_dir,
                  "has no run.json to say which slices were its inputs: give --stride K%s",
                  is_dir_with_run_json(cli->truth_dir)
                      ? " (or swap the folders: the truth comes first, then the result)"
                      : "");
  } else if (k && text) {
    st = result_input_count(text, path, inputs, err);
    /* checked against the truth before the count sizes anything */
    if (st == LSM_OK && *inputs > n_truth)
      st = lsm_fail(err, LSM_ERR_INPUT, cli->result_dir,
                    "was made from %zu slices (run.json), more than the %zu truth slices: the "
                    "result was not made from slices of %s", *inputs, n_truth, cli->truth_dir);
    if (st == LSM_OK) offsets = lsm_alloc(*inputs, sizeof *offsets, err, "slice list");
    if (st == LSM_OK && !offsets) st = err ? err->status : LSM_ERR_NOMEM;
    for (size_t i = 0; st == LSM_OK && i < *inputs; ++i) offsets[i] = i * k;
    n_offsets = *inputs;
  } else if (!k) {
    st = result_input_positions(text, path, 0, n_truth, cli->truth_dir, &offsets, &n_offsets, err);
  }
  int named = 0;
  if (st == LSM_OK && cli->first == 0 && text)
    named = first_by_names(text, truth, n_truth, offsets, n_offsets, &first);
  *row_step = result_row_step(text);
  *invert = result_inverted(text);
  *outlines = result_from_outlines(text);
  free(text);
  if (first > 0) snprintf(from, 64, " from slice %zu", first + 1);
  if (st == LSM_OK && named && first > 0) {
    fprintf(stderr,
            "lsmorph: note: the inputs are named as truth slices %zu", first + offsets[0] + 1);
    for (size_t i = 1; i < n_offsets && i < 3; ++i) fprintf(stderr, ", %zu", first + offsets[i] + 1);
    fprintf(stderr, "%s of %s (run.json's input.files), so the first input is truth slice %zu "
                    "(--first 1 counts from the first truth slice instead)\n",
            n_offsets > 3 ? ", ..." : "", cli->truth_dir, first + 1);
  }
  if (st == LSM_OK && k && n_truth <= first + k) /* nothing held out between two inputs */
    st = lsm_fail(err, LSM_ERR_INPUT, cli->truth_dir,
                  "%zu slice images: --stride %zu%s needs at least %zu to hold any out", n_truth, k,
                  from, first + k + 1);
  if (st == LSM_OK && k) {
    *n_kept = (n_truth - 1 - first) / k + 1;
    *kept = lsm_alloc(*n_kept, sizeof **kept, err, "slice list");
    if (!*kept) st = err ? err->status : LSM_ERR_NOMEM;
    for (size_t i = 0; st == LSM_OK && i < *n_kept; ++i) (*kept)[i] = first + i * k;
  } else if (st == LSM_OK) {
    for (size_t i = 0; i < n_offsets; ++i) offsets[i] += first;
    *kept = offsets;
    *n_kept = n_offsets;
    offsets = NULL;
    if ((*kept)[*n_kept - 1] >= n_truth)
      st = lsm_fail(err, LSM_ERR_INPUT, cli->result_dir,
                    "its last input lies at truth slice %zu (run.json's heights and dz, the first "
                    "at slice %zu), but %s has %zu slices (score needs --dz equal to the truth's "
                    "slice spacing)",
                    (*kept)[*n_kept - 1] + 1, first + 1, cli->truth_dir, n_truth);
    if (st == LSM_OK && (*kept)[*n_kept - 1] - first + 1 == *n_kept)
      st = lsm_fail(err, LSM_ERR_INPUT, cli->result_dir,
                    "its inputs are truth slices %zu to %zu, every one: none is held out to score",
                    first + 1, (*kept)[*n_kept - 1] + 1);
  }
  free(offsets);
  if (st != LSM_OK) {
    free(*kept);
    *kept = NULL;
    *n_kept = 0;
  }
  return st;
}

/* A held-out slice's distances count in the means: non-empty on both sides
 * (one side empty: distances undefined; both empty: no boundary to measure). */
static int has_distances(const lsm_slice_score *s) {
  return s->comparable && (s->area_result || s->area_truth);
}

/* A result of another stride or stack would be scored against the wrong
 * slices: its slice count must be the one the kept slices first .. last give,
 * and with --stride run.json's input count (inputs, 0: none) theirs. */
static lsm_status check_result_count(const lsm_cli *cli, size_t n_truth, size_t first,
                                     size_t last, size_t n_kept, size_t inputs,
                                     const char *from, lsm_err *err) {
  char dir[4200], **result = NULL;
  size_t m = 0;
  snprintf(dir, sizeof dir, "%s/slices", cli->result_dir);
  struct stat info;
  if (stat(dir, &info) != 0 && errno == ENOENT && stat(cli->result_dir, &info) == 0)
    return lsm_fail(err, LSM_ERR_INPUT, dir,
                    "no such folder: score reads the result's slices (a reconstruct run with "
                    "--no-slices has none)");
  LSM_TRY(lsm_dir_list_slices(dir, &result, &m, NULL, err));
  lsm_path_list_free(result, m);
  if (m != last - first + 1 && cli->stride)
    return lsm_fail(err, LSM_ERR_INPUT, dir,
                    "%zu slices, but slices %zu, %zu, %zu, ... of the %zu truth slices, "
                    "reconstructed with --spacing %d and the default --dz, give %zu",
                    m, first + 1, first + 1 + (size_t)cli->stride,
                    first + 1 + 2 * (size_t)cli->stride, n_truth, cli->stride, last - first + 1);
  if (m != last - first + 1)
    return lsm_fail(err, LSM_ERR_INPUT, dir,
                    "%zu slices, but its inputs (run.json) are truth slices %zu to %zu, one "
                    "output step (--dz) apart: %zu",
                    m, first + 1, last + 1, last - first + 1);
  if (inputs && inputs != n_kept)
    return lsm_fail(err, LSM_ERR_INPUT, cli->result_dir,
                    "was made from %zu slices (run.json), but --stride %d%s keeps %zu of the %zu "
                    "truth slices",
                    inputs, cli->stride, from, n_kept, n_truth);
  return LSM_OK;
}

/* An input slice comes back exactly: otherwise the result was not made from
 * these slices of this truth.  path: the result's slice; truth: its truth
 * slice; first: the first input's truth slice (0-based). */
static lsm_status check_input_back(const lsm_cli *cli, const char *path, const char *truth,
                                   const lsm_mask *a, const lsm_mask *b, size_t first,
                                   lsm_err *err) {
  if (memcmp(a->pixels, b->pixels, (size_t)a->width * (size_t)a->height) == 0) return LSM_OK;
  if (cli->stride)
    return lsm_fail(err, LSM_ERR_INPUT, path,
                    "differs from the truth slice %s, which --stride %d makes an input: was "
                    "the result made from slices %zu, %zu, %zu, ... of %s?",
                    truth, cli->stride, first + 1, first + 1 + (size_t)cli->stride,
                    first + 1 + 2 * (size_t)cli->stride, cli->truth_dir);
  return lsm_fail(err, LSM_ERR_INPUT, path,
                  "differs from the truth slice %s, which run.json's input heights make "
                  "an input, the first input taken as truth slice %zu (--first N if it "
                  "is slice N): was the result made from slices of %s?",
                  truth, first + 1, cli->truth_dir);
}

/* The held-out slices' scores, summed as they come. */
typedef struct score_sums {
  double dice, hd95, msd, vol_r, vol_t, inter;
  size_t count, incomparable, measured;
  double *pool; /* every boundary distance, for the pooled HD95 */
  size_t pool_n, pool_cap;
  lsm_slice_score *per; /* --per-slice: each slice's scores, and its truth slice */
  size_t *per_at;
} score_sums;

static void add_score(score_sums *t, const lsm_slice_score *s, size_t truth_slice) {
  if (t->per) {
    t->per[t->count] = *s;
    t->per_at[t->count] = truth_slice;
  }
  t->dice += s->dice;
  t->vol_r += (double)s->area_result;
  t->vol_t += (double)s->area_truth;
  t->inter += s->dice * (double)(s->area_result + s->area_truth) / 2.0;
  t->incomparable += !s->comparable;
  if (has_distances(s)) {
    t->hd95 += s->hd95;
    t->msd += s->mean_surface;
    t->measured++;
  }
  t->count++;
}

/* Notes on the truth slices outside the inputs first .. last, which are not scored. */
static void note_unscored(size_t n_truth, size_t first, size_t last) {
  if (first == 1)
    fprintf(stderr, "lsmorph: note: truth slice 1 lies before the first kept slice (2) and is "
                    "not scored\n");
  else if (first > 1)
    fprintf(stderr,
            "lsmorph: note: truth slices 1 to %zu lie before the first kept slice (%zu) and are "
            "not scored\n",
            first, first + 1);
  if (last + 2 == n_truth)
    fprintf(stderr,
            "lsmorph: note: truth slice %zu lies past the last kept slice (%zu) and is not "
            "scored (nothing is extrapolated past it)\n",
            n_truth, last + 1);
  else if (last + 2 < n_truth)
    fprintf(stderr,
            "lsmorph: note: truth slices %zu to %zu lie past the last kept slice (%zu) and are "
            "not scored (nothing is extrapolated past it)\n",
            last + 2, n_truth, last + 1);
}

/* The scores as one JSON object on stdout; undefined ones (no held-out slice,
 * no boundary on both sides, an empty truth) are null, as in run.json. */
static void print_scores(const score_sums *t, double pooled, char **truth, const size_t *kept,
                         size_t n_kept) {
  printf("{\"held_out\": %zu, \"dice_volume\": ", t->count);
  lsm_json_number(stdout, t->vol_r + t->vol_t > 0 ? 2.0 * t->inter / (t->vol_r + t->vol_t) : 1.0);
  printf(", \"dice\": ");
  lsm_json_number(stdout, t->count ? t->dice / (double)t->count : NAN);
  printf(", \"hd95\": ");
  lsm_json_number(stdout, t->measured ? t->hd95 / (double)t->measured : NAN);
  printf(", \"hd95_pooled\": ");
  lsm_json_number(stdout, pooled);
  printf(", \"mean_surface\": ");
  lsm_json_number(stdout, t->measured ? t->msd / (double)t->measured : NAN);
  printf(", \"volume_error\": ");
  lsm_json_number(stdout, t->vol_t > 0 ? (t->vol_r - t->vol_t) / t->vol_t : NAN);
  printf(", \"one_sided_empty\": %zu", t->incomparable);
  if (t->per) {
    printf(", \"slices\": [");
    for (size_t i = 0, below = 0; i < t->count; ++i) {
      const lsm_slice_score *p = &t->per[i];
      const size_t at = t->per_at[i];
      while (below + 1 < n_kept && kept[below + 1] < at) ++below;
      printf("%s{\"truth\": %zu, \"file\": ", i ? ", " : "", at + 1);
      lsm_json_string(stdout, lsm_base_name(truth[at]));
      printf(", \"between\": [%zu, %zu], \"dice\": ", kept[below] + 1, kept[below + 1] + 1);
      lsm_json_number(stdout, p->dice);
      printf(", \"hd95\": ");
      lsm_json_number(stdout, has_distances(p) ? p->hd95 : NAN);
      printf(", \"mean_surface\": ");
      lsm_json_number(stdout, has_distances(p) ? p->mean_surface : NAN);
      printf(", \"area_result\": %zu, \"area_truth\": %zu}", p->area_result, p->area_truth);
    }
    printf("]");
  }
  printf("}\n");
}

lsm_status lsm_score(const lsm_cli *cli, lsm_err *err) {
  char **truth = NULL;
  size_t n = 0, *kept = NULL, n_kept = 0;
  LSM_TRY(lsm_dir_list_slices(cli->truth_dir, &truth, &n, NULL, err));
  size_t inputs = 0; /* run.json's input count, with --stride */
  char from[64] = ""; /* where --stride starts, when not at the first slice */
  double row_step = 1.0; /* pixel height / width: distances are in pixel widths */
  int invert = 0;        /* made with --invert: the truth is dark inside */
  int outlines = 0;      /* made from outlines: so is the truth */
  lsm_status st = score_kept(cli, truth, n, from, &kept, &n_kept, &inputs, &row_step, &invert,
                             &outlines, err);
  lsm_image_read_opts ro = {0, (uint64_t)1 << 28, 0}, ro_truth = ro;
  ro_truth.invert = invert;
  score_sums sums;
  memset(&sums, 0, sizeof sums);
  const size_t first = n_kept ? kept[0] : 0, last = n_kept ? kept[n_kept - 1] : 0;
  if (st == LSM_OK && cli->per_slice) {
    sums.per = lsm_alloc(last - first + 1, sizeof *sums.per, err, "per-slice scores");
    sums.per_at = lsm_alloc(last - first + 1, sizeof *sums.per_at, err, "per-slice scores");
    if (!sums.per || !sums.per_at) st = err ? err->status : LSM_ERR_NOMEM;
  }
  /* truth stored as 0/1 labels is read as such (the result slices are
   * 0/255), decided as reconstruct decided it: over the kept slices alone
   * (one bright pixel in a held-out slice must not change how they read) */
  char **kept_paths = st == LSM_OK ? lsm_alloc(n_kept, sizeof *kept_paths, err, "slice list") : NULL;
  if (st == LSM_OK && !kept_paths) st = err ? err->status : LSM_ERR_NOMEM;
  if (st == LSM_OK) {
    for (size_t i = 0; i < n_kept; ++i) kept_paths[i] = truth[kept[i]];
    st = lsm_pick_foreground(kept_paths, n_kept, &ro_truth, 1, cli->truth_dir, err);
  }
  free(kept_paths);
  if (st == LSM_OK) st = check_result_count(cli, n, first, last, n_kept, inputs, from, err);
  for (size_t k = first, next = 0; st == LSM_OK && k <= last; ++k) {
    char path[4200];
    snprintf(path, sizeof path, "%s/slices/%05zu.png", cli->result_dir, k - first + 1);
    lsm_mask a = {0}, b = {0};
    st = lsm_slice_read_mask(path, &ro, &a, err);
    if (st == LSM_OK) st = lsm_slice_read_mask(truth[k], &ro_truth, &b, err);
    if (st == LSM_OK && outlines) { /* filled as reconstruct filled its inputs */
      lsm_mask filled = {0};
      st = lsm_outline_fill(&b, &filled, err);
      lsm_mask_free(&b);
      b = filled;
    }
    if (st == LSM_OK && (a.width != b.width || a.height != b.height))
      st = lsm_fail(err, LSM_ERR_INPUT, path, "slice is %dx%d but the truth slice %s is %dx%d",
                    a.width, a.height, truth[k], b.width, b.height);
    if (next < n_kept && kept[next] == k) { /* an input slice */
      ++next;
      if (st == LSM_OK) st = check_input_back(cli, path, truth[k], &a, &b, first, err);
    } else {
      lsm_slice_score s;
      if (st == LSM_OK)
        st = lsm_score_slice(&a, &b, row_step, &s, &sums.pool, &sums.pool_n, &sums.pool_cap, err);
      if (st == LSM_OK) add_score(&sums, &s, k);
    }
    lsm_mask_free(&a);
    lsm_mask_free(&b);
  }
  const double pooled = lsm_quantile(sums.pool, sums.pool_n, 0.95);
  free(sums.pool);
  if (st == LSM_OK) {
    note_unscored(n, first, last);
    print_scores(&sums, pooled, truth, kept, n_kept);
  }
  lsm_path_list_free(truth, n);
  free(kept);
  free(sums.per);
  free(sums.per_at);
  return st;
}
