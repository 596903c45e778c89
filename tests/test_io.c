/* Tests of the io room: PNG in/out, folder listing, heights, NRRD. */
#include "lsm_test.h"

#include <dirent.h>
#include <errno.h>
#include <png.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <tiffio.h>
#include <unistd.h>
#include <zlib.h>

#include "io/lsm_io.h"

/* ---- fixture: a fresh temporary folder per test ------------------------------ */

typedef struct tmp_fixture {
  char dir[64];
} tmp_fixture;

static void rm_rf(const char *path) {
  struct stat sb;
  if (lstat(path, &sb) != 0) return;
  if (S_ISDIR(sb.st_mode)) {
    DIR *d = opendir(path);
    if (d) {
      struct dirent *e;
      while ((e = readdir(d)) != NULL) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
        char child[1024];
        snprintf(child, sizeof child, "%s/%s", path, e->d_name);
        rm_rf(child);
      }
      closedir(d);
    }
    rmdir(path);
  } else {
    unlink(path);
  }
}

static int setup_tmp(void **state) {
  tmp_fixture *f = malloc(sizeof *f);
  if (!f) return -1;
  snprintf(f->dir, sizeof f->dir, "/tmp/lsm_test_io_XXXXXX");
  if (!mkdtemp(f->dir)) {
    free(f);
    return -1;
  }
  *state = f;
  return 0;
}

static int teardown_tmp(void **state) {
  tmp_fixture *f = *state;
  if (f) {
    rm_rf(f->dir);
    free(f);
  }
  return 0;
}

static void join(char *out, size_t size, const char *dir, const char *name) {
  int n = snprintf(out, size, "%s/%s", dir, name);
  assert_true(n > 0 && (size_t)n < size);
}

static void write_bytes(const char *path, const void *data, size_t len) {
  FILE *fp = fopen(path, "wb");
  assert_non_null(fp);
  if (len) assert_int_equal(fwrite(data, 1, len, fp), len);
  assert_int_equal(fclose(fp), 0);
}

static uint8_t *read_bytes(const char *path, size_t *len) {
  char *data = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_read_file(path, (size_t)1 << 30, &data, len, &err), LSM_OK);
  return (uint8_t *)data;
}

#define assert_msg_contains(err, text)                                                \
  do {                                                                                \
    if (!strstr((err).msg, (text)))                                                   \
      fail_msg("message \"%s\" does not contain \"%s\"", (err).msg, (text));          \
  } while (0)

/* ---- writing test PNGs with libpng directly --------------------------------- */

typedef struct test_png {
  int width, height, depth, color_type, interlace;
  const unsigned *samples; /* width*channels per row, one value per sample */
  const png_color *palette;
  int num_palette;
  const png_byte *trans_alpha; /* palette tRNS */
  int num_trans;
  const png_color_16 *trans_color; /* gray / RGB tRNS */
} test_png;

static int channels_of(int color_type) {
  switch (color_type) {
    case PNG_COLOR_TYPE_GRAY: return 1;
    case PNG_COLOR_TYPE_GRAY_ALPHA: return 2;
    case PNG_COLOR_TYPE_RGB: return 3;
    case PNG_COLOR_TYPE_RGB_ALPHA: return 4;
    default: return 1; /* palette index */
  }
}

