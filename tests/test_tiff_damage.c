/* Damaged TIFF slices are refused (issue 54, item 3): a cut CCITT G4 strip,
 * a cut tile, garbage CCITT data, a missing tile, a cut LZW strip.  Each
 * file is built as writers such as tifffile lay them out, directory first and
 * pixel data after it, so that cutting the file cuts the pixels and keeps the
 * directory readable; the encoded strips and tiles come from libtiff.  The
 * intact files read back exactly; every damaged one gives LSM_ERR_INPUT with
 * the file's name and libtiff's cause. */
#include "tests/lsm_test_io.h"

#include <tiffio.h>
#include <unistd.h>

#include "io/lsm_io.h"

#define SIDE 64    /* image width and height */
#define CHUNKS 16  /* strips or tiles at most */

/* The shape: a disc of radius 20 in the middle. */
static int shape(int x, int y) { return (x - 32) * (x - 32) + (y - 32) * (y - 32) <= 400; }

typedef struct layout {
  uint16_t bits, photometric, compression;
  uint32_t tile;           /* tile side, or 0 for strips */
  uint32_t rows_per_strip; /* strips */
} layout;

typedef struct chunks {
  size_t n;
  uint8_t *data[CHUNKS];
  uint32_t size[CHUNKS];
} chunks;

static void chunks_free(chunks *c) {
  for (size_t k = 0; k < c->n; ++k) free(c->data[k]);
  c->n = 0;
}

/* The shape's sample at (x, y): 1 bit (white = 1 = inside), or 8 bits. */
static uint8_t sample8(const layout *l, int x, int y) {
  if (l->photometric == PHOTOMETRIC_PALETTE) return shape(x, y) ? 3 : 1;
  return shape(x, y) ? 220 : 20;
}

/* Encodes the shape with libtiff (its usual layout, in a scratch file) and
 * takes the encoded strips or tiles back out of it. */
static void encode(const char *scratch, const layout *l, chunks *out) {
  TIFF *tif = TIFFOpen(scratch, "w");
  assert_non_null(tif);
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, (uint32_t)SIDE);
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, (uint32_t)SIDE);
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, l->bits);
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, (uint16_t)1);
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, l->photometric);
  TIFFSetField(tif, TIFFTAG_COMPRESSION, l->compression);
  TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  if (l->photometric == PHOTOMETRIC_PALETTE) {
    static uint16_t red[256], green[256], blue[256];
    for (int k = 0; k < 256; ++k) red[k] = green[k] = blue[k] = k == 3 ? 65535 : 4096;
    TIFFSetField(tif, TIFFTAG_COLORMAP, red, green, blue);
  }
  const size_t row_bytes = l->bits == 1 ? SIDE / 8 : SIDE;
  uint8_t img[SIDE * SIDE];
  memset(img, 0, sizeof img);
  for (int y = 0; y < SIDE; ++y)
    for (int x = 0; x < SIDE; ++x) {
      uint8_t *row = img + (size_t)y * row_bytes;
      if (l->bits == 1) {
        if (shape(x, y)) row[x >> 3] |= (uint8_t)(0x80u >> (x & 7));
      } else {
        row[x] = sample8(l, x, y);
      }
    }
  if (l->tile) {
    TIFFSetField(tif, TIFFTAG_TILEWIDTH, l->tile);
    TIFFSetField(tif, TIFFTAG_TILELENGTH, l->tile);
    uint8_t tile[SIDE * SIDE];
    const size_t tile_row = l->bits == 1 ? l->tile / 8 : l->tile;
    for (uint32_t ty = 0; ty < SIDE; ty += l->tile)
      for (uint32_t tx = 0; tx < SIDE; tx += l->tile) {
        for (uint32_t r = 0; r < l->tile; ++r)
          memcpy(tile + r * tile_row, img + (ty + r) * row_bytes + tx * tile_row / l->tile,
                 tile_row);
        assert_true(TIFFWriteTile(tif, tile, tx, ty, 0, 0) > 0);
      }
  } else {
    TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, l->rows_per_strip);
    for (int y = 0; y < SIDE; ++y)
      assert_int_equal(TIFFWriteScanline(tif, img + (size_t)y * row_bytes, (uint32_t)y, 0), 1);
  }
  assert_int_equal(TIFFWriteDirectory(tif), 1);
  TIFFClose(tif);

  tif = TIFFOpen(scratch, "r");
  assert_non_null(tif);
  out->n = l->tile ? TIFFNumberOfTiles(tif) : TIFFNumberOfStrips(tif);
  assert_true(out->n >= 1 && out->n <= CHUNKS);
  for (size_t k = 0; k < out->n; ++k) {
    const uint64_t size = TIFFGetStrileByteCount(tif, (uint32_t)k);
    assert_true(size > 0 && size < 1u << 20);
    out->size[k] = (uint32_t)size;
    out->data[k] = malloc(size);
    assert_non_null(out->data[k]);
    const tmsize_t got = l->tile ? TIFFReadRawTile(tif, (uint32_t)k, out->data[k], (tmsize_t)size)
                                 : TIFFReadRawStrip(tif, (uint32_t)k, out->data[k], (tmsize_t)size);
    assert_int_equal(got, (tmsize_t)size);
  }
  TIFFClose(tif);
  unlink(scratch);
}

