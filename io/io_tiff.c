/* io_tiff: TIFF slices in (libtiff), by the PNG reader's foreground rule.
 *
 * Two paths.  Gray, gray + alpha, RGB or RGBA at 1, 8 or 16 bits a sample,
 * in strips or tiles, top-left oriented, are read sample for sample (strips
 * by scanline, tiles a row of tiles at a time) and each row goes through
 * lsm_mask_row_from_samples as a PNG row would (16-bit samples put big
 * endian first), so a 16-bit label mask stored as 0/1 keeps its values.
 * Every other layout libtiff can decode (palette, YCbCr, CMYK, separate
 * planes, 2 or 4 bits, the orientations that flip rows or columns) is read
 * through its RGBA interface, stopping at the first bad strip or tile: 8 bits a sample,
 * alpha premultiplied, so the colour is already composited over black and
 * the alpha is dropped.
 *
 * Files are read, never mapped (mode "rm"): a slice rewritten while it is
 * read gives a read error, not SIGBUS.  Streams go through a FILE *
 * (TIFFClientOpenExt: memory for the fuzzer).  libtiff's messages go to a
 * handler per file, never to stderr.  A damaged file is refused: any error
 * libtiff reports, also one it recovers from, and any warning while the
 * pixels are decoded ("Premature EOF": a cut CCITT strip decodes short
 * without an error) but a few compatibility notes; the first becomes the
 * message of the failure.
 */
#include "io/lsm_io.h"

#include <inttypes.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <tiffio.h>

/* The largest single allocation libtiff may make for one file: a strip as
 * large as the largest image the pixel limit lets through. */
#define TIFF_MAX_ALLOC ((tmsize_t)1 << 31)

typedef struct tiff_messages {
  char first[200];  /* the first error, or warning that means damage; "" if none */
  int decoding;     /* set once the directory is read: pixels are being decoded */
  const char *name; /* the file's name, which the message names already */
} tiff_messages;

/* Drops the "<name>: " that some of libtiff's messages start with. */
static void drop_name(char *text, const char *name) {
  const size_t n = name ? strlen(name) : 0;
  if (n && strncmp(text, name, n) == 0 && text[n] == ':' && text[n + 1] == ' ')
    memmove(text, text + n + 2, strlen(text + n + 2) + 1);
}

static int on_tiff_error(TIFF *tif, void *user, const char *module, const char *fmt, va_list ap) {
  (void)tif;
  (void)module;
  tiff_messages *m = user;
  if (m && !m->first[0]) {
    vsnprintf(m->first, sizeof m->first, fmt, ap);
    drop_name(m->first, m->name);
  }
  return 1; /* handled: not to stderr */
}

/* Warnings while decoding mean missing or bad pixel data, but for these
 * notes on old yet readable encodings. */
static int harmless_decode_warning(const char *text) {
  static const char *const notes[] = {"Old-style LZW codes", "Assuming 8-bit colormap",
                                      "old-style JPEG compression",
                                      "Auto-corrected former TIFF subsampling values"};
  for (size_t k = 0; k < sizeof notes / sizeof notes[0]; ++k)
    if (strstr(text, notes[k])) return 1;
  return 0;
}

static int on_tiff_warning(TIFF *tif, void *user, const char *module, const char *fmt,
                           va_list ap) {
  (void)tif;
  (void)module;
  tiff_messages *m = user;
  if (!m || m->first[0]) return 1;
  char text[sizeof m->first];
  vsnprintf(text, sizeof text, fmt, ap);
  /* in the directory, unknown or odd tags mean nothing to a mask; a tag whose
   * data lies past the end of the file means the file was cut */
  const int damage = m->decoding ? !harmless_decode_warning(text) : strstr(text, "IO error") != NULL;
  if (damage) {
    memcpy(m->first, text, sizeof text);
    drop_name(m->first, m->name);
  }
  return 1;
}

