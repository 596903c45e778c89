/* lsm_reconstruct: the `reconstruct` command.  Reads and checks the input
 * slices (lsm_inputs, lsm_checks, lsm_out_dir), runs the stack driver on the
 * chosen backend, writes the outputs (lsm_outputs, lsm_run_json) into a
 * temporary folder and publishes it as OUT_DIR (lsm_out_dir).  Under MPI, rank
 * 0 does all that and the other ranks compute their share of the gaps. */
#ifndef LSM_RECONSTRUCT_H
#define LSM_RECONSTRUCT_H

#include "solver/app/lsm_cli.h"
#include "solver/app/lsm_mpi.h"
#include "solver/base/lsm_status.h"

/* Runs the command cli describes (argv is recorded in run.json); cli's stack
 * options are resolved and completed with the run's threads and backend. */
lsm_status lsm_reconstruct(int argc, char **argv, lsm_cli *cli, const lsm_mpi *mpi, lsm_err *err);

#endif