/* Little-endian TIFF bytes. */
typedef struct bytes {
  uint8_t b[1 << 16];
  size_t n;
} bytes;

static void put16(bytes *o, uint16_t v) {
  o->b[o->n++] = (uint8_t)(v & 0xff);
  o->b[o->n++] = (uint8_t)(v >> 8);
}
static void put32(bytes *o, uint32_t v) {
  put16(o, (uint16_t)(v & 0xffff));
  put16(o, (uint16_t)(v >> 16));
}
static void entry(bytes *o, uint16_t tag, uint16_t type, uint32_t count, uint32_t value) {
  put16(o, tag);
  put16(o, type);
  put32(o, count);
  if (type == TIFF_SHORT && count == 1) {
    put16(o, (uint16_t)value);
    put16(o, 0);
  } else {
    put32(o, value);
  }
}

/* The damage done while laying the file out. */
typedef struct damage {
  size_t keep;            /* bytes of the file kept (0: all) */
  int missing;            /* this strip or tile has offset 0 and byte count 0 (-1: none) */
  int declare_kept;       /* byte counts say what the cut file still holds */
  const uint8_t *replace; /* replaces chunk 0's data, replace_size bytes (NULL: none) */
  uint32_t replace_size;
} damage;

/* Writes header, directory, the offset and count arrays, [colour map], then
 * the data of every chunk, as damage says; returns the intact file's length. */