/* libtiff's I/O on a FILE * (a file, or fmemopen() memory), read only; the
 * stream is not closed here. */
static tmsize_t fp_read(thandle_t h, void *buf, tmsize_t n) {
  return n < 0 ? -1 : (tmsize_t)fread(buf, 1, (size_t)n, (FILE *)h);
}
static tmsize_t fp_write(thandle_t h, void *buf, tmsize_t n) {
  (void)h, (void)buf, (void)n;
  return -1;
}
static toff_t fp_seek(thandle_t h, toff_t off, int whence) {
  if (off > (toff_t)INT64_MAX || fseeko((FILE *)h, (off_t)off, whence) != 0) return (toff_t)-1;
  const off_t at = ftello((FILE *)h);
  return at < 0 ? (toff_t)-1 : (toff_t)at;
}
static int fp_close(thandle_t h) {
  (void)h;
  return 0;
}
static toff_t fp_size(thandle_t h) {
  FILE *fp = h;
  const off_t at = ftello(fp);
  if (at < 0 || fseeko(fp, 0, SEEK_END) != 0) return 0;
  const off_t end = ftello(fp);
  if (fseeko(fp, at, SEEK_SET) != 0 || end < 0) return 0;
  return (toff_t)end;
}
static int fp_map(thandle_t h, void **base, toff_t *size) {
  (void)h, (void)base, (void)size;
  return 0; /* no mapping: libtiff reads */
}
static void fp_unmap(thandle_t h, void *base, toff_t size) { (void)h, (void)base, (void)size; }

/* libtiff's options for one file: its messages to msgs, allocations capped. */
static TIFFOpenOptions *open_options(tiff_messages *msgs, const char *name) {
  msgs->first[0] = '\0';
  msgs->decoding = 0; /* libtiff warns while it reads the directory, in TIFFOpen */
  msgs->name = name;
  TIFFOpenOptions *o = TIFFOpenOptionsAlloc();
  if (!o) return NULL;
  TIFFOpenOptionsSetErrorHandlerExtR(o, on_tiff_error, msgs);
  TIFFOpenOptionsSetWarningHandlerExtR(o, on_tiff_warning, msgs);
  TIFFOpenOptionsSetMaxSingleMemAlloc(o, TIFF_MAX_ALLOC);
  return o;
}

/* Opens a file by name, read without mapping it, or, with path NULL, the
 * stream fp under name. */
static lsm_status tiff_open(const char *path, FILE *fp, const char *name, tiff_messages *msgs,
                            TIFF **out, lsm_err *err) {
  *out = NULL;
  TIFFOpenOptions *o = open_options(msgs, name);
  if (!o) return lsm_fail(err, LSM_ERR_NOMEM, name, "cannot allocate libtiff's options");
  TIFF *tif = path ? TIFFOpenExt(path, "rm", o)
                   : TIFFClientOpenExt(name, "rm", (thandle_t)fp, fp_read, fp_write, fp_seek,
                                       fp_close, fp_size, fp_map, fp_unmap, o);
  TIFFOpenOptionsFree(o);
  if (!tif)
    return lsm_fail(err, LSM_ERR_INPUT, name, "cannot read as TIFF: %s",
                    msgs->first[0] ? msgs->first : "not a TIFF file");
  *out = tif;
  return LSM_OK;
}

/* Refuses the file if libtiff reported damage so far (see tiff_messages). */
static lsm_status tiff_damage(const tiff_messages *msgs, const char *name, lsm_err *err) {
  if (!msgs->first[0]) return LSM_OK;
  return lsm_fail(err, LSM_ERR_INPUT, name, "corrupt TIFF: %s", msgs->first);
}

/* Size and page count; refuses several pages, images over max_pixels and
 * orientations that swap rows and columns. */
