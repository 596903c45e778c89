#include "solver/app/lsm_cli.h"

#include "io/lsm_io.h"

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char general_help[] =
    "lsmorph " LSM_VERSION " - fill the gaps between sparse parallel slices by level-set morphing\n"
    "\n"
    "Usage:\n"
    "  lsmorph fill LABELS -o OUT [options]      (label volumes: .nii, .nii.gz, .nrrd)\n"
    "  lsmorph reconstruct SLICE_DIR -o OUT_DIR [options]\n"
    "  lsmorph score TRUTH_DIR OUT_DIR [--stride K] [--first N] [--per-slice]\n"
    "  lsmorph devices\n"
    "  lsmorph --help [COMMAND] | --version | help fill|reconstruct|score|devices|rules\n"
    "\n"
    "Commands:\n"
    "  fill          fill the slices between the drawn slices of a NIfTI or NRRD label map,\n"
    "                every label at once ('lsmorph help fill')\n"
    "  reconstruct   read PNG or TIFF slices, morph between consecutive slices, write a volume\n"
    "  score         compare a reconstruction with full-resolution truth slices\n"
    "  devices       list the OpenCL platforms and devices\n"
    "\n"
    "Run 'lsmorph help reconstruct' for the options.  Every option also takes the\n"
    "form --name=value; after '--' every argument is a folder (for names that\n"
    "start with '-').\n";

static const char reconstruct_help[] =
    "Usage: lsmorph reconstruct SLICE_DIR -o OUT_DIR [options]\n"
    "       (-o is also --output)\n"
    "\n"
    "Reads the PNG and TIFF files of SLICE_DIR (.png, .tif, .tiff; one page each) in\n"
    "natural order (2.png before 10.png), one slice each, evolves each slice into the\n"
    "next with phi_t + (phi - phi_target)|grad phi| = 0,\n"
    "and writes the stacked slices to OUT_DIR.  An empty slice (no foreground) ends\n"
    "the object: each part of the last section beside it closes inside that gap the\n"
    "way the slices before it were narrowing, up to mid-gap; past it a small tip\n"
    "reaches the empty slice when that slice is the first or last one given (see\n"
    "--ends; solver/README.md, section 8).  Nothing is extrapolated past the first\n"
    "and last slices: keep one empty slice beyond each end for the object to close\n"
    "there.\n"
    "\n"
    "Input:\n"
    "  --input mask|outline   mask: filled regions (default); outline: thin closed\n"
    "                         8-connected contours, inside found by parity (nested\n"
    "                         contours, holes, islands in holes)\n"
    "  --invert               foreground is dark (default: luminance >= 50 %; label\n"
    "                         masks stored as 0/1 are read as non-zero = foreground)\n"
    "  --spacing Z            distance between consecutive slices (default 1); with\n"
    "                         --heights-from-names, between consecutive numbers\n"
    "  --heights FILE         one height per slice, strictly increasing (overrides\n"
    "                         --spacing); blank lines and # comments allowed\n"
    "  --heights-from-names   each slice's height is the number its file name ends\n"
    "                         with (slice_012.png: 12) times --spacing, for slices kept\n"
    "                         under their index in the scan (001.png 009.png 017.png,\n"
    "                         or unevenly); without it consecutive files are --spacing\n"
    "                         apart whatever their names (a note says when the names\n"
    "                         number the slices with gaps)\n"
    "  --pixel-size S|SX,SY   physical size of a pixel (default 1), or its width (x,\n"
    "                         along a row) and height (y, down a column) when it is\n"
    "                         not square; all distances, heights and the output\n"
    "                         signed distance use this unit;\n"
    "                         the pixel size, --spacing, --dz and every gap between\n"
    "                         heights must lie in 1e-30 .. 1e30 (lengths are floats);\n"
    "                         an output step below about 1.8e-15 of the largest\n"
    "                         |height| is refused (it would repeat heights)\n"
    "  --max-pixels N         refuse slices with more pixels (default 268435456); with\n"
    "                         --align auto|hull also a gap's working canvas, up to\n"
    "                         (2W+4) x (2H+4) cells for W x H slices, must stay\n"
    "                         within 4 N: (W+2) x (H+2) <= N (or use --align none);\n"
    "                         whatever N, a working grid has at most 2^31 - 1 cells\n"
    "  --max-voxels N         refuse runs whose output volume would have more voxels\n"
    "                         (default 17179869184 = 2^34; with --per-iteration,\n"
    "                         whose slice count is not known ahead, the run stops\n"
    "                         with an error when the next slice would pass N)\n"
    "\n";

