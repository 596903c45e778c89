/* lsm_io: everything lsmorph reads and writes on disk.
 *
 *   io_png.c      PNG slices in (any bit depth / colour type) and masks out (libpng)
 *   io_tiff.c     TIFF slices in (libtiff); lsm_slice_read_* pick PNG or TIFF by name
 *   io_dir.c      natural-order listing of the slice images (PNG, TIFF) of a folder
 *   io_heights.c  the heights text file
 *   io_nrrd.c     streaming NRRD volume writer (attached header, raw float LE)
 *   io_volume.c   streaming writer for every selected volume format at once
 *   io_mha.c      MetaImage header (volume.mha)
 *   io_vtk.c      legacy VTK header (volume.vtk)
 *   io_nifti.c    NIfTI-1 header (volume.nii, volume.nii.gz)
 *   io_gzip.c     streaming gzip whose first bytes are rewritten at the end
 *   io_raw.c      JSON sidecar of volume.raw
 *   io_json.c     JSON strings and numbers (run.json, scores, volume.json)
 *   io_exr.c      one OpenEXR file per slice (OpenEXRCore C API)
 *
 * Every function returns an lsm_status and records "<file>: <what>" in err.
 */
#ifndef LSM_IO_H
#define LSM_IO_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_names.h"
#include "solver/base/lsm_status.h"

/* ---- PNG ---------------------------------------------------------------- */

/* How a slice image (PNG or TIFF) becomes a mask. */
typedef struct lsm_image_read_opts {
  int invert;          /* 1: foreground is dark (luminance < 50 %) */
  uint64_t max_pixels; /* refuse images with more pixels (0 = no limit) */
  int nonzero;         /* 1: foreground is any non-zero luminance (label masks
                          stored as 0/1); with invert, exactly zero */
} lsm_image_read_opts;

/* Reads a PNG of any bit depth (1..16) and colour type (gray, gray+alpha, RGB,
 * RGBA, palette, with or without tRNS) into a binary mask.  A pixel is
 * foreground when its luminance (Rec. 709 weights on the stored values, after
 * compositing over black with its alpha) is >= 50 % of full scale, or < 50 %
 * with opts->invert.  The size is checked against opts->max_pixels from the
 * header, before any pixel buffer is allocated. */
lsm_status lsm_png_read_mask(const char *path, const lsm_image_read_opts *opts,
                             lsm_mask *out, lsm_err *err);

/* The same from an open stream positioned at the PNG signature (a file, a pipe,
 * or fmemopen() memory: the fuzzer uses that); name is used in messages.  The
 * stream is read but not closed. */
lsm_status lsm_png_read_mask_stream(FILE *fp, const char *name, const lsm_image_read_opts *opts,
                                    lsm_mask *out, lsm_err *err);

/* Reads only the header: width and height. */
lsm_status lsm_png_read_size(const char *path, int *width, int *height, lsm_err *err);
/* The same, refusing (LSM_ERR_LIMIT) an image of more than max_pixels pixels
 * (0 = no limit) as soon as the IHDR chunk is read, before the rest of the
 * header: a 200000 x 200000 header alone is refused with the limit message. */
lsm_status lsm_png_read_header(const char *path, uint64_t max_pixels, int *width, int *height,
                               lsm_err *err);

/* One row of 8- or 16-bit G, GA, RGB or RGBA samples (16-bit ones big
 * endian) to 0/1 by the rule of lsm_png_read_mask (opts' invert and
 * nonzero); the TIFF reader shares it. */
void lsm_mask_row_from_samples(const uint8_t *row, uint32_t width, int channels, int depth,
                               int invert, int nonzero, uint8_t *out);

/* The number of distinct non-zero values that fill regions of a PNG (a value
 * with a pixel whose four neighbours hold it too), read as gray of the file's
 * depth, counting up to 256 (io_levels.c).  For a note: a label map given
 * where masks are read. */