static lsm_status tiff_size(TIFF *tif, const char *path, uint64_t max_pixels, uint32_t *w,
                            uint32_t *h, lsm_err *err) {
  *w = *h = 0;
  if (!TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, w) || !TIFFGetField(tif, TIFFTAG_IMAGELENGTH, h) ||
      *w == 0 || *h == 0)
    return lsm_fail(err, LSM_ERR_INPUT, path, "corrupt TIFF: no image size");
  if (*w > INT32_MAX || *h > INT32_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, path, "image is %" PRIu32 "x%" PRIu32 ", too large", *w,
                    *h);
  const uint64_t pixels = (uint64_t)*w * (uint64_t)*h;
  if (max_pixels != 0 && pixels > max_pixels)
    return lsm_fail(err, LSM_ERR_LIMIT, path,
                    "image is %" PRIu32 "x%" PRIu32 " = %" PRIu64
                    " pixels, more than the limit of %" PRIu64,
                    *w, *h, pixels, max_pixels);
  if (!TIFFLastDirectory(tif))
    return lsm_fail(err, LSM_ERR_INPUT, path,
                    "TIFF with several pages: give one slice a file (tiffsplit from "
                    "libtiff-tools splits a stack)");
  /* libtiff's RGBA reader flips rows and columns but does not transpose: 5 to
   * 8 would come back with width and height swapped */
  uint16_t orientation = ORIENTATION_TOPLEFT;
  TIFFGetFieldDefaulted(tif, TIFFTAG_ORIENTATION, &orientation);
  if (orientation < ORIENTATION_TOPLEFT || orientation > ORIENTATION_BOTLEFT)
    return lsm_fail(err, LSM_ERR_UNSUPPORTED, path,
                    "TIFF orientation %u (rows stored as columns: rotated or transposed) is not "
                    "read: save the mask as it is displayed, top-left",
                    (unsigned)orientation);
  return LSM_OK;
}

lsm_status lsm_tiff_read_header(const char *path, uint64_t max_pixels, int *width, int *height,
                                lsm_err *err) {
  if (width) *width = 0;
  if (height) *height = 0;
  if (!path || !width || !height)
    return lsm_fail(err, LSM_ERR_INTERNAL, path, "bad arguments to read a TIFF header");
  tiff_messages msgs;
  TIFF *tif;
  LSM_TRY(tiff_open(path, NULL, path, &msgs, &tif, err));
  uint32_t w, h;
  lsm_status st = tiff_damage(&msgs, path, err);
  if (st == LSM_OK) st = tiff_size(tif, path, max_pixels, &w, &h, err);
  TIFFClose(tif);
  if (st == LSM_OK) {
    *width = (int)w;
    *height = (int)h;
  }
  return st;
}

/* How the samples of a gray or RGB image map to a PNG-like row: the
 * channels kept (gray or RGB, then an unassociated alpha), each sample's
 * index in the pixel, and whether gray is stored with white as zero. */
typedef struct sample_layout {
  int channels;   /* 1 to 4, as lsm_mask_row_from_samples takes them */
  int source[4];  /* sample index of each kept channel */
  int spp;        /* samples per pixel in the file */
  int bits;       /* 1, 8 or 16 */
  int white_zero; /* PHOTOMETRIC_MINISWHITE */
  int tiled;      /* in tiles, else in strips */
} sample_layout;