/* (the help is split: C17 compilers need to support string literals of 4095 bytes only) */
static const char reconstruct_help_output[] =
    "Output:\n"
    "  --dz Z                 output slice spacing (default: the pixel size, isotropic\n"
    "                         voxels; the smaller side of a pixel that is not square);\n"
    "                         output heights are z0, z0+dz, ... up to the last input\n"
    "                         height; input heights on that grid get their input\n"
    "                         slice back exactly (a note says when the last one is not\n"
    "                         on it, and which --dz would end on it)\n"
    "  --per-iteration        the design document's mode: every solver iteration of\n"
    "                         every pair is a slice, heights by linspace per pair;\n"
    "                         linear profile (--interp and --ends do not apply); next\n"
    "                         to an empty slice the shape shrinks until it vanishes\n"
    "                         and its iterates fill the half gap beside the full slice\n"
    "  --no-slices            do not write slices/*.png\n"
    "  --format LIST          volume formats, comma separated (default nrrd):\n"
    "                         nrrd, mha (MetaImage), vtk (legacy VTK), nii (NIfTI-1),\n"
    "                         nii.gz (NIfTI-1, gzip), exr (one OpenEXR file per\n"
    "                         slice), raw (+ volume.json)\n"
    "  --values sdf|mask      sdf: float32 signed distance (default); mask: uint8,\n"
    "                         255 inside, 0 outside (EXR: half 1.0 / 0.0)\n"
    "  --nrrd-encoding raw|gzip  volume.nrrd's samples as they are (default) or as\n"
    "                         one gzip stream (NRRD's standard encoding gzip, as 3D\n"
    "                         Slicer writes it; masks shrink most)\n"
    "  --mesh                 also write surface.ply, a closed triangle mesh of the\n"
    "                         surface phi = 0\n"
    "  --no-preview           do not write preview.png and preview3d.png\n"
    "\n";

static const char reconstruct_help_method[] =
    "Method:\n"
    "  --method ls|pls|blend  ls: level-set morph (default); pls: level-set morph\n"
    "                         corrected by Lagrangian particles (keeps corners and thin\n"
    "                         features); blend: linear interpolation of the two signed\n"
    "                         distance functions\n"
    "  --particles-per-cell N pls: particles seeded per band cell, half of each sign\n"
    "                         (odd: one more positive; 2 .. 256, default 16)\n"
    "  --pls-reseed N         pls: reseed the particles every N steps (default 0 = never)\n"
    "  --pls-radius-adjust    pls: reset particle radii after each correction (off)\n"
    "  --seed N               pls: random seed, 0 .. 2^64 - 1 (same seed, same volume,\n"
    "                         any --threads)\n"
    "  --scheme upwind|roe-fix|weno5  numerical Hamiltonian (default upwind:\n"
    "                         first-order Godunov; roe-fix: Algorithm 3.1 of the design\n"
    "                         document; weno5: fifth-order HJ-WENO derivatives in the\n"
    "                         Godunov Hamiltonian, with --time rk3, not monotone)\n"
    "  --time euler|rk2|rk3   time integrator (default euler; rk2/rk3: TVD Runge-Kutta)\n"
    "  --cfl C                CFL number, 0 < C (default 0.75; upwind and roe-fix are\n"
    "                         monotone up to 1, a note says when C is above)\n"
    "  --reinit-every N       reinitialise phi to a signed distance every N steps\n"
    "                         (default 0 = never, as in the design document)\n"
    "  --reinit-iters N       pseudo-time iterations per reinitialisation (1 .. 100000,\n"
    "                         default 10)\n"
    "  --tol T                per-iteration mode: stop a pair when\n"
    "                         CP = | ||phi^n - phi_T|| - ||phi^(n-1) - phi_T|| | <= T\n"
    "                         (default 0.25; the norm is over all cells, so CP grows\n"
    "                         with the square root of the cell count: scale T with it;\n"
    "                         a pair next to an empty slice stops when the shape vanishes)\n"
    "  --max-iter N           most solver steps per morph (default 100000); a gap runs\n"
    "                         two, A -> B and B -> A (one with --per-iteration)\n"
    "  --interp linear|cubic  z-profile through the slices (default cubic): cubic adds to\n"
    "                         each gap's morph the departure of a monotone cubic (PCHIP)\n"
    "                         through the four nearest slices from the straight line,\n"
    "                         so surfaces are C1 across the slices inside an object,\n"
    "                         without overshoot\n"
    "  --ends auto|tip|halfway  where an object meets an empty slice (cubic profile):\n"
    "                         tip keeps a shrinking tip past mid-gap up to the empty slice,\n"
    "                         right when the object reaches close to it (a stack cut one\n"
    "                         slice beyond the object); halfway draws nothing past mid-gap,\n"
    "                         right when the true end may lie anywhere in the gap (slices\n"
    "                         placed independently of the object); auto (default): tip\n"
    "                         where the empty slice is the first or last slice given,\n"
    "                         halfway where more slices lie beyond it (--interp linear\n"
    "                         always ends at mid-gap)\n"
    "  --align auto|hull|none hull: move each slice's convex-hull centroid to the image\n"
    "                         centre before morphing and move intermediate slices back\n"
    "                         along the line (or monotone cubic) through the centroids;\n"
    "                         auto (default): hull for a pair only when the shape moved\n"
    "                         rather than changed: little overlap in place (IoU < 1/2),\n"
    "                         more once shifted, the shift of largest overlap nearer the\n"
    "                         centroid shift than none, and the two alike at that shift\n"
    "                         (solver/README.md, section 9); none: no alignment\n"
    "  --rules-off NAME,...   switch rules off, for experiments ('lsmorph help rules')\n"
    "\n";

