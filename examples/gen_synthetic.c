/* gen_synthetic: writes the three synthetic slice sets of the design document
 * (Fazanaro 2013, chapter 4, Table 4.2): Pyramid, Candlestick, Vase.
 *
 *   gen_synthetic SET OUT_DIR [--mask]      SET = pyramid | candlestick | vase | all
 *
 * For each set it writes, under OUT_DIR/<set>/:
 *   001.png, 002.png, ...  8-bit grayscale slices.  By default the document's input
 *                          form: thin closed 8-connected contour outlines (255 on the
 *                          contour, 0 elsewhere).  With --mask: filled masks (255 inside).
 *   heights.txt            the height of each slice, one per line.
 *   shapes.txt             the exact analytic shapes of each slice, one primitive a line:
 *                            slice <k> rect <x0> <y0> <x1> <y1>
 *                            slice <k> circle <cx> <cy> <r>
 *                            slice <k> hole-rect <x0> <y0> <x1> <y1>
 *                            slice <k> hole-circle <cx> <cy> <r>
 *                          in pixel coordinates (x = column, y = row, pixel centres at
 *                          integers).  A rect is the closed box x0<=x<=x1, y0<=y<=y1; a
 *                          circle the closed disc (x-cx)^2+(y-cy)^2 <= r^2.
 *
 * Rasterisation.  A pixel (x, y) belongs to a primitive when its centre lies in the
 * closed shape.  The contour of a primitive is the set of its pixels that have a
 * 4-neighbour outside it (or outside the image): a thin closed 8-connected curve.
 * The filled mask is the union of the outer primitives minus the strict inside
 * (pixels not on the contour) of the holes, so hole contour pixels belong to the
 * object, as when outlines are filled by parity with contour pixels counted inside.
 *
 * Geometry and the pixel counts it gives are described in examples/README.md.
 */
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/lsm_io.h"
#include "solver/base/lsm_status.h"

/* ---- the data sets ------------------------------------------------------------ */

typedef enum prim_kind { PRIM_RECT, PRIM_CIRCLE } prim_kind;

typedef struct prim {
  prim_kind kind;
  int hole;     /* 1: a hole cut out of the enclosing outer primitive */
  double a, b;  /* rect: x0, y0      circle: cx, cy */
  double c, d;  /* rect: x1, y1      circle: r, (unused) */
} prim;

#define MAX_PRIMS 4
#define MAX_SLICES 8

typedef struct slice_def {
  int count;
  prim p[MAX_PRIMS];
} slice_def;

typedef struct set_def {
  const char *name;
  int width, height;
  int slices;
  double z[MAX_SLICES]; /* heights, strictly increasing */
  slice_def s[MAX_SLICES];
} set_def;

#define RECT(x0, y0, x1, y1) {PRIM_RECT, 0, (x0), (y0), (x1), (y1)}
#define CIRCLE(cx, cy, r) {PRIM_CIRCLE, 0, (cx), (cy), (r), 0.0}
#define HOLE_RECT(x0, y0, x1, y1) {PRIM_RECT, 1, (x0), (y0), (x1), (y1)}
#define HOLE_CIRCLE(cx, cy, r) {PRIM_CIRCLE, 1, (cx), (cy), (r), 0.0}

/* Centred w x h rectangle (w, h even) in a 100 x 70 image: centre (49.5, 34.5). */
#define PYR(w, h) {1, {RECT(50 - (w) / 2, 35 - (h) / 2, 49 + (w) / 2, 34 + (h) / 2)}}

static const set_def SETS[] = {
    /* Pyramid: 7 axis-aligned rectangles with a common centre, each about 0.744 times
     * the size of the one below (w + h = 142, 106, 78, 58, 44, 32, 24), so that the
     * contour pixel counts 280 .. 44 (mean 134.29) match Table 4.2 (44 .. 278, 134.29). */
    {"pyramid",
     100,
     70,
     7,
     {0, 40, 80, 120, 160, 200, 240},
     {PYR(86, 56), PYR(64, 42), PYR(48, 30), PYR(36, 22), PYR(26, 18), PYR(20, 12),
      PYR(14, 10)}},
    /* Candlestick: two feet -> one stem (merge) -> two arms (split) -> three candles. */
    {"candlestick",
     100,
     70,
     4,
     {0, 50, 100, 200},
     {{2, {CIRCLE(25.5, 34.5, 21), CIRCLE(73.5, 34.5, 21)}},
      {1, {CIRCLE(49.5, 34.5, 30)}},
      {2, {CIRCLE(27.5, 34.5, 19), CIRCLE(71.5, 34.5, 19)}},
      {3, {CIRCLE(17.5, 34.5, 14), CIRCLE(49.5, 34.5, 14), CIRCLE(81.5, 34.5, 14)}}}},
    /* Vase: circle with a square hole -> square with a circular hole -> as slice 1. */
    {"vase",
     125,
     125,
     3,
     {0, 75, 150},
     {{2, {CIRCLE(62, 62, 45.25), HOLE_RECT(51, 51, 73, 73)}},
      {2, {RECT(17, 17, 107, 107), HOLE_CIRCLE(62, 62, 11.5)}},
      {2, {CIRCLE(62, 62, 45.25), HOLE_RECT(51, 51, 73, 73)}}}},
};

