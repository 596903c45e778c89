#include "solver/app/lsm_cli.h"

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "io/lsm_labels.h"
#include "solver/app/lsm_fill_cmd.h"
#include "solver/recon/lsm_rules.h"

#define COUNT_OF(a) ((int)(sizeof(a) / sizeof *(a)))

/* ---- the choices, from the lists that declare their enums ---------------------------- */

static const char *const input_names[] = {LSM_INPUT_LIST(LSM_ENUM_TEXT)};
static const char *const values_names[] = {LSM_VALUES_LIST(LSM_ENUM_TEXT)};
static const char *const nrrd_encoding_names[] = {LSM_NRRD_ENCODING_LIST(LSM_ENUM_TEXT)};
static const char *const method_names[] = {LSM_METHOD_LIST(LSM_ENUM_TEXT)};
static const char *const scheme_names[] = {LSM_SCHEME_LIST(LSM_ENUM_TEXT)};
static const char *const time_names[] = {LSM_TIME_LIST(LSM_ENUM_TEXT)};
static const char *const interp_names[] = {LSM_INTERP_LIST(LSM_ENUM_TEXT)};
static const char *const ends_names[] = {LSM_ENDS_LIST(LSM_ENUM_TEXT)};
static const char *const align_names[] = {LSM_ALIGN_LIST(LSM_ENUM_TEXT)};
static const char *const motion_names[] = {LSM_MOTION_LIST(LSM_ENUM_TEXT)};
static const char *const backend_names[] = {LSM_BACKEND_TABLE(LSM_BACKEND_NAME) "auto"};
static const char *const band_names[] = {"off", "on"};

LSM_NAME_FUNCTIONS(lsm_nrrd_encoding, LSM_NRRD_ENCODING_LIST, lsm_nrrd_encoding_name,
                   lsm_nrrd_encoding_from_name)

/* names[0 .. count-1] joined by sep into out (cut short if it does not fit). */
static void join_names(char *out, size_t size, const char *const *names, int count,
                       const char *sep) {
  size_t used = 0;
  out[0] = '\0';
  for (int k = 0; k < count && used < size; ++k) {
    const int n = snprintf(out + used, size - used, "%s%s", k ? sep : "", names[k]);
    if (n < 0) break;
    used += (size_t)n;
  }
}

/* ---- help ---------------------------------------------------------------------------- */

/* One line of an option list: the option and its value (a choice shows its
 * names, a|b|c), then what it does; '\n' in text starts a continuation line.
 * A row without an option is a heading. */
typedef struct help_row {
  const char *option;
  const char *const *choices;
  int n_choices;
  const char *text;
  int formats; /* the text ends with the --format names */
} help_row;

#define HEAD(text) {NULL, NULL, 0, text, 0}
#define OPT(option, text) {option, NULL, 0, text, 0}
#define CHOOSE(option, names, text) {option, names, COUNT_OF(names), text, 0}

/* The text column: option and value take columns 0 .. 24. */
enum { HELP_INDENT = 25 };

