/* lsm_out_file: the OUT file of `lsmorph fill`, decided before any work.
 *
 * The result is written beside OUT as .NAME.tmp-TAG-XXXXXX (io/lsm_temp.h;
 * a detached .nhdr's data file likewise) and renamed into place when
 * complete (io/lsm_labels.h).  Before the work: a symbolic link is followed
 * to the file it names (a note says so; the link stays), one to nothing is
 * refused; a mount point (a file bound into a container) is refused, since
 * a rename cannot replace it; temporaries of runs that provably ended are
 * removed.  While the result is written, a second stop signal removes this
 * run's temporaries (lsm_out_file_abandon, a signal guard's clean-up).
 */
#ifndef LSM_OUT_FILE_H
#define LSM_OUT_FILE_H

#include <stdio.h>

#include "solver/base/lsm_status.h"

typedef struct lsm_out_file {
  char path[4096];   /* the file written: OUT, or the one its link names */
  char folder[4096]; /* the folder it lies in */
  char prefixes[3][300]; /* its temporaries: .NAME.tmp-, .NAME.raw.tmp-, .NAME.raw.gz.tmp- */
  char tag[64];      /* this process's tag (io/lsm_temp.h) */
} lsm_out_file;

/* Decides where OUT (out) is written, refusing a link to nothing and a mount
 * point; removes stale temporaries beside it.  Notes go to notes unless NULL. */
lsm_status lsm_out_file_check(lsm_out_file *o, const char *out, FILE *notes, lsm_err *err);

/* A signal guard's clean-up (ctx: the lsm_out_file): removes this process's
 * temporaries beside OUT. */
void lsm_out_file_abandon(void *ctx);

#endif
