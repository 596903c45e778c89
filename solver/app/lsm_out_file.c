#define _XOPEN_SOURCE 700 /* realpath, readlink */
#include "solver/app/lsm_out_file.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "io/lsm_temp.h"
#include "solver/app/lsm_out_dir.h"

/* The temporaries' prefixes of the file at o->path: its own and, for a
 * detached .nhdr header, its data file's (NAME.raw or NAME.raw.gz). */
static void set_prefixes(lsm_out_file *o) {
  const char *slash = strrchr(o->path, '/');
  const char *name = slash ? slash + 1 : o->path;
  const size_t len = strlen(name);
  snprintf(o->folder, sizeof o->folder, "%.*s",
           slash ? (int)(slash == o->path ? 1 : slash - o->path) : 1, slash ? o->path : ".");
  snprintf(o->prefixes[0], sizeof o->prefixes[0], ".%.280s.tmp-", name);
  o->prefixes[1][0] = o->prefixes[2][0] = '\0';
  if (len > 5 && strcmp(name + len - 5, ".nhdr") == 0) {
    const int stem = len - 5 < 270 ? (int)(len - 5) : 270;
    snprintf(o->prefixes[1], sizeof o->prefixes[1], ".%.*s.raw.tmp-", stem, name);
    snprintf(o->prefixes[2], sizeof o->prefixes[2], ".%.*s.raw.gz.tmp-", stem, name);
  }
}

lsm_status lsm_out_file_check(lsm_out_file *o, const char *out, FILE *notes, lsm_err *err) {
  memset(o, 0, sizeof *o);
  lsm_temp_tag(o->tag);
  if (strlen(out) >= sizeof o->path) return lsm_fail(err, LSM_ERR_INPUT, out, "path is too long");
  snprintf(o->path, sizeof o->path, "%s", out);
  struct stat sb;
  if (lstat(out, &sb) == 0 && S_ISLNK(sb.st_mode)) {
    char target[4096];
    const ssize_t n = readlink(out, target, sizeof target - 1);
    target[n > 0 ? n : 0] = '\0';
    char *real = realpath(out, NULL);
    if (!real)
      return lsm_fail(err, LSM_ERR_INPUT, out,
                      "is a symbolic link to nothing (%s): lsmorph follows a link only to a "
                      "file; name the file itself", target);
    const int fits = strlen(real) < sizeof o->path;
    if (fits) snprintf(o->path, sizeof o->path, "%s", real);
    free(real);
    if (!fits) return lsm_fail(err, LSM_ERR_INPUT, out, "path is too long");
    if (notes)
      fprintf(notes, "lsmorph: note: %s is a symbolic link: the result replaces the file it "
                     "names, %s (the link stays)\n", out, o->path);
  }
  char *real = realpath(o->path, NULL);
  const int mount = real && lsm_is_mount_point(real);
  free(real);
  if (mount)
    return lsm_fail(err, LSM_ERR_INPUT, out,
                    "is a mount point (a file bound into a container?): the result is written "
                    "beside it and renamed into place, which a mount point does not allow; "
                    "mount its folder instead");
  set_prefixes(o);
  for (int k = 0; k < 3 && o->prefixes[k][0]; ++k) {
    lsm_temp_sweep_result swept;
    lsm_temp_sweep(o->folder, o->prefixes[k], NULL, &swept);
    lsm_temp_sweep_note(notes, o->folder, "file", &swept);
  }
  return LSM_OK;
}

void lsm_out_file_abandon(void *ctx) {
  lsm_out_file *o = ctx;
  if (!o->tag[0]) return;
  for (int k = 0; k < 3 && o->prefixes[k][0]; ++k) {
    lsm_temp_sweep_result swept;
    lsm_temp_sweep(o->folder, o->prefixes[k], o->tag, &swept);
  }
}
