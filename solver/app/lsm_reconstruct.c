#include "solver/app/lsm_reconstruct.h"

#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/lsm_io.h"
#include "io/lsm_labels.h"
#include "io/lsm_preview.h"
#include "io/lsm_slice_worker.h"
#include "solver/app/lsm_checks.h"
#include "solver/app/lsm_inputs.h"
#include "solver/app/lsm_out_dir.h"
#include "solver/app/lsm_outputs.h"
#include "solver/app/lsm_progress_bar.h"
#include "solver/app/lsm_run_json.h"
#include "solver/app/lsm_signals.h"
#include "solver/base/lsm_clock.h"
#include "solver/pde/lsm_backend.h"
#include "solver/recon/lsm_stack.h"

/* The run-wide settings: the thread count (--threads, or all cores), which the
 * loops without their own count (distance transforms, previews) follow too,
 * and the stop flag that long gaps poll.  Returns the thread count. */
static int setup_run(lsm_cli *cli) {
  const int threads = cli->threads > 0 ? cli->threads : omp_get_num_procs();
  cli->stack.morph.threads = threads;
  omp_set_num_threads(threads);
  cli->stack.morph.stop = lsm_signals_flag();
  return threads;
}

/* A numerical failure names the iteration; add the gap (the pair of input
 * files) it happened in: the last pair whose statistics the stack started. */