static const help_row reconstruct_rows[] = {
    HEAD("Input:"),
    OPT("-o, --output OUT_DIR", "the folder to write (replaced only when complete)"),
    CHOOSE("--input", input_names, "filled regions (default), or thin closed contours\n"
                                   "(inside by parity: nested contours, holes)"),
    OPT("--invert", "foreground is dark (default: luminance >= 50 %;\n"
                    "0/1 label masks: non-zero)"),
    OPT("--spacing Z", "distance between consecutive slices (default 1)"),
    OPT("--heights FILE", "one height per slice, strictly increasing"),
    OPT("--heights-from-names", "each height is the number the file name ends\n"
                                "with times --spacing (001.png 009.png ...)"),
    OPT("--pixel-size S|SX,SY", "pixel size, or width and height (default 1);\n"
                                "every length is in this unit"),
    OPT("--max-pixels N", "refuse larger slices (default 67108864 = 2^26,\n"
                          "8192 x 8192)"),
    OPT("--max-voxels N", "refuse larger volumes (default 1073741824 = 2^30,\n"
                          "1024^3: 4 GiB of float32)"),
    OPT("--max-memory BYTES", "refuse runs estimated to need more memory\n"
                              "(default: what is available at the start)"),
    HEAD("Output:"),
    OPT("--dz Z", "output slice spacing (default: the pixel size)"),
    OPT("--per-iteration", "every solver iteration is a slice (the design\n"
                           "document's mode; linear profile)"),
    {"--format LIST", NULL, 0, "volume formats, comma separated (default nrrd):", 1},
    CHOOSE("--values", values_names, "float32 signed distance (default) or uint8 mask"),
    CHOOSE("--nrrd-encoding", nrrd_encoding_names, "volume.nrrd's samples raw (default) or gzipped"),
    OPT("--mesh", "also write surface.ply, a closed mesh of phi = 0"),
    OPT("--no-slices", "do not write slices/00001.png ..."),
    OPT("--no-preview", "do not write preview.png and preview3d.png"),
    HEAD("Method:"),
    CHOOSE("--method", method_names, "ls: level-set morph (default); pls: ls\n"
                                     "corrected by Lagrangian particles; blend:\n"
                                     "linear blend of the two signed distances"),
    CHOOSE("--interp", interp_names, "z-profile through the slices (default cubic:\n"
                                     "a monotone cubic through the four nearest)"),
    CHOOSE("--ends", ends_names, "where an object meets an empty slice: a tip\n"
                                 "that reaches it (tip) or nothing past mid-gap\n"
                                 "(halfway); default auto: tip beside the first\n"
                                 "and last slice given, halfway elsewhere"),
    CHOOSE("--align", align_names, "move slices by their convex-hull centroids:\n"
                                   "pairs whose shape moved (auto, the default),\n"
                                   "every pair (hull), none"),
    CHOOSE("--motion", motion_names, "auto (default): field in the pairs where it\n"
                                     "predicts the slices left out better; field:\n"
                                     "parts that moved follow a registration (ls,\n"
                                     "pls; not with hull, --per-iteration); none"),
    OPT("--rules-off NAME,...", "switch reconstruction rules off, for experiments\n"
                               "('lsmorph help rules' lists them)"),
    CHOOSE("--scheme", scheme_names, "numerical Hamiltonian\n"
                                     "(default upwind; weno5 with --time rk3)"),
    CHOOSE("--time", time_names, "time integrator (default euler)"),
    OPT("--cfl C", "CFL number (default 0.75; monotone up to 1)"),
    CHOOSE("--band", band_names, "update only the cells near the front (on, the\n"
                                 "default) or every cell (off: for comparisons)"),
    OPT("--max-iter N", "most solver steps per morph (default 100000)"),
    OPT("--reinit-every N", "reinitialise phi every N steps (default 0: never)"),
    OPT("--reinit-iters N", "iterations per reinitialisation (default 10)"),
    OPT("--tol T", "--per-iteration: a pair stops when CP <= T\n"
                   "(default 0.25)"),
    OPT("--particles-per-cell N", "pls: particles per band cell, 2 .. 256 (default 16)"),
    OPT("--pls-reseed N", "pls: reseed every N steps (default 0: never)"),
    OPT("--pls-radius-adjust", "pls: reset particle radii after each correction"),
    OPT("--seed N", "pls: random seed (default 20130101)"),
    HEAD("Running:"),
    OPT("--threads N", "threads (default: all cores)"),
    CHOOSE("--backend", backend_names, "where the grid work runs (default c;\n"
                                       "auto: OpenCL when a device is present)"),
    OPT("--device N", "OpenCL device of 'lsmorph devices' (default: the\n"
                      "first GPU, else 0)"),
    OPT("-q, --quiet", "no progress or notes on stderr (errors still)"),
};

static void print_row(FILE *f, const help_row *row) {
  if (!row->option) {
    fprintf(f, "\n%s\n", row->text);
    return;
  }
  char choices[128] = "";
  if (row->choices) join_names(choices, sizeof choices, row->choices, row->n_choices, "|");
  const int width =
      fprintf(f, "  %s%s%s", row->option, row->choices ? " " : "", choices);
  /* the text in its column, or two spaces after a long option */
  fprintf(f, "%*s", width < HELP_INDENT - 1 ? HELP_INDENT - width : 2, "");
  for (const char *line = row->text; line;) {
    const char *end = strchr(line, '\n');
    fprintf(f, "%.*s\n", end ? (int)(end - line) : (int)strlen(line), line);
    line = end ? end + 1 : NULL;
    if (line) fprintf(f, "%*s", HELP_INDENT, "");
  }
  if (row->formats) {
    fprintf(f, "%*s", HELP_INDENT, "");
    for (unsigned bit = 1, n = 0; bit <= LSM_FORMAT_ALL; bit <<= 1)
      if (LSM_FORMAT_ALL & bit) fprintf(f, "%s%s", n++ ? ", " : "", lsm_format_name(bit));
    fputc('\n', f);
  }
}