static const char reconstruct_help_running[] =
    "Running:\n"
    "  --threads N            threads, 1 .. 4096 (default: all cores): gaps side by\n"
    "                         side for slices up to 1024^2 (any size with --backend\n"
    "                         opencl), as many as their waiting output slices fit in\n"
    "                         512 MiB; else inside a gap\n"
    "  --backend c|opencl|auto  where the grid work runs (default c, the reference);\n"
    "                         auto: OpenCL when a device is present, else C\n"
    "  --device N             OpenCL device index from 'lsmorph devices', 0 .. 1000\n"
    "                         (default: the first GPU listed, else device 0)\n"
    "  -q, --quiet            no progress or notes on stderr (errors still)\n"
    "\n";

/* (several strings: one would pass the 4095 characters C compilers must support) */
static const char reconstruct_help_files[] =
    "Files written to OUT_DIR:\n"
    "  volume.nrrd            float32 signed distance (negative inside) of every output\n"
    "                         slice, x fastest, spacings in physical units: exact at\n"
    "                         the input slices, between them the interpolated level\n"
    "                         set (zero on the surface, close to a distance near it)\n"
    "  volume.mha             the same as MetaImage (--format mha; header + data in\n"
    "                         one file, little endian)\n"
    "  volume.vtk             the same as legacy VTK STRUCTURED_POINTS (--format vtk;\n"
    "                         binary, big endian as the format requires)\n"
    "  volume.nii             the same as NIfTI-1 (--format nii; one file, little\n"
    "                         endian, at most 32767 samples along each axis): its\n"
    "                         affine is diag(-sx, -sy, sz) in NIfTI's RAS world, so\n"
    "                         3D Slicer and ITK place it where they place volume.nrrd\n"
    "  volume.nii.gz          the same, gzip compressed (--format nii.gz; on the bunny\n"
    "                         masks shrink 48x, signed distances 1.3x to 3.8x)\n"
    "  exr/00001.exr ...      one single-channel (Y) OpenEXR file per slice (--format\n"
    "                         exr): float32, or half 1/0 with --values mask; header\n"
    "                         attributes pixelSize, sliceHeight\n"
    "  volume.raw, volume.json  headerless little-endian samples and a JSON sidecar\n"
    "                         with sizes, spacing, origin, dtype (--format raw)\n"
    "                         All volumes carry spacing and origin (the centre of the\n"
    "                         first sample) in physical units.\n"
    "  surface.ply            (--mesh) binary little-endian PLY of the surface\n"
    "                         phi = 0 (marching tetrahedra, closed and manifold;\n"
    "                         x = column * pixel width, y = row * pixel height,\n"
    "                         z = height;\n"
    "                         outward normals)\n"
    "  preview.png            up to 16 evenly spaced slices (input slices framed in\n"
    "                         orange)\n"
    "  preview3d.png          a shaded rendering of the surface\n"
    "  heights.txt            the height of each output slice, one per line\n"
    "  slices/00001.png ...   binary mask of each output slice (255 inside: phi < 0;\n"
    "                         no sample is exactly 0)\n"
    "  run.json               options, per-pair iterations, dt, CP, seconds, cells; totals\n"
    "\n"
    "Exit status: 0 success, 1 bad input or failure, 2 usage error, 130 / 143 / 129\n"
    "interrupted by SIGINT / SIGTERM / SIGHUP (the process ends by that signal).\n"
    "Results are written to a temporary folder OUT_DIR.tmp-XXXXXX next to OUT_DIR and\n"
    "moved into place only when complete; on any failure or interruption it is\n"
    "removed and an earlier OUT_DIR is left as it was.  An existing OUT_DIR is replaced\n"
    "only when it is empty or an earlier result (it has a run.json).\n";

