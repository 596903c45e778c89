/* lsmorph: the command-line program.  Parses the command line (lsm_cli), wires
 * PNG or TIFF slices (io/) into the stack driver (lsm_stack) and its output slices into
 * the writers, writes run.json, and publishes OUT_DIR atomically. */
#define _XOPEN_SOURCE 700
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <inttypes.h>
#if defined(__GLIBC__) || defined(__linux__)
#include <malloc.h>
#endif
#include <math.h>
#include <omp.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "io/lsm_io.h"
#include "solver/pde/lsm_backend.h"
#include "solver/app/lsm_cli.h"
#include "io/lsm_mesh.h"
#include "solver/app/lsm_metrics.h"
#include "solver/app/lsm_mpi.h"
#include "io/lsm_preview.h"
#include "solver/recon/lsm_stack.h"

static double wall_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- removing a folder tree (temporary results) ------------------------------------ */

static int remove_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw) {
  (void)sb;
  (void)flag;
  (void)ftw;
  return remove(path);
}

static void remove_tree(const char *path) {
  if (path && *path) nftw(path, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
}

/* ---- interruption: SIGINT, SIGTERM ------------------------------------------------------ */

/* The signal that asked the run to stop, 0 while none has.  This is the one
 * file-scope mutable variable of the program, and it has to be one: a signal
 * handler receives no context pointer, and the only thing C (C17 7.14.1.1) and
 * POSIX let it do with program state is store to a volatile sig_atomic_t.
 * Everything else travels in values (lsm_err, the source, the sinks). */
static volatile sig_atomic_t stop_signal = 0;

static void on_stop_signal(int sig) { stop_signal = sig; }

/* SIGINT, SIGTERM and SIGHUP only set stop_signal; the run notices it before
 * the next input or output slice (and before publishing) and unwinds through
 * the normal error path, which removes the temporary folder.  SA_RESETHAND
 * makes a second signal of the same kind take the default action at once (a
 * stuck run can still be killed).  A signal ignored when we started (SIGINT of
 * a background job of a shell without job control, nohup's SIGHUP) stays
 * ignored.  SIGPIPE is ignored: progress on stderr piped into a reader that
 * quit is not worth a half-written result.  So is SIGXFSZ: past a file-size
 * limit (ulimit -f) the write fails with EFBIG and the error path removes the
 * temporary folder, where the signal's default action left it behind.
 *
 * While the input is read (restart 0) a signal interrupts a blocking call: a
 * --heights FIFO whose writer never comes (`--heights <(cmd)` with a failed
 * cmd) would otherwise hold open() through the first SIGTERM.  From the first
 * output on (restart 1, set again unless a signal has already come) SA_RESTART
 * keeps writes in progress from failing with EINTR. */
static void install_stop_handlers(int restart) {
  struct sigaction ign;
  memset(&ign, 0, sizeof ign);
  ign.sa_handler = SIG_IGN;
  sigemptyset(&ign.sa_mask);
  sigaction(SIGPIPE, &ign, NULL);
  sigaction(SIGXFSZ, &ign, NULL); /* past a file-size limit a write fails (EFBIG) instead */
  const int sigs[3] = {SIGINT, SIGTERM, SIGHUP};
  for (int k = 0; k < 3; ++k) {
    struct sigaction old, sa;
    if (sigaction(sigs[k], NULL, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = (restart ? SA_RESTART : 0) | SA_RESETHAND;
    sigaction(sigs[k], &sa, NULL);
  }
}

static const char *stop_signal_name(int sig) {
  return sig == SIGINT    ? "SIGINT"
         : sig == SIGTERM ? "SIGTERM"
         : sig == SIGHUP  ? "SIGHUP"
                          : "a signal";
}

/* LSM_ERR_INTERRUPTED once a stop signal has arrived. */
static lsm_status check_stop(lsm_err *err) {
  const int sig = stop_signal;
  if (!sig) return LSM_OK;
  return lsm_fail(err, LSM_ERR_INTERRUPTED, NULL, "interrupted by %s", stop_signal_name(sig));
}

/* The run-wide settings of a reconstruction: the thread count (--threads, or
 * all cores), which the loops without their own count (distance transforms,
 * previews) follow too, and the stop flag that long gaps check at every step.
 * Returns the thread count. */
static int setup_run(lsm_cli *cli) {
  const int threads = cli->threads > 0 ? cli->threads : omp_get_num_procs();
  cli->stack.morph.threads = threads;
  omp_set_num_threads(threads);
  cli->stack.morph.stop = &stop_signal;
  return threads;
}

/* A sink that checks for a stop signal before handing each slice to the real one. */
static lsm_status stoppable_emit(void *ctx, const float *phi, int width, int height, double z,
                                 long input_index, lsm_err *err) {
  const lsm_slice_sink *inner = ctx;
  LSM_TRY(check_stop(err));
  return inner->emit(inner->ctx, phi, width, height, z, input_index, err);
}

/* ---- input: PNG or TIFF slices ---------------------------------------------------------------- */

/* The PNG and TIFF files of SLICE_DIR, in natural order, and how they read. */
typedef struct slice_files {
  char **paths;
  size_t count;
  lsm_image_read_opts read;
} slice_files;

/* A note when the first slice with foreground has black pixels and at
 * least as many that are non-zero but below 50 % as at or above it: not the
 * grey edge of a drawn mask (nor a dark grey background, with no black) but
 * a label map on 0 (labels 1, 2, ... with some at 128 or more), whose dark
 * labels read as background. */
static lsm_status note_dark_labels(const char *path, const lsm_image_read_opts *ro, size_t bright,
                                   lsm_err *err) {
  lsm_image_read_opts any = *ro;
  any.nonzero = 1;
  lsm_mask m = {0, 0, NULL};
  LSM_TRY(lsm_slice_read_mask(path, &any, &m, err));
  const size_t nonzero = lsm_mask_count(&m), all = (size_t)m.width * (size_t)m.height;
  lsm_mask_free(&m);
  if (nonzero < all && nonzero - bright >= bright)
    fprintf(stderr,
            "lsmorph: note: %s: %zu pixels are non-zero but below 50 %% luminance, as many "
            "as or more than the %zu at or above it; they read as background (for a label "
            "map, write a mask of the labels wanted)\n",
            path, nonzero - bright, bright);
  return LSM_OK;
}

/* Foreground rule for a stack: luminance >= 50 % (the default), unless no
 * pixel of any slice reaches 50 % while the stack has both zero and non-zero
 * pixels: label masks stored as 0/1 would otherwise all read as empty.  Then
 * any non-zero pixel is foreground (with --invert: any zero pixel), and a
 * note says so.  (A stack that is uniformly dark but not black, with no zero
 * pixel, stays empty.)  Reads slices only until the first non-empty one, so a
 * normal stack costs one or two reads. */
static lsm_status pick_foreground(char **paths, size_t count, lsm_image_read_opts *ro, int quiet,
                                  const char *dir, lsm_err *err) {
  int none_reach_half = 1, some_zero = 0, some_nonzero = 0;
  for (int pass = 0; pass < 2 && none_reach_half; ++pass) {
    ro->nonzero = pass;
    for (size_t k = 0; k < count && !(some_zero && some_nonzero); ++k) {
      lsm_mask m = {0, 0, NULL};
      LSM_TRY(lsm_slice_read_mask(paths[k], ro, &m, err));
      const size_t inside = lsm_mask_count(&m), all = (size_t)m.width * (size_t)m.height;
      lsm_mask_free(&m);
      /* with --invert the mask holds the pixels below 50 %, or the zero ones */
      const size_t fg = ro->invert ? all - inside : inside;
      if (pass == 0 && fg > 0) { /* some pixel reaches 50 % */
        none_reach_half = 0;
        if (!quiet && !ro->invert) LSM_TRY(note_dark_labels(paths[k], ro, fg, err));
        break;
      }
      if (pass == 1) {
        some_nonzero |= fg > 0;
        some_zero |= fg < all;
      }
    }
  }
  ro->nonzero = none_reach_half && some_zero && some_nonzero;
  if (ro->nonzero && !quiet)
    fprintf(stderr,
            "lsmorph: note: %s: no pixel reaches 50 %% luminance in any slice; reading "
            "non-zero pixels as %s (label masks stored as 0/1)\n",
            dir, ro->invert ? "background" : "foreground");
  return LSM_OK;
}

/* With --input outline, a note when the first non-empty slice looks filled
 * (most of its foreground pixels have all four neighbours in it): outlines
 * are thin contours, and a filled region read as one has no inside. */
static void note_filled_outlines(const slice_files *src, const char *dir) {
  for (size_t k = 0; k < src->count; ++k) {
    lsm_mask m = {0, 0, NULL};
    lsm_err ignored;
    lsm_err_clear(&ignored);
    if (lsm_slice_read_mask(src->paths[k], &src->read, &m, &ignored) != LSM_OK) return;
    size_t fg = 0, interior = 0;
    for (int j = 0; j < m.height; ++j)
      for (int i = 0; i < m.width; ++i) {
        const uint8_t *p = m.pixels + (size_t)j * (size_t)m.width + (size_t)i;
        if (!*p) continue;
        fg++;
        interior += i > 0 && i + 1 < m.width && j > 0 && j + 1 < m.height && p[-1] && p[1] &&
                    p[-m.width] && p[m.width];
      }
    lsm_mask_free(&m);
    if (!fg) continue;
    if (2 * interior > fg)
      fprintf(stderr,
              "lsmorph: note: %s: --input outline, but %s looks filled (%.0f %% of its foreground "
              "pixels are interior): outlines are thin closed contours; filled regions need "
              "--input mask\n",
              dir, lsm_base_name(src->paths[k]), 100.0 * (double)interior / (double)fg);
    return;
  }
}

/* The input slices' heights: --heights FILE, the numbers the file names end
 * with times --spacing (--heights-from-names), or consecutive files --spacing
 * apart.  Shared by rank 0 and the MPI workers, so that all agree.  *z_out is
 * malloc'd with count values. */
static lsm_status input_heights(const lsm_cli *cli, char *const *paths, size_t count,
                                double **z_out, lsm_err *err) {
  double *z = NULL;
  *z_out = NULL;
  if (cli->heights_file) {
    size_t nz = 0;
    LSM_TRY(lsm_heights_read(cli->heights_file, &z, &nz, err));
    if (nz != count) {
      free(z);
      return lsm_fail(err, LSM_ERR_INPUT, cli->heights_file, "%zu heights for %zu slices in %s",
                      nz, count, cli->slice_dir);
    }
    *z_out = z;
    return LSM_OK;
  }
  z = lsm_alloc(count, sizeof *z, err, "heights");
  if (!z) return err->status;
  uint64_t previous = 0;
  for (size_t k = 0; k < count; ++k) {
    if (!cli->heights_from_names) {
      z[k] = (double)k * cli->spacing;
      continue;
    }
    uint64_t n = 0;
    if (!lsm_name_number(paths[k], &n)) {
      free(z);
      return lsm_fail(err, LSM_ERR_INPUT, paths[k],
                      "--heights-from-names: the file name does not end with a number "
                      "(of at most 18 digits)");
    }
    if (k > 0 && n <= previous) {
      free(z);
      return lsm_fail(err, LSM_ERR_INPUT, paths[k],
                      "--heights-from-names: its number %" PRIu64 " does not follow %s's %" PRIu64
                      " (the numbers must increase in the files' natural order)",
                      n, lsm_base_name(paths[k - 1]), previous);
    }
    previous = n;
    z[k] = (double)n * cli->spacing;
  }
  *z_out = z;
  return LSM_OK;
}

/* Without --spacing or --heights, consecutive files are one unit apart.  A
 * note when the file names number the slices with gaps (001.png, 009.png,
 * ..., every 8th of a scan kept under its own names): that is most likely
 * where they lie (--heights-from-names), and the run would then fill nothing
 * between them.  Only when every name ends with a number and the numbers
 * increase. */
static void note_numbered_names(const slice_files *src, const char *dir) {
  uint64_t first = 0, previous = 0, step = 0;
  int even = 1;
  for (size_t k = 0; k < src->count; ++k) {
    uint64_t n;
    if (!lsm_name_number(src->paths[k], &n) || (k > 0 && n <= previous)) return;
    if (k == 0)
      first = n;
    else if (k == 1)
      step = n - previous;
    else if (n - previous != step)
      even = 0;
    previous = n;
  }
  if (even && step == 1) return; /* consecutive: what the default assumes */
  fprintf(stderr, "lsmorph: note: %s: the file names number the slices ", dir);
  if (even)
    fprintf(stderr, "%" PRIu64 ", %" PRIu64 ", ... %" PRIu64 " (steps of %" PRIu64 ")", first,
            first + step, previous, step);
  else
    fprintf(stderr, "%" PRIu64 " to %" PRIu64 " unevenly", first, previous);
  fputs(", but without --spacing, --heights or --heights-from-names consecutive files are 1 "
        "apart; if the numbers are the slices' indices in the scan, add --heights-from-names "
        "(each height is then the number times --spacing, the slice thickness)\n",
        stderr);
}

/* A heights.txt among the slices (as examples/gen_synthetic writes them) is
 * not read unless given with --heights: a note says so. */
static void note_heights_beside(const char *dir) {
  char path[4096];
  struct stat sb;
  const int n = snprintf(path, sizeof path, "%s/heights.txt", dir);
  if (n > 0 && (size_t)n < sizeof path && stat(path, &sb) == 0 && S_ISREG(sb.st_mode))
    fprintf(stderr, "lsmorph: note: %s is not read: the slices are 1 apart; give it with "
                    "--heights to place them by it\n", path);
}

static lsm_status slice_files_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
  slice_files *ps = ctx;
  LSM_TRY(check_stop(err));
  return lsm_slice_read_mask(ps->paths[index], &ps->read, out, err);
}

static const char *slice_files_name(void *ctx, size_t index) {
  slice_files *ps = ctx;
  return ps->paths[index];
}

/* ---- output: volume.<ext>, heights.txt, slices/, surface.ply, previews ------------------ */

typedef struct out_sink {
  char dir[4096];
  int write_slices;
  lsm_volume_writer *volume; /* every --format */
  lsm_mesh *mesh;            /* --mesh */
  lsm_preview *preview;      /* unless --no-preview */
  FILE *heights;
  size_t count;
  double z_first, z_last;
  double step_min, step_max; /* between consecutive output slices */
  uint8_t *mask;
  uint64_t max_voxels; /* --max-voxels: checked ahead, but with --per-iteration only here */
  const char *input;   /* the slice folder, named in that error */
} out_sink;

/* The files written to OUT_DIR, in the order they are listed. */
static size_t output_files(const lsm_cli *cli, const char **names, size_t cap) {
  const char *vol[8];
  size_t nv = lsm_volume_file_names(cli->formats, vol, 8);
  size_t n = 0;
#define ADD(name)                  \
  do {                             \
    if (n < cap) names[n] = name;  \
    n++;                           \
  } while (0)
  for (size_t k = 0; k < nv && k < 8; ++k) ADD(vol[k]);
  ADD("heights.txt");
  if (cli->write_slices) ADD("slices/");
  if (cli->mesh) ADD("surface.ply");
  if (cli->preview) {
    ADD("preview.png");
    ADD("preview3d.png");
  }
  ADD("run.json");
#undef ADD
  return n;
}

/* The mean step between output heights (0 for fewer than two slices). */
static double sink_mean_step(const out_sink *s) {
  return s->count > 1 ? (s->z_last - s->z_first) / (double)(s->count - 1) : 0.0;
}

/* Whether the output heights are evenly spaced (always so but with
 * --per-iteration, whose pairs each have their own iteration count). */
static int sink_evenly_spaced(const out_sink *s) {
  return s->count <= 2 || s->step_max - s->step_min <= 1e-6 * fabs(s->step_max);
}

static lsm_status sink_emit(void *ctx, const float *phi, int width, int height, double z,
                            long input_index, lsm_err *err) {
  out_sink *s = ctx;
  /* the slice count of --per-iteration is not known ahead: its volume is held
   * to --max-voxels as it grows (any other run was checked before it began) */
  if ((double)(s->count + 1) * (double)width * (double)height > (double)s->max_voxels)
    return lsm_fail(err, LSM_ERR_LIMIT, s->input,
                    "%zu output slices of %dx%d written; one more would pass --max-voxels %llu "
                    "(with --per-iteration every solver step is a slice: raise --tol, lower "
                    "--max-iter or raise --max-voxels)",
                    s->count, width, height, (unsigned long long)s->max_voxels);
  /* the mesh and the previews need increasing heights: a repeated one adds nothing */
  const int higher = s->count == 0 || z > s->z_last;
  LSM_TRY(lsm_volume_writer_write_slice(s->volume, phi, z, err));
  if (s->mesh && higher) LSM_TRY(lsm_mesh_add_slice(s->mesh, phi, z, err));
  if (s->preview && higher) LSM_TRY(lsm_preview_add_slice(s->preview, phi, z, input_index, err));
  char z_text[40]; /* the shortest form that reads back as z: 0.8, not 0.80000000000000004 */
  lsm_shortest_number(z_text, sizeof z_text, z);
  if (fprintf(s->heights, "%s\n", z_text) < 0)
    return lsm_fail(err, LSM_ERR_IO, NULL, "%s/heights.txt: write failed: %s", s->dir,
                    strerror(errno));
  if (s->count == 0) {
    s->z_first = z;
  } else {
    const double step = z - s->z_last;
    if (s->count == 1 || step < s->step_min) s->step_min = step;
    if (s->count == 1 || step > s->step_max) s->step_max = step;
  }
  s->z_last = z;
  s->count++;
  if (s->write_slices) {
    const size_t n = (size_t)width * (size_t)height;
    for (size_t k = 0; k < n; ++k) s->mask[k] = phi[k] <= 0.0f ? 255 : 0;
    char path[4200];
    snprintf(path, sizeof path, "%s/slices/%05zu.png", s->dir, s->count);
    LSM_TRY(lsm_png_write_gray8(path, s->mask, width, height, err));
  }
  return LSM_OK;
}

/* ---- progress ---------------------------------------------------------------------------- */

typedef struct progress_state {
  int tty;
  int last_percent;
  size_t last_pair;
  double start;
} progress_state;

static void progress_update(void *ctx, size_t done, size_t total, size_t pair, size_t pairs) {
  progress_state *p = ctx;
  (void)pair;
  if (total == 0) {
    if (p->tty) fprintf(stderr, "\rlsmorph: %zu slices written", done);
    return;
  }
  int percent = (int)(100.0 * (double)done / (double)total);
  double elapsed = wall_seconds() - p->start;
  if (p->tty) {
    char bar[41];
    int fill = percent * 40 / 100;
    for (int k = 0; k < 40; ++k) bar[k] = k < fill ? '#' : '.';
    bar[40] = '\0';
    fprintf(stderr, "\rlsmorph: [%s] %3d%%  slice %zu/%zu  %.1f s", bar, percent, done, total,
            elapsed);
    if (done == total) fputc('\n', stderr);
  } else if (percent / 10 != p->last_percent / 10 || done == total) {
    fprintf(stderr, "lsmorph: %3d%% (%zu/%zu slices, %zu gaps, %.1f s)\n", percent, done, total,
            pairs, elapsed);
  }
  p->last_percent = percent;
}

/* ---- run.json -------------------------------------------------------------------------------- */

static lsm_status write_run_json(const char *path, int argc, char **argv, const lsm_cli *cli,
                                 const slice_files *src, const double *z, int width, int height,
                                 const out_sink *sink, const lsm_pair_stats *stats, int threads,
                                 const lsm_backend *backend, double wall, lsm_err *err) {
  FILE *f = fopen(path, "w");
  if (!f) return lsm_fail(err, LSM_ERR_IO, path, "cannot create: %s", strerror(errno));
  const lsm_stack_opts *o = &cli->stack;
  fprintf(f, "{\n  \"lsmorph_version\": \"%s\",\n  \"command\": [", LSM_VERSION);
  for (int k = 0; k < argc; ++k) {
    if (k) fputs(", ", f);
    lsm_json_string(f, argv[k]);
  }
  fputs("],\n  \"backend\": {\"name\": ", f);
  lsm_json_string(f, backend->ops->name);
  fputs(", \"device\": ", f);
  lsm_json_string(f, backend->device);
  fputs(", \"build_seconds\": ", f);
  lsm_json_number(f, backend->build_seconds);
  fprintf(f, ", \"kernel_cache_hit\": %s},\n", backend->kernel_cache_hit ? "true" : "false");
  fputs("  \"options\": {\"method\": ", f);
  lsm_json_string(f, lsm_method_name(o->method));
  fputs(", \"scheme\": ", f);
  lsm_json_string(f, lsm_scheme_name(o->morph.scheme));
  fputs(", \"time\": ", f);
  lsm_json_string(f, lsm_time_name(o->morph.time));
  fputs(", \"input\": ", f);
  lsm_json_string(f, lsm_input_name(o->input));
  fputs(", \"align\": ", f);
  lsm_json_string(f, lsm_align_name(o->align));
  fputs(", \"interp\": ", f);
  lsm_json_string(f, lsm_interp_name(o->interp));
  fputs(", \"ends\": ", f);
  lsm_json_string(f, lsm_end_rule_name(o->ends));
  fputs(", \"cfl\": ", f);
  lsm_json_number(f, o->morph.cfl);
  fprintf(f, ", \"reinit_every\": %d, \"reinit_iters\": %d, \"tol\": ", o->morph.reinit_every,
          o->morph.reinit_iters);
  lsm_json_number(f, o->tol);
  fprintf(f, ", \"max_iter\": %d, \"per_iteration\": %s, \"pixel_size\": ", o->max_iter,
          o->per_iteration ? "true" : "false");
  lsm_json_number(f, o->pixel_dx);
  fputs(", \"pixel_size_y\": ", f);
  lsm_json_number(f, o->pixel_dy);
  fputs(", \"dz\": ", f);
  lsm_json_number(f, lsm_stack_output_dz(o));
  fprintf(f, ", \"invert\": %s, \"heights_from_names\": %s, \"threads\": %d, \"values\": ",
          cli->invert ? "true" : "false", cli->heights_from_names ? "true" : "false", threads);
  lsm_json_string(f, lsm_values_name((lsm_values)cli->values));
  fputs(", \"formats\": [", f);
  int listed = 0;
  for (unsigned bit = 1; bit <= LSM_FORMAT_ALL; bit <<= 1) {
    if (!(cli->formats & bit)) continue;
    if (listed++) fputs(", ", f);
    lsm_json_string(f, lsm_format_name(bit));
  }
  const lsm_pls_opts *pls = &o->morph.pls;
  fprintf(f, "], \"nrrd_encoding\": \"%s\", \"mesh\": %s, \"preview\": %s, \"particles_per_cell\": %d, \"pls_reseed\": %d, "
          "\"pls_radius_adjust\": %s, \"seed\": %" PRIu64 "},\n",
          cli->nrrd_gzip ? "gzip" : "raw", cli->mesh ? "true" : "false", cli->preview ? "true" : "false", pls->particles_per_cell,
          pls->reseed_every, pls->radius_adjust ? "true" : "false", pls->seed);
  fputs("  \"input\": {\"folder\": ", f);
  lsm_json_string(f, cli->slice_dir);
  fprintf(f, ", \"slices\": %zu, \"width\": %d, \"height\": %d, \"files\": [", src->count, width,
          height);
  for (size_t k = 0; k < src->count; ++k) {
    if (k) fputs(", ", f);
    lsm_json_string(f, lsm_base_name(src->paths[k]));
  }
  fputs("], \"heights\": [", f);
  for (size_t k = 0; k < src->count; ++k) {
    if (k) fputs(", ", f);
    lsm_json_number(f, z[k]);
  }
  fprintf(f, "]},\n  \"output\": {\"slices\": %zu, \"first_height\": ", sink->count);
  lsm_json_number(f, sink->z_first);
  fputs(", \"last_height\": ", f);
  lsm_json_number(f, sink->z_last);
  fprintf(f, ", \"evenly_spaced\": %s",
          sink_evenly_spaced(sink) ? "true" : "false");
  fputs(", \"files\": [", f);
  const char *files[16];
  size_t nfiles = output_files(cli, files, 16);
  for (size_t k = 0; k < nfiles && k < 16; ++k) {
    if (k) fputs(", ", f);
    lsm_json_string(f, files[k]);
  }
  fputs("]},\n  \"pairs\": [\n", f);
  long long iterations = 0, updates = 0;
  double seconds = 0.0;
  for (size_t k = 0; k + 1 < src->count; ++k) {
    const lsm_pair_stats *p = &stats[k];
    fputs("    {\"source\": ", f);
    lsm_json_string(f, lsm_base_name(src->paths[p->source]));
    fputs(", \"target\": ", f);
    lsm_json_string(f, lsm_base_name(src->paths[p->target]));
    fprintf(f, ", \"iterations\": %d, \"dt\": ", p->iterations);
    lsm_json_number(f, p->dt);
    fputs(", \"cp\": ", f);
    lsm_json_number(f, p->cp);
    fputs(", \"seconds\": ", f);
    lsm_json_number(f, p->seconds);
    fprintf(f, ", \"cells\": %lld, \"t_final\": ", p->cells);
    lsm_json_number(f, p->t_final);
    fprintf(f, ", \"slices\": %zu, \"hit_max_iter\": %s, \"rank\": %d", p->slices,
            p->hit_max_iter ? "true" : "false", p->rank);
    fprintf(f, ", \"aligned\": %s, \"moving_parts\": %d", p->aligned ? "true" : "false",
            p->moving_parts);
    if (o->method == LSM_METHOD_PLS) {
      fprintf(f, ", \"particles\": {\"seeded\": %lld, \"discarded\": %lld, \"escaped_per_step\": ",
              p->pls_seeded, p->pls_discarded);
      lsm_json_number(f, p->pls_steps ? (double)p->pls_escaped / (double)p->pls_steps : 0.0);
      fprintf(f, ", \"escaped\": %lld, \"corrected\": %lld, \"steps\": %lld}", p->pls_escaped,
              p->pls_corrected, p->pls_steps);
    }
    fprintf(f, "}%s\n", k + 2 < src->count ? "," : "");
    iterations += p->iterations;
    updates += (long long)p->iterations * p->cells * lsm_time_stages(o->morph.time);
    seconds += p->seconds;
  }
  fprintf(f, "  ],\n  \"totals\": {\"pairs\": %zu, \"iterations\": %lld, \"seconds\": ",
          src->count - 1, iterations);
  lsm_json_number(f, seconds);
  fputs(", \"wall_seconds\": ", f);
  lsm_json_number(f, wall);
  fprintf(f, ", \"cell_updates\": %lld, \"cells_per_second\": ", updates);
  lsm_json_number(f, seconds > 0 ? (double)updates / seconds : NAN);
  /* per process (MPI rank): how many gaps it ran and their solver seconds */
  int ranks = 1;
  for (size_t k = 0; k + 1 < src->count; ++k)
    if (stats[k].rank + 1 > ranks) ranks = stats[k].rank + 1;
  fputs("},\n  \"ranks\": [", f);
  for (int q = 0; q < ranks; ++q) {
    size_t gaps = 0;
    double rank_seconds = 0.0;
    for (size_t k = 0; k + 1 < src->count; ++k)
      if (stats[k].rank == q) {
        gaps++;
        rank_seconds += stats[k].seconds;
      }
    fprintf(f, "%s{\"rank\": %d, \"gaps\": %zu, \"seconds\": ", q ? ", " : "", q, gaps);
    lsm_json_number(f, rank_seconds);
    fputc('}', f);
  }
  fputs("]\n}\n", f);
  const int bad = ferror(f), closed = fclose(f);
  if (bad || closed != 0)
    return lsm_fail(err, LSM_ERR_IO, path, "write failed: %s",
                    closed != 0 ? strerror(errno) : "stream error");
  return LSM_OK;
}

/* ---- reconstruct ----------------------------------------------------------------------------- */

/* Makes a fresh temporary folder next to out_dir: "<out_dir>.tmp-XXXXXX". */
static lsm_status make_temp_dir(const char *out_dir, char *tmp, size_t size, lsm_err *err) {
  size_t len = strlen(out_dir);
  while (len > 1 && out_dir[len - 1] == '/') --len;
  if (len + 12 >= size) return lsm_fail(err, LSM_ERR_INPUT, out_dir, "path is too long");
  snprintf(tmp, size, "%.*s.tmp-XXXXXX", (int)len, out_dir);
  if (!mkdtemp(tmp))
    return lsm_fail(err, LSM_ERR_IO, out_dir, "cannot create a folder next to it: %s",
                    strerror(errno));
  /* mkdtemp makes it private (0700); the published result gets the usual
   * permissions of a new folder (0777 less the umask). */
  const mode_t mask = umask(0);
  umask(mask);
  if (chmod(tmp, 0777 & ~mask) != 0)
    return lsm_fail(err, LSM_ERR_IO, tmp, "cannot set permissions: %s", strerror(errno));
  return LSM_OK;
}

/* Moves the finished tmp folder to out_dir, replacing an earlier result.
 * Where the system allows, the two are exchanged atomically (renameat2
 * RENAME_EXCHANGE): out_dir is at every moment either the complete earlier
 * result or the complete new one, and tmp then holds the earlier one, which is
 * removed.  Elsewhere the earlier result is first renamed aside (out_dir is
 * briefly absent) and put back if the new one cannot be moved in. */
static lsm_status publish(const char *tmp, const char *out_dir, lsm_err *err) {
  struct stat st;
  if (stat(out_dir, &st) == 0) {
    if (!S_ISDIR(st.st_mode)) return lsm_fail(err, LSM_ERR_INPUT, out_dir, "exists and is not a folder");
    if (lsm_rename_exchange(tmp, out_dir) == 0) {
      remove_tree(tmp);
      return LSM_OK;
    }
    if (errno != ENOSYS && errno != EINVAL
#ifdef ENOTSUP
        && errno != ENOTSUP
#endif
    )
      return lsm_fail(err, LSM_ERR_IO, out_dir, "cannot replace: %s", strerror(errno));
    char old[4200];
    snprintf(old, sizeof old, "%s.old-XXXXXX", tmp);
    if (!mkdtemp(old)) return lsm_fail(err, LSM_ERR_IO, out_dir, "cannot replace: %s", strerror(errno));
    char old_out[4300];
    snprintf(old_out, sizeof old_out, "%s/previous", old);
    if (rename(out_dir, old_out) != 0) {
      int e = errno;
      remove_tree(old);
      return lsm_fail(err, LSM_ERR_IO, out_dir, "cannot replace: %s", strerror(e));
    }
    if (rename(tmp, out_dir) != 0) {
      int e = errno;
      if (rename(old_out, out_dir) != 0) /* never delete the earlier result: say where it is */
        return lsm_fail(err, LSM_ERR_IO, out_dir,
                        "cannot move the result into place (%s); the earlier result is in %s",
                        strerror(e), old_out);
      remove_tree(old);
      return lsm_fail(err, LSM_ERR_IO, out_dir, "cannot move the result into place: %s", strerror(e));
    }
    remove_tree(old);
    return LSM_OK;
  }
  if (rename(tmp, out_dir) != 0)
    return lsm_fail(err, LSM_ERR_IO, out_dir, "cannot move the result into place: %s", strerror(errno));
  return LSM_OK;
}

/* Longest slice side accepted: keeps every canvas size of the stack driver
 * (the image plus alignment margins, at most three times a side) within an int. */
#define LSM_SIDE_MAX (1 << 24)

/* Whether the path `inner` (resolved) is `outer_real` or lies inside it. */
static int path_within(const char *inner, const char *outer_real) {
  char *inner_real = realpath(inner, NULL);
  if (!inner_real || !outer_real) {
    free(inner_real);
    return 0;
  }
  const size_t n = strlen(outer_real);
  const int within = strncmp(inner_real, outer_real, n) == 0 &&
                     (inner_real[n] == '/' || inner_real[n] == '\0' ||
                      (n == 1 && outer_real[0] == '/'));
  free(inner_real);
  return within;
}

/* 1 when the folder `dir` is not empty and has no run.json: not an earlier
 * result, so not lsmorph's to replace. */
static int foreign_folder(const char *dir) {
  char path[4200];
  snprintf(path, sizeof path, "%s/run.json", dir);
  struct stat sb;
  if (stat(path, &sb) == 0 && S_ISREG(sb.st_mode)) return 0;
  DIR *d = opendir(dir);
  if (!d) return 0; /* unreadable: publishing will say what is wrong */
  int foreign = 0;
  for (struct dirent *e; !foreign && (e = readdir(d)) != NULL;)
    foreign = strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
  closedir(d);
  return foreign;
}

/* Checks made before anything is allocated for the run or written:
 * the output path, the heights, every slice header (PNG IHDR, TIFF size:
 * all slices the same size), and the resource limits: pixels per slice
 * (--max-pixels), the longest side, the working canvas of an aligned gap and
 * the voxels of the output volume (--max-voxels).  All sizes are computed in
 * 64-bit or double arithmetic, so nothing can wrap around.  On success
 * *width x *height is the slice size. */
static lsm_status check_inputs(const lsm_cli *cli, const slice_files *src, const double *z,
                               int *width, int *height, lsm_err *err) {
  struct stat sb, in;
  if (stat(cli->out_dir, &sb) == 0) {
    if (!S_ISDIR(sb.st_mode))
      return lsm_fail(err, LSM_ERR_INPUT, cli->out_dir, "exists and is not a folder");
    /* OUT is replaced as a whole: it must not be, or contain, the input folder
     * or the heights file, and a folder that is not an earlier result (no
     * run.json) but holds something is left alone. */
    char *out_real = realpath(cli->out_dir, NULL);
    int clash = stat(cli->slice_dir, &in) == 0 && in.st_dev == sb.st_dev && in.st_ino == sb.st_ino;
    clash = clash || path_within(cli->slice_dir, out_real);
    const int heights_inside = cli->heights_file && path_within(cli->heights_file, out_real);
    free(out_real);
    if (clash)
      return lsm_fail(err, LSM_ERR_INPUT, cli->out_dir,
                      "is or contains the input folder %s, which replacing it would delete",
                      cli->slice_dir);
    if (heights_inside)
      return lsm_fail(err, LSM_ERR_INPUT, cli->out_dir,
                      "contains the heights file %s, which replacing it would delete",
                      cli->heights_file);
    if (foreign_folder(cli->out_dir))
      return lsm_fail(err, LSM_ERR_INPUT, cli->out_dir,
                      "exists, is not empty and is not an earlier lsmorph result (no run.json): "
                      "lsmorph replaces OUT_DIR as a whole; remove it or name a new folder");
  }
  for (size_t k = 0; k < src->count; ++k) {
    if (!isfinite(z[k]))
      return lsm_fail(err, LSM_ERR_INPUT, cli->heights_file ? cli->heights_file : cli->slice_dir,
                      "height of slice %zu is not finite (--spacing %g)", k + 1, cli->spacing);
    if (k > 0 && !(z[k] > z[k - 1]))
      return lsm_fail(err, LSM_ERR_INPUT, cli->heights_file ? cli->heights_file : cli->slice_dir,
                      "heights of slices %zu and %zu are not increasing", k, k + 1);
    if (k > 0 && !lsm_length_in_range(z[k] - z[k - 1]))
      return lsm_fail(err, LSM_ERR_INPUT, cli->heights_file ? cli->heights_file : cli->slice_dir,
                      "slices %zu and %zu are %g apart, outside %g to %g (lengths are held as "
                      "floats; choose a unit that brings it into range)",
                      k, k + 1, z[k] - z[k - 1], LSM_LENGTH_MIN, LSM_LENGTH_MAX);
  }
  /* output heights are doubles: steps too small for them repeat heights */
  const double z_mag = fmax(fabs(z[0]), fabs(z[src->count - 1]));
  const char *heights_name = cli->heights_file ? cli->heights_file : cli->slice_dir;
  if (cli->stack.per_iteration) {
    for (size_t k = 0; k + 1 < src->count; ++k) {
      const double step = (z[k + 1] - z[k]) / ((double)cli->stack.max_iter + 1.0);
      if (!lsm_output_step_resolved(step, z_mag))
        return lsm_fail(err, LSM_ERR_INPUT, heights_name,
                        "slices %zu and %zu are %g apart at heights near %g: --per-iteration's "
                        "up to --max-iter %d steps between them would repeat heights (double "
                        "precision); subtract an offset from the heights or lower --max-iter",
                        k + 1, k + 2, z[k + 1] - z[k], z_mag, cli->stack.max_iter);
    }
  } else {
    const double dz = lsm_stack_output_dz(&cli->stack);
    if (!lsm_output_step_resolved(dz, z_mag))
      return lsm_fail(err, LSM_ERR_INPUT, heights_name,
                      "output steps of %g (%s) at heights near %g would repeat heights (double "
                      "precision); subtract an offset from the heights or raise --dz",
                      dz, cli->stack.dz > 0 ? "--dz" : "the pixel size", z_mag);
  }
  int w = 0, h = 0;
  for (size_t k = 0; k < src->count; ++k) {
    LSM_TRY(check_stop(err));
    int wk = 0, hk = 0;
    LSM_TRY(lsm_slice_read_header(src->paths[k], cli->max_pixels, &wk, &hk, err));
    if (k == 0) {
      w = wk;
      h = hk;
      const uint64_t pixels = (uint64_t)w * (uint64_t)h; /* both < 2^31: no overflow */
      if (pixels > cli->max_pixels)
        return lsm_fail(err, LSM_ERR_LIMIT, src->paths[0],
                        "%dx%d = %llu pixels is more than --max-pixels %llu", w, h,
                        (unsigned long long)pixels, (unsigned long long)cli->max_pixels);
      if (w > LSM_SIDE_MAX || h > LSM_SIDE_MAX)
        return lsm_fail(err, LSM_ERR_LIMIT, src->paths[0],
                        "%dx%d: a side longer than %d pixels is not supported", w, h,
                        LSM_SIDE_MAX);
    } else if (wk != w || hk != h) {
      return lsm_fail(err, LSM_ERR_INPUT, src->paths[k], "slice is %dx%d but %s is %dx%d", wk,
                      hk, lsm_base_name(src->paths[0]), w, h);
    }
  }
  /* An aligned gap pads each axis by the largest centroid shift along it (at
   * most half the side) plus 2 cells. */
  const uint64_t canvas = cli->stack.align == LSM_ALIGN_NONE
                              ? (uint64_t)w * (uint64_t)h
                              : ((uint64_t)w + 2 * ((uint64_t)w / 2 + 2)) *
                                    ((uint64_t)h + 2 * ((uint64_t)h / 2 + 2));
  if (canvas > (uint64_t)LSM_GRID_CELLS_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, src->paths[0],
                    "%dx%d slices need a working grid of up to %llu cells%s, more than the %lld "
                    "supported", w, h, (unsigned long long)canvas,
                    cli->stack.align != LSM_ALIGN_NONE &&
                            (uint64_t)w * (uint64_t)h <= (uint64_t)LSM_GRID_CELLS_MAX
                        ? " (use --align none)"
                        : "",
                    (long long)LSM_GRID_CELLS_MAX);
  if (cli->stack.align != LSM_ALIGN_NONE) {
    if (canvas / 4 > cli->max_pixels)
      return lsm_fail(err, LSM_ERR_LIMIT, src->paths[0],
                      "%dx%d slices need a working canvas of up to %llu cells with --align %s, "
                      "more than 4 x --max-pixels %llu (use --align none or raise --max-pixels)",
                      w, h, (unsigned long long)canvas, lsm_align_name(cli->stack.align),
                      (unsigned long long)cli->max_pixels);
  }
  const char *nifti = (cli->formats & LSM_FORMAT_NII) ? "volume.nii" : "volume.nii.gz";
  if ((cli->formats & LSM_FORMATS_NIFTI) && (w > LSM_NIFTI_DIM_MAX || h > LSM_NIFTI_DIM_MAX))
    return lsm_fail(err, LSM_ERR_LIMIT, src->paths[0],
                    "%dx%d slices do not fit %s: NIfTI-1 holds at most %d samples along "
                    "an axis (choose another --format)", w, h, nifti, LSM_NIFTI_DIM_MAX);
  if (!cli->stack.per_iteration) {
    const double dz = lsm_stack_output_dz(&cli->stack);
    const size_t count = lsm_stack_output_count(z, src->count, dz);
    const double slices = (double)count;
    if ((cli->formats & LSM_FORMATS_NIFTI) && count > LSM_NIFTI_DIM_MAX)
      return lsm_fail(err, LSM_ERR_LIMIT, cli->heights_file ? cli->heights_file : cli->slice_dir,
                      "the output would have %s%zu slices, more than the %d %s holds "
                      "(NIfTI-1 sizes are 16-bit: raise --dz or choose another --format)",
                      count >= LSM_OUTPUT_COUNT_MAX ? "at least " : "", count, LSM_NIFTI_DIM_MAX,
                      nifti);
    const double voxels = slices * (double)w * (double)h;
    if (!(voxels <= (double)cli->max_voxels))
      return lsm_fail(err, LSM_ERR_LIMIT, cli->heights_file ? cli->heights_file : cli->slice_dir,
                      "the output would have %s%.4g slices of %dx%d = %.4g voxels, more than "
                      "--max-voxels %llu (raise --dz or --max-voxels)",
                      count >= LSM_OUTPUT_COUNT_MAX ? "at least " : "", slices, w, h, voxels,
                      (unsigned long long)cli->max_voxels);
  }
  *width = w;
  *height = h;
  return LSM_OK;
}

/* A numerical failure names the iteration; add the gap (the pair of input
 * files) it happened in: the last pair whose statistics the stack started. */
static void name_failed_pair(lsm_err *err, const slice_files *src, const lsm_pair_stats *stats) {
  if (!err || !stats) return;
  size_t pair = SIZE_MAX;
  for (size_t k = 0; k + 1 < src->count; ++k)
    if (stats[k].target == k + 1) pair = k;
  if (pair == SIZE_MAX) return;
  char what[LSM_ERR_MSG_MAX];
  memcpy(what, err->msg, sizeof what);
  what[sizeof what - 1] = '\0';
  int n = snprintf(err->msg, sizeof err->msg, "%s -> %s (gap %zu of %zu): ", src->paths[pair],
                   lsm_base_name(src->paths[pair + 1]), pair + 1, src->count - 1);
  if (n > 0 && (size_t)n < sizeof err->msg)
    snprintf(err->msg + n, sizeof err->msg - (size_t)n, "%s; try a smaller --cfl", what);
}

/* Messages about files of the removed temporary folder name them under OUT_DIR
 * ("out/volume.nrrd: write failed: ..."), where the user will look for them. */
static void name_out_not_tmp(lsm_err *err, const char *tmp, const char *out_dir) {
  if (!err || !*tmp) return;
  const char *at = strstr(err->msg, tmp);
  if (!at) return;
  char msg[LSM_ERR_MSG_MAX];
  const size_t before = (size_t)(at - err->msg);
  size_t len = strlen(out_dir); /* as make_temp_dir: without trailing slashes */
  while (len > 1 && out_dir[len - 1] == '/') --len;
  snprintf(msg, sizeof msg, "%.*s%.*s%s", (int)before, err->msg, (int)len, out_dir,
           at + strlen(tmp));
  memcpy(err->msg, msg, sizeof msg);
}

/* A worker's transport: counts what it has sent to rank 0. */
typedef struct counted_transport {
  const lsm_gap_transport *inner;
  size_t sent;
} counted_transport;

static lsm_status counted_send(void *ctx, size_t gap, const lsm_gap_result *result, lsm_err *err) {
  counted_transport *c = ctx;
  c->sent++;
  return c->inner->send(c->inner->ctx, gap, result, err);
}

/* An MPI rank other than 0: computes its share of the gaps (gap i is rank
 * i % size's) and sends them to rank 0, which reads the same input, checks it,
 * and writes everything.  A worker that owns no gap has nothing to do.  One
 * that fails before it has sent anything (its own view of the input: a
 * --heights pipe that only rank 0 reads) sends the failure as its first gap,
 * which rank 0 waits for: rank 0 reports it and ends the run, instead of
 * waiting for ever. */
static lsm_status reconstruct_worker(lsm_cli *cli, const lsm_gap_transport *transport,
                                     lsm_err *err) {
  slice_files src = {NULL, 0, {cli->invert, cli->max_pixels, 0}};
  double *z = NULL;
  lsm_pair_stats *stats = NULL;
  lsm_backend *backend = NULL;
  int width = 0, height = 0;
  counted_transport counted = {transport, 0};
  lsm_gap_transport mine = *transport;
  mine.ctx = &counted;
  mine.send = counted_send;
  lsm_status st = lsm_dir_list_slices(cli->slice_dir, &src.paths, &src.count, NULL, err);
  if (st == LSM_OK && src.count < 2)
    st = lsm_fail(err, LSM_ERR_INPUT, cli->slice_dir, "need at least two PNG or TIFF slices");
  if (st == LSM_OK && (size_t)transport->rank >= src.count - 1) { /* no gap of its own */
    lsm_path_list_free(src.paths, src.count);
    return LSM_OK;
  }
  if (st == LSM_OK) st = input_heights(cli, src.paths, src.count, &z, err);
  if (st == LSM_OK) st = lsm_slice_read_header(src.paths[0], 0, &width, &height, err);
  if (st == LSM_OK) st = pick_foreground(src.paths, src.count, &src.read, 1, cli->slice_dir, err);
  const int threads = setup_run(cli);
  if (st == LSM_OK) st = lsm_backend_open(cli->backend, cli->device, threads, &backend, err);
  if (st == LSM_OK) {
    cli->stack.morph.backend = backend;
    cli->stack.transport = &mine;
    stats = calloc(src.count, sizeof *stats);
    if (!stats) st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the run");
  }
  if (st == LSM_OK && !stop_signal) install_stop_handlers(1);
  if (st == LSM_OK) {
    lsm_slice_source source = {&src, src.count, z, slice_files_load, slice_files_name};
    st = lsm_stack_run(&source, width, height, &cli->stack, NULL, stats, NULL, err);
  }
  if (st != LSM_OK && counted.sent == 0) {
    lsm_gap_result failed;
    memset(&failed, 0, sizeof failed);
    failed.status = st;
    failed.stats.rank = transport->rank;
    snprintf(failed.msg, sizeof failed.msg, "%s", err->msg[0] ? err->msg : lsm_status_name(st));
    lsm_err send_err;
    lsm_err_clear(&send_err);
    (void)transport->send(transport->ctx, (size_t)transport->rank, &failed, &send_err);
  }
  lsm_backend_close(&backend);
  free(stats);
  free(z);
  lsm_path_list_free(src.paths, src.count);
  return st;
}

static lsm_status reconstruct(int argc, char **argv, lsm_cli *cli, const lsm_mpi *mpi,
                              lsm_err *err) {
  if (lsm_mpi_rank(mpi) != 0) return reconstruct_worker(cli, lsm_mpi_transport(mpi), err);
  cli->stack.transport = lsm_mpi_transport(mpi);
  const double t_start = wall_seconds();
  slice_files src = {NULL, 0, {cli->invert, cli->max_pixels, 0}};
  double *z = NULL;
  lsm_pair_stats *stats = NULL;
  out_sink sink;
  memset(&sink, 0, sizeof sink);
  char tmp[4096] = "";
  size_t others = 0;
  lsm_status st = lsm_dir_list_slices(cli->slice_dir, &src.paths, &src.count, &others, err);
  if (st == LSM_OK && others && !cli->quiet)
    fprintf(stderr, "lsmorph: note: %s: %zu image file%s in another format than PNG or TIFF "
                    "(.jpg, .bmp, ...) left out: slices are read from PNG and TIFF files only\n",
            cli->slice_dir, others, others == 1 ? "" : "s");
  if (st == LSM_OK && src.count == 0)
    st = lsm_fail(err, LSM_ERR_INPUT, cli->slice_dir, "no PNG or TIFF files in this folder");
  if (st == LSM_OK && src.count == 1)
    st = lsm_fail(err, LSM_ERR_INPUT, cli->slice_dir, "only one slice: need at least two to fill a gap");
  if (st == LSM_OK) st = input_heights(cli, src.paths, src.count, &z, err);
  int width = 0, height = 0;
  if (st == LSM_OK) st = check_inputs(cli, &src, z, &width, &height, err);
  if (st == LSM_OK)
    st = pick_foreground(src.paths, src.count, &src.read, cli->quiet, cli->slice_dir, err);
  if (st == LSM_OK && !cli->quiet) {
    if (cli->stack.input == LSM_INPUT_OUTLINE) note_filled_outlines(&src, cli->slice_dir);
    if (!cli->heights_file && !cli->spacing_given && !cli->heights_from_names) {
      note_numbered_names(&src, cli->slice_dir);
      note_heights_beside(cli->slice_dir);
    }
    if (cli->stack.per_iteration && cli->stack.dz > 0)
      fprintf(stderr, "lsmorph: note: --dz has no effect with --per-iteration (every solver "
                      "iteration is a slice)\n");
    if (cli->stack.per_iteration &&
        ((cli->interp_given && cli->stack.interp != LSM_INTERP_LINEAR) ||
         (cli->ends_given && cli->stack.ends != LSM_ENDS_HALFWAY)))
      fprintf(stderr, "lsmorph: note: --per-iteration takes the linear profile and ends an "
                      "object at mid-gap: --interp cubic and --ends tip|auto have no effect\n");
    else if (cli->stack.interp == LSM_INTERP_LINEAR && cli->ends_given &&
             cli->stack.ends != LSM_ENDS_HALFWAY)
      fprintf(stderr, "lsmorph: note: --interp linear ends an object at mid-gap: --ends "
                      "tip|auto have no effect (they shape the cubic profile's ends)\n");
    if (cli->stack.method == LSM_METHOD_BLEND && cli->solver_option)
      fprintf(stderr, "lsmorph: note: %s has no effect with --method blend, which solves no "
                      "PDE (no solver option does: --scheme, --time, --cfl, --max-iter, "
                      "--reinit-every, --reinit-iters)\n", cli->solver_option);
    if (cli->stack.method != LSM_METHOD_PLS && cli->pls_option)
      fprintf(stderr, "lsmorph: note: %s has no effect without --method pls (it sets up the "
                      "particles)\n", cli->pls_option);
    if (!cli->stack.per_iteration && cli->tol_given)
      fprintf(stderr, "lsmorph: note: --tol has no effect without --per-iteration (it stops "
                      "each pair of that mode)\n");
    if (cli->backend == LSM_BACKEND_C && cli->device_given)
      fprintf(stderr, "lsmorph: note: --device has no effect with --backend c\n");
    if (cli->nrrd_encoding_given && !(cli->formats & LSM_FORMAT_NRRD))
      fprintf(stderr, "lsmorph: note: --nrrd-encoding has no effect without nrrd in --format\n");
    if (cli->stack.method != LSM_METHOD_BLEND && cli->stack.morph.cfl > 1.0)
      fprintf(stderr, "lsmorph: note: --cfl %g is above 1, where the schemes are no longer "
                      "monotone: thin parts may oscillate or blow up (a blow-up stops the run "
                      "with an error)\n", cli->stack.morph.cfl);
  }
  lsm_stack_opts_resolve(&cli->stack); /* run.json records what the run uses */
  const int threads = setup_run(cli);
  lsm_backend *backend = NULL;
  if (st == LSM_OK) st = lsm_backend_open(cli->backend, cli->device, threads, &backend, err);
  if (st == LSM_OK) {
    cli->stack.morph.backend = backend;
    if (!cli->quiet && cli->backend != LSM_BACKEND_C)
      fprintf(stderr, "lsmorph: backend %s: %s\n", backend->ops->name, backend->device);
    /* auto fell back to C: say why, also when a --device given does not exist */
    if (!cli->quiet && backend->fallback[0])
      fprintf(stderr, "lsmorph: note: --backend auto runs on C: %s\n", backend->fallback);
  }
  if (st == LSM_OK) {
    stats = calloc(src.count, sizeof *stats);
    sink.mask = malloc((size_t)width * (size_t)height);
    if (!stats || !sink.mask) st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the run");
  }
  if (st == LSM_OK && !stop_signal) install_stop_handlers(1);
  if (st == LSM_OK) st = make_temp_dir(cli->out_dir, tmp, sizeof tmp, err);
  if (st == LSM_OK) {
    char path[4200];
    snprintf(sink.dir, sizeof sink.dir, "%s", tmp);
    sink.write_slices = cli->write_slices;
    sink.max_voxels = cli->max_voxels;
    sink.input = cli->slice_dir;
    const double pixel_dx = cli->stack.pixel_dx, pixel_dy = cli->stack.pixel_dy;
    const double dz = lsm_stack_output_dz(&cli->stack);
    /* --nrrd-encoding gzip: the writer's gzip NRRD in place of the raw one */
    const unsigned formats = cli->nrrd_gzip && (cli->formats & LSM_FORMAT_NRRD)
                                 ? (cli->formats & ~LSM_FORMAT_NRRD) | LSM_FORMAT_NRRD_GZ
                                 : cli->formats;
    st = lsm_volume_writer_open(tmp, formats, (lsm_values)cli->values, width, height, pixel_dx,
                                pixel_dy, dz, 0.0, 0.0, z[0], &sink.volume, err);
    /* the mesh caps an object cut by the first or last slice half a slice step
     * beyond it: dz, or with --per-iteration (uneven heights, --dz unused) the
     * step to the neighbouring slice */
    if (st == LSM_OK && cli->mesh)
      st = lsm_mesh_open(width, height, pixel_dx, pixel_dy, cli->stack.per_iteration ? 0.0 : dz,
                         tmp, &sink.mesh, err);
    if (st == LSM_OK && cli->preview)
      st = lsm_preview_open(width, height, pixel_dx, pixel_dy, dz, &sink.preview, err);
    if (st == LSM_OK) {
      snprintf(path, sizeof path, "%s/heights.txt", tmp);
      sink.heights = fopen(path, "w");
      if (!sink.heights) st = lsm_fail(err, LSM_ERR_IO, path, "cannot create: %s", strerror(errno));
    }
    if (st == LSM_OK && sink.write_slices) {
      snprintf(path, sizeof path, "%s/slices", tmp);
      st = lsm_make_dir(path, err);
    }
  }
  if (st == LSM_OK) {
    if (!cli->quiet)
      fprintf(stderr, "lsmorph: %zu slices of %dx%d from %s, method %s, %d threads\n", src.count,
              width, height, cli->slice_dir, lsm_method_name(cli->stack.method), threads);
    progress_state ps = {isatty(fileno(stderr)), -1, 0, t_start};
    lsm_progress progress = {&ps, progress_update};
    lsm_slice_source source = {&src, src.count, z, slice_files_load, slice_files_name};
    lsm_slice_sink out = {&sink, sink_emit};
    lsm_slice_sink stoppable = {&out, stoppable_emit};
    st = lsm_stack_run(&source, width, height, &cli->stack, &stoppable, stats,
                       cli->quiet ? NULL : &progress, err);
    if (st == LSM_ERR_NUMERIC) name_failed_pair(err, &src, stats);
  }
  if (st == LSM_OK) {
    double sz = lsm_stack_output_dz(&cli->stack);
    if (cli->stack.per_iteration && sink.count > 1)
      sz = sink_mean_step(&sink);
    st = lsm_volume_writer_finish(&sink.volume, sz, sink.count, err);
  }
  if (st == LSM_OK && sink.mesh) {
    char path[4200];
    snprintf(path, sizeof path, "%s/surface.ply", tmp);
    st = lsm_mesh_close(sink.mesh, err);
    if (st == LSM_OK) st = lsm_mesh_write_ply(sink.mesh, path, err);
  }
  lsm_mesh_free(&sink.mesh);
  if (st == LSM_OK && sink.preview) {
    char montage[4200], render[4200];
    snprintf(montage, sizeof montage, "%s/preview.png", tmp);
    snprintf(render, sizeof render, "%s/preview3d.png", tmp);
    st = lsm_preview_write(sink.preview, montage, render, err);
  }
  lsm_preview_free(&sink.preview);
  if (sink.heights) {
    int bad = ferror(sink.heights);
    if ((fclose(sink.heights) != 0 || bad) && st == LSM_OK)
      st = lsm_fail(err, LSM_ERR_IO, NULL, "%s/heights.txt: write failed: %s", tmp,
                    bad ? "stream error" : strerror(errno));
    sink.heights = NULL;
  }
  if (st == LSM_OK) {
    char path[4200];
    snprintf(path, sizeof path, "%s/run.json", tmp);
    st = write_run_json(path, argc, argv, cli, &src, z, width, height, &sink, stats, threads,
                        backend, wall_seconds() - t_start, err);
  }
  if (st == LSM_OK) st = check_stop(err); /* a signal now still means no result */
  if (st == LSM_OK) st = publish(tmp, cli->out_dir, err);
  if (st == LSM_OK) {
    if (!cli->quiet) {
      int capped = 0;
      for (size_t k = 0; k + 1 < src.count; ++k) capped += stats[k].hit_max_iter;
      if (capped)
        fprintf(stderr, "lsmorph: note: %d gaps stopped at --max-iter %d before finishing\n",
                capped, cli->stack.max_iter);
      if (!sink_evenly_spaced(&sink))
        fprintf(stderr,
                "lsmorph: note: the output slices are not evenly spaced (steps %.4g to %.4g); "
                "the volume files hold one z spacing, the mean (%.4g): heights.txt has each "
                "slice's height\n",
                sink.step_min, sink.step_max, sink_mean_step(&sink));
      if (!cli->stack.per_iteration && src.count > 1 && sink.count > 0) {
        /* the regular grid stops at the last step within the heights */
        const double dz = lsm_stack_output_dz(&cli->stack);
        const double top = z[src.count - 1], range = top - z[0], short_by = top - sink.z_last;
        if (short_by > 1e-6 * dz) {
          const double steps = ceil(range / dz);
          char last[40], top_text[40], dz_text[40], range_text[40], fit[40];
          lsm_shortest_number(last, sizeof last, sink.z_last); /* 1e6 - 4e-6 stays apart */
          lsm_shortest_number(top_text, sizeof top_text, top);
          lsm_shortest_number(dz_text, sizeof dz_text, dz);
          lsm_shortest_number(range_text, sizeof range_text, range);
          lsm_shortest_number(fit, sizeof fit, range / steps);
          fprintf(stderr,
                  "lsmorph: note: the output slices stop at height %s, %.4g below the last "
                  "input slice (%s), which is not in the volume: the step %s does not divide "
                  "the heights' range %s; --dz %s (%.0f step%s) ends on it\n",
                  last, short_by, top_text, dz_text, range_text, fit, steps,
                  steps == 1.0 ? "" : "s");
        }
      }
      const char *files[16];
      size_t nfiles = output_files(cli, files, 16);
      fprintf(stderr, "lsmorph: wrote %zu slices to %s (", sink.count, cli->out_dir);
      for (size_t k = 0; k < nfiles && k < 16; ++k) fprintf(stderr, "%s%s", k ? ", " : "", files[k]);
      fprintf(stderr, ") in %.2f s\n", wall_seconds() - t_start);
    }
  } else {
    lsm_volume_writer_abort(&sink.volume);
    lsm_mesh_free(&sink.mesh);
    lsm_preview_free(&sink.preview);
    if (*tmp) {
      remove_tree(tmp);
      name_out_not_tmp(err, tmp, cli->out_dir);
    }
  }
  lsm_backend_close(&backend);
  free(sink.mask);
  free(stats);
  free(z);
  lsm_path_list_free(src.paths, src.count);
  return st;
}

/* ---- score ------------------------------------------------------------------------------ */

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

/* Where a result's input slices lie among the truth slices (0-based), from
 * its run.json: the input heights (input.heights) are whole output steps
 * (options.dz) apart, the first input being truth slice first.  *pos is
 * allocated, *n_pos entries. */
static lsm_status result_input_positions(const char *text, const char *path, size_t first,
                                         size_t **pos, size_t *n_pos, lsm_err *err) {
  static const char *const heights_key[] = {"input", "heights"}, *const dz_key[] = {"options", "dz"};
  size_t n = 0;
  double dz = 0.0;
  *pos = NULL;
  *n_pos = 0;
  if (lsm_json_find_numbers(text, heights_key, 2, NULL, 0, &n, NULL) != 1 || n == 0)
    return lsm_fail(err, LSM_ERR_INPUT, path,
                    "does not give the input heights (input.heights): give --stride K");
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
 * (result_row_step), from the same run.json. */
static lsm_status score_kept(const lsm_cli *cli, char **truth, size_t n_truth, char from[64],
                             size_t **kept, size_t *n_kept, size_t *inputs, double *row_step,
                             lsm_err *err) {
  const size_t k = (size_t)cli->stride;
  size_t first = cli->first > 0 ? (size_t)cli->first - 1 : 0;
  char path[4200], *text = NULL;
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
    if (st == LSM_OK) offsets = lsm_alloc(*inputs, sizeof *offsets, err, "slice list");
    if (st == LSM_OK && !offsets) st = err ? err->status : LSM_ERR_NOMEM;
    for (size_t i = 0; st == LSM_OK && i < *inputs; ++i) offsets[i] = i * k;
    n_offsets = *inputs;
  } else if (!k) {
    st = result_input_positions(text, path, 0, &offsets, &n_offsets, err);
  }
  int named = 0;
  if (st == LSM_OK && cli->first == 0 && text)
    named = first_by_names(text, truth, n_truth, offsets, n_offsets, &first);
  *row_step = result_row_step(text);
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

/* Whatever went to standard output (help, version, the device list, the scores) reached it. */
static lsm_status check_stdout(lsm_err *err) {
  if (fflush(stdout) != 0 || ferror(stdout))
    return lsm_fail(err, LSM_ERR_IO, "standard output", "write failed: %s", strerror(errno));
  return LSM_OK;
}

static lsm_status score(const lsm_cli *cli, lsm_err *err) {
  char **truth = NULL;
  size_t n = 0, *kept = NULL, n_kept = 0;
  LSM_TRY(lsm_dir_list_slices(cli->truth_dir, &truth, &n, NULL, err));
  size_t inputs = 0; /* run.json's input count, with --stride */
  char from[64] = ""; /* where --stride starts, when not at the first slice */
  double row_step = 1.0; /* pixel height / width: distances are in pixel widths */
  lsm_status st = score_kept(cli, truth, n, from, &kept, &n_kept, &inputs, &row_step, err);
  lsm_image_read_opts ro = {0, (uint64_t)1 << 28, 0}, ro_truth = ro;
  double dice = 0, hd95 = 0, msd = 0, vol_r = 0, vol_t = 0, inter = 0;
  size_t count = 0, incomparable = 0, measured = 0, pool_n = 0, pool_cap = 0;
  double *pool = NULL;
  const size_t first = n_kept ? kept[0] : 0, last = n_kept ? kept[n_kept - 1] : 0;
  /* --per-slice: each held-out slice's scores, and its truth slice */
  lsm_slice_score *per = NULL;
  size_t *per_at = NULL;
  if (st == LSM_OK && cli->per_slice) {
    per = lsm_alloc(last - first + 1, sizeof *per, err, "per-slice scores");
    per_at = lsm_alloc(last - first + 1, sizeof *per_at, err, "per-slice scores");
    if (!per || !per_at) st = err ? err->status : LSM_ERR_NOMEM;
  }
  /* truth stored as 0/1 labels is read as such (the result slices are
   * 0/255), decided as reconstruct decided it: over the kept slices alone
   * (one bright pixel in a held-out slice must not change how they read) */
  char **kept_paths = st == LSM_OK ? lsm_alloc(n_kept, sizeof *kept_paths, err, "slice list") : NULL;
  if (st == LSM_OK && !kept_paths) st = err ? err->status : LSM_ERR_NOMEM;
  if (st == LSM_OK) {
    for (size_t i = 0; i < n_kept; ++i) kept_paths[i] = truth[kept[i]];
    st = pick_foreground(kept_paths, n_kept, &ro_truth, 1, cli->truth_dir, err);
  }
  free(kept_paths);
  if (st == LSM_OK) {
    /* a result of another stride or stack would be scored against the wrong
     * slices: its slice count must be the one the kept slices give */
    char dir[4200], **result = NULL;
    size_t m = 0;
    snprintf(dir, sizeof dir, "%s/slices", cli->result_dir);
    struct stat info;
    if (stat(dir, &info) != 0 && errno == ENOENT && stat(cli->result_dir, &info) == 0)
      st = lsm_fail(err, LSM_ERR_INPUT, dir,
                    "no such folder: score reads the result's slices (a reconstruct run with "
                    "--no-slices has none)");
    if (st == LSM_OK) st = lsm_dir_list_slices(dir, &result, &m, NULL, err);
    lsm_path_list_free(result, m);
    if (st == LSM_OK && m != last - first + 1 && cli->stride)
      st = lsm_fail(err, LSM_ERR_INPUT, dir,
                    "%zu slices, but slices %zu, %zu, %zu, ... of the %zu truth slices, "
                    "reconstructed with --spacing %d and the default --dz, give %zu",
                    m, first + 1, first + 1 + (size_t)cli->stride,
                    first + 1 + 2 * (size_t)cli->stride, n, cli->stride, last - first + 1);
    else if (st == LSM_OK && m != last - first + 1)
      st = lsm_fail(err, LSM_ERR_INPUT, dir,
                    "%zu slices, but its inputs (run.json) are truth slices %zu to %zu, one "
                    "output step (--dz) apart: %zu",
                    m, first + 1, last + 1, last - first + 1);
    if (st == LSM_OK && inputs && inputs != n_kept)
      st = lsm_fail(err, LSM_ERR_INPUT, cli->result_dir,
                    "was made from %zu slices (run.json), but --stride %d%s keeps %zu of the %zu "
                    "truth slices",
                    inputs, cli->stride, from, n_kept, n);
  }
  for (size_t k = first, next = 0; st == LSM_OK && k <= last; ++k) {
    char path[4200];
    snprintf(path, sizeof path, "%s/slices/%05zu.png", cli->result_dir, k - first + 1);
    lsm_mask a = {0}, b = {0};
    st = lsm_slice_read_mask(path, &ro, &a, err);
    if (st == LSM_OK) st = lsm_slice_read_mask(truth[k], &ro_truth, &b, err);
    if (st == LSM_OK && (a.width != b.width || a.height != b.height))
      st = lsm_fail(err, LSM_ERR_INPUT, path, "slice is %dx%d but the truth slice %s is %dx%d",
                    a.width, a.height, truth[k], b.width, b.height);
    if (next < n_kept && kept[next] == k) {
      /* an input slice comes back exactly: otherwise the result was not made
       * from these slices of this truth */
      ++next;
      if (st == LSM_OK && memcmp(a.pixels, b.pixels, (size_t)a.width * (size_t)a.height) != 0) {
        if (cli->stride)
          st = lsm_fail(err, LSM_ERR_INPUT, path,
                        "differs from the truth slice %s, which --stride %d makes an input: was "
                        "the result made from slices %zu, %zu, %zu, ... of %s?",
                        truth[k], cli->stride, first + 1, first + 1 + (size_t)cli->stride,
                        first + 1 + 2 * (size_t)cli->stride, cli->truth_dir);
        else
          st = lsm_fail(err, LSM_ERR_INPUT, path,
                        "differs from the truth slice %s, which run.json's input heights make "
                        "an input, the first input taken as truth slice %zu (--first N if it "
                        "is slice N): was the result made from slices of %s?",
                        truth[k], first + 1, cli->truth_dir);
      }
      lsm_mask_free(&a);
      lsm_mask_free(&b);
      continue;
    }
    lsm_slice_score s;
    if (st == LSM_OK) st = lsm_score_slice(&a, &b, row_step, &s, &pool, &pool_n, &pool_cap, err);
    if (st == LSM_OK && per) {
      per[count] = s;
      per_at[count] = k;
    }
    if (st == LSM_OK) {
      dice += s.dice;
      vol_r += (double)s.area_result;
      vol_t += (double)s.area_truth;
      inter += s.dice * (double)(s.area_result + s.area_truth) / 2.0;
      incomparable += !s.comparable;
      if (has_distances(&s)) {
        hd95 += s.hd95;
        msd += s.mean_surface;
        measured++;
      }
      count++;
    }
    lsm_mask_free(&a);
    lsm_mask_free(&b);
  }
  double pooled = lsm_quantile(pool, pool_n, 0.95);
  free(pool);
  if (st == LSM_OK) {
    if (first == 1)
      fprintf(stderr, "lsmorph: note: truth slice 1 lies before the first kept slice (2) and is "
                      "not scored\n");
    else if (first > 1)
      fprintf(stderr,
              "lsmorph: note: truth slices 1 to %zu lie before the first kept slice (%zu) and are "
              "not scored\n",
              first, first + 1);
    if (last + 2 == n)
      fprintf(stderr,
              "lsmorph: note: truth slice %zu lies past the last kept slice (%zu) and is not "
              "scored (nothing is extrapolated past it)\n",
              n, last + 1);
    else if (last + 2 < n)
      fprintf(stderr,
              "lsmorph: note: truth slices %zu to %zu lie past the last kept slice (%zu) and are "
              "not scored (nothing is extrapolated past it)\n",
              last + 2, n, last + 1);
    /* undefined scores (no held-out slice, no boundary on both sides, an empty
     * truth) are JSON null, as in run.json */
    printf("{\"held_out\": %zu, \"dice_volume\": ", count);
    lsm_json_number(stdout, vol_r + vol_t > 0 ? 2.0 * inter / (vol_r + vol_t) : 1.0);
    printf(", \"dice\": ");
    lsm_json_number(stdout, count ? dice / (double)count : NAN);
    printf(", \"hd95\": ");
    lsm_json_number(stdout, measured ? hd95 / (double)measured : NAN);
    printf(", \"hd95_pooled\": ");
    lsm_json_number(stdout, pooled);
    printf(", \"mean_surface\": ");
    lsm_json_number(stdout, measured ? msd / (double)measured : NAN);
    printf(", \"volume_error\": ");
    lsm_json_number(stdout, vol_t > 0 ? (vol_r - vol_t) / vol_t : NAN);
    printf(", \"one_sided_empty\": %zu", incomparable);
    if (per) {
      printf(", \"slices\": [");
      for (size_t i = 0, below = 0; i < count; ++i) {
        const lsm_slice_score *p = &per[i];
        while (below + 1 < n_kept && kept[below + 1] < per_at[i]) ++below;
        printf("%s{\"truth\": %zu, \"file\": ", i ? ", " : "", per_at[i] + 1);
        lsm_json_string(stdout, lsm_base_name(truth[per_at[i]]));
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
    st = check_stdout(err);
  }
  lsm_path_list_free(truth, n);
  free(kept);
  free(per);
  free(per_at);
  return st;
}

/* With file descriptor 0, 1 or 2 closed by the caller, the first file opened
 * would take its number, and stderr's progress lines would land in a volume
 * file: hold every one of them open (on /dev/null). */
static int hold_standard_fds(void) {
  for (int fd = 0; fd <= 2; ++fd) {
    if (fcntl(fd, F_GETFD) != -1) continue;
    const int got = open("/dev/null", fd == 0 ? O_RDONLY : O_WRONLY);
    if (got < 0) return -1;
    if (got != fd) { /* lower ones are open, so got > fd: should not happen */
      close(got);
      return -1;
    }
  }
  return 0;
}

static int run(int argc, char **argv, const lsm_mpi *mpi) {
  lsm_cli cli;
  lsm_err err;
  lsm_err_clear(&err);
  if (lsm_cli_parse(argc, argv, &cli, &err) != LSM_OK) {
    if (lsm_mpi_rank(mpi) == 0) fprintf(stderr, "lsmorph: error: %s\n", err.msg);
    return 2;
  }
  lsm_status st = LSM_OK;
  switch (cli.command) {
  case LSM_CMD_HELP:
    lsm_cli_help(stdout, cli.help_topic);
    st = check_stdout(&err);
    break;
  case LSM_CMD_VERSION:
    printf("lsmorph %s\n", LSM_VERSION);
    st = check_stdout(&err);
    break;
  case LSM_CMD_RECONSTRUCT:
    install_stop_handlers(0);
    st = reconstruct(argc, argv, &cli, mpi, &err);
    break;
  case LSM_CMD_DEVICES:
    st = lsm_backend_list_devices(stdout, &err);
    if (st == LSM_OK) st = check_stdout(&err);
    break;
  case LSM_CMD_SCORE:
    st = score(&cli, &err);
    break;
  default:
    lsm_cli_help(stderr, NULL);
    return 2;
  }
  const int sig = stop_signal;
  if (st != LSM_OK && sig) {
    /* Whatever failed on the way out was caused by the signal: say so, then end
     * by that signal (exit status 128 + N in a shell: 130 for SIGINT, 143 for
     * SIGTERM), so that a calling shell script stops too. */
    fprintf(stderr, "lsmorph: error: %s: interrupted by %s; no result was written%s\n",
            cli.out_dir ? cli.out_dir : "lsmorph", stop_signal_name(sig),
            cli.out_dir ? " (an earlier result there is unchanged)" : "");
    signal(sig, SIG_DFL);
    raise(sig);
    return 128 + sig;
  }
  if (st != LSM_OK) {
    if (lsm_mpi_rank(mpi) == 0) /* other MPI ranks: rank 0 reports for all */
      fprintf(stderr, "lsmorph: error: %s\n", err.msg[0] ? err.msg : lsm_status_name(st));
    return st == LSM_ERR_USAGE ? 2 : 1;
  }
  return 0;
}

int main(int argc, char **argv) {
#if defined(M_MMAP_THRESHOLD)
  /* Keep freed grids in the heap: every gap allocates and frees tens of MB of
   * grids, and returning them to the kernel costs a page fault per page on
   * the next gap (about a fifth of the run time on 512^2 slices). */
  mallopt(M_MMAP_THRESHOLD, 1 << 30);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
  if (hold_standard_fds() != 0) return 1; /* no stderr to say so */
  lsm_mpi *mpi = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  if (lsm_mpi_init(&argc, &argv, &mpi, &err) != LSM_OK) {
    fprintf(stderr, "lsmorph: error: %s\n", err.msg);
    return 1;
  }
  const int rc = run(argc, argv, mpi);
  /* With several ranks, rank 0 has reported the error and removed its
   * temporary output: end the other ranks too (they may be waiting to send). */
  if (rc != 0 && lsm_mpi_size(mpi) > 1 && lsm_mpi_rank(mpi) == 0) lsm_mpi_abort(mpi, rc);
  lsm_mpi_finalize(&mpi);
  return rc;
}
