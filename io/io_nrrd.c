/* io_nrrd: streaming NRRD writer (attached header, raw little-endian float32).
 *
 * The header has a fixed length (LSM_NRRD_HEADER_BYTES): a padding comment line
 * absorbs the difference between the provisional header written at open (slice
 * count 0) and the final one written by lsm_nrrd_finish, which seeks back to
 * offset 0 and rewrites it in place.
 */
#include "io/lsm_io.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NRRD_HEADER_BYTES LSM_NRRD_HEADER_BYTES

struct lsm_nrrd_writer {
  FILE *fp;
  char *path;
  int nx, ny;
  double sx, sy, sz, ox, oy, oz;
  size_t slices;
  size_t slice_bytes;
  unsigned char *buf; /* one slice, already little endian */
  int failed;         /* a write failed: finish refuses */
};

size_t lsm_nrrd_header(char *out, size_t cap, int is_float, int gzip, int nx, int ny, size_t nz,
                       double sx, double sy, double sz, double ox, double oy, double oz) {
  char body[LSM_NRRD_HEADER_BYTES + 1];
  if (cap < LSM_NRRD_HEADER_BYTES + 1) return 0;
  char t[6][32]; /* shortest round-trip forms: 0.8, not 0.80000000000000004 */
  const double v[6] = {sx, sy, sz, ox, oy, oz};
  for (int k = 0; k < 6; ++k) lsm_shortest_number(t[k], sizeof t[k], v[k]);
  int len = snprintf(body, sizeof body,
                     "NRRD0004\n"
                     "# Complete NRRD file format specification at:\n"
                     "# http://teem.sourceforge.net/nrrd/format.html\n"
                     "# written by lsmorph%s\n"
                     "type: %s\n"
                     "dimension: 3\n"
                     "space dimension: 3\n"
                     "sizes: %d %d %zu\n"
                     "space directions: (%s,0,0) (0,%s,0) (0,0,%s)\n"
                     "space origin: (%s,%s,%s)\n"
                     "kinds: domain domain domain\n"
                     "%s"
                     "encoding: %s\n",
                     is_float ? "" : ": mask, 255 inside, 0 outside", is_float ? "float" : "uchar",
                     nx, ny, nz, t[0], t[1], t[2], t[3], t[4], t[5], is_float ? "endian: little\n" : "",
                     gzip ? "gzip" : "raw");
  /* then "# " + dots + "\n" + "\n" (the blank line that ends the header) */
  if (len < 0 || (size_t)len + 4 > LSM_NRRD_HEADER_BYTES) return 0;
  size_t pad = LSM_NRRD_HEADER_BYTES - (size_t)len - 4;
  memcpy(out, body, (size_t)len);
  char *p = out + len;
  *p++ = '#';
  *p++ = ' ';
  memset(p, '.', pad);
  p += pad;
  *p++ = '\n';
  *p++ = '\n';
  *p = '\0';
  return LSM_NRRD_HEADER_BYTES;
}

/* The float header of this writer. */
static int nrrd_header(char out[LSM_NRRD_HEADER_BYTES + 1], const lsm_nrrd_writer *w, size_t nz,
                       double sz) {
  return lsm_nrrd_header(out, LSM_NRRD_HEADER_BYTES + 1, 1, 0, w->nx, w->ny, nz, w->sx, w->sy, sz,
                         w->ox, w->oy, w->oz) != 0;
}

static int finite_positive(double v) { return isfinite(v) && v > 0.0; }

lsm_status lsm_volume_check_geometry(const char *where, int nx, int ny, double sx, double sy,
                                     double sz, double ox, double oy, double oz, lsm_err *err) {
  if (nx <= 0 || ny <= 0)
    return lsm_fail(err, LSM_ERR_INPUT, where, "volume slice size %dx%d is not positive", nx, ny);
  if (!finite_positive(sx) || !finite_positive(sy) || !finite_positive(sz))
    return lsm_fail(err, LSM_ERR_INPUT, where, "spacings %g %g %g must be finite and positive", sx,
                    sy, sz);
  if (!isfinite(ox) || !isfinite(oy) || !isfinite(oz))
    return lsm_fail(err, LSM_ERR_INPUT, where, "origin %g %g %g is not finite", ox, oy, oz);
  size_t bytes;
  if (!lsm_size_mul3((size_t)nx, (size_t)ny, 4, &bytes))
    return lsm_fail(err, LSM_ERR_LIMIT, where, "slice size %dx%d is too large", nx, ny);
  return LSM_OK;
}

