/* lsm_fill_cmd: `lsmorph fill`: the command line, the notes, and the run:
 * read LABELS (io/lsm_labels.h), plan and fill (solver/fill/lsm_fill.h),
 * write OUT.  The options fill shares with reconstruct are parsed by
 * reconstruct's own parser (lsm_cli_parse), so they mean the same. */
#include "solver/app/lsm_fill_cmd.h"

#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "io/lsm_labels.h"
#include "solver/app/lsm_checks.h"
#include "solver/app/lsm_cli.h"
#include "solver/app/lsm_out_file.h"
#include "solver/app/lsm_signals.h"
#include "solver/fill/lsm_fill.h"
#include "solver/pde/lsm_backend.h"

/* The options of reconstruct that fill takes: those with a value, then flags. */
static const char *const shared_valued[] = {
    "--method", "--interp", "--ends", "--align", "--motion", "--scheme", "--time", "--cfl",
    "--reinit-every", "--reinit-iters", "--max-iter", "--particles-per-cell", "--pls-reseed",
    "--seed", "--backend", "--device", "--max-voxels", "--max-memory", "--rules-off", NULL};
static const char *const shared_flags[] = {"--pls-radius-adjust", "-q", "--quiet", NULL};
/* fill's own options with a value */
static const char *const own_valued[] = {"-o", "--output", "--axis", "--slices", "--labels",
                                         "--threads", NULL};
/* reconstruct's options that say nothing to fill, and why */
static const char *const not_for_fill[] = {
    "--spacing", "--heights", "--heights-from-names", "--pixel-size", "--dz", "--per-iteration",
    "--no-slices", "--format", "--values", "--nrrd-encoding", "--mesh", "--no-preview",
    "--input", "--invert", "--tol", "--max-pixels", NULL};

static int in_list(const char *name, const char *const *list) {
  for (; *list; ++list)
    if (strcmp(name, *list) == 0) return 1;
  return 0;
}

/* An option's name as fill reads it: up to '=', with '_' for '-' after the
 * leading dashes (3D Slicer's flags cannot hold '-'). */
static void option_name(const char *arg, char *name, size_t cap) {
  size_t k = 0;
  for (; arg[k] && arg[k] != '=' && k + 1 < cap; ++k)
    name[k] = k >= 2 && arg[k] == '_' ? '-' : arg[k];
  name[k] = '\0';
}

static int takes_value(const char *name) {
  return in_list(name, shared_valued) || in_list(name, own_valued);
}

int lsm_fill_wanted(int argc, char **argv) {
  if (argc < 2) return 0;
  if (strcmp(argv[1], "fill") == 0) return 1;
  if (argc == 2 && strcmp(argv[1], "--xml") == 0) return 1;
  if (argc >= 3 && strcmp(argv[2], "fill") == 0 &&
      (strcmp(argv[1], "help") == 0 || strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0))
    return 1;
  /* 3D Slicer's: flags of fill first, then "fill" */
  int i = 1;
  while (i < argc && strncmp(argv[i], "--", 2) == 0 && argv[i][2]) {
    char name[64];
    option_name(argv[i], name, sizeof name);
    if (!takes_value(name) && !in_list(name, shared_flags)) return 0;
    i += takes_value(name) && !strchr(argv[i], '=') ? 2 : 1;
  }
  return i > 1 && i < argc && strcmp(argv[i], "fill") == 0;
}

/* ---- lists ------------------------------------------------------------------------------ */

static lsm_status parse_number(const char *opt, const char *text, size_t len, int allow_negative,
                               long long *out, lsm_err *err) {
  char buf[32];
  if (len == 0 || len >= sizeof buf)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: '%.*s' is not a number", opt, (int)len, text);
  memcpy(buf, text, len);
  buf[len] = '\0';
  const char *digits = allow_negative && buf[0] == '-' ? buf + 1 : buf;
  for (const char *c = digits; *c; ++c)
    if (*c < '0' || *c > '9' || !digits[0])
      return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: '%s' is not a%s whole number", opt, buf,
                      allow_negative ? "" : " non-negative");
  if (!digits[0]) return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: '%s' is not a number", opt, buf);
  errno = 0;
  const long long v = strtoll(buf, NULL, 10);
  if (errno == ERANGE || v > (long long)1e15 || v < -(long long)1e15)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: %s is out of range", opt, buf);
  *out = v;
  return LSM_OK;
}

