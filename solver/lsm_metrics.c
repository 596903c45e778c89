#include "lsm_metrics.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lsm_sdf.h"

static void boundary(const lsm_mask *m, uint8_t *b) {
  const int w = m->width, h = m->height;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const uint8_t *p = m->pixels + (size_t)y * w + x;
      int edge = 0;
      if (*p) {
        edge = x == 0 || y == 0 || x == w - 1 || y == h - 1 || !p[-1] || !p[1] || !p[-w] || !p[w];
      }
      b[(size_t)y * w + x] = (uint8_t)edge;
    }
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

lsm_status lsm_score_slice(const lsm_mask *result, const lsm_mask *truth, lsm_slice_score *out,
                           lsm_err *err) {
  memset(out, 0, sizeof *out);
  if (result->width != truth->width || result->height != truth->height)
    return lsm_fail(err, LSM_ERR_INPUT, NULL, "slice sizes differ (%dx%d vs %dx%d)", result->width,
                    result->height, truth->width, truth->height);
  const size_t n = (size_t)truth->width * truth->height;
  size_t inter = 0;
  for (size_t k = 0; k < n; ++k) {
    out->area_result += result->pixels[k] != 0;
    out->area_truth += truth->pixels[k] != 0;
    inter += result->pixels[k] && truth->pixels[k];
  }
  const size_t sum = out->area_result + out->area_truth;
  out->dice = sum ? 2.0 * (double)inter / (double)sum : 1.0;
  if (!out->area_result && !out->area_truth) {
    out->comparable = 1;
    return LSM_OK;
  }
  if (!out->area_result || !out->area_truth) {
    out->comparable = 0;
    out->hd95 = out->hd_max = out->mean_surface = INFINITY;
    return LSM_OK;
  }
  out->comparable = 1;
  uint8_t *br = malloc(n), *bt = malloc(n);
  double *dr = malloc(n * sizeof *dr), *dt = malloc(n * sizeof *dt), *all = malloc(2 * n * sizeof *all);
  lsm_status st = LSM_OK;
  if (!br || !bt || !dr || !dt || !all) {
    st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate scoring buffers");
    goto done;
  }
  boundary(result, br);
  boundary(truth, bt);
  st = lsm_edt_squared(br, result->width, result->height, 1.0, 1.0, dr, err);
  if (st == LSM_OK) st = lsm_edt_squared(bt, truth->width, truth->height, 1.0, 1.0, dt, err);
  if (st != LSM_OK) goto done;
  size_t m = 0;
  double total = 0.0;
  for (size_t k = 0; k < n; ++k) {
    if (br[k]) all[m++] = sqrt(dt[k]);
    if (bt[k]) all[m++] = sqrt(dr[k]);
  }
  qsort(all, m, sizeof *all, cmp_double);
  for (size_t k = 0; k < m; ++k) total += all[k];
  out->mean_surface = m ? total / (double)m : 0.0;
  out->hd_max = m ? all[m - 1] : 0.0;
  /* 95th percentile by the nearest-rank method. */
  size_t rank = m ? (size_t)ceil(0.95 * (double)m) : 0;
  out->hd95 = m ? all[rank ? rank - 1 : 0] : 0.0;
done:
  free(br);
  free(bt);
  free(dr);
  free(dt);
  free(all);
  return st;
}
