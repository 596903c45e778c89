/* io_json: strings and numbers in the JSON that lsmorph writes (run.json, the
 * scores, volume.json). */
#include "io/lsm_io.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The length of the well-formed UTF-8 sequence at p (1 to 4), or 0 when the
 * byte at p does not start one (a stray continuation byte, an overlong or
 * surrogate form, a code point past U+10FFFF, a truncated sequence). */
static int utf8_length(const unsigned char *p) {
  if (p[0] < 0x80) return 1;
  int n = p[0] >= 0xc2 && p[0] <= 0xdf ? 2 : p[0] >= 0xe0 && p[0] <= 0xef ? 3
          : p[0] >= 0xf0 && p[0] <= 0xf4 ? 4 : 0;
  for (int k = 1; k < n; ++k)
    if ((p[k] & 0xc0) != 0x80) return 0;
  if ((p[0] == 0xe0 && p[1] < 0xa0) || (p[0] == 0xed && p[1] > 0x9f) ||
      (p[0] == 0xf0 && p[1] < 0x90) || (p[0] == 0xf4 && p[1] > 0x8f))
    return 0;
  return n;
}

/* A JSON string.  File names are bytes: a byte that is not part of well-formed
 * UTF-8 is written as the Latin-1 character of that value (\u00XX), so the
 * file stays valid JSON for any name. */
void lsm_json_string(FILE *f, const char *s) {
  fputc('"', f);
  for (const unsigned char *p = (const unsigned char *)s; *p;) {
    const int n = utf8_length(p);
    if (*p == '"' || *p == '\\')
      fprintf(f, "\\%c", *p);
    else if (*p < 0x20 || n == 0)
      fprintf(f, "\\u%04x", *p);
    else
      fwrite(p, 1, (size_t)n, f);
    p += n > 0 ? n : 1;
  }
  fputc('"', f);
}

void lsm_shortest_number(char *text, size_t size, double v) {
  if (!text || size == 0) return;
  for (int digits = 15; digits <= 17; ++digits) {
    snprintf(text, size, "%.*g", digits, v);
    if (strtod(text, NULL) == v) return;
  }
}

/* A JSON number: the shortest of 15 to 17 significant digits that reads back
 * as the same double (heights and lengths exactly as the run used them). */
void lsm_json_number(FILE *f, double v) {
  if (!isfinite(v)) {
    fputs("null", f);
    return;
  }
  char text[40];
  lsm_shortest_number(text, sizeof text, v);
  fputs(text, f);
}

/* ---- reading: one number by its member path ---------------------------------------------- */

typedef struct json_reader {
  const char *p;           /* the next byte */
  const char *const *keys; /* the member path sought */
  int count;
  int found;
  double value;
  int want_array;   /* seeking an array (of numbers, or of strings), not one number */
  int want_strings; /* ... of strings */
  int want_string;  /* one string, not one number: its bytes in spans[0], span_lengths[0] */
  int want_bool;    /* true or false, not one number: value 1 or 0 */
  double *items;    /* its numbers (up to capacity), counted in n_items */
  const char **spans; /* or its strings: bytes between the quotes, escapes unresolved */
  size_t *span_lengths;
  size_t capacity, n_items;
} json_reader;

enum { JSON_MAX_DEPTH = 256 };

static void json_space(json_reader *r) {
  while (*r->p == ' ' || *r->p == '\t' || *r->p == '\n' || *r->p == '\r') r->p++;
}

static int is_hex(char c) {
  return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
}

/* A string; *raw / *len: its bytes between the quotes, escapes unresolved. */
static int json_read_string(json_reader *r, const char **raw, size_t *len) {
  if (*r->p != '"') return 0;
  const char *start = ++r->p;
  for (;;) {
    const unsigned char c = (unsigned char)*r->p;
    if (c == '"') break;
    if (c < 0x20) return 0; /* a control character, or the end of the text */
    if (c == '\\') {
      const char e = r->p[1];
      if (e == 'u') {
        for (int k = 2; k < 6; ++k)
          if (!is_hex(r->p[k])) return 0;
        r->p += 6;
        continue;
      }
      if (!e || !strchr("\"\\/bfnrt", e)) return 0;
      r->p += 2;
      continue;
    }
    r->p++;
  }
  *raw = start;
  *len = (size_t)(r->p - start);
  r->p++;
  return 1;
}

static int json_digits(json_reader *r) {
  if (*r->p < '0' || *r->p > '9') return 0;
  while (*r->p >= '0' && *r->p <= '9') r->p++;
  return 1;
}