lsm_status lsm_fill_parse_list(const char *opt, const char *text, int allow_negative,
                               long long **out, size_t *n, lsm_err *err) {
  *out = NULL;
  *n = 0;
  size_t cap = 0;
  long long *list = NULL;
  lsm_status st = LSM_OK;
  const char *p = text;
  if (!*p) return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: the list is empty", opt);
  while (st == LSM_OK) {
    const char *end = strchr(p, ',');
    const size_t len = end ? (size_t)(end - p) : strlen(p);
    /* N, A:B, A:B:S, or (without negatives) A-B */
    long long part[3] = {0, 0, 1};
    int parts = 0;
    size_t at = 0;
    while (st == LSM_OK && parts < 3) {
      size_t stop = at;
      while (stop < len && p[stop] != ':' && !(!allow_negative && p[stop] == '-' && parts == 0 && stop > at))
        ++stop;
      st = parse_number(opt, p + at, stop - at, allow_negative, &part[parts], err);
      parts++;
      if (stop >= len) break;
      at = stop + 1;
    }
    if (st == LSM_OK && parts == 3 && at < len && memchr(p + at, ':', len - at))
      st = lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: '%.*s' has too many parts", opt, (int)len, p);
    if (st == LSM_OK && parts == 3 && part[2] <= 0)
      st = lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: the step in '%.*s' must be positive", opt,
                    (int)len, p);
    if (st == LSM_OK && parts >= 2 && part[1] < part[0])
      st = lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: '%.*s' ends before it starts", opt, (int)len, p);
    const long long last = parts >= 2 ? part[1] : part[0];
    if (st == LSM_OK && (last - part[0]) / part[2] + 1 + (long long)*n > (1LL << 26))
      st = lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: more than 2^26 entries", opt);
    for (long long x = part[0]; st == LSM_OK && x <= last; x += part[2]) {
      if (*n == cap) {
        cap = cap ? 2 * cap : 16;
        long long *grown = realloc(list, cap * sizeof *grown);
        if (!grown) {
          st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "%s: cannot allocate the list", opt);
          break;
        }
        list = grown;
      }
      list[(*n)++] = x;
    }
    if (!end) break;
    p = end + 1;
  }
  if (st != LSM_OK) {
    free(list);
    *n = 0;
    return st;
  }
  *out = list;
  return LSM_OK;
}

/* ---- the command line ----------------------------------------------------------------------- */

typedef struct fill_args {
  const char *labels_path, *out_path;
  int axis;                        /* -1 auto */
  long long *slices, *labels;
  size_t n_slices, n_labels;
  int threads;
  int xml, help;
  lsm_cli shared;                  /* reconstruct's options as reconstruct parses them */
} fill_args;

static void fill_args_free(fill_args *a) {
  free(a->slices);
  free(a->labels);
}