static void write_test_png(const char *path, const test_png *t) {
  const int ch = channels_of(t->color_type);
  const size_t per_row = (size_t)t->width * (size_t)ch;
  const size_t rowbytes = (per_row * (size_t)t->depth + 7) / 8;
  uint8_t *buf = calloc(rowbytes * (size_t)t->height, 1);
  png_bytep *rows = malloc((size_t)t->height * sizeof *rows);
  assert_non_null(buf);
  assert_non_null(rows);
  for (int y = 0; y < t->height; ++y) {
    uint8_t *row = buf + (size_t)y * rowbytes;
    rows[y] = row;
    for (size_t s = 0; s < per_row; ++s) {
      unsigned v = t->samples[(size_t)y * per_row + s];
      if (t->depth == 16) {
        row[2 * s] = (uint8_t)(v >> 8);
        row[2 * s + 1] = (uint8_t)(v & 255u);
      } else if (t->depth == 8) {
        row[s] = (uint8_t)v;
      } else {
        size_t bit = s * (size_t)t->depth;
        row[bit / 8] |= (uint8_t)(v << (8 - t->depth - (int)(bit % 8)));
      }
    }
  }
  FILE *fp = fopen(path, "wb");
  assert_non_null(fp);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
  assert_non_null(png);
  png_infop info = png_create_info_struct(png);
  assert_non_null(info);
  if (setjmp(png_jmpbuf(png))) fail_msg("libpng failed to write the test image %s", path);
  png_init_io(png, fp);
  png_set_IHDR(png, info, (png_uint_32)t->width, (png_uint_32)t->height, t->depth,
               t->color_type, t->interlace ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (t->palette) png_set_PLTE(png, info, t->palette, t->num_palette);
  if (t->trans_alpha || t->trans_color)
    png_set_tRNS(png, info, t->trans_alpha, t->num_trans, t->trans_color);
  png_write_info(png, info);
  png_write_image(png, rows);
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  assert_int_equal(fclose(fp), 0);
  free(rows);
  free(buf);
}

/* Writes t, reads it back with the given options and compares to expected. */
static void check_png(const char *dir, const char *name, const test_png *t, int invert,
                      const uint8_t *expected) {
  char path[256];
  join(path, sizeof path, dir, name);
  write_test_png(path, t);
  lsm_image_read_opts opts = {invert, 0, 0};
  lsm_mask mask;
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = lsm_png_read_mask(path, &opts, &mask, &err);
  if (st != LSM_OK) fail_msg("%s: %s", name, err.msg);
  assert_int_equal(mask.width, t->width);
  assert_int_equal(mask.height, t->height);
  size_t n = (size_t)t->width * (size_t)t->height;
  for (size_t k = 0; k < n; ++k)
    if (mask.pixels[k] != expected[k])
      fail_msg("%s: pixel %zu (x=%zu y=%zu) is %d, expected %d", name, k, k % (size_t)t->width,
               k / (size_t)t->width, mask.pixels[k], expected[k]);
  lsm_mask_free(&mask);
}

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
      {"gray8-lzw.tif", {8, 1, PHOTOMETRIC_MINISBLACK, 0, COMPRESSION_LZW, 0, 0, 0, 1, gray8}, 0},
      {"white-zero8.tif", {8, 1, PHOTOMETRIC_MINISWHITE, 0, 0, 0, 0, 0, 1, white_zero8}, 0},
      {"bilevel.TIFF", {1, 1, PHOTOMETRIC_MINISWHITE, 0, COMPRESSION_CCITTFAX4, 0, 0, 0, 1, white_zero1}, 0},
      {"labels16.tif", {16, 1, PHOTOMETRIC_MINISBLACK, 0, COMPRESSION_ADOBE_DEFLATE, 0, 0, 0, 1, label16}, 1},
      {"rgb8.tif", {8, 3, PHOTOMETRIC_RGB, 0, COMPRESSION_PACKBITS, 0, 0, 0, 1, rgb8}, 0},
      {"gray-alpha8.tif", {8, 2, PHOTOMETRIC_MINISBLACK, 0, 0, 0, EXTRASAMPLE_UNASSALPHA, 0, 1, gray_alpha8}, 0},
      {"palette8.tif", {8, 1, PHOTOMETRIC_PALETTE, 0, 0, 0, 0, 0, 1, index8}, 0},
      {"tiled8.tif", {8, 1, PHOTOMETRIC_MINISBLACK, 0, 0, 0, 0, 1, 1, gray8}, 0},
      {"tiled-rgb8.tif", {8, 3, PHOTOMETRIC_RGB, 0, 0, 0, 0, 1, 1, rgb8}, 0},
      {"tiled16.tif", {16, 1, PHOTOMETRIC_MINISBLACK, 0, COMPRESSION_LZW, 0, 0, 1, 1, label16}, 1},
      {"tiled-bilevel.tif", {1, 1, PHOTOMETRIC_MINISWHITE, 0, COMPRESSION_CCITTFAX4, 0, 0, 1, 1, white_zero1}, 0},
      {"tiled-palette8.tif", {8, 1, PHOTOMETRIC_PALETTE, 0, COMPRESSION_LZW, 0, 0, 1, 1, index8}, 0},
      {"tiled-palette8-raw.tif", {8, 1, PHOTOMETRIC_PALETTE, 0, 0, 0, 0, 1, 1, index8}, 0},
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
      {"stack.tif", {8, 1, PHOTOMETRIC_MINISBLACK, 0, 0, 0, 0, 0, 2, gray8}, LSM_ERR_INPUT, "several pages"},
      {"float.tif", {32, 1, PHOTOMETRIC_MINISBLACK, 0, 0, SAMPLEFORMAT_IEEEFP, 0, 0, 1, gray8}, LSM_ERR_UNSUPPORTED, "floating point"},
      {"planes16.tif", {16, 2, PHOTOMETRIC_MINISBLACK, PLANARCONFIG_SEPARATE, 0, 0, EXTRASAMPLE_UNASSALPHA, 0, 1, label16}, LSM_ERR_UNSUPPORTED, "16-bit TIFF in separate planes"},
  };
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    const lsm_status st = read_test_tiff(f->dir, bad[k].name, &bad[k].t, 0, &err);
    if (st != bad[k].want) fail_msg("%s: status %d (%s)", bad[k].name, (int)st, err.msg);
    assert_msg_contains(err, bad[k].msg);
  }
  /* not a TIFF at all, and a truncated one: errors with the file's name */
  join(path, sizeof path, f->dir, "garbage.tif");
  write_bytes(path, "II*\0garbage", 11);
  lsm_err_clear(&err);
  assert_int_equal(lsm_slice_read_mask(path, NULL, &m, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, "garbage.tif");
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

/* ---- natural sort ------------------------------------------------------------- */

static int cmp_natural_qsort(const void *a, const void *b) {
  return lsm_natural_cmp(*(const char *const *)a, *(const char *const *)b);
}

static void test_natural_cmp(void **state) {
  (void)state;
  assert_true(lsm_natural_cmp("2.png", "10.png") < 0);
  assert_true(lsm_natural_cmp("10.png", "2.png") > 0);
  assert_true(lsm_natural_cmp("a2", "a10") < 0);
  assert_true(lsm_natural_cmp("a10", "b1") < 0);
  assert_true(lsm_natural_cmp("a2", "b1") < 0);
  assert_true(lsm_natural_cmp("slice_9.png", "slice_10.png") < 0);
  assert_true(lsm_natural_cmp("x99999999999999999999999", "x100000000000000000000000") < 0);
  assert_true(lsm_natural_cmp("abc", "abc") == 0);
  assert_true(lsm_natural_cmp("", "a") < 0);
  assert_true(lsm_natural_cmp("a", "a1") < 0);
  /* equal numbers with leading zeros: not 0, antisymmetric, stable */
  int c1 = lsm_natural_cmp("01.png", "1.png"), c2 = lsm_natural_cmp("1.png", "01.png");
  assert_true(c1 != 0);
  assert_true((c1 < 0) == (c2 > 0));
  assert_int_equal(c1, lsm_natural_cmp("01.png", "1.png"));
  assert_true(lsm_natural_cmp("001", "01") != 0);
  assert_true(lsm_natural_cmp("01.png", "2.png") < 0); /* value first */
  assert_true(lsm_natural_cmp("img007b", "img7a") > 0); /* 'b' > 'a' after equal 7 */

  const char *names[] = {"10.png", "2.png", "b1", "a10", "1.png", "a2", "01.png", "001.png", "0.png"};
  const char *want[] = {"0.png", "001.png", "01.png", "1.png", "2.png", "10.png", "a2", "a10", "b1"};
  size_t n = sizeof names / sizeof names[0];
  const char *sorted[sizeof names / sizeof names[0]];
  memcpy(sorted, names, sizeof names);
  qsort(sorted, n, sizeof sorted[0], cmp_natural_qsort);
  for (size_t i = 0; i < n; ++i) assert_string_equal(sorted[i], want[i]);
}

/* The number a slice's file name ends with (the note on numbered names). */
static void test_name_number(void **state) {
  (void)state;
  uint64_t n = 12345;
  assert_int_equal(lsm_name_number("dir/slice_0009.png", &n), 1);
  assert_true(n == 9);
  assert_int_equal(lsm_name_number("12b.png", &n), 1); /* the last run of digits */
  assert_true(n == 12);
  assert_int_equal(lsm_name_number("ct_2024_113.PNG", &n), 1);
  assert_true(n == 113);
  assert_int_equal(lsm_name_number("0000.png", &n), 1);
  assert_true(n == 0);
  assert_int_equal(lsm_name_number("x/7", &n), 1); /* no extension */
  assert_true(n == 7);
  assert_int_equal(lsm_name_number(".5.png", &n), 1);
  assert_true(n == 5);
  assert_int_equal(lsm_name_number("999999999999999999.png", &n), 1); /* 18 digits */
  assert_true(n == UINT64_C(999999999999999999));
  n = 42;
  assert_int_equal(lsm_name_number("1234567890123456789.png", &n), 0); /* 19 digits */
  assert_int_equal(lsm_name_number("slice.png", &n), 0);
  assert_int_equal(lsm_name_number("d1r/a.png", &n), 0); /* digits in the folder only */
  assert_int_equal(lsm_name_number("a.7z", &n), 0);     /* digits in the extension only */
  assert_true(n == 42); /* untouched when there is no number */
}

/* ---- heights ----------------------------------------------------------------------- */

static void test_heights_good(void **state) {
  (void)state;
  const char *text =
      "\xEF\xBB\xBF# slice heights in mm, after a UTF-8 byte order mark\n"
      "\n"
      "  -3.5 # the first slice\n"
      "-1e-1\r\n"
      "\t0#no space before the comment\n"
      "# comment in the middle\n"
      "   \n"
      "2.5E+1  \n"
      "+26\n"
      "1.25e2"; /* no final newline */
  double *z = NULL;
  size_t n = 0;
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = lsm_heights_parse(text, strlen(text), "heights.txt", &z, &n, &err);
  if (st != LSM_OK) fail_msg("%s", err.msg);
  const double want[] = {-3.5, -0.1, 0.0, 25.0, 26.0, 125.0};
  assert_int_equal(n, sizeof want / sizeof want[0]);
  for (size_t i = 0; i < n; ++i) assert_true(z[i] == want[i]);
  free(z);
}

static void test_heights_bad(void **state) {
  (void)state;
  static const struct {
    const char *text;
    const char *needle;
  } cases[] = {
      {"1\nnan\n", "line 2: \"nan\" is not a number"},
      {"1\n2\ninf\n", "line 3: \"inf\" is not a number"},
      {"-infinity\n", "line 1:"},
      {"1\n2\nabc\n", "line 3: \"abc\" is not a number"},
      {"1\n2 x\n", "line 2: \"2 x\" is not a number"},
      {"1\n2.5mm\n", "line 2:"},
      {"0x10\n", "line 1:"},
      {"1\n1e999\n", "line 2:"},
      {"1\n3\n\n2\n", "line 4: 2 is not greater than the previous height 3"},
      {"# c\n0.5\n0.5\n", "line 3: 0.5 is not greater than the previous height 0.5"},
      {"0\n75\n50\n", "line 3: 50 is not greater than the previous height 75"},
      {"100\n120\n120\n", "line 3: 120 is not greater than the previous height 120"},
      {"1e-400\n1\n", "line 1: \"1e-400\" is out of range"},
      {"0\n-1e-400\n1\n", "line 2: \"-1e-400\" is out of range"},
      {"1\n2 3 # two values\n", "line 2: \"2 3\" is not a number"},
      {"\xEF\xBB" "1\n", "line 1:"}, /* half a byte order mark */
      {"", "no heights"},
      {"# only a comment\n\n   \n", "no heights"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
    double *z = (double *)&z; /* must be reset to NULL */
    size_t n = 99;
    lsm_err err;
    lsm_err_clear(&err);
    lsm_status st = lsm_heights_parse(cases[i].text, strlen(cases[i].text), "heights.txt", &z, &n, &err);
    if (st != LSM_ERR_INPUT) fail_msg("case %zu: status %d (%s)", i, (int)st, err.msg);
    assert_null(z);
    assert_int_equal(n, 0);
    assert_true(strncmp(err.msg, "heights.txt: ", 13) == 0);
    assert_msg_contains(err, cases[i].needle);
  }
  /* a NUL byte inside the text is refused, not silently cut */
  const char nul_text[] = {'1', '\n', '2', '\0', '5', '\n'};
  double *z = NULL;
  size_t n = 0;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_heights_parse(nul_text, sizeof nul_text, "h", &z, &n, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, "line 2");
}

static void test_heights_read(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  join(path, sizeof path, f->dir, "heights.txt");
  const char *text = "0\n1.5\n3\n";
  write_bytes(path, text, strlen(text));
  double *z = NULL;
  size_t n = 0;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_heights_read(path, &z, &n, &err), LSM_OK);
  assert_int_equal(n, 3);
  assert_true(z[0] == 0.0 && z[1] == 1.5 && z[2] == 3.0);
  free(z);

  write_bytes(path, "1\n0\n", 4);
  lsm_err_clear(&err);
  assert_int_equal(lsm_heights_read(path, &z, &n, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, path);
  assert_msg_contains(err, "line 2");

  join(path, sizeof path, f->dir, "missing.txt");
  lsm_err_clear(&err);
  assert_int_equal(lsm_heights_read(path, &z, &n, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, path);
}

/* ---- PNG: round trips through our writers ---------------------------------------- */

static void test_png_roundtrip_mask(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  join(path, sizeof path, f->dir, "mask.png");
  lsm_mask m;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_mask_create(37, 23, &m, &err), LSM_OK);
  uint64_t seed = 12345;
  for (size_t k = 0; k < 37u * 23u; ++k) m.pixels[k] = (uint8_t)(lsm_test_rand(&seed) & 1u);
  assert_int_equal(lsm_png_write_mask(path, &m, &err), LSM_OK);

  int w = 0, h = 0;
  assert_int_equal(lsm_png_read_size(path, &w, &h, &err), LSM_OK);
  assert_int_equal(w, 37);
  assert_int_equal(h, 23);

  lsm_mask back;
  lsm_image_read_opts opts = {0, 0, 0};
  assert_int_equal(lsm_png_read_mask(path, &opts, &back, &err), LSM_OK);
  assert_int_equal(back.width, 37);
  assert_int_equal(back.height, 23);
  assert_memory_equal(back.pixels, m.pixels, 37u * 23u);
  lsm_mask_free(&back);

  /* NULL options mean defaults */
  assert_int_equal(lsm_png_read_mask(path, NULL, &back, &err), LSM_OK);
  assert_memory_equal(back.pixels, m.pixels, 37u * 23u);
  lsm_mask_free(&back);
  lsm_mask_free(&m);
}

static void test_png_roundtrip_gray_rgb(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  lsm_err err;
  lsm_err_clear(&err);
  const uint8_t gray[] = {0, 127, 128, 255, 200, 3};
  join(path, sizeof path, f->dir, "gray.png");
  assert_int_equal(lsm_png_write_gray8(path, gray, 3, 2, &err), LSM_OK);
  lsm_mask m;
  assert_int_equal(lsm_png_read_mask(path, NULL, &m, &err), LSM_OK);
  const uint8_t want_gray[] = {0, 0, 1, 1, 1, 0};
  assert_int_equal(m.width, 3);
  assert_int_equal(m.height, 2);
  assert_memory_equal(m.pixels, want_gray, sizeof want_gray);
  lsm_mask_free(&m);

  const uint8_t rgb[] = {255, 255, 255, 0, 255, 0, 255, 0, 0, 128, 128, 128};
  join(path, sizeof path, f->dir, "rgb.png");
  assert_int_equal(lsm_png_write_rgb8(path, rgb, 2, 2, &err), LSM_OK);
  assert_int_equal(lsm_png_read_mask(path, NULL, &m, &err), LSM_OK);
  const uint8_t want_rgb[] = {1, 1, 0, 1};
  assert_memory_equal(m.pixels, want_rgb, sizeof want_rgb);
  lsm_mask_free(&m);

  /* bad arguments are refused with a message, nothing is left behind */
  join(path, sizeof path, f->dir, "bad.png");
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_write_gray8(path, gray, 0, 2, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, path);
  assert_int_equal(access(path, F_OK), -1);
}

/* ---- PNG: every colour type and bit depth ------------------------------------------- */

static void test_png_gray1(void **state) {
  tmp_fixture *f = *state;
  const unsigned s[] = {1, 0, 1, 1, 0, 0, 1, 0, 1, 1, /* row 2 */ 0, 0, 0, 1, 1, 1, 1, 0, 0, 1};
  test_png t = {.width = 10, .height = 2, .depth = 1, .color_type = PNG_COLOR_TYPE_GRAY, .samples = s};
  uint8_t want[20];
  for (int k = 0; k < 20; ++k) want[k] = (uint8_t)s[k];
  check_png(f->dir, "g1.png", &t, 0, want);
  uint8_t inv[20];
  for (int k = 0; k < 20; ++k) inv[k] = (uint8_t)!s[k];
  check_png(f->dir, "g1i.png", &t, 1, inv);
}

static void test_png_gray2_4(void **state) {
  tmp_fixture *f = *state;
  const unsigned s2[] = {0, 1, 2, 3};
  const uint8_t w2[] = {0, 0, 1, 1}; /* 2v >= 4 */
  test_png t2 = {.width = 4, .height = 1, .depth = 2, .color_type = PNG_COLOR_TYPE_GRAY, .samples = s2};
  check_png(f->dir, "g2.png", &t2, 0, w2);
  unsigned s4[16];
  uint8_t w4[16];
  for (unsigned v = 0; v < 16; ++v) {
    s4[v] = v;
    w4[v] = v >= 8;
  }
  test_png t4 = {.width = 16, .height = 1, .depth = 4, .color_type = PNG_COLOR_TYPE_GRAY, .samples = s4};
  check_png(f->dir, "g4.png", &t4, 0, w4);
}

static void test_png_gray8(void **state) {
  tmp_fixture *f = *state;
  const unsigned s[] = {0, 127, 128, 255, 1, 254};
  const uint8_t want[] = {0, 0, 1, 1, 0, 1};
  test_png t = {.width = 3, .height = 2, .depth = 8, .color_type = PNG_COLOR_TYPE_GRAY, .samples = s};
  check_png(f->dir, "g8.png", &t, 0, want);
}

static void test_png_gray16(void **state) {
  tmp_fixture *f = *state;
  const unsigned s[] = {32767, 32768, 0, 65535, 32767 + 128, 32512};
  /* 32895 is >= 50 % and 32512 (= 127*256) is not: only the 16-bit values decide */
  const uint8_t want[] = {0, 1, 0, 1, 1, 0};
  test_png t = {.width = 6, .height = 1, .depth = 16, .color_type = PNG_COLOR_TYPE_GRAY, .samples = s};
  check_png(f->dir, "g16.png", &t, 0, want);
  const uint8_t inv[] = {1, 0, 1, 0, 0, 1};
  check_png(f->dir, "g16i.png", &t, 1, inv);
}

static void test_png_gray_trns(void **state) {
  tmp_fixture *f = *state;
  const unsigned s[] = {255, 200, 0, 200};
  png_color_16 key = {0};
  key.gray = 200; /* gray 200 is fully transparent: composited over black */
  const uint8_t want[] = {1, 0, 0, 0};
  test_png t = {.width = 4, .height = 1, .depth = 8, .color_type = PNG_COLOR_TYPE_GRAY,
                .samples = s, .trans_color = &key};
  check_png(f->dir, "gtrns.png", &t, 0, want);
}

static void test_png_gray_alpha(void **state) {
  tmp_fixture *f = *state;
  const unsigned s[] = {255, 255, 255, 127, 255, 128, 0, 255, 200, 0};
  const uint8_t want[] = {1, 0, 1, 0, 0};
  test_png t = {.width = 5, .height = 1, .depth = 8, .color_type = PNG_COLOR_TYPE_GRAY_ALPHA, .samples = s};
  check_png(f->dir, "ga8.png", &t, 0, want);

  const unsigned s16[] = {65535, 32768, 65535, 32767, 32768, 65535, 65535, 0};
  const uint8_t want16[] = {1, 0, 1, 0};
  test_png t16 = {.width = 4, .height = 1, .depth = 16, .color_type = PNG_COLOR_TYPE_GRAY_ALPHA, .samples = s16};
  check_png(f->dir, "ga16.png", &t16, 0, want16);
}

static void test_png_rgb(void **state) {
  tmp_fixture *f = *state;
  const unsigned s[] = {
      255, 255, 255, /* white: 1 */
      0,   0,   0,   /* black: 0 */
      0,   255, 0,   /* green 0.7152: 1 */
      255, 0,   0,   /* red 0.2126: 0 */
      0,   0,   255, /* blue 0.0722: 0 */
      128, 128, 128, /* 128 >= 127.5 (50 %): 1 */
      127, 127, 127, /* just below: 0 */
      255, 255, 0,   /* yellow 0.9278: 1 */
      255, 0,   255, /* magenta 0.2848: 0 */
      0,   180, 0,   /* 0.7152*180 = 128.7: 1 */
      0,   178, 0,   /* 0.7152*178 = 127.3: 0 */
      0,   255, 255, /* cyan 0.7874: 1 */
      128, 128, 127, /* 127.93, 50.17 %: 1 (the threshold is 50 %, not 128/255) */
      127, 127, 128, /* 127.07: 0 */
  };
  const uint8_t want[] = {1, 0, 1, 0, 0, 1, 0, 1, 0, 1, 0, 1, 1, 0};
  test_png t = {.width = 7, .height = 2, .depth = 8, .color_type = PNG_COLOR_TYPE_RGB, .samples = s};
  check_png(f->dir, "rgb8.png", &t, 0, want);

  const unsigned s16[] = {32768, 32768, 32768, 32767, 32767, 32767, 0, 65535, 0, 65535, 0, 0};
  const uint8_t want16[] = {1, 0, 1, 0};
  test_png t16 = {.width = 2, .height = 2, .depth = 16, .color_type = PNG_COLOR_TYPE_RGB, .samples = s16};
  check_png(f->dir, "rgb16.png", &t16, 0, want16);
}

static void test_png_rgba(void **state) {
  tmp_fixture *f = *state;
  const unsigned s[] = {
      255, 255, 255, 0,   /* transparent white: background */
      255, 255, 255, 255, /* opaque white */
      255, 255, 255, 128, /* half: 128 -> foreground */
      255, 255, 255, 127, /* 127 -> background */
      0,   0,   0,   255, /* opaque black */
      0,   0,   0,   0,   /* transparent black */
      200, 200, 200, 163, /* 200 * 163 / 255 = 127.84, 50.13 %: foreground */
      200, 200, 200, 162, /* 127.06: background */
  };
  const uint8_t want[] = {0, 1, 1, 0, 0, 0, 1, 0};
  test_png t = {.width = 4, .height = 2, .depth = 8, .color_type = PNG_COLOR_TYPE_RGB_ALPHA, .samples = s};
  check_png(f->dir, "rgba8.png", &t, 0, want);
  const uint8_t inv[] = {1, 0, 0, 1, 1, 1, 0, 1};
  check_png(f->dir, "rgba8i.png", &t, 1, inv);

  const unsigned s16[] = {65535, 65535, 65535, 0, 65535, 65535, 65535, 32768,
                          65535, 65535, 65535, 32767, 65535, 65535, 65535, 65535};
  const uint8_t want16[] = {0, 1, 0, 1};
  test_png t16 = {.width = 4, .height = 1, .depth = 16, .color_type = PNG_COLOR_TYPE_RGB_ALPHA, .samples = s16};
  check_png(f->dir, "rgba16.png", &t16, 0, want16);
}

static void test_png_palette(void **state) {
  tmp_fixture *f = *state;
  const png_color pal[] = {{0, 0, 0}, {255, 255, 255}, {255, 255, 255}, {0, 255, 0}};
  const png_byte trans[] = {255, 255, 0}; /* entry 2 transparent, entry 3 opaque (implicit) */
  const unsigned s[] = {0, 1, 2, 3, 3, 2, 1, 0};
  const uint8_t want[] = {0, 1, 0, 1, 1, 0, 1, 0};
  test_png t = {.width = 4, .height = 2, .depth = 2, .color_type = PNG_COLOR_TYPE_PALETTE, .samples = s,
                .palette = pal, .num_palette = 4, .trans_alpha = trans, .num_trans = 3};
  check_png(f->dir, "pal2trns.png", &t, 0, want);
  const uint8_t inv[] = {1, 0, 1, 0, 0, 1, 0, 1};
  check_png(f->dir, "pal2trnsi.png", &t, 1, inv);

  /* 8-bit palette, no tRNS: entry 2 is plain white */
  const uint8_t want8[] = {0, 1, 1, 1, 1, 1, 1, 0};
  test_png t8 = {.width = 4, .height = 2, .depth = 8, .color_type = PNG_COLOR_TYPE_PALETTE, .samples = s,
                 .palette = pal, .num_palette = 4};
  check_png(f->dir, "pal8.png", &t8, 0, want8);

  /* 1-bit palette with half-transparent white */
  const png_color pal1[] = {{255, 255, 255}, {255, 255, 255}};
  const png_byte trans1[] = {127, 128};
  const unsigned s1[] = {0, 1, 1, 0};
  const uint8_t want1[] = {0, 1, 1, 0};
  test_png t1 = {.width = 4, .height = 1, .depth = 1, .color_type = PNG_COLOR_TYPE_PALETTE, .samples = s1,
                 .palette = pal1, .num_palette = 2, .trans_alpha = trans1, .num_trans = 2};
  check_png(f->dir, "pal1.png", &t1, 0, want1);
}

static void test_png_interlaced(void **state) {
  tmp_fixture *f = *state;
  enum { W = 13, H = 11 };
  unsigned s[W * H];
  uint8_t want[W * H];
  uint64_t seed = 777;
  for (int k = 0; k < W * H; ++k) {
    s[k] = (unsigned)(lsm_test_rand(&seed) % 256u);
    want[k] = s[k] >= 128;
  }
  test_png t = {.width = W, .height = H, .depth = 8, .color_type = PNG_COLOR_TYPE_GRAY,
                .interlace = 1, .samples = s};
  check_png(f->dir, "inter8.png", &t, 0, want);

  unsigned rgba[W * H * 4];
  for (int k = 0; k < W * H; ++k) {
    unsigned v = (unsigned)(lsm_test_rand(&seed) % 256u), a = (k % 3) ? 255u : 0u;
    rgba[4 * k] = rgba[4 * k + 1] = rgba[4 * k + 2] = v;
    rgba[4 * k + 3] = a;
    want[k] = a && v >= 128;
  }
  test_png t4 = {.width = W, .height = H, .depth = 8, .color_type = PNG_COLOR_TYPE_RGB_ALPHA,
                 .interlace = 1, .samples = rgba};
  check_png(f->dir, "inter_rgba.png", &t4, 0, want);

  unsigned bits[W * H];
  for (int k = 0; k < W * H; ++k) {
    bits[k] = (unsigned)(lsm_test_rand(&seed) & 1u);
    want[k] = (uint8_t)bits[k];
  }
  test_png t1 = {.width = W, .height = H, .depth = 1, .color_type = PNG_COLOR_TYPE_GRAY,
                 .interlace = 1, .samples = bits};
  check_png(f->dir, "inter1.png", &t1, 0, want);
}

static void test_png_invert(void **state) {
  tmp_fixture *f = *state;
  const unsigned s[] = {0, 127, 128, 255};
  const uint8_t want[] = {1, 1, 0, 0};
  test_png t = {.width = 4, .height = 1, .depth = 8, .color_type = PNG_COLOR_TYPE_GRAY, .samples = s};
  check_png(f->dir, "inv.png", &t, 1, want);
}

/* ---- PNG: limits and broken files ---------------------------------------------------- */

static void test_png_max_pixels(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  join(path, sizeof path, f->dir, "big.png");
  uint8_t *px = calloc(100 * 100, 1);
  assert_non_null(px);
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_write_gray8(path, px, 100, 100, &err), LSM_OK);
  free(px);

  lsm_image_read_opts opts = {0, 5000, 0};
  lsm_mask m = {7, 7, (uint8_t *)&m};
  assert_int_equal(lsm_png_read_mask(path, &opts, &m, &err), LSM_ERR_LIMIT);
  assert_null(m.pixels);
  assert_int_equal(m.width, 0);
  assert_msg_contains(err, path);
  assert_msg_contains(err, "10000");

  opts.max_pixels = 10000;
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_read_mask(path, &opts, &m, &err), LSM_OK);
  assert_int_equal(lsm_mask_count(&m), 0);
  lsm_mask_free(&m);
}