/* Whether the image can be read sample for sample, and how (else RGBA). */
static int sample_layout_of(TIFF *tif, sample_layout *l) {
  uint16_t bits = 1, spp = 1, photometric = 0, planar = PLANARCONFIG_CONTIG;
  uint16_t orientation = ORIENTATION_TOPLEFT, extra_count = 0;
  uint16_t *extra = NULL;
  TIFFGetFieldDefaulted(tif, TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLESPERPIXEL, &spp);
  TIFFGetFieldDefaulted(tif, TIFFTAG_PLANARCONFIG, &planar);
  TIFFGetFieldDefaulted(tif, TIFFTAG_ORIENTATION, &orientation);
  TIFFGetFieldDefaulted(tif, TIFFTAG_EXTRASAMPLES, &extra_count, &extra);
  if (!TIFFGetField(tif, TIFFTAG_PHOTOMETRIC, &photometric)) return 0;
  if (planar != PLANARCONFIG_CONTIG || orientation != ORIENTATION_TOPLEFT) return 0;
  const int gray = photometric == PHOTOMETRIC_MINISBLACK || photometric == PHOTOMETRIC_MINISWHITE;
  const int colour = gray ? 1 : photometric == PHOTOMETRIC_RGB ? 3 : 0;
  if (!colour || spp < colour || spp > 4 || spp - colour != extra_count) return 0;
  if (!(bits == 8 || bits == 16 || (bits == 1 && spp == 1))) return 0;
  const int tiled = TIFFIsTiled(tif);
  if (tiled) { /* a row of tiles is a row of whole bytes (1-bit tiles are 16k wide) */
    uint32_t tile_width = 0;
    if (!TIFFGetField(tif, TIFFTAG_TILEWIDTH, &tile_width) ||
        ((uint64_t)tile_width * spp * bits) % 8 != 0)
      return 0;
  }
  memset(l, 0, sizeof *l);
  l->channels = colour;
  for (int c = 0; c < colour; ++c) l->source[c] = c;
  /* an unassociated alpha is composited as PNG's is; an associated one is
   * already in the colour, and an unspecified extra sample is no alpha */
  for (int e = 0; e < extra_count; ++e)
    if (extra && extra[e] == EXTRASAMPLE_UNASSALPHA && l->channels == colour) {
      l->source[l->channels] = colour + e;
      l->channels++;
    }
  l->spp = spp;
  l->bits = bits;
  l->white_zero = photometric == PHOTOMETRIC_MINISWHITE;
  l->tiled = tiled;
  return 1;
}

/* The kept samples of one scanline as a PNG-like row: 8-bit (1-bit samples
 * to 0 / 255) or 16-bit big endian. */
static void sample_row(const sample_layout *l, const uint8_t *line, uint32_t width, uint8_t *row) {
  const int wide = l->bits == 16;
  for (uint32_t x = 0; x < width; ++x)
    for (int c = 0; c < l->channels; ++c) {
      const size_t s = (size_t)x * (size_t)l->spp + (size_t)l->source[c];
      uint32_t v, maxval = wide ? 65535u : 255u;
      if (l->bits == 1)
        v = ((line[s >> 3] >> (7 - (s & 7))) & 1u) ? 255u : 0u;
      else if (wide) {
        uint16_t u;
        memcpy(&u, line + 2 * s, 2); /* libtiff gives host order */
        v = u;
      } else
        v = line[s];
      if (l->white_zero && c == 0) v = maxval - v;
      uint8_t *o = row + ((size_t)x * (size_t)l->channels + (size_t)c) * (wide ? 2 : 1);
      if (wide) {
        o[0] = (uint8_t)(v >> 8);
        o[1] = (uint8_t)(v & 0xffu);
      } else {
        o[0] = (uint8_t)v;
      }
    }
}

/* Refuses samples that are not unsigned integers, and 16-bit samples that
 * only the RGBA path could read (it would scale 0/1 labels to 0). */
static lsm_status check_samples(TIFF *tif, const char *path, int by_sample, lsm_err *err) {
  uint16_t format = SAMPLEFORMAT_UINT, bits = 1;
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLEFORMAT, &format);
  TIFFGetFieldDefaulted(tif, TIFFTAG_BITSPERSAMPLE, &bits);
  if (format != SAMPLEFORMAT_UINT)
    return lsm_fail(err, LSM_ERR_UNSUPPORTED, path,
                    "TIFF samples are %s, not unsigned integers: save the mask as 8-bit gray",
                    format == SAMPLEFORMAT_IEEEFP ? "floating point" : "signed or complex");
  if (!by_sample && bits > 8)
    return lsm_fail(err, LSM_ERR_UNSUPPORTED, path,
                    "%u-bit TIFF in separate planes, this orientation or this colour model is "
                    "not read: save it as gray, or at 8 bits",
                    (unsigned)bits);
  return LSM_OK;
}