static lsm_status parse_fill(int argc, char **argv, fill_args *a, lsm_err *err) {
  memset(a, 0, sizeof *a);
  a->axis = -1;
  /* argv for reconstruct's parser: its shared options; names with '_' rewritten */
  char **pass = calloc((size_t)argc + 6, sizeof *pass);
  char *names = calloc((size_t)argc, 64);
  if (!pass || !names) {
    free(pass);
    free(names);
    return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot parse the command line");
  }
  int np = 0;
  pass[np++] = argv[0];
  pass[np++] = "reconstruct";
  pass[np++] = "unused";
  pass[np++] = "-o";
  pass[np++] = "unused";
  lsm_status st = LSM_OK;
  int options = 1, fill_seen = 0;
  for (int i = 1; st == LSM_OK && i < argc; ++i) {
    const char *arg = argv[i];
    if (!fill_seen && strcmp(arg, "fill") == 0) { /* the command (anywhere in Slicer's form) */
      fill_seen = 1;
      continue;
    }
    if (options && strcmp(arg, "--") == 0) {
      options = 0;
      continue;
    }
    if (!options || arg[0] != '-' || strcmp(arg, "-") == 0) {
      if (!a->labels_path)
        a->labels_path = arg;
      else if (!a->out_path)
        a->out_path = arg;
      else
        st = lsm_fail(err, LSM_ERR_USAGE, NULL, "unexpected argument '%s' (LABELS and OUT only)", arg);
      continue;
    }
    char *name = names + 64 * (size_t)i;
    option_name(arg, name, 64);
    const char *eq = strchr(arg, '=');
    const char *value = eq ? eq + 1 : NULL;
    if (takes_value(name) && !value) {
      if (i + 1 >= argc) {
        st = lsm_fail(err, LSM_ERR_USAGE, NULL, "%s needs a value", name);
        break;
      }
      value = argv[++i];
    }
    if (!takes_value(name) && eq) {
      st = lsm_fail(err, LSM_ERR_USAGE, NULL, "%s takes no value", name);
      break;
    }
    long n = 0;
    if (strcmp(name, "-h") == 0 || strcmp(name, "--help") == 0) {
      a->help = 1;
    } else if (strcmp(name, "--xml") == 0) {
      a->xml = 1;
    } else if (strcmp(name, "-o") == 0 || strcmp(name, "--output") == 0) {
      if (a->out_path) st = lsm_fail(err, LSM_ERR_USAGE, NULL, "OUT is given twice");
      a->out_path = value;
    } else if (strcmp(name, "--axis") == 0) {
      if (strcmp(value, "auto") == 0) a->axis = -1;
      else if (strlen(value) == 1 && strchr("ijk", value[0])) a->axis = value[0] - 'i';
      else st = lsm_fail(err, LSM_ERR_USAGE, NULL, "--axis: '%s' is not one of i, j, k, auto", value);
    } else if (strcmp(name, "--slices") == 0) {
      free(a->slices);
      st = lsm_fill_parse_list("--slices", value, 0, &a->slices, &a->n_slices, err);
    } else if (strcmp(name, "--labels") == 0) {
      free(a->labels);
      st = lsm_fill_parse_list("--labels", value, 1, &a->labels, &a->n_labels, err);
    } else if (strcmp(name, "--threads") == 0) {
      char *end = NULL;
      errno = 0;
      n = value[0] >= '0' && value[0] <= '9' ? strtol(value, &end, 10) : -1;
      if (!end || *end || errno || n < 0 || n > 4096)
        st = lsm_fail(err, LSM_ERR_USAGE, NULL, "--threads: '%s' is not 0 .. 4096", value);
      a->threads = (int)n;
    } else if (in_list(name, shared_valued) || in_list(name, shared_flags)) {
      pass[np++] = (char *)name;
      if (in_list(name, shared_valued)) pass[np++] = (char *)value;
    } else if (in_list(name, not_for_fill)) {
      st = lsm_fail(err, LSM_ERR_USAGE, NULL,
                    "%s does not apply to fill: the slices, their spacing and the output's "
                    "grid and format come from LABELS and OUT (see 'lsmorph help fill')",
                    name);
    } else {
      st = lsm_fail(err, LSM_ERR_USAGE, NULL, "unknown option '%s' (see 'lsmorph help fill')", arg);
    }
  }
  if (st == LSM_OK && !a->help && !a->xml) {
    if (!a->labels_path) st = lsm_fail(err, LSM_ERR_USAGE, NULL, "fill: missing LABELS");
    else if (!a->out_path) st = lsm_fail(err, LSM_ERR_USAGE, NULL, "fill: missing -o OUT");
    else if (!*a->labels_path || !*a->out_path)
      st = lsm_fail(err, LSM_ERR_USAGE, NULL, "fill: %s is empty", *a->labels_path ? "OUT" : "LABELS");
  }
  if (st == LSM_OK) {
    lsm_err e;
    lsm_err_clear(&e);
    st = lsm_cli_parse(np, pass, &a->shared, &e);
    if (st != LSM_OK) {
      /* reconstruct's parser points to reconstruct's help */
      char *see = strstr(e.msg, "'lsmorph help reconstruct'");
      if (see) memcpy(see, "'lsmorph help fill'", sizeof "'lsmorph help fill'");
      lsm_fail(err, st, NULL, "%s", e.msg);
    }
  }
  free(pass);
  free(names);
  return st;
}

