/* lsm_slice_worker: slices consumed on a thread of their own (see the header). */
#include "io/lsm_slice_worker.h"

#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define RING_MAX 16

typedef struct queued {
  float *phi;
  double z;
  long input_index;
} queued;

struct lsm_slice_worker {
  lsm_slice_consumer consume;
  void *ctx;
  int width, height;
  size_t cells;
  int direct; /* slices too large to copy: consumed on the caller's thread */
  queued ring[RING_MAX];
  int slots, head, count; /* next slot to consume, slots filled */
  int closing, dropping;
  lsm_status status; /* the consumer's first error */
  lsm_err error;
  pthread_mutex_t lock;
  pthread_cond_t changed;
  pthread_t thread;
  int started;
};

static void *work(void *arg) {
  lsm_slice_worker *w = arg;
  pthread_mutex_lock(&w->lock);
  for (;;) {
    while (w->count == 0 && !w->closing) pthread_cond_wait(&w->changed, &w->lock);
    if (w->count == 0) break; /* closing, and nothing left */
    queued *q = &w->ring[w->head];
    const int skip = w->status != LSM_OK || w->dropping;
    pthread_mutex_unlock(&w->lock);
    lsm_err err;
    lsm_err_clear(&err);
    const lsm_status st =
        skip ? LSM_OK : w->consume(w->ctx, q->phi, w->width, w->height, q->z, q->input_index, &err);
    pthread_mutex_lock(&w->lock);
    if (st != LSM_OK && w->status == LSM_OK) {
      w->status = st;
      w->error = err;
    }
    w->head = (w->head + 1) % w->slots;
    w->count--;
    pthread_cond_broadcast(&w->changed);
  }
  pthread_mutex_unlock(&w->lock);
  return NULL;
}

static void worker_free(lsm_slice_worker *w) {
  for (int k = 0; k < RING_MAX; ++k) free(w->ring[k].phi);
  free(w);
}

lsm_status lsm_slice_worker_open(lsm_slice_consumer consume, void *ctx, int width, int height,
                                 size_t max_bytes, lsm_slice_worker **out, lsm_err *err) {
  if (out) *out = NULL;
  if (!consume || !out || width <= 0 || height <= 0)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "bad arguments to start the slice writer");
  lsm_slice_worker *w = calloc(1, sizeof *w);
  if (!w) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the slice writer");
  w->consume = consume;
  w->ctx = ctx;
  w->width = width;
  w->height = height;
  w->cells = (size_t)width * (size_t)height;
  const size_t bytes = w->cells * sizeof(float);
  w->direct = bytes > max_bytes / 2 || w->cells > SIZE_MAX / sizeof(float);
  if (!w->direct) {
    w->slots = max_bytes / bytes < RING_MAX ? (int)(max_bytes / bytes) : RING_MAX;
    for (int k = 0; k < w->slots; ++k)
      if (!(w->ring[k].phi = malloc(bytes))) {
        worker_free(w);
        return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the slice writer's buffers");
      }
    if (pthread_mutex_init(&w->lock, NULL) != 0) {
      worker_free(w);
      return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot start the slice writer");
    }
    if (pthread_cond_init(&w->changed, NULL) != 0) {
      pthread_mutex_destroy(&w->lock);
      worker_free(w);
      return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot start the slice writer");
    }
    if (pthread_create(&w->thread, NULL, work, w) != 0) {
      pthread_cond_destroy(&w->changed);
      pthread_mutex_destroy(&w->lock);
      w->direct = 1; /* no thread to be had: consume on the caller's thread */
    } else {
      w->started = 1;
    }
  }
  *out = w;
  return LSM_OK;
}

lsm_status lsm_slice_worker_emit(void *worker, const float *phi, int width, int height, double z,
                                 long input_index, lsm_err *err) {
  lsm_slice_worker *w = worker;
  if (!w || !phi || width != w->width || height != w->height)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "bad arguments to queue a slice");
  if (!w->started) return w->consume(w->ctx, phi, width, height, z, input_index, err);
  pthread_mutex_lock(&w->lock);
  while (w->count == w->slots && w->status == LSM_OK) pthread_cond_wait(&w->changed, &w->lock);
  if (w->status != LSM_OK) {
    const lsm_status st = w->status;
    if (err) *err = w->error;
    pthread_mutex_unlock(&w->lock);
    return st;
  }
  queued *q = &w->ring[(w->head + w->count) % w->slots];
  pthread_mutex_unlock(&w->lock);
  /* the slot is the producer's until counted in */
  memcpy(q->phi, phi, w->cells * sizeof *phi);
  q->z = z;
  q->input_index = input_index;
  pthread_mutex_lock(&w->lock);
  w->count++;
  pthread_cond_broadcast(&w->changed);
  pthread_mutex_unlock(&w->lock);
  return LSM_OK;
}

lsm_status lsm_slice_worker_close(lsm_slice_worker **wp, lsm_status st, lsm_err *err) {
  if (!wp || !*wp) return st;
  lsm_slice_worker *w = *wp;
  *wp = NULL;
  if (w->started) {
    pthread_mutex_lock(&w->lock);
    w->closing = 1;
    w->dropping = st != LSM_OK;
    pthread_cond_broadcast(&w->changed);
    pthread_mutex_unlock(&w->lock);
    pthread_join(w->thread, NULL);
    pthread_cond_destroy(&w->changed);
    pthread_mutex_destroy(&w->lock);
    if (st == LSM_OK && w->status != LSM_OK) {
      st = w->status;
      if (err) *err = w->error;
    }
  }
  worker_free(w);
  return st;
}
