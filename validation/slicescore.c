/* slicescore: per-slice scores of result masks against truth masks, with the
 * same function `lsmorph score` uses (lsm_score_slice, solver/app/lsm_metrics.c),
 * so the validation's per-slice curves and `lsmorph score`'s averages agree.
 *
 * Usage: slicescore LIST_FILE
 * LIST_FILE has one line per comparison: "ID RESULT_PNG TRUTH_PNG" (white
 * space separated; paths without spaces).  Prints CSV on stdout:
 *   id,dice,hd95,hd_max,mean_surface,area_result,area_truth,comparable,
 *   components_result,components_truth,stray_components,stray_pixels
 * Distances are in pixels between boundary pixel centres; hd95, hd_max and
 * mean_surface are empty when exactly one of the two masks is empty
 * (comparable = 0).  Components are 8-connected; a stray component is a
 * connected part of the result that does not touch any truth pixel.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/lsm_io.h"
#include "solver/base/lsm_grid.h"
#include "solver/app/lsm_metrics.h"
#include "solver/base/lsm_status.h"

typedef struct components {
  size_t count, stray, stray_pixels;
} components;

/* 8-connected components of m; those with no pixel inside `other` are stray.
 * stack has room for width*height indices; seen is width*height bytes. */
static components count_components(const lsm_mask *m, const lsm_mask *other, size_t *stack,
                                   uint8_t *seen) {
  components c = {0, 0, 0};
  const int w = m->width, h = m->height;
  memset(seen, 0, (size_t)w * (size_t)h);
  for (size_t start = 0; start < (size_t)w * (size_t)h; ++start) {
    if (!m->pixels[start] || seen[start]) continue;
    size_t top = 0, size = 0;
    int touches = 0;
    stack[top++] = start;
    seen[start] = 1;
    while (top) {
      const size_t k = stack[--top];
      size++;
      touches |= other->pixels[k] != 0;
      const int x = (int)(k % (size_t)w), y = (int)(k / (size_t)w);
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int u = x + dx, v = y + dy;
          if (u < 0 || v < 0 || u >= w || v >= h) continue;
          const size_t q = (size_t)v * (size_t)w + (size_t)u;
          if (m->pixels[q] && !seen[q]) {
            seen[q] = 1;
            stack[top++] = q;
          }
        }
    }
    c.count++;
    if (!touches) {
      c.stray++;
      c.stray_pixels += size;
    }
  }
  return c;
}

static lsm_status score_line(const char *id, const char *result, const char *truth, lsm_err *err) {
  lsm_image_read_opts ro = {0, (uint64_t)1 << 28, 0};
  lsm_mask a = {0, 0, NULL}, b = {0, 0, NULL};
  lsm_slice_score s;
  lsm_status st = lsm_slice_read_mask(result, &ro, &a, err);
  if (st == LSM_OK) st = lsm_slice_read_mask(truth, &ro, &b, err);
  if (st == LSM_OK) st = lsm_score_slice(&a, &b, 1.0, &s, NULL, NULL, NULL, err);
  size_t *stack = NULL;
  uint8_t *seen = NULL;
  if (st == LSM_OK) {
    const size_t n = (size_t)a.width * (size_t)a.height;
    stack = lsm_alloc(n, sizeof *stack, err, "component stack");
    seen = stack ? lsm_alloc(n, 1, err, "component marks") : NULL;
    if (!stack || !seen) st = LSM_ERR_NOMEM;
  }
  if (st == LSM_OK) {
    const components cr = count_components(&a, &b, stack, seen);
    const components ct = count_components(&b, &a, stack, seen);
    if (s.comparable)
      printf("%s,%.8f,%.6f,%.6f,%.6f,%zu,%zu,1", id, s.dice, s.hd95, s.hd_max, s.mean_surface,
             s.area_result, s.area_truth);
    else
      printf("%s,%.8f,,,,%zu,%zu,0", id, s.dice, s.area_result, s.area_truth);
    printf(",%zu,%zu,%zu,%zu\n", cr.count, ct.count, cr.stray, cr.stray_pixels);
  }
  free(stack);
  free(seen);
  lsm_mask_free(&a);
  lsm_mask_free(&b);
  return st;
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: slicescore LIST_FILE\n");
    return 2;
  }
  lsm_err err;
  lsm_err_clear(&err);
  FILE *f = fopen(argv[1], "r");
  if (!f) {
    fprintf(stderr, "slicescore: error: %s: cannot open\n", argv[1]);
    return 1;
  }
  printf("id,dice,hd95,hd_max,mean_surface,area_result,area_truth,comparable,"
         "components_result,components_truth,stray_components,stray_pixels\n");
  char line[3 * 4200], id[256], result[4200], truth[4200];
  lsm_status st = LSM_OK;
  long lineno = 0;
  while (st == LSM_OK && fgets(line, sizeof line, f)) {
    lineno++;
    if (line[0] == '\n' || line[0] == '#') continue;
    if (sscanf(line, "%255s %4199s %4199s", id, result, truth) != 3) {
      st = lsm_fail(&err, LSM_ERR_INPUT, argv[1], "line %ld: expected ID RESULT TRUTH", lineno);
      break;
    }
    st = score_line(id, result, truth, &err);
  }
  if (st == LSM_OK && ferror(f)) st = lsm_fail(&err, LSM_ERR_IO, argv[1], "read failed");
  fclose(f);
  if (st == LSM_OK && (fflush(stdout) != 0 || ferror(stdout)))
    st = lsm_fail(&err, LSM_ERR_IO, NULL, "write failed");
  if (st != LSM_OK) {
    fprintf(stderr, "slicescore: error: %s\n", err.msg[0] ? err.msg : lsm_status_name(st));
    return 1;
  }
  return 0;
}
