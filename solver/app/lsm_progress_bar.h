/* lsm_progress_bar: a run's progress on stderr: a bar redrawn in place on a
 * terminal (with the pair --motion auto is trying, while it tries), else a
 * line every 10 %. */
#ifndef LSM_PROGRESS_BAR_H
#define LSM_PROGRESS_BAR_H

#include "solver/recon/lsm_stack.h"

typedef struct lsm_progress_bar {
  int tty;            /* stderr is a terminal */
  int last_percent;   /* the last percentage shown (-1: none yet) */
  double start;       /* lsm_clock_seconds() when the run began */
  size_t done, total; /* the last slice count shown */
} lsm_progress_bar;

/* The progress callback of a run that began at start (lsm_clock_seconds);
 * *bar holds its state and must outlive the run. */
lsm_progress lsm_progress_bar_start(lsm_progress_bar *bar, double start);

#endif
