/* io_png: PNG slices in (any bit depth / colour type) and masks out, via libpng.
 *
 * libpng reports errors by calling an error callback that must not return.
 * Ours records the message in a per-call context (png_io, passed as libpng's
 * error pointer; no global state) and longjmps back to the setjmp inside a
 * small "guarded" function.  Every resource lives in a struct owned by the
 * caller of that function, so nothing local to the function that called setjmp
 * is needed after the jump (no clobbering issues); the caller then releases
 * everything and turns the recorded message into an lsm_status.
 */
#include "io/lsm_io.h"

#include <errno.h>
#include <inttypes.h>
#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <zlib.h>

#define PNG_SIG_BYTES 8
/* libpng's own default limit is 1,000,000 x 1,000,000; opts->max_pixels is
 * the policy here, so allow every size the format allows. */
#define PNG_DIM_MAX 0x7fffffffu

/* Per-call libpng context: where to jump, what went wrong. */
typedef struct png_io {
  jmp_buf jmp;
  FILE *fp;
  lsm_status status; /* status to report when the guarded part fails */
  int msg_set;       /* msg already holds the final text */
  char msg[320];
} png_io;

static void png_io_init(png_io *io) {
  io->fp = NULL;
  io->status = LSM_ERR_INPUT;
  io->msg_set = 0;
  io->msg[0] = '\0';
}

/* Records "<prefix><text>" unless a message is already recorded. */
static void png_io_set(png_io *io, lsm_status status, const char *prefix, const char *text) {
  if (io->msg_set) return;
  io->status = status;
  snprintf(io->msg, sizeof io->msg, "%s%s", prefix, text);
  io->msg_set = 1;
}

static void on_png_error(png_structp png, png_const_charp msg) {
  png_io *io = png_get_error_ptr(png);
  png_io_set(io, io->status, "corrupt PNG: ", msg ? msg : "unknown libpng error");
  longjmp(io->jmp, 1);
}

static void on_png_warning(png_structp png, png_const_charp msg) {
  (void)png; /* warnings (e.g. a bad ancillary chunk) are not fatal; stay quiet */
  (void)msg;
}

static void on_png_read(png_structp png, png_bytep data, size_t length) {
  png_io *io = png_get_io_ptr(png);
  if (fread(data, 1, length, io->fp) != length) {
    if (ferror(io->fp))
      png_io_set(io, LSM_ERR_IO, "read error: ", strerror(errno));
    else
      png_io_set(io, LSM_ERR_INPUT, "", "truncated PNG file (unexpected end of data)");
    png_error(png, io->msg);
  }
}

static void on_png_write(png_structp png, png_bytep data, size_t length) {
  png_io *io = png_get_io_ptr(png);
  if (fwrite(data, 1, length, io->fp) != length) {
    png_io_set(io, LSM_ERR_IO, "write failed: ", strerror(errno));
    png_error(png, io->msg);
  }
}

static void on_png_flush(png_structp png) {
  png_io *io = png_get_io_ptr(png);
  if (fflush(io->fp) != 0) {
    png_io_set(io, LSM_ERR_IO, "write failed: ", strerror(errno));
    png_error(png, io->msg);
  }
}

/* ---- reading --------------------------------------------------------------- */

typedef struct png_reader {
  png_io io;
  png_structp png;
  png_infop info;
  const lsm_image_read_opts *opts; /* NULL: defaults */
  int header_only;
  png_uint_32 width, height;
  png_bytep buffer; /* one row, or the whole image when interlaced */
  png_bytepp rows;  /* row pointers into buffer (interlaced only) */
  int palette;      /* 1: rows hold palette indices, mapped through palette_mask */
  int num_palette;
  uint8_t palette_mask[256]; /* 0/1 of each palette entry (the rule of lsm_mask_row_from_samples) */
  lsm_mask mask;
} png_reader;

static uint32_t sample_at(png_const_bytep p, int wide) {
  return wide ? ((uint32_t)p[0] << 8) | p[1] : p[0];
}