lsm_status lsm_png_count_levels(const char *path, unsigned *levels);

/* Writes an 8-bit grayscale PNG; pixels are width*height bytes, row-major. */
lsm_status lsm_png_write_gray8(const char *path, const uint8_t *pixels, int width,
                               int height, lsm_err *err);

/* Writes a mask as 8-bit grayscale PNG, 255 inside and 0 outside. */
lsm_status lsm_png_write_mask(const char *path, const lsm_mask *mask, lsm_err *err);

/* Writes an 8-bit RGB PNG; pixels are width*height*3 bytes. */
lsm_status lsm_png_write_rgb8(const char *path, const uint8_t *pixels, int width,
                              int height, lsm_err *err);

/* ---- TIFF ---------------------------------------------------------------- */

/* Reads a one-page TIFF into a binary mask by the rule of lsm_png_read_mask
 * (opts as there).  Gray (white or black is zero), gray + alpha, RGB and
 * RGBA in strips or tiles at 1, 8 or 16 bits a sample are read sample for
 * sample, so 16-bit label masks stored as 0/1 keep their values
 * (opts->nonzero); every other layout libtiff decodes (palette, YCbCr,
 * separate planes, 2 or 4 bits) is read as 8-bit RGBA.  The file is read,
 * not mapped.  Refused (LSM_ERR_INPUT, "corrupt TIFF: " and libtiff's
 * message): a file libtiff reports an error on, even one it recovers from,
 * or a warning on while decoding the pixels (a cut or garbled strip or tile,
 * a missing one).  Refused as well: several pages (one slice a file),
 * floating-point or signed samples, 16-bit samples in other layouts. */
lsm_status lsm_tiff_read_mask(const char *path, const lsm_image_read_opts *opts, lsm_mask *out,
                              lsm_err *err);
/* The same from an open, seekable stream positioned at the TIFF header
 * (fmemopen() memory: the fuzzer uses it); name is used in messages.  The
 * stream is read but not closed. */
lsm_status lsm_tiff_read_mask_stream(FILE *fp, const char *name, const lsm_image_read_opts *opts,
                                     lsm_mask *out, lsm_err *err);
/* Reads only the size, refusing (LSM_ERR_LIMIT) more than max_pixels pixels
 * (0 = no limit). */
lsm_status lsm_tiff_read_header(const char *path, uint64_t max_pixels, int *width, int *height,
                                lsm_err *err);

/* A slice image by its name (io_dir.c): .tif or .tiff (any case) through the TIFF
 * reader, anything else through the PNG reader. */
int lsm_is_tiff_name(const char *path);
/* Whether a file name ends like a slice image read: .png, .tif, .tiff (any
 * case; io_dir.c, with lsm_is_tiff_name). */
int lsm_is_slice_image_name(const char *path);
lsm_status lsm_slice_read_mask(const char *path, const lsm_image_read_opts *opts, lsm_mask *out,
                               lsm_err *err);
lsm_status lsm_slice_read_header(const char *path, uint64_t max_pixels, int *width, int *height,
                                 lsm_err *err);

/* ---- folders -------------------------------------------------------------- */

/* Natural order: digit runs compare by value ("2.png" < "10.png"), the rest
 * byte by byte; ties broken by plain strcmp so the order is total. */
int lsm_natural_cmp(const char *a, const char *b);

/* Lists the regular files of dir whose name ends in ".png", ".tif" or
 * ".tiff" (any case), in natural order, as full paths "dir/name".  Free with
 * lsm_path_list_free.  others (NULL: not counted): the regular files left out
 * whose names end like another image format (.jpg, .bmp, .pgm, .dcm, ...;
 * not hidden). */
lsm_status lsm_dir_list_slices(const char *dir, char ***paths, size_t *count, size_t *others,
                            lsm_err *err);
void lsm_path_list_free(char **paths, size_t count);

