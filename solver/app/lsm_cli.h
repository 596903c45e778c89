/* lsm_cli: the command line of lsmorph, parsed into plain options, and its
 * help.  Kept apart from main() so tests and the fuzzer can drive it directly.
 * Each option of reconstruct is one row of a table (lsm_cli.c) that both the
 * parser and the help read; a choice's names come from its enum's list
 * (solver/base/lsm_names.h). */
#ifndef LSM_CLI_H
#define LSM_CLI_H

#include <stdint.h>
#include <stdio.h>

#include "io/lsm_io.h"
#include "solver/base/lsm_names.h"
#include "solver/base/lsm_status.h"
#include "solver/pde/lsm_backend.h"
#include "solver/recon/lsm_stack.h"

#define LSM_VERSION "0.1.0"

typedef enum lsm_command {
  LSM_CMD_NONE = 0,
  LSM_CMD_HELP,
  LSM_CMD_VERSION,
  LSM_CMD_RECONSTRUCT,
  LSM_CMD_SCORE,
  LSM_CMD_DEVICES
} lsm_command;

/* --nrrd-encoding; add new items at the end (lsm_names.h). */
#define LSM_NRRD_ENCODING_LIST(X)                                               \
  X(LSM_NRRD_RAW, "raw")   /* the samples as they are */                        \
  X(LSM_NRRD_GZIP, "gzip") /* one gzip stream: NRRD's standard encoding gzip */
LSM_ENUM(lsm_nrrd_encoding, LSM_NRRD, LSM_NRRD_ENCODING_LIST, lsm_nrrd_encoding_name,
         lsm_nrrd_encoding_from_name);

typedef struct lsm_cli {
  lsm_command command;
  const char *help_topic;    /* topic whose help was asked, or NULL */
  /* reconstruct */
  const char *slice_dir;
  const char *out_dir;
  const char *heights_file;  /* --heights */
  int heights_from_names;    /* --heights-from-names: the numbers the names end with */
  double spacing;            /* --spacing (uniform heights) */
  int invert;
  int quiet;
  int threads;               /* 0 = all cores */
  uint64_t max_pixels;       /* per slice */
  uint64_t max_voxels;       /* output volume (checked as written with --per-iteration) */
  uint64_t max_memory;       /* bytes the run is estimated to need (0: what is available) */
  int write_slices;          /* PNG masks of every output slice */
  const char *backend;       /* --backend NAME: a row of lsm_backend.h's table, or "auto" (default "c") */
  int device;                /* --device N (-1: first GPU, else first device) */
  unsigned formats;          /* --format: set of LSM_FORMAT_* bits (io/lsm_io.h) */
  lsm_values values;         /* --values */
  lsm_nrrd_encoding nrrd_encoding;
  int nrrd_encoding_given;
  int mesh;                  /* --mesh: write surface.ply */
  int preview;               /* preview.png and preview3d.png (--no-preview: 0) */
  lsm_stack_opts stack;
  int interp_given, ends_given, motion_given; /* --interp / --ends / --motion given */
  /* options given that may not apply to the run (a note then says so): the
   * first solver option (--scheme, --time, --cfl, --max-iter, --reinit-*), the
   * first particle option (--particles-per-cell, --pls-*, --seed) */
  const char *solver_option, *pls_option;
  int tol_given, device_given, spacing_given;
  /* score */
  const char *truth_dir;
  const char *result_dir;
  int stride;                /* score: input slices were every stride-th (0: from run.json) */
  long first;                /* score: the first input is this truth slice (from 1; 0: not given) */
  int per_slice;             /* score --per-slice: each held-out slice's scores too */
} lsm_cli;

/* Parses argv (argv[0] is the program).  Returns LSM_OK, or LSM_ERR_USAGE
 * with a message in err. */
lsm_status lsm_cli_parse(int argc, char **argv, lsm_cli *cli, lsm_err *err);

/* Prints the help text for a topic (NULL: general) to f. */
void lsm_cli_help(FILE *f, const char *topic);

/* Notes (one line each) on options given that have no effect in this run, or
 * may not do what was meant (--cfl above 1). */
void lsm_cli_note_unused(const lsm_cli *cli, FILE *f);

#endif