static size_t write_tiff(const char *path, const layout *l, const chunks *c, const damage *d) {
  static bytes o;
  o.n = 0;
  const uint16_t entries = (uint16_t)(l->tile ? 11 : 10) + (l->photometric == PHOTOMETRIC_PALETTE);
  const uint32_t ifd = 8, arrays = ifd + 2 + 12u * entries + 4;
  const uint32_t n = (uint32_t)c->n, arrays_bytes = n > 1 ? 8 * n : 0;
  const uint32_t cmap = arrays + arrays_bytes;
  const uint32_t cmap_bytes = l->photometric == PHOTOMETRIC_PALETTE ? 3 * 256 * 2 : 0;
  const uint32_t data = cmap + cmap_bytes;
  uint32_t offset[CHUNKS], count[CHUNKS], at = data;
  for (uint32_t k = 0; k < n; ++k) {
    const uint32_t size = k == 0 && d->replace ? d->replace_size : c->size[k];
    offset[k] = at;
    count[k] = size;
    at += size;
    if (d->keep && d->declare_kept)
      count[k] = offset[k] >= d->keep ? 1 : offset[k] + size > d->keep ? (uint32_t)d->keep - offset[k] : size;
    if ((int)k == d->missing) offset[k] = count[k] = 0;
  }
  const uint32_t offsets_at = n > 1 ? arrays : offset[0];
  const uint32_t counts_at = n > 1 ? arrays + 4 * n : count[0];
  o.b[0] = 'I', o.b[1] = 'I', o.n = 2;
  put16(&o, 42);
  put32(&o, ifd);
  put16(&o, entries);
  entry(&o, TIFFTAG_IMAGEWIDTH, TIFF_LONG, 1, SIDE);
  entry(&o, TIFFTAG_IMAGELENGTH, TIFF_LONG, 1, SIDE);
  entry(&o, TIFFTAG_BITSPERSAMPLE, TIFF_SHORT, 1, l->bits);
  entry(&o, TIFFTAG_COMPRESSION, TIFF_SHORT, 1, l->compression);
  entry(&o, TIFFTAG_PHOTOMETRIC, TIFF_SHORT, 1, l->photometric);
  if (!l->tile) entry(&o, TIFFTAG_STRIPOFFSETS, TIFF_LONG, n, offsets_at);
  entry(&o, TIFFTAG_SAMPLESPERPIXEL, TIFF_SHORT, 1, 1);
  if (!l->tile) {
    entry(&o, TIFFTAG_ROWSPERSTRIP, TIFF_LONG, 1, l->rows_per_strip);
    entry(&o, TIFFTAG_STRIPBYTECOUNTS, TIFF_LONG, n, counts_at);
  }
  entry(&o, TIFFTAG_PLANARCONFIG, TIFF_SHORT, 1, PLANARCONFIG_CONTIG);
  if (cmap_bytes) entry(&o, TIFFTAG_COLORMAP, TIFF_SHORT, 3 * 256, cmap);
  if (l->tile) {
    entry(&o, TIFFTAG_TILEWIDTH, TIFF_LONG, 1, l->tile);
    entry(&o, TIFFTAG_TILELENGTH, TIFF_LONG, 1, l->tile);
    entry(&o, TIFFTAG_TILEOFFSETS, TIFF_LONG, n, offsets_at);
    entry(&o, TIFFTAG_TILEBYTECOUNTS, TIFF_LONG, n, counts_at);
  }
  put32(&o, 0); /* no next directory */
  assert_int_equal(o.n, arrays);
  if (n > 1) {
    for (uint32_t k = 0; k < n; ++k) put32(&o, offset[k]);
    for (uint32_t k = 0; k < n; ++k) put32(&o, count[k]);
  }
  for (int plane = 0; plane < 3 && cmap_bytes; ++plane)
    for (int k = 0; k < 256; ++k) put16(&o, k == 3 ? 65535 : 4096);
  assert_int_equal(o.n, data);
  for (uint32_t k = 0; k < n; ++k) {
    const uint8_t *src = k == 0 && d->replace ? d->replace : c->data[k];
    const uint32_t size = k == 0 && d->replace ? d->replace_size : c->size[k];
    assert_true(o.n + size <= sizeof o.b);
    memcpy(o.b + o.n, src, size);
    o.n += size;
  }
  const size_t len = d->keep && d->keep < o.n ? d->keep : o.n;
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  assert_int_equal(fwrite(o.b, 1, len, f), len);
  assert_int_equal(fclose(f), 0);
  return o.n;
}

/* Reads path; intact: the shape exactly, else refused naming the file. */
static void check(const char *path, int intact, const char *cause) {
  lsm_mask m;
  lsm_err err;
  lsm_err_clear(&err);
  const lsm_status st = lsm_slice_read_mask(path, NULL, &m, &err);
  if (intact) {
    if (st != LSM_OK) fail_msg("%s: %s", path, err.msg);
    for (int y = 0; y < SIDE; ++y)
      for (int x = 0; x < SIDE; ++x)
        if (m.pixels[y * SIDE + x] != shape(x, y))
          fail_msg("%s: pixel (%d, %d) is %d", path, x, y, m.pixels[y * SIDE + x]);
    lsm_mask_free(&m);
  } else {
    if (st == LSM_OK) {
      long lost = 0;
      for (int k = 0; k < SIDE * SIDE; ++k) lost += m.pixels[k] != shape(k % SIDE, k / SIDE);
      lsm_mask_free(&m);
      fail_msg("%s (%s) was read without an error, %ld pixels wrong", path, cause, lost);
    }
    if (st != LSM_ERR_INPUT) fail_msg("%s (%s): status %d, %s", path, cause, (int)st, err.msg);
    if (strncmp(err.msg, path, strlen(path)) != 0 || !strstr(err.msg, "TIFF"))
      fail_msg("%s (%s): message '%s'", path, cause, err.msg);
  }
  int w = 0, h = 0; /* the header alone stays readable */
  assert_int_equal(lsm_slice_read_header(path, 0, &w, &h, &err), LSM_OK);
  assert_int_equal(w, SIDE);
  unlink(path);
}

