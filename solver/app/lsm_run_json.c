#include "solver/app/lsm_run_json.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "io/lsm_io.h"

static const char *json_bool(int value) { return value ? "true" : "false"; }

/* "backend": where the grid work ran: its name and the facts it reports (every backend:
 * device, build_seconds, kernel_cache_hit). */
static void write_backend(FILE *f, const lsm_backend *backend) {
  fputs("  \"backend\": {\"name\": ", f);
  lsm_json_string(f, lsm_backend_name(backend));
  lsm_backend_fact facts[LSM_BACKEND_FACTS_MAX];
  const int n = lsm_backend_facts(backend, facts, LSM_BACKEND_FACTS_MAX);
  for (int k = 0; k < n; ++k) {
    fprintf(f, ", \"%s\": ", facts[k].key);
    if (facts[k].kind == LSM_FACT_TEXT)
      lsm_json_string(f, facts[k].text);
    else if (facts[k].kind == LSM_FACT_NUMBER)
      lsm_json_number(f, facts[k].number);
    else
      fputs(json_bool(facts[k].flag), f);
  }
  fputs("},\n", f);
}

/* "options": every option as the run used it. */
static void write_options(FILE *f, const lsm_run_record *run) {
  const lsm_cli *cli = run->cli;
  const lsm_stack_opts *o = &cli->stack;
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
  fputs(", \"motion\": ", f);
  lsm_json_string(f, lsm_motion_name(o->motion));
  fputs(", \"interp\": ", f);
  lsm_json_string(f, lsm_interp_name(o->interp));
  fputs(", \"ends\": ", f);
  lsm_json_string(f, lsm_end_rule_name(o->ends));
  fputs(", \"rules_off\": [", f);
  for (int r = 0, n = 0; r < LSM_RULE_COUNT; ++r)
    if (!lsm_rule_on(&o->rules, (lsm_rule)r)) {
      if (n++) fputs(", ", f);
      lsm_json_string(f, lsm_rule_name((lsm_rule)r));
    }
  fputs("]", f);
  fputs(", \"cfl\": ", f);
  lsm_json_number(f, o->morph.cfl);
  /* as the run used it: per-iteration mode runs the full grid */
  fprintf(f, ", \"band\": \"%s\"", o->morph.band && !o->per_iteration ? "on" : "off");
  fprintf(f, ", \"reinit_every\": %d, \"reinit_iters\": %d, \"tol\": ", o->morph.reinit_every,
          o->morph.reinit_iters);
  lsm_json_number(f, o->tol);
  fprintf(f, ", \"max_iter\": %d, \"per_iteration\": %s, \"pixel_size\": ", o->max_iter,
          json_bool(o->per_iteration));
  lsm_json_number(f, o->pixel_dx);
  fputs(", \"pixel_size_y\": ", f);
  lsm_json_number(f, o->pixel_dy);
  fputs(", \"dz\": ", f);
  lsm_json_number(f, lsm_stack_output_dz(o));
  fprintf(f, ", \"invert\": %s, \"heights_from_names\": %s, \"threads\": %d, \"values\": ",
          json_bool(cli->invert), json_bool(cli->heights_from_names), run->threads);
  lsm_json_string(f, lsm_values_name(cli->values));
  fputs(", \"formats\": [", f);
  int listed = 0;
  for (unsigned bit = 1; bit <= LSM_FORMAT_ALL; bit <<= 1) {
    if (!(cli->formats & bit)) continue;
    if (listed++) fputs(", ", f);
    lsm_json_string(f, lsm_format_name(bit));
  }
  const lsm_pls_opts *pls = &o->morph.pls;
  fprintf(f, "], \"nrrd_encoding\": \"%s\", \"mesh\": %s, \"preview\": %s, "
          "\"particles_per_cell\": %d, \"pls_reseed\": %d, \"pls_radius_adjust\": %s, "
          "\"seed\": %" PRIu64 "},\n",
          lsm_nrrd_encoding_name(cli->nrrd_encoding), json_bool(cli->mesh),
          json_bool(cli->preview), pls->particles_per_cell, pls->reseed_every,
          json_bool(pls->radius_adjust), pls->seed);
}

/* "input": the slice files and their heights; "output": what was written. */
static void write_input_output(FILE *f, const lsm_run_record *run) {
  const lsm_slice_files *src = run->input;
  const lsm_outputs *out = run->output;
  fputs("  \"input\": {\"folder\": ", f);
  lsm_json_string(f, run->cli->slice_dir);
  fprintf(f, ", \"slices\": %zu, \"width\": %d, \"height\": %d, \"files\": [", src->count,
          run->width, run->height);
  for (size_t k = 0; k < src->count; ++k) {
    if (k) fputs(", ", f);
    lsm_json_string(f, lsm_base_name(src->paths[k]));
  }
  fputs("], \"heights\": [", f);
  for (size_t k = 0; k < src->count; ++k) {
    if (k) fputs(", ", f);
    lsm_json_number(f, run->z[k]);
  }
  fprintf(f, "]},\n  \"output\": {\"slices\": %zu, \"first_height\": ", out->count);
  lsm_json_number(f, out->z_first);
  fputs(", \"last_height\": ", f);
  lsm_json_number(f, out->z_last);
  fprintf(f, ", \"evenly_spaced\": %s", json_bool(lsm_outputs_evenly_spaced(out)));
  fputs(", \"files\": [", f);
  const char *files[16];
  size_t nfiles = lsm_output_file_names(run->cli, files, 16);
  for (size_t k = 0; k < nfiles && k < 16; ++k) {
    if (k) fputs(", ", f);
    lsm_json_string(f, files[k]);
  }
  fputs("]},\n", f);
}

