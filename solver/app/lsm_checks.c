#include "solver/app/lsm_checks.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/statvfs.h>

#include "solver/app/lsm_signals.h"
#include "solver/recon/lsm_schedule.h"

/* Longest slice side accepted: keeps every canvas of the stack driver (the
 * image plus alignment margins, at most three times a side) within an int. */
#define LSM_SIDE_MAX (1 << 24)

/* Increasing, finite heights whose gaps and output steps the floats and
 * doubles of the run resolve. */
static lsm_status check_heights(const lsm_cli *cli, const lsm_slice_files *src, const double *z,
                                lsm_err *err) {
  const char *heights_name = cli->heights_file ? cli->heights_file : cli->slice_dir;
  for (size_t k = 0; k < src->count; ++k) {
    if (!isfinite(z[k]))
      return lsm_fail(err, LSM_ERR_INPUT, heights_name,
                      "height of slice %zu is not finite (--spacing %g)", k + 1, cli->spacing);
    if (k > 0 && !(z[k] > z[k - 1]))
      return lsm_fail(err, LSM_ERR_INPUT, heights_name,
                      "heights of slices %zu and %zu are not increasing", k, k + 1);
    if (k > 0 && !lsm_length_in_range(z[k] - z[k - 1]))
      return lsm_fail(err, LSM_ERR_INPUT, heights_name,
                      "slices %zu and %zu are %g apart, outside %g to %g (lengths are held as "
                      "floats; choose a unit that brings it into range)",
                      k, k + 1, z[k] - z[k - 1], LSM_LENGTH_MIN, LSM_LENGTH_MAX);
  }
  /* output heights are doubles: steps too small for them repeat heights */
  const double z_mag = fmax(fabs(z[0]), fabs(z[src->count - 1]));
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
  return LSM_OK;
}

/* Every slice header: the first within --max-pixels and LSM_SIDE_MAX, the
 * others the first's size. */