static void reconstruct_help(FILE *f) {
  fputs("Usage: lsmorph reconstruct SLICE_DIR -o OUT_DIR [options]\n"
        "\n"
        "Reads the PNG and TIFF slices of SLICE_DIR in natural order (2.png before\n"
        "10.png), morphs each slice into the next by level sets, and writes the stack\n"
        "to OUT_DIR.  An object closes where it meets an empty slice: keep one beyond\n"
        "each end.  Options also take the form --name=value; after '--' every argument\n"
        "is SLICE_DIR.  README.md tabulates the options; solver/README.md explains the\n"
        "method, io/README.md the files.\n",
        f);
  for (int k = 0; k < COUNT_OF(reconstruct_rows); ++k) print_row(f, &reconstruct_rows[k]);
  fputs("\n"
        "OUT_DIR gets volume.nrrd (or the --format files), heights.txt, slices/,\n"
        "preview.png, preview3d.png, surface.ply (--mesh) and run.json.  They are\n"
        "written to OUT_DIR.tmp-XXXXXX and moved into place when complete; an existing\n"
        "OUT_DIR is replaced only when it is empty or an earlier result (a run.json).\n"
        "Exit status: 0 success, 1 bad input or failure, 2 usage error; SIGINT, SIGTERM,\n"
        "SIGHUP end the run by that signal (130, 143, 129) and write nothing.\n",
        f);
}

static void score_help(FILE *f) {
  fputs("Usage: lsmorph score TRUTH_DIR OUT_DIR [--stride K] [--first N] [--per-slice]\n"
        "\n"
        "Scores a reconstruction made from some slices of TRUTH_DIR (a full stack, in\n"
        "natural order) against the slices held out between its first and last input,\n"
        "and prints one line of JSON.  Which truth slices were the inputs:\n"
        "  --stride K     every K-th (K >= 2), reconstructed with --spacing K\n"
        "  (no --stride)  where OUT_DIR/run.json's input heights put them, reconstructed\n"
        "                 with --dz equal to the truth's slice spacing\n"
        "  --first N      the first input is truth slice N (default: the truth slice\n"
        "                 named as the first input, else slice 1)\n"
        "  --per-slice    also print each held-out slice's scores\n"
        "\n"
        "Printed: held_out, dice_volume (Dice pooled), dice (mean per slice), hd95,\n"
        "hd95_pooled, mean_surface (distances in pixel widths), volume_error,\n"
        "one_sided_empty; with --per-slice, slices.  An undefined score is null.  A\n"
        "result that does not fit TRUTH_DIR and its inputs is refused.  Details:\n"
        "validation/README.md, section Scoring.\n",
        f);
}

static void devices_help(FILE *f) {
  fputs("Usage: lsmorph devices\n"
        "\n"
        "Lists the OpenCL platforms and devices of this machine, one index each, with\n"
        "name, type, version, compute units and global memory.  'reconstruct --backend\n"
        "opencl --device N' runs on device N; without --device, on the first GPU\n"
        "listed, else on device 0.  Exits 1 when OpenCL is not available (no ICD loader\n"
        "or no platform).\n",
        f);
}

/* The help topics: `lsmorph help TOPIC`. */
typedef struct help_topic {
  const char *name;
  void (*print)(FILE *f);
} help_topic;

static const help_topic help_topics[] = {
    {"fill", lsm_fill_help},
    {"reconstruct", reconstruct_help},
    {"score", score_help},
    {"devices", devices_help},
    {"rules", lsm_rules_print},
};

static const help_topic *find_topic(const char *name) {
  for (int k = 0; name && k < COUNT_OF(help_topics); ++k)
    if (strcmp(name, help_topics[k].name) == 0) return &help_topics[k];
  return NULL;
}

/* The topics' names joined by sep, each after prefix: "fill, reconstruct, ..."
 * or "help fill, help reconstruct, ...". */
static void topic_list(char *out, size_t size, const char *prefix, const char *sep) {
  const char *names[COUNT_OF(help_topics)];
  char with_prefix[COUNT_OF(help_topics)][32];
  for (int k = 0; k < COUNT_OF(help_topics); ++k) {
    snprintf(with_prefix[k], sizeof with_prefix[k], "%s%s", prefix, help_topics[k].name);
    names[k] = with_prefix[k];
  }
  join_names(out, size, names, COUNT_OF(help_topics), sep);
}

