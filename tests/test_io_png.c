/* Tests of the io room's PNG path: masks and gray/RGB images round-tripped
 * through lsmorph's writers; the reader on every colour type and bit depth
 * (1/2/4/8/16-bit gray, tRNS, gray+alpha, RGB, RGBA, palettes, Adam7
 * interlacing, --invert) on PNGs written with libpng directly; the pixel limit,
 * files that are not PNGs, truncated and corrupted files (bad CRCs, broken
 * zlib data, single flipped bytes), and write errors on a full device. */
#include "tests/lsm_test_io.h"

#include <png.h>
#include <sys/stat.h>
#include <unistd.h>

#include "io/lsm_io.h"

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

/* The count of label values composites an alpha channel over black, as the
 * slice readers do, not over whatever its buffer held (libpng's simplified
 * API composites over the buffer when given no background): a white square,
 * opaque on a transparent white page, is one level however the heap was used. */
static void test_png_levels_alpha(void **state) {
  tmp_fixture *f = *state;
  enum { N = 32 };
  static unsigned s[N * N * 2];
  for (int y = 0; y < N; ++y)
    for (int x = 0; x < N; ++x) {
      s[2 * (y * N + x)] = 255;
      s[2 * (y * N + x) + 1] = x >= 8 && x < 20 && y >= 8 && y < 20 ? 255 : 0;
    }
  test_png t = {.width = N, .height = N, .depth = 8, .color_type = PNG_COLOR_TYPE_GRAY_ALPHA, .samples = s};
  char path[256];
  join(path, sizeof path, f->dir, "levels-ga8.png");
  write_test_png(path, &t);
  for (int k = 0; k < 3; ++k) {
    unsigned char *junk[8]; /* freed blocks of the size the count allocates */
    for (int j = 0; j < 8; ++j) {
      junk[j] = malloc(N * N);
      assert_non_null(junk[j]);
      memset(junk[j], 0xa5, N * N);
    }
    for (int j = 0; j < 8; ++j) free(junk[j]);
    unsigned levels = 99;
    assert_int_equal(lsm_png_count_levels(path, &levels), LSM_OK);
    assert_int_equal(levels, 1);
  }
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

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_png_roundtrip_mask, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_roundtrip_gray_rgb, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_gray1, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_gray2_4, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_gray8, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_gray16, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_gray_trns, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_gray_alpha, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_png_levels_alpha, setup_tmp, teardown_tmp),
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
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
