/* Replays fuzz inputs without libFuzzer: linked with one fuzz_*.c harness by
 * the normal compiler, it runs LLVMFuzzerTestOneInput on every file named on
 * the command line (folders: every file in them).  make test uses it to keep
 * the seed corpora and the crash regressions passing
 * (tests/test_fuzz_corpus.sh).  A failing input aborts, as under libFuzzer. */
#include <dirent.h>
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int run_file(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "replay: %s: %s\n", path, strerror(errno));
    return 1;
  }
  size_t cap = 4096, n = 0;
  uint8_t *buf = malloc(cap);
  for (;;) {
    if (!buf) {
      fprintf(stderr, "replay: %s: out of memory\n", path);
      fclose(f);
      return 1;
    }
    n += fread(buf + n, 1, cap - n, f);
    if (n < cap) break;
    uint8_t *grown = realloc(buf, cap * 2);
    if (!grown) free(buf);
    buf = grown;
    cap *= 2;
  }
  int bad = ferror(f);
  fclose(f);
  if (bad) {
    fprintf(stderr, "replay: %s: read error\n", path);
    free(buf);
    return 1;
  }
  /* An exact-size copy, so reading past the end is caught by the sanitizers. */
  uint8_t *data = malloc(n ? n : 1);
  if (!data) {
    free(buf);
    return 1;
  }
  if (n) memcpy(data, buf, n);
  free(buf);
  LLVMFuzzerTestOneInput(data, n);
  free(data);
  return 0;
}

int main(int argc, char **argv) {
  int failures = 0, files = 0;
  for (int a = 1; a < argc; ++a) {
    struct stat sb;
    if (stat(argv[a], &sb) != 0) {
      fprintf(stderr, "replay: %s: %s\n", argv[a], strerror(errno));
      ++failures;
      continue;
    }
    if (!S_ISDIR(sb.st_mode)) {
      failures += run_file(argv[a]);
      ++files;
      continue;
    }
    DIR *d = opendir(argv[a]);
    if (!d) {
      fprintf(stderr, "replay: %s: %s\n", argv[a], strerror(errno));
      ++failures;
      continue;
    }
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
      if (e->d_name[0] == '.') continue;
      char path[4096];
      snprintf(path, sizeof path, "%s/%s", argv[a], e->d_name);
      if (stat(path, &sb) != 0 || !S_ISREG(sb.st_mode)) continue;
      failures += run_file(path);
      ++files;
    }
    closedir(d);
  }
  printf("replay: %d inputs, %d unreadable\n", files, failures);
  return failures != 0;
}