static void general_help(FILE *f) {
  char topics[128];
  topic_list(topics, sizeof topics, "", ", ");
  fprintf(f,
          "lsmorph " LSM_VERSION " - fill the gaps between sparse slices by level-set morphing\n"
          "\n"
          "Usage:\n"
          "  lsmorph fill LABELS -o OUT [options]   (label volumes: .nii, .nii.gz, .nrrd)\n"
          "  lsmorph reconstruct SLICE_DIR -o OUT_DIR [options]\n"
          "  lsmorph score TRUTH_DIR OUT_DIR [--stride K] [--first N] [--per-slice]\n"
          "  lsmorph devices\n"
          "  lsmorph --help [TOPIC] | --version | help TOPIC\n"
          "\n"
          "Commands:\n"
          "  fill          fill the slices between the drawn slices of a NIfTI or NRRD\n"
          "                label map, every label at once\n"
          "  reconstruct   read PNG or TIFF slices, morph between consecutive slices,\n"
          "                write a volume\n"
          "  score         compare a reconstruction with full-resolution truth slices\n"
          "  devices       list the OpenCL platforms and devices\n"
          "\n"
          "Help topics: %s.\n"
          "Run 'lsmorph help reconstruct' for the options.  Every option also takes the\n"
          "form --name=value; after '--' every argument is a folder (for names that\n"
          "start with '-').\n",
          topics);
}

void lsm_cli_help(FILE *f, const char *topic) {
  const help_topic *t = find_topic(topic);
  if (t)
    t->print(f);
  else
    general_help(f);
}

/* ---- value parsers ---------------------------------------------------------------- */

static lsm_status parse_double(const char *opt, const char *text, double *out, int positive,
                               lsm_err *err) {
  if (!lsm_decimal_syntax(text))
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: '%s' is not a number", opt, text);
  errno = 0;
  const double v = strtod(text, NULL);
  if (errno == ERANGE || !isfinite(v))
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: '%s' is out of range", opt, text);
  if (positive && !(v > 0.0))
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: %s must be positive", opt, text);
  *out = v;
  return LSM_OK;
}

/* A length option (--pixel-size, --spacing, --dz): a positive number within
 * the range the solver's floats hold (LSM_LENGTH_MIN .. LSM_LENGTH_MAX). */
static lsm_status parse_length(const char *opt, const char *text, double *out, lsm_err *err) {
  double v = 0.0;
  LSM_TRY(parse_double(opt, text, &v, 1, err));
  if (!lsm_length_in_range(v))
    return lsm_fail(err, LSM_ERR_USAGE, NULL,
                    "%s: %s is outside %g to %g (lengths are held as floats; choose a unit that "
                    "brings it into range)",
                    opt, text, LSM_LENGTH_MIN, LSM_LENGTH_MAX);
  *out = v;
  return LSM_OK;
}

/* --pixel-size S (a square pixel) or SX,SY: the pixel's width (the step
 * along a row, x) and height (down a column, y), each a length as above.
 * (The x size first, as in NRRD's spacings and ITK's; DICOM's PixelSpacing
 * lists the row step, y, first.) */
static lsm_status parse_pixel_size(const char *opt, const char *text, double *dx, double *dy,
                                   lsm_err *err) {
  const char *comma = strchr(text, ',');
  if (!comma) {
    LSM_TRY(parse_length(opt, text, dx, err));
    *dy = *dx;
    return LSM_OK;
  }
  char first[64];
  const size_t n = (size_t)(comma - text);
  if (n >= sizeof first || strchr(comma + 1, ','))
    return lsm_fail(err, LSM_ERR_USAGE, NULL,
                    "%s: '%s' is not one size S or two sizes SX,SY (x, then y)", opt, text);
  memcpy(first, text, n);
  first[n] = '\0';
  LSM_TRY(parse_length(opt, first, dx, err));
  return parse_length(opt, comma + 1, dy, err);
}

/* A limit counted in `unit` (--max-pixels, --max-voxels, --max-memory): a positive whole
 * number, any form parse_double takes (2^34 as 17179869184 or 1.7179869184e10),
 * up to 9e15 (exact in a double). */
static lsm_status parse_count(const char *opt, const char *text, const char *unit, uint64_t *out,
                              lsm_err *err) {
  double d = 0.0;
  LSM_TRY(parse_double(opt, text, &d, 1, err));
  if (d != floor(d))
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: '%s' is not a whole number of %s", opt, text,
                    unit);
  if (d > 9.0e15) return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: %s is more than 9e15", opt, text);
  *out = (uint64_t)d;
  return LSM_OK;
}

static lsm_status parse_int(const char *opt, const char *text, long min, long max, long *out,
                            lsm_err *err) {
  /* digits with an optional leading '-', nothing else (strtol alone would
   * take leading blanks and a '+') */
  const char *digits = text[0] == '-' ? text + 1 : text;
  char *end = NULL;
  errno = 0;
  long v = isdigit((unsigned char)digits[0]) ? strtol(text, &end, 10) : 0;
  if (!end || end == text || *end != '\0')
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: '%s' is not an integer", opt, text);
  if (errno == ERANGE)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: %s is out of range [%ld, %ld]", opt, text, min,
                    max);
  if (v < min || v > max)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: %ld is out of range [%ld, %ld]", opt, v, min,
                    max);
  *out = v;
  return LSM_OK;
}


