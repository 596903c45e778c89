/* The checks the image-reader harnesses (fuzz_png.c, fuzz_tiff.c) make on a
 * read: on success a mask of positive size within max_pixels holding only
 * 0/1 pixels (freed here); on failure an error recorded with that status,
 * its message naming the file ("NAME: ..."), and no mask.  Aborts otherwise,
 * as libFuzzer expects of a failed check. */
#ifndef LSM_FUZZ_MASK_H
#define LSM_FUZZ_MASK_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/lsm_io.h"

static inline void fuzz_check_mask(lsm_status st, lsm_mask *m, const lsm_err *err,
                                   uint64_t max_pixels, const char *name) {
  if (st == LSM_OK) {
    if (m->width <= 0 || m->height <= 0 || !m->pixels) abort();
    if ((uint64_t)m->width * (uint64_t)m->height > max_pixels) abort();
    const size_t n = (size_t)m->width * (size_t)m->height;
    for (size_t k = 0; k < n; ++k)
      if (m->pixels[k] > 1) abort();
    lsm_mask_free(m);
  } else {
    const size_t len = strlen(name);
    if (err->status != st || err->msg[0] == '\0' || m->pixels) abort();
    if (strncmp(err->msg, name, len) != 0 || strncmp(err->msg + len, ": ", 2) != 0) abort();
  }
}

/* Reads the size bytes at data (kept alive by the caller) as the file name
 * through read, from fmemopen() memory, with --invert and the label rule
 * from bits 0 and 1 of `last` (the input's last byte, before any repair) and
 * a 4 Mpixel limit, and checks the result (fuzz_check_mask). */
typedef lsm_status (*fuzz_mask_reader)(FILE *fp, const char *name, const lsm_image_read_opts *opts,
                                       lsm_mask *out, lsm_err *err);
static inline void fuzz_read_mask(uint8_t *data, size_t size, uint8_t last, fuzz_mask_reader read,
                                  const char *name) {
  FILE *fp = fmemopen(data, size, "rb");
  if (!fp) abort();
  lsm_image_read_opts opts = {last & 1, (uint64_t)1 << 22, (last >> 1) & 1};
  lsm_mask m;
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = read(fp, name, &opts, &m, &err);
  fclose(fp);
  fuzz_check_mask(st, &m, &err, opts.max_pixels, name);
}

#endif
