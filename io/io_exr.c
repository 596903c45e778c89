/* io_exr: one single-channel scanline OpenEXR file per slice, written with the
 * OpenEXR core C API (OpenEXRCore, openexr.h; OpenEXR >= 3.1).
 *
 * The file is created here (open + pwrite through a custom stream) so every
 * failure carries the file name and the system's reason; the library's own
 * messages are caught by an error handler and kept for the lsm_err message
 * instead of being printed.
 *
 *   channel "Y": float32 signed distance (LSM_VALUES_SDF), or half 1.0 inside
 *                (phi <= 0) / 0.0 outside (LSM_VALUES_MASK: exact in half, half
 *                the size of float)
 *   compression ZIP (lossless, 16 scanlines per chunk; the chunks are
 *                compressed here with zlib and written with
 *                exr_write_scanline_chunk), INCREASING_Y: row 0 of the slice is
 *                scanline 0 (the top row, as in the PNG slices)
 *   attributes   pixelSize (v2d: sx, sy), sliceHeight (double), sliceIndex (int,
 *                from 1), values (string "sdf" or "mask"); pixelAspectRatio
 *                is sx / sy
 */
#include "io/lsm_io.h"

#include <OpenEXR/openexr.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

typedef struct exr_stream {
  int fd;
  int write_errno;   /* errno of the first failed write, 0 if none */
  char message[256]; /* the library's first error message */
} exr_stream;

static void exr_error_handler(exr_const_context_t ctxt, exr_result_t code, const char *msg) {
  void *ud = NULL;
  if (exr_get_user_data(ctxt, &ud) != EXR_ERR_SUCCESS || !ud) return;
  exr_stream *s = ud;
  if (s->message[0] == '\0')
    snprintf(s->message, sizeof s->message, "%s", msg ? msg : exr_get_default_error_message(code));
}