static void test_png_not_png(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  lsm_err err;
  lsm_mask m;
  join(path, sizeof path, f->dir, "text.png");
  write_bytes(path, "hello, this is not an image\n", 28);
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_read_mask(path, NULL, &m, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, path);
  assert_msg_contains(err, "not a PNG file");
  int w, h;
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_read_size(path, &w, &h, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, "not a PNG file");

  join(path, sizeof path, f->dir, "empty.png");
  write_bytes(path, "", 0);
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_read_mask(path, NULL, &m, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, "not a PNG file");

  /* a PNG signature and nothing else */
  const uint8_t sig[8] = {137, 80, 78, 71, 13, 10, 26, 10};
  join(path, sizeof path, f->dir, "sigonly.png");
  write_bytes(path, sig, sizeof sig);
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_read_mask(path, NULL, &m, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, path);

  join(path, sizeof path, f->dir, "missing.png");
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_read_mask(path, NULL, &m, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, path);

  /* a folder is not a PNG either */
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_read_mask(f->dir, NULL, &m, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, f->dir);
  assert_msg_contains(err, "folder");
}

/* A 64x64 noise image (incompressible, several KB) written by our writer. */
static uint8_t *noise_png(const char *path, size_t *len) {
  enum { N = 64 };
  uint8_t px[N * N];
  uint64_t seed = 99;
  for (int k = 0; k < N * N; ++k) px[k] = (uint8_t)lsm_test_rand(&seed);
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_write_gray8(path, px, N, N, &err), LSM_OK);
  return read_bytes(path, len);
}

