/* libFuzzer harness for the heights parser (lsm_heights_parse, io/io_heights.c).
 *
 * Each input is the text of a heights file (any bytes, NULs included).
 * Checks: on success at least one height, all finite and strictly increasing;
 * on failure a message that names the file. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "io/lsm_io.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  /* An exact-size copy, without a terminating NUL, so reading past the end is caught. */
  char *text = malloc(size ? size : 1);
  if (!text) abort();
  if (size) memcpy(text, data, size);
  double *z = NULL;
  size_t n = 0;
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = lsm_heights_parse(text, size, "h.txt", &z, &n, &err);
  if (st == LSM_OK) {
    if (n == 0 || !z) abort();
    for (size_t k = 0; k < n; ++k) {
      if (!isfinite(z[k])) abort();
      if (k > 0 && !(z[k] > z[k - 1])) abort();
    }
  } else {
    if (z || n || err.status != st || strncmp(err.msg, "h.txt: ", 7) != 0) abort();
  }
  free(z);
  free(text);
  return 0;
}
