/* io_gzip: a streaming gzip file whose first bytes can be rewritten at the end.
 *
 * volume.nii.gz must start with the NIfTI header, and the header holds the
 * slice count, known only when the last slice is written.  A gzip file cannot
 * be patched where its bytes are deflated, so the head is not deflated:
 *
 *   gzip header (10 bytes: 1f 8b 08, no flags, no time, OS unix)
 *   deflate block 1: stored, not final: 1 byte (BFINAL 0, BTYPE 00, padding),
 *                    LEN and NLEN (2 bytes each, little endian), the head bytes
 *   deflate blocks 2..: the rest, deflated by zlib (a raw deflate stream, its
 *                    own window: nothing in it refers back into the head)
 *   gzip trailer (CRC-32 of all uncompressed bytes, their count mod 2^32)
 *
 * One member, plain RFC 1951/1952: every gzip reader reads it.  The head sits
 * at byte LSM_GZIP_HEAD_OFFSET of the member; finish writes the new head there
 * and the trailer with the CRC of the new head combined with the CRC of the
 * rest (zlib's crc32_combine), so the rest is never read back.
 *
 * volume.nrrd with encoding gzip is the other way round: its header is plain
 * text before the member (a prefix, rewritten in place at the end too) and
 * the member holds the samples only (no head).
 */
#include "io/lsm_io.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#define GZIP_OUT_CHUNK 65536

struct lsm_gzip_writer {
  char *path;
  FILE *fp;
  z_stream z;
  int z_ready;             /* deflateInit2 succeeded: deflateEnd is owed */
  size_t prefix_bytes;     /* plain bytes before the gzip member */
  size_t head_bytes;
  uLong crc_rest;          /* CRC-32 of the bytes after the head */
  uint64_t rest_bytes;
  unsigned char out[GZIP_OUT_CHUNK];
};

static lsm_status write_fail(const lsm_gzip_writer *g, lsm_err *err) {
  return lsm_fail(err, LSM_ERR_IO, g->path, "write failed: %s", strerror(errno));
}

static void put_u32_le(unsigned char *p, uint32_t v) {
  for (int k = 0; k < 4; ++k) p[k] = (unsigned char)((v >> (8 * k)) & 0xffu);
}

/* Runs deflate with flush over the pending input and writes what it makes. */
static lsm_status pump(lsm_gzip_writer *g, int flush, lsm_err *err) {
  for (;;) {
    g->z.next_out = g->out;
    g->z.avail_out = GZIP_OUT_CHUNK;
    int r = deflate(&g->z, flush);
    if (r == Z_STREAM_ERROR)
      return lsm_fail(err, LSM_ERR_INTERNAL, g->path, "zlib deflate failed");
    size_t made = GZIP_OUT_CHUNK - g->z.avail_out;
    if (made && fwrite(g->out, 1, made, g->fp) != made) return write_fail(g, err);
    if (flush == Z_FINISH ? r == Z_STREAM_END : g->z.avail_out != 0) return LSM_OK;
  }
}

