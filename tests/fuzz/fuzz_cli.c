/* libFuzzer harness for the command-line parser (lsm_cli_parse, solver/app/lsm_cli.c).
 *
 * The input is split at NUL bytes into arguments (at most 64), after a fixed
 * argv[0] "lsmorph".  Checks: every status is OK or a usage error with a
 * message; a parsed reconstruct or score command has the fields its command
 * needs and option values in range; the help text for the parsed topic can
 * be printed. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "solver/app/lsm_cli.h"

#define MAX_ARGS 64

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *buf = malloc(size + 1);
  if (!buf) abort();
  if (size) memcpy(buf, data, size);
  buf[size] = '\0';
  char *argv[MAX_ARGS + 2];
  int argc = 0;
  argv[argc++] = (char *)"lsmorph";
  size_t start = 0;
  for (size_t k = 0; k <= size && argc <= MAX_ARGS; ++k) {
    if (buf[k] != '\0') continue;
    if (!(k == size && start == size)) argv[argc++] = buf + start; /* no empty tail argument */
    start = k + 1;
  }
  argv[argc] = NULL;

  lsm_cli cli;
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = lsm_cli_parse(argc, argv, &cli, &err);
  if (st != LSM_OK) {
    if (st != LSM_ERR_USAGE || err.status != st || err.msg[0] == '\0') abort();
  } else {
    switch (cli.command) {
    case LSM_CMD_HELP: {
      FILE *devnull = fopen("/dev/null", "w");
      if (devnull) {
        lsm_cli_help(devnull, cli.help_topic);
        fclose(devnull);
      }
      break;
    }
    case LSM_CMD_VERSION:
    case LSM_CMD_DEVICES:
      break;
    case LSM_CMD_RECONSTRUCT: {
      const lsm_stack_opts *o = &cli.stack;
      if (!cli.slice_dir || !cli.out_dir) abort();
      if (!(cli.spacing > 0) || !isfinite(cli.spacing)) abort();
      if (!(o->pixel_dx > 0) || !isfinite(o->pixel_dx)) abort();
      if (!(o->pixel_dy > 0) || !isfinite(o->pixel_dy)) abort();
      if (o->dz < 0 || !isfinite(o->dz)) abort();
      if (!(o->morph.cfl > 0) || !isfinite(o->morph.cfl)) abort();
      if (!(o->tol > 0) || !isfinite(o->tol)) abort();
      if (o->max_iter < 1 || cli.threads < 0 || cli.max_pixels == 0) abort();
      if (o->method <= LSM_METHOD_UNKNOWN || o->method >= LSM_METHOD_COUNT) abort();
      if (o->input <= LSM_INPUT_UNKNOWN || o->input >= LSM_INPUT_COUNT) abort();
      if (o->align <= LSM_ALIGN_UNKNOWN || o->align >= LSM_ALIGN_COUNT) abort();
      if (o->interp <= LSM_INTERP_UNKNOWN || o->interp >= LSM_INTERP_COUNT) abort();
      if (o->per_iteration && o->method == LSM_METHOD_BLEND) abort();
      break;
    }
    case LSM_CMD_SCORE:
      /* --stride is optional (0: the count comes from run.json), else 2 to 1000000 */
      if (!cli.truth_dir || !cli.result_dir || !*cli.truth_dir || !*cli.result_dir) abort();
      if (cli.stride != 0 && (cli.stride < 2 || cli.stride > 1000000)) abort();
      if (cli.first < 0 || cli.first > 1000000000) abort();
      break;
    default:
      abort();
    }
  }
  free(buf);
  return 0;
}
