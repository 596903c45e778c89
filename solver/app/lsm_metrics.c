#include "solver/app/lsm_metrics.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "solver/sdf/lsm_sdf.h"

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

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


static lsm_status append(double **dist, size_t *n, size_t *cap, double v, lsm_err *err) {
  if (*n == *cap) {
    size_t next = *cap ? 2 * *cap : 4096;
    double *p = realloc(*dist, next * sizeof *p);
    if (!p) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot grow the distance list");
    *dist = p;
    *cap = next;
  }
  (*dist)[(*n)++] = v;
  return LSM_OK;
}

double lsm_quantile(double *values, size_t n, double q) {
  if (n == 0) return NAN;
  qsort(values, n, sizeof *values, cmp_double);
  size_t rank = (size_t)ceil(q * (double)n);
  return values[rank ? rank - 1 : 0];
}

lsm_status lsm_score_slice(const lsm_mask *result, const lsm_mask *truth, double row_step,
                           lsm_slice_score *out, double **dist, size_t *dn, size_t *dcap,
                           lsm_err *err) {
  memset(out, 0, sizeof *out);
  if (!(row_step > 0.0) || !isfinite(row_step))
    return lsm_fail(err, LSM_ERR_INPUT, NULL, "row step %g is not a positive length", row_step);
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
    if (dist) {
      const lsm_mask *full = out->area_result ? result : truth;
      uint8_t *b = malloc(n);
      if (!b) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate scoring buffers");
      boundary(full, b);
      const double penalty = fmax((double)truth->width, (double)truth->height * row_step);
      lsm_status st = LSM_OK;
      for (size_t k = 0; st == LSM_OK && k < n; ++k)
        if (b[k]) st = append(dist, dn, dcap, penalty, err);
      free(b);
      return st;
    }
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
  st = lsm_edt_squared(br, result->width, result->height, 1.0, row_step, dr, err);
  if (st == LSM_OK) st = lsm_edt_squared(bt, truth->width, truth->height, 1.0, row_step, dt, err);
  if (st != LSM_OK) goto done;
  size_t m = 0;
  double total = 0.0;
  for (size_t k = 0; k < n; ++k) {
    if (br[k]) all[m++] = sqrt(dt[k]);
    if (bt[k]) all[m++] = sqrt(dr[k]);
  }
  for (size_t k = 0; dist && st == LSM_OK && k < m; ++k) st = append(dist, dn, dcap, all[k], err);
  out->hd95 = m ? lsm_quantile(all, m, 0.95) : 0.0; /* sorts all */
  for (size_t k = 0; k < m; ++k) total += all[k];
  out->mean_surface = m ? total / (double)m : 0.0;
  out->hd_max = m ? all[m - 1] : 0.0;
done:
  free(br);
  free(bt);
  free(dr);
  free(dt);
  free(all);
  return st;
}
