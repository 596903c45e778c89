/* libFuzzer harness for the label-volume readers (io/lsm_labels.h: NRRD
 * through teem, NIfTI through nifticlib).
 *
 * Each input is a file's bytes, written to a temporary file whose name says
 * the format its first bytes look like (NRRD magic: .nrrd; a gzip stream:
 * .nii.gz; anything else: .nii), then read with a limit of 2^22 voxels and
 * made integer.  Checks: on success a volume within the limit whose spacings
 * are positive lengths; on failure a message that names the file. */
#define _DEFAULT_SOURCE /* mkstemps */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "io/lsm_labels.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *suffix = size >= 4 && memcmp(data, "NRRD", 4) == 0       ? ".nrrd"
                       : size >= 2 && data[0] == 0x1f && data[1] == 0x8b ? ".nii.gz"
                                                                          : ".nii";
  char path[64];
  snprintf(path, sizeof path, "/tmp/fuzz_labels_XXXXXX%s", suffix);
  const int fd = mkstemps(path, (int)strlen(suffix));
  if (fd < 0) abort();
  FILE *fp = fdopen(fd, "wb");
  if (!fp || (size && fwrite(data, 1, size, fp) != size) || fclose(fp) != 0) abort();
  lsm_label_file *f = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  const uint64_t limit = (uint64_t)1 << 22;
  lsm_status st = lsm_labels_read(path, limit, &f, &err);
  int converted = 0;
  if (st == LSM_OK) {
    const lsm_voxels *v = lsm_labels_voxels(f);
    if (!v->data || (uint64_t)v->n[0] * v->n[1] * v->n[2] > limit) abort();
    for (int a = 0; a < 3; ++a)
      if (!(v->spacing[a] > 0.0) || !isfinite(v->spacing[a])) abort();
    st = lsm_labels_to_integer(f, &converted, &err);
  }
  if (st != LSM_OK && (err.status != st || strncmp(err.msg, path, strlen(path)) != 0)) abort();
  lsm_labels_free(&f);
  unlink(path);
  return 0;
}