static void test_png_truncated(void **state) {
  tmp_fixture *f = *state;
  char path[256], cut[256];
  join(path, sizeof path, f->dir, "noise.png");
  join(cut, sizeof cut, f->dir, "cut.png");
  size_t len = 0;
  uint8_t *data = noise_png(path, &len);
  assert_true(len > 1000);

  write_bytes(cut, data, len / 2);
  lsm_mask m;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_read_mask(cut, NULL, &m, &err), LSM_ERR_INPUT);
  assert_null(m.pixels);
  assert_msg_contains(err, cut);
  assert_msg_contains(err, "truncated");

  /* every shorter length fails cleanly (IEND included: nothing may be missing) */
  for (size_t n = 0; n < len; n += (n < 64 || n + 64 > len) ? 1 : 37) {
    write_bytes(cut, data, n);
    lsm_err_clear(&err);
    lsm_status st = lsm_png_read_mask(cut, NULL, &m, &err);
    if (st != LSM_ERR_INPUT) fail_msg("cut at %zu of %zu: status %d (%s)", n, len, (int)st, err.msg);
    assert_true(err.msg[0] != '\0');
  }
  free(data);
}

/* Offset of the first chunk of the given type (its length field), or 0. */
static size_t find_chunk(const uint8_t *data, size_t len, const char *type) {
  size_t pos = 8;
  while (pos + 12 <= len) {
    size_t clen = ((size_t)data[pos] << 24) | ((size_t)data[pos + 1] << 16) |
                  ((size_t)data[pos + 2] << 8) | data[pos + 3];
    if (memcmp(data + pos + 4, type, 4) == 0) return pos;
    pos += 12 + clen;
  }
  return 0;
}

static void test_png_corrupt(void **state) {
  tmp_fixture *f = *state;
  char path[256], bad[256];
  join(path, sizeof path, f->dir, "noise.png");
  join(bad, sizeof bad, f->dir, "bad.png");
  size_t len = 0;
  uint8_t *data = noise_png(path, &len);
  size_t idat = find_chunk(data, len, "IDAT");
  assert_true(idat > 0);
  size_t idat_len = ((size_t)data[idat] << 24) | ((size_t)data[idat + 1] << 16) |
                    ((size_t)data[idat + 2] << 8) | data[idat + 3];
  assert_true(idat_len > 100);
  lsm_mask m;
  lsm_err err;

  /* a byte inside the IDAT data */
  data[idat + 8 + idat_len / 2] ^= 0x5a;
  write_bytes(bad, data, len);
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_read_mask(bad, NULL, &m, &err), LSM_ERR_INPUT);
  assert_null(m.pixels);
  assert_msg_contains(err, bad);
  assert_msg_contains(err, "corrupt PNG");
  data[idat + 8 + idat_len / 2] ^= 0x5a;

  /* the IDAT CRC itself: libpng reports a CRC error */
  data[idat + 8 + idat_len] ^= 0x01;
  write_bytes(bad, data, len);
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_read_mask(bad, NULL, &m, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, "CRC");
  data[idat + 8 + idat_len] ^= 0x01;

  /* IHDR CRC: even the size query fails */
  data[8 + 8 + 13] ^= 0x80;
  write_bytes(bad, data, len);
  int w, h;
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_read_size(bad, &w, &h, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, "CRC");
  data[8 + 8 + 13] ^= 0x80;

  /* sanity: the repaired bytes read fine again */
  write_bytes(bad, data, len);
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_read_mask(bad, NULL, &m, &err), LSM_OK);
  lsm_mask_free(&m);

  /* flipping any single byte never crashes; it is either rejected as bad input
   * or still decodes */
  size_t rejected = 0, tried = 0;
  for (size_t k = 0; k < len; k += (k < 80 ? 1 : 53)) {
    data[k] ^= 0xff;
    write_bytes(bad, data, len);
    lsm_err_clear(&err);
    lsm_status st = lsm_png_read_mask(bad, NULL, &m, &err);
    if (st == LSM_OK) {
      lsm_mask_free(&m);
    } else {
      if (st != LSM_ERR_INPUT && st != LSM_ERR_LIMIT)
        fail_msg("flip at %zu: status %d (%s)", k, (int)st, err.msg);
      assert_msg_contains(err, bad);
      ++rejected;
    }
    ++tried;
    data[k] ^= 0xff;
  }
  assert_true(rejected * 10 >= tried * 9); /* CRCs catch essentially all of them */
  free(data);
}

static void test_png_write_errors(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  join(path, sizeof path, f->dir, "no/such/folder/x.png");
  const uint8_t px[4] = {0, 255, 255, 0};
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_png_write_gray8(path, px, 2, 2, &err), LSM_ERR_IO);
  assert_msg_contains(err, path);

  struct stat sb;
  if (stat("/dev/full", &sb) == 0 && S_ISCHR(sb.st_mode)) {
    /* every write fails with ENOSPC: the error must surface (and the device
     * must of course not be removed) */
    lsm_err_clear(&err);
    assert_int_equal(lsm_png_write_gray8("/dev/full", px, 2, 2, &err), LSM_ERR_IO);
    assert_msg_contains(err, "/dev/full");
    assert_int_equal(stat("/dev/full", &sb), 0);
    assert_true(S_ISCHR(sb.st_mode));
  }
}

/* ---- folders --------------------------------------------------------------------------- */