/* ---- notes --------------------------------------------------------------------------------- */

static const char axis_names[3] = {'i', 'j', 'k'};

/* A list of slices or labels for a note: "4, 8, ..., 104 (every 4th)" when
 * evenly spaced, else the first ones and a count. */
static void list_text(char *out, size_t cap, const size_t *v, const int64_t *w, size_t n) {
#define AT(k) (v ? (long long)v[k] : (long long)w[k])
  size_t used = 0;
  out[0] = '\0';
  if (n >= 4) {
    const long long step = AT(1) - AT(0);
    size_t k = 2;
    while (k < n && AT(k) - AT(k - 1) == step) ++k;
    if (k == n && step > 1) {
      snprintf(out, cap, "%lld, %lld, ..., %lld (every %lld%s)", AT(0), AT(1), AT(n - 1), step,
               step == 2 ? "nd" : step == 3 ? "rd" : "th");
      return;
    }
    if (k == n && step == 1) {
      snprintf(out, cap, "%lld to %lld", AT(0), AT(n - 1));
      return;
    }
  }
  for (size_t k = 0; k < n && used + 40 < cap; ++k) {
    if (k == 12 && n > 14) {
      snprintf(out + used, cap - used, ", ... (%zu in all)", n);
      return;
    }
    const int m = snprintf(out + used, cap - used, "%s%lld", k ? ", " : "", AT(k));
    if (m > 0) used += (size_t)m;
  }
#undef AT
}

static void print_notes(const lsm_fill_plan *plan, const lsm_voxels *v, const fill_args *a,
                        const char *labels_path) {
  char drawn[512], labels[512];
  list_text(drawn, sizeof drawn, plan->drawn, NULL, plan->n_drawn);
  list_text(labels, sizeof labels, NULL, plan->labels, plan->n_labels);
  const int ax = plan->axis;
  fprintf(stderr,
          "lsmorph: %s: %zu x %zu x %zu voxels (%s), slices across %c, %g apart%s; %zu label%s "
          "to fill: %s\n",
          labels_path, v->n[0], v->n[1], v->n[2], lsm_voxel_type_name(v->type), axis_names[ax],
          v->spacing[ax], a->axis < 0 ? " (the largest spacing)" : "", plan->n_labels,
          plan->n_labels == 1 ? "" : "s", labels);
  if (a->slices) {
    fprintf(stderr, "lsmorph: note: drawn slices (--slices): %s\n", drawn);
  } else {
    char found[512];
    const size_t off = plan->added[0] != SIZE_MAX ? 1 : 0;
    list_text(found, sizeof found, plan->drawn + off, NULL, plan->n_found);
    fprintf(stderr, "lsmorph: note: taken as drawn: the %zu slice%s holding labels (%s)",
            plan->n_found, plan->n_found == 1 ? "" : "s", found);
    if (plan->added[0] != SIZE_MAX || plan->added[1] != SIZE_MAX) {
      fprintf(stderr, ", and ");
      if (plan->added[0] != SIZE_MAX) fprintf(stderr, "%zu", plan->added[0]);
      if (plan->added[0] != SIZE_MAX && plan->added[1] != SIZE_MAX) fprintf(stderr, " and ");
      if (plan->added[1] != SIZE_MAX) fprintf(stderr, "%zu", plan->added[1]);
      fprintf(stderr, ", one typical step (%zu) beyond, as drawn empty", plan->step);
    }
    fprintf(stderr, "; give --slices to say otherwise\n");
  }
  if (plan->n_absent) {
    char absent[512];
    list_text(absent, sizeof absent, NULL, plan->absent, plan->n_absent);
    fprintf(stderr,
            "lsmorph: note: label%s %s on no drawn slice: removed from the slices filled\n",
            plan->n_absent == 1 ? "" : "s", absent);
  }
}

