/* libFuzzer harness for the TIFF reader (io/io_tiff.c).
 *
 *   make fuzz            builds build/fuzz/fuzz_tiff and runs it on tests/fuzz/corpus/tiff
 *   build/fuzz/fuzz_tiff -max_total_time=60 tests/fuzz/corpus/tiff
 *
 * Each input is a whole file, handed to lsm_tiff_read_mask_stream through
 * fmemopen(): no temporary file is written.  Bits 0 and 1 of the last byte
 * select --invert and the label rule (nonzero).  Checks: on success the mask
 * has a positive size within the pixel limit and only 0/1 pixels; on
 * failure an error message naming the file was recorded.  The pixel limit is
 * kept small (4 Mpixel) so that the fuzzer explores layouts rather than big
 * allocations. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/lsm_io.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size == 0) return 0; /* fmemopen cannot open an empty buffer for reading */
  uint8_t *copy = malloc(size);
  if (!copy) abort();
  memcpy(copy, data, size);
  FILE *fp = fmemopen(copy, size, "rb");
  if (!fp) abort();
  lsm_png_read_opts opts = {data[size - 1] & 1, (uint64_t)1 << 22, (data[size - 1] >> 1) & 1};
  lsm_mask m;
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = lsm_tiff_read_mask_stream(fp, "fuzz.tif", &opts, &m, &err);
  fclose(fp);
  free(copy);
  if (st == LSM_OK) {
    if (m.width <= 0 || m.height <= 0 || !m.pixels) abort();
    if ((uint64_t)m.width * (uint64_t)m.height > opts.max_pixels) abort();
    const size_t n = (size_t)m.width * (size_t)m.height;
    for (size_t k = 0; k < n; ++k)
      if (m.pixels[k] > 1) abort();
    lsm_mask_free(&m);
  } else {
    if (err.status != st || err.msg[0] == '\0' || m.pixels) abort();
    if (strncmp(err.msg, "fuzz.tif: ", 10) != 0) abort(); /* every message names the file */
  }
  return 0;
}
