/* lsm_slice_worker: slices reach the consumer whole and in order, on another
 * thread; the consumer's first error stops the producer and comes back from
 * close; a failed run drops what is queued; slices too large to copy are
 * consumed at once. */
#include "lsm_test.h"

#include <pthread.h>

#include "io/lsm_slice_worker.h"

#define W 17
#define H 9

typedef struct record {
  int seen;           /* slices consumed */
  int order_ok;       /* each slice's values and height were its own */
  int fail_at;        /* fail on this slice (-1: never) */
  int other_thread;   /* some slice was consumed on another thread */
  pthread_t producer;
} record;

static void fill(float *phi, int k) {
  for (int q = 0; q < W * H; ++q) phi[q] = (float)(k * 1000 + q);
}

static lsm_status consume(void *ctx, const float *phi, int width, int height, double z,
                          long input_index, lsm_err *err) {
  record *r = ctx;
  int ok = width == W && height == H && z == 0.5 * r->seen && input_index == (r->seen % 3 ? -1 : r->seen);
  for (int q = 0; q < W * H; ++q) ok &= phi[q] == (float)(r->seen * 1000 + q);
  r->order_ok &= ok;
  if (!pthread_equal(pthread_self(), r->producer)) r->other_thread = 1;
  if (r->seen == r->fail_at) return lsm_fail(err, LSM_ERR_IO, "slice.png", "write failed: disk full");
  r->seen++;
  return LSM_OK;
}

static lsm_status feed(lsm_slice_worker *w, int n, lsm_err *err) {
  float phi[W * H];
  for (int k = 0; k < n; ++k) {
    fill(phi, k);
    LSM_TRY(lsm_slice_worker_emit(w, phi, W, H, 0.5 * k, k % 3 ? -1 : k, err));
  }
  return LSM_OK;
}

static void test_in_order(void **state) {
  (void)state;
  record r = {0, 1, -1, 0, pthread_self()};
  lsm_slice_worker *w = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  /* room for 3 slices: the producer waits for the consumer */
  assert_int_equal(lsm_slice_worker_open(consume, &r, W, H, 3 * W * H * sizeof(float), &w, &err), LSM_OK);
  assert_int_equal(feed(w, 200, &err), LSM_OK);
  assert_int_equal(lsm_slice_worker_close(&w, LSM_OK, &err), LSM_OK);
  assert_null(w);
  assert_int_equal(r.seen, 200);
  assert_true(r.order_ok);
  assert_true(r.other_thread);
}

static void test_error_stops(void **state) {
  (void)state;
  record r = {0, 1, 7, 0, pthread_self()};
  lsm_slice_worker *w = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_slice_worker_open(consume, &r, W, H, 4 * W * H * sizeof(float), &w, &err), LSM_OK);
  lsm_status st = feed(w, 100, &err); /* fails once slice 7's error is seen */
  st = lsm_slice_worker_close(&w, st, &err);
  assert_int_equal(st, LSM_ERR_IO);
  assert_non_null(strstr(err.msg, "slice.png: write failed: disk full"));
  assert_int_equal(r.seen, 7);
  assert_true(r.order_ok);
}

static void test_failed_run_drops(void **state) {
  (void)state;
  record r = {0, 1, -1, 0, pthread_self()};
  lsm_slice_worker *w = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_slice_worker_open(consume, &r, W, H, 16 * W * H * sizeof(float), &w, &err), LSM_OK);
  assert_int_equal(feed(w, 10, &err), LSM_OK);
  lsm_fail(&err, LSM_ERR_NUMERIC, "gap", "blew up");
  assert_int_equal(lsm_slice_worker_close(&w, LSM_ERR_NUMERIC, &err), LSM_ERR_NUMERIC);
  assert_non_null(strstr(err.msg, "blew up")); /* the run's own error stays */
  assert_true(r.seen <= 10);
  assert_true(r.order_ok);
}

static void test_large_slices_direct(void **state) {
  (void)state;
  record r = {0, 1, -1, 0, pthread_self()};
  lsm_slice_worker *w = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  /* under two slices' room: consumed on the caller's thread, at once */
  assert_int_equal(lsm_slice_worker_open(consume, &r, W, H, W * H * sizeof(float), &w, &err), LSM_OK);
  assert_int_equal(feed(w, 5, &err), LSM_OK);
  assert_int_equal(r.seen, 5);
  assert_false(r.other_thread);
  assert_int_equal(lsm_slice_worker_close(&w, LSM_OK, &err), LSM_OK);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_in_order),
      cmocka_unit_test(test_error_stops),
      cmocka_unit_test(test_failed_run_drops),
      cmocka_unit_test(test_large_slices_direct),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