static void test_dir_list(void **state) {
  tmp_fixture *f = *state;
  const char *files[] = {"10.png", "2.png",   "1.PNG",  "notes.txt", ".hidden.png",
                         "png",    "x.png.txt", "3.TIF", "4.jpeg",    ".5.tif",
                         "6.tiff", "7.bmp"};
  char path[256];
  for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
    join(path, sizeof path, f->dir, files[i]);
    write_bytes(path, "x", 1);
  }
  join(path, sizeof path, f->dir, "subdir.png");
  assert_int_equal(mkdir(path, 0755), 0);

  char **list = NULL;
  size_t n = 0;
  lsm_err err;
  lsm_err_clear(&err);
  size_t others = 99;
  assert_int_equal(lsm_dir_list_slices(f->dir, &list, &n, &others, &err), LSM_OK);
  assert_int_equal(n, 5);
  /* images of other formats: 4.jpeg and 7.bmp (not the hidden .5.tif, nor
   * notes.txt, png, x.png.txt) */
  assert_int_equal(others, 2);
  const char *want[] = {"1.PNG", "2.png", "3.TIF", "6.tiff", "10.png"};
  for (size_t i = 0; i < 5; ++i) {
    join(path, sizeof path, f->dir, want[i]);
    assert_string_equal(list[i], path);
  }
  lsm_path_list_free(list, n);

  /* a trailing slash does not double up */
  char slashed[256];
  snprintf(slashed, sizeof slashed, "%s/", f->dir);
  assert_int_equal(lsm_dir_list_slices(slashed, &list, &n, NULL, &err), LSM_OK);
  assert_int_equal(n, 5);
  join(path, sizeof path, f->dir, "1.PNG");
  assert_string_equal(list[0], path);
  lsm_path_list_free(list, n);

  /* an empty folder lists nothing */
  join(path, sizeof path, f->dir, "empty");
  assert_int_equal(mkdir(path, 0755), 0);
  assert_int_equal(lsm_dir_list_slices(path, &list, &n, NULL, &err), LSM_OK);
  assert_int_equal(n, 0);
  lsm_path_list_free(list, n);
}