#define SET_COUNT (sizeof SETS / sizeof SETS[0])

/* ---- rasterisation ------------------------------------------------------------ */

/* Is the centre of pixel (x, y) in the closed primitive?  Pixels outside the image
 * are never in it. */
static int prim_contains(const prim *p, int x, int y, int width, int height) {
  if (x < 0 || y < 0 || x >= width || y >= height) return 0;
  if (p->kind == PRIM_RECT) return x >= p->a && x <= p->c && y >= p->b && y <= p->d;
  double dx = x - p->a, dy = y - p->b;
  return dx * dx + dy * dy <= p->c * p->c;
}

/* In the primitive with all four 4-neighbours in it too (not on its contour). */
static int prim_strictly_contains(const prim *p, int x, int y, int width, int height) {
  return prim_contains(p, x, y, width, height) &&
         prim_contains(p, x - 1, y, width, height) &&
         prim_contains(p, x + 1, y, width, height) &&
         prim_contains(p, x, y - 1, width, height) &&
         prim_contains(p, x, y + 1, width, height);
}

/* Draws one slice into pixels (width*height bytes): contour outlines, or the filled
 * mask when filled is set.  Returns the number of pixels set to 255. */
static size_t draw_slice(const slice_def *s, int width, int height, int filled,
                         uint8_t *pixels) {
  size_t set = 0;
  for (int y = 0; y < height; y++) {
    for (int x = 0; x < width; x++) {
      int on = 0;
      if (filled) {
        int in_outer = 0, in_hole = 0;
        for (int k = 0; k < s->count; k++) {
          const prim *p = &s->p[k];
          if (p->hole)
            in_hole |= prim_strictly_contains(p, x, y, width, height);
          else
            in_outer |= prim_contains(p, x, y, width, height);
        }
        on = in_outer && !in_hole;
      } else {
        for (int k = 0; k < s->count && !on; k++) {
          const prim *p = &s->p[k];
          on = prim_contains(p, x, y, width, height) &&
               !prim_strictly_contains(p, x, y, width, height);
        }
      }
      pixels[(size_t)y * (size_t)width + (size_t)x] = on ? 255 : 0;
      set += on ? 1u : 0u;
    }
  }
  return set;
}

/* ---- output ------------------------------------------------------------------- */

/* malloc'd "a/b" (b may be NULL: a copy of a). */
static char *path_join(const char *a, const char *b, lsm_err *err) {
  size_t la = strlen(a), lb = b ? strlen(b) : 0;
  char *out = lsm_alloc(la + lb + 2, 1, err, "path");
  if (!out) return NULL;
  memcpy(out, a, la);
  size_t n = la;
  if (b) {
    if (n == 0 || out[n - 1] != '/') out[n++] = '/';
    memcpy(out + n, b, lb);
    n += lb;
  }
  out[n] = '\0';
  return out;
}

static lsm_status write_heights(const char *path, const set_def *set, lsm_err *err) {
  FILE *f = fopen(path, "w");
  if (!f) return lsm_fail(err, LSM_ERR_IO, path, "cannot create: %s", strerror(errno));
  int bad = 0;
  for (int k = 0; k < set->slices; k++) bad |= fprintf(f, "%.10g\n", set->z[k]) < 0;
  bad |= ferror(f) != 0;
  if (fclose(f) != 0) bad = 1;
  return bad ? lsm_fail(err, LSM_ERR_IO, path, "write failed") : LSM_OK;
}

static lsm_status write_shapes(const char *path, const set_def *set, lsm_err *err) {
  FILE *f = fopen(path, "w");
  if (!f) return lsm_fail(err, LSM_ERR_IO, path, "cannot create: %s", strerror(errno));
  int bad = 0;
  for (int k = 0; k < set->slices; k++) {
    const slice_def *s = &set->s[k];
    for (int i = 0; i < s->count; i++) {
      const prim *p = &s->p[i];
      const char *hole = p->hole ? "hole-" : "";
      if (p->kind == PRIM_RECT)
        bad |= fprintf(f, "slice %d %srect %.10g %.10g %.10g %.10g\n", k + 1, hole, p->a,
                       p->b, p->c, p->d) < 0;
      else
        bad |= fprintf(f, "slice %d %scircle %.10g %.10g %.10g\n", k + 1, hole, p->a, p->b,
                       p->c) < 0;
    }
  }
  bad |= ferror(f) != 0;
  if (fclose(f) != 0) bad = 1;
  return bad ? lsm_fail(err, LSM_ERR_IO, path, "write failed") : LSM_OK;
}