/* ---- the parser ---------------------------------------------------------------------- */

typedef struct arg_cursor {
  int argc, i;
  char **argv;
} arg_cursor;

/* The value of an option: "--opt=value" or "--opt value". */
static lsm_status take_value(arg_cursor *c, const char *opt, const char *inline_value,
                             const char **out, lsm_err *err) {
  if (inline_value) {
    *out = inline_value;
    return LSM_OK;
  }
  if (c->i + 1 >= c->argc)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s needs a value", opt);
  *out = c->argv[++c->i];
  return LSM_OK;
}

/* A choice: the index of text in names (its enum's value), or an error that
 * lists the names. */
static lsm_status parse_choice(const char *opt, const char *text, const char *const *names,
                               int count, int *out, lsm_err *err) {
  const int k = lsm_name_index(names, count, text);
  if (k < 0) {
    char list[256];
    join_names(list, sizeof list, names, count, ", ");
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: '%s' is not one of %s", opt, text, list);
  }
  *out = k;
  return LSM_OK;
}

/* --seed: any 64-bit unsigned value, digits only. */
static lsm_status parse_seed(const char *text, uint64_t *out, lsm_err *err) {
  char *end = NULL;
  errno = 0;
  const unsigned long long seed = isdigit((unsigned char)text[0]) ? strtoull(text, &end, 10) : 0;
  if (!end || *end != '\0')
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "--seed: '%s' is not a whole number", text);
  if (errno == ERANGE || seed > UINT64_MAX)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "--seed: %s is out of range [0, 2^64 - 1]", text);
  *out = (uint64_t)seed;
  return LSM_OK;
}

static void cli_defaults(lsm_cli *cli) {
  memset(cli, 0, sizeof *cli);
  cli->spacing = 1.0;
  cli->max_pixels = (uint64_t)1 << 26;
  cli->max_voxels = (uint64_t)1 << 30;
  cli->write_slices = 1;
  cli->formats = LSM_FORMAT_NRRD;
  cli->values = LSM_VALUES_SDF;
  cli->nrrd_encoding = LSM_NRRD_RAW;
  cli->mesh = 0;
  cli->preview = 1;
  cli->backend = "c";
  cli->device = -1; /* the first GPU, else the first device */
  lsm_stack_opts_default(&cli->stack);
}

/* The entry of list (NULL-terminated) equal to name, or NULL. */
static const char *listed(const char *name, const char *const *list) {
  for (; *list; ++list)
    if (strcmp(name, *list) == 0) return *list;
  return NULL;
}

/* One option of reconstruct, `name` as given (before any "=value"); *value
 * is set when the option took a value. */
