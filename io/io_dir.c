/* io_dir: natural-order listing of the PNG files of a folder, and small file
 * helpers (mkdir of one level, whole-file read with a size limit, atomic
 * exchange of two paths). */
#if defined(__linux__) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* renameat2 (glibc >= 2.28) */
#endif
#include "io/lsm_io.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>

static int is_digit(char c) { return c >= '0' && c <= '9'; }

int lsm_natural_cmp(const char *a, const char *b) {
  const char *pa = a, *pb = b;
  while (*pa && *pb) {
    if (is_digit(*pa) && is_digit(*pb)) {
      /* Compare digit runs by value: skip leading zeros, longer run is larger,
       * equal lengths compare digit by digit. */
      while (*pa == '0' && is_digit(pa[1])) ++pa;
      while (*pb == '0' && is_digit(pb[1])) ++pb;
      const char *ea = pa, *eb = pb;
      while (is_digit(*ea)) ++ea;
      while (is_digit(*eb)) ++eb;
      size_t la = (size_t)(ea - pa), lb = (size_t)(eb - pb);
      if (la != lb) return la < lb ? -1 : 1;
      int c = memcmp(pa, pb, la);
      if (c != 0) return c < 0 ? -1 : 1;
      pa = ea;
      pb = eb;
      continue;
    }
    unsigned char ca = (unsigned char)*pa, cb = (unsigned char)*pb;
    if (ca != cb) return ca < cb ? -1 : 1;
    ++pa;
    ++pb;
  }
  if (*pa || *pb) return *pa ? 1 : -1;
  /* Equal in natural order ("01" vs "1"): plain strcmp makes the order total. */
  int c = strcmp(a, b);
  return c < 0 ? -1 : (c > 0 ? 1 : 0);
}

const char *lsm_base_name(const char *path) {
  const char *slash = strrchr(path, '/');
  return slash ? slash + 1 : path;
}

int lsm_name_number(const char *path, uint64_t *number) {
  const char *name = lsm_base_name(path), *dot = strrchr(name, '.');
  const char *end = dot && dot != name ? dot : name + strlen(name);
  while (end > name && !is_digit(end[-1])) --end;
  const char *start = end;
  while (start > name && is_digit(start[-1])) --start;
  while (start + 1 < end && *start == '0') ++start; /* leading zeros */
  if (start == end || end - start > 18) return 0;
  uint64_t n = 0;
  for (const char *c = start; c < end; ++c) n = 10u * n + (uint64_t)(*c - '0');
  *number = n;
  return 1;
}

static int cmp_paths(const void *a, const void *b) {
  const char *pa = *(const char *const *)a, *pb = *(const char *const *)b;
  return lsm_natural_cmp(lsm_base_name(pa), lsm_base_name(pb));
}

/* Whether name ends in "." ext, any case. */
static int has_extension(const char *name, const char *ext) {
  const size_t n = strlen(name), k = strlen(ext);
  if (n <= k || name[n - k - 1] != '.') return 0;
  for (size_t i = 0; i < k; ++i)
    if (tolower((unsigned char)name[n - k + i]) != ext[i]) return 0;
  return 1;
}

int lsm_is_tiff_name(const char *path) {
  return path && (has_extension(path, "tif") || has_extension(path, "tiff"));
}

int lsm_is_slice_image_name(const char *path) {
  return path && (has_extension(path, "png") || lsm_is_tiff_name(path));
}

/* Other image formats slices often come in (a note counts those left out). */
static int other_image(const char *name) {
  static const char *const exts[] = {"jpg", "jpeg", "bmp", "gif", "pgm", "ppm",
                                     "pbm", "pnm", "webp", "jp2", "dcm", NULL};
  for (const char *const *e = exts; *e; ++e)
    if (has_extension(name, *e)) return 1;
  return 0;
}

void lsm_path_list_free(char **paths, size_t count) {
  if (!paths) return;
  for (size_t i = 0; i < count; ++i) free(paths[i]);
  free(paths);
}

