/* lsm_status: status codes and error context shared by every lsmorph module.
 *
 * Errors are values.  A function that can fail returns an lsm_status and, when
 * given a non-NULL lsm_err, records a message "<where>: <what>" in it.  The
 * command line prints that message as "lsmorph: error: <where>: <what>".
 * There is no global error state.
 */
#ifndef LSM_STATUS_H
#define LSM_STATUS_H

#include <stddef.h>

/* One list builds both the enum and lsm_status_name(). Add new items at the end. */
#define LSM_STATUS_LIST(X)                                                   \
  X(LSM_OK, "ok")                                                            \
  X(LSM_ERR_USAGE, "usage error")                                            \
  X(LSM_ERR_INPUT, "bad input")                                              \
  X(LSM_ERR_IO, "input/output error")                                        \
  X(LSM_ERR_NOMEM, "out of memory")                                          \
  X(LSM_ERR_LIMIT, "resource limit exceeded")                                \
  X(LSM_ERR_NUMERIC, "numerical failure")                                    \
  X(LSM_ERR_INTERRUPTED, "interrupted")                                      \
  X(LSM_ERR_UNSUPPORTED, "not supported")                                    \
  X(LSM_ERR_INTERNAL, "internal error")

typedef enum lsm_status {
#define LSM_STATUS_ENUM(code, text) code,
  LSM_STATUS_LIST(LSM_STATUS_ENUM)
#undef LSM_STATUS_ENUM
  LSM_STATUS_COUNT
} lsm_status;

#define LSM_ERR_MSG_MAX 1024

/* Error context: the first failure recorded wins (later ones add nothing). */
typedef struct lsm_err {
  lsm_status status;
  char msg[LSM_ERR_MSG_MAX];
} lsm_err;

/* Short name of a status ("bad input"). Never NULL. */
const char *lsm_status_name(lsm_status status);

/* Clears an error context. */
void lsm_err_clear(lsm_err *err);

/* Records "<where>: <printf-formatted what>" (or just "<what>" when where is
 * NULL; an empty where reads '') in err if err is non-NULL and holds no earlier error; returns status.
 * Typical use:  return lsm_fail(err, LSM_ERR_INPUT, path, "not a PNG file"); */
lsm_status lsm_fail(lsm_err *err, lsm_status status, const char *where,
                    const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* Evaluate an expression returning lsm_status; return it from the caller on failure. */
#define LSM_TRY(expr)                                                        \
  do {                                                                       \
    lsm_status lsm_try_status_ = (expr);                                     \
    if (lsm_try_status_ != LSM_OK) return lsm_try_status_;                   \
  } while (0)

/* Overflow-checked size arithmetic: return 0 on overflow, 1 on success. */
int lsm_size_mul(size_t a, size_t b, size_t *out);
int lsm_size_mul3(size_t a, size_t b, size_t c, size_t *out);

/* malloc of count*size bytes with an overflow check; records LSM_ERR_NOMEM. */
void *lsm_alloc(size_t count, size_t size, lsm_err *err, const char *what);

#endif
