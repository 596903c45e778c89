/* lsmorph: the command-line program.  Parses the command line (lsm_cli), wires
 * PNG slices (io/) into the stack driver (lsm_stack) and its output slices into
 * the writers, writes run.json, and publishes OUT_DIR atomically. */
#define _XOPEN_SOURCE 700
#include <errno.h>
#include <ftw.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "io/lsm_io.h"
#include "solver/lsm_cli.h"
#include "solver/lsm_metrics.h"
#include "solver/lsm_stack.h"

static double wall_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static const char *base_name(const char *path) {
  const char *s = strrchr(path, '/');
  return s ? s + 1 : path;
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

/* ---- input: PNG slices ---------------------------------------------------------------- */

typedef struct png_source {
  char **paths;
  size_t count;
  lsm_png_read_opts read;
} png_source;

static lsm_status png_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
  png_source *ps = ctx;
  return lsm_png_read_mask(ps->paths[index], &ps->read, out, err);
}

static const char *png_name(void *ctx, size_t index) {
  png_source *ps = ctx;
  return ps->paths[index];
}

/* ---- output: volume.nrrd, heights.txt, slices/ ------------------------------------------- */

typedef struct out_sink {
  char dir[4096];
  int write_slices;
  lsm_nrrd_writer *nrrd;
  FILE *heights;
  size_t count;
  double z_first, z_last;
  uint8_t *mask;
} out_sink;