/* The record of the fill kept in OUT's header, which `score` reads:
 * "axis=k drawn=0,4,8 labels=1,2,3". */
static lsm_status note_fill(lsm_label_file *f, const lsm_fill_plan *plan, lsm_err *err) {
  size_t cap = 64 + 24 * (plan->n_drawn + plan->n_labels), used = 0;
  char *text = malloc(cap);
  if (!text) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot record the fill");
  used += (size_t)snprintf(text, cap, "axis=%c drawn=", axis_names[plan->axis]);
  for (size_t k = 0; k < plan->n_drawn; ++k)
    used += (size_t)snprintf(text + used, cap - used, "%s%zu", k ? "," : "", plan->drawn[k]);
  used += (size_t)snprintf(text + used, cap - used, " labels=");
  for (size_t k = 0; k < plan->n_labels; ++k)
    used += (size_t)snprintf(text + used, cap - used, "%s%lld", k ? "," : "",
                             (long long)plan->labels[k]);
  const lsm_status st = lsm_labels_set_note(f, "lsmorph_fill", text, err);
  free(text);
  return st;
}

/* ---- progress ---------------------------------------------------------------------------------- */

typedef struct fill_progress {
  int tty, last;
  double start;
} fill_progress;

static void fill_progress_update(void *ctx, size_t done, size_t total, size_t pair, size_t pairs) {
  fill_progress *p = ctx;
  (void)pair;
  (void)pairs;
  if (!total) return;
  const int percent = (int)(100.0 * (double)done / (double)total);
  if (p->tty)
    fprintf(stderr, "\rlsmorph: %3d%%  %zu/%zu label slices  %.1f s%s", percent, done, total,
            omp_get_wtime() - p->start, done == total ? "\n" : "");
  else if (percent / 10 != p->last / 10 || done == total)
    fprintf(stderr, "lsmorph: %3d%% (%zu/%zu label slices, %.1f s)\n", percent, done, total,
            omp_get_wtime() - p->start);
  p->last = percent;
}

/* ---- the run ------------------------------------------------------------------------------------- */

/* Memory and disk before the work (lsm_check_fill_resources). */
static lsm_status check_resources(const fill_args *a, lsm_label_file *f, const lsm_fill_plan *plan,
                                  int threads, const lsm_out_file *out, double *canvas_max,
                                  lsm_err *err) {
  const lsm_voxels *v = lsm_labels_voxels(f);
  const int u = plan->axis == 0 ? 1 : 0, w = plan->axis == 2 ? 1 : 2;
  lsm_stack_opts resolved = a->shared.stack;
  lsm_stack_opts_resolve(&resolved);
  lsm_fill_need need = {0.0, (int)v->n[u], (int)v->n[w], 0, threads, 0.0,
                        resolved.motion != LSM_MOTION_NONE};
  need.gap_voxels = (double)plan->gap_slices * (double)v->n[u] * (double)v->n[w];
  for (size_t k = 0; k + 1 < plan->n_drawn; ++k)
    if (plan->drawn[k + 1] - plan->drawn[k] - 1 > need.most) need.most = plan->drawn[k + 1] - plan->drawn[k] - 1;
  const size_t len = strlen(out->path);
  const int gz_name = len > 3 && strcmp(out->path + len - 3, ".gz") == 0;
  const int nifti = lsm_labels_format_of(out->path) == LSM_LABELS_NIFTI;
  if (!(nifti ? gz_name : lsm_labels_compressed(f)))
    need.out_bytes = (double)v->n[0] * (double)v->n[1] * (double)v->n[2] * (double)lsm_voxel_size(v->type);
  return lsm_check_fill_resources(a->shared.max_memory, &need, a->labels_path, out->folder,
                                  canvas_max, err);
}

