/* lsm_park: slices held in memory until their turn (see the header). */
#include "solver/recon/lsm_park.h"

#include <stdlib.h>
#include <string.h>

struct lsm_park {
  float *slots;
  size_t cells, count;
};

lsm_status lsm_park_open(size_t cells, size_t slots, double max_bytes, lsm_park **out,
                         lsm_err *err) {
  *out = NULL;
  size_t floats;
  const double bytes = (double)cells * (double)slots * sizeof(float);
  if (!lsm_size_mul(cells, slots ? slots : 1, &floats) || (max_bytes > 0.0 && bytes > max_bytes))
    return lsm_fail(err, LSM_ERR_LIMIT, NULL,
                    "%zu slices of %zu cells wait for their turn in reverse order: %.3g GB, "
                    "more than the %.3g GB of memory left for them (--max-memory)",
                    slots, cells, bytes / 1e9, max_bytes / 1e9);
  lsm_park *p = lsm_alloc(1, sizeof *p, err, "held slices");
  if (!p) return err ? err->status : LSM_ERR_NOMEM;
  p->slots = lsm_alloc(floats, sizeof(float), err, "the reverse morph's slices held for their turn");
  if (!p->slots) {
    free(p);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  p->cells = cells;
  p->count = slots;
  *out = p;
  return LSM_OK;
}

lsm_status lsm_park_put(lsm_park *p, size_t slot, const float *v, lsm_err *err) {
  if (slot >= p->count) return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "held slice %zu of %zu", slot, p->count);
  memcpy(p->slots + slot * p->cells, v, p->cells * sizeof(float));
  return LSM_OK;
}

lsm_status lsm_park_get(lsm_park *p, size_t slot, float *v, lsm_err *err) {
  if (slot >= p->count) return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "held slice %zu of %zu", slot, p->count);
  memcpy(v, p->slots + slot * p->cells, p->cells * sizeof(float));
  return LSM_OK;
}

void lsm_park_close(lsm_park **p) {
  if (!p || !*p) return;
  free((*p)->slots);
  free(*p);
  *p = NULL;
}
