/* lsm_park: slices held until their turn.
 *
 * The reverse morph of a gap produces its snapshots in the opposite order to
 * the output (and per-iteration mode's reverse gaps likewise), so they wait
 * in memory, one slot of `cells` floats each: as much as the gap's own
 * output, allocated at once when the count is known.  It is counted where a
 * gap's memory is: the scheduler's budget for gaps in flight
 * (lsm_schedule.c) and the estimate before any work (solver/app/lsm_checks).
 * There is no file behind it (it once was an unbounded tmpfile() in /tmp).
 * The one place that holds slices so.
 */
#ifndef LSM_PARK_H
#define LSM_PARK_H

#include <stddef.h>

#include "solver/base/lsm_status.h"

typedef struct lsm_park lsm_park;

/* Opens a park of `slots` slots of `cells` floats; LSM_ERR_LIMIT (with the
 * numbers) past max_bytes (0: no limit), LSM_ERR_NOMEM when they cannot be
 * allocated. */
lsm_status lsm_park_open(size_t cells, size_t slots, double max_bytes, lsm_park **out,
                         lsm_err *err);
/* Writes v (cells floats) to slot `slot` (< slots). */
lsm_status lsm_park_put(lsm_park *p, size_t slot, const float *v, lsm_err *err);
/* Reads slot `slot` into v. */
lsm_status lsm_park_get(lsm_park *p, size_t slot, float *v, lsm_err *err);
/* Frees the park; NULL is fine. */
void lsm_park_close(lsm_park **p);

#endif