lsm_status lsm_dir_list_slices(const char *dir, char ***paths, size_t *count, size_t *others,
                            lsm_err *err) {
  if (paths) *paths = NULL;
  if (count) *count = 0;
  if (others) *others = 0;
  if (!dir || !paths || !count) return lsm_fail(err, LSM_ERR_INTERNAL, dir, "bad arguments to the folder listing");

  struct stat sb;
  if (stat(dir, &sb) != 0) {
    if (errno == ENOENT) return lsm_fail(err, LSM_ERR_INPUT, dir, "no such folder");
    return lsm_fail(err, LSM_ERR_INPUT, dir, "cannot access folder: %s", strerror(errno));
  }
  if (!S_ISDIR(sb.st_mode)) return lsm_fail(err, LSM_ERR_INPUT, dir, "not a folder");
  DIR *d = opendir(dir);
  if (!d) return lsm_fail(err, LSM_ERR_INPUT, dir, "cannot open folder: %s", strerror(errno));

  size_t dir_len = strlen(dir);
  int need_slash = dir_len > 0 && dir[dir_len - 1] != '/';
  char **list = NULL;
  size_t n = 0, cap = 0;
  lsm_status st = LSM_OK;
  for (;;) {
    errno = 0;
    struct dirent *e = readdir(d);
    if (!e) {
      if (errno != 0) st = lsm_fail(err, LSM_ERR_IO, dir, "cannot read folder: %s", strerror(errno));
      break;
    }
    const char *name = e->d_name;
    const int slice = lsm_is_slice_image_name(name);
    if (name[0] == '.' || (!slice && !(others && other_image(name)))) continue;
    size_t name_len = strlen(name);
    size_t len = dir_len + (size_t)need_slash + name_len + 1;
    char *path = malloc(len);
    if (!path) {
      st = lsm_fail(err, LSM_ERR_NOMEM, dir, "out of memory while listing the folder");
      break;
    }
    memcpy(path, dir, dir_len);
    if (need_slash) path[dir_len] = '/';
    memcpy(path + dir_len + (size_t)need_slash, name, name_len + 1);

    struct stat fs, ls;
    if (!slice) { /* another image format: counted when it is a regular file */
      if (stat(path, &fs) == 0 && S_ISREG(fs.st_mode)) ++*others;
      free(path);
      continue;
    }
    if (stat(path, &fs) != 0) {
      /* a file that vanished since the listing is skipped; a broken link is
       * an error (skipping it would shift every later slice's height) */
      if (errno == ENOENT && lstat(path, &ls) != 0) {
        free(path);
        continue;
      }
      st = lsm_fail(err, LSM_ERR_INPUT, path, "cannot access: %s",
                    errno == ENOENT ? "a link to nothing" : strerror(errno));
      free(path);
      break;
    }
    if (!S_ISREG(fs.st_mode)) {
      free(path);
      continue;
    }
    if (n == cap) {
      size_t new_cap = cap ? cap * 2 : 16, bytes;
      char **grown = NULL;
      if (new_cap > cap && lsm_size_mul(new_cap, sizeof *list, &bytes))
        grown = realloc(list, bytes);
      if (!grown) {
        st = lsm_fail(err, LSM_ERR_NOMEM, dir, "out of memory while listing the folder");
        free(path);
        break;
      }
      list = grown;
      cap = new_cap;
    }
    list[n++] = path;
  }
  closedir(d);
  if (st != LSM_OK) {
    lsm_path_list_free(list, n);
    return st;
  }
  if (n > 1) qsort(list, n, sizeof *list, cmp_paths);
  *paths = list;
  *count = n;
  return LSM_OK;
}

lsm_status lsm_make_dir(const char *path, lsm_err *err) {
  if (!path || !*path) return lsm_fail(err, LSM_ERR_INPUT, NULL, "empty folder name");
  if (mkdir(path, 0777) == 0) return LSM_OK;
  int e = errno;
  struct stat sb;
  if (e == EEXIST) {
    if (stat(path, &sb) == 0 && S_ISDIR(sb.st_mode)) return LSM_OK;
    return lsm_fail(err, LSM_ERR_INPUT, path, "exists and is not a folder");
  }
  return lsm_fail(err, LSM_ERR_IO, path, "cannot create folder: %s", strerror(e));
}