/* Writes one set under out_dir/<name>/ and prints a one-line summary. */
static lsm_status write_set(const set_def *set, const char *out_dir, int filled,
                            lsm_err *err) {
  lsm_status st = LSM_OK;
  uint8_t *pixels = NULL;
  char *file = NULL;
  size_t npix = 0, min = SIZE_MAX, max = 0, sum = 0;
  char *dir = path_join(out_dir, set->name, err);
  if (!dir) return err->status;
  st = lsm_make_dir(dir, err);
  if (st != LSM_OK) goto done;

  if (!lsm_size_mul((size_t)set->width, (size_t)set->height, &npix)) {
    st = lsm_fail(err, LSM_ERR_LIMIT, set->name, "image size overflows");
    goto done;
  }
  pixels = lsm_alloc(npix, 1, err, "slice image");
  if (!pixels) {
    st = err->status;
    goto done;
  }

  for (int k = 0; k < set->slices; k++) {
    char name[32];
    snprintf(name, sizeof name, "%03d.png", k + 1);
    size_t n = draw_slice(&set->s[k], set->width, set->height, filled, pixels);
    min = n < min ? n : min;
    max = n > max ? n : max;
    sum += n;
    free(file);
    file = path_join(dir, name, err);
    if (!file) {
      st = err->status;
      goto done;
    }
    st = lsm_png_write_gray8(file, pixels, set->width, set->height, err);
    if (st != LSM_OK) goto done;
  }

  free(file);
  file = path_join(dir, "heights.txt", err);
  if (!file) {
    st = err->status;
    goto done;
  }
  st = write_heights(file, set, err);
  if (st != LSM_OK) goto done;

  free(file);
  file = path_join(dir, "shapes.txt", err);
  if (!file) {
    st = err->status;
    goto done;
  }
  st = write_shapes(file, set, err);
  if (st != LSM_OK) goto done;

  printf("%s: %d slices %dx%d (w x h) in %s, %s pixels per slice min %zu max %zu mean %.2f\n",
         set->name, set->slices, set->width, set->height, dir, filled ? "mask" : "contour",
         min, max, (double)sum / set->slices);
  if (fflush(stdout) != 0) st = lsm_fail(err, LSM_ERR_IO, "stdout", "write failed");

done:
  free(file);
  free(pixels);
  free(dir);
  return st;
}

/* ---- command line ------------------------------------------------------------- */

static void usage(FILE *f) {
  fprintf(f,
          "usage: gen_synthetic SET OUT_DIR [--mask]\n"
          "  SET      pyramid | candlestick | vase | all\n"
          "  OUT_DIR  output folder; each set goes to OUT_DIR/<set>/\n"
          "           (001.png ..., heights.txt, shapes.txt)\n"
          "  --mask   write filled masks instead of contour outlines\n");
}

int main(int argc, char **argv) {
  const char *set_name = NULL, *out_dir = NULL;
  int filled = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (strcmp(a, "--mask") == 0) {
      filled = 1;
    } else if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
      usage(stdout);
      return 0;
    } else if (a[0] == '-' && a[1] != '\0') {
      fprintf(stderr, "gen_synthetic: unknown option '%s'\n", a);
      usage(stderr);
      return 2;
    } else if (!set_name) {
      set_name = a;
    } else if (!out_dir) {
      out_dir = a;
    } else {
      fprintf(stderr, "gen_synthetic: too many arguments\n");
      usage(stderr);
      return 2;
    }
  }
  if (!set_name || !out_dir || out_dir[0] == '\0') {
    usage(stderr);
    return 2;
  }
  int all = strcmp(set_name, "all") == 0, found = all;
  for (size_t i = 0; i < SET_COUNT && !found; i++) found = strcmp(set_name, SETS[i].name) == 0;
  if (!found) {
    fprintf(stderr, "gen_synthetic: unknown set '%s'\n", set_name);
    usage(stderr);
    return 2;
  }

  lsm_err err;
  lsm_err_clear(&err);
  if (lsm_make_dir(out_dir, &err) != LSM_OK) {
    fprintf(stderr, "gen_synthetic: error: %s\n", err.msg);
    return 1;
  }
  for (size_t i = 0; i < SET_COUNT; i++) {
    if (!all && strcmp(set_name, SETS[i].name) != 0) continue;
    if (write_set(&SETS[i], out_dir, filled, &err) != LSM_OK) {
      fprintf(stderr, "gen_synthetic: error: %s\n", err.msg);
      return 1;
    }
  }
  return 0;
}