static int64_t exr_stream_write(exr_const_context_t ctxt, void *userdata, const void *buffer,
                                uint64_t sz, uint64_t offset, exr_stream_error_func_ptr_t error_cb) {
  (void)ctxt;
  (void)error_cb;
  exr_stream *s = userdata;
  const unsigned char *p = buffer;
  uint64_t done = 0;
  while (done < sz) {
    ssize_t n = pwrite(s->fd, p + done, (size_t)(sz - done), (off_t)(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (!s->write_errno) s->write_errno = n < 0 ? errno : EIO;
      return -1;
    }
    done += (uint64_t)n;
  }
  return (int64_t)done;
}

/* OpenEXR's ZIP compression of one chunk, done here with zlib (the encoder of
 * OpenEXRCore 3.1.5, Debian 12's, corrupts some float chunks): even bytes then
 * odd bytes, each byte replaced by its difference to the previous one + 128,
 * deflated.  Returns 1 with *out_bytes set when the result is smaller than
 * the input (else the chunk is stored as is, as the format prescribes). */
static int zip_chunk(const unsigned char *raw, size_t bytes, unsigned char *tmp,
                     unsigned char *zip, uLongf zip_cap, size_t *out_bytes) {
  size_t half_n = (bytes + 1) / 2;
  for (size_t k = 0; k < bytes; ++k) tmp[(k & 1) ? half_n + k / 2 : k / 2] = raw[k];
  int prev = tmp[0];
  for (size_t k = 1; k < bytes; ++k) {
    int cur = tmp[k];
    tmp[k] = (unsigned char)(cur - prev + 128 + 256);
    prev = cur;
  }
  uLongf len = zip_cap;
  if (compress2(zip, &len, tmp, (uLong)bytes, Z_DEFAULT_COMPRESSION) != Z_OK) return 0;
  if ((size_t)len >= bytes) return 0;
  *out_bytes = (size_t)len;
  return 1;
}

/* Half-float bit patterns of the mask values. */
#define HALF_ONE 0x3c00u
#define HALF_ZERO 0x0000u

static lsm_status exr_fail(lsm_err *err, const char *path, const exr_stream *s, exr_result_t rv,
                           const char *what) {
  if (s->write_errno)
    return lsm_fail(err, LSM_ERR_IO, path, "write failed: %s", strerror(s->write_errno));
  return lsm_fail(err, rv == EXR_ERR_OUT_OF_MEMORY ? LSM_ERR_NOMEM : LSM_ERR_IO, path,
                  "OpenEXR: %s: %s", what,
                  s->message[0] ? s->message : exr_get_default_error_message(rv));
}

lsm_status lsm_exr_write_slice(const char *path, const float *phi, const lsm_volume_info *info,
                               double z, size_t index, lsm_err *err) {
  if (!path || !phi || !info)
    return lsm_fail(err, LSM_ERR_INTERNAL, path, "bad arguments to the EXR writer");
  if (info->nx <= 0 || info->ny <= 0)
    return lsm_fail(err, LSM_ERR_INPUT, path, "slice size %dx%d is not positive", info->nx,
                    info->ny);
  if (!(isfinite(info->sx) && info->sx > 0 && isfinite(info->sy) && info->sy > 0))
    return lsm_fail(err, LSM_ERR_INPUT, path, "pixel size %g x %g must be finite and positive",
                    info->sx, info->sy);
  const int mask = info->values == LSM_VALUES_MASK;
  const size_t n = (size_t)info->nx * (size_t)info->ny;
  uint16_t *half = NULL;
  if (mask) {
    half = lsm_alloc(n, sizeof *half, err, path);
    if (!half) return LSM_ERR_NOMEM;
    for (size_t k = 0; k < n; ++k) half[k] = phi[k] <= 0.0f ? HALF_ONE : HALF_ZERO;
  }

  exr_stream s;
  memset(&s, 0, sizeof s);
  s.fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0666);
  if (s.fd < 0) {
    lsm_status st = lsm_fail(err, LSM_ERR_IO, path, "cannot create: %s", strerror(errno));
    free(half);
    return st;
  }
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.error_handler_fn = exr_error_handler;
  init.user_data = &s;
  init.write_fn = exr_stream_write;

  lsm_status st = LSM_OK;
  exr_context_t ctx = NULL;
  exr_result_t rv = exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
  if (rv != EXR_ERR_SUCCESS) st = exr_fail(err, path, &s, rv, "cannot start the file");
  int part = 0;
  if (st == LSM_OK) {
    const char *what = "cannot set up the header";
    rv = exr_add_part(ctx, "", EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_ERR_SUCCESS)
      rv = exr_initialize_required_attr_simple(ctx, part, info->nx, info->ny,
                                               EXR_COMPRESSION_ZIP);
    if (rv == EXR_ERR_SUCCESS)
      rv = exr_set_pixel_aspect_ratio(ctx, part, (float)(info->sx / info->sy));
    if (rv == EXR_ERR_SUCCESS)
      rv = exr_add_channel(ctx, part, "Y", mask ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT,
                           EXR_PERCEPTUALLY_LINEAR, 1, 1);
    exr_attr_v2d_t pixel;
    pixel.x = info->sx;
    pixel.y = info->sy;
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_v2d(ctx, part, "pixelSize", &pixel);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_double(ctx, part, "sliceHeight", z);
    if (rv == EXR_ERR_SUCCESS)
      rv = exr_attr_set_int(ctx, part, "sliceIndex", index > INT32_MAX ? INT32_MAX : (int32_t)index);
    if (rv == EXR_ERR_SUCCESS)
      rv = exr_attr_set_string(ctx, part, "values", mask ? "mask" : "sdf");
    if (rv == EXR_ERR_SUCCESS) {
      what = "cannot write the header";
      rv = exr_write_header(ctx);
    }
    if (rv != EXR_ERR_SUCCESS) st = exr_fail(err, path, &s, rv, what);
  }
  int lines = 0;
  if (st == LSM_OK) {
    rv = exr_get_scanlines_per_chunk(ctx, part, &lines);
    if (rv != EXR_ERR_SUCCESS || lines <= 0) st = exr_fail(err, path, &s, rv, "bad chunk size");
  }
  const size_t bpp = mask ? 2 : 4;
  const size_t row_bytes = (size_t)info->nx * bpp;
  unsigned char *raw = NULL, *tmp = NULL, *zip = NULL;
  uLongf zip_cap = 0;
  if (st == LSM_OK) {
    size_t chunk_bytes = row_bytes * (size_t)lines;
    zip_cap = compressBound((uLong)chunk_bytes);
    raw = malloc(chunk_bytes);
    tmp = malloc(chunk_bytes);
    zip = malloc(zip_cap);
    if (!raw || !tmp || !zip || chunk_bytes > (size_t)UINT32_MAX)
      st = lsm_fail(err, LSM_ERR_NOMEM, path, "cannot allocate %zu bytes for a chunk", chunk_bytes);
  }
  for (int y = 0; st == LSM_OK && y < info->ny; y += lines) {
    const int rows = info->ny - y < lines ? info->ny - y : lines;
    const size_t count = (size_t)rows * (size_t)info->nx;
    const size_t bytes = count * bpp;
    /* the pixels of the chunk's lines, little endian (one channel: line after line) */
    for (size_t k = 0; k < count; ++k) {
      const size_t src = (size_t)y * (size_t)info->nx + k;
      if (mask) {
        raw[2 * k] = (unsigned char)(half[src] & 0xffu);
        raw[2 * k + 1] = (unsigned char)(half[src] >> 8);
      } else {
        uint32_t u;
        memcpy(&u, &phi[src], sizeof u);
        raw[4 * k] = (unsigned char)(u & 0xffu);
        raw[4 * k + 1] = (unsigned char)((u >> 8) & 0xffu);
        raw[4 * k + 2] = (unsigned char)((u >> 16) & 0xffu);
        raw[4 * k + 3] = (unsigned char)(u >> 24);
      }
    }
    const unsigned char *out = raw;
    size_t out_bytes = bytes;
    if (zip_chunk(raw, bytes, tmp, zip, zip_cap, &out_bytes))
      out = zip;
    else
      out_bytes = bytes;
    rv = exr_write_scanline_chunk(ctx, part, y, out, (uint64_t)out_bytes);
    if (rv != EXR_ERR_SUCCESS) st = exr_fail(err, path, &s, rv, "cannot write the pixels");
  }
  free(raw);
  free(tmp);
  free(zip);
  if (ctx) {
    rv = exr_finish(&ctx); /* writes the chunk offset table */
    if (rv != EXR_ERR_SUCCESS && st == LSM_OK)
      st = exr_fail(err, path, &s, rv, "cannot finish the file");
  }
  if (close(s.fd) != 0 && st == LSM_OK)
    st = lsm_fail(err, LSM_ERR_IO, path, "write failed on close: %s", strerror(errno));
  free(half);
  return st;
}
