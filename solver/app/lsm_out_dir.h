/* lsm_out_dir: OUT_DIR, the folder a reconstruction is published to.
 *
 * This module is the only one that touches OUT_DIR itself.  Before any work it
 * checks that OUT_DIR may be replaced; the result is written into a temporary
 * folder OUT_DIR.tmp-XXXXXX beside it and moved into place only when complete
 * (an earlier result is swapped out atomically where the system allows); on
 * failure the temporary folder is removed and an earlier result stays as it
 * was. */
#ifndef LSM_OUT_DIR_H
#define LSM_OUT_DIR_H

#include <stddef.h>

#include "solver/base/lsm_status.h"

typedef struct lsm_out_dir {
  const char *path; /* OUT_DIR as given */
  char tmp[4096];   /* the temporary folder being filled; "" before lsm_out_dir_begin */
} lsm_out_dir;

/* Whether OUT_DIR may be replaced, checked before any work: when it exists it
 * must be a folder that neither is nor contains the input folder or the
 * heights file (may be NULL), and that is empty or an earlier result. */
lsm_status lsm_out_dir_check(const char *out_dir, const char *slice_dir, const char *heights_file,
                             lsm_err *err);

/* Creates the temporary folder beside out_dir (in o->tmp), with the
 * permissions of a new folder. */
lsm_status lsm_out_dir_begin(lsm_out_dir *o, const char *out_dir, lsm_err *err);

/* Moves the finished temporary folder to OUT_DIR, replacing an earlier result. */
lsm_status lsm_out_dir_publish(lsm_out_dir *o, lsm_err *err);

/* After a failure: removes the temporary folder, and names the files of a
 * message about it under OUT_DIR, where the user will look for them. */
void lsm_out_dir_discard(lsm_out_dir *o, lsm_err *err);

#endif
