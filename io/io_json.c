/* io_json: strings and numbers in the JSON that lsmorph writes (run.json, the
 * scores, volume.json). */
#include "lsm_io.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

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
