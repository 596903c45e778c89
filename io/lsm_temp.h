/* lsm_temp: temporary files and folders that say who made them.
 *
 * A result is written beside its final place under a temporary name and
 * moved there when complete.  A run that ends abruptly (SIGKILL, a power
 * cut) leaves that temporary behind; a later run removes it only when it can
 * prove that its maker has ended.  The proof is carried in the name:
 *
 *     PREFIX<pid>.<start>.<machine>-XXXXXX
 *
 * pid and start (the process's start time in clock ticks after boot,
 * /proc/PID/stat) name one process for the life of the running kernel
 * whatever pid reuse does; machine (16 hex digits) hashes the kernel's boot
 * id and the process's pid namespace, so that only a run on the same running
 * kernel, looking at the same pids, judges it.  A temporary of another
 * machine on a shared file system, of another container, of a boot before,
 * or named by an older lsmorph is never removed.  Where the system does not
 * give these facts (no /proc) the tag is empty: PREFIX-XXXXXX, never removed
 * by another run.
 */
#ifndef LSM_TEMP_H
#define LSM_TEMP_H

#include <stddef.h>

#include "solver/base/lsm_status.h"

/* Room for a tag ("<pid>.<start>.<16 hex>") and its terminating NUL. */
#define LSM_TEMP_TAG_MAX 64

/* This process's tag into tag (LSM_TEMP_TAG_MAX bytes); "" where the system
 * does not say (then nothing this process makes can be shown stale later). */
void lsm_temp_tag(char tag[LSM_TEMP_TAG_MAX]);

/* The tag of a temporary's name (the part after prefix), "" when the name is
 * not PREFIX<tag>-XXXXXX exactly (six letters or digits, nothing after).
 * Returns 1 when name has that form, else 0. */
int lsm_temp_name_tag(const char *name, const char *prefix, char tag[LSM_TEMP_TAG_MAX]);

/* Whether the maker of a temporary with this tag has provably ended: the tag
 * is of this machine (same running kernel and pid namespace) and its pid is
 * gone, a zombie, or a process that started at another time. */
int lsm_temp_owner_ended(const char *tag);

/* Makes path into "<stem><tag>-XXXXXX" (stem: the folder and PREFIX) with
 * this process's tag; fails (LSM_ERR_INPUT) when it would not fit cap or
 * would make a name longer than 255 bytes. */
lsm_status lsm_temp_template(char *path, size_t cap, const char *stem, lsm_err *err);

/* What a sweep did. */
typedef struct lsm_temp_sweep_result {
  size_t removed;       /* temporaries removed */
  size_t unproven;      /* left: of another machine or an older lsmorph, or their maker lives */
  char first_removed[256], first_unproven[256]; /* a name of each, for a note */
} lsm_temp_sweep_result;

/* Removes the temporaries PREFIX<tag>-XXXXXX in folder dir whose makers have
 * provably ended (own_tag NULL), or those of tag own_tag (a run cleaning up
 * after itself).  Names of other forms that begin with prefix are counted in
 * r->unproven when their maker cannot be shown to have ended and is not a
 * live process of this machine.  Never fails: what cannot be read is left. */
void lsm_temp_sweep(const char *dir, const char *prefix, const char *own_tag,
                    lsm_temp_sweep_result *r);

/* Removes a file or a folder with all it holds, following no symbolic link
 * and staying on one file system.  0 when path is gone afterwards. */
int lsm_remove_tree(const char *path);

#endif
