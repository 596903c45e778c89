/* libFuzzer harness for the PNG reader (io/io_png.c).
 *
 *   make fuzz            builds build/fuzz/fuzz_png and runs it on tests/fuzz/corpus/png
 *   build/fuzz/fuzz_png -max_total_time=60 tests/fuzz/corpus/png
 *
 * Each input is a whole file: it is handed to lsm_png_read_mask_stream through
 * fmemopen(), so no temporary file is written.  Bit 0 of the last byte selects
 * --invert; when bit 1 is set the harness first rewrites every chunk CRC to
 * the right value, so that mutated headers and chunks get past libpng's CRC
 * check (libpng itself is not instrumented, so the fuzzer cannot learn the CRC).
 * Checks: on success the mask has the header's positive size and only 0/1
 * pixels; on failure an error message was recorded.  The pixel limit is kept
 * small (4 Mpixel) so that the fuzzer explores formats rather than big
 * allocations; the limit itself is exercised by the seed "huge_ihdr.png". */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/lsm_io.h"
#include "tests/fuzz/fuzz_mask.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static uint32_t crc32_png(const uint8_t *p, size_t n) {
  uint32_t c = 0xffffffffu;
  for (size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
  }
  return c ^ 0xffffffffu;
}

/* Rewrites the CRC of every complete chunk after the 8-byte signature. */
static void fix_crcs(uint8_t *d, size_t size) {
  size_t pos = 8;
  while (pos + 12 <= size) {
    const uint32_t len = (uint32_t)d[pos] << 24 | (uint32_t)d[pos + 1] << 16 |
                         (uint32_t)d[pos + 2] << 8 | d[pos + 3];
    if (len > size - pos - 12) break;
    const uint32_t crc = crc32_png(d + pos + 4, (size_t)len + 4);
    uint8_t *c = d + pos + 8 + len;
    c[0] = (uint8_t)(crc >> 24);
    c[1] = (uint8_t)(crc >> 16);
    c[2] = (uint8_t)(crc >> 8);
    c[3] = (uint8_t)crc;
    pos += (size_t)len + 12;
  }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size == 0) return 0; /* fmemopen cannot open an empty buffer for reading */
  uint8_t *copy = malloc(size);
  if (!copy) abort();
  memcpy(copy, data, size);
  if (data[size - 1] & 2) fix_crcs(copy, size);
  fuzz_read_mask(copy, size, data[size - 1], lsm_png_read_mask_stream, "fuzz.png");
  free(copy);
  return 0;
}
