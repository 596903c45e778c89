/* Tests of the io room's TIFF reader: the same shape written by libtiff in
 * every layout lsmorph accepts (8-bit gray, MINISWHITE at 8 and 1 bit, 16-bit
 * labels, RGB, gray+alpha, palettes; strips and 16 x 16 tiles; LZW, CCITT G4,
 * Deflate, PackBits) reads back as the same mask; the pixel limit; several
 * pages, floating point, 16-bit separate planes and orientations 5 to 8 (rows
 * stored as columns) refused with clear errors;
 * garbage and truncated files are errors naming the file; and .tif/.tiff
 * names are recognised. */
#include "tests/lsm_test_io.h"

#include <tiffio.h>

#include "io/lsm_io.h"

/* ---- TIFF ------------------------------------------------------------------------------ */

/* A TIFF to write: W x H, the sample at (x, y, c) from sample(), which
 * returns a value in the file's own terms (for MINISWHITE, 0 is white). */
#define TW 24
#define TH 10
typedef struct test_tiff {
  uint16_t bits, spp, photometric, planar, compression, format;
  uint16_t extra;   /* 0: none; else the type of one extra sample (the last) */
  int tiled;        /* 16 x 16 tiles */
  int pages;        /* 1, or 2 for a stack */
  uint32_t (*sample)(int x, int y, int c);
  uint16_t orientation; /* 0: not written (top-left) */
} test_tiff;

/* The shape: a disc-like blob left of x = 12, plus the top-right corner. */
static int tiff_shape(int x, int y) { return (x < 12 && y > 1 && y < 8) || (x >= 20 && y < 3); }

static uint32_t gray8(int x, int y, int c) { (void)c; return tiff_shape(x, y) ? 200u : 30u; }
static uint32_t white_zero8(int x, int y, int c) { (void)c; return tiff_shape(x, y) ? 0u : 255u; }
static uint32_t white_zero1(int x, int y, int c) { (void)c; return tiff_shape(x, y) ? 0u : 1u; }
static uint32_t label16(int x, int y, int c) { (void)c; return tiff_shape(x, y) ? 1u : 0u; }
static uint32_t rgb8(int x, int y, int c) { return tiff_shape(x, y) ? (c == 1 ? 250u : 120u) : 0u; }
static uint32_t index8(int x, int y, int c) { (void)c; return tiff_shape(x, y) ? 3u : 1u; }
/* gray 255 everywhere; alpha opaque on the shape, clear elsewhere */
static uint32_t gray_alpha8(int x, int y, int c) { return c == 0 ? 255u : tiff_shape(x, y) ? 255u : 0u; }

static void write_test_tiff(const char *path, const test_tiff *t) {
  TIFF *tif = TIFFOpen(path, "w");
  assert_non_null(tif);
  for (int page = 0; page < t->pages; ++page) {
    TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, (uint32_t)TW);
    TIFFSetField(tif, TIFFTAG_IMAGELENGTH, (uint32_t)TH);
    TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, t->bits);
    TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, t->spp);
    TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, t->photometric);
    TIFFSetField(tif, TIFFTAG_PLANARCONFIG, t->planar ? t->planar : PLANARCONFIG_CONTIG);
    TIFFSetField(tif, TIFFTAG_COMPRESSION, t->compression ? t->compression : COMPRESSION_NONE);
    TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, t->format ? t->format : SAMPLEFORMAT_UINT);
    if (t->orientation) TIFFSetField(tif, TIFFTAG_ORIENTATION, t->orientation);
    if (t->extra) {
      uint16_t types[1] = {t->extra};
      TIFFSetField(tif, TIFFTAG_EXTRASAMPLES, 1, types);
    }
    if (t->photometric == PHOTOMETRIC_PALETTE) {
      static uint16_t red[256], green[256], blue[256];
      for (int k = 0; k < 256; ++k) red[k] = green[k] = blue[k] = k == 3 ? 65535 : 4096;
      TIFFSetField(tif, TIFFTAG_COLORMAP, red, green, blue);
    }
    const int bytes = t->bits / 8 ? t->bits / 8 : 1;
    if (t->tiled) {
      TIFFSetField(tif, TIFFTAG_TILEWIDTH, 16u);
      TIFFSetField(tif, TIFFTAG_TILELENGTH, 16u);
      uint8_t *tile = calloc((size_t)16 * 16 * t->spp * bytes, 1);
      assert_non_null(tile);
      for (int ty = 0; ty < TH; ty += 16)
        for (int tx = 0; tx < TW; tx += 16) {
          memset(tile, 0, (size_t)16 * 16 * t->spp * bytes);
          for (int y = ty; y < ty + 16 && y < TH; ++y)
            for (int x = tx; x < tx + 16 && x < TW; ++x)
              for (int c = 0; c < t->spp; ++c) {
                const size_t k = ((size_t)(y - ty) * 16 + (size_t)(x - tx)) * t->spp + (size_t)c;
                const uint32_t v = t->sample(x, y, c);
                if (t->bits == 1) { /* 16 pixels: 2 bytes a tile row */
                  if (v) tile[k >> 3] |= (uint8_t)(0x80u >> (k & 7));
                } else if (bytes == 2) {
                  const uint16_t u = (uint16_t)v;
                  memcpy(tile + 2 * k, &u, 2);
                } else {
                  tile[k] = (uint8_t)v;
                }
              }
          assert_true(TIFFWriteTile(tif, tile, (uint32_t)tx, (uint32_t)ty, 0, 0) > 0);
        }
      free(tile);
    } else {
      TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, 4u);
      const size_t line = t->bits == 1 ? (TW + 7) / 8 : (size_t)TW * t->spp * bytes;
      uint8_t *row = calloc(line, 1);
      assert_non_null(row);
      for (int y = 0; y < TH; ++y) {
        memset(row, 0, line);
        for (int x = 0; x < TW; ++x)
          for (int c = 0; c < t->spp; ++c) {
            const size_t k = (size_t)x * t->spp + (size_t)c;
            const uint32_t v = t->sample(x, y, c);
            if (t->bits == 1) {
              if (v) row[k >> 3] |= (uint8_t)(0x80u >> (k & 7));
            } else if (bytes == 2) {
              const uint16_t u = (uint16_t)v;
              memcpy(row + 2 * k, &u, 2);
            } else {
              row[k] = (uint8_t)v;
            }
          }
        assert_int_equal(TIFFWriteScanline(tif, row, (uint32_t)y, 0), 1);
      }
      free(row);
    }
    assert_int_equal(TIFFWriteDirectory(tif), 1);
  }
  TIFFClose(tif);
}