/* "pairs": each gap's statistics; "totals"; "ranks": each process's gaps. */
static void write_pairs(FILE *f, const lsm_run_record *run) {
  const lsm_slice_files *src = run->input;
  const lsm_pair_stats *stats = run->stats;
  const lsm_stack_opts *o = &run->cli->stack;
  fputs("  \"pairs\": [\n", f);
  long long iterations = 0, updates = 0, full = 0;
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
    const long long stages = lsm_time_stages(o->morph.time);
    const long long pair_full = (long long)p->iterations * p->cells * stages;
    fprintf(f, ", \"cells\": %lld, \"cell_updates\": %lld, \"band_share\": ", p->cells,
            p->cell_updates);
    lsm_json_number(f, pair_full > 0 ? (double)p->cell_updates / (double)pair_full : NAN);
    fputs(", \"t_final\": ", f);
    lsm_json_number(f, p->t_final);
    fprintf(f, ", \"slices\": %zu, \"hit_max_iter\": %s, \"rank\": %d", p->slices,
            json_bool(p->hit_max_iter), p->rank);
    fprintf(f, ", \"aligned\": %s, \"moving_parts\": %d", json_bool(p->aligned),
            p->moving_parts);
    if (o->motion != LSM_MOTION_NONE) {
      fputs(", \"motion\": {\"max_displacement\": ", f);
      lsm_json_number(f, p->motion_max_px);
      fprintf(f, ", \"registration_iterations\": %d, \"registration_seconds\": ",
              p->motion_iterations);
      lsm_json_number(f, p->motion_seconds);
      fprintf(f, ", \"field\": %s", json_bool(p->motion_field));
      if (o->motion == LSM_MOTION_AUTO)
        fprintf(f, ", \"left_out\": %d, \"missed_with_field\": %lld, \"missed_in_place\": %lld",
                p->motion_tests, p->motion_missed_field, p->motion_missed_in_place);
      fputs("}", f);
    }
    if (o->method == LSM_METHOD_PLS) {
      fprintf(f, ", \"particles\": {\"seeded\": %lld, \"discarded\": %lld, \"escaped_per_step\": ",
              p->pls_seeded, p->pls_discarded);
      lsm_json_number(f, p->pls_steps ? (double)p->pls_escaped / (double)p->pls_steps : 0.0);
      fprintf(f, ", \"escaped\": %lld, \"corrected\": %lld, \"steps\": %lld}", p->pls_escaped,
              p->pls_corrected, p->pls_steps);
    }
    fprintf(f, "}%s\n", k + 2 < src->count ? "," : "");
    iterations += p->iterations;
    updates += p->cell_updates;
    full += pair_full;
    seconds += p->seconds;
  }
  fprintf(f, "  ],\n  \"totals\": {\"pairs\": %zu, \"iterations\": %lld, \"seconds\": ",
          src->count - 1, iterations);
  lsm_json_number(f, seconds);
  fputs(", \"wall_seconds\": ", f);
  lsm_json_number(f, run->wall_seconds);
  fprintf(f, ", \"cell_updates\": %lld, \"cells_per_second\": ", updates);
  lsm_json_number(f, seconds > 0 ? (double)updates / seconds : NAN);
  fputs(", \"band_share\": ", f);
  lsm_json_number(f, full > 0 ? (double)updates / (double)full : NAN);
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
  fputs("]\n", f);
}

lsm_status lsm_run_json_write(const char *path, const lsm_run_record *run, lsm_err *err) {
  FILE *f = fopen(path, "w");
  if (!f) return lsm_fail(err, LSM_ERR_IO, path, "cannot create: %s", strerror(errno));
  fprintf(f, "{\n  \"lsmorph_version\": \"%s\",\n  \"command\": [", LSM_VERSION);
  for (int k = 0; k < run->argc; ++k) {
    if (k) fputs(", ", f);
    lsm_json_string(f, run->argv[k]);
  }
  fputs("],\n", f);
  write_backend(f, run->backend);
  write_options(f, run);
  write_input_output(f, run);
  write_pairs(f, run);
  fputs("}\n", f);
  const int bad = ferror(f), closed = fclose(f);
  if (bad || closed != 0)
    return lsm_fail(err, LSM_ERR_IO, path, "write failed: %s",
                    closed != 0 ? strerror(errno) : "stream error");
  return LSM_OK;
}