lsm_status lsm_read_file(const char *path, size_t max_bytes, char **data, size_t *length,
                         lsm_err *err) {
  if (data) *data = NULL;
  if (length) *length = 0;
  if (!path || !data) return lsm_fail(err, LSM_ERR_INTERNAL, path, "bad arguments to read a file");
  FILE *fp = fopen(path, "rb");
  if (!fp) return lsm_fail(err, LSM_ERR_INPUT, path, "cannot open: %s", strerror(errno));
  struct stat sb;
  int have_stat = fstat(fileno(fp), &sb) == 0;
  if (have_stat && S_ISDIR(sb.st_mode)) {
    fclose(fp);
    return lsm_fail(err, LSM_ERR_INPUT, path, "is a folder, not a file");
  }

  /* Read up to max_bytes + 1 so an oversized file is detected without
   * trusting the size reported by stat (pipes, growing files). */
  size_t cap = 4096, n = 0;
  if (have_stat && S_ISREG(sb.st_mode) && sb.st_size >= 0 &&
      (unsigned long long)sb.st_size < (unsigned long long)max_bytes)
    cap = (size_t)sb.st_size + 2;
  if (max_bytes < SIZE_MAX - 1 && cap > max_bytes + 2) cap = max_bytes + 2;
  char *buf = malloc(cap);
  lsm_status st = LSM_OK;
  if (!buf) st = lsm_fail(err, LSM_ERR_NOMEM, path, "cannot allocate %zu bytes", cap);
  while (st == LSM_OK) {
    if (n == cap - 1) { /* keep room for the terminating NUL */
      if (n > max_bytes) break;
      size_t new_cap = cap > SIZE_MAX / 2 ? SIZE_MAX : cap * 2;
      if (max_bytes < SIZE_MAX - 1 && new_cap > max_bytes + 2) new_cap = max_bytes + 2;
      char *grown = new_cap > cap ? realloc(buf, new_cap) : NULL;
      if (!grown) {
        st = lsm_fail(err, LSM_ERR_NOMEM, path, "cannot allocate %zu bytes", new_cap);
        break;
      }
      buf = grown;
      cap = new_cap;
    }
    size_t got = fread(buf + n, 1, cap - 1 - n, fp);
    n += got;
    if (got == 0) {
      if (ferror(fp)) st = lsm_fail(err, LSM_ERR_IO, path, "read error: %s", strerror(errno));
      break;
    }
    if (n > max_bytes) break;
  }
  if (st == LSM_OK && n > max_bytes)
    st = lsm_fail(err, LSM_ERR_LIMIT, path, "file is larger than the limit of %zu bytes", max_bytes);
  if (fclose(fp) != 0 && st == LSM_OK)
    st = lsm_fail(err, LSM_ERR_IO, path, "read error on close: %s", strerror(errno));
  if (st != LSM_OK) {
    free(buf);
    return st;
  }
  buf[n] = '\0';
  *data = buf;
  if (length) *length = n;
  return LSM_OK;
}

lsm_status lsm_close_written(FILE **fp, const char *path, lsm_status st, lsm_err *err) {
  if (!fp || !*fp) return st;
  if (st == LSM_OK && (fflush(*fp) != 0 || ferror(*fp)))
    st = lsm_fail(err, LSM_ERR_IO, path, "write failed: %s", strerror(errno));
  const int closed = fclose(*fp);
  const int close_errno = errno;
  *fp = NULL;
  if (closed != 0 && st == LSM_OK)
    st = lsm_fail(err, LSM_ERR_IO, path, "write failed on close: %s", strerror(close_errno));
  return st;
}

int lsm_rename_exchange(const char *a, const char *b) {
#if defined(__linux__) && defined(RENAME_EXCHANGE)
  return renameat2(AT_FDCWD, a, AT_FDCWD, b, RENAME_EXCHANGE);
#else
  (void)a;
  (void)b;
  errno = ENOSYS;
  return -1;
#endif
}