static const char score_help[] =
    "Usage: lsmorph score TRUTH_DIR OUT_DIR [--stride K] [--first N] [--per-slice]\n"
    "\n"
    "Scores a reconstruction made from some of the slices of TRUTH_DIR (a full\n"
    "stack, in natural order) against the slices left out between them.  Which\n"
    "slices were the inputs:\n"
    "  --stride K   every K-th (K >= 2), from the first input (below):\n"
    "               reconstructed with --spacing K and the default --dz and\n"
    "               --pixel-size (or with --heights-from-names on slices kept under\n"
    "               their own numbers)\n"
    "  (none)       where OUT_DIR/run.json's input heights put them: each input\n"
    "               lies as many truth slices above the first as its height lies\n"
    "               output steps (--dz) above the first's.  For any kept slices,\n"
    "               evenly or not, reconstructed with --dz equal to the truth's\n"
    "               slice spacing (--heights-from-names on slices kept under\n"
    "               their numbers in the truth: 1 apart by default)\n"
    "  --first N    the first input is truth slice N; the slices before it are\n"
    "               not scored.  Without it: the truth slice whose file name is\n"
    "               the first input's, when every input is named as the truth\n"
    "               slice it lies at (run.json's input.files; slices kept under\n"
    "               their own names, a note says so), else truth slice 1\n"
    "The n-th file of OUT_DIR/slices (00001.png, 00002.png, ...) is compared with\n"
    "the n-th truth slice counted from the first input, for every one that was\n"
    "not an input, up to the last input (nothing is extrapolated past it; a note\n"
    "names the truth slices beyond it, which are not scored).  Prints one JSON\n"
    "object (distances in pixel widths, a row step counting run.json's\n"
    "pixel_size_y / pixel_size of them; symmetric, between boundary pixels):\n"
    "  held_out         slices scored\n"
    "  dice_volume      Dice pooled over all held-out slices\n"
    "  dice             mean Dice per slice\n"
    "  hd95             mean 95 % Hausdorff distance over the slices non-empty on\n"
    "                   both sides (slices empty on both sides have no boundary\n"
    "                   and are left out of it and of mean_surface)\n"
    "  hd95_pooled      95 % Hausdorff distance over all boundary pixels pooled; a\n"
    "                   slice empty on one side only counts the image size for each\n"
    "                   of its boundary pixels\n"
    "  mean_surface     mean surface distance over the slices non-empty on both sides\n"
    "  volume_error     (result - truth) / truth volume over the held-out slices\n"
    "  one_sided_empty  held-out slices empty on one side only\n"
    "  slices           with --per-slice: one object per held-out slice, in order:\n"
    "                   truth (its number, from 1), file, between (the truth\n"
    "                   numbers of the inputs below and above it), dice, hd95,\n"
    "                   mean_surface (null unless non-empty on both sides),\n"
    "                   area_result, area_truth (pixels)\n"
    "A score that is undefined is null: the distances where no slice has a boundary,\n"
    "the volume error where the truth is empty.\n"
    "The folders come in that order: TRUTH_DIR has no run.json, OUT_DIR has one.\n"
    "A result that does not fit TRUTH_DIR and its inputs is refused: its slices\n"
    "must run from the first input to the last, one truth slice apart, with\n"
    "--stride its run.json must count the kept slices (input.slices), and every\n"
    "input must come back exactly.  (Slices written by another tool, with no\n"
    "run.json, need --stride and are scored without the count's check.)  Truth\n"
    "stored as 0/1 label masks is read as reconstruct reads them, the rule decided\n"
    "over the kept slices.\n";