lsm_status lsm_nrrd_open(const char *path, int nx, int ny, double sx, double sy,
                         double sz, double ox, double oy, double oz,
                         lsm_nrrd_writer **out, lsm_err *err) {
  if (out) *out = NULL;
  if (!path || !out) return lsm_fail(err, LSM_ERR_INTERNAL, path, "bad arguments to the NRRD writer");
  LSM_TRY(lsm_volume_check_geometry(path, nx, ny, sx, sy, sz, ox, oy, oz, err));
  const size_t slice_bytes = (size_t)nx * (size_t)ny * 4;

  lsm_nrrd_writer *w = calloc(1, sizeof *w);
  if (!w) return lsm_fail(err, LSM_ERR_NOMEM, path, "cannot allocate the NRRD writer");
  size_t path_len = strlen(path);
  w->path = malloc(path_len + 1);
  w->buf = malloc(slice_bytes);
  if (!w->path || !w->buf) {
    free(w->path);
    free(w->buf);
    free(w);
    return lsm_fail(err, LSM_ERR_NOMEM, path, "cannot allocate %zu bytes for a slice", slice_bytes);
  }
  memcpy(w->path, path, path_len + 1);
  w->nx = nx;
  w->ny = ny;
  w->sx = sx;
  w->sy = sy;
  w->sz = sz;
  w->ox = ox;
  w->oy = oy;
  w->oz = oz;
  w->slice_bytes = slice_bytes;

  char header[NRRD_HEADER_BYTES + 1];
  if (!nrrd_header(header, w, 0, sz)) {
    lsm_nrrd_abort(&w);
    return lsm_fail(err, LSM_ERR_INTERNAL, path, "NRRD header does not fit in %d bytes",
                    NRRD_HEADER_BYTES);
  }
  w->fp = fopen(path, "wb");
  if (!w->fp) {
    lsm_status st = lsm_fail(err, LSM_ERR_IO, path, "cannot create: %s", strerror(errno));
    lsm_nrrd_abort(&w);
    return st;
  }
  if (fwrite(header, 1, NRRD_HEADER_BYTES, w->fp) != NRRD_HEADER_BYTES) {
    lsm_status st = lsm_fail(err, LSM_ERR_IO, path, "write failed: %s", strerror(errno));
    lsm_nrrd_abort(&w);
    return st;
  }
  *out = w;
  return LSM_OK;
}

lsm_status lsm_nrrd_write_slice(lsm_nrrd_writer *w, const float *slice, lsm_err *err) {
  if (!w || !slice) return lsm_fail(err, LSM_ERR_INTERNAL, w ? w->path : NULL, "bad arguments to write a slice");
  if (w->failed) return lsm_fail(err, LSM_ERR_IO, w->path, "an earlier write failed");
  size_t n = w->slice_bytes / 4;
  unsigned char *b = w->buf;
  for (size_t k = 0; k < n; ++k) {
    uint32_t u;
    memcpy(&u, &slice[k], sizeof u);
    b[4 * k + 0] = (unsigned char)(u & 0xffu);
    b[4 * k + 1] = (unsigned char)((u >> 8) & 0xffu);
    b[4 * k + 2] = (unsigned char)((u >> 16) & 0xffu);
    b[4 * k + 3] = (unsigned char)((u >> 24) & 0xffu);
  }
  if (fwrite(b, 1, w->slice_bytes, w->fp) != w->slice_bytes) {
    w->failed = 1;
    return lsm_fail(err, LSM_ERR_IO, w->path, "write failed: %s", strerror(errno));
  }
  w->slices++;
  return LSM_OK;
}

size_t lsm_nrrd_slices(const lsm_nrrd_writer *w) { return w ? w->slices : 0; }

lsm_status lsm_nrrd_finish(lsm_nrrd_writer **wp, double sz, lsm_err *err) {
  if (!wp || !*wp) return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "NRRD writer is not open");
  lsm_nrrd_writer *w = *wp;
  lsm_status st = LSM_OK;
  char header[NRRD_HEADER_BYTES + 1];
  if (w->failed) {
    st = lsm_fail(err, LSM_ERR_IO, w->path, "an earlier write failed");
  } else if (w->slices == 0) {
    st = lsm_fail(err, LSM_ERR_INPUT, w->path, "no slices were written");
  } else if (!finite_positive(sz)) {
    st = lsm_fail(err, LSM_ERR_INPUT, w->path, "z spacing %g must be finite and positive", sz);
  } else if (!nrrd_header(header, w, w->slices, sz)) {
    st = lsm_fail(err, LSM_ERR_INTERNAL, w->path, "NRRD header does not fit in %d bytes",
                  NRRD_HEADER_BYTES);
  } else if (fseek(w->fp, 0, SEEK_SET) != 0) {
    st = lsm_fail(err, LSM_ERR_IO, w->path, "write failed: %s", strerror(errno));
  } else if (fwrite(header, 1, NRRD_HEADER_BYTES, w->fp) != NRRD_HEADER_BYTES) {
    st = lsm_fail(err, LSM_ERR_IO, w->path, "write failed: %s", strerror(errno));
  }
  st = lsm_close_written(&w->fp, w->path, st, err);
  lsm_nrrd_abort(wp);
  return st;
}

void lsm_nrrd_abort(lsm_nrrd_writer **wp) {
  if (!wp || !*wp) return;
  lsm_nrrd_writer *w = *wp;
  if (w->fp) fclose(w->fp);
  free(w->buf);
  free(w->path);
  free(w);
  *wp = NULL;
}