static lsm_status reconstruct_option(arg_cursor *c, const char *name, const char *inline_value,
                                     const char **value, lsm_cli *cli, lsm_err *err) {
  lsm_stack_opts *so = &cli->stack;
  const char *v = NULL;
  long n = 0;
  int k = 0;
#define IS(s) (strcmp(name, (s)) == 0)
#define VALUE() LSM_TRY(take_value(c, name, inline_value, &v, err))
#define CHOICE(names, field)                                                  \
  do {                                                                        \
    VALUE();                                                                  \
    LSM_TRY(parse_choice(name, v, names, COUNT_OF(names), &k, err));          \
    field = k;                                                                \
  } while (0)
#define INT(min, max, field)                                                  \
  do {                                                                        \
    VALUE();                                                                  \
    LSM_TRY(parse_int(name, v, min, max, &n, err));                           \
    field = (int)n;                                                           \
  } while (0)
#define TEXT(field) do { VALUE(); field = v; } while (0)
#define CALL(parse) do { VALUE(); LSM_TRY(parse); } while (0)
  if (IS("-o") || IS("--output")) TEXT(cli->out_dir);
  else if (IS("--input")) CHOICE(input_names, so->input);
  else if (IS("--invert")) cli->invert = 1;
  else if (IS("--spacing")) CALL(parse_length(name, v, &cli->spacing, err));
  else if (IS("--heights")) TEXT(cli->heights_file);
  else if (IS("--heights-from-names")) cli->heights_from_names = 1;
  else if (IS("--pixel-size")) CALL(parse_pixel_size(name, v, &so->pixel_dx, &so->pixel_dy, err));
  else if (IS("--dz")) CALL(parse_length(name, v, &so->dz, err));
  else if (IS("--per-iteration")) so->per_iteration = 1;
  else if (IS("--no-slices")) cli->write_slices = 0;
  else if (IS("--format")) CALL(lsm_format_list_parse(v, &cli->formats, err));
  else if (IS("--values")) CHOICE(values_names, cli->values);
  else if (IS("--nrrd-encoding")) CHOICE(nrrd_encoding_names, cli->nrrd_encoding);
  else if (IS("--mesh")) cli->mesh = 1;
  else if (IS("--no-preview")) cli->preview = 0;
  else if (IS("--method")) CHOICE(method_names, so->method);
  else if (IS("--scheme")) CHOICE(scheme_names, so->morph.scheme);
  else if (IS("--time")) CHOICE(time_names, so->morph.time);
  else if (IS("--cfl")) CALL(parse_double(name, v, &so->morph.cfl, 1, err));
  else if (IS("--band")) CHOICE(band_names, so->morph.band);
  else if (IS("--reinit-every")) INT(0, INT_MAX, so->morph.reinit_every);
  else if (IS("--reinit-iters")) INT(1, 100000, so->morph.reinit_iters);
  else if (IS("--tol")) CALL(parse_double(name, v, &so->tol, 1, err));
  else if (IS("--max-iter")) INT(1, INT_MAX, so->max_iter);
  else if (IS("--particles-per-cell")) INT(2, 256, so->morph.pls.particles_per_cell);
  else if (IS("--pls-reseed")) INT(0, INT_MAX, so->morph.pls.reseed_every);
  else if (IS("--pls-radius-adjust")) so->morph.pls.radius_adjust = 1;
  else if (IS("--seed")) CALL(parse_seed(v, &so->morph.pls.seed, err));
  else if (IS("--backend")) {
    int row = 0;
    CHOICE(backend_names, row);
    cli->backend = backend_names[row];
  }
  else if (IS("--device")) INT(0, 1000, cli->device);
  else if (IS("--interp")) CHOICE(interp_names, so->interp);
  else if (IS("--ends")) CHOICE(ends_names, so->ends);
  else if (IS("--align")) CHOICE(align_names, so->align);
  else if (IS("--motion")) CHOICE(motion_names, so->motion);
  else if (IS("--rules-off")) CALL(lsm_rules_switch_off(&so->rules, v, err));
  else if (IS("--threads")) INT(1, 4096, cli->threads);
  else if (IS("--max-pixels")) CALL(parse_count(name, v, "pixels", &cli->max_pixels, err));
  else if (IS("--max-voxels")) CALL(parse_count(name, v, "voxels", &cli->max_voxels, err));
  else if (IS("--max-memory")) CALL(parse_count(name, v, "bytes", &cli->max_memory, err));
  else if (IS("-q") || IS("--quiet")) cli->quiet = 1;
  else
    return lsm_fail(err, LSM_ERR_USAGE, NULL,
                    "unknown option '%s' (see 'lsmorph help reconstruct')", c->argv[c->i]);
#undef IS
#undef VALUE
#undef CHOICE
#undef INT
#undef TEXT
#undef CALL
  *value = v;
  return LSM_OK;
}

