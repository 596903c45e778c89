/* lsm_io: everything lsmorph reads and writes on disk.
 *
 *   io_png.c      PNG slices in (any bit depth / colour type) and masks out (libpng)
 *   io_dir.c      natural-order listing of the PNG files of a folder
 *   io_heights.c  the heights text file
 *   io_nrrd.c     streaming NRRD volume writer (attached header, raw float LE)
 *
 * Every function returns an lsm_status and records "<file>: <what>" in err.
 */
#ifndef LSM_IO_H
#define LSM_IO_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "../solver/lsm_grid.h"
#include "../solver/lsm_status.h"

/* ---- PNG ---------------------------------------------------------------- */

typedef struct lsm_png_read_opts {
  int invert;          /* 1: foreground is dark (luminance < 50 %) */
  uint64_t max_pixels; /* refuse images with more pixels (0 = no limit) */
} lsm_png_read_opts;

/* Reads a PNG of any bit depth (1..16) and colour type (gray, gray+alpha, RGB,
 * RGBA, palette, with or without tRNS) into a binary mask.  A pixel is
 * foreground when its luminance (Rec. 709 weights on the stored values, after
 * compositing over black with its alpha) is >= 50 % of full scale, or < 50 %
 * with opts->invert.  The size is checked against opts->max_pixels from the
 * header, before any pixel buffer is allocated. */
lsm_status lsm_png_read_mask(const char *path, const lsm_png_read_opts *opts,
                             lsm_mask *out, lsm_err *err);

/* Reads only the header: width and height. */
lsm_status lsm_png_read_size(const char *path, int *width, int *height, lsm_err *err);

/* Writes an 8-bit grayscale PNG; pixels are width*height bytes, row-major. */
lsm_status lsm_png_write_gray8(const char *path, const uint8_t *pixels, int width,
                               int height, lsm_err *err);

/* Writes a mask as 8-bit grayscale PNG, 255 inside and 0 outside. */
lsm_status lsm_png_write_mask(const char *path, const lsm_mask *mask, lsm_err *err);

/* Writes an 8-bit RGB PNG; pixels are width*height*3 bytes. */
lsm_status lsm_png_write_rgb8(const char *path, const uint8_t *pixels, int width,
                              int height, lsm_err *err);

/* ---- folders -------------------------------------------------------------- */

/* Natural order: digit runs compare by value ("2.png" < "10.png"), the rest
 * byte by byte; ties broken by plain strcmp so the order is total. */
int lsm_natural_cmp(const char *a, const char *b);

/* Lists the regular files of dir whose name ends in ".png" (any case), in
 * natural order, as full paths "dir/name".  Free with lsm_path_list_free. */
lsm_status lsm_dir_list_png(const char *dir, char ***paths, size_t *count, lsm_err *err);
void lsm_path_list_free(char **paths, size_t count);

/* ---- heights -------------------------------------------------------------- */

/* Parses a heights file: one number per line (blank lines and lines starting
 * with '#' are skipped; surrounding white space allowed; decimal or exponent
 * notation).  Each value must be finite and strictly greater than the one
 * before.  On success *z is malloc'd with *count values. */
lsm_status lsm_heights_parse(const char *text, size_t length, const char *name,
                             double **z, size_t *count, lsm_err *err);
lsm_status lsm_heights_read(const char *path, double **z, size_t *count, lsm_err *err);

/* ---- NRRD ------------------------------------------------------------------ */

typedef struct lsm_nrrd_writer lsm_nrrd_writer;

/* Opens path and writes a provisional NRRD header for a float volume of
 * nx x ny x (unknown) slices, x fastest, little endian, raw encoding, with
 * spacings (sx, sy, sz) and origin (ox, oy, oz) in physical units, written as
 * "space directions" and "space origin" (the position of the first sample's
 * centre), which ITK, 3D Slicer and VTK read.  The slice
 * count and z spacing are fixed in place by lsm_nrrd_finish (the header has a
 * fixed length: a padding comment absorbs the difference). */
lsm_status lsm_nrrd_open(const char *path, int nx, int ny, double sx, double sy,
                         double sz, double ox, double oy, double oz,
                         lsm_nrrd_writer **out, lsm_err *err);
/* Appends one slice: nx*ny floats, row-major (x fastest), row 0 first. */
lsm_status lsm_nrrd_write_slice(lsm_nrrd_writer *w, const float *slice, lsm_err *err);
/* Number of slices written so far. */
size_t lsm_nrrd_slices(const lsm_nrrd_writer *w);
/* Rewrites the header with the final slice count and z spacing, flushes,
 * closes (checking every write and the close) and frees the writer. */
lsm_status lsm_nrrd_finish(lsm_nrrd_writer **w, double sz, lsm_err *err);
/* Closes without finishing (after an error); the file is left incomplete. */
void lsm_nrrd_abort(lsm_nrrd_writer **w);

/* ---- small helpers ----------------------------------------------------------- */

/* mkdir -p for one level; ok if it already exists as a folder. */
lsm_status lsm_make_dir(const char *path, lsm_err *err);
/* Reads a whole file into a malloc'd buffer (NUL-terminated); refuses files
 * larger than max_bytes. */
lsm_status lsm_read_file(const char *path, size_t max_bytes, char **data, size_t *length,
                         lsm_err *err);

#endif
