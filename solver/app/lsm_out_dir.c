#define _XOPEN_SOURCE 700 /* realpath */
#include "solver/app/lsm_out_dir.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "io/lsm_io.h"
#include "io/lsm_temp.h"
#include "solver/app/lsm_outputs.h"

/* The temporary folder of a run that writes in place, inside OUT_DIR. */
#define IN_PLACE_PREFIX ".lsmorph.tmp-"

/* The length of path without trailing slashes (but "/" itself). */
static size_t trimmed_length(const char *path) {
  size_t len = strlen(path);
  while (len > 1 && path[len - 1] == '/') --len;
  return len;
}

/* "dir/name" into out (cap bytes), name without a trailing '/'; 0 when it does not fit. */
static int join(char *out, size_t cap, const char *dir, const char *name) {
  const size_t n = strlen(name) - (name[0] && name[strlen(name) - 1] == '/');
  const int k = snprintf(out, cap, "%.*s/%.*s", (int)trimmed_length(dir), dir, (int)n, name);
  return k > 0 && (size_t)k < cap;
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

/* ---- how OUT_DIR can be written ---------------------------------------------------------- */

lsm_out_mode lsm_out_dir_decide(const lsm_out_facts *f, const char **why) {
  *why = NULL;
  if (!f->exists) {
    if (f->link) *why = "is a symbolic link to nothing: lsmorph follows a link only to a folder";
    return f->link ? LSM_OUT_REFUSE : LSM_OUT_NEW;
  }
  if (!f->folder) {
    *why = "exists and is not a folder";
    return LSM_OUT_REFUSE;
  }
  /* a folder that cannot be renamed: its entries are replaced one by one */
  if (f->mount_point)
    *why = "is a mount point, which cannot be replaced as a whole";
  else if (f->holds_cwd)
    *why = "is the current folder or holds it, which is not replaced as a whole";
  else if (f->parent_locked)
    *why = "lies in a folder lsmorph cannot write, so it cannot be replaced as a whole";
  return *why ? LSM_OUT_IN_PLACE : LSM_OUT_REPLACE;
}

int lsm_is_mount_point(const char *real) {
  char parent[4200];
  struct stat a, b;
  snprintf(parent, sizeof parent, "%s/..", real);
  if (stat(real, &a) == 0 && stat(parent, &b) == 0 &&
      (a.st_dev != b.st_dev || a.st_ino == b.st_ino))
    return 1;
  FILE *f = fopen("/proc/self/mountinfo", "r");
  if (!f) return 0;
  char line[8192], point[4200];
  int found = 0;
  while (!found && fgets(line, sizeof line, f)) {
    /* the fifth field, with \ooo escapes for blanks and backslashes */
    const char *p = line;
    for (int field = 1; field < 5 && p; ++field) {
      p = strchr(p, ' ');
      if (p) ++p;
    }
    if (!p) continue;
    size_t n = 0;
    for (; *p && *p != ' ' && n + 1 < sizeof point; ++p) {
      if (p[0] == '\\' && p[1] >= '0' && p[1] <= '3' && p[2] >= '0' && p[2] <= '7' &&
          p[3] >= '0' && p[3] <= '7') {
        point[n++] = (char)((p[1] - '0') * 64 + (p[2] - '0') * 8 + (p[3] - '0'));
        p += 3;
      } else {
        point[n++] = *p;
      }
    }
    point[n] = '\0';
    found = strcmp(point, real) == 0;
  }
  fclose(f);
  return found;
}

/* The facts of OUT_DIR (given); o->path becomes the folder to write. */
static lsm_status gather_facts(lsm_out_dir *o, const char *given, lsm_out_facts *f,
                               char *target, size_t cap, lsm_err *err) {
  memset(f, 0, sizeof *f);
  target[0] = '\0';
  struct stat sb;
  if (trimmed_length(given) + 1 > sizeof o->path)
    return lsm_fail(err, LSM_ERR_INPUT, given, "path is too long");
  snprintf(o->path, sizeof o->path, "%.*s", (int)trimmed_length(given), given);
  /* ".", "..", "x/.": no name to put a temporary folder beside: the folder's own path */
  const char *base = strrchr(o->path, '/');
  base = base ? base + 1 : o->path;
  if (strcmp(base, ".") == 0 || strcmp(base, "..") == 0) {
    char *real = realpath(o->path, NULL);
    if (!real) return lsm_fail(err, LSM_ERR_INPUT, given, "cannot access: %s", strerror(errno));
    const int fits = strlen(real) < sizeof o->path;
    if (fits) snprintf(o->path, sizeof o->path, "%s", real);
    free(real);
    if (!fits) return lsm_fail(err, LSM_ERR_INPUT, given, "path is too long");
  }
  if (lstat(o->path, &sb) != 0) {
    if (errno != ENOENT && errno != ENOTDIR)
      return lsm_fail(err, LSM_ERR_INPUT, given, "cannot access: %s", strerror(errno));
    return LSM_OK;
  }
  f->link = S_ISLNK(sb.st_mode);
  if (f->link) {
    const ssize_t n = readlink(o->path, target, cap - 1);
    target[n > 0 ? n : 0] = '\0';
    char *real = realpath(o->path, NULL);
    if (!real) return LSM_OK; /* to nothing (or a loop) */
    const int fits = strlen(real) < sizeof o->path;
    if (fits) snprintf(o->path, sizeof o->path, "%s", real);
    free(real);
    if (!fits) return lsm_fail(err, LSM_ERR_INPUT, given, "path is too long");
    if (stat(o->path, &sb) != 0) return LSM_OK;
  }
  f->exists = 1;
  f->folder = S_ISDIR(sb.st_mode);
  if (!f->folder) return LSM_OK;
  char *real = realpath(o->path, NULL);
  if (real) {
    f->mount_point = lsm_is_mount_point(real);
    f->holds_cwd = path_within(".", real);
    char parent[4200];
    snprintf(parent, sizeof parent, "%s/..", real);
    f->parent_locked = access(parent, W_OK | X_OK) != 0 && access(real, W_OK | X_OK) == 0;
    free(real);
  }
  return LSM_OK;
}

/* ---- what an existing folder holds ------------------------------------------------------- */

/* Whether name is digits (five or more) and ext: slices/00001.png, exr/00001.exr. */
static int numbered(const char *name, const char *ext) {
  size_t k = 0;
  while (name[k] >= '0' && name[k] <= '9') ++k;
  return k >= 5 && strcmp(name + k, ext) == 0;
}

/* Whether the folder dir holds only regular files of numbered(name, ext);
 * the first other entry into foreign. */
static int only_numbered(const char *dir, const char *ext, const char *shown, char *foreign,
                         size_t cap) {
  DIR *d = opendir(dir);
  if (!d) {
    snprintf(foreign, cap, "%s (unreadable)", shown);
    return 0;
  }
  int ok = 1;
  for (struct dirent *e; ok && (e = readdir(d)) != NULL;) {
    if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
    char path[4400];
    struct stat sb;
    ok = numbered(e->d_name, ext) && join(path, sizeof path, dir, e->d_name) &&
         lstat(path, &sb) == 0 && S_ISREG(sb.st_mode);
    if (!ok) snprintf(foreign, cap, "%s%s", shown, e->d_name);
  }
  closedir(d);
  return ok;
}

/* The entry of known (an output name) that `name` is, or NULL. */
static const char *known_entry(const char *name, const char *const *known, size_t n_known) {
  const size_t len = strlen(name);
  for (size_t k = 0; k < n_known; ++k)
    if (strncmp(known[k], name, len) == 0 && (known[k][len] == '\0' || strcmp(known[k] + len, "/") == 0))
      return known[k];
  return NULL;
}

/* Whether the entry `name` of dir is as lsmorph writes it: a regular file,
 * or slices/ and exr/ holding only their numbered files.  The first entry
 * that is not into foreign (as "name" or "slices/name"). */
static int entry_is_ours(const char *dir, const char *name, const char *known, char *foreign,
                         size_t cap) {
  char path[4400];
  struct stat sb;
  if (!join(path, sizeof path, dir, name) || lstat(path, &sb) != 0) {
    snprintf(foreign, cap, "%s", name);
    return 0;
  }
  const int folder = known[strlen(known) - 1] == '/';
  if (folder != S_ISDIR(sb.st_mode) || (!folder && !S_ISREG(sb.st_mode))) {
    snprintf(foreign, cap, "%s (%s)", name,
             S_ISLNK(sb.st_mode) ? "a symbolic link" : folder ? "not a folder" : "not a file");
    return 0;
  }
  if (!folder) return 1;
  return only_numbered(path, strcmp(known, "exr/") == 0 ? ".exr" : ".png", known, foreign, cap);
}

/* Whether run.json in dir is lsmorph's: valid JSON with a string
 * lsmorph_version and an array of strings output.files.  0 with *why. */
static int run_json_is_lsmorph(const char *dir, const char **why) {
  static const char *const version_key[] = {"lsmorph_version"};
  static const char *const files_key[] = {"output", "files"};
  char path[4400];
  struct stat sb;
  *why = "no run.json";
  if (!join(path, sizeof path, dir, "run.json") || lstat(path, &sb) != 0) return 0;
  *why = "its run.json is not a file";
  if (!S_ISREG(sb.st_mode)) return 0;
  char *text = NULL;
  size_t len = 0, n = 0;
  lsm_err ignored;
  lsm_err_clear(&ignored);
  *why = "its run.json cannot be read";
  if (lsm_read_file(path, (size_t)64 << 20, &text, &len, &ignored) != LSM_OK) return 0;
  const int version = lsm_json_find_string(text, version_key, 1, NULL, NULL, NULL);
  const int files = strlen(text) == len
                        ? lsm_json_find_strings(text, files_key, 2, NULL, NULL, 0, &n, NULL)
                        : -1;
  free(text);
  *why = version < 0 || files < 0 ? "its run.json is not JSON"
                                  : "its run.json has no lsmorph_version and output.files";
  return version == 1 && files == 1;
}

/* What the existing folder o->path holds, against what this run writes
 * (o->earlier set; why: why it is not an earlier result). */
static lsm_status survey(const lsm_out_dir *o, const char *given, int in_place, const char *why,
                         lsm_err *err) {
  const char *known[24];
  const size_t n_known = lsm_output_known_names(known, 24);
  DIR *d = opendir(o->path);
  if (!d) return lsm_fail(err, LSM_ERR_INPUT, given, "cannot read the folder: %s", strerror(errno));
  size_t entries = 0;
  char foreign[600] = "", clash[300] = "";
  for (struct dirent *e; (e = readdir(d)) != NULL;) {
    const char *name = e->d_name;
    if (strcmp(name, ".") == 0 || strcmp(name, "..") == 0) continue;
    if (strncmp(name, IN_PLACE_PREFIX, strlen(IN_PLACE_PREFIX)) == 0) continue; /* lsmorph's */
    ++entries;
    const char *entry = known_entry(name, known, n_known);
    const int written = known_entry(name, o->names, o->n_names) != NULL;
    char what[600] = "";
    const int ours = entry && entry_is_ours(o->path, name, entry, what, sizeof what);
    if (!entry) snprintf(what, sizeof what, "%s", name);
    if (!in_place) { /* replaced as a whole: everything must be lsmorph's */
      if (!ours && !foreign[0]) snprintf(foreign, sizeof foreign, "%s", what);
    } else if (entry && (o->earlier || written) && !ours && !foreign[0]) {
      snprintf(foreign, sizeof foreign, "%s", what); /* slices/ holding another file */
    } else if (written && !o->earlier && !clash[0]) {
      snprintf(clash, sizeof clash, "%s", name);
    }
  }
  closedir(d);
  if (!in_place && entries > 0 && !o->earlier)
    return lsm_fail(err, LSM_ERR_INPUT, given,
                    "exists, is not empty and is not an earlier lsmorph result (%s); lsmorph "
                    "replaces OUT_DIR as a whole: remove it or name a new folder", why);
  if (foreign[0])
    return lsm_fail(err, LSM_ERR_INPUT, given,
                    "holds %s, which lsmorph does not write: it is not only an earlier lsmorph "
                    "result, and lsmorph %s; move that out or name another folder",
                    foreign, in_place ? "would replace what holds it" : "replaces OUT_DIR as a whole");
  if (clash[0])
    return lsm_fail(err, LSM_ERR_INPUT, given,
                    "holds %s, which this run would write, and is not an earlier lsmorph "
                    "result (%s): move it out or name another folder", clash, why);
  return LSM_OK;
}

/* The input folder and the heights file must survive: not OUT_DIR itself,
 * nor inside it when it is replaced as a whole, nor inside an entry that
 * writing in place replaces. */
static lsm_status check_inputs_survive(const lsm_out_dir *o, const char *given,
                                       const char *slice_dir, const char *heights_file,
                                       lsm_err *err) {
  char *out_real = realpath(o->path, NULL);
  struct stat in, sb;
  const int same = stat(slice_dir, &in) == 0 && stat(o->path, &sb) == 0 &&
                   in.st_dev == sb.st_dev && in.st_ino == sb.st_ino;
  int input_hit = same, heights_hit = 0;
  if (o->mode == LSM_OUT_REPLACE) {
    input_hit = input_hit || path_within(slice_dir, out_real);
    heights_hit = heights_file && path_within(heights_file, out_real);
  } else if (o->mode == LSM_OUT_IN_PLACE) {
    const char *known[24];
    const size_t n_known = lsm_output_known_names(known, 24);
    const char *const *touched = o->earlier ? known : o->names;
    const size_t n_touched = o->earlier ? n_known : o->n_names;
    for (size_t k = 0; k < n_touched; ++k) {
      char entry[4400], *entry_real = NULL;
      if (join(entry, sizeof entry, o->path, touched[k])) entry_real = realpath(entry, NULL);
      input_hit = input_hit || path_within(slice_dir, entry_real);
      heights_hit = heights_hit || (heights_file && path_within(heights_file, entry_real));
      free(entry_real);
    }
  }
  free(out_real);
  if (input_hit)
    return lsm_fail(err, LSM_ERR_INPUT, given,
                    "is or contains the input folder %s, which %s would delete", slice_dir,
                    o->mode == LSM_OUT_IN_PLACE ? "writing into it" : "replacing it");
  if (heights_hit)
    return lsm_fail(err, LSM_ERR_INPUT, given,
                    "contains the heights file %s, which %s would delete", heights_file,
                    o->mode == LSM_OUT_IN_PLACE ? "writing into it" : "replacing it");
  return LSM_OK;
}

lsm_status lsm_out_dir_check(lsm_out_dir *o, const char *out_dir, const char *const *names,
                             size_t n_names, const char *slice_dir, const char *heights_file,
                             FILE *notes, lsm_err *err) {
  memset(o, 0, sizeof *o);
  o->given = out_dir;
  o->names = names;
  o->n_names = n_names;
  if (pthread_mutex_init(&o->lock, NULL) != 0)
    return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot set up the output folder");
  o->lock_ready = 1;
  lsm_out_facts f;
  char target[4096];
  LSM_TRY(gather_facts(o, out_dir, &f, target, sizeof target, err));
  const char *why = NULL;
  o->mode = lsm_out_dir_decide(&f, &why);
  if (o->mode == LSM_OUT_REFUSE && f.link && !f.exists)
    return lsm_fail(err, LSM_ERR_INPUT, out_dir,
                    "is a symbolic link to nothing (%s): lsmorph follows a link only to a "
                    "folder; create that folder, or name another", target);
  if (o->mode == LSM_OUT_REFUSE) return lsm_fail(err, LSM_ERR_INPUT, out_dir, "%s", why);
  const char *why_not_earlier = NULL;
  if (o->mode != LSM_OUT_NEW) o->earlier = run_json_is_lsmorph(o->path, &why_not_earlier);
  LSM_TRY(check_inputs_survive(o, out_dir, slice_dir, heights_file, err));
  if (o->mode != LSM_OUT_NEW)
    LSM_TRY(survey(o, out_dir, o->mode == LSM_OUT_IN_PLACE, why_not_earlier, err));
  if (notes && f.link)
    fprintf(notes, "lsmorph: note: %s is a symbolic link: the result goes to the folder it "
                   "names, %s (the link stays)\n", out_dir, o->path);
  if (notes && o->mode == LSM_OUT_IN_PLACE)
    fprintf(notes, "lsmorph: note: %s %s: its files are replaced one by one (each atomically, "
                   "run.json last)%s\n", out_dir, why,
            o->earlier ? "" : "; what else it holds is left as it is");
  return LSM_OK;
}

/* ---- writing --------------------------------------------------------------------------- */

void lsm_out_dir_temp_folder(const lsm_out_dir *o, char *folder, size_t cap) {
  const char *slash = strrchr(o->path, '/');
  if (o->mode == LSM_OUT_IN_PLACE)
    snprintf(folder, cap, "%s", o->path);
  else if (!slash)
    snprintf(folder, cap, ".");
  else
    snprintf(folder, cap, "%.*s", (int)(slash == o->path ? 1 : slash - o->path), o->path);
}

void lsm_temp_sweep_note(FILE *notes, const char *dir, const char *what,
                         const lsm_temp_sweep_result *r) {
  if (!notes) return;
  const int here = strcmp(dir, ".") == 0;
  if (r->removed)
    fprintf(notes, "lsmorph: note: removed %zu temporary %s%s of earlier runs that ended without "
                   "finishing (%s%s)\n", r->removed, what, r->removed == 1 ? "" : "s",
            r->first_removed, r->removed > 1 ? ", ..." : "");
  if (r->unproven)
    fprintf(notes, "lsmorph: note: %s%s%s%s: left by a run that cannot be shown to have ended "
                   "(another machine or container, an earlier boot, or an older lsmorph): remove "
                   "it by hand once no run writes it\n", here ? "" : dir, here ? "" : "/",
            r->first_unproven, r->unproven > 1 ? " and others" : "");
}

lsm_status lsm_out_dir_begin(lsm_out_dir *o, FILE *notes, lsm_err *err) {
  o->tmp[0] = '\0';
  lsm_temp_tag(o->tag);
  /* stale temporaries of this OUT_DIR: beside it, or inside it (in place) */
  char dir[4200], prefix[4200], stem[4200];
  const int in_place = o->mode == LSM_OUT_IN_PLACE;
  const char *slash = strrchr(o->path, '/');
  lsm_out_dir_temp_folder(o, dir, sizeof dir);
  if (in_place) {
    snprintf(prefix, sizeof prefix, "%s", IN_PLACE_PREFIX);
    snprintf(stem, sizeof stem, "%s/%s", o->path, IN_PLACE_PREFIX);
  } else {
    snprintf(prefix, sizeof prefix, "%s.tmp-", slash ? slash + 1 : o->path);
    snprintf(stem, sizeof stem, "%s.tmp-", o->path);
  }
  lsm_temp_sweep_result swept;
  lsm_temp_sweep(dir, prefix, NULL, &swept);
  lsm_temp_sweep_note(notes, dir, "folder", &swept);
  LSM_TRY(lsm_temp_template(o->tmp, sizeof o->tmp, stem, err));
  if (!mkdtemp(o->tmp)) {
    const int e = errno;
    o->tmp[0] = '\0'; /* nothing of ours to remove */
    return lsm_fail(err, LSM_ERR_IO, o->given, in_place ? "cannot create a folder in it: %s"
                                                        : "cannot create a folder next to it: %s",
                    strerror(e));
  }
  /* mkdtemp makes it private (0700); the result gets a new folder's usual
   * permissions (0777 less the umask). */
  const mode_t mask = umask(0);
  umask(mask);
  if (chmod(o->tmp, 0777 & ~mask) != 0)
    return lsm_fail(err, LSM_ERR_IO, o->tmp, "cannot set permissions: %s", strerror(errno));
  return LSM_OK;
}

/* Whether errno says the system cannot exchange two paths atomically. */
static int exchange_unsupported(int e) {
  return e == ENOSYS || e == EINVAL
#ifdef ENOTSUP
         || e == ENOTSUP
#endif
      ;
}

/* Replaces the folder dst by src, atomically where the system allows
 * (renameat2 RENAME_EXCHANGE, then the former dst, now at src, is removed);
 * elsewhere dst is renamed to aside (a path in a folder that exists), src to
 * dst, and dst put back if that fails.  0, or -1 with errno; *kept: the
 * earlier folder could not be put back and is at aside. */
static int replace_folder(const char *src, const char *dst, const char *aside, int *kept) {
  *kept = 0;
  if (lsm_rename_exchange(src, dst) == 0) {
    lsm_remove_tree(src); /* now the earlier one */
    return 0;
  }
  if (!exchange_unsupported(errno) || rename(dst, aside) != 0) return -1;
  if (rename(src, dst) != 0) {
    const int e = errno;
    *kept = rename(aside, dst) != 0;
    errno = e;
    return -1;
  }
  lsm_remove_tree(aside);
  return 0;
}

/* Whole: OUT_DIR is at every moment the complete earlier result or the
 * complete new one (where the system cannot exchange, briefly absent: the
 * earlier result waits in OUT_DIR.tmp-...old-XXXXXX/previous and is put back
 * if the new one cannot be moved in). */
static lsm_status publish_whole(lsm_out_dir *o, lsm_err *err) {
  struct stat st;
  if (stat(o->path, &st) != 0) {
    if (rename(o->tmp, o->path) != 0)
      return lsm_fail(err, LSM_ERR_IO, o->given, "cannot move the result into place: %s",
                      strerror(errno));
    return LSM_OK;
  }
  if (!S_ISDIR(st.st_mode)) return lsm_fail(err, LSM_ERR_INPUT, o->given, "exists and is not a folder");
  if (lsm_rename_exchange(o->tmp, o->path) == 0) {
    lsm_remove_tree(o->tmp); /* now the earlier result */
    return LSM_OK;
  }
  if (!exchange_unsupported(errno))
    return lsm_fail(err, LSM_ERR_IO, o->given, "cannot replace: %s", strerror(errno));
  char old[4200], old_out[4300];
  snprintf(old, sizeof old, "%s.old-XXXXXX", o->tmp);
  if (!mkdtemp(old)) return lsm_fail(err, LSM_ERR_IO, o->given, "cannot replace: %s", strerror(errno));
  snprintf(old_out, sizeof old_out, "%s/previous", old);
  int kept = 0;
  const int failed = replace_folder(o->tmp, o->path, old_out, &kept);
  const int e = errno;
  if (failed && kept) /* never delete the earlier result: say where it is */
    return lsm_fail(err, LSM_ERR_IO, o->given,
                    "cannot move the result into place (%s); the earlier result is in %s",
                    strerror(e), old_out);
  lsm_remove_tree(old);
  if (failed)
    return lsm_fail(err, LSM_ERR_IO, o->given, "cannot %s: %s",
                    exchange_unsupported(e) ? "replace" : "move the result into place", strerror(e));
  return LSM_OK;
}

/* In place: each entry this run wrote replaces its namesake (run.json last),
 * and an earlier result's entries this run does not write are removed. */
static lsm_status publish_in_place(lsm_out_dir *o, lsm_err *err) {
  const char *known[24];
  const size_t n_known = lsm_output_known_names(known, 24);
  char src[4400], dst[4400], aside[4400];
  for (size_t k = 0; k < o->n_names; ++k) {
    const char *name = o->names[k];
    if (strcmp(name, "run.json") == 0) continue;
    if (!join(src, sizeof src, o->tmp, name) || !join(dst, sizeof dst, o->path, name))
      return lsm_fail(err, LSM_ERR_INPUT, o->given, "path is too long");
    struct stat sb;
    int failed = 0, kept = 0;
    if (name[strlen(name) - 1] == '/' && lstat(dst, &sb) == 0) {
      snprintf(aside, sizeof aside, "%s/.previous-%.*s", o->tmp, (int)strlen(name) - 1, name);
      failed = replace_folder(src, dst, aside, &kept);
    } else {
      failed = rename(src, dst) != 0;
    }
    if (failed)
      return lsm_fail(err, LSM_ERR_IO, dst,
                      "cannot move the result into place: %s; %s now holds part of the new "
                      "result beside the earlier one%s", strerror(errno), o->given,
                      kept ? " (the earlier folder is in the temporary folder)" : "");
  }
  for (size_t k = 0; o->earlier && k < n_known; ++k) {
    if (known_entry(known[k], o->names, o->n_names) || strcmp(known[k], "run.json") == 0) continue;
    const size_t len = strlen(known[k]) - (known[k][strlen(known[k]) - 1] == '/');
    char name[64];
    snprintf(name, sizeof name, "%.*s", (int)len, known[k]);
    if (known_entry(name, o->names, o->n_names)) continue;
    if (join(dst, sizeof dst, o->path, known[k])) lsm_remove_tree(dst);
  }
  if (!join(src, sizeof src, o->tmp, "run.json") || !join(dst, sizeof dst, o->path, "run.json") ||
      rename(src, dst) != 0)
    return lsm_fail(err, LSM_ERR_IO, dst, "cannot move the result into place: %s",
                    strerror(errno));
  lsm_remove_tree(o->tmp);
  return LSM_OK;
}

lsm_status lsm_out_dir_publish(lsm_out_dir *o, lsm_err *err) {
  pthread_mutex_lock(&o->lock);
  const lsm_status st =
      o->mode == LSM_OUT_IN_PLACE ? publish_in_place(o, err) : publish_whole(o, err);
  o->published = st == LSM_OK;
  pthread_mutex_unlock(&o->lock);
  return st;
}

void lsm_out_dir_abandon(void *ctx) {
  lsm_out_dir *o = ctx;
  pthread_mutex_lock(&o->lock);
  /* writers may still add files: try until the folder is gone (up to 2 s) */
  for (int k = 0; !o->published && o->tmp[0] && k < 100 && lsm_remove_tree(o->tmp) != 0; ++k) {
    const struct timespec pause = {0, 20 * 1000 * 1000};
    nanosleep(&pause, NULL);
  }
  pthread_mutex_unlock(&o->lock);
}

void lsm_out_dir_discard(lsm_out_dir *o, lsm_err *err) {
  if (!o->tmp[0] || o->published) return;
  lsm_remove_tree(o->tmp);
  if (!err) return;
  const char *at = strstr(err->msg, o->tmp);
  if (!at) return;
  char msg[LSM_ERR_MSG_MAX];
  const size_t before = (size_t)(at - err->msg);
  snprintf(msg, sizeof msg, "%.*s%.*s%s", (int)before, err->msg, (int)trimmed_length(o->given),
           o->given, at + strlen(o->tmp));
  memcpy(err->msg, msg, sizeof msg);
}

void lsm_out_dir_free(lsm_out_dir *o) {
  if (o->lock_ready) pthread_mutex_destroy(&o->lock);
  o->lock_ready = 0;
}