static lsm_status parse_reconstruct(arg_cursor *c, lsm_cli *cli, lsm_err *err) {
  static const char *const solver_options[] = {"--scheme",   "--time",         "--cfl",
                                               "--max-iter", "--reinit-every", "--reinit-iters",
                                               NULL};
  static const char *const pls_options[] = {"--particles-per-cell", "--pls-reseed",
                                            "--pls-radius-adjust", "--seed", NULL};
  const lsm_stack_opts *so = &cli->stack;
  int options = 1; /* until "--": after it every argument is SLICE_DIR */
  for (; c->i < c->argc; ++c->i) {
    const char *arg = c->argv[c->i];
    if (options && strcmp(arg, "--") == 0) {
      options = 0;
      continue;
    }
    if (!options || arg[0] != '-' || strcmp(arg, "-") == 0) {
      if (cli->slice_dir)
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "unexpected argument '%s' (one SLICE_DIR only)", arg);
      cli->slice_dir = arg;
      continue;
    }
    /* split "--name=value" */
    char name[64];
    const char *eq = strchr(arg, '=');
    const size_t len = eq ? (size_t)(eq - arg) : strlen(arg);
    if (len >= sizeof name) return lsm_fail(err, LSM_ERR_USAGE, NULL, "unknown option '%s'", arg);
    memcpy(name, arg, len);
    name[len] = '\0';
    if (strcmp(name, "-h") == 0 || strcmp(name, "--help") == 0) {
      cli->command = LSM_CMD_HELP;
      cli->help_topic = "reconstruct";
      return LSM_OK;
    }
    const char *inline_value = eq ? eq + 1 : NULL, *v = NULL;
    LSM_TRY(reconstruct_option(c, name, inline_value, &v, cli, err));
    if (inline_value && !v)
      return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s takes no value", name);
    if (!cli->solver_option) cli->solver_option = listed(name, solver_options);
    if (!cli->pls_option) cli->pls_option = listed(name, pls_options);
    cli->tol_given |= strcmp(name, "--tol") == 0;
    cli->device_given |= strcmp(name, "--device") == 0;
    cli->spacing_given |= strcmp(name, "--spacing") == 0;
    cli->interp_given |= strcmp(name, "--interp") == 0;
    cli->ends_given |= strcmp(name, "--ends") == 0;
    cli->motion_given |= strcmp(name, "--motion") == 0;
    cli->nrrd_encoding_given |= strcmp(name, "--nrrd-encoding") == 0;
  }
  const char *excluded = lsm_stack_field_excluded_by(so);
  if (cli->motion_given && so->motion == LSM_MOTION_FIELD && excluded)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "--motion field works in default mode with --align "
                    "auto or none, not with %s", excluded);
  if (!cli->slice_dir) return lsm_fail(err, LSM_ERR_USAGE, NULL, "reconstruct: missing SLICE_DIR");
  if (!cli->out_dir) return lsm_fail(err, LSM_ERR_USAGE, NULL, "reconstruct: missing -o OUT_DIR");
  if (!*cli->out_dir)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "-o: the output folder name is empty");
  if (!*cli->slice_dir)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "reconstruct: SLICE_DIR is empty");
  if (cli->heights_file && !*cli->heights_file)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "--heights: the file name is empty");
  if (cli->heights_file && cli->heights_from_names)
    return lsm_fail(err, LSM_ERR_USAGE, NULL,
                    "--heights and --heights-from-names both place the slices: give one");
  if (so->per_iteration && so->method == LSM_METHOD_BLEND)
    return lsm_fail(err, LSM_ERR_USAGE, NULL,
                    "--per-iteration needs a level-set method (--method ls or pls)");
  return LSM_OK;
}

static lsm_status parse_score(arg_cursor *c, lsm_cli *cli, lsm_err *err) {
  int options = 1; /* until "--": after it every argument is a folder */
  for (; c->i < c->argc; ++c->i) {
    const char *arg = c->argv[c->i];
    const int option = options && arg[0] == '-';
    if (option && strcmp(arg, "--") == 0) {
      options = 0;
    } else if (option && (strcmp(arg, "-h") == 0 || strcmp(arg, "--help") == 0)) {
      cli->command = LSM_CMD_HELP;
      cli->help_topic = "score";
      return LSM_OK;
    } else if (option && strncmp(arg, "--stride", 8) == 0 && (arg[8] == '\0' || arg[8] == '=')) {
      const char *v = NULL;
      LSM_TRY(take_value(c, "--stride", arg[8] == '=' ? arg + 9 : NULL, &v, err));
      long n;
      LSM_TRY(parse_int("--stride", v, 2, 1000000, &n, err));
      cli->stride = (int)n;
    } else if (option && strncmp(arg, "--first", 7) == 0 && (arg[7] == '\0' || arg[7] == '=')) {
      const char *v = NULL;
      LSM_TRY(take_value(c, "--first", arg[7] == '=' ? arg + 8 : NULL, &v, err));
      LSM_TRY(parse_int("--first", v, 1, 1000000000, &cli->first, err));
    } else if (option && strcmp(arg, "--per-slice") == 0) {
      cli->per_slice = 1;
    } else if (option) {
      return lsm_fail(err, LSM_ERR_USAGE, NULL, "unknown option '%s' (see 'lsmorph help score')", arg);
    } else if (!cli->truth_dir) {
      cli->truth_dir = arg;
    } else if (!cli->result_dir) {
      cli->result_dir = arg;
    } else {
      return lsm_fail(err, LSM_ERR_USAGE, NULL, "unexpected argument '%s'", arg);
    }
  }
  if (!cli->truth_dir || !cli->result_dir)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "score: needs TRUTH_DIR and OUT_DIR");
  if (!*cli->truth_dir || !*cli->result_dir)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "score: %s is empty",
                    *cli->truth_dir ? "OUT_DIR" : "TRUTH_DIR");
  return LSM_OK;
}


