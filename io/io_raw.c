/* io_raw: the JSON sidecar of volume.raw (headerless samples, x fastest, then
 * rows, then slices; float32 or uint8, little endian). */
#include "io/lsm_io.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

lsm_status lsm_raw_write_json(const char *path, const char *data_file,
                              const lsm_volume_info *info, lsm_err *err) {
  if (!path || !data_file || !info)
    return lsm_fail(err, LSM_ERR_INTERNAL, path, "bad arguments to the raw sidecar writer");
  FILE *f = fopen(path, "w");
  if (!f) return lsm_fail(err, LSM_ERR_IO, path, "cannot create: %s", strerror(errno));
  const int mask = info->values == LSM_VALUES_MASK;
  fputs("{\n  \"file\": ", f);
  lsm_json_string(f, data_file);
  fprintf(f, ",\n  \"sizes\": [%d, %d, %zu],\n  \"spacing\": [", info->nx, info->ny, info->nz);
  lsm_json_number(f, info->sx);
  fputs(", ", f);
  lsm_json_number(f, info->sy);
  fputs(", ", f);
  lsm_json_number(f, info->sz);
  fputs("],\n  \"origin\": [", f);
  lsm_json_number(f, info->ox);
  fputs(", ", f);
  lsm_json_number(f, info->oy);
  fputs(", ", f);
  lsm_json_number(f, info->oz);
  fprintf(f,
          "],\n  \"dtype\": \"%s\",\n  \"endianness\": \"little\",\n  \"header_bytes\": 0,\n"
          "  \"order\": \"x fastest, then y (image row), then z (slice)\",\n"
          "  \"values\": \"%s\",\n  \"description\": \"%s\"\n}\n",
          mask ? "uint8" : "float32", mask ? "mask" : "sdf",
          mask ? "255 inside (phi <= 0), 0 outside"
               : "signed distance in physical units, negative inside");
  int bad = ferror(f);
  int e = errno;
  if (fclose(f) != 0 || bad)
    return lsm_fail(err, LSM_ERR_IO, path, "write failed: %s", strerror(bad ? e : errno));
  return LSM_OK;
}
