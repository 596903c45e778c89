/* lsm_run_json: run.json, the record of a reconstruction: the version and
 * command line, the backend, the options the run used, the input slices, the
 * output, each gap's solver statistics, totals and the work of each process.
 * Its fields are a contract (scripts and `lsmorph score` read them): add to
 * them, never rename or remove one. */
#ifndef LSM_RUN_JSON_H
#define LSM_RUN_JSON_H

#include "solver/app/lsm_cli.h"
#include "solver/app/lsm_inputs.h"
#include "solver/app/lsm_outputs.h"
#include "solver/base/lsm_status.h"
#include "solver/pde/lsm_backend.h"
#include "solver/recon/lsm_stack.h"

/* What a finished run reports. */
typedef struct lsm_run_record {
  int argc;
  char **argv;
  const lsm_cli *cli;            /* its stack options resolved (lsm_stack_opts_resolve) */
  const lsm_slice_files *input;
  const double *z;               /* input heights, input->count of them */
  int width, height;             /* slice size */
  const lsm_outputs *output;
  const lsm_pair_stats *stats;   /* input->count - 1 gaps */
  int threads;
  const lsm_backend *backend;
  double wall_seconds;           /* the whole run so far */
} lsm_run_record;

/* Writes run.json to path. */
lsm_status lsm_run_json_write(const char *path, const lsm_run_record *run, lsm_err *err);

#endif