/* Writes t as name, reads it back and compares with the shape. */
static lsm_status read_test_tiff(const char *dir, const char *name, const test_tiff *t,
                                 int nonzero, lsm_err *err) {
  char path[256];
  join(path, sizeof path, dir, name);
  write_test_tiff(path, t);
  lsm_image_read_opts opts = {0, 0, nonzero};
  lsm_mask m;
  lsm_err_clear(err);
  lsm_status st = lsm_slice_read_mask(path, &opts, &m, err);
  if (st != LSM_OK) return st;
  assert_int_equal(m.width, TW);
  assert_int_equal(m.height, TH);
  for (int y = 0; y < TH; ++y)
    for (int x = 0; x < TW; ++x)
      if (m.pixels[y * TW + x] != tiff_shape(x, y))
        fail_msg("%s: pixel (%d, %d) is %d", name, x, y, m.pixels[y * TW + x]);
  lsm_mask_free(&m);
  int w = 0, h = 0;
  assert_int_equal(lsm_slice_read_header(path, 0, &w, &h, err), LSM_OK);
  assert_int_equal(w, TW);
  assert_int_equal(h, TH);
  return LSM_OK;
}

static void test_tiff_layouts(void **state) {
  tmp_fixture *f = *state;
  lsm_err err;
  const struct {
    const char *name;
    test_tiff t;
    int nonzero;
  } good[] = {
      {"gray8-lzw.tif", {8, 1, PHOTOMETRIC_MINISBLACK, 0, COMPRESSION_LZW, 0, 0, 0, 1, gray8, 0}, 0},
      {"white-zero8.tif", {8, 1, PHOTOMETRIC_MINISWHITE, 0, 0, 0, 0, 0, 1, white_zero8, 0}, 0},
      {"bilevel.TIFF", {1, 1, PHOTOMETRIC_MINISWHITE, 0, COMPRESSION_CCITTFAX4, 0, 0, 0, 1, white_zero1, 0}, 0},
      {"labels16.tif", {16, 1, PHOTOMETRIC_MINISBLACK, 0, COMPRESSION_ADOBE_DEFLATE, 0, 0, 0, 1, label16, 0}, 1},
      {"rgb8.tif", {8, 3, PHOTOMETRIC_RGB, 0, COMPRESSION_PACKBITS, 0, 0, 0, 1, rgb8, 0}, 0},
      {"gray-alpha8.tif", {8, 2, PHOTOMETRIC_MINISBLACK, 0, 0, 0, EXTRASAMPLE_UNASSALPHA, 0, 1, gray_alpha8, 0}, 0},
      {"palette8.tif", {8, 1, PHOTOMETRIC_PALETTE, 0, 0, 0, 0, 0, 1, index8, 0}, 0},
      {"tiled8.tif", {8, 1, PHOTOMETRIC_MINISBLACK, 0, 0, 0, 0, 1, 1, gray8, 0}, 0},
      {"tiled-rgb8.tif", {8, 3, PHOTOMETRIC_RGB, 0, 0, 0, 0, 1, 1, rgb8, 0}, 0},
      {"tiled16.tif", {16, 1, PHOTOMETRIC_MINISBLACK, 0, COMPRESSION_LZW, 0, 0, 1, 1, label16, 0}, 1},
      {"tiled-bilevel.tif", {1, 1, PHOTOMETRIC_MINISWHITE, 0, COMPRESSION_CCITTFAX4, 0, 0, 1, 1, white_zero1, 0}, 0},
      {"tiled-palette8.tif", {8, 1, PHOTOMETRIC_PALETTE, 0, COMPRESSION_LZW, 0, 0, 1, 1, index8, 0}, 0},
      {"tiled-palette8-raw.tif", {8, 1, PHOTOMETRIC_PALETTE, 0, 0, 0, 0, 1, 1, index8, 0}, 0},
  };
  for (size_t k = 0; k < sizeof good / sizeof good[0]; ++k)
    if (read_test_tiff(f->dir, good[k].name, &good[k].t, good[k].nonzero, &err) != LSM_OK)
      fail_msg("%s: %s", good[k].name, err.msg);

  /* 0/1 labels read by the 50 % rule are all background: the CLI's label
   * detection (pick_foreground) sets nonzero for such stacks */
  char path[256];
  join(path, sizeof path, f->dir, "labels16.tif");
  lsm_image_read_opts plain = {0, 0, 0};
  lsm_mask m;
  assert_int_equal(lsm_slice_read_mask(path, &plain, &m, &err), LSM_OK);
  assert_int_equal(lsm_mask_count(&m), 0);
  lsm_mask_free(&m);
  /* the pixel limit, from the header */
  lsm_image_read_opts small = {0, TW * TH - 1, 0};
  lsm_err_clear(&err);
  assert_int_equal(lsm_slice_read_mask(path, &small, &m, &err), LSM_ERR_LIMIT);
  assert_msg_contains(err, "more than the limit of 239");
  int w, h;
  assert_int_equal(lsm_slice_read_header(path, TW * TH - 1, &w, &h, &err), LSM_ERR_LIMIT);

  const struct {
    const char *name;
    test_tiff t;
    lsm_status want;
    const char *msg;
  } bad[] = {
      {"stack.tif", {8, 1, PHOTOMETRIC_MINISBLACK, 0, 0, 0, 0, 0, 2, gray8, 0}, LSM_ERR_INPUT, "several pages"},
      {"float.tif", {32, 1, PHOTOMETRIC_MINISBLACK, 0, 0, SAMPLEFORMAT_IEEEFP, 0, 0, 1, gray8, 0}, LSM_ERR_UNSUPPORTED, "floating point"},
      {"planes16.tif", {16, 2, PHOTOMETRIC_MINISBLACK, PLANARCONFIG_SEPARATE, 0, 0, EXTRASAMPLE_UNASSALPHA, 0, 1, label16, 0}, LSM_ERR_UNSUPPORTED, "16-bit TIFF in separate planes"},
      /* rows stored as columns: libtiff's RGBA reader would swap width and height */
      {"lefttop.tif", {8, 1, PHOTOMETRIC_MINISBLACK, 0, 0, 0, 0, 0, 1, gray8, ORIENTATION_LEFTTOP}, LSM_ERR_UNSUPPORTED, "TIFF orientation 5 (rows stored as columns"},
      {"rightbot.tif", {8, 3, PHOTOMETRIC_RGB, 0, 0, 0, 0, 1, 1, rgb8, ORIENTATION_RIGHTBOT}, LSM_ERR_UNSUPPORTED, "TIFF orientation 7 (rows stored as columns"},
  };
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    const lsm_status st = read_test_tiff(f->dir, bad[k].name, &bad[k].t, 0, &err);
    if (st != bad[k].want) fail_msg("%s: status %d (%s)", bad[k].name, (int)st, err.msg);
    assert_msg_contains(err, bad[k].msg);
  }
  join(path, sizeof path, f->dir, "lefttop.tif"); /* refused from the header too */
  lsm_err_clear(&err);
  assert_int_equal(lsm_slice_read_header(path, 0, &w, &h, &err), LSM_ERR_UNSUPPORTED);
  /* not a TIFF at all, and a truncated one: errors with the file's name */
  join(path, sizeof path, f->dir, "garbage.tif");
  write_bytes(path, "II*\0garbage", 11);
  lsm_err_clear(&err);
  assert_int_equal(lsm_slice_read_mask(path, NULL, &m, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, "garbage.tif");
  assert_null(strstr(strstr(err.msg, "garbage.tif") + 1, "garbage.tif")); /* named once */
  char good_path[256], cut[256];
  join(good_path, sizeof good_path, f->dir, "gray8-lzw.tif");
  join(cut, sizeof cut, f->dir, "cut.tif");
  FILE *in = fopen(good_path, "rb");
  assert_non_null(in);
  uint8_t buf[4096];
  const size_t got = fread(buf, 1, sizeof buf, in);
  fclose(in);
  for (size_t len = 0; len < got; len += 7) {
    write_bytes(cut, (const char *)buf, len);
    lsm_err_clear(&err);
    const lsm_status st = lsm_slice_read_mask(cut, NULL, &m, &err);
    if (st == LSM_OK) lsm_mask_free(&m);
    else assert_true(st == LSM_ERR_INPUT || st == LSM_ERR_UNSUPPORTED);
  }
}

