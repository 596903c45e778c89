/* lsm_out_dir: OUT_DIR, the folder a reconstruction is published to.
 *
 * This module is the only one that touches OUT_DIR itself.  Before any work
 * it decides how OUT_DIR will be written, or refuses with the reason:
 *
 *   new        no such folder yet: the result is written into a temporary
 *              folder OUT_DIR.tmp-TAG-XXXXXX beside it (io/lsm_temp.h) and
 *              renamed to OUT_DIR when complete;
 *   replace    an empty folder, or provably an earlier lsmorph result (its
 *              run.json is lsmorph's and it holds nothing lsmorph does not
 *              write): the complete result is exchanged with it atomically;
 *   in place   a folder that cannot be renamed (a mount point, the current
 *              folder or one holding it, a folder in a parent that cannot be
 *              written): the result is written into OUT_DIR/.lsmorph.tmp-TAG-
 *              XXXXXX and its files and folders are moved into OUT_DIR one by
 *              one, each atomically, run.json last; entries lsmorph does not
 *              write are left alone, and a name this run writes is replaced
 *              only where it belongs to an earlier result.
 *
 * A symbolic link to a folder is followed (a note says so: the link stays);
 * one to nothing is refused.  Nothing else of the user's is ever deleted: on
 * failure the temporary folder is removed and an earlier result stays as it
 * was.  Temporary folders of earlier runs that provably ended (killed, a
 * power cut) are removed when the next run begins.
 */
#ifndef LSM_OUT_DIR_H
#define LSM_OUT_DIR_H

#include <pthread.h>
#include <stddef.h>
#include <stdio.h>

#include "solver/base/lsm_status.h"

typedef enum lsm_out_mode {
  LSM_OUT_NEW,
  LSM_OUT_REPLACE,
  LSM_OUT_IN_PLACE,
  LSM_OUT_REFUSE
} lsm_out_mode;

/* What is known of OUT_DIR before deciding (lsm_out_dir_decide). */
typedef struct lsm_out_facts {
  int exists;        /* the path (or what its link names) exists */
  int link;          /* the path is a symbolic link */
  int folder;        /* what it names is a folder */
  int mount_point;   /* ... the root of a mounted file system */
  int holds_cwd;     /* ... the current folder, or a folder that holds it */
  int parent_locked; /* ... in a parent folder that cannot be written (it can) */
} lsm_out_facts;

/* How OUT_DIR is to be written; *why: the reason, for a note or an error
 * (NULL for new and replace). */
lsm_out_mode lsm_out_dir_decide(const lsm_out_facts *f, const char **why);

typedef struct lsm_out_dir {
  const char *given;        /* OUT_DIR as given */
  char path[4096];          /* the folder written: OUT_DIR, or the one its link names */
  lsm_out_mode mode;
  int earlier;              /* it holds an earlier lsmorph result */
  const char *const *names; /* the entries this run writes ("slices/": a folder) */
  size_t n_names;
  char tmp[4096];           /* the temporary folder being filled; "" before lsm_out_dir_begin */
  char tag[64];             /* this process's tag in its name (io/lsm_temp.h) */
  pthread_mutex_t lock;     /* publishing and a signal guard's clean-up exclude each other */
  int lock_ready, published;
} lsm_out_dir;

/* Decides how OUT_DIR (out_dir) will be written, before any work, and
 * refuses what would lose data or fail only after the work: OUT_DIR must not
 * be, hold, or (in place) be replaced over the input folder or the heights
 * file (may be NULL).  names (n_names): the entries this run writes
 * (lsm_output_file_names).  Notes (a link followed, writing in place) go to
 * notes unless it is NULL. */
lsm_status lsm_out_dir_check(lsm_out_dir *o, const char *out_dir, const char *const *names,
                             size_t n_names, const char *slice_dir, const char *heights_file,
                             FILE *notes, lsm_err *err);

/* The folder the temporary folder goes in (OUT_DIR's parent, or OUT_DIR
 * itself in place): where the disk space is taken. */
void lsm_out_dir_temp_folder(const lsm_out_dir *o, char *folder, size_t cap);

/* Removes the temporary folders of earlier runs that provably ended (a note
 * names them, and those that cannot be shown to have ended), then creates
 * the temporary folder, with the permissions of a new folder. */
lsm_status lsm_out_dir_begin(lsm_out_dir *o, FILE *notes, lsm_err *err);

/* Moves the finished temporary folder's result into place. */
lsm_status lsm_out_dir_publish(lsm_out_dir *o, lsm_err *err);

/* A signal guard's clean-up (ctx: the lsm_out_dir): removes the temporary
 * folder unless the result was published; safe while other threads write. */
void lsm_out_dir_abandon(void *ctx);

/* After a failure: removes the temporary folder, and names the files of a
 * message about it under OUT_DIR, where the user will look for them. */
void lsm_out_dir_discard(lsm_out_dir *o, lsm_err *err);

/* Whether real (a resolved path) is the root of a mount: a folder on another
 * device than its parent, the root itself, or a mount point of this process
 * (a bind mount of a folder or a file, as a container's -v makes). */
int lsm_is_mount_point(const char *real);

/* The notes on a sweep of dir's stale temporaries (io/lsm_temp.h; what:
 * "folder" or "file"): those removed, and those left that cannot be shown
 * stale.  Nothing when notes is NULL. */
struct lsm_temp_sweep_result;
void lsm_temp_sweep_note(FILE *notes, const char *dir, const char *what,
                         const struct lsm_temp_sweep_result *r);

/* Frees what lsm_out_dir_check set up. */
void lsm_out_dir_free(lsm_out_dir *o);

#endif