/* One line of samples (the file's bytes for a row) into row y of the mask. */
static void mask_row(const sample_layout *l, const uint8_t *line, uint32_t w, uint32_t y,
                     int invert, int nonzero, uint8_t *row, lsm_mask *mask) {
  sample_row(l, line, w, row);
  lsm_mask_row_from_samples(row, w, l->channels, l->bits == 16 ? 16 : 8, invert, nonzero,
                            mask->pixels + (size_t)y * (size_t)w);
}

static lsm_status read_strips(TIFF *tif, const char *path, const sample_layout *l, uint32_t w,
                              uint32_t h, int invert, int nonzero, lsm_mask *mask,
                              tiff_messages *msgs, uint8_t *row, lsm_err *err) {
  const tmsize_t line_bytes = TIFFScanlineSize(tif);
  const size_t need = ((size_t)w * (size_t)l->spp * (size_t)l->bits + 7) / 8;
  if (line_bytes <= 0 || (size_t)line_bytes < need)
    return lsm_fail(err, LSM_ERR_INPUT, path, "corrupt TIFF: scanline of %" PRId64 " bytes",
                    (int64_t)line_bytes);
  uint8_t *line = malloc((size_t)line_bytes);
  if (!line) return lsm_fail(err, LSM_ERR_NOMEM, path, "out of memory for a row");
  lsm_status st = LSM_OK;
  for (uint32_t y = 0; y < h; ++y) {
    if (TIFFReadScanline(tif, line, y, 0) < 0) {
      st = lsm_fail(err, LSM_ERR_INPUT, path, "corrupt TIFF: %s",
                    msgs->first[0] ? msgs->first : "cannot read a scanline");
      break;
    }
    mask_row(l, line, w, y, invert, nonzero, row, mask);
  }
  free(line);
  return st;
}

/* Tiles are read a row of tiles at a time; each row of pixels is put
 * together from the tiles' rows (whole bytes: sample_layout_of). */
static lsm_status read_tiles(TIFF *tif, const char *path, const sample_layout *l, uint32_t w,
                             uint32_t h, int invert, int nonzero, lsm_mask *mask,
                             tiff_messages *msgs, uint8_t *row, lsm_err *err) {
  uint32_t tw = 0, th = 0;
  TIFFGetField(tif, TIFFTAG_TILEWIDTH, &tw);
  TIFFGetField(tif, TIFFTAG_TILELENGTH, &th);
  const tmsize_t tile_bytes = TIFFTileSize(tif), tile_row = TIFFTileRowSize(tif);
  const size_t across = tw ? ((size_t)w + tw - 1) / tw : 0;
  size_t band_bytes, line_bytes;
  if (tw == 0 || th == 0 || tile_bytes <= 0 || tile_row <= 0 ||
      (uint64_t)tile_row * th > (uint64_t)tile_bytes ||
      (uint64_t)tile_row * 8 != (uint64_t)tw * (uint64_t)l->spp * (uint64_t)l->bits)
    return lsm_fail(err, LSM_ERR_INPUT, path, "corrupt TIFF: tiles of %" PRIu32 "x%" PRIu32, tw,
                    th);
  if (!lsm_size_mul(across, (size_t)tile_bytes, &band_bytes) ||
      !lsm_size_mul(across, (size_t)tile_row, &line_bytes))
    return lsm_fail(err, LSM_ERR_LIMIT, path, "a row of %zu tiles is too large", across);
  uint8_t *band = malloc(band_bytes), *line = malloc(line_bytes);
  lsm_status st = LSM_OK;
  if (!band || !line) st = lsm_fail(err, LSM_ERR_NOMEM, path, "out of memory for a row of tiles");
  for (uint32_t y0 = 0; st == LSM_OK && y0 < h; y0 += th) {
    for (size_t k = 0; k < across; ++k)
      if (TIFFReadTile(tif, band + k * (size_t)tile_bytes, (uint32_t)(k * tw), y0, 0, 0) < 0) {
        st = lsm_fail(err, LSM_ERR_INPUT, path, "corrupt TIFF: %s",
                      msgs->first[0] ? msgs->first : "cannot read a tile");
        break;
      }
    for (uint32_t r = 0; st == LSM_OK && r < th && r < h - y0; ++r) {
      for (size_t k = 0; k < across; ++k)
        memcpy(line + k * (size_t)tile_row,
               band + k * (size_t)tile_bytes + (size_t)r * (size_t)tile_row, (size_t)tile_row);
      mask_row(l, line, w, y0 + r, invert, nonzero, row, mask);
    }
    if (y0 > UINT32_MAX - th) break;
  }
  free(band);
  free(line);
  return st;
}