/* The part of path after its last '/' (path itself when it has none). */
const char *lsm_base_name(const char *path);

/* The number a slice's file name ends with: the last run of digits in the
 * base name of path before its extension ("slice_0009.png" -> 9, "12b.png"
 * -> 12).  Returns 1 with *number set, or 0 when the name has no digits or
 * a run longer than 18 of them (past what a 64-bit integer holds). */
int lsm_name_number(const char *path, uint64_t *number);

/* ---- heights -------------------------------------------------------------- */

/* Whether s is a number in decimal or exponent notation only: [sign] digits
 * [. digits] [e [sign] digits] (strtod alone also takes "nan", "inf" and
 * hexadecimal).  Shared by the heights file and the command line. */
int lsm_decimal_syntax(const char *s);

/* Parses a heights file: one number per line (blank lines are skipped, a
 * '#' starts a comment to the end of its line, a UTF-8 byte order mark is
 * ignored; surrounding white space allowed; decimal or exponent notation).
 * Each value must be finite and strictly greater than the one before.  On
 * success *z is malloc'd with *count values. */
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
/* Length of every NRRD header lsmorph writes: a padding comment absorbs the
 * difference between the provisional and the final header. */
#define LSM_NRRD_HEADER_BYTES 512

/* Builds the fixed-length NRRD header (and a NUL) into out: float32 little
 * endian (is_float) or uchar, encoding raw or gzip, sizes nx ny nz, space
 * directions and origin.  Returns LSM_NRRD_HEADER_BYTES, or 0 if cap is too
 * small. */
size_t lsm_nrrd_header(char *out, size_t cap, int is_float, int gzip, int nx, int ny, size_t nz,
                       double sx, double sy, double sz, double ox, double oy, double oz);

/* Checks the geometry every volume writer needs: positive slice size whose
 * byte count does not overflow, finite positive spacings, finite origin. */
lsm_status lsm_volume_check_geometry(const char *where, int nx, int ny, double sx, double sy,
                                     double sz, double ox, double oy, double oz, lsm_err *err);

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

/* Atomically exchanges two existing paths (Linux renameat2 RENAME_EXCHANGE):
 * 0, or -1 with errno (ENOSYS or EINVAL where the system or file system
 * cannot, and the caller must fall back to two renames). */
int lsm_rename_exchange(const char *a, const char *b);
/* mkdir -p for one level; ok if it already exists as a folder. */
lsm_status lsm_make_dir(const char *path, lsm_err *err);
/* Ends a file that was written: flushes it, checks its error flag, closes it
 * and sets *fp to NULL.  Returns st when st already is an error (the file is
 * still closed), else the first failure as "<path>: write failed: ...", else
 * LSM_OK.  Harmless when *fp is NULL (returns st). */
lsm_status lsm_close_written(FILE **fp, const char *path, lsm_status st, lsm_err *err);
/* Reads a whole file into a malloc'd buffer (NUL-terminated); refuses files
 * larger than max_bytes. */
lsm_status lsm_read_file(const char *path, size_t max_bytes, char **data, size_t *length,
                         lsm_err *err);

/* ---- volumes in several formats (io_volume.c, io_mha.c, io_vtk.c, io_raw.c, io_exr.c) ---- */

/* Output formats, as bits of a set. */
#define LSM_FORMAT_NRRD 0x01u /* volume.nrrd: attached header, raw little endian */
#define LSM_FORMAT_MHA 0x02u  /* volume.mha: MetaImage, ElementDataFile = LOCAL */
#define LSM_FORMAT_VTK 0x04u  /* volume.vtk: legacy BINARY STRUCTURED_POINTS, big endian */
#define LSM_FORMAT_EXR 0x08u  /* exr/00001.exr ...: one OpenEXR scanline file per slice */
#define LSM_FORMAT_RAW 0x10u  /* volume.raw + volume.json sidecar, little endian */
#define LSM_FORMAT_NII 0x20u  /* volume.nii: NIfTI-1 single file, little endian */
#define LSM_FORMAT_NII_GZ 0x40u /* volume.nii.gz: the same, gzip compressed */
#define LSM_FORMAT_ALL 0x7fu  /* the formats --format names */
/* volume.nrrd with encoding gzip (--nrrd-encoding gzip): in place of
 * LSM_FORMAT_NRRD in a writer's set, never with it; not a --format name. */