/* One row of 8- or 16-bit (big-endian) G, GA, RGB or RGBA samples to 0/1.  Foreground when
 * luminance*alpha/maxval >= maxval/2, 50 % of full scale (or > 0 with
 * nonzero), computed exactly in integers with Rec. 709 weights scaled by
 * 10000.  (For plain gray samples that is 128 of 255; an RGB or composited
 * luminance of 127.9 is past it too.) */
void lsm_mask_row_from_samples(const uint8_t *row, uint32_t width, int channels, int depth,
                               int invert, int nonzero, uint8_t *out) {
  const int wide = depth == 16;
  const size_t step = (size_t)(wide ? 2 : 1);
  const uint64_t maxval = wide ? 65535u : 255u;
  const uint64_t limit = 10000u * maxval * maxval;
  const int has_alpha = channels == 2 || channels == 4;
  for (uint32_t x = 0; x < width; ++x) {
    const uint8_t *p = row + (size_t)x * (size_t)channels * step;
    uint64_t lum, alpha = maxval;
    if (channels <= 2) {
      lum = 10000u * (uint64_t)sample_at(p, wide);
    } else {
      lum = 2126u * (uint64_t)sample_at(p, wide) + 7152u * (uint64_t)sample_at(p + step, wide) +
            722u * (uint64_t)sample_at(p + 2 * step, wide);
    }
    if (has_alpha) alpha = sample_at(p + (size_t)(channels - 1) * step, wide);
    int bright = nonzero ? lum * alpha > 0u : lum * alpha * 2u >= limit;
    out[x] = (uint8_t)(invert ? !bright : bright);
  }
}

/* A palette image's row: each index through its entry's 0/1.  An index past
 * the palette is an error (the PNG specification's; libpng would read it as
 * black).  Returns 1, or 0 with the error set. */
static int convert_index_row(png_reader *r, png_const_bytep row, png_uint_32 y, uint8_t *out) {
  for (png_uint_32 x = 0; x < r->width; ++x) {
    if (row[x] >= r->num_palette) {
      char text[160];
      snprintf(text, sizeof text,
               "pixel (%" PRIu32 ", %" PRIu32 ") has palette index %d, but the palette has %d "
               "entr%s",
               (uint32_t)x, (uint32_t)y, row[x], r->num_palette, r->num_palette == 1 ? "y" : "ies");
      png_io_set(&r->io, LSM_ERR_INPUT, "corrupt PNG: ", text);
      return 0;
    }
    out[x] = r->palette_mask[row[x]];
  }
  return 1;
}

/* Each palette entry, with its tRNS alpha, to 0/1 by lsm_mask_row_from_samples's rule. */
static void palette_to_mask(png_reader *r, int invert, int nonzero) {
  png_colorp palette = NULL;
  png_bytep trans = NULL;
  int num_trans = 0;
  r->num_palette = 0;
  if (!png_get_PLTE(r->png, r->info, &palette, &r->num_palette)) r->num_palette = 0;
  if (!png_get_tRNS(r->png, r->info, &trans, &num_trans, NULL)) num_trans = 0;
  for (int k = 0; k < r->num_palette && k < 256; ++k) {
    const png_byte rgba[4] = {palette[k].red, palette[k].green, palette[k].blue,
                              k < num_trans ? trans[k] : 255};
    lsm_mask_row_from_samples(rgba, 1, 4, 8, invert, nonzero, &r->palette_mask[k]);
  }
}