static lsm_status read_rgba(TIFF *tif, const char *path, uint32_t w, uint32_t h, int invert,
                            int nonzero, lsm_mask *mask, tiff_messages *msgs, lsm_err *err) {
  size_t pixels;
  if (!lsm_size_mul(w, h, &pixels) || pixels > SIZE_MAX / 4)
    return lsm_fail(err, LSM_ERR_LIMIT, path, "image too large");
  uint32_t *raster = malloc(pixels * sizeof *raster);
  uint8_t *row = malloc((size_t)w * 3);
  lsm_status st = LSM_OK;
  if (!raster || !row) st = lsm_fail(err, LSM_ERR_NOMEM, path, "out of memory for the image");
  /* stop_on_error: a strip or tile that cannot be read fails the image */
  if (st == LSM_OK && !TIFFReadRGBAImageOriented(tif, w, h, raster, ORIENTATION_TOPLEFT, 1))
    st = lsm_fail(err, LSM_ERR_INPUT, path, "cannot decode the TIFF: %s",
                  msgs->first[0] ? msgs->first : "a strip or tile cannot be read");
  for (uint32_t y = 0; st == LSM_OK && y < h; ++y) {
    const uint32_t *p = raster + (size_t)y * (size_t)w;
    for (uint32_t x = 0; x < w; ++x) { /* premultiplied: over black already */
      row[3 * (size_t)x + 0] = (uint8_t)TIFFGetR(p[x]);
      row[3 * (size_t)x + 1] = (uint8_t)TIFFGetG(p[x]);
      row[3 * (size_t)x + 2] = (uint8_t)TIFFGetB(p[x]);
    }
    lsm_mask_row_from_samples(row, w, 3, 8, invert, nonzero, mask->pixels + (size_t)y * (size_t)w);
  }
  free(raster);
  free(row);
  return st;
}

/* libtiff 4.5's RGBA reader refuses an uncompressed tile read without a
 * mapping unless its raw buffer is exactly one tile ("Invalid tile byte
 * count"): such an image gets that buffer, *raw, freed after TIFFClose. */
static lsm_status rgba_tile_buffer(TIFF *tif, const char *path, uint8_t **raw, lsm_err *err) {
  uint16_t compression = COMPRESSION_NONE;
  TIFFGetFieldDefaulted(tif, TIFFTAG_COMPRESSION, &compression);
  if (!TIFFIsTiled(tif) || compression != COMPRESSION_NONE) return LSM_OK;
  const tmsize_t size = TIFFTileSize(tif);
  if (size <= 0) return lsm_fail(err, LSM_ERR_INPUT, path, "corrupt TIFF: no tile size");
  *raw = malloc((size_t)size);
  if (!*raw) return lsm_fail(err, LSM_ERR_NOMEM, path, "out of memory for a tile");
  if (!TIFFReadBufferSetup(tif, *raw, size))
    return lsm_fail(err, LSM_ERR_NOMEM, path, "cannot set up a tile buffer");
  return LSM_OK;
}