#define LSM_FORMAT_NRRD_GZ 0x80u
#define LSM_FORMATS_NIFTI (LSM_FORMAT_NII | LSM_FORMAT_NII_GZ) /* 16-bit sizes */

/* What the volume holds: the signed distance (float32, physical units,
 * negative inside) or a mask (uint8, 255 where phi <= 0, else 0; in EXR
 * files a half-float 1.0 / 0.0). */
#define LSM_VALUES_LIST(X)                                                      \
  X(LSM_VALUES_SDF, "sdf")   /* float32 signed distance */                      \
  X(LSM_VALUES_MASK, "mask") /* uint8 255 inside, 0 outside */
LSM_ENUM(lsm_values, LSM_VALUES, LSM_VALUES_LIST, lsm_values_name, lsm_values_from_name);

/* Name of one format bit ("nrrd"), or "unknown". */
const char *lsm_format_name(unsigned format);
/* Parses a comma-separated list ("nrrd,mha,vtk,exr,raw,nii,nii.gz", any order, repeats
 * allowed) into a set of LSM_FORMAT_* bits; LSM_ERR_USAGE on an empty list or
 * an unknown name. */
lsm_status lsm_format_list_parse(const char *list, unsigned *formats, lsm_err *err);
/* The names, relative to the output folder, of the files (folders end in '/')
 * the given formats write, in a fixed order; returns how many (at most 8),
 * storing at most cap of them in names. */
size_t lsm_volume_file_names(unsigned formats, const char **names, size_t cap);

/* Geometry and sample type of a volume: nx x ny x nz samples, x fastest,
 * sample (i, j, k) centred at (ox + i sx, oy + j sy, oz + k sz). */
typedef struct lsm_volume_info {
  int nx, ny;
  size_t nz;
  double sx, sy, sz;
  double ox, oy, oz;
  lsm_values values;
} lsm_volume_info;

/* Fixed-length headers: the length depends neither on nz nor on sz (those
 * are printed in fixed-width fields), so a header written with a provisional
 * slice count can be rewritten in place once the count is known.  Each writes
 * the header and a NUL into out and returns its length, or 0 if cap is too
 * small. */
size_t lsm_mha_header(char *out, size_t cap, const lsm_volume_info *info);
/* The spacings and origin of info as the headers print them: each in its
 * shortest round-trip form (0.8, not 0.80000000000000004). */
void lsm_volume_geometry_text(const lsm_volume_info *info, char spacing[3][32],
                              char origin[3][32]);
size_t lsm_vtk_header(char *out, size_t cap, const lsm_volume_info *info);

/* NIfTI-1 ("n+1", one file): the 348-byte header and the 4-byte extension
 * flag, little endian, samples from byte LSM_NIFTI_HEADER_BYTES on: float32
 * (DT_FLOAT32) for LSM_VALUES_SDF, uint8 (DT_UINT8) for LSM_VALUES_MASK.  The
 * qform and sform are diag(-sx, -sy, sz) with offset (-ox, -oy, oz): NIfTI's
 * world is RAS, and ITK and 3D Slicer, which work in LPS, place the volume
 * exactly where they place volume.nrrd and volume.mha.  Sizes are 16-bit in
 * NIfTI-1: returns 0 (nothing written) when nx, ny or nz passes
 * LSM_NIFTI_DIM_MAX or cap is short; else LSM_NIFTI_HEADER_BYTES.  No NUL is
 * added (the header is binary). */