static void test_dir_errors(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  char **list = (char **)&list;
  size_t n = 5;
  lsm_err err;
  join(path, sizeof path, f->dir, "nope");
  lsm_err_clear(&err);
  assert_int_equal(lsm_dir_list_slices(path, &list, &n, NULL, &err), LSM_ERR_INPUT);
  assert_null(list);
  assert_int_equal(n, 0);
  assert_msg_contains(err, path);
  assert_msg_contains(err, "no such folder");

  join(path, sizeof path, f->dir, "file.png");
  write_bytes(path, "x", 1);
  lsm_err_clear(&err);
  assert_int_equal(lsm_dir_list_slices(path, &list, &n, NULL, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, "not a folder");
}

static void test_make_dir(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  lsm_err err;
  lsm_err_clear(&err);
  join(path, sizeof path, f->dir, "out");
  assert_int_equal(lsm_make_dir(path, &err), LSM_OK);
  struct stat sb;
  assert_int_equal(stat(path, &sb), 0);
  assert_true(S_ISDIR(sb.st_mode));
  assert_int_equal(lsm_make_dir(path, &err), LSM_OK); /* exists: fine */

  join(path, sizeof path, f->dir, "plain");
  write_bytes(path, "x", 1);
  assert_int_equal(lsm_make_dir(path, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, path);

  join(path, sizeof path, f->dir, "a/b/c");
  lsm_err_clear(&err);
  assert_int_equal(lsm_make_dir(path, &err), LSM_ERR_IO); /* one level only */
  assert_msg_contains(err, path);
}

static void test_read_file(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  join(path, sizeof path, f->dir, "data.bin");
  uint8_t bytes[10000];
  uint64_t seed = 5;
  for (size_t k = 0; k < sizeof bytes; ++k) bytes[k] = (uint8_t)lsm_test_rand(&seed);
  write_bytes(path, bytes, sizeof bytes);

  char *data = NULL;
  size_t len = 0;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_read_file(path, sizeof bytes, &data, &len, &err), LSM_OK);
  assert_int_equal(len, sizeof bytes);
  assert_memory_equal(data, bytes, sizeof bytes);
  assert_int_equal(data[len], '\0');
  free(data);

  assert_int_equal(lsm_read_file(path, sizeof bytes - 1, &data, &len, &err), LSM_ERR_LIMIT);
  assert_null(data);
  assert_msg_contains(err, path);

  join(path, sizeof path, f->dir, "empty.txt");
  write_bytes(path, "", 0);
  lsm_err_clear(&err);
  assert_int_equal(lsm_read_file(path, 0, &data, &len, &err), LSM_OK);
  assert_int_equal(len, 0);
  assert_int_equal(data[0], '\0');
  free(data);

  join(path, sizeof path, f->dir, "missing.txt");
  assert_int_equal(lsm_read_file(path, 100, &data, &len, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, path);

  lsm_err_clear(&err);
  assert_int_equal(lsm_read_file(f->dir, 100, &data, &len, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, "folder");
}

/* ---- NRRD ------------------------------------------------------------------------------- */

static uint32_t le32(const uint8_t *p) {
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static int has_line(const char *header, const char *line) {
  size_t n = strlen(line);
  for (const char *p = header; (p = strstr(p, line)) != NULL; ++p)
    if ((p == header || p[-1] == '\n') && p[n] == '\n') return 1;
  return 0;
}

static void test_nrrd_roundtrip(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  join(path, sizeof path, f->dir, "vol.nrrd");
  enum { NX = 4, NY = 3, NZ = 3 };
  float vals[NZ][NX * NY];
  for (int z = 0; z < NZ; ++z)
    for (int k = 0; k < NX * NY; ++k) vals[z][k] = (float)(z * 100 + k) * 0.25f - 7.0f;
  vals[1][5] = 1e-30f;
  vals[2][0] = -0.0f;
  vals[2][11] = 3.4e38f;

  lsm_nrrd_writer *w = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_nrrd_open(path, NX, NY, 0.5, 0.25, 1.0, -1.5, 0.0, 3.25, &w, &err), LSM_OK);
  assert_non_null(w);
  for (int z = 0; z < NZ; ++z) {
    assert_int_equal(lsm_nrrd_slices(w), (size_t)z);
    assert_int_equal(lsm_nrrd_write_slice(w, vals[z], &err), LSM_OK);
  }
  assert_int_equal(lsm_nrrd_slices(w), NZ);
  assert_int_equal(lsm_nrrd_finish(&w, 2.5, &err), LSM_OK);
  assert_null(w);

  size_t len = 0;
  uint8_t *data = read_bytes(path, &len);
  size_t header_len = 0;
  for (size_t k = 0; k + 1 < len && header_len == 0; ++k)
    if (data[k] == '\n' && data[k + 1] == '\n') header_len = k + 2;
  assert_true(header_len > 0);
  assert_int_equal(len, header_len + (size_t)NX * NY * NZ * 4);

  char *header = malloc(header_len + 1);
  assert_non_null(header);
  memcpy(header, data, header_len);
  header[header_len] = '\0';
  assert_true(strncmp(header, "NRRD0004\n", 9) == 0);
  assert_true(has_line(header, "type: float"));
  assert_true(has_line(header, "dimension: 3"));
  assert_true(has_line(header, "sizes: 4 3 3"));
  assert_true(has_line(header, "space dimension: 3"));
  assert_true(has_line(header, "space directions: (0.5,0,0) (0,0.25,0) (0,0,2.5)"));
  assert_true(has_line(header, "space origin: (-1.5,0,3.25)"));
  assert_true(has_line(header, "kinds: domain domain domain"));
  assert_true(has_line(header, "endian: little"));
  assert_true(has_line(header, "encoding: raw"));
  assert_null(strstr(header, "space:"));
  /* every line is a field, a comment or the final blank line */
  for (const char *p = header + 9; *p && p[0] != '\n'; p = strchr(p, '\n') + 1) {
    const char *colon = strstr(p, ": ");
    assert_true(p[0] == '#' || (colon && colon < strchr(p, '\n')));
  }
  free(header);

  for (int z = 0; z < NZ; ++z)
    for (int k = 0; k < NX * NY; ++k) {
      uint32_t want;
      memcpy(&want, &vals[z][k], sizeof want);
      uint32_t got = le32(data + header_len + 4 * ((size_t)z * NX * NY + (size_t)k));
      if (got != want) fail_msg("float %d,%d: got 0x%08x, want 0x%08x", z, k, got, want);
    }
  free(data);
}

static void test_nrrd_fixed_header(void **state) {
  /* the header length does not depend on the numbers in it */
  tmp_fixture *f = *state;
  char path[256];
  join(path, sizeof path, f->dir, "one.nrrd");
  float slice[2] = {1.0f, 2.0f};
  size_t lengths[2];
  for (int pass = 0; pass < 2; ++pass) {
    lsm_nrrd_writer *w = NULL;
    lsm_err err;
    lsm_err_clear(&err);
    double s = pass ? 0.1234567890123456789e-300 : 1.0;
    assert_int_equal(lsm_nrrd_open(path, 2, 1, s, s, s, -s, -s, -s, &w, &err), LSM_OK);
    for (int z = 0; z < (pass ? 12 : 1); ++z) assert_int_equal(lsm_nrrd_write_slice(w, slice, &err), LSM_OK);
    if (lsm_nrrd_finish(&w, pass ? -1.0 / 3.0 * -1e300 : 1.0, &err) != LSM_OK) fail_msg("%s", err.msg);
    size_t len;
    uint8_t *data = read_bytes(path, &len);
    lengths[pass] = len - (pass ? 12u : 1u) * 8u;
    if (pass) assert_true(has_line((const char *)data, "sizes: 2 1 12"));
    free(data);
  }
  assert_int_equal(lengths[0], lengths[1]);
}

static void test_nrrd_errors(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  lsm_nrrd_writer *w = NULL;
  lsm_err err;

  join(path, sizeof path, f->dir, "no/such/dir/v.nrrd");
  lsm_err_clear(&err);
  assert_int_equal(lsm_nrrd_open(path, 4, 3, 1, 1, 1, 0, 0, 0, &w, &err), LSM_ERR_IO);
  assert_null(w);
  assert_msg_contains(err, path);

  join(path, sizeof path, f->dir, "v.nrrd");
  lsm_err_clear(&err);
  assert_int_equal(lsm_nrrd_open(path, 0, 3, 1, 1, 1, 0, 0, 0, &w, &err), LSM_ERR_INPUT);
  assert_null(w);
  lsm_err_clear(&err);
  assert_int_equal(lsm_nrrd_open(path, 4, 3, 1, NAN, 1, 0, 0, 0, &w, &err), LSM_ERR_INPUT);
  assert_null(w);

  /* finishing with no slices is refused */
  lsm_err_clear(&err);
  assert_int_equal(lsm_nrrd_open(path, 4, 3, 1, 1, 1, 0, 0, 0, &w, &err), LSM_OK);
  assert_int_equal(lsm_nrrd_finish(&w, 1.0, &err), LSM_ERR_INPUT);
  assert_null(w);
  assert_msg_contains(err, path);

  /* abort frees everything (valgrind checks) */
  float slice[12] = {0};
  lsm_err_clear(&err);
  assert_int_equal(lsm_nrrd_open(path, 4, 3, 1, 1, 1, 0, 0, 0, &w, &err), LSM_OK);
  assert_int_equal(lsm_nrrd_write_slice(w, slice, &err), LSM_OK);
  lsm_nrrd_abort(&w);
  assert_null(w);
  lsm_nrrd_abort(&w); /* twice is harmless */

  struct stat sb;
  if (stat("/dev/full", &sb) == 0 && S_ISCHR(sb.st_mode)) {
    lsm_err_clear(&err);
    lsm_status st = lsm_nrrd_open("/dev/full", 4, 3, 1, 1, 1, 0, 0, 0, &w, &err);
    for (int z = 0; st == LSM_OK && z < 3; ++z) st = lsm_nrrd_write_slice(w, slice, &err);
    if (st == LSM_OK) st = lsm_nrrd_finish(&w, 1.0, &err);
    else lsm_nrrd_abort(&w);
    assert_int_equal(st, LSM_ERR_IO);
    assert_null(w);
    assert_msg_contains(err, "/dev/full");
  }
}

/* ---- NIfTI-1 (volume.nii) ------------------------------------------------------------ */

static int16_t le16s(const uint8_t *p) { return (int16_t)(uint16_t)(p[0] | (p[1] << 8)); }

static float le_f32(const uint8_t *p) {
  uint32_t u = le32(p);
  float v;
  memcpy(&v, &u, sizeof v);
  return v;
}

/* Writes volume.nii and volume.raw of three slices through the volume writer;
 * returns volume.nii's bytes (and *len). */
static uint8_t *write_nii(const char *dir, lsm_values values, size_t *len, uint8_t **raw,
                          size_t *raw_len) {
  enum { NX = 4, NY = 3, NZ = 3 };
  float vals[NZ][NX * NY];
  for (int z = 0; z < NZ; ++z)
    for (int k = 0; k < NX * NY; ++k) vals[z][k] = (float)(z * 100 + k) * 0.25f - 7.0f;
  vals[1][5] = 0.0f; /* phi = 0 counts as inside in a mask */
  lsm_volume_writer *w = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  if (lsm_volume_writer_open(dir, LSM_FORMAT_NII | LSM_FORMAT_RAW, values, NX, NY, 0.5, 0.25,
                             9.0, 1.5, 0.0, 3.25, &w, &err) != LSM_OK)
    fail_msg("%s", err.msg);
  for (int z = 0; z < NZ; ++z)
    assert_int_equal(lsm_volume_writer_write_slice(w, vals[z], 3.25 + 2.5 * z, &err), LSM_OK);
  if (lsm_volume_writer_finish(&w, 2.5, NZ, &err) != LSM_OK) fail_msg("%s", err.msg);
  char path[256];
  join(path, sizeof path, dir, "volume.raw");
  *raw = read_bytes(path, raw_len);
  join(path, sizeof path, dir, "volume.nii");
  return read_bytes(path, len);
}

/* Every field a reader needs, at its offset in the NIfTI-1 layout; the samples
 * after byte 352 are volume.raw's. */
static void test_nifti_header_fields(void **state) {
  tmp_fixture *f = *state;
  for (int pass = 0; pass < 2; ++pass) {
    const int mask = pass == 1;
    size_t len = 0, raw_len = 0;
    uint8_t *raw = NULL;
    uint8_t *h = write_nii(f->dir, mask ? LSM_VALUES_MASK : LSM_VALUES_SDF, &len, &raw, &raw_len);
    const size_t samples = 4 * 3 * 3, bytes = samples * (mask ? 1u : 4u);
    assert_int_equal(len, LSM_NIFTI_HEADER_BYTES + bytes);
    assert_int_equal(raw_len, bytes);
    assert_int_equal(le32(h + 0), 348);                /* sizeof_hdr: little endian */
    assert_int_equal(h[38], 'r');
    const int16_t dim[8] = {3, 4, 3, 3, 1, 1, 1, 1};
    for (int k = 0; k < 8; ++k) assert_int_equal(le16s(h + 40 + 2 * k), dim[k]);
    assert_int_equal(le16s(h + 70), mask ? 2 : 16);   /* DT_UINT8 / DT_FLOAT32 */
    assert_int_equal(le16s(h + 72), mask ? 8 : 32);
    const float pixdim[4] = {1.0f, 0.5f, 0.25f, 2.5f}; /* qfac, then the final z step */
    for (int k = 0; k < 4; ++k) assert_true(le_f32(h + 76 + 4 * k) == pixdim[k]);
    assert_true(le_f32(h + 108) == 352.0f);            /* vox_offset */
    assert_true(le_f32(h + 112) == 1.0f && le_f32(h + 116) == 0.0f); /* scl_slope, inter */
    assert_true(le_f32(h + 124) == (mask ? 255.0f : 0.0f) && le_f32(h + 128) == 0.0f);
    assert_int_equal(h[123], 0);                       /* xyzt_units: unknown */
    assert_int_equal(le16s(h + 252), 1);               /* qform_code */
    assert_int_equal(le16s(h + 254), 1);               /* sform_code */
    const float quat[6] = {0.0f, 0.0f, 1.0f, -1.5f, 0.0f, 3.25f}; /* b c d, offsets */
    for (int k = 0; k < 6; ++k) assert_true(le_f32(h + 256 + 4 * k) == quat[k]);
    assert_false(h[272 + 3] & 0x80);                   /* qoffset_y is +0, not -0 */
    const float srow[12] = {-0.5f, 0, 0, -1.5f, 0, -0.25f, 0, 0, 0, 0, 2.5f, 3.25f};
    for (int k = 0; k < 12; ++k)
      if (le_f32(h + 280 + 4 * k) != srow[k])
        fail_msg("srow element %d: %g, want %g", k, (double)le_f32(h + 280 + 4 * k),
                 (double)srow[k]);
    assert_memory_equal(h + 344, "n+1", 4);
    for (int k = 348; k < 352; ++k) assert_int_equal(h[k], 0); /* no extensions */
    assert_non_null(memchr(h + 148, '\0', 80));        /* descrip is terminated */
    assert_memory_equal(h + LSM_NIFTI_HEADER_BYTES, raw, bytes);
    if (mask) {
      assert_int_equal(h[LSM_NIFTI_HEADER_BYTES + 12 + 5], 255); /* phi = 0: inside */
      for (size_t k = 0; k < samples; ++k)
        assert_true(h[LSM_NIFTI_HEADER_BYTES + k] == 0 || h[LSM_NIFTI_HEADER_BYTES + k] == 255);
    }
    free(h);
    free(raw);
  }
}

/* NIfTI-1 sizes are 16-bit: wider slices are refused at open, a 32768th slice
 * when it comes; the header builder refuses them too. */
static void test_nifti_limits(void **state) {
  tmp_fixture *f = *state;
  lsm_volume_writer *w = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_volume_writer_open(f->dir, LSM_FORMAT_NII, LSM_VALUES_SDF,
                                          LSM_NIFTI_DIM_MAX + 1, 1, 1, 1, 1, 0, 0, 0, &w, &err),
                   LSM_ERR_LIMIT);
  assert_null(w);
  assert_msg_contains(err, "32767");
  lsm_err_clear(&err);
  assert_int_equal(lsm_volume_writer_open(f->dir, LSM_FORMAT_NII, LSM_VALUES_MASK, 1, 1, 1, 1,
                                          1, 0, 0, 0, &w, &err),
                   LSM_OK);
  const float one = -1.0f;
  lsm_status st = LSM_OK;
  for (int k = 0; st == LSM_OK && k < LSM_NIFTI_DIM_MAX; ++k)
    st = lsm_volume_writer_write_slice(w, &one, k, &err);
  assert_int_equal(st, LSM_OK);
  assert_int_equal(lsm_volume_writer_write_slice(w, &one, 1e6, &err), LSM_ERR_LIMIT);
  assert_msg_contains(err, "volume.nii");
  assert_int_equal(lsm_volume_writer_finish(&w, 1.0, LSM_NIFTI_DIM_MAX + 1, &err), LSM_ERR_IO);
  assert_null(w);

  unsigned char h[LSM_NIFTI_HEADER_BYTES];
  lsm_volume_info info = {2, 2, LSM_NIFTI_DIM_MAX, 1, 1, 1, 0, 0, 0, LSM_VALUES_SDF};
  assert_int_equal(lsm_nifti_header(h, sizeof h, &info), LSM_NIFTI_HEADER_BYTES);
  assert_int_equal(lsm_nifti_header(h, sizeof h - 1, &info), 0);
  info.nz = LSM_NIFTI_DIM_MAX + 1;
  assert_int_equal(lsm_nifti_header(h, sizeof h, &info), 0);
  info.nz = 1;
  info.ny = LSM_NIFTI_DIM_MAX + 1;
  assert_int_equal(lsm_nifti_header(h, sizeof h, &info), 0);

  unsigned formats = 0;
  lsm_err_clear(&err);
  assert_int_equal(lsm_format_list_parse("nii,nrrd", &formats, &err), LSM_OK);
  assert_int_equal(formats, LSM_FORMAT_NII | LSM_FORMAT_NRRD);
  assert_string_equal(lsm_format_name(LSM_FORMAT_NII), "nii");
  const char *names[8];
  assert_int_equal(lsm_volume_file_names(LSM_FORMAT_ALL, names, 8), 8);
  assert_int_equal(lsm_volume_file_names(LSM_FORMAT_NII, names, 8), 1);
  assert_string_equal(names[0], "volume.nii");
  lsm_err_clear(&err);
  assert_int_equal(lsm_format_list_parse("nifti", &formats, &err), LSM_ERR_USAGE);
  assert_msg_contains(err, "nii");
}

/* ---- gzip with a rewritable head (volume.nii.gz) ------------------------------------- */

/* Inflates a whole gzip file with zlib (any number of members); returns the
 * bytes (and *len), or NULL when zlib finds the stream broken. */
static uint8_t *gunzip_bytes(const uint8_t *gz, size_t gz_len, size_t *len) {
  size_t cap = 1 << 16, n = 0;
  uint8_t *out = malloc(cap);
  assert_non_null(out);
  z_stream z;
  memset(&z, 0, sizeof z);
  assert_int_equal(inflateInit2(&z, 16 + MAX_WBITS), Z_OK);
  z.next_in = (Bytef *)(uintptr_t)gz;
  z.avail_in = (uInt)gz_len;
  int r = Z_OK;
  while (r != Z_STREAM_END) {
    if (n == cap) {
      cap *= 2;
      out = realloc(out, cap);
      assert_non_null(out);
    }
    z.next_out = out + n;
    z.avail_out = (uInt)(cap - n);
    r = inflate(&z, Z_NO_FLUSH);
    n = cap - z.avail_out;
    if (r != Z_OK && r != Z_STREAM_END) break;
  }
  const int whole = r == Z_STREAM_END && z.avail_in == 0; /* one member, nothing after */
  inflateEnd(&z);
  if (!whole) {
    free(out);
    return NULL;
  }
  *len = n;
  return out;
}

/* The head written at open is replaced at finish; the file is one plain gzip
 * member that zlib inflates to the new head and the data, CRC and length
 * checked by zlib; the head lies uncompressed at LSM_GZIP_HEAD_OFFSET. */
static void test_gzip_rewritable_head(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  join(path, sizeof path, f->dir, "x.gz");
  enum { HEAD = 352, DATA = 300000 };
  unsigned char head0[HEAD], head1[HEAD];
  uint8_t *data = malloc(DATA);
  assert_non_null(data);
  uint32_t seed = 12345u;
  for (int k = 0; k < HEAD; ++k) {
    head0[k] = (unsigned char)k;
    head1[k] = (unsigned char)(255 - k);
  }
  for (int k = 0; k < DATA; ++k) { /* half noise (incompressible), half runs */
    seed = seed * 1664525u + 1013904223u;
    data[k] = k < DATA / 2 ? (uint8_t)(seed >> 24) : (uint8_t)(k / 1000);
  }
  for (int level = 0; level <= 9; level += 9) {
    lsm_gzip_writer *g = NULL;
    lsm_err err;
    lsm_err_clear(&err);
    assert_int_equal(lsm_gzip_writer_open(path, NULL, 0, head0, HEAD, level, &g, &err), LSM_OK);
    size_t at = 0, step = 1;
    while (at < DATA) { /* uneven pieces: 1, 3, 9, ... bytes */
      size_t piece = step < DATA - at ? step : DATA - at;
      assert_int_equal(lsm_gzip_writer_write(g, data + at, piece, &err), LSM_OK);
      at += piece;
      step *= 3;
    }
    assert_int_equal(lsm_gzip_writer_finish(&g, NULL, head1, &err), LSM_OK);
    assert_null(g);
    size_t gz_len = 0, len = 0;
    uint8_t *gz = read_bytes(path, &gz_len);
    assert_memory_equal(gz, "\x1f\x8b\x08", 3);
    assert_memory_equal(gz + LSM_GZIP_HEAD_OFFSET, head1, HEAD);
    uint8_t *plain = gunzip_bytes(gz, gz_len, &len);
    if (!plain) fail_msg("zlib cannot inflate the file written at level %d", level);
    assert_int_equal(len, HEAD + DATA);
    assert_memory_equal(plain, head1, HEAD);
    assert_memory_equal(plain + HEAD, data, DATA);
    assert_int_equal(le32(gz + gz_len - 4), HEAD + DATA); /* ISIZE */
    if (level == 9) assert_true(gz_len < HEAD + DATA * 3 / 4); /* the runs compress */
    free(gz);
    free(plain);
  }
  free(data);

  /* no head at all, no data: still a valid (empty) gzip file */
  lsm_gzip_writer *g = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_gzip_writer_open(path, NULL, 0, NULL, 0, 1, &g, &err), LSM_OK);
  assert_int_equal(lsm_gzip_writer_finish(&g, NULL, NULL, &err), LSM_OK);
  size_t gz_len = 0, len = 1;
  uint8_t *gz = read_bytes(path, &gz_len);
  uint8_t *plain = gunzip_bytes(gz, gz_len, &len);
  assert_non_null(plain);
  assert_int_equal(len, 0);
  free(gz);
  free(plain);

  /* a plain prefix before the member (volume.nrrd's header with encoding gzip), rewritten at
   * the end: the file is the new prefix, then a gzip member of the data alone */
  {
    const unsigned char pre0[] = "PROVISIONAL HEADER\n\n", pre1[] = "the final header..\n\n";
    const size_t pre = sizeof pre0 - 1;
    assert_int_equal(sizeof pre1 - 1, pre);
    const uint8_t bytes[5] = {1, 2, 3, 4, 5};
    assert_int_equal(lsm_gzip_writer_open(path, pre0, pre, NULL, 0, 1, &g, &err), LSM_OK);
    assert_int_equal(lsm_gzip_writer_write(g, bytes, sizeof bytes, &err), LSM_OK);
    assert_int_equal(lsm_gzip_writer_finish(&g, pre1, NULL, &err), LSM_OK);
    gz = read_bytes(path, &gz_len);
    assert_true(gz_len > pre);
    assert_memory_equal(gz, pre1, pre);
    plain = gunzip_bytes(gz + pre, gz_len - pre, &len);
    assert_non_null(plain);
    assert_int_equal(len, sizeof bytes);
    assert_memory_equal(plain, bytes, sizeof bytes);
    free(gz);
    free(plain);
    /* a prefix promised but not given at the end is an error */
    assert_int_equal(lsm_gzip_writer_open(path, pre0, pre, NULL, 0, 1, &g, &err), LSM_OK);
    lsm_err_clear(&err);
    assert_int_equal(lsm_gzip_writer_finish(&g, NULL, NULL, &err), LSM_ERR_INTERNAL);
    assert_null(g);
  }

  /* errors are values, with the file named */
  lsm_err_clear(&err);
  join(path, sizeof path, f->dir, "missing/x.gz");
  assert_int_equal(lsm_gzip_writer_open(path, NULL, 0, head0, HEAD, 1, &g, &err), LSM_ERR_IO);
  assert_null(g);
  assert_msg_contains(err, "missing/x.gz");
  assert_int_equal(lsm_gzip_writer_open(path, NULL, 0, head0, 70000, 1, &g, &err), LSM_ERR_INTERNAL);
  assert_int_equal(lsm_gzip_writer_open(path, NULL, 0, head0, HEAD, 10, &g, &err), LSM_ERR_INTERNAL);
  lsm_gzip_writer_abort(&g);
  lsm_gzip_writer_abort(NULL);
}

/* volume.nii.gz inflates to volume.nii's bytes, header included (slice count
 * and z step fixed at the end), for float and mask volumes. */
static void test_nifti_gz_is_nii(void **state) {
  tmp_fixture *f = *state;
  for (int mask = 0; mask < 2; ++mask) {
    lsm_volume_writer *w = NULL;
    lsm_err err;
    lsm_err_clear(&err);
    enum { NX = 37, NY = 29, NZ = 11 };
    float *phi = malloc(sizeof(float) * NX * NY);
    assert_non_null(phi);
    assert_int_equal(lsm_volume_writer_open(f->dir, LSM_FORMAT_NII | LSM_FORMAT_NII_GZ,
                                            mask ? LSM_VALUES_MASK : LSM_VALUES_SDF, NX, NY, 0.5,
                                            0.5, 7.0, 0.0, 0.0, 2.0, &w, &err),
                     LSM_OK);
    for (int z = 0; z < NZ; ++z) {
      for (int k = 0; k < NX * NY; ++k) phi[k] = (float)((k % NX) - 18) * 0.3f + (float)z;
      assert_int_equal(lsm_volume_writer_write_slice(w, phi, 2.0 + 1.5 * z, &err), LSM_OK);
    }
    free(phi);
    if (lsm_volume_writer_finish(&w, 1.5, NZ, &err) != LSM_OK) fail_msg("%s", err.msg);
    char path[256];
    size_t nii_len = 0, gz_len = 0, len = 0;
    join(path, sizeof path, f->dir, "volume.nii");
    uint8_t *nii = read_bytes(path, &nii_len);
    join(path, sizeof path, f->dir, "volume.nii.gz");
    uint8_t *gz = read_bytes(path, &gz_len);
    uint8_t *plain = gunzip_bytes(gz, gz_len, &len);
    assert_non_null(plain);
    assert_int_equal(nii_len, LSM_NIFTI_HEADER_BYTES + (size_t)NX * NY * NZ * (mask ? 1 : 4));
    assert_int_equal(len, nii_len);
    assert_memory_equal(plain, nii, nii_len);
    assert_int_equal(le16s(plain + 46), NZ);
    free(nii);
    free(gz);
    free(plain);
  }
  unsigned formats = 0;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_format_list_parse("nii.gz,nii", &formats, &err), LSM_OK);
  assert_int_equal(formats, LSM_FORMAT_NII | LSM_FORMAT_NII_GZ);
  assert_string_equal(lsm_format_name(LSM_FORMAT_NII_GZ), "nii.gz");
  const char *names[8];
  assert_int_equal(lsm_volume_file_names(LSM_FORMAT_NII_GZ, names, 8), 1);
  assert_string_equal(names[0], "volume.nii.gz");
  /* the 16-bit limit names the file written */
  lsm_volume_writer *w = NULL;
  assert_int_equal(lsm_volume_writer_open(f->dir, LSM_FORMAT_NII_GZ, LSM_VALUES_SDF,
                                          LSM_NIFTI_DIM_MAX + 1, 1, 1, 1, 1, 0, 0, 0, &w, &err),
                   LSM_ERR_LIMIT);
  assert_msg_contains(err, "volume.nii.gz");
}

