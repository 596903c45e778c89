/* Helpers shared by the cmocka tests of the io room (tests/test_io_*.c): a
 * fresh temporary folder per test (setup_tmp / teardown_tmp), paths in it, whole
 * files written and read back, and a check on an error message's text. */
#ifndef LSM_TEST_IO_H
#define LSM_TEST_IO_H

#include "tests/lsm_test.h"

#include <dirent.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include "io/lsm_io.h"

/* ---- fixture: a fresh temporary folder per test ------------------------------ */

typedef struct tmp_fixture {
  char dir[64];
} tmp_fixture;

static inline void rm_rf(const char *path) {
  struct stat sb;
  if (lstat(path, &sb) != 0) return;
  if (S_ISDIR(sb.st_mode)) {
    DIR *d = opendir(path);
    if (d) {
      struct dirent *e;
      while ((e = readdir(d)) != NULL) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
        char child[1024];
        int n = snprintf(child, sizeof child, "%s/%s", path, e->d_name);
        if (n < 0 || (size_t)n >= sizeof child) continue; /* no such path here */
        rm_rf(child);
      }
      closedir(d);
    }
    rmdir(path);
  } else {
    unlink(path);
  }
}

static inline int setup_tmp(void **state) {
  tmp_fixture *f = malloc(sizeof *f);
  if (!f) return -1;
  snprintf(f->dir, sizeof f->dir, "/tmp/lsm_test_io_XXXXXX");
  if (!mkdtemp(f->dir)) {
    free(f);
    return -1;
  }
  *state = f;
  return 0;
}

static inline int teardown_tmp(void **state) {
  tmp_fixture *f = *state;
  if (f) {
    rm_rf(f->dir);
    free(f);
  }
  return 0;
}

static inline void join(char *out, size_t size, const char *dir, const char *name) {
  int n = snprintf(out, size, "%s/%s", dir, name);
  assert_true(n > 0 && (size_t)n < size);
}

static inline void write_bytes(const char *path, const void *data, size_t len) {
  FILE *fp = fopen(path, "wb");
  assert_non_null(fp);
  if (len) assert_int_equal(fwrite(data, 1, len, fp), len);
  assert_int_equal(fclose(fp), 0);
}

static inline uint8_t *read_bytes(const char *path, size_t *len) {
  char *data = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_read_file(path, (size_t)1 << 30, &data, len, &err), LSM_OK);
  return (uint8_t *)data;
}

#define assert_msg_contains(err, text)                                                \
  do {                                                                                \
    if (!strstr((err).msg, (text)))                                                   \
      fail_msg("message \"%s\" does not contain \"%s\"", (err).msg, (text));          \
  } while (0)

#endif
