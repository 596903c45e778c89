/* io_heights: the heights text file, one z value per slice. */
#include "io/lsm_io.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define HEIGHTS_MAX_BYTES ((size_t)64 * 1024 * 1024)
#define QUOTE_MAX 40 /* characters of a bad line quoted in a message */

static int is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/* A printable, possibly shortened copy of a bad token for messages. */
static void quote_token(char *out, size_t size, const char *tok) {
  size_t n = strlen(tok), j = 0;
  for (size_t i = 0; i < n && j + 4 < size && i < QUOTE_MAX; ++i) {
    unsigned char c = (unsigned char)tok[i];
    out[j++] = (c >= 0x20 && c < 0x7f) ? (char)c : '?';
  }
  if (n > QUOTE_MAX && j + 4 < size) {
    out[j++] = '.';
    out[j++] = '.';
    out[j++] = '.';
  }
  out[j] = '\0';
}

int lsm_decimal_syntax(const char *s) {
  if (*s == '+' || *s == '-') ++s;
  int digits = 0;
  while (*s >= '0' && *s <= '9') ++s, ++digits;
  if (*s == '.') {
    ++s;
    while (*s >= '0' && *s <= '9') ++s, ++digits;
  }
  if (!digits) return 0;
  if (*s == 'e' || *s == 'E') {
    ++s;
    if (*s == '+' || *s == '-') ++s;
    if (!(*s >= '0' && *s <= '9')) return 0;
    while (*s >= '0' && *s <= '9') ++s;
  }
  return *s == '\0';
}

lsm_status lsm_heights_parse(const char *text, size_t length, const char *name,
                             double **z, size_t *count, lsm_err *err) {
  if (z) *z = NULL;
  if (count) *count = 0;
  if (!z || !count) return lsm_fail(err, LSM_ERR_INTERNAL, name, "bad arguments to the heights parser");
  if (!text) length = 0;

  char *line = malloc(length + 1); /* scratch copy of one line, NUL-terminated */
  if (!line) return lsm_fail(err, LSM_ERR_NOMEM, name, "cannot allocate %zu bytes", length + 1);
  double *values = NULL;
  size_t n = 0, cap = 0, line_no = 0;
  lsm_status st = LSM_OK;
  size_t pos = 0;
  if (length >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0) pos = 3; /* a UTF-8 byte order mark */
  while (st == LSM_OK && pos < length) {
    ++line_no;
    const char *start = text + pos;
    const char *nl = memchr(start, '\n', length - pos);
    size_t len = nl ? (size_t)(nl - start) : length - pos;
    pos += len + (nl ? 1 : 0);

    /* a comment runs from '#' to the end of the line; trim the rest */
    const char *hash = memchr(start, '#', len);
    if (hash) len = (size_t)(hash - start);
    while (len > 0 && is_space(*start)) ++start, --len;
    while (len > 0 && is_space(start[len - 1])) --len;
    if (len == 0) continue;
    if (memchr(start, '\0', len)) {
      st = lsm_fail(err, LSM_ERR_INPUT, name, "line %zu: contains a NUL byte", line_no);
      break;
    }
    memcpy(line, start, len);
    line[len] = '\0';

    char quoted[QUOTE_MAX + 8];
    quote_token(quoted, sizeof quoted, line);
    if (!lsm_decimal_syntax(line)) {
      st = lsm_fail(err, LSM_ERR_INPUT, name, "line %zu: \"%s\" is not a number", line_no, quoted);
      break;
    }
    errno = 0;
    char *end = NULL;
    double v = strtod(line, &end);
    if (end == line || *end != '\0') { /* cannot happen after the syntax check */
      st = lsm_fail(err, LSM_ERR_INPUT, name, "line %zu: \"%s\" is not a number", line_no, quoted);
      break;
    }
    if (!isfinite(v) || errno == ERANGE) { /* overflow, or underflow to 0 or a subnormal */
      st = lsm_fail(err, LSM_ERR_INPUT, name, "line %zu: \"%s\" is out of range", line_no, quoted);
      break;
    }
    if (n > 0 && !(v > values[n - 1])) {
      char cur[32], prev[32];
      lsm_shortest_number(cur, sizeof cur, v);
      lsm_shortest_number(prev, sizeof prev, values[n - 1]);
      st = lsm_fail(err, LSM_ERR_INPUT, name,
                    "line %zu: %s is not greater than the previous height %s", line_no, cur, prev);
      break;
    }
    if (n == cap) {
      size_t new_cap = cap ? cap * 2 : 64, bytes;
      double *grown = NULL;
      if (new_cap > cap && lsm_size_mul(new_cap, sizeof *values, &bytes))
        grown = realloc(values, bytes);
      if (!grown) {
        st = lsm_fail(err, LSM_ERR_NOMEM, name, "out of memory for %zu heights", new_cap);
        break;
      }
      values = grown;
      cap = new_cap;
    }
    values[n++] = v;
  }
  free(line);
  if (st == LSM_OK && n == 0) st = lsm_fail(err, LSM_ERR_INPUT, name, "no heights");
  if (st != LSM_OK) {
    free(values);
    return st;
  }
  *z = values;
  *count = n;
  return LSM_OK;
}

lsm_status lsm_heights_read(const char *path, double **z, size_t *count, lsm_err *err) {
  if (z) *z = NULL;
  if (count) *count = 0;
  char *text = NULL;
  size_t length = 0;
  LSM_TRY(lsm_read_file(path, HEIGHTS_MAX_BYTES, &text, &length, err));
  lsm_status st = lsm_heights_parse(text, length, path, z, count, err);
  free(text);
  return st;
}
