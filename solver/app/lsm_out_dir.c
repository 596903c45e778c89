#define _XOPEN_SOURCE 700 /* nftw, realpath */
#include "solver/app/lsm_out_dir.h"

#include <dirent.h>
#include <errno.h>
#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "io/lsm_io.h"

static int remove_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw) {
  (void)sb;
  (void)flag;
  (void)ftw;
  return remove(path);
}

static void remove_tree(const char *path) {
  if (path && *path) nftw(path, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
}

/* The length of path without trailing slashes (but "/" itself). */
static size_t trimmed_length(const char *path) {
  size_t len = strlen(path);
  while (len > 1 && path[len - 1] == '/') --len;
  return len;
}

/* Whether the path `inner` (resolved) is `outer_real` or lies inside it. */
static int path_within(const char *inner, const char *outer_real) {
  char *inner_real = realpath(inner, NULL);
  if (!inner_real || !outer_real) {
    free(inner_real);
    return 0;
  }
  const size_t n = strlen(outer_real);
  const int within = strncmp(inner_real, outer_real, n) == 0 &&
                     (inner_real[n] == '/' || inner_real[n] == '\0' ||
                      (n == 1 && outer_real[0] == '/'));
  free(inner_real);
  return within;
}

/* 1 when the folder `dir` is not empty and has no run.json: not an earlier
 * result, so not lsmorph's to replace. */
static int foreign_folder(const char *dir) {
  char path[4200];
  snprintf(path, sizeof path, "%s/run.json", dir);
  struct stat sb;
  if (stat(path, &sb) == 0 && S_ISREG(sb.st_mode)) return 0;
  DIR *d = opendir(dir);
  if (!d) return 0; /* unreadable: publishing will say what is wrong */
  int foreign = 0;
  for (struct dirent *e; !foreign && (e = readdir(d)) != NULL;)
    foreign = strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
  closedir(d);
  return foreign;
}

lsm_status lsm_out_dir_check(const char *out_dir, const char *slice_dir, const char *heights_file,
                             lsm_err *err) {
  struct stat sb, in;
  if (stat(out_dir, &sb) != 0) return LSM_OK; /* a new folder */
  if (!S_ISDIR(sb.st_mode))
    return lsm_fail(err, LSM_ERR_INPUT, out_dir, "exists and is not a folder");
  char *out_real = realpath(out_dir, NULL);
  int clash = stat(slice_dir, &in) == 0 && in.st_dev == sb.st_dev && in.st_ino == sb.st_ino;
  clash = clash || path_within(slice_dir, out_real);
  const int heights_inside = heights_file && path_within(heights_file, out_real);
  free(out_real);
  if (clash)
    return lsm_fail(err, LSM_ERR_INPUT, out_dir,
                    "is or contains the input folder %s, which replacing it would delete",
                    slice_dir);
  if (heights_inside)
    return lsm_fail(err, LSM_ERR_INPUT, out_dir,
                    "contains the heights file %s, which replacing it would delete",
                    heights_file);
  if (foreign_folder(out_dir))
    return lsm_fail(err, LSM_ERR_INPUT, out_dir,
                    "exists, is not empty and is not an earlier lsmorph result (no run.json): "
                    "lsmorph replaces OUT_DIR as a whole; remove it or name a new folder");
  return LSM_OK;
}

lsm_status lsm_out_dir_begin(lsm_out_dir *o, const char *out_dir, lsm_err *err) {
  o->path = out_dir;
  o->tmp[0] = '\0';
  const size_t len = trimmed_length(out_dir);
  if (len + 12 >= sizeof o->tmp) return lsm_fail(err, LSM_ERR_INPUT, out_dir, "path is too long");
  snprintf(o->tmp, sizeof o->tmp, "%.*s.tmp-XXXXXX", (int)len, out_dir);
  if (!mkdtemp(o->tmp)) {
    o->tmp[0] = '\0'; /* nothing of ours to remove */
    return lsm_fail(err, LSM_ERR_IO, out_dir, "cannot create a folder next to it: %s",
                    strerror(errno));
  }
  /* mkdtemp makes it private (0700); the result gets a new folder's usual
   * permissions (0777 less the umask). */
  const mode_t mask = umask(0);
  umask(mask);
  if (chmod(o->tmp, 0777 & ~mask) != 0)
    return lsm_fail(err, LSM_ERR_IO, o->tmp, "cannot set permissions: %s", strerror(errno));
  return LSM_OK;
}

/* Where the system allows, the two folders are exchanged atomically
 * (renameat2 RENAME_EXCHANGE): OUT_DIR is at every moment the complete earlier
 * result or the complete new one.  Elsewhere the earlier result is renamed
 * aside (OUT_DIR is briefly absent) and put back if the new one cannot be
 * moved in. */
lsm_status lsm_out_dir_publish(lsm_out_dir *o, lsm_err *err) {
  const char *tmp = o->tmp, *out_dir = o->path;
  struct stat st;
  if (stat(out_dir, &st) == 0) {
    if (!S_ISDIR(st.st_mode)) return lsm_fail(err, LSM_ERR_INPUT, out_dir, "exists and is not a folder");
    if (lsm_rename_exchange(tmp, out_dir) == 0) {
      remove_tree(tmp); /* now the earlier result */
      return LSM_OK;
    }
    if (errno != ENOSYS && errno != EINVAL
#ifdef ENOTSUP
        && errno != ENOTSUP
#endif
    )
      return lsm_fail(err, LSM_ERR_IO, out_dir, "cannot replace: %s", strerror(errno));
    char old[4200];
    snprintf(old, sizeof old, "%s.old-XXXXXX", tmp);
    if (!mkdtemp(old)) return lsm_fail(err, LSM_ERR_IO, out_dir, "cannot replace: %s", strerror(errno));
    char old_out[4300];
    snprintf(old_out, sizeof old_out, "%s/previous", old);
    if (rename(out_dir, old_out) != 0) {
      int e = errno;
      remove_tree(old);
      return lsm_fail(err, LSM_ERR_IO, out_dir, "cannot replace: %s", strerror(e));
    }
    if (rename(tmp, out_dir) != 0) {
      int e = errno;
      if (rename(old_out, out_dir) != 0) /* never delete the earlier result: say where it is */
        return lsm_fail(err, LSM_ERR_IO, out_dir,
                        "cannot move the result into place (%s); the earlier result is in %s",
                        strerror(e), old_out);
      remove_tree(old);
      return lsm_fail(err, LSM_ERR_IO, out_dir, "cannot move the result into place: %s", strerror(e));
    }
    remove_tree(old);
    return LSM_OK;
  }
  if (rename(tmp, out_dir) != 0)
    return lsm_fail(err, LSM_ERR_IO, out_dir, "cannot move the result into place: %s", strerror(errno));
  return LSM_OK;
}

void lsm_out_dir_discard(lsm_out_dir *o, lsm_err *err) {
  if (!o->tmp[0]) return;
  remove_tree(o->tmp);
  if (!err) return;
  const char *at = strstr(err->msg, o->tmp);
  if (!at) return;
  char msg[LSM_ERR_MSG_MAX];
  const size_t before = (size_t)(at - err->msg);
  snprintf(msg, sizeof msg, "%.*s%.*s%s", (int)before, err->msg, (int)trimmed_length(o->path),
           o->path, at + strlen(o->tmp));
  memcpy(err->msg, msg, sizeof msg);
}