static lsm_status sink_emit(void *ctx, const float *phi, int width, int height, double z,
                            long input_index, lsm_err *err) {
  (void)input_index;
  out_sink *s = ctx;
  LSM_TRY(lsm_nrrd_write_slice(s->nrrd, phi, err));
  if (fprintf(s->heights, "%.17g\n", z) < 0)
    return lsm_fail(err, LSM_ERR_IO, "heights.txt", "write failed: %s", strerror(errno));
  if (s->count == 0) s->z_first = z;
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

static void json_string(FILE *f, const char *s) {
  fputc('"', f);
  for (const unsigned char *p = (const unsigned char *)s; *p; ++p) {
    if (*p == '"' || *p == '\\')
      fprintf(f, "\\%c", *p);
    else if (*p < 0x20)
      fprintf(f, "\\u%04x", *p);
    else
      fputc(*p, f);
  }
  fputc('"', f);
}

static void json_number(FILE *f, double v) {
  if (isfinite(v))
    fprintf(f, "%.10g", v);
  else
    fputs("null", f);
}

static lsm_status write_run_json(const char *path, int argc, char **argv, const lsm_cli *cli,
                                 const png_source *src, const double *z, int width, int height,
                                 const out_sink *sink, const lsm_pair_stats *stats, int threads,
                                 double wall, lsm_err *err) {
  FILE *f = fopen(path, "w");
  if (!f) return lsm_fail(err, LSM_ERR_IO, path, "cannot create: %s", strerror(errno));
  const lsm_stack_opts *o = &cli->stack;
  fprintf(f, "{\n  \"lsmorph_version\": \"%s\",\n  \"command\": [", LSM_VERSION);
  for (int k = 0; k < argc; ++k) {
    if (k) fputs(", ", f);
    json_string(f, argv[k]);
  }
  fputs("],\n  \"options\": {\"method\": ", f);
  json_string(f, lsm_method_name(o->method));
  fputs(", \"scheme\": ", f);
  json_string(f, lsm_scheme_name(o->morph.scheme));
  fputs(", \"time\": ", f);
  json_string(f, lsm_time_name(o->morph.time));
  fputs(", \"input\": ", f);
  json_string(f, lsm_input_name(o->input));
  fputs(", \"align\": ", f);
  json_string(f, lsm_align_name(o->align));
  fputs(", \"interp\": ", f);
  json_string(f, lsm_interp_name(o->interp));
  fprintf(f, ", \"cfl\": %.10g, \"reinit_every\": %d, \"reinit_iters\": %d, \"tol\": %.10g, "
             "\"max_iter\": %d, \"per_iteration\": %s, \"pixel_size\": %.10g, \"dz\": %.10g, "
             "\"invert\": %s, \"threads\": %d},\n",
          o->morph.cfl, o->morph.reinit_every, o->morph.reinit_iters, o->tol, o->max_iter,
          o->per_iteration ? "true" : "false", o->pixel_size,
          o->dz > 0 ? o->dz : o->pixel_size, cli->invert ? "true" : "false", threads);
  fputs("  \"input\": {\"folder\": ", f);
  json_string(f, cli->slice_dir);
  fprintf(f, ", \"slices\": %zu, \"width\": %d, \"height\": %d, \"files\": [", src->count, width,
          height);
  for (size_t k = 0; k < src->count; ++k) {
    if (k) fputs(", ", f);
    json_string(f, base_name(src->paths[k]));
  }
  fputs("], \"heights\": [", f);
  for (size_t k = 0; k < src->count; ++k) {
    if (k) fputs(", ", f);
    json_number(f, z[k]);
  }
  fprintf(f, "]},\n  \"output\": {\"slices\": %zu, \"first_height\": ", sink->count);
  json_number(f, sink->z_first);
  fputs(", \"last_height\": ", f);
  json_number(f, sink->z_last);
  fputs("},\n  \"pairs\": [\n", f);
  long long iterations = 0, updates = 0;
  double seconds = 0.0;
  for (size_t k = 0; k + 1 < src->count; ++k) {
    const lsm_pair_stats *p = &stats[k];
    fputs("    {\"source\": ", f);
    json_string(f, base_name(src->paths[p->source]));
    fputs(", \"target\": ", f);
    json_string(f, base_name(src->paths[p->target]));
    fprintf(f, ", \"iterations\": %d, \"dt\": ", p->iterations);
    json_number(f, p->dt);
    fputs(", \"cp\": ", f);
    json_number(f, p->cp);
    fputs(", \"seconds\": ", f);
    json_number(f, p->seconds);
    fprintf(f, ", \"cells\": %lld, \"t_final\": ", p->cells);
    json_number(f, p->t_final);
    fprintf(f, ", \"slices\": %zu, \"hit_max_iter\": %s}%s\n", p->slices,
            p->hit_max_iter ? "true" : "false", k + 2 < src->count ? "," : "");
    iterations += p->iterations;
    updates += (long long)p->iterations * p->cells * lsm_time_stages(o->morph.time);
    seconds += p->seconds;
  }
  fprintf(f, "  ],\n  \"totals\": {\"pairs\": %zu, \"iterations\": %lld, \"seconds\": ",
          src->count - 1, iterations);
  json_number(f, seconds);
  fputs(", \"wall_seconds\": ", f);
  json_number(f, wall);
  fprintf(f, ", \"cell_updates\": %lld, \"cells_per_second\": ", updates);
  json_number(f, seconds > 0 ? (double)updates / seconds : NAN);
  fputs("}\n}\n", f);
  int bad = ferror(f);
  if (fclose(f) != 0 || bad) return lsm_fail(err, LSM_ERR_IO, path, "write failed");
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
  return LSM_OK;
}

/* Moves the finished tmp folder to out_dir, replacing an earlier result. */
static lsm_status publish(const char *tmp, const char *out_dir, lsm_err *err) {
  struct stat st;
  if (stat(out_dir, &st) == 0) {
    if (!S_ISDIR(st.st_mode)) return lsm_fail(err, LSM_ERR_INPUT, out_dir, "exists and is not a folder");
    char old[4200];
    snprintf(old, sizeof old, "%s.old-XXXXXX", tmp);
    if (!mkdtemp(old)) return lsm_fail(err, LSM_ERR_IO, out_dir, "cannot replace: %s", strerror(errno));
    char old_out[4300];
    snprintf(old_out, sizeof old_out, "%s/previous", old);
    if (rename(out_dir, old_out) != 0) {
      remove_tree(old);
      return lsm_fail(err, LSM_ERR_IO, out_dir, "cannot replace: %s", strerror(errno));
    }
    if (rename(tmp, out_dir) != 0) {
      int e = errno;
      if (rename(old_out, out_dir) != 0) { /* keep the old result where it was */
      }
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

static lsm_status reconstruct(int argc, char **argv, lsm_cli *cli, lsm_err *err) {
  const double t_start = wall_seconds();
  png_source src = {NULL, 0, {cli->invert, cli->max_pixels}};
  double *z = NULL;
  size_t nz = 0;
  lsm_pair_stats *stats = NULL;
  out_sink sink;
  memset(&sink, 0, sizeof sink);
  char tmp[4096] = "";
  lsm_status st = lsm_dir_list_png(cli->slice_dir, &src.paths, &src.count, err);
  if (st == LSM_OK && src.count == 0)
    st = lsm_fail(err, LSM_ERR_INPUT, cli->slice_dir, "no PNG files in this folder");
  if (st == LSM_OK && src.count == 1)
    st = lsm_fail(err, LSM_ERR_INPUT, cli->slice_dir, "only one slice: need at least two to fill a gap");
  if (st == LSM_OK) {
    if (cli->heights_file) {
      st = lsm_heights_read(cli->heights_file, &z, &nz, err);
      if (st == LSM_OK && nz != src.count)
        st = lsm_fail(err, LSM_ERR_INPUT, cli->heights_file,
                      "%zu heights for %zu slices in %s", nz, src.count, cli->slice_dir);
    } else {
      z = lsm_alloc(src.count, sizeof *z, err, "heights");
      if (!z) st = err->status;
      for (size_t k = 0; z && k < src.count; ++k) z[k] = (double)k * cli->spacing;
    }
  }
  int width = 0, height = 0;
  if (st == LSM_OK) st = lsm_png_read_size(src.paths[0], &width, &height, err);
  if (st == LSM_OK && (uint64_t)width * (uint64_t)height > cli->max_pixels)
    st = lsm_fail(err, LSM_ERR_LIMIT, src.paths[0], "%dx%d pixels is more than --max-pixels %llu",
                  width, height, (unsigned long long)cli->max_pixels);
  const int threads = cli->threads > 0 ? cli->threads : omp_get_num_procs();
  cli->stack.morph.threads = threads;
  if (st == LSM_OK) {
    stats = calloc(src.count, sizeof *stats);
    sink.mask = malloc((size_t)width * (size_t)height);
    if (!stats || !sink.mask) st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the run");
  }
  if (st == LSM_OK) st = make_temp_dir(cli->out_dir, tmp, sizeof tmp, err);
  if (st == LSM_OK) {
    char path[4200];
    snprintf(sink.dir, sizeof sink.dir, "%s", tmp);
    sink.write_slices = cli->write_slices;
    const double pixel = cli->stack.pixel_size;
    const double dz = cli->stack.dz > 0 ? cli->stack.dz : pixel;
    snprintf(path, sizeof path, "%s/volume.nrrd", tmp);
    st = lsm_nrrd_open(path, width, height, pixel, pixel, dz, 0.0, 0.0, z[0], &sink.nrrd, err);
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
    lsm_slice_source source = {&src, src.count, z, png_load, png_name};
    lsm_slice_sink out = {&sink, sink_emit};
    st = lsm_stack_run(&source, width, height, &cli->stack, &out, stats,
                       cli->quiet ? NULL : &progress, err);
  }
  if (st == LSM_OK) {
    double sz = cli->stack.dz > 0 ? cli->stack.dz : cli->stack.pixel_size;
    if (cli->stack.per_iteration && sink.count > 1)
      sz = (sink.z_last - sink.z_first) / (double)(sink.count - 1);
    st = lsm_nrrd_finish(&sink.nrrd, sz, err);
  }
  if (sink.heights) {
    int bad = ferror(sink.heights);
    if (fclose(sink.heights) != 0 || bad)
      if (st == LSM_OK) st = lsm_fail(err, LSM_ERR_IO, "heights.txt", "write failed");
    sink.heights = NULL;
  }
  if (st == LSM_OK) {
    char path[4200];
    snprintf(path, sizeof path, "%s/run.json", tmp);
    st = write_run_json(path, argc, argv, cli, &src, z, width, height, &sink, stats, threads,
                        wall_seconds() - t_start, err);
  }
  if (st == LSM_OK) st = publish(tmp, cli->out_dir, err);
  if (st == LSM_OK) {
    if (!cli->quiet) {
      int capped = 0;
      for (size_t k = 0; k + 1 < src.count; ++k) capped += stats[k].hit_max_iter;
      if (capped)
        fprintf(stderr, "lsmorph: note: %d gaps stopped at --max-iter %d before finishing\n",
                capped, cli->stack.max_iter);
      fprintf(stderr, "lsmorph: wrote %zu slices to %s (volume.nrrd, heights.txt%s, run.json) in %.2f s\n",
              sink.count, cli->out_dir, cli->write_slices ? ", slices/" : "",
              wall_seconds() - t_start);
    }
  } else {
    lsm_nrrd_abort(&sink.nrrd);
    if (*tmp) remove_tree(tmp);
  }
  free(sink.mask);
  free(stats);
  free(z);
  lsm_path_list_free(src.paths, src.count);
  return st;
}

/* ---- score ------------------------------------------------------------------------------ */

static lsm_status score(const lsm_cli *cli, lsm_err *err) {
  char **truth = NULL;
  size_t n = 0;
  LSM_TRY(lsm_dir_list_png(cli->truth_dir, &truth, &n, err));
  lsm_png_read_opts ro = {0, (uint64_t)1 << 28};
  double dice = 0, hd95 = 0, msd = 0, vol_r = 0, vol_t = 0, inter = 0;
  size_t count = 0, incomparable = 0, pool_n = 0, pool_cap = 0;
  double *pool = NULL;
  lsm_status st = LSM_OK;
  const size_t last_input = (n - 1) / (size_t)cli->stride * (size_t)cli->stride;
  for (size_t k = 0; st == LSM_OK && k <= last_input && k < n; ++k) {
    if (k % (size_t)cli->stride == 0) continue;
    char path[4200];
    snprintf(path, sizeof path, "%s/slices/%05zu.png", cli->result_dir, k + 1);
    lsm_mask a = {0}, b = {0};
    st = lsm_png_read_mask(path, &ro, &a, err);
    if (st == LSM_OK) st = lsm_png_read_mask(truth[k], &ro, &b, err);
    lsm_slice_score s;
    if (st == LSM_OK) st = lsm_score_slice(&a, &b, &s, &pool, &pool_n, &pool_cap, err);
    if (st == LSM_OK) {
      dice += s.dice;
      vol_r += (double)s.area_result;
      vol_t += (double)s.area_truth;
      inter += s.dice * (double)(s.area_result + s.area_truth) / 2.0;
      if (s.comparable) {
        hd95 += s.hd95;
        msd += s.mean_surface;
      } else {
        incomparable++;
      }
      count++;
    }
    lsm_mask_free(&a);
    lsm_mask_free(&b);
  }
  lsm_path_list_free(truth, n);
  double pooled = lsm_quantile(pool, pool_n, 0.95);
  free(pool);
  if (st != LSM_OK) return st;
  size_t cmp = count - incomparable;
  printf("{\"held_out\": %zu, \"dice_volume\": %.6f, \"dice\": %.6f, \"hd95\": %.4f, "
         "\"hd95_pooled\": %.4f, \"mean_surface\": %.4f, \"volume_error\": %.6f, "
         "\"one_sided_empty\": %zu}\n",
         count, vol_r + vol_t > 0 ? 2.0 * inter / (vol_r + vol_t) : 1.0,
         count ? dice / (double)count : NAN, cmp ? hd95 / (double)cmp : NAN, pooled,
         cmp ? msd / (double)cmp : NAN, vol_t > 0 ? (vol_r - vol_t) / vol_t : NAN, incomparable);
  return LSM_OK;
}

int main(int argc, char **argv) {
  lsm_cli cli;
  lsm_err err;
  lsm_err_clear(&err);
  if (lsm_cli_parse(argc, argv, &cli, &err) != LSM_OK) {
    fprintf(stderr, "lsmorph: error: %s\n", err.msg);
    return 2;
  }
  lsm_status st = LSM_OK;
  switch (cli.command) {
  case LSM_CMD_HELP:
    lsm_cli_help(stdout, cli.help_topic);
    return 0;
  case LSM_CMD_VERSION:
    printf("lsmorph %s\n", LSM_VERSION);
    return 0;
  case LSM_CMD_RECONSTRUCT:
    st = reconstruct(argc, argv, &cli, &err);
    break;
  case LSM_CMD_SCORE:
    st = score(&cli, &err);
    break;
  default:
    lsm_cli_help(stderr, NULL);
    return 2;
  }
  if (st != LSM_OK) {
    fprintf(stderr, "lsmorph: error: %s\n", err.msg[0] ? err.msg : lsm_status_name(st));
    return st == LSM_ERR_USAGE ? 2 : 1;
  }
  return 0;
}