/* lsm_json_find_number: a member path through any valid formatting; invalid
 * JSON is refused wherever it breaks, not only on the way to the member. */
static void test_json_find_number(void **state) {
  (void)state;
  static const char *const path[] = {"input", "slices"};
  double v = 0.0;
  size_t at = 0;
  assert_int_equal(lsm_json_find_number("{\"input\": {\"folder\": \"a\", \"slices\": 15}}", path, 2, &v, &at), 1);
  assert_true(v == 15.0);
  /* indented, reordered, with arrays, escapes and literals around it */
  const char *pretty =
      "{\n  \"pairs\": [ {\"slices\": 7}, [1, 2.5e-3, -0, true, false, null] ],\n"
      "  \"name\": \"a \\\"quoted\\\" \\u00e9 \\\\ name\",\n"
      "  \"input\": {\n    \"slices\": 3E+1\n  }\n}\n";
  assert_int_equal(lsm_json_find_number(pretty, path, 2, &v, &at), 1);
  assert_true(v == 30.0);
  /* a later duplicate wins; the key must match whole and at its level */
  assert_int_equal(lsm_json_find_number("{\"input\":{\"slices\":1,\"slices\":2}}", path, 2, &v, &at), 1);
  assert_true(v == 2.0);
  assert_int_equal(lsm_json_find_number("{\"input\":{\"slice\":1},\"slices\":4}", path, 2, &v, &at), 0);
  assert_int_equal(lsm_json_find_number("{\"x\":{\"input\":{\"slices\":4}}}", path, 2, &v, &at), 0);
  assert_int_equal(lsm_json_find_number("{\"input\":{\"slices\":\"4\"}}", path, 2, &v, &at), 0);
  assert_int_equal(lsm_json_find_number("[1, {\"input\":{\"slices\":4}}]", path, 2, &v, &at), 0);
  /* invalid: where it breaks */
  static const struct { const char *text; size_t at; } bad[] = {
      {"{", 1},
      {"{\"input\": {\"slices\": 3}", 23},
      {"{\"input\": {\"slices\": 3},}", 24},
      {"{\"input\": {\"slices\": 03}}", 22},
      {"{\"input\": {\"slices\": 3.}}", 23},
      {"{\"input\": {\"slices\": 3}} x", 25},
      {"{\"a\": tru}", 6},
      {"{\"a\": \"\\x\"}", 7},
      {"{\"a\": \"\\u12g4\"}", 7},
      {"{\"a\": \"line\nbreak\"}", 11},
      {"", 0},
  };
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    at = 999;
    assert_int_equal(lsm_json_find_number(bad[k].text, path, 2, &v, &at), -1);
    assert_int_equal(at, bad[k].at);
  }
  /* nesting: 256 levels read, 300 refused (no stack overflow on deeper) */
  char deep[1000];
  for (int depth = 256; depth <= 300; depth += 44) {
    size_t n = 0;
    for (int k = 0; k < depth; ++k) deep[n++] = '[';
    for (int k = 0; k < depth; ++k) deep[n++] = ']';
    deep[n] = '\0';
    assert_int_equal(lsm_json_find_number(deep, path, 2, &v, &at), depth <= 256 ? 0 : -1);
  }
}

