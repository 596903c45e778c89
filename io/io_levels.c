/* io_levels: how many distinct non-zero values fill regions of a PNG
 * (lsm_png_count_levels): a label map (0, 1, 2, 3, ...) given where binary
 * masks are read is read as one object, and `reconstruct` says so.  A value
 * counts when some pixel of it has its four neighbours of the same value: the
 * grey ramp of an anti-aliased mask's edge is one pixel wide and does not.  libpng's simplified API reads the
 * PNG as gray of its own depth, so that stored values stay as they are: 8-bit
 * gray for 1 to 8 bits (colours through their luminance), 16-bit linear gray
 * for 16 bits (the API converts between the two, which would lose small
 * values). */
#include "io/lsm_io.h"

#include <png.h>
#include <stdlib.h>
#include <string.h>

/* The k-th 16-bit sample, in the machine's order (the simplified API's). */
static uint16_t sample16(const unsigned char *p, size_t k) {
  uint16_t v;
  memcpy(&v, p + 2 * k, sizeof v);
  return v;
}

lsm_status lsm_png_count_levels(const char *path, unsigned *levels) {
  *levels = 0;
  png_image image;
  memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path)) return LSM_ERR_INPUT;
  const int wide = (image.format & PNG_FORMAT_FLAG_LINEAR) != 0;
  image.format = wide ? PNG_FORMAT_LINEAR_Y : PNG_FORMAT_GRAY;
  const size_t bytes = PNG_IMAGE_SIZE(image);
  if (bytes == 0 || bytes > ((size_t)1 << 31)) {
    png_image_free(&image);
    return LSM_ERR_LIMIT;
  }
  /* zeroed: with no background given, libpng composites an alpha channel
   * over the buffer's contents (here black, as the slice readers do) */
  unsigned char *pixels = calloc(bytes, 1);
  if (!pixels) {
    png_image_free(&image);
    return LSM_ERR_NOMEM;
  }
  lsm_status st = png_image_finish_read(&image, NULL, pixels, 0, NULL) ? LSM_OK : LSM_ERR_INPUT;
  uint16_t seen[256];
  const size_t w = image.width, h = image.height;
#define AT(k) (wide ? sample16(pixels, k) : pixels[k])
  for (size_t y = 1; st == LSM_OK && y + 1 < h && *levels < 256; ++y)
    for (size_t x = 1; x + 1 < w && *levels < 256; ++x) {
      const size_t k = y * w + x;
      const uint16_t v = AT(k);
      if (!v || AT(k - 1) != v || AT(k + 1) != v || AT(k - w) != v || AT(k + w) != v) continue;
      unsigned q = 0;
      while (q < *levels && seen[q] != v) ++q;
      if (q == *levels) seen[(*levels)++] = v;
    }
#undef AT
  free(pixels);
  png_image_free(&image);
  return st;
}