lsm_status lsm_cli_parse(int argc, char **argv, lsm_cli *cli, lsm_err *err) {
  cli_defaults(cli);
  if (argc < 2) return lsm_fail(err, LSM_ERR_USAGE, NULL, "no command (see 'lsmorph --help')");
  const char *cmd = argv[1];
  arg_cursor c = {argc, 2, argv};
  /* help [COMMAND], and --help [COMMAND] the same */
  if (strcmp(cmd, "help") == 0 || strcmp(cmd, "-h") == 0 || strcmp(cmd, "--help") == 0) {
    cli->command = LSM_CMD_HELP;
    cli->help_topic = argc > 2 ? argv[2] : NULL;
    if (cli->help_topic && !find_topic(cli->help_topic)) {
      char topics[256];
      topic_list(topics, sizeof topics, "help ", ", ");
      return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s: no command '%s' (%s)", cmd, cli->help_topic,
                      topics);
    }
    if (argc > 3)
      return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s takes one command at most, not '%s'", cmd,
                      argv[3]);
    return LSM_OK;
  }
  if (strcmp(cmd, "-V") == 0 || strcmp(cmd, "--version") == 0) {
    cli->command = LSM_CMD_VERSION;
    if (argc > 2) return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s takes no arguments", cmd);
    return LSM_OK;
  }
  if (strcmp(cmd, "reconstruct") == 0) {
    cli->command = LSM_CMD_RECONSTRUCT;
    return parse_reconstruct(&c, cli, err);
  }
  if (strcmp(cmd, "devices") == 0) {
    cli->command = LSM_CMD_DEVICES;
    if (argc == 3 && (strcmp(argv[2], "-h") == 0 || strcmp(argv[2], "--help") == 0)) {
      cli->command = LSM_CMD_HELP;
      cli->help_topic = "devices";
      return LSM_OK;
    }
    if (argc > 2) return lsm_fail(err, LSM_ERR_USAGE, NULL, "devices takes no arguments");
    return LSM_OK;
  }
  if (strcmp(cmd, "score") == 0) {
    cli->command = LSM_CMD_SCORE;
    return parse_score(&c, cli, err);
  }
  if (lsm_labels_format_of(cmd) != LSM_LABELS_UNKNOWN)
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "unknown command '%s': to fill a label volume, "
                    "'lsmorph fill %s -o OUT' (see 'lsmorph help fill')", cmd, cmd);
  return lsm_fail(err, LSM_ERR_USAGE, NULL, "unknown command '%s' (see 'lsmorph --help')", cmd);
}


void lsm_cli_note_unused(const lsm_cli *cli, FILE *f) {
  if (cli->stack.per_iteration && cli->stack.dz > 0)
    fprintf(f, "lsmorph: note: --dz has no effect with --per-iteration (every solver "
               "iteration is a slice)\n");
  if (cli->stack.per_iteration &&
      ((cli->interp_given && cli->stack.interp != LSM_INTERP_LINEAR) ||
       (cli->ends_given && cli->stack.ends != LSM_ENDS_HALFWAY)))
    fprintf(f, "lsmorph: note: --per-iteration takes the linear profile and ends an "
               "object at mid-gap: --interp cubic and --ends tip|auto have no effect\n");
  else if (cli->stack.interp == LSM_INTERP_LINEAR && cli->ends_given &&
           cli->stack.ends != LSM_ENDS_HALFWAY)
    fprintf(f, "lsmorph: note: --interp linear ends an object at mid-gap: --ends "
               "tip|auto have no effect (they shape the cubic profile's ends)\n");
  if (cli->stack.method == LSM_METHOD_BLEND && cli->solver_option)
    fprintf(f, "lsmorph: note: %s has no effect with --method blend, which solves no "
               "PDE (no solver option does: --scheme, --time, --cfl, --max-iter, "
               "--reinit-every, --reinit-iters)\n", cli->solver_option);
  if (cli->stack.method != LSM_METHOD_PLS && cli->pls_option)
    fprintf(f, "lsmorph: note: %s has no effect without --method pls (it sets up the "
               "particles)\n", cli->pls_option);
  if (!cli->stack.per_iteration && cli->tol_given)
    fprintf(f, "lsmorph: note: --tol has no effect without --per-iteration (it stops "
               "each pair of that mode)\n");
  if (cli->heights_file && cli->spacing_given)
    fprintf(f, "lsmorph: note: --spacing has no effect with --heights (the file gives "
               "every slice's height)\n");
  if (strcmp(cli->backend, "c") == 0 && cli->device_given)
    fprintf(f, "lsmorph: note: --device has no effect with --backend c\n");
  if (cli->nrrd_encoding_given && !(cli->formats & LSM_FORMAT_NRRD))
    fprintf(f, "lsmorph: note: --nrrd-encoding has no effect without nrrd in --format\n");
  if (cli->stack.method != LSM_METHOD_BLEND && cli->stack.morph.cfl > 1.0)
    fprintf(f, "lsmorph: note: --cfl %g is above 1, where the schemes are no longer "
               "monotone: thin parts may oscillate or blow up (a blow-up stops the run "
               "with an error)\n", cli->stack.morph.cfl);
}