static void name_failed_pair(lsm_err *err, const lsm_slice_files *src,
                             const lsm_pair_stats *stats) {
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
  /* a smaller CFL number helps a morph that blew up, not a step that underflowed to 0 */
  const char *hint = strstr(what, "no longer finite") ? "; try a smaller --cfl" : "";
  if (n > 0 && (size_t)n < sizeof err->msg)
    snprintf(err->msg + n, sizeof err->msg - (size_t)n, "%s%s", what, hint);
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
 * i % size's) and sends them to rank 0, which reads the same input, checks
 * it, and writes everything.  A worker that fails before it has sent anything
 * (a --heights pipe that only rank 0 reads) sends the failure as its first
 * gap, which rank 0 waits for: rank 0 then reports it and ends the run. */
static lsm_status reconstruct_worker(lsm_cli *cli, const lsm_gap_transport *transport,
                                     lsm_err *err) {
  lsm_slice_files src = {NULL, 0, {cli->invert, cli->max_pixels, 0}, NULL};
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
    lsm_slice_files_free(&src);
    return LSM_OK;
  }
  if (st == LSM_OK) st = lsm_input_heights(cli, src.paths, src.count, &z, err);
  if (st == LSM_OK) st = lsm_slice_read_header(src.paths[0], 0, &width, &height, err);
  if (st == LSM_OK)
    st = lsm_pick_foreground(src.paths, src.count, &src.read, 1, cli->slice_dir, err);
  const int threads = setup_run(cli);
  if (st == LSM_OK) st = lsm_backend_open(cli->backend, cli->device, threads, &backend, err);
  if (st == LSM_OK) {
    cli->stack.morph.backend = backend;
    cli->stack.transport = &mine;
    stats = calloc(src.count, sizeof *stats);
    if (!stats) st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the run");
  }
  if (st == LSM_OK && !lsm_signals_caught()) lsm_signals_install(1);
  if (st == LSM_OK) {
    lsm_slice_source source = lsm_slice_files_source(&src, z);
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
  lsm_slice_files_free(&src);
  return st;
}

/* Rank 0's inputs, read and checked before any work: the slice files, their
 * heights z (malloc'd), OUT_DIR, the slice size and the foreground rule; then
 * the notes on inputs and options. */
static lsm_status read_inputs(const lsm_cli *cli, lsm_slice_files *src, double **z, int *width,
                              int *height, lsm_out_dir *out_dir, const char *const *names,
                              size_t n_names, lsm_err *err) {
  size_t others = 0;
  const lsm_status listed = lsm_dir_list_slices(cli->slice_dir, &src->paths, &src->count, &others, err);
  if (listed != LSM_OK && err && lsm_labels_format_of(cli->slice_dir) != LSM_LABELS_UNKNOWN) {
    const size_t used = strlen(err->msg); /* a label volume given where a folder goes */
    snprintf(err->msg + used, sizeof err->msg - used,
             " (a label volume? 'lsmorph fill %.200s -o OUT' fills the slices between its drawn "
             "ones)", cli->slice_dir);
  }
  LSM_TRY(listed);
  if (others && !cli->quiet)
    fprintf(stderr, "lsmorph: note: %s: %zu image file%s in another format than PNG or TIFF "
                    "(.jpg, .bmp, ...) left out: slices are read from PNG and TIFF files only\n",
            cli->slice_dir, others, others == 1 ? "" : "s");
  if (src->count == 0)
    return lsm_fail(err, LSM_ERR_INPUT, cli->slice_dir, "no PNG or TIFF files in this folder");
  if (src->count == 1)
    return lsm_fail(err, LSM_ERR_INPUT, cli->slice_dir,
                    "only one slice: need at least two to fill a gap");
  LSM_TRY(lsm_input_heights(cli, src->paths, src->count, z, err));
  LSM_TRY(lsm_out_dir_check(out_dir, cli->out_dir, names, n_names, cli->slice_dir,
                            cli->heights_file, cli->quiet ? NULL : stderr, err));
  LSM_TRY(lsm_check_inputs(cli, src, *z, width, height, err));
  LSM_TRY(lsm_pick_foreground(src->paths, src->count, &src->read, cli->quiet, cli->slice_dir,
                              err));
  if (!cli->quiet) {
    lsm_inputs_note(cli, src);
    lsm_cli_note_unused(cli, stderr);
  }
  return LSM_OK;
}

/* Opens the backend --backend asks for, and says where the work runs. */
static lsm_status open_backend(lsm_cli *cli, int threads, lsm_backend **backend, lsm_err *err) {
  LSM_TRY(lsm_backend_open(cli->backend, cli->device, threads, backend, err));
  cli->stack.morph.backend = *backend;
  if (!cli->quiet && strcmp(cli->backend, "c") != 0)
    fprintf(stderr, "lsmorph: backend %s: %s\n", lsm_backend_name(*backend),
            lsm_backend_device(*backend));
  /* auto fell back to C: say why, also when a --device given does not exist */
  if (!cli->quiet && lsm_backend_fallback(*backend)[0])
    fprintf(stderr, "lsmorph: note: --backend auto runs on C: %s\n",
            lsm_backend_fallback(*backend));
  return LSM_OK;
}

/* After publishing: notes on what the run did that may surprise, then what
 * was written where. */
static void report_result(const lsm_cli *cli, const lsm_slice_files *src, const double *z,
                          const lsm_outputs *out, const lsm_pair_stats *stats, double t_start) {
  int capped = 0;
  for (size_t k = 0; k + 1 < src->count; ++k) capped += stats[k].hit_max_iter;
  if (capped)
    fprintf(stderr, "lsmorph: note: %d gaps stopped at --max-iter %d before finishing\n", capped,
            cli->stack.max_iter);
  int tried = 0, took = 0;
  for (size_t k = 0; k + 1 < src->count; ++k) {
    tried += stats[k].motion_tests > 0;
    took += stats[k].motion_field;
  }
  if (cli->stack.motion == LSM_MOTION_AUTO && tried)
    fprintf(stderr,
            "lsmorph: note: --motion auto tried %d of %zu pairs by leaving their slices out; "
            "%d follow the correspondence field (run.json: pairs[].motion)\n",
            tried, src->count - 1, took);
  if (!lsm_outputs_evenly_spaced(out))
    fprintf(stderr,
            "lsmorph: note: the output slices are not evenly spaced (steps %.4g to %.4g); "
            "the volume files hold one z spacing, the mean (%.4g): heights.txt has each "
            "slice's height\n",
            out->step_min, out->step_max, lsm_outputs_mean_step(out));
  if (!cli->stack.per_iteration && src->count > 1 && out->count > 0) {
    /* the regular grid stops at the last step within the heights */
    const double dz = lsm_stack_output_dz(&cli->stack);
    const double top = z[src->count - 1], range = top - z[0], short_by = top - out->z_last;
    if (short_by > 1e-6 * dz) {
      const double steps = ceil(range / dz);
      char last[40], top_text[40], dz_text[40], range_text[40], fit[40];
      lsm_shortest_number(last, sizeof last, out->z_last); /* 1e6 - 4e-6 stays apart */
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
  size_t nfiles = lsm_output_file_names(cli, files, 16);
  fprintf(stderr, "lsmorph: wrote %zu slices to %s (", out->count, cli->out_dir);
  for (size_t k = 0; k < nfiles && k < 16; ++k) fprintf(stderr, "%s%s", k ? ", " : "", files[k]);
  fprintf(stderr, ") in %.2f s\n", lsm_clock_seconds() - t_start);
}

lsm_status lsm_reconstruct(int argc, char **argv, lsm_cli *cli, const lsm_mpi *mpi,
                           lsm_err *err) {
  if (lsm_mpi_rank(mpi) != 0) return reconstruct_worker(cli, lsm_mpi_transport(mpi), err);
  cli->stack.transport = lsm_mpi_transport(mpi);
  const double t_start = lsm_clock_seconds();
  lsm_slice_files src = {NULL, 0, {cli->invert, cli->max_pixels, 0}, NULL};
  double *z = NULL;
  int width = 0, height = 0;
  lsm_pair_stats *stats = NULL;
  lsm_backend *backend = NULL;
  lsm_outputs out;
  memset(&out, 0, sizeof out);
  lsm_out_dir out_dir;
  memset(&out_dir, 0, sizeof out_dir);
  lsm_signal_guard guard; /* a second Ctrl-C removes the temporary folder */
  memset(&guard, 0, sizeof guard);
  const char *names[16];
  const size_t n_names = lsm_output_file_names(cli, names, 16);
  lsm_status st = read_inputs(cli, &src, &z, &width, &height, &out_dir, names,
                              n_names < 16 ? n_names : 16, err);
  if (st == LSM_OK && !cli->quiet) src.blank = calloc(src.count, 1); /* for a note; optional */
  lsm_stack_opts_resolve(&cli->stack); /* run.json records what the run uses */
  const int threads = setup_run(cli);
  if (st == LSM_OK) st = open_backend(cli, threads, &backend, err);
  if (st == LSM_OK) { /* memory and disk: the gaps at once are known with the backend */
    char folder[4200];
    lsm_out_dir_temp_folder(&out_dir, folder, sizeof folder);
    st = lsm_check_resources(cli, &src, z, width, height, folder, err);
  }
  if (st == LSM_OK) {
    stats = calloc(src.count, sizeof *stats);
    if (!stats) st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the run");
  }
  if (st == LSM_OK && !lsm_signals_caught()) lsm_signals_install(1);
  if (st == LSM_OK) st = lsm_out_dir_begin(&out_dir, cli->quiet ? NULL : stderr, err);
  if (st == LSM_OK) st = lsm_signals_guard_start(&guard, lsm_out_dir_abandon, &out_dir, err);
  if (st == LSM_OK) st = lsm_outputs_open(&out, cli, out_dir.tmp, width, height, z[0], err);
  /* the 3D preview is drawn as the slices come when their heights are known ahead */
  if (st == LSM_OK && out.preview && !cli->stack.per_iteration)
    st = lsm_preview_expect(out.preview, z[0], z[src.count - 1], err);
  if (st == LSM_OK) {
    if (!cli->quiet)
      fprintf(stderr, "lsmorph: %zu slices of %dx%d from %s, method %s, %d threads\n", src.count,
              width, height, cli->slice_dir, lsm_method_name(cli->stack.method), threads);
    lsm_progress_bar bar;
    lsm_progress progress = lsm_progress_bar_start(&bar, t_start);
    lsm_slice_source source = lsm_slice_files_source(&src, z);
    lsm_slice_sink sink = lsm_outputs_sink(&out);
    /* the outputs are written on a thread of their own, while the solver goes on */
    lsm_slice_worker *writer = NULL;
    st = lsm_slice_worker_open(sink.emit, sink.ctx, width, height, (size_t)64 << 20, &writer, err);
    lsm_slice_sink queued = {writer, lsm_slice_worker_emit};
    lsm_slice_sink stoppable = lsm_signals_stoppable(&queued);
    if (st == LSM_OK)
      st = lsm_stack_run(&source, width, height, &cli->stack, &stoppable, stats,
                         cli->quiet ? NULL : &progress, err);
    st = lsm_slice_worker_close(&writer, st, err);
    if (st == LSM_ERR_NUMERIC) name_failed_pair(err, &src, stats);
  }
  st = lsm_outputs_finish(&out, st, err);
  if (st == LSM_OK) {
    char path[4200];
    snprintf(path, sizeof path, "%s/run.json", out_dir.tmp);
    const lsm_run_record run = {.argc = argc,
                                .argv = argv,
                                .cli = cli,
                                .input = &src,
                                .z = z,
                                .width = width,
                                .height = height,
                                .output = &out,
                                .stats = stats,
                                .threads = threads,
                                .backend = backend,
                                .wall_seconds = lsm_clock_seconds() - t_start};
    st = lsm_run_json_write(path, &run, err);
  }
  if (st == LSM_OK) st = lsm_signals_check(err); /* a signal now still means no result */
  if (st == LSM_OK) st = lsm_out_dir_publish(&out_dir, err);
  if (st == LSM_OK && !cli->quiet) lsm_inputs_note_blank(&src, cli->slice_dir);
  if (st == LSM_OK && !cli->quiet) report_result(cli, &src, z, &out, stats, t_start);
  lsm_outputs_free(&out); /* before a failed run's folder is removed */
  if (st != LSM_OK) lsm_out_dir_discard(&out_dir, err);
  lsm_signals_guard_stop(&guard);
  lsm_out_dir_free(&out_dir);
  lsm_backend_close(&backend);
  free(stats);
  free(z);
  lsm_slice_files_free(&src);
  return st;
}
