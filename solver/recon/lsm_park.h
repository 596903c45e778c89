/* lsm_park: slices parked on disk until their turn.
 *
 * The reverse morph of a gap produces its snapshots in the opposite order to
 * the output (and per-iteration mode's reverse gaps likewise), so they wait
 * in an anonymous temporary file, one slot of `cells` floats each.  The one
 * place that does so.
 */
#ifndef LSM_PARK_H
#define LSM_PARK_H

#include <stddef.h>

#include "solver/base/lsm_status.h"

typedef struct lsm_park lsm_park;

/* Opens a park of slots of `cells` floats. */
lsm_status lsm_park_open(size_t cells, lsm_park **out, lsm_err *err);
/* Writes v (cells floats) to slot `slot`. */
lsm_status lsm_park_put(lsm_park *p, size_t slot, const float *v, lsm_err *err);
/* Reads slot `slot` into v. */
lsm_status lsm_park_get(lsm_park *p, size_t slot, float *v, lsm_err *err);
/* Closes the park (its file goes with it); NULL is fine. */
void lsm_park_close(lsm_park **p);

#endif