static void damaged(const char *dir, const char *name, const layout *l, const damage *d,
                    const char *cause) {
  char scratch[128], path[128];
  snprintf(scratch, sizeof scratch, "%s/scratch.tif", dir);
  snprintf(path, sizeof path, "%s/%s", dir, name);
  chunks c = {0};
  encode(scratch, l, &c);
  const damage none = {0, -1, 0, NULL, 0};
  const size_t size = write_tiff(path, l, &c, &none);
  check(path, 1, "intact");
  /* keep counts from the end of the file: the damage lies in the pixel data */
  damage cut = *d;
  if (cut.keep) {
    size_t total = 0;
    for (size_t k = 0; k < c.n; ++k) total += c.size[k];
    assert_true(cut.keep < total);
    cut.keep = size - cut.keep;
  }
  write_tiff(path, l, &c, &cut);
  check(path, 0, cause);
  chunks_free(&c);
}

static void test_cut_g4_strip(void **state) {
  const tmp_fixture *t = *state;
  const layout g4 = {1, PHOTOMETRIC_MINISBLACK, COMPRESSION_CCITTFAX4, 0, SIDE};
  /* the strip cut in half: its byte count past the end, or saying what is left */
  uint32_t half;
  {
    char scratch[128];
    snprintf(scratch, sizeof scratch, "%s/scratch.tif", t->dir);
    chunks c = {0};
    encode(scratch, &g4, &c);
    half = c.size[0] / 2;
    chunks_free(&c);
  }
  const damage past_end = {half, -1, 0, NULL, 0}, consistent = {half, -1, 1, NULL, 0};
  damaged(t->dir, "g4-cut.tif", &g4, &past_end, "a cut CCITT G4 strip");
  damaged(t->dir, "g4-cut-counted.tif", &g4, &consistent,
          "a cut CCITT G4 strip, its byte count fitting the file");
}

static void test_garbage_g4(void **state) {
  const tmp_fixture *t = *state;
  const layout g4 = {1, PHOTOMETRIC_MINISBLACK, COMPRESSION_CCITTFAX4, 0, SIDE};
  uint8_t junk[256];
  uint64_t seed = 20240601;
  for (size_t k = 0; k < sizeof junk; ++k) junk[k] = (uint8_t)lsm_test_rand(&seed);
  const damage garbage = {0, -1, 0, junk, sizeof junk};
  damaged(t->dir, "g4-garbage.tif", &g4, &garbage, "garbage CCITT G4 data");
}

static void test_cut_and_missing_tiles(void **state) {
  const tmp_fixture *t = *state;
  /* gray is read tile by tile, a palette through libtiff's RGBA reader */
  const layout gray = {8, PHOTOMETRIC_MINISBLACK, COMPRESSION_NONE, 32, 0};
  const layout palette = {8, PHOTOMETRIC_PALETTE, COMPRESSION_ADOBE_DEFLATE, 16, 0};
  const layout *layouts[] = {&gray, &palette};
  const char *names[] = {"gray", "palette"};
  for (int k = 0; k < 2; ++k) {
    char name[64];
    const damage cut = {100, -1, 0, NULL, 0}, missing = {0, 1, 0, NULL, 0};
    snprintf(name, sizeof name, "tiles-%s-cut.tif", names[k]);
    damaged(t->dir, name, layouts[k], &cut, "a cut tile");
    snprintf(name, sizeof name, "tiles-%s-missing.tif", names[k]);
    damaged(t->dir, name, layouts[k], &missing, "a missing tile");
  }
}

static void test_cut_lzw_strip(void **state) {
  const tmp_fixture *t = *state;
  const layout lzw = {8, PHOTOMETRIC_MINISBLACK, COMPRESSION_LZW, 0, 16};
  const damage consistent = {40, -1, 1, NULL, 0};
  damaged(t->dir, "lzw-cut-counted.tif", &lzw, &consistent,
          "a cut LZW strip, its byte count fitting the file");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_cut_g4_strip, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_garbage_g4, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_cut_and_missing_tiles, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_cut_lzw_strip, setup_tmp, teardown_tmp),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
