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
#include "tests/fuzz/fuzz_mask.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size == 0) return 0; /* fmemopen cannot open an empty buffer for reading */
  uint8_t *copy = malloc(size);
  if (!copy) abort();
  memcpy(copy, data, size);
  fuzz_read_mask(copy, size, data[size - 1], lsm_tiff_read_mask_stream, "fuzz.tif");
  free(copy);
  return 0;
}
