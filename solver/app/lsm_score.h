/* lsm_score: the `score` command.  Compares a reconstruction made from some
 * slices of a full stack with the slices held out between them (Dice,
 * HD95, mean surface distance: lsm_metrics) and prints one JSON object on
 * stdout.  Which truth slices were the inputs comes from --stride and --first
 * or from the result's run.json. */
#ifndef LSM_SCORE_H
#define LSM_SCORE_H

#include "solver/app/lsm_cli.h"
#include "solver/base/lsm_status.h"

/* Scores cli->result_dir against cli->truth_dir; prints to stdout (the
 * caller checks that it was written). */
lsm_status lsm_score(const lsm_cli *cli, lsm_err *err);

#endif