static lsm_status run_fill(fill_args *a, const volatile sig_atomic_t *stop, lsm_err *err) {
  const int quiet = a->shared.quiet;
  const double t0 = omp_get_wtime();
  lsm_out_file out; /* OUT, or the file its link names; stale temporaries removed */
  LSM_TRY(lsm_out_file_check(&out, a->out_path, quiet ? NULL : stderr, err));
  LSM_TRY(lsm_labels_check_output(out.path, a->labels_path, err));
  lsm_label_file *f = NULL;
  LSM_TRY(lsm_labels_read(a->labels_path, a->shared.max_voxels, &f, err));
  const double t_read = omp_get_wtime();
  lsm_voxels *v = lsm_labels_voxels(f);
  const lsm_voxel_type was = v->type;
  int converted = 0;
  lsm_status st = lsm_labels_to_integer(f, &converted, err);
  if (st == LSM_OK && converted && !quiet)
    fprintf(stderr, "lsmorph: note: %s: labels stored as %s (whole numbers), written as %s\n",
            a->labels_path, lsm_voxel_type_name(was), lsm_voxel_type_name(v->type));
  double cosine = 0.0;
  lsm_labels_axes_cosine(f, &cosine);
  if (st == LSM_OK && cosine > 1e-3 && !quiet)
    fprintf(stderr, "lsmorph: note: %s: the grid's axes are not at right angles (|cos| up to "
                    "%.3g, a sheared grid such as a tilted CT gantry gives): distances are taken "
                    "as if they were\n", a->labels_path, cosine);
  /* the options */
  lsm_fill_opts o;
  lsm_fill_opts_default(&o);
  o.axis = a->axis;
  size_t *slices = NULL;
  int64_t *labels = NULL;
  if (st == LSM_OK && a->slices) {
    slices = lsm_alloc(a->n_slices, sizeof *slices, err, "slice list");
    if (!slices) st = err ? err->status : LSM_ERR_NOMEM;
    for (size_t k = 0; st == LSM_OK && k < a->n_slices; ++k) slices[k] = (size_t)a->slices[k];
    o.slices = slices;
    o.n_slices = a->n_slices;
  }
  if (st == LSM_OK && a->labels) {
    labels = lsm_alloc(a->n_labels, sizeof *labels, err, "label list");
    if (!labels) st = err ? err->status : LSM_ERR_NOMEM;
    for (size_t k = 0; st == LSM_OK && k < a->n_labels; ++k) labels[k] = a->labels[k];
    o.labels = labels;
    o.n_labels = a->n_labels;
  }
  o.stack = a->shared.stack;
  o.ends_given = a->shared.ends_given;
  o.threads = a->threads > 0 ? a->threads : omp_get_num_procs();
  o.stack.morph.stop = stop;
  fill_progress fp = {isatty(fileno(stderr)), -1, t0};
  lsm_progress progress = {&fp, fill_progress_update, NULL};
  o.progress = quiet ? NULL : &progress;
  lsm_fill_plan *plan = NULL;
  if (st == LSM_OK) {
    st = lsm_fill_plan_make(v, &o, &plan, err);
    if (st != LSM_OK && err && strncmp(err->msg, "--", 2) != 0) { /* the plan names no file */
      char what[LSM_ERR_MSG_MAX];
      snprintf(what, sizeof what, "%s", err->msg);
      snprintf(err->msg, sizeof err->msg, "%s: %.900s", a->labels_path, what);
    }
  }
  if (st == LSM_OK && !quiet) {
    print_notes(plan, v, a, a->labels_path);
    if (plan->gap_slices == 0) {
      fprintf(stderr, "lsmorph: note: every slice from %zu to %zu across %c is drawn: nothing to "
                      "fill, OUT is LABELS%s",
              plan->drawn[0], plan->drawn[plan->n_drawn - 1], axis_names[plan->axis],
              converted ? " with integer voxels" : " copied");
      if (plan->other_axis >= 0)
        fprintf(stderr, " (across %c the labels lie on separate slices: --axis %c?)",
                axis_names[plan->other_axis], axis_names[plan->other_axis]);
      fputc('\n', stderr);
    }
    if (o.stack.method == LSM_METHOD_BLEND && a->shared.solver_option)
      fprintf(stderr, "lsmorph: note: %s has no effect with --method blend\n",
              a->shared.solver_option);
    if (o.stack.method != LSM_METHOD_PLS && a->shared.pls_option)
      fprintf(stderr, "lsmorph: note: %s has no effect without --method pls\n",
              a->shared.pls_option);
  }
  if (st == LSM_OK && plan->gap_slices > 0)
    st = check_resources(a, f, plan, o.threads, &out, &o.stack.canvas_max, err);
  lsm_backend *backend = NULL;
  if (st == LSM_OK && plan->gap_slices > 0) {
    omp_set_num_threads(o.threads);
    st = lsm_backend_open(a->shared.backend, a->shared.device, o.threads, &backend, err);
    if (st == LSM_OK) {
      o.stack.morph.backend = backend;
      if (!quiet && lsm_backend_fallback(backend)[0])
        fprintf(stderr, "lsmorph: note: --backend auto runs on C: %s\n",
                lsm_backend_fallback(backend));
    }
  }
  lsm_fill_stats stats;
  memset(&stats, 0, sizeof stats);
  if (st == LSM_OK) st = lsm_fill_run(plan, v, &o, &stats, err);
  if (st == LSM_OK) st = note_fill(f, plan, err);
  if (st == LSM_OK && stop && *stop) st = lsm_fail(err, LSM_ERR_INTERRUPTED, NULL, "interrupted");
  lsm_signal_guard guard; /* a second Ctrl-C removes the temporary files */
  memset(&guard, 0, sizeof guard);
  const double t_filled = omp_get_wtime();
  if (st == LSM_OK) st = lsm_signals_guard_start(&guard, lsm_out_file_abandon, &out, err);
  if (st == LSM_OK) st = lsm_labels_write(f, out.path, err);
  lsm_signals_guard_stop(&guard);
  const double t_end = omp_get_wtime();
  if (st == LSM_OK && !quiet)
    fprintf(stderr,
            "lsmorph: filled %zu slices across %c (%zu voxels labelled), %zu label%s, %d "
            "threads: wrote %s in %.2f s (reading %.2f s, filling %.2f s of which %.2f s of "
            "thread time in %lld morph steps, writing %.2f s)\n",
            plan->gap_slices, axis_names[plan->axis], stats.voxels_filled, stats.runs,
            stats.runs == 1 ? "" : "s", stats.threads, a->out_path, t_end - t0, t_read - t0,
            t_filled - t_read, stats.solver_seconds, stats.iterations, t_end - t_filled);
  if (st == LSM_OK && !quiet && stats.motion_tried)
    fprintf(stderr,
            "lsmorph: note: --motion auto tried %lld gap%s of the labels by leaving their drawn "
            "slices out; %lld follow%s the correspondence field\n",
            stats.motion_tried, stats.motion_tried == 1 ? "" : "s", stats.motion_field,
            stats.motion_field == 1 ? "s" : "");
  lsm_backend_close(&backend);
  lsm_fill_plan_free(&plan);
  free(slices);
  free(labels);
  lsm_labels_free(&f);
  return st;
}

lsm_status lsm_fill_main(int argc, char **argv, const volatile sig_atomic_t *stop, lsm_err *err) {
  if (argc >= 3 && strcmp(argv[1], "fill") != 0 && strcmp(argv[2], "fill") == 0 &&
      argv[1][0] != '-') { /* help fill */
    lsm_fill_help(stdout);
    return LSM_OK;
  }
  if (argc >= 3 && strcmp(argv[2], "fill") == 0 &&
      (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0)) {
    lsm_fill_help(stdout);
    return LSM_OK;
  }
  fill_args a;
  lsm_status st = parse_fill(argc, argv, &a, err);
  if (st == LSM_OK && a.help) lsm_fill_help(stdout);
  else if (st == LSM_OK && a.xml) lsm_fill_xml(stdout);
  else if (st == LSM_OK) st = run_fill(&a, stop, err);
  fill_args_free(&a);
  return st;
}