#define LSM_NIFTI_HEADER_BYTES 352
#define LSM_NIFTI_DIM_MAX 32767
size_t lsm_nifti_header(unsigned char *out, size_t cap, const lsm_volume_info *info);

/* ---- gzip with a rewritable head (io_gzip.c) ------------------------------ */

/* A gzip file (RFC 1952, one member) written as a stream, whose first
 * head_bytes uncompressed bytes (at most 65535) are kept in a stored deflate
 * block at byte LSM_GZIP_HEAD_OFFSET of the member, so that finish can
 * replace them with a head of the same length (volume.nii.gz's header, with
 * the slice count known only at the end); the rest is deflated at level
 * (0..9).  prefix_bytes plain bytes come before the member, replaced at the
 * end the same way (volume.nrrd's text header with encoding gzip; 0 for a
 * plain gzip file).  Memory: zlib's state and a 64 KiB buffer. */
#define LSM_GZIP_HEAD_OFFSET 15
typedef struct lsm_gzip_writer lsm_gzip_writer;
lsm_status lsm_gzip_writer_open(const char *path, const unsigned char *prefix,
                                size_t prefix_bytes, const unsigned char *head, size_t head_bytes,
                                int level, lsm_gzip_writer **out, lsm_err *err);
/* Compresses and appends bytes after the head. */
lsm_status lsm_gzip_writer_write(lsm_gzip_writer *g, const void *data, size_t bytes,
                                 lsm_err *err);
/* Ends the deflate stream, writes the trailer, puts prefix and head (as long
 * as at open; NULL where that was 0) in place of the provisional ones, closes
 * the file (checking every write and the close) and frees the writer. */
lsm_status lsm_gzip_writer_finish(lsm_gzip_writer **g, const unsigned char *prefix,
                                  const unsigned char *head, lsm_err *err);
/* Closes and frees without finishing (after an error); harmless on NULL. */
void lsm_gzip_writer_abort(lsm_gzip_writer **g);

/* ---- JSON ---------------------------------------------------------------- */

/* A JSON string of s.  File names are bytes: a byte that is not part of
 * well-formed UTF-8 is written as the Latin-1 character of that value
 * (\u00XX), so the output is valid JSON for any name. */
void lsm_json_string(FILE *f, const char *s);
/* A JSON number: the shortest of 15, 16 or 17 significant digits that reads
 * back as v; null when v is not finite. */
void lsm_json_number(FILE *f, double v);

/* The shortest of %.15g, %.16g, %.17g that reads back as v ("50", "0.1"). */
void lsm_shortest_number(char *text, size_t size, double v);

/* Reads a number from a JSON document (text, NUL-terminated) by its member
 * path: keys[0] of the top-level object, keys[1] of that member's object,
 * and so on (count keys; a later duplicate wins).  The whole document is
 * checked against the JSON grammar (nesting up to 256 levels), so any
 * formatting reads alike.  Returns 1 and *value when the member is there and
 * a number, 0 when the document is valid but has no such number, -1 when it
 * is not valid JSON (*error_at: the byte offset where it stops being so). */
int lsm_json_find_number(const char *text, const char *const *keys, int count, double *value,
                         size_t *error_at);

/* The same for an array of numbers: returns 1 when the member is there and
 * an array whose elements are all numbers, with *n its length and its first
 * min(n, capacity) elements in values (values may be NULL with capacity 0, to
 * learn n); 0 when the document is valid but has no such array (*n = 0); -1
 * when it is not valid JSON. */
int lsm_json_find_numbers(const char *text, const char *const *keys, int count, double *values,
                          size_t capacity, size_t *n, size_t *error_at);

/* The same for an array of strings (run.json's input.files): raw[i] points
 * into text at the bytes between element i's quotes, raw_lengths[i] bytes,
 * escapes unresolved (lsm_json_unescape resolves them); raw and raw_lengths
 * may be NULL with capacity 0, to learn n. */
