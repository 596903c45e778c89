/* lsm_park: slices parked in an anonymous temporary file (see the header). */
#include "solver/recon/lsm_park.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

struct lsm_park {
  FILE *file;
  size_t cells;
};

lsm_status lsm_park_open(size_t cells, lsm_park **out, lsm_err *err) {
  *out = NULL;
  lsm_park *p = lsm_alloc(1, sizeof *p, err, "parked slices");
  if (!p) return err ? err->status : LSM_ERR_NOMEM;
  p->cells = cells;
  if (!(p->file = tmpfile())) {
    lsm_status st =
        lsm_fail(err, LSM_ERR_IO, NULL, "cannot create a temporary file: %s", strerror(errno));
    free(p);
    return st;
  }
  *out = p;
  return LSM_OK;
}

lsm_status lsm_park_put(lsm_park *p, size_t slot, const float *v, lsm_err *err) {
  if (fseeko(p->file, (off_t)(slot * p->cells * sizeof(float)), SEEK_SET) != 0 ||
      fwrite(v, sizeof(float), p->cells, p->file) != p->cells)
    return lsm_fail(err, LSM_ERR_IO, NULL, "cannot write a temporary file: %s", strerror(errno));
  return LSM_OK;
}

lsm_status lsm_park_get(lsm_park *p, size_t slot, float *v, lsm_err *err) {
  if (fseeko(p->file, (off_t)(slot * p->cells * sizeof(float)), SEEK_SET) != 0 ||
      fread(v, sizeof(float), p->cells, p->file) != p->cells)
    return lsm_fail(err, LSM_ERR_IO, NULL, "cannot read a temporary file");
  return LSM_OK;
}

void lsm_park_close(lsm_park **p) {
  if (!p || !*p) return;
  fclose((*p)->file);
  free(*p);
  *p = NULL;
}