/* A number by the JSON grammar: -? (0 | [1-9][0-9]*) (. [0-9]+)? ([eE] [+-]? [0-9]+)? */
static int json_read_number(json_reader *r) {
  if (*r->p == '-') r->p++;
  if (*r->p == '0') r->p++;
  else if (!json_digits(r)) return 0;
  if (*r->p == '.') {
    r->p++;
    if (!json_digits(r)) return 0;
  }
  if (*r->p == 'e' || *r->p == 'E') {
    r->p++;
    if (*r->p == '+' || *r->p == '-') r->p++;
    if (!json_digits(r)) return 0;
  }
  return 1;
}

static int json_literal(json_reader *r, const char *word) {
  const size_t n = strlen(word);
  if (strncmp(r->p, word, n) != 0) return 0;
  r->p += n;
  return 1;
}

/* One value at nesting level `level`; on_path: the members that led here are
 * keys[0 .. level - 1]. */
static int json_read_value(json_reader *r, int level, int on_path) {
  if (level > JSON_MAX_DEPTH) return 0;
  json_space(r);
  const char c = *r->p;
  if (c == '{' || c == '[') { /* an object's members, an array's elements */
    const char close = c == '{' ? '}' : ']';
    /* the array sought: its elements are collected, and it is found when
     * every one is a number (a string) (a later duplicate wins) */
    const int target = c == '[' && r->want_array && on_path && level == r->count;
    int all_kind = 1;
    if (target) r->n_items = 0;
    r->p++;
    json_space(r);
    if (*r->p == close) {
      r->p++;
      if (target) r->found = 2;
      return 1;
    }
    for (;;) {
      int match = 0; /* a member on the path sought */
      if (c == '{') {
        const char *key;
        size_t len;
        json_space(r);
        if (!json_read_string(r, &key, &len)) return 0;
        json_space(r);
        if (*r->p != ':') return 0;
        r->p++;
        match = on_path && level < r->count && strlen(r->keys[level]) == len &&
                memcmp(r->keys[level], key, len) == 0;
      }
      json_space(r);
      const char *value = r->p;
      if (!json_read_value(r, level + 1, match)) return 0;
      const int number = *value == '-' || (*value >= '0' && *value <= '9');
      const int kind = r->want_strings ? *value == '"' : number; /* an element of the kind sought */
      if (match && level + 1 == r->count) {
        if (r->want_array) /* the member's value was read: found if the array sought */
          r->found = *value == '[' && r->found == 2;
        else if (r->want_string) {
          r->found = *value == '"';
          if (r->found) {
            r->spans[0] = value + 1;
            r->span_lengths[0] = (size_t)(r->p - value) - 2;
          }
        } else if (r->want_bool) {
          r->found = *value == 't' || *value == 'f';
          r->value = *value == 't';
        } else if (number) {
          r->found = 1; /* the number sought, read by the grammar above */
          r->value = strtod(value, NULL);
        }
      }
      if (target) {
        if (kind && r->n_items < r->capacity) {
          if (r->want_strings) {
            r->spans[r->n_items] = value + 1;
            r->span_lengths[r->n_items] = (size_t)(r->p - value) - 2;
          } else {
            r->items[r->n_items] = strtod(value, NULL);
          }
        }
        r->n_items += kind;
        all_kind &= kind;
      }
      json_space(r);
      if (*r->p == ',') {
        r->p++;
        continue;
      }
      if (*r->p != close) return 0;
      r->p++;
      if (target) r->found = all_kind ? 2 : 0; /* 2: an array of the kind, seen by the member */
      return 1;
    }
  }
  if (c == '"') {
    const char *raw;
    size_t len;
    return json_read_string(r, &raw, &len);
  }
  if (c == 't') return json_literal(r, "true");
  if (c == 'f') return json_literal(r, "false");
  if (c == 'n') return json_literal(r, "null");
  return json_read_number(r);
}

/* Reads the whole document with r (the search set up); 1 when it is valid
 * JSON, else 0 with *error_at where it stops being so. */
static int json_read_document(json_reader *r, const char *text, size_t *error_at) {
  int ok = json_read_value(r, 0, 1);
  if (ok) {
    json_space(r);
    ok = *r->p == '\0';
  }
  if (!ok && error_at) *error_at = (size_t)(r->p - text);
  return ok;
}

int lsm_json_find_number(const char *text, const char *const *keys, int count, double *value,
                         size_t *error_at) {
  json_reader r = {.p = text, .keys = keys, .count = count};
  if (!json_read_document(&r, text, error_at)) return -1;
  if (r.found && value) *value = r.value;
  return r.found;
}

int lsm_json_find_numbers(const char *text, const char *const *keys, int count, double *values,
                          size_t capacity, size_t *n, size_t *error_at) {
  json_reader r = {.p = text, .keys = keys, .count = count, .want_array = 1,
                   .items = values, .capacity = values ? capacity : 0};
  *n = 0;
  if (!json_read_document(&r, text, error_at)) return -1;
  if (r.found) *n = r.n_items;
  return r.found;
}