/* The mask of an open TIFF (closed here). */
static lsm_status read_mask(TIFF *tif, const char *name, const lsm_image_read_opts *opts,
                            tiff_messages *msgs, lsm_mask *out, lsm_err *err) {
  uint32_t w = 0, h = 0;
  sample_layout layout;
  uint8_t *raw = NULL;
  lsm_status st = tiff_damage(msgs, name, err);
  if (st == LSM_OK) st = tiff_size(tif, name, opts ? opts->max_pixels : 0, &w, &h, err);
  const int by_sample = st == LSM_OK && sample_layout_of(tif, &layout);
  if (st == LSM_OK) st = check_samples(tif, name, by_sample, err);
  if (st == LSM_OK) st = lsm_mask_create((int)w, (int)h, out, err);
  const int invert = opts ? opts->invert : 0, nonzero = opts ? opts->nonzero : 0;
  msgs->decoding = 1;
  if (st == LSM_OK && by_sample) {
    /* a PNG-like row: up to 4 channels of up to 2 bytes */
    uint8_t *row = malloc((size_t)w * 8);
    if (!row) st = lsm_fail(err, LSM_ERR_NOMEM, name, "out of memory for a row");
    else if (layout.tiled)
      st = read_tiles(tif, name, &layout, w, h, invert, nonzero, out, msgs, row, err);
    else
      st = read_strips(tif, name, &layout, w, h, invert, nonzero, out, msgs, row, err);
    free(row);
  } else if (st == LSM_OK) {
    st = rgba_tile_buffer(tif, name, &raw, err);
    if (st == LSM_OK) st = read_rgba(tif, name, w, h, invert, nonzero, out, msgs, err);
  }
  /* an error libtiff recovered from, or a warning while decoding: damaged */
  if (st == LSM_OK) st = tiff_damage(msgs, name, err);
  TIFFClose(tif);
  free(raw);
  if (st != LSM_OK) lsm_mask_free(out);
  return st;
}

lsm_status lsm_tiff_read_mask(const char *path, const lsm_image_read_opts *opts, lsm_mask *out,
                              lsm_err *err) {
  if (out) memset(out, 0, sizeof *out);
  if (!path || !out) return lsm_fail(err, LSM_ERR_INTERNAL, path, "bad arguments to read a TIFF");
  tiff_messages msgs;
  TIFF *tif;
  LSM_TRY(tiff_open(path, NULL, path, &msgs, &tif, err));
  return read_mask(tif, path, opts, &msgs, out, err);
}

lsm_status lsm_tiff_read_mask_stream(FILE *fp, const char *name, const lsm_image_read_opts *opts,
                                     lsm_mask *out, lsm_err *err) {
  if (out) memset(out, 0, sizeof *out);
  if (!fp || !name || !out)
    return lsm_fail(err, LSM_ERR_INTERNAL, name, "bad arguments to read a TIFF");
  tiff_messages msgs;
  TIFF *tif;
  LSM_TRY(tiff_open(NULL, fp, name, &msgs, &tif, err));
  return read_mask(tif, name, opts, &msgs, out, err);
}

/* ---- slice images by name ------------------------------------------------------------ */

lsm_status lsm_slice_read_mask(const char *path, const lsm_image_read_opts *opts, lsm_mask *out,
                               lsm_err *err) {
  return lsm_is_tiff_name(path) ? lsm_tiff_read_mask(path, opts, out, err)
                                : lsm_png_read_mask(path, opts, out, err);
}

lsm_status lsm_slice_read_header(const char *path, uint64_t max_pixels, int *width, int *height,
                                 lsm_err *err) {
  return lsm_is_tiff_name(path) ? lsm_tiff_read_header(path, max_pixels, width, height, err)
                                : lsm_png_read_header(path, max_pixels, width, height, err);
}
