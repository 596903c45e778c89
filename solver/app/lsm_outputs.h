/* lsm_outputs: the files of a reconstruction, written into a folder as the
 * stack driver emits its output slices: volume.<ext> in every --format,
 * heights.txt, slices/, surface.ply (--mesh) and the previews.  (run.json is
 * lsm_run_json's; the folder is lsm_out_dir's.) */
#ifndef LSM_OUTPUTS_H
#define LSM_OUTPUTS_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "io/lsm_io.h"
#include "io/lsm_mesh.h"
#include "io/lsm_preview.h"
#include "solver/app/lsm_cli.h"
#include "solver/base/lsm_status.h"
#include "solver/recon/lsm_stack.h"

typedef struct lsm_outputs {
  char dir[4096];
  int write_slices;          /* slices/00001.png ... */
  lsm_volume_writer *volume; /* every --format */
  lsm_mesh *mesh;            /* --mesh */
  lsm_preview *preview;      /* unless --no-preview */
  FILE *heights;             /* heights.txt */
  uint8_t *mask;             /* one slice's PNG mask */
  uint64_t max_voxels;       /* --max-voxels: with --per-iteration checked only here */
  const char *input;         /* the slice folder, named in that error */
  int per_iteration;
  double dz;                 /* the output step (per_iteration: unused) */
  /* what has been written (read these; run.json and the notes report them) */
  size_t count;
  double z_first, z_last;
  double step_min, step_max; /* between consecutive output slices */
} lsm_outputs;

/* Opens every output file in dir for width x height slices, the first at
 * height z0, as cli asks. */
lsm_status lsm_outputs_open(lsm_outputs *o, const lsm_cli *cli, const char *dir, int width,
                            int height, double z0, lsm_err *err);

/* The sink that writes each output slice to every open file. */
lsm_slice_sink lsm_outputs_sink(lsm_outputs *o);

/* Ends the files after the run (status st): completes the volumes, the mesh
 * and the previews when st is LSM_OK, closes heights.txt.  Returns st, or the
 * first failure. */
lsm_status lsm_outputs_finish(lsm_outputs *o, lsm_status st, lsm_err *err);

/* Frees everything; after a failure also closes unfinished volume files. */
void lsm_outputs_free(lsm_outputs *o);

/* The mean step between output heights (0 for fewer than two slices). */
double lsm_outputs_mean_step(const lsm_outputs *o);

/* Whether the output heights are evenly spaced (always but with
 * --per-iteration, whose pairs each have their own iteration count). */
int lsm_outputs_evenly_spaced(const lsm_outputs *o);

/* The names of the files cli writes to OUT_DIR (folders end in '/'), in the
 * order they are listed; returns how many, storing at most cap. */
size_t lsm_output_file_names(const lsm_cli *cli, const char **names, size_t cap);

/* Every name reconstruct writes to OUT_DIR with some options (every format,
 * slices, mesh, previews). */
size_t lsm_output_known_names(const char **names, size_t cap);

#endif