static const char devices_help[] =
    "Usage: lsmorph devices\n"
    "\n"
    "Lists the OpenCL platforms and devices this machine offers, one index each, with\n"
    "name, type, version, compute units and global memory.  'reconstruct --backend\n"
    "opencl --device N' runs on device N; without --device, on the first GPU listed,\n"
    "else on device 0.  Exits 1 when OpenCL is not available (no ICD loader or no\n"
    "platform).\n";

void lsm_cli_help(FILE *f, const char *topic) {
  if (topic && strcmp(topic, "reconstruct") == 0) {
    fputs(reconstruct_help, f);
    fputs(reconstruct_help_output, f);
    fputs(reconstruct_help_method, f);
    fputs(reconstruct_help_running, f);
    fputs(reconstruct_help_files, f);
  }
  else if (topic && strcmp(topic, "score") == 0)
    fputs(score_help, f);
  else if (topic && strcmp(topic, "devices") == 0)
    fputs(devices_help, f);
  else if (topic && strcmp(topic, "rules") == 0)
    lsm_rules_print(f);
  else
    fputs(general_help, f);
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

/* A limit counted in `unit` (--max-pixels, --max-voxels): a positive whole
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

static void cli_defaults(lsm_cli *cli) {
  memset(cli, 0, sizeof *cli);
  cli->spacing = 1.0;
  cli->max_pixels = (uint64_t)1 << 28;
  cli->max_voxels = (uint64_t)1 << 34;
  cli->write_slices = 1;
  cli->formats = LSM_FORMAT_NRRD;
  cli->values = LSM_VALUES_SDF;
  cli->mesh = 0;
  cli->preview = 1;
  cli->device = -1; /* the first GPU, else the first device */
  lsm_stack_opts_default(&cli->stack);
}

/* The entry of list (NULL-terminated) equal to name, or NULL. */
static const char *listed(const char *name, const char *const *list) {
  for (; *list; ++list)
    if (strcmp(name, *list) == 0) return *list;
  return NULL;
}

