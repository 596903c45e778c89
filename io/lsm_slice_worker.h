/* lsm_slice_worker: a slice consumer run on a thread of its own, so that
 * writing the outputs of a slice (volume, slice PNG, previews, mesh) overlaps
 * the solver's work on the next ones.
 *
 * Slices are copied into a ring of buffers and handed, in order, to the
 * consumer on the worker thread; the producer waits only when the ring is
 * full.  The first error of the consumer is kept: the next emit returns it
 * (so the solver stops), and so does close.  Slices larger than half the
 * ring's byte budget are handed on at once, on the caller's thread, without
 * a copy.  The consumer must not be used by another thread until close.
 */
#ifndef LSM_SLICE_WORKER_H
#define LSM_SLICE_WORKER_H

#include <stddef.h>

#include "solver/base/lsm_status.h"

/* A slice consumer: phi is width * height floats, row 0 first, at height z;
 * input_index >= 0 marks a slice that reproduces an input. */
typedef lsm_status (*lsm_slice_consumer)(void *ctx, const float *phi, int width, int height,
                                         double z, long input_index, lsm_err *err);

typedef struct lsm_slice_worker lsm_slice_worker;

/* Starts the worker for slices of width x height, with at most max_bytes of
 * slice copies in its ring (2 to 16 buffers). */
lsm_status lsm_slice_worker_open(lsm_slice_consumer consume, void *ctx, int width, int height,
                                 size_t max_bytes, lsm_slice_worker **out, lsm_err *err);
/* Queues a copy of the slice (a consumer itself: worker is the context). */
lsm_status lsm_slice_worker_emit(void *worker, const float *phi, int width, int height, double z,
                                 long input_index, lsm_err *err);
/* Waits for the queued slices to be consumed (or, when st is not LSM_OK,
 * drops them) and stops the thread; returns st, or else the consumer's
 * first error.  *w is NULL afterwards. */
lsm_status lsm_slice_worker_close(lsm_slice_worker **w, lsm_status st, lsm_err *err);

#endif