/* The part of the read that libpng may longjmp out of. Returns 1 on success. */
static int png_read_guarded(png_reader *r) {
  if (setjmp(r->io.jmp)) return 0;

  png_set_read_fn(r->png, &r->io, on_png_read);
  png_set_sig_bytes(r->png, PNG_SIG_BYTES);
  png_set_user_limits(r->png, PNG_DIM_MAX, PNG_DIM_MAX);
  /* text chunks mean nothing to a mask: skip them unread (libpng allocated
   * what one claimed before reading it, 2 GB for a 44-byte file), and cap
   * what any other ancillary chunk may allocate */
  static const png_byte text_chunks[] = "tEXt\0zTXt\0iTXt";
  png_set_keep_unknown_chunks(r->png, PNG_HANDLE_CHUNK_NEVER, text_chunks, 3);
  png_set_chunk_malloc_max(r->png, (png_alloc_size_t)16 << 20);
  png_read_info(r->png, r->info);
  r->width = png_get_image_width(r->png, r->info);
  r->height = png_get_image_height(r->png, r->info);
  if (r->header_only) return 1;

  size_t pixels;
  uint64_t max_pixels = r->opts ? r->opts->max_pixels : 0;
  if (!lsm_size_mul(r->width, r->height, &pixels) ||
      (max_pixels != 0 && (uint64_t)pixels > max_pixels)) {
    char text[160];
    snprintf(text, sizeof text, "image is %" PRIu32 "x%" PRIu32 " = %" PRIu64
             " pixels, more than the limit of %" PRIu64,
             (uint32_t)r->width, (uint32_t)r->height,
             (uint64_t)r->width * (uint64_t)r->height, max_pixels);
    png_io_set(&r->io, LSM_ERR_LIMIT, "", text);
    return 0;
  }

  int color_type = png_get_color_type(r->png, r->info);
  int depth = png_get_bit_depth(r->png, r->info);
  int invert = r->opts ? r->opts->invert : 0;
  int nonzero = r->opts ? r->opts->nonzero : 0;
  r->palette = color_type == PNG_COLOR_TYPE_PALETTE;
  if (r->palette) {
    /* indices, one byte each, mapped here so that an index past the palette
     * is caught */
    palette_to_mask(r, invert, nonzero);
    if (depth < 8) png_set_packing(r->png);
  } else {
    if (color_type == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(r->png);
    if (png_get_valid(r->png, r->info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(r->png);
  }
  /* 16-bit samples stay big-endian (network order) and are decoded by hand. */
  int passes = png_set_interlace_handling(r->png);
  png_read_update_info(r->png, r->info);

  int channels = png_get_channels(r->png, r->info);
  depth = png_get_bit_depth(r->png, r->info);
  size_t rowbytes = png_get_rowbytes(r->png, r->info);
  if ((depth != 8 && depth != 16) || channels < 1 || channels > 4 ||
      rowbytes / (size_t)channels / (size_t)(depth / 8) < r->width ||
      (r->palette && (depth != 8 || channels != 1))) {
    png_io_set(&r->io, LSM_ERR_INTERNAL, "", "unexpected pixel layout after libpng transforms");
    return 0;
  }

  r->mask.pixels = malloc(pixels ? pixels : 1);
  if (!r->mask.pixels) {
    png_io_set(&r->io, LSM_ERR_NOMEM, "", "out of memory for the mask");
    return 0;
  }
  r->mask.width = (int)r->width;
  r->mask.height = (int)r->height;

  if (passes <= 1) {
    r->buffer = malloc(rowbytes);
    if (!r->buffer) {
      png_io_set(&r->io, LSM_ERR_NOMEM, "", "out of memory for a row");
      return 0;
    }
    for (png_uint_32 y = 0; y < r->height; ++y) {
      png_read_row(r->png, r->buffer, NULL);
      uint8_t *out = r->mask.pixels + (size_t)y * r->width;
      if (r->palette) {
        if (!convert_index_row(r, r->buffer, y, out)) return 0;
      } else {
        lsm_mask_row_from_samples(r->buffer, r->width, channels, depth, invert, nonzero, out);
      }
    }
  } else {
    size_t bytes;
    if (!lsm_size_mul(rowbytes, r->height, &bytes)) {
      png_io_set(&r->io, LSM_ERR_LIMIT, "", "interlaced image too large");
      return 0;
    }
    size_t row_ptr_bytes;
    if (!lsm_size_mul(r->height, sizeof *r->rows, &row_ptr_bytes)) {
      png_io_set(&r->io, LSM_ERR_LIMIT, "", "interlaced image too large");
      return 0;
    }
    r->buffer = malloc(bytes ? bytes : 1);
    r->rows = malloc(row_ptr_bytes ? row_ptr_bytes : 1);
    if (!r->buffer || !r->rows) {
      png_io_set(&r->io, LSM_ERR_NOMEM, "", "out of memory for the interlaced image");
      return 0;
    }
    for (png_uint_32 y = 0; y < r->height; ++y) r->rows[y] = r->buffer + (size_t)y * rowbytes;
    png_read_image(r->png, r->rows);
    for (png_uint_32 y = 0; y < r->height; ++y) {
      uint8_t *out = r->mask.pixels + (size_t)y * r->width;
      if (r->palette) {
        if (!convert_index_row(r, r->rows[y], y, out)) return 0;
      } else {
        lsm_mask_row_from_samples(r->rows[y], r->width, channels, depth, invert, nonzero, out);
      }
    }
  }
  png_read_end(r->png, NULL); /* checks the rest of the image data and CRCs */
  return 1;
}

static void png_reader_init(png_reader *r) {
  png_io_init(&r->io);
  r->png = NULL;
  r->info = NULL;
  r->width = r->height = 0;
  r->buffer = NULL;
  r->rows = NULL;
  r->palette = 0;
  r->num_palette = 0;
  r->mask.width = r->mask.height = 0;
  r->mask.pixels = NULL;
}

/* The pixel limit applied straight from the IHDR chunk, before libpng reads
 * any further: a header that declares a huge image followed by little or no
 * data (or data that would take long to inflate) is refused at once with the
 * limit message.  Only on seekable streams (files, fmemopen), with a complete
 * IHDR whose CRC is right; everything else is left to libpng.  The stream is
 * put back right after the signature.  Returns 0 when the image is over the
 * limit or the stream cannot be put back (the message is in r->io). */
static int ihdr_within_limit(png_reader *r) {
  const uint64_t max_pixels = r->opts ? r->opts->max_pixels : 0;
  if (max_pixels == 0) return 1;
  FILE *fp = r->io.fp;
  long start = ftell(fp);
  if (start < 0) return 1;
  png_byte c[25]; /* length, "IHDR", 13 bytes of data, CRC */
  size_t got = fread(c, 1, sizeof c, fp);
  int over = 0;
  uint32_t w = 0, h = 0;
  if (got == sizeof c && png_get_uint_32(c) == 13 && memcmp(c + 4, "IHDR", 4) == 0 &&
      (uint32_t)crc32(0L, c + 4, 17) == png_get_uint_32(c + 21)) {
    w = png_get_uint_32(c + 8);
    h = png_get_uint_32(c + 12);
    over = w > 0 && h > 0 && (uint64_t)w * (uint64_t)h > max_pixels; /* < 2^64 */
  }
  clearerr(fp);
  if (fseek(fp, start, SEEK_SET) != 0) {
    png_io_set(&r->io, LSM_ERR_IO, "", "cannot seek back to the PNG header");
    return 0;
  }
  if (!over) return 1;
  char text[160];
  snprintf(text, sizeof text, "image is %" PRIu32 "x%" PRIu32 " = %" PRIu64
           " pixels, more than the limit of %" PRIu64, w, h, (uint64_t)w * (uint64_t)h,
           max_pixels);
  png_io_set(&r->io, LSM_ERR_LIMIT, "", text);
  return 0;
}

/* Reads from an open stream positioned at the signature; name is for messages.
 * Does not close fp. */
static lsm_status png_read_stream(FILE *fp, const char *name, png_reader *r, lsm_err *err) {
  png_reader_init(r);
  r->io.fp = fp;
  lsm_status st = LSM_OK;
  png_byte sig[PNG_SIG_BYTES];
  size_t got = fread(sig, 1, sizeof sig, fp);
  if (got != sizeof sig && ferror(fp)) {
    st = lsm_fail(err, LSM_ERR_IO, name, "read error: %s", strerror(errno));
  } else if (got == 0) {
    st = lsm_fail(err, LSM_ERR_INPUT, name, "empty file, not a PNG file");
  } else if (got != sizeof sig || png_sig_cmp(sig, 0, sizeof sig) != 0) {
    st = lsm_fail(err, LSM_ERR_INPUT, name, "not a PNG file");
  } else if (!ihdr_within_limit(r)) {
    st = lsm_fail(err, r->io.status, name, "%s", r->io.msg);
  } else {
    r->png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &r->io, on_png_error, on_png_warning);
    if (r->png) r->info = png_create_info_struct(r->png);
    if (!r->png || !r->info)
      st = lsm_fail(err, LSM_ERR_NOMEM, name, "cannot create a PNG reader");
    else if (!png_read_guarded(r))
      st = lsm_fail(err, r->io.status, name, "%s", r->io.msg);
  }

  if (r->png) png_destroy_read_struct(&r->png, r->info ? &r->info : NULL, NULL);
  free(r->rows);
  free(r->buffer);
  r->rows = NULL;
  r->buffer = NULL;
  if (st != LSM_OK) {
    free(r->mask.pixels);
    r->mask.pixels = NULL;
    r->mask.width = r->mask.height = 0;
  }
  return st;
}

static lsm_status png_read_common(const char *path, png_reader *r, lsm_err *err) {
  png_reader_init(r);
  if (!path) return lsm_fail(err, LSM_ERR_INPUT, NULL, "no PNG file name given");
  FILE *fp = fopen(path, "rb");
  if (!fp) return lsm_fail(err, LSM_ERR_INPUT, path, "cannot open: %s", strerror(errno));
  struct stat sb;
  if (fstat(fileno(fp), &sb) == 0 && S_ISDIR(sb.st_mode)) {
    fclose(fp);
    return lsm_fail(err, LSM_ERR_INPUT, path, "is a folder, not a PNG file");
  }
  lsm_status st = png_read_stream(fp, path, r, err);
  fclose(fp); /* read-only: nothing to lose on close */
  return st;
}

/* A reader of a whole mask into *out (emptied first, when given). */
static png_reader mask_reader(const lsm_image_read_opts *opts, lsm_mask *out) {
  png_reader r = {.opts = opts, .header_only = 0};
  if (out) {
    out->width = out->height = 0;
    out->pixels = NULL;
  }
  return r;
}

lsm_status lsm_png_read_mask(const char *path, const lsm_image_read_opts *opts,
                             lsm_mask *out, lsm_err *err) {
  png_reader r = mask_reader(opts, out);
  if (!out) return lsm_fail(err, LSM_ERR_INTERNAL, path, "no output mask given");
  lsm_status st = png_read_common(path, &r, err);
  if (st == LSM_OK) *out = r.mask;
  return st;
}

lsm_status lsm_png_read_mask_stream(FILE *fp, const char *name, const lsm_image_read_opts *opts,
                                    lsm_mask *out, lsm_err *err) {
  png_reader r = mask_reader(opts, out);
  if (!out || !fp) return lsm_fail(err, LSM_ERR_INTERNAL, name, "bad arguments to the PNG reader");
  lsm_status st = png_read_stream(fp, name, &r, err);
  if (st == LSM_OK) *out = r.mask;
  return st;
}

lsm_status lsm_png_read_header(const char *path, uint64_t max_pixels, int *width, int *height,
                               lsm_err *err) {
  png_reader r;
  lsm_image_read_opts opts = {0, max_pixels, 0};
  r.opts = &opts;
  r.header_only = 1;
  lsm_status st = png_read_common(path, &r, err);
  if (st != LSM_OK) return st;
  if (width) *width = (int)r.width;
  if (height) *height = (int)r.height;
  return LSM_OK;
}

lsm_status lsm_png_read_size(const char *path, int *width, int *height, lsm_err *err) {
  return lsm_png_read_header(path, 0, width, height, err);
}

/* ---- writing --------------------------------------------------------------- */

typedef struct png_writer {
  png_io io;
  png_structp png;
  png_infop info;
  const uint8_t *pixels;
  int width, height;
  int channels; /* 1 gray, 3 RGB */
  int is_mask;  /* pixels are 0/1 mask values: write 0/255 */
  uint8_t *row; /* conversion buffer for masks */
} png_writer;

static int png_write_guarded(png_writer *w) {
  if (setjmp(w->io.jmp)) return 0;
  png_set_write_fn(w->png, &w->io, on_png_write, on_png_flush);
  png_set_user_limits(w->png, PNG_DIM_MAX, PNG_DIM_MAX);
  /* Speed over the last bytes: gray masks are runs of 0 and 255, which run-length
   * deflate packs unfiltered with a small hash table; the RGB pictures
   * (previews) take the up filter and deflate's fastest level.  libpng's default
   * (every filter tried on every row, level 6) costs several times as much. */
  if (w->channels == 1) {
    png_set_filter(w->png, PNG_FILTER_TYPE_BASE, PNG_FILTER_NONE);
    png_set_compression_strategy(w->png, Z_RLE);
    png_set_compression_mem_level(w->png, 1);
  } else {
    png_set_filter(w->png, PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
    png_set_compression_level(w->png, 1);
  }
  png_set_IHDR(w->png, w->info, (png_uint_32)w->width, (png_uint_32)w->height, 8,
               w->channels == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(w->png, w->info);
  const size_t stride = (size_t)w->width * (size_t)w->channels;
  for (int y = 0; y < w->height; ++y) {
    const uint8_t *src = w->pixels + (size_t)y * stride;
    if (w->is_mask) {
      for (size_t x = 0; x < stride; ++x) w->row[x] = src[x] ? 255 : 0;
      src = w->row;
    }
    png_write_row(w->png, src);
  }
  png_write_end(w->png, w->info);
  return 1;
}

static lsm_status png_write_common(const char *path, const uint8_t *pixels, int width,
                                   int height, int channels, int is_mask, lsm_err *err) {
  if (!path) return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "no PNG file name given");
  if (!pixels || width <= 0 || height <= 0)
    return lsm_fail(err, LSM_ERR_INPUT, path, "cannot write a %dx%d image", width, height);
  size_t bytes;
  if (!lsm_size_mul3((size_t)width, (size_t)height, (size_t)channels, &bytes))
    return lsm_fail(err, LSM_ERR_LIMIT, path, "image %dx%d is too large", width, height);

  png_writer w;
  png_io_init(&w.io);
  w.png = NULL;
  w.info = NULL;
  w.pixels = pixels;
  w.width = width;
  w.height = height;
  w.channels = channels;
  w.is_mask = is_mask;
  w.row = NULL;
  if (is_mask) {
    w.row = malloc((size_t)width * (size_t)channels);
    if (!w.row) return lsm_fail(err, LSM_ERR_NOMEM, path, "out of memory for a row");
  }

  FILE *fp = fopen(path, "wb");
  if (!fp) {
    lsm_status st = lsm_fail(err, LSM_ERR_IO, path, "cannot create: %s", strerror(errno));
    free(w.row);
    return st;
  }
  struct stat sb;
  int regular = fstat(fileno(fp), &sb) == 0 && S_ISREG(sb.st_mode);
  w.io.fp = fp;

  lsm_status st = LSM_OK;
  w.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &w.io, on_png_error, on_png_warning);
  if (w.png) w.info = png_create_info_struct(w.png);
  if (!w.png || !w.info) {
    st = lsm_fail(err, LSM_ERR_NOMEM, path, "cannot create a PNG writer");
  } else if (!png_write_guarded(&w)) {
    /* libpng complaining about our own data is an internal error, not the user's */
    st = lsm_fail(err, w.io.status == LSM_ERR_INPUT ? LSM_ERR_INTERNAL : w.io.status, path,
                  "%s", w.io.msg);
  }
  if (w.png) png_destroy_write_struct(&w.png, w.info ? &w.info : NULL);
  free(w.row);

  st = lsm_close_written(&fp, path, st, err);
  if (st != LSM_OK && regular) remove(path); /* never unlink a device or FIFO */
  return st;
}

lsm_status lsm_png_write_gray8(const char *path, const uint8_t *pixels, int width,
                               int height, lsm_err *err) {
  return png_write_common(path, pixels, width, height, 1, 0, err);
}

lsm_status lsm_png_write_rgb8(const char *path, const uint8_t *pixels, int width,
                              int height, lsm_err *err) {
  return png_write_common(path, pixels, width, height, 3, 0, err);
}

lsm_status lsm_png_write_mask(const char *path, const lsm_mask *mask, lsm_err *err) {
  if (!mask) return lsm_fail(err, LSM_ERR_INTERNAL, path, "no mask given");
  return png_write_common(path, mask->pixels, mask->width, mask->height, 1, 1, err);
}