/* Fills a stretch of the stack below the caller with non-zero bytes, so that a
 * reader's uninitialised locals are not zero by luck. */
static __attribute__((noinline)) void dirty_stack(void) {
  volatile unsigned char junk[1 << 16];
  for (size_t i = 0; i < sizeof junk; ++i) junk[i] = 0xa5;
}

/* A private tag (65000, as ImageJ and microscopes write them) draws a warning
 * from libtiff while the directory is read: a note, not damage (it was read as
 * damage when the reader's state was left uninitialised). */
static void test_tiff_unknown_tag(void **state) {
  tmp_fixture *f = *state;
  /* little endian, 4 x 4 gray 8-bit, one strip at byte 8, then 10 entries */
  static const unsigned char tiff[] = {
      'I', 'I', 42, 0, 24, 0, 0, 0, 0, 0, 0, 0, 255, 255, 0, 0, 255, 255, 0, 0, 0, 0, 0, 0,
      10, 0,
      0x00, 1, 3, 0, 1, 0, 0, 0, 4, 0, 0, 0,          /* ImageWidth 4 */
      0x01, 1, 3, 0, 1, 0, 0, 0, 4, 0, 0, 0,          /* ImageLength 4 */
      0x02, 1, 3, 0, 1, 0, 0, 0, 8, 0, 0, 0,          /* BitsPerSample 8 */
      0x03, 1, 3, 0, 1, 0, 0, 0, 1, 0, 0, 0,          /* Compression none */
      0x06, 1, 3, 0, 1, 0, 0, 0, 1, 0, 0, 0,          /* MinIsBlack */
      0x11, 1, 4, 0, 1, 0, 0, 0, 8, 0, 0, 0,          /* StripOffsets 8 */
      0x15, 1, 3, 0, 1, 0, 0, 0, 1, 0, 0, 0,          /* SamplesPerPixel 1 */
      0x16, 1, 3, 0, 1, 0, 0, 0, 4, 0, 0, 0,          /* RowsPerStrip 4 */
      0x17, 1, 4, 0, 1, 0, 0, 0, 16, 0, 0, 0,         /* StripByteCounts 16 */
      0xe8, 0xfd, 2, 0, 2, 0, 0, 0, 'x', 0, 0, 0,     /* 65000, ASCII "x" */
      0, 0, 0, 0};
  char path[256];
  join(path, sizeof path, f->dir, "private-tag.tif");
  write_bytes(path, tiff, sizeof tiff);
  lsm_err err;
  int w = 0, h = 0;
  for (int k = 0; k < 3; ++k) {
    lsm_err_clear(&err);
    dirty_stack();
    if (lsm_slice_read_header(path, 0, &w, &h, &err) != LSM_OK) fail_msg("header: %s", err.msg);
    assert_int_equal(w, 4);
    assert_int_equal(h, 4);
    lsm_mask m;
    dirty_stack();
    if (lsm_slice_read_mask(path, NULL, &m, &err) != LSM_OK) fail_msg("mask: %s", err.msg);
    assert_int_equal(lsm_mask_count(&m), 4); /* rows 1 and 2: two bright pixels each */
    lsm_mask_free(&m);
  }
}

static void test_tiff_names(void **state) {
  (void)state;
  assert_true(lsm_is_tiff_name("a/1.tif"));
  assert_true(lsm_is_tiff_name("1.TIFF"));
  assert_true(lsm_is_tiff_name("x.Tif"));
  assert_false(lsm_is_tiff_name("1.png"));
  assert_false(lsm_is_tiff_name("tif"));
  assert_false(lsm_is_tiff_name("a.tif/1.png"));
  assert_false(lsm_is_tiff_name("1.tiff.png"));
  assert_false(lsm_is_tiff_name("1.tiffs"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_tiff_layouts, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_tiff_unknown_tag, setup_tmp, teardown_tmp),
      cmocka_unit_test(test_tiff_names),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