static lsm_status check_slice_sizes(const lsm_cli *cli, const lsm_slice_files *src, int *width,
                                    int *height, lsm_err *err) {
  int w = 0, h = 0;
  for (size_t k = 0; k < src->count; ++k) {
    LSM_TRY(lsm_signals_check(err));
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
  *width = w;
  *height = h;
  return LSM_OK;
}

/* The working grid of a gap and the output volume, for w x h slices. */
static lsm_status check_limits(const lsm_cli *cli, const lsm_slice_files *src, const double *z,
                               int w, int h, lsm_err *err) {
  const char *heights_name = cli->heights_file ? cli->heights_file : cli->slice_dir;
  /* an aligned gap pads each axis by the largest centroid shift along it (at
   * most half the side) plus 2 cells */
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
  if (cli->stack.align != LSM_ALIGN_NONE && canvas / 4 > cli->max_pixels)
    return lsm_fail(err, LSM_ERR_LIMIT, src->paths[0],
                    "%dx%d slices need a working canvas of up to %llu cells with --align %s, "
                    "more than 4 x --max-pixels %llu (use --align none or raise --max-pixels)",
                    w, h, (unsigned long long)canvas, lsm_align_name(cli->stack.align),
                    (unsigned long long)cli->max_pixels);
  const char *nifti = (cli->formats & LSM_FORMAT_NII) ? "volume.nii" : "volume.nii.gz";
  if ((cli->formats & LSM_FORMATS_NIFTI) && (w > LSM_NIFTI_DIM_MAX || h > LSM_NIFTI_DIM_MAX))
    return lsm_fail(err, LSM_ERR_LIMIT, src->paths[0],
                    "%dx%d slices do not fit %s: NIfTI-1 holds at most %d samples along "
                    "an axis (choose another --format)", w, h, nifti, LSM_NIFTI_DIM_MAX);
  if (cli->stack.per_iteration) return LSM_OK; /* its volume is checked as it is written */
  const double dz = lsm_stack_output_dz(&cli->stack);
  const size_t count = lsm_stack_output_count(z, src->count, dz);
  const double slices = (double)count;
  if ((cli->formats & LSM_FORMATS_NIFTI) && count > LSM_NIFTI_DIM_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, heights_name,
                    "the output would have %s%zu slices, more than the %d %s holds "
                    "(NIfTI-1 sizes are 16-bit: raise --dz or choose another --format)",
                    count >= LSM_OUTPUT_COUNT_MAX ? "at least " : "", count, LSM_NIFTI_DIM_MAX,
                    nifti);
  const double voxels = slices * (double)w * (double)h;
  if (!(voxels <= (double)cli->max_voxels))
    return lsm_fail(err, LSM_ERR_LIMIT, heights_name,
                    "the output would have %s%.4g slices of %dx%d = %.4g voxels, more than "
                    "--max-voxels %llu (raise --dz or --max-voxels)",
                    count >= LSM_OUTPUT_COUNT_MAX ? "at least " : "", slices, w, h, voxels,
                    (unsigned long long)cli->max_voxels);
  return LSM_OK;
}

lsm_status lsm_check_inputs(const lsm_cli *cli, const lsm_slice_files *src, const double *z,
                            int *width, int *height, lsm_err *err) {
  int w = 0, h = 0;
  LSM_TRY(check_heights(cli, src, z, err));
  LSM_TRY(check_slice_sizes(cli, src, &w, &h, err));
  LSM_TRY(check_limits(cli, src, z, w, h, err));
  *width = w;
  *height = h;
  return LSM_OK;
}

/* ---- memory and disk, before any work -------------------------------------------------- */

/* The model of a run's peak memory, in bytes (measured peaks of two-sided
 * gaps at 512^2 to 4096^2, one and two threads, one and six slices:
 * validation/measurements/limits.md).  A gap in flight works on a canvas of
 * (W + 4) x (H + 4) cells where its pair is not aligned (more where it is):
 * about 40 floats a cell for both morphs and their narrow bands, the signed
 * distances and slopes of its four slices, the combined field and the
 * distance transforms' scratch (measured: 123 to 148 bytes); the particles
 * of pls add 12 more.  The mesh keeps its slab of slices and
 * vertex maps (about 24 floats a pixel); the slice writer queues at most
 * 64 MiB of slices. */
#define LSM_MEM_BASE (16.0 * 1048576.0)
#define LSM_MEM_GAP_PER_CELL 160.0
#define LSM_MEM_PLS_PER_CELL 48.0
#define LSM_MEM_MESH_PER_PIXEL 96.0
/* --motion field and auto: the pair's registration and its field (the velocity, the
 * exponentials both ways, the warped distances, the update and the smoothing's scratch, at
 * full resolution and the coarser levels; limits.md has the peaks). */
#define LSM_MEM_FIELD_PER_CELL 64.0
#define LSM_MEM_WRITER_QUEUE (64.0 * 1048576.0)

/* A number from the first line of path (0 when absent, or "max"). */
static double number_in(const char *path) {
  FILE *f = fopen(path, "r");
  if (!f) return 0.0;
  char line[128] = "";
  const int ok = fgets(line, sizeof line, f) != NULL;
  fclose(f);
  return ok ? strtod(line, NULL) : 0.0;
}

double lsm_memory_available(void) {
  double available = 0.0;
  FILE *f = fopen("/proc/meminfo", "r");
  if (f) {
    char line[256];
    while (fgets(line, sizeof line, f))
      if (strncmp(line, "MemAvailable:", 13) == 0) available = 1024.0 * strtod(line + 13, NULL);
    fclose(f);
  }
  /* a container's cgroup (v2) may allow less: its limit less what it uses */
  char group[600] = "", path[700];
  f = fopen("/proc/self/cgroup", "r");
  if (f) {
    char line[600];
    while (fgets(line, sizeof line, f))
      if (strncmp(line, "0::", 3) == 0) snprintf(group, sizeof group, "%.500s", line + 3);
    fclose(f);
  }
  group[strcspn(group, "\n")] = '\0';
  for (int up = 0; up < 2; ++up) { /* the group, then the namespace's root */
    snprintf(path, sizeof path, "/sys/fs/cgroup%s/memory.max", up ? "" : group);
    const double limit = number_in(path);
    snprintf(path, sizeof path, "/sys/fs/cgroup%s/memory.current", up ? "" : group);
    const double used = number_in(path);
    if (limit > 0.0 && (available <= 0.0 || limit - used < available))
      available = limit > used ? limit - used : 1.0;
  }
  return available;
}

/* bytes as "1.5 GiB", "300 MiB", "12 KiB" */
static const char *bytes_text(double b, char *text, size_t cap) {
  static const char *const units[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB"};
  int u = 0;
  while (b >= 1024.0 && u < 5) {
    b /= 1024.0;
    ++u;
  }
  snprintf(text, cap, u ? "%.3g %s" : "%.0f %s", b, units[u]);
  return text;
}

/* Bytes a sample takes in each uncompressed volume format of cli; the
 * compressed ones (nii.gz, gzip NRRD, EXR) are not counted (their size is
 * not known ahead).  *names: the formats counted, for the message. */
static double sample_bytes(const lsm_cli *cli, char *names, size_t cap) {
  const double each = cli->values == LSM_VALUES_MASK ? 1.0 : 4.0;
  static const unsigned plain[] = {LSM_FORMAT_NRRD, LSM_FORMAT_MHA, LSM_FORMAT_VTK,
                                   LSM_FORMAT_NII, LSM_FORMAT_RAW};
  double total = 0.0;
  names[0] = '\0';
  for (size_t k = 0; k < sizeof plain / sizeof plain[0]; ++k) {
    if (!(cli->formats & plain[k])) continue;
    if (plain[k] == LSM_FORMAT_NRRD && cli->nrrd_encoding == LSM_NRRD_GZIP) continue;
    total += each;
    const size_t n = strlen(names);
    snprintf(names + n, cap - n, "%s%s", n ? ", " : "", lsm_format_name(plain[k]));
  }
  return total;
}

lsm_status lsm_check_resources(lsm_cli *cli, const lsm_slice_files *src, const double *z, int w,
                               int h, const char *folder, lsm_err *err) {
  const lsm_stack_opts *o = &cli->stack;
  const double pixels = (double)w * (double)h;
  const double canvas = ((double)w + 4.0) * ((double)h + 4.0);
  /* the output grid, gap by gap (default mode; per iteration: unknown) */
  size_t count = 0, most = 0;
  if (!o->per_iteration) {
    const double dz = lsm_stack_output_dz(o);
    const lsm_output_grid g = lsm_output_grid_of(z, src->count, dz);
    count = lsm_stack_output_count(z, src->count, dz);
    for (size_t i = 0, k = 0; i + 1 < src->count; ++i) {
      const size_t first = k;
      while (k < count && lsm_output_below(&g, k, z[i + 1])) ++k;
      if (k - first > most) most = k - first;
    }
  }
  const int workers = o->per_iteration ? 1 : lsm_schedule_gap_workers(o, w, h, src->count - 1, most);
  const double per_gap =
      canvas * (LSM_MEM_GAP_PER_CELL + (o->method == LSM_METHOD_PLS ? LSM_MEM_PLS_PER_CELL : 0.0) +
                (o->motion != LSM_MOTION_NONE ? LSM_MEM_FIELD_PER_CELL : 0.0));
  const double held = (double)most * (canvas + (workers > 1 ? pixels : 0.0)) * sizeof(float);
  const double output = (double)count * pixels * sizeof(float);
  const double queue = o->per_iteration || output > LSM_MEM_WRITER_QUEUE ? LSM_MEM_WRITER_QUEUE : output;
  const double fixed = LSM_MEM_BASE + workers * per_gap + queue +
                       (cli->mesh ? LSM_MEM_MESH_PER_PIXEL * pixels : 0.0);
  const double memory = fixed + workers * held;
  const double available = cli->max_memory ? (double)cli->max_memory : lsm_memory_available();
  char a[32], b[64], c[32];
  if (cli->max_memory)
    snprintf(b, sizeof b, "--max-memory %llu", (unsigned long long)cli->max_memory);
  else
    snprintf(b, sizeof b, "the %s available", bytes_text(available, c, sizeof c));
  if (available > 0.0 && memory > available)
    return lsm_fail(err, LSM_ERR_LIMIT, cli->slice_dir,
                    "the run needs about %s of memory (%d gap%s at %s working on %dx%d cells%s%s), "
                    "more than %s: lower --threads (fewer gaps at once), raise --dz (fewer slices "
                    "per gap), or allow more with --max-memory BYTES",
                    bytes_text(memory, a, sizeof a), workers, workers == 1 ? "" : "s",
                    workers == 1 ? "a time," : "once, each", w + 4, h + 4,
                    most ? " and holding up to " : "", most ? bytes_text(held, c, sizeof c) : "", b);
  /* what one gap may hold for its turn (per iteration: known only then) */
  if (available > 0.0) cli->stack.held_max = (available - fixed) / workers;
  /* and how large a canvas one gap may work on: an aligned pair pads its canvas by its shift
   * (up to four times the cells), which only the gap knows */
  if (available > 0.0)
    cli->stack.canvas_max = canvas + (available - memory) / (workers * per_gap / canvas);
  if (o->per_iteration) return LSM_OK;
  /* disk: what is sure to be written, in the temporary folder's file system */
  char formats[128];
  const double volumes = output * sample_bytes(cli, formats, sizeof formats) / sizeof(float);
  const double pngs = cli->write_slices ? 4096.0 * (double)count : 0.0; /* a block each at least */
  const double disk = volumes + pngs + 24.0 * (double)count;
  struct statvfs fs; /* a file system that cannot tell (/proc: no blocks): writing will */
  if (statvfs(folder, &fs) != 0 || fs.f_blocks == 0) return LSM_OK;
  const double free_bytes = (double)fs.f_bavail * (double)fs.f_frsize;
  char d[32];
  if (disk > free_bytes)
    return lsm_fail(err, LSM_ERR_LIMIT, cli->out_dir,
                    "the result needs at least %s on the file system of %s (%zu slices: %s%s%s%s), "
                    "which has %s free: raise --dz, write fewer --format%s, or name an OUT_DIR "
                    "with more room",
                    bytes_text(disk, a, sizeof a), folder, count,
                    formats[0] ? bytes_text(volumes, b, sizeof b) : "", formats[0] ? " of " : "",
                    formats, pngs > 0 ? (formats[0] ? " and slice PNGs" : "slice PNGs") : "",
                    bytes_text(free_bytes, d, sizeof d), cli->write_slices ? ", --no-slices" : "");
  return LSM_OK;
}

lsm_status lsm_check_fill_resources(uint64_t max_memory, const lsm_fill_need *need,
                                    const char *labels_path, const char *folder,
                                    double *canvas_max, lsm_err *err) {
  /* the volume is held already; the fill adds the gap slices' label depths
   * (16-bit), and each thread one gap's working canvas and the slices it holds */
  const double canvas = ((double)need->width + 4.0) * ((double)need->height + 4.0);
  const double per_cell = LSM_MEM_GAP_PER_CELL + (need->field ? LSM_MEM_FIELD_PER_CELL : 0.0) +
                          4.0 * (double)need->most;
  const double memory = LSM_MEM_BASE + 2.0 * need->gap_voxels + need->threads * canvas * per_cell;
  const double available = max_memory ? (double)max_memory : lsm_memory_available();
  *canvas_max = available > 0.0 ? (available - memory) / (need->threads * per_cell) + canvas : 0.0;
  char a[32], b[64], c[32];
  if (max_memory)
    snprintf(b, sizeof b, "--max-memory %llu", (unsigned long long)max_memory);
  else
    snprintf(b, sizeof b, "the %s available", bytes_text(available, c, sizeof c));
  if (available > 0.0 && memory > available)
    return lsm_fail(err, LSM_ERR_LIMIT, labels_path,
                    "filling needs about %s of memory more than the volume (%d thread%s, each "
                    "working on %dx%d cells), more than %s: lower --threads, or allow more with "
                    "--max-memory BYTES",
                    bytes_text(memory, a, sizeof a), need->threads, need->threads == 1 ? "" : "s",
                    need->width + 4, need->height + 4, b);
  struct statvfs fs;
  if (need->out_bytes <= 0.0 || statvfs(folder, &fs) != 0 || fs.f_blocks == 0) return LSM_OK;
  const double free_bytes = (double)fs.f_bavail * (double)fs.f_frsize;
  if (need->out_bytes > free_bytes)
    return lsm_fail(err, LSM_ERR_LIMIT, labels_path,
                    "the result needs %s on the file system of %s, which has %s free: write a "
                    "compressed file (.nii.gz) or to a file system with more room",
                    bytes_text(need->out_bytes, a, sizeof a), folder,
                    bytes_text(free_bytes, c, sizeof c));
  return LSM_OK;
}
