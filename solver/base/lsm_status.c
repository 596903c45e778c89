#include "solver/base/lsm_status.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *lsm_status_name(lsm_status status) {
  static const char *const names[] = {
#define LSM_STATUS_NAME(code, text) text,
      LSM_STATUS_LIST(LSM_STATUS_NAME)
#undef LSM_STATUS_NAME
  };
  if ((int)status < 0 || status >= LSM_STATUS_COUNT) return "unknown status";
  return names[status];
}

void lsm_err_clear(lsm_err *err) {
  if (!err) return;
  err->status = LSM_OK;
  err->msg[0] = '\0';
}

lsm_status lsm_fail(lsm_err *err, lsm_status status, const char *where,
                    const char *fmt, ...) {
  if (!err || err->status != LSM_OK) return status;
  err->status = status;
  size_t used = 0;
  if (where) { /* an empty name still shows where: '' */
    int n = snprintf(err->msg, sizeof err->msg, "%s: ", *where ? where : "''");
    used = n < 0 ? 0 : ((size_t)n >= sizeof err->msg ? sizeof err->msg - 1 : (size_t)n);
  }
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(err->msg + used, sizeof err->msg - used, fmt, ap);
  va_end(ap);
  return status;
}

int lsm_size_mul(size_t a, size_t b, size_t *out) {
  if (a != 0 && b > SIZE_MAX / a) return 0;
  *out = a * b;
  return 1;
}

int lsm_size_mul3(size_t a, size_t b, size_t c, size_t *out) {
  size_t ab;
  return lsm_size_mul(a, b, &ab) && lsm_size_mul(ab, c, out);
}

void *lsm_alloc(size_t count, size_t size, lsm_err *err, const char *what) {
  size_t bytes;
  if (!lsm_size_mul(count, size, &bytes)) {
    lsm_fail(err, LSM_ERR_LIMIT, NULL, "%s: size overflows", what ? what : "allocation");
    return NULL;
  }
  void *p = malloc(bytes ? bytes : 1);
  if (!p) lsm_fail(err, LSM_ERR_NOMEM, NULL, "%s: cannot allocate %zu bytes", what ? what : "allocation", bytes);
  return p;
}
