/* Common includes for lsmorph's cmocka tests. */
#ifndef LSM_TEST_H
#define LSM_TEST_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A fixed-seed xorshift generator so tests are reproducible. */
static inline uint64_t lsm_test_rand(uint64_t *state) {
  uint64_t x = *state;
  x ^= x << 13;
  x ^= x >> 7;
  x ^= x << 17;
  return *state = x;
}

#define assert_close(a, b, tol)                                                   \
  do {                                                                            \
    double lsm_a_ = (double)(a), lsm_b_ = (double)(b), lsm_t_ = (double)(tol);    \
    if (!(fabs(lsm_a_ - lsm_b_) <= lsm_t_)) {                                     \
      fail_msg("%s = %.9g, %s = %.9g, differ by more than %g", #a, lsm_a_, #b,    \
               lsm_b_, lsm_t_);                                                   \
    }                                                                             \
  } while (0)

#endif