int lsm_json_find_strings(const char *text, const char *const *keys, int count, const char **raw,
                          size_t *raw_lengths, size_t capacity, size_t *n, size_t *error_at);

/* The same for one string (run.json's lsmorph_version): *raw points into
 * text at the bytes between its quotes, *raw_length bytes, escapes
 * unresolved; either may be NULL. */
int lsm_json_find_string(const char *text, const char *const *keys, int count, const char **raw,
                         size_t *raw_length, size_t *error_at);

/* The same for true or false (run.json's options.invert): *value 1 or 0. */
int lsm_json_find_bool(const char *text, const char *const *keys, int count, int *value,
                       size_t *error_at);

/* Resolves the escapes of a JSON string's raw bytes (length of them) into
 * out, which must hold length + 1 bytes (nothing grows); NUL-terminated.  As
 * lsm_json_string writes file names, \u0001 to \u00ff are the bytes of those
 * values; a higher code point is written as UTF-8.  Returns the length, or
 * (size_t)-1 on a malformed escape, a lone surrogate or \u0000 (no C
 * string holds it). */
size_t lsm_json_unescape(const char *raw, size_t length, char *out);

/* Writes the JSON sidecar of a raw volume (sizes, spacing, origin, dtype,
 * endianness, data file name). */
lsm_status lsm_raw_write_json(const char *path, const char *data_file,
                              const lsm_volume_info *info, lsm_err *err);

/* Writes one slice (info->nx x info->ny values of phi, row 0 first) as a
 * single-channel ("Y") scanline OpenEXR file, ZIP compressed: float32 phi
 * for LSM_VALUES_SDF, half 1.0 (phi <= 0) / 0.0 for LSM_VALUES_MASK.  The
 * header carries the pixel size ("pixelSize", v2d: sx, sy), the slice height
 * ("sliceHeight", double), the slice number ("sliceIndex", int, from 1) and
 * "values" ("sdf" or "mask"); pixelAspectRatio is sx / sy. */
lsm_status lsm_exr_write_slice(const char *path, const float *phi, const lsm_volume_info *info,
                               double z, size_t index, lsm_err *err);

/* A streaming writer for every selected format at once: slices go out as
 * they come (memory: a few slices), headers with the slice count are fixed
 * at the end. */
typedef struct lsm_volume_writer lsm_volume_writer;

/* Creates dir/volume.<ext> for each selected format (and dir/exr/ for EXR)
 * for nx x ny slices with pixel spacings sx, sy, provisional slice spacing
 * sz and first-sample origin (ox, oy, oz).  With LSM_FORMAT_NII or _NII_GZ, nx and ny
 * above LSM_NIFTI_DIM_MAX are refused here (LSM_ERR_LIMIT) and a slice past
 * that count by lsm_volume_writer_write_slice. */
lsm_status lsm_volume_writer_open(const char *dir, unsigned formats, lsm_values values, int nx,
                                  int ny, double sx, double sy, double sz, double ox, double oy,
                                  double oz, lsm_volume_writer **out, lsm_err *err);
/* Appends one slice: nx*ny floats of phi (row-major, row 0 first) at height z. */
lsm_status lsm_volume_writer_write_slice(lsm_volume_writer *w, const float *phi, double z,
                                         lsm_err *err);
/* Number of slices written so far. */
size_t lsm_volume_writer_slices(const lsm_volume_writer *w);
/* Fixes every header with the final z spacing sz and slice count (which must
 * equal the number of slices written), writes the raw sidecar, closes every
 * file (checking each write and close) and frees the writer. */
lsm_status lsm_volume_writer_finish(lsm_volume_writer **w, double sz, size_t count,
                                    lsm_err *err);
/* Closes everything without finishing (after an error); harmless on NULL. */
void lsm_volume_writer_abort(lsm_volume_writer **w);

#endif