/* lsm_json_find_numbers: an array of numbers by its member path, in any
 * formatting; its length without a buffer; only arrays of numbers count. */
static void test_json_find_numbers(void **state) {
  (void)state;
  static const char *const path[] = {"input", "heights"};
  double v[4] = {0.0, 0.0, 0.0, 0.0};
  size_t n = 99, at = 0;
  const char *run = "{\"input\": {\"files\": [\"1.png\", \"9.png\"], \"heights\":\n"
                    "  [ 1 ,9,\t-2.5e1 ]}, \"options\": {\"heights\": [7]}}";
  assert_int_equal(lsm_json_find_numbers(run, path, 2, NULL, 0, &n, &at), 1);
  assert_int_equal(n, 3);
  assert_int_equal(lsm_json_find_numbers(run, path, 2, v, 4, &n, &at), 1);
  assert_int_equal(n, 3);
  assert_true(v[0] == 1.0 && v[1] == 9.0 && v[2] == -25.0 && v[3] == 0.0);
  /* a buffer shorter than the array: its first elements, and the length */
  v[0] = v[1] = 0.0;
  assert_int_equal(lsm_json_find_numbers(run, path, 2, v, 1, &n, &at), 1);
  assert_int_equal(n, 3);
  assert_true(v[0] == 1.0 && v[1] == 0.0);
  /* empty; a later duplicate wins, also when it is not an array of numbers */
  assert_int_equal(lsm_json_find_numbers("{\"input\":{\"heights\":[ ]}}", path, 2, v, 4, &n, &at), 1);
  assert_int_equal(n, 0);
  assert_int_equal(lsm_json_find_numbers("{\"input\":{\"heights\":[1],\"heights\":[2,3]}}", path, 2,
                                         v, 4, &n, &at), 1);
  assert_true(n == 2 && v[0] == 2.0 && v[1] == 3.0);
  assert_int_equal(lsm_json_find_numbers("{\"input\":{\"heights\":[1],\"heights\":4}}", path, 2, v,
                                         4, &n, &at), 0);
  assert_int_equal(n, 0);
  /* not an array of numbers, or not there */
  static const char *const none[] = {
      "{\"input\":{\"heights\":[1,\"2\"]}}", "{\"input\":{\"heights\":[1,[2]]}}",
      "{\"input\":{\"heights\":[null]}}",   "{\"input\":{\"heights\":{\"a\":1}}}",
      "{\"input\":{\"height\":[1]}}",      "{\"heights\":[1]}",
      "[{\"input\":{\"heights\":[1]}}]",
  };
  for (size_t k = 0; k < sizeof none / sizeof none[0]; ++k) {
    n = 99;
    assert_int_equal(lsm_json_find_numbers(none[k], path, 2, v, 4, &n, &at), 0);
    assert_int_equal(n, 0);
  }
  /* invalid JSON, wherever it breaks */
  at = 0;
  assert_int_equal(lsm_json_find_numbers("{\"input\":{\"heights\":[1,]}}", path, 2, v, 4, &n, &at), -1);
  assert_int_equal(at, 23);
}

/* lsm_json_find_strings and lsm_json_unescape: run.json's input.files read
 * back as the names lsm_json_string wrote, whatever the bytes. */
static void test_json_find_strings(void **state) {
  (void)state;
  static const char *const path[] = {"input", "files"};
  const char *raw[4] = {NULL, NULL, NULL, NULL};
  size_t len[4] = {0, 0, 0, 0}, n = 99, at = 0;
  const char *run = "{\"input\": {\"heights\": [1, 9], \"files\":\n"
                    "  [ \"001.png\" ,\"a\\\"b\\\\c.png\",\t\"\" ]}, \"options\": {\"files\": [\"x\"]}}";
  assert_int_equal(lsm_json_find_strings(run, path, 2, NULL, NULL, 0, &n, &at), 1);
  assert_int_equal(n, 3);
  assert_int_equal(lsm_json_find_strings(run, path, 2, raw, len, 4, &n, &at), 1);
  assert_int_equal(n, 3);
  assert_true(len[0] == 7 && memcmp(raw[0], "001.png", 7) == 0);
  assert_true(len[1] == 11 && memcmp(raw[1], "a\\\"b\\\\c.png", 11) == 0);
  assert_true(len[2] == 0 && raw[3] == NULL);
  char out[32];
  assert_int_equal(lsm_json_unescape(raw[1], len[1], out), 9);
  assert_string_equal(out, "a\"b\\c.png");
  /* a buffer shorter than the array: its first elements, and the length */
  raw[0] = raw[1] = NULL;
  assert_int_equal(lsm_json_find_strings(run, path, 2, raw, len, 1, &n, &at), 1);
  assert_true(n == 3 && raw[0] && raw[1] == NULL);
  /* not an array of strings, or not there; invalid JSON */
  static const char *const none[] = {"{\"input\":{\"files\":[\"a\",1]}}",
                                     "{\"input\":{\"files\":\"a\"}}", "{\"files\":[\"a\"]}"};
  for (size_t k = 0; k < sizeof none / sizeof none[0]; ++k) {
    n = 99;
    assert_int_equal(lsm_json_find_strings(none[k], path, 2, raw, len, 4, &n, &at), 0);
    assert_int_equal(n, 0);
  }
  assert_int_equal(lsm_json_find_strings("{\"input\":{\"files\":[\"a]}}", path, 2, raw, len, 4, &n, &at),
                   -1);

  /* a name with bytes that are not UTF-8 and a control byte comes back as it
   * was written; other escapes as JSON means them */
  const char name[] = "s\xe9\x01\xc3\xa9/\xff.png";
  char *text = NULL;
  size_t size = 0;
  FILE *f = open_memstream(&text, &size);
  assert_non_null(f);
  lsm_json_string(f, name);
  assert_int_equal(fclose(f), 0);
  assert_true(size >= 2 && text[0] == '"' && text[size - 1] == '"');
  assert_int_equal(lsm_json_unescape(text + 1, size - 2, out), strlen(name));
  assert_string_equal(out, name);
  free(text);
  static const struct {
    const char *raw, *want;
  } cases[] = {{"\\u20ac \\n\\t\\/", "\xe2\x82\xac \n\t/"},
               {"\\ud83d\\ude00", "\xf0\x9f\x98\x80"}};
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
    assert_int_equal(lsm_json_unescape(cases[k].raw, strlen(cases[k].raw), out), strlen(cases[k].want));
    assert_string_equal(out, cases[k].want);
  }
  static const char *const bad[] = {"\\u0000", "\\ud83d", "\\ude00", "\\ud83dx", "\\q", "\\", "\\u12"};
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k)
    assert_true(lsm_json_unescape(bad[k], strlen(bad[k]), out) == (size_t)-1);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_natural_cmp),
      cmocka_unit_test(test_name_number),
      cmocka_unit_test(test_json_find_number),
      cmocka_unit_test(test_json_find_numbers),
      cmocka_unit_test(test_json_find_strings),
      cmocka_unit_test(test_heights_good),
      cmocka_unit_test(test_heights_bad),
      cmocka_unit_test_setup_teardown(test_heights_read, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_roundtrip_mask, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_roundtrip_gray_rgb, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_gray1, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_gray2_4, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_gray8, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_gray16, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_gray_trns, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_gray_alpha, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_rgb, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_rgba, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_palette, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_interlaced, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_invert, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_max_pixels, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_not_png, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_truncated, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_corrupt, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_write_errors, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_tiff_layouts, setup_tmp, teardown_tmp),
      cmocka_unit_test(test_tiff_names),
      cmocka_unit_test_setup_teardown(test_dir_list, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_dir_errors, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_make_dir, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_read_file, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_nrrd_roundtrip, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_nrrd_fixed_header, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_nrrd_errors, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_nifti_header_fields, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_nifti_limits, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_gzip_rewritable_head, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_nifti_gz_is_nii, setup_tmp, teardown_tmp),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