int lsm_json_find_strings(const char *text, const char *const *keys, int count, const char **raw,
                          size_t *raw_lengths, size_t capacity, size_t *n, size_t *error_at) {
  const int buffers = raw && raw_lengths;
  json_reader r = {.p = text, .keys = keys, .count = count, .want_array = 1, .want_strings = 1,
                   .spans = raw, .span_lengths = raw_lengths, .capacity = buffers ? capacity : 0};
  *n = 0;
  if (!json_read_document(&r, text, error_at)) return -1;
  if (r.found) *n = r.n_items;
  return r.found;
}

int lsm_json_find_string(const char *text, const char *const *keys, int count, const char **raw,
                         size_t *raw_length, size_t *error_at) {
  const char *span = NULL;
  size_t length = 0;
  json_reader r = {.p = text, .keys = keys, .count = count, .want_string = 1, .spans = &span,
                   .span_lengths = &length};
  if (!json_read_document(&r, text, error_at)) return -1;
  if (r.found && raw) *raw = span;
  if (r.found && raw_length) *raw_length = length;
  return r.found;
}

static unsigned hex_value(const char *p) {
  unsigned v = 0;
  for (int k = 0; k < 4; ++k) {
    const char c = p[k];
    v = 16 * v + (unsigned)(c <= '9' ? c - '0' : (c | 0x20) - 'a' + 10);
  }
  return v;
}

/* Appends code point cp as UTF-8. */
static size_t put_utf8(char *out, unsigned long cp) {
  unsigned char *o = (unsigned char *)out;
  if (cp < 0x800) {
    o[0] = (unsigned char)(0xc0 | (cp >> 6));
    o[1] = (unsigned char)(0x80 | (cp & 0x3f));
    return 2;
  }
  if (cp < 0x10000) {
    o[0] = (unsigned char)(0xe0 | (cp >> 12));
    o[1] = (unsigned char)(0x80 | ((cp >> 6) & 0x3f));
    o[2] = (unsigned char)(0x80 | (cp & 0x3f));
    return 3;
  }
  o[0] = (unsigned char)(0xf0 | (cp >> 18));
  o[1] = (unsigned char)(0x80 | ((cp >> 12) & 0x3f));
  o[2] = (unsigned char)(0x80 | ((cp >> 6) & 0x3f));
  o[3] = (unsigned char)(0x80 | (cp & 0x3f));
  return 4;
}

size_t lsm_json_unescape(const char *raw, size_t length, char *out) {
  static const char from[] = "\"\\/bfnrt", to[] = "\"\\/\b\f\n\r\t";
  size_t n = 0;
  for (size_t k = 0; k < length;) {
    if (raw[k] != '\\') {
      out[n++] = raw[k++];
      continue;
    }
    if (k + 1 >= length) return (size_t)-1;
    const char *e = strchr(from, raw[k + 1]);
    if (raw[k + 1] != 'u') {
      if (!raw[k + 1] || !e) return (size_t)-1;
      out[n++] = to[e - from];
      k += 2;
      continue;
    }
    if (k + 6 > length) return (size_t)-1;
    for (size_t j = k + 2; j < k + 6; ++j)
      if (!is_hex(raw[j])) return (size_t)-1;
    unsigned long cp = hex_value(raw + k + 2);
    k += 6;
    if (cp >= 0xd800 && cp <= 0xdbff) { /* a surrogate pair */
      if (k + 6 > length || raw[k] != '\\' || raw[k + 1] != 'u') return (size_t)-1;
      for (size_t j = k + 2; j < k + 6; ++j)
        if (!is_hex(raw[j])) return (size_t)-1;
      const unsigned low = hex_value(raw + k + 2);
      if (low < 0xdc00 || low > 0xdfff) return (size_t)-1;
      cp = 0x10000 + ((cp - 0xd800) << 10) + (low - 0xdc00);
      k += 6;
    } else if (cp >= 0xdc00 && cp <= 0xdfff) {
      return (size_t)-1;
    }
    if (cp == 0) return (size_t)-1; /* no NUL inside a C string */
    if (cp < 0x100)                 /* a byte, as lsm_json_string writes it */
      out[n++] = (char)(unsigned char)cp;
    else
      n += put_utf8(out + n, cp);
  }
  out[n] = '\0';
  return n;
}

int lsm_json_find_bool(const char *text, const char *const *keys, int count, int *value,
                       size_t *error_at) {
  json_reader r = {.p = text, .keys = keys, .count = count, .want_bool = 1};
  if (!json_read_document(&r, text, error_at)) return -1;
  if (r.found && value) *value = r.value != 0.0;
  return r.found;
}