static lsm_status parse_reconstruct(arg_cursor *c, lsm_cli *cli, lsm_err *err) {
  static const char *const solver_options[] = {"--scheme",   "--time",         "--cfl",
                                               "--max-iter", "--reinit-every", "--reinit-iters",
                                               NULL};
  static const char *const pls_options[] = {"--particles-per-cell", "--pls-reseed",
                                            "--pls-radius-adjust", "--seed", NULL};
  lsm_stack_opts *so = &cli->stack;
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
    /* Split "--name=value". */
    char name[64];
    const char *eq = strchr(arg, '=');
    const char *inline_value = NULL;
    size_t len = eq ? (size_t)(eq - arg) : strlen(arg);
    if (len >= sizeof name) return lsm_fail(err, LSM_ERR_USAGE, NULL, "unknown option '%s'", arg);
    memcpy(name, arg, len);
    name[len] = '\0';
    if (eq) inline_value = eq + 1;
    const char *v = NULL;
    long n;
#define NEEDS_VALUE() LSM_TRY(take_value(c, name, inline_value, &v, err))
#define IS(s) (strcmp(name, (s)) == 0)
    if (IS("-h") || IS("--help")) {
      cli->command = LSM_CMD_HELP;
      cli->help_topic = "reconstruct";
      return LSM_OK;
    } else if (IS("-o") || IS("--output")) {
      NEEDS_VALUE();
      cli->out_dir = v;
    } else if (IS("--input")) {
      NEEDS_VALUE();
      if ((so->input = lsm_input_from_name(v)) == LSM_INPUT_UNKNOWN)
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "--input: '%s' is not one of mask, outline", v);
    } else if (IS("--invert")) {
      cli->invert = 1;
    } else if (IS("--spacing")) {
      NEEDS_VALUE();
      LSM_TRY(parse_length(name, v, &cli->spacing, err));
    } else if (IS("--heights")) {
      NEEDS_VALUE();
      cli->heights_file = v;
    } else if (IS("--heights-from-names")) {
      cli->heights_from_names = 1;
    } else if (IS("--pixel-size")) {
      NEEDS_VALUE();
      LSM_TRY(parse_pixel_size(name, v, &so->pixel_dx, &so->pixel_dy, err));
    } else if (IS("--dz")) {
      NEEDS_VALUE();
      LSM_TRY(parse_length(name, v, &so->dz, err));
    } else if (IS("--per-iteration")) {
      so->per_iteration = 1;
    } else if (IS("--no-slices")) {
      cli->write_slices = 0;
    } else if (IS("--format")) {
      NEEDS_VALUE();
      LSM_TRY(lsm_format_list_parse(v, &cli->formats, err));
    } else if (IS("--values")) {
      NEEDS_VALUE();
      if ((cli->values = lsm_values_from_name(v)) == LSM_VALUES_UNKNOWN)
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "--values: '%s' is not one of sdf, mask", v);
    } else if (IS("--nrrd-encoding")) {
      NEEDS_VALUE();
      if (strcmp(v, "raw") != 0 && strcmp(v, "gzip") != 0)
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "--nrrd-encoding: '%s' is not one of raw, gzip", v);
      cli->nrrd_gzip = strcmp(v, "gzip") == 0;
      cli->nrrd_encoding_given = 1;
    } else if (IS("--mesh")) {
      cli->mesh = 1;
    } else if (IS("--no-preview")) {
      cli->preview = 0;
    } else if (IS("--method")) {
      NEEDS_VALUE();
      if ((so->method = lsm_method_from_name(v)) == LSM_METHOD_UNKNOWN)
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "--method: '%s' is not one of ls, pls, blend", v);
    } else if (IS("--scheme")) {
      NEEDS_VALUE();
      if ((so->morph.scheme = lsm_scheme_from_name(v)) == LSM_SCHEME_UNKNOWN)
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "--scheme: '%s' is not one of upwind, roe-fix, weno5", v);
    } else if (IS("--time")) {
      NEEDS_VALUE();
      if ((so->morph.time = lsm_time_from_name(v)) == LSM_TIME_UNKNOWN)
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "--time: '%s' is not one of euler, rk2, rk3", v);
    } else if (IS("--cfl")) {
      NEEDS_VALUE();
      LSM_TRY(parse_double(name, v, &so->morph.cfl, 1, err));
    } else if (IS("--reinit-every")) {
      NEEDS_VALUE();
      LSM_TRY(parse_int(name, v, 0, INT_MAX, &n, err));
      so->morph.reinit_every = (int)n;
    } else if (IS("--reinit-iters")) {
      NEEDS_VALUE();
      LSM_TRY(parse_int(name, v, 1, 100000, &n, err));
      so->morph.reinit_iters = (int)n;
    } else if (IS("--tol")) {
      NEEDS_VALUE();
      LSM_TRY(parse_double(name, v, &so->tol, 1, err));
    } else if (IS("--max-iter")) {
      NEEDS_VALUE();
      LSM_TRY(parse_int(name, v, 1, INT_MAX, &n, err));
      so->max_iter = (int)n;
    } else if (IS("--particles-per-cell")) {
      NEEDS_VALUE();
      LSM_TRY(parse_int(name, v, 2, 256, &n, err));
      so->morph.pls.particles_per_cell = (int)n;
    } else if (IS("--pls-reseed")) {
      NEEDS_VALUE();
      LSM_TRY(parse_int(name, v, 0, INT_MAX, &n, err));
      so->morph.pls.reseed_every = (int)n;
    } else if (IS("--pls-radius-adjust")) {
      so->morph.pls.radius_adjust = 1;
    } else if (IS("--seed")) {
      NEEDS_VALUE();
      /* any 64-bit unsigned value: digits only */
      char *end = NULL;
      errno = 0;
      const unsigned long long seed = isdigit((unsigned char)v[0]) ? strtoull(v, &end, 10) : 0;
      if (!end || *end != '\0')
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "--seed: '%s' is not a whole number", v);
      if (errno == ERANGE || seed > UINT64_MAX)
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "--seed: %s is out of range [0, 2^64 - 1]", v);
      so->morph.pls.seed = (uint64_t)seed;
    } else if (IS("--backend")) {
      NEEDS_VALUE();
      if ((cli->backend = lsm_backend_kind_from_name(v)) == LSM_BACKEND_UNKNOWN)
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "--backend: '%s' is not one of c, opencl, auto", v);
    } else if (IS("--device")) {
      NEEDS_VALUE();
      LSM_TRY(parse_int(name, v, 0, 1000, &n, err));
      cli->device = (int)n;
    } else if (IS("--interp")) {
      NEEDS_VALUE();
      cli->interp_given = 1;
      if ((so->interp = lsm_interp_from_name(v)) == LSM_INTERP_UNKNOWN)
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "--interp: '%s' is not one of linear, cubic", v);
    } else if (IS("--ends")) {
      NEEDS_VALUE();
      cli->ends_given = 1;
      if ((so->ends = lsm_end_rule_from_name(v)) == LSM_ENDS_UNKNOWN)
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "--ends: '%s' is not one of auto, tip, halfway", v);
    } else if (IS("--align")) {
      NEEDS_VALUE();
      if ((so->align = lsm_align_from_name(v)) == LSM_ALIGN_UNKNOWN)
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "--align: '%s' is not one of auto, hull, none", v);
    } else if (IS("--rules-off")) {
      NEEDS_VALUE();
      LSM_TRY(lsm_rules_switch_off(&so->rules, v, err));
    } else if (IS("--threads")) {
      NEEDS_VALUE();
      LSM_TRY(parse_int(name, v, 1, 4096, &n, err));
      cli->threads = (int)n;
    } else if (IS("--max-pixels")) {
      NEEDS_VALUE();
      LSM_TRY(parse_count(name, v, "pixels", &cli->max_pixels, err));
    } else if (IS("--max-voxels")) {
      NEEDS_VALUE();
      LSM_TRY(parse_count(name, v, "voxels", &cli->max_voxels, err));
    } else if (IS("-q") || IS("--quiet")) {
      cli->quiet = 1;
    } else {
      return lsm_fail(err, LSM_ERR_USAGE, NULL, "unknown option '%s' (see 'lsmorph help reconstruct')", arg);
    }
    if (inline_value && !v)
      return lsm_fail(err, LSM_ERR_USAGE, NULL, "%s takes no value", name);
    if (!cli->solver_option) cli->solver_option = listed(name, solver_options);
    if (!cli->pls_option) cli->pls_option = listed(name, pls_options);
    cli->tol_given |= IS("--tol");
    cli->device_given |= IS("--device");
    cli->spacing_given |= IS("--spacing");
#undef NEEDS_VALUE
#undef IS
  }
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
    if (cli->help_topic && strcmp(cli->help_topic, "reconstruct") != 0 &&
        strcmp(cli->help_topic, "score") != 0 && strcmp(cli->help_topic, "devices") != 0 &&
        strcmp(cli->help_topic, "rules") != 0)
      return lsm_fail(err, LSM_ERR_USAGE, NULL,
                      "%s: no command '%s' (help reconstruct, help score, help devices, help rules)",
                      cmd, cli->help_topic);
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
  if (cli->backend == LSM_BACKEND_C && cli->device_given)
    fprintf(f, "lsmorph: note: --device has no effect with --backend c\n");
  if (cli->nrrd_encoding_given && !(cli->formats & LSM_FORMAT_NRRD))
    fprintf(f, "lsmorph: note: --nrrd-encoding has no effect without nrrd in --format\n");
  if (cli->stack.method != LSM_METHOD_BLEND && cli->stack.morph.cfl > 1.0)
    fprintf(f, "lsmorph: note: --cfl %g is above 1, where the schemes are no longer "
               "monotone: thin parts may oscillate or blow up (a blow-up stops the run "
               "with an error)\n", cli->stack.morph.cfl);
}