lsm_status lsm_gzip_writer_open(const char *path, const unsigned char *prefix,
                                size_t prefix_bytes, const unsigned char *head, size_t head_bytes,
                                int level, lsm_gzip_writer **out, lsm_err *err) {
  if (out) *out = NULL;
  if (!path || !out || (!head && head_bytes) || (!prefix && prefix_bytes) || head_bytes > 65535 ||
      level < 0 || level > 9)
    return lsm_fail(err, LSM_ERR_INTERNAL, path, "bad arguments to the gzip writer");
  lsm_gzip_writer *g = calloc(1, sizeof *g);
  if (!g) return lsm_fail(err, LSM_ERR_NOMEM, path, "cannot allocate the gzip writer");
  size_t len = strlen(path);
  g->path = malloc(len + 1);
  if (!g->path) {
    free(g);
    return lsm_fail(err, LSM_ERR_NOMEM, path, "cannot allocate the gzip writer");
  }
  memcpy(g->path, path, len + 1);
  g->prefix_bytes = prefix_bytes;
  g->head_bytes = head_bytes;
  g->crc_rest = crc32(0L, Z_NULL, 0);
  lsm_status st = LSM_OK;
  /* raw deflate (negative window bits): the gzip framing is written here */
  if (deflateInit2(&g->z, level, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    st = lsm_fail(err, LSM_ERR_NOMEM, path, "cannot start zlib's deflate");
  else
    g->z_ready = 1;
  if (st == LSM_OK) {
    g->fp = fopen(path, "wb");
    if (!g->fp) st = lsm_fail(err, LSM_ERR_IO, path, "cannot create: %s", strerror(errno));
  }
  if (st == LSM_OK) {
    const unsigned n = (unsigned)head_bytes;
    const unsigned char lead[LSM_GZIP_HEAD_OFFSET] = {
        0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 3,  /* gzip: deflate, no flags, no time, unix */
        0x00,                                /* stored block, not the last */
        (unsigned char)(n & 0xffu), (unsigned char)(n >> 8),
        (unsigned char)(~n & 0xffu), (unsigned char)((~n >> 8) & 0xffu)};
    if ((prefix_bytes && fwrite(prefix, 1, prefix_bytes, g->fp) != prefix_bytes) ||
        fwrite(lead, 1, sizeof lead, g->fp) != sizeof lead ||
        (head_bytes && fwrite(head, 1, head_bytes, g->fp) != head_bytes))
      st = write_fail(g, err);
  }
  if (st != LSM_OK) {
    lsm_gzip_writer_abort(&g);
    return st;
  }
  *out = g;
  return LSM_OK;
}

lsm_status lsm_gzip_writer_write(lsm_gzip_writer *g, const void *data, size_t bytes,
                                 lsm_err *err) {
  if (!g || (!data && bytes))
    return lsm_fail(err, LSM_ERR_INTERNAL, g ? g->path : NULL, "bad arguments to a gzip write");
  const unsigned char *p = data;
  while (bytes > 0) {
    /* zlib counts in uInt: feed at most 1 GiB at a time */
    const uInt n = bytes > (1u << 30) ? (1u << 30) : (uInt)bytes;
    g->crc_rest = crc32(g->crc_rest, p, n);
    g->rest_bytes += n;
    g->z.next_in = (Bytef *)(uintptr_t)p; /* zlib does not write through next_in */
    g->z.avail_in = n;
    LSM_TRY(pump(g, Z_NO_FLUSH, err));
    p += n;
    bytes -= n;
  }
  return LSM_OK;
}

lsm_status lsm_gzip_writer_finish(lsm_gzip_writer **gp, const unsigned char *prefix,
                                  const unsigned char *head, lsm_err *err) {
  if (!gp || !*gp) return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "gzip writer is not open");
  lsm_gzip_writer *g = *gp;
  if ((!head && g->head_bytes) || (!prefix && g->prefix_bytes)) {
    lsm_gzip_writer_abort(gp);
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "bad arguments to finish a gzip file");
  }
  g->z.next_in = Z_NULL;
  g->z.avail_in = 0;
  lsm_status st = pump(g, Z_FINISH, err);
  if (st == LSM_OK) {
    uLong crc = crc32(0L, Z_NULL, 0);
    if (g->head_bytes) crc = crc32(crc, head, (uInt)g->head_bytes);
    crc = crc32_combine(crc, g->crc_rest, (z_off_t)g->rest_bytes);
    unsigned char trailer[8];
    put_u32_le(trailer, (uint32_t)crc);
    put_u32_le(trailer + 4, (uint32_t)((g->head_bytes + g->rest_bytes) & 0xffffffffu));
    if (fwrite(trailer, 1, sizeof trailer, g->fp) != sizeof trailer) st = write_fail(g, err);
  }
  if (st == LSM_OK && g->head_bytes &&
      (fseek(g->fp, (long)(g->prefix_bytes + LSM_GZIP_HEAD_OFFSET), SEEK_SET) != 0 ||
       fwrite(head, 1, g->head_bytes, g->fp) != g->head_bytes))
    st = write_fail(g, err);
  if (st == LSM_OK && g->prefix_bytes &&
      (fseek(g->fp, 0, SEEK_SET) != 0 || fwrite(prefix, 1, g->prefix_bytes, g->fp) != g->prefix_bytes))
    st = write_fail(g, err);
  st = lsm_close_written(&g->fp, g->path, st, err);
  lsm_gzip_writer_abort(gp);
  return st;
}

void lsm_gzip_writer_abort(lsm_gzip_writer **gp) {
  if (!gp || !*gp) return;
  lsm_gzip_writer *g = *gp;
  if (g->z_ready) deflateEnd(&g->z);
  if (g->fp) fclose(g->fp);
  free(g->path);
  free(g);
  *gp = NULL;
}
