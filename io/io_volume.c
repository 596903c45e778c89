/* io_volume: one streaming writer for every selected volume format.
 *
 *   nrrd  volume.nrrd  float: io_nrrd.c as before; mask: a uchar NRRD with the
 *                      same fixed 512-byte header layout (written here); with
 *                      --nrrd-encoding gzip (LSM_FORMAT_NRRD_GZ) either one is
 *                      the header, then the samples as one gzip member
 *                      (io_gzip.c, the header a rewritable prefix)
 *   mha   volume.mha   MetaImage header (io_mha.c) + samples, little endian
 *   vtk   volume.vtk   legacy VTK header (io_vtk.c) + samples, big endian
 *   raw   volume.raw   samples only, little endian; volume.json at the end
 *   nii   volume.nii   NIfTI-1 header (io_nifti.c) + samples, little endian
 *   nii.gz volume.nii.gz the same through io_gzip.c (header stored, samples
 *                      deflated; the header is rewritten in place at the end)
 *   exr   exr/NNNNN.exr one OpenEXR file per slice (io_exr.c)
 *
 * Each slice is converted once per sample encoding and appended to every file
 * that uses it; memory is a few slices whatever the slice count.  The headers
 * with a slice count have a fixed length: they are written with a provisional
 * count at open and rewritten in place by lsm_volume_writer_finish.
 */
#include "io/lsm_io.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- names --------------------------------------------------------------------------- */

LSM_NAME_FUNCTIONS(lsm_values, LSM_VALUES_LIST, lsm_values_name, lsm_values_from_name)

typedef struct format_entry {
  unsigned bit;
  const char *name;
} format_entry;

static const format_entry formats_known[] = {{LSM_FORMAT_NRRD, "nrrd"},
                                              {LSM_FORMAT_MHA, "mha"},
                                              {LSM_FORMAT_VTK, "vtk"},
                                              {LSM_FORMAT_EXR, "exr"},
                                              {LSM_FORMAT_RAW, "raw"},
                                              {LSM_FORMAT_NII, "nii"},
                                              {LSM_FORMAT_NII_GZ, "nii.gz"}};
#define FORMAT_COUNT (sizeof formats_known / sizeof formats_known[0])

const char *lsm_format_name(unsigned format) {
  for (size_t k = 0; k < FORMAT_COUNT; ++k)
    if (formats_known[k].bit == format) return formats_known[k].name;
  return "unknown";
}

lsm_status lsm_format_list_parse(const char *list, unsigned *formats, lsm_err *err) {
  if (!list || !formats) return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "bad arguments to parse formats");
  unsigned set = 0;
  const char *p = list;
  for (;;) {
    const char *end = strchr(p, ',');
    size_t len = end ? (size_t)(end - p) : strlen(p);
    unsigned bit = 0;
    for (size_t k = 0; k < FORMAT_COUNT; ++k)
      if (strlen(formats_known[k].name) == len && strncmp(p, formats_known[k].name, len) == 0)
        bit = formats_known[k].bit;
    if (!bit) {
      if (len == 0)
        return lsm_fail(err, LSM_ERR_USAGE, NULL, "--format: empty name in '%s'", list);
      return lsm_fail(err, LSM_ERR_USAGE, NULL,
                      "--format: '%.*s' is not one of nrrd, mha, vtk, nii, nii.gz, exr, raw", (int)(len > 64 ? 64 : len), p);
    }
    set |= bit;
    if (!end) break;
    p = end + 1;
  }
  *formats = set;
  return LSM_OK;
}

/* The files each format writes, in the order run.json lists them; a stream
 * format's sample file comes first (volume.raw before volume.json). */
static const struct {
  unsigned bit;
  const char *file;
} files[] = {{LSM_FORMAT_NRRD, "volume.nrrd"}, {LSM_FORMAT_NRRD_GZ, "volume.nrrd"},
             {LSM_FORMAT_MHA, "volume.mha"},
             {LSM_FORMAT_VTK, "volume.vtk"},   {LSM_FORMAT_NII, "volume.nii"},
             {LSM_FORMAT_NII_GZ, "volume.nii.gz"}, {LSM_FORMAT_RAW, "volume.raw"},
             {LSM_FORMAT_RAW, "volume.json"},  {LSM_FORMAT_EXR, "exr/"}};

/* The sample file of a stream format (one of nrrd, mha, vtk, nii, nii.gz, raw;
 * nrrd with gzip). */
static const char *stream_file_name(unsigned format) {
  for (size_t k = 0; k < sizeof files / sizeof files[0]; ++k)
    if (files[k].bit == format) return files[k].file;
  return NULL;
}

size_t lsm_volume_file_names(unsigned formats, const char **names, size_t cap) {
  size_t n = 0;
  for (size_t k = 0; k < sizeof files / sizeof files[0]; ++k) {
    if (!(formats & files[k].bit)) continue;
    if (names && n < cap) names[n] = files[k].file;
    n++;
  }
  return n;
}

void lsm_volume_geometry_text(const lsm_volume_info *info, char spacing[3][32],
                              char origin[3][32]) {
  const double sv[3] = {info->sx, info->sy, info->sz}, ov[3] = {info->ox, info->oy, info->oz};
  for (int k = 0; k < 3; ++k) {
    lsm_shortest_number(spacing[k], sizeof spacing[k], sv[k]);
    lsm_shortest_number(origin[k], sizeof origin[k], ov[k]);
  }
}

/* ---- the NRRD header of a stream (a uchar mask, or gzip): io_nrrd.c builds it -------------- */

static size_t nrrd_stream_header(char *out, size_t cap, const lsm_volume_info *v, int gzip) {
  return lsm_nrrd_header(out, cap, v->values == LSM_VALUES_SDF, gzip, v->nx, v->ny, v->nz, v->sx,
                         v->sy, v->sz, v->ox, v->oy, v->oz);
}

/* ---- the writer ------------------------------------------------------------------------- */

typedef enum sample_enc { ENC_F32_LE, ENC_F32_BE, ENC_U8, ENC_COUNT } sample_enc;

typedef struct vol_stream {
  unsigned format;
  char *path;
  FILE *fp;
  size_t header_bytes;   /* fixed header length (0: raw) */
  sample_enc enc;
  lsm_nrrd_writer *nrrd; /* float NRRD goes through io_nrrd.c */
  lsm_gzip_writer *gz;   /* volume.nii.gz and gzip NRRD go through io_gzip.c */
} vol_stream;

struct lsm_volume_writer {
  char *dir;
  unsigned formats;
  lsm_volume_info info;
  vol_stream streams[7];
  int nstreams;
  size_t samples;                 /* nx * ny */
  unsigned char *buf[ENC_COUNT];  /* one converted slice per encoding in use */
  size_t slices;
  int failed;                     /* a write failed: finish refuses */
};

/* The NIfTI file named in a limit message. */
static const char *nifti_file(unsigned formats) {
  return (formats & LSM_FORMAT_NII) ? "volume.nii" : "volume.nii.gz";
}

static int finite_positive(double v) { return isfinite(v) && v > 0.0; }

static char *join_path(const char *dir, const char *name) {
  size_t a = strlen(dir), b = strlen(name);
  char *p = malloc(a + b + 2);
  if (!p) return NULL;
  memcpy(p, dir, a);
  p[a] = '/';
  memcpy(p + a + 1, name, b + 1);
  return p;
}

static size_t stream_header(const vol_stream *s, const lsm_volume_info *info, char *out,
                            size_t cap) {
  switch (s->format) {
  case LSM_FORMAT_NRRD: return nrrd_stream_header(out, cap, info, 0);
  case LSM_FORMAT_NRRD_GZ: return nrrd_stream_header(out, cap, info, 1);
  case LSM_FORMAT_MHA: return lsm_mha_header(out, cap, info);
  case LSM_FORMAT_VTK: return lsm_vtk_header(out, cap, info);
  case LSM_FORMAT_NII:
  case LSM_FORMAT_NII_GZ: return lsm_nifti_header((unsigned char *)out, cap, info);
  default: return 0;
  }
}

#define HEADER_CAP 2048
/* zlib level of volume.nii.gz and of a gzip volume.nrrd: 1, as nibabel
 * writes; see validation/README.md (output sizes and times) */
#define GZIP_LEVEL 1

static lsm_status stream_open(lsm_volume_writer *w, unsigned format, lsm_err *err) {
  vol_stream *s = &w->streams[w->nstreams];
  memset(s, 0, sizeof *s);
  s->format = format;
  const int mask = w->info.values == LSM_VALUES_MASK;
  const char *name = stream_file_name(format);
  s->enc = mask ? ENC_U8 : format == LSM_FORMAT_VTK ? ENC_F32_BE : ENC_F32_LE;
  s->path = join_path(w->dir, name);
  if (!s->path) return lsm_fail(err, LSM_ERR_NOMEM, w->dir, "cannot allocate a file name");
  w->nstreams++;
  const lsm_volume_info *v = &w->info;
  if (format == LSM_FORMAT_NRRD && !mask)
    return lsm_nrrd_open(s->path, v->nx, v->ny, v->sx, v->sy, v->sz, v->ox, v->oy, v->oz,
                         &s->nrrd, err);
  char header[HEADER_CAP];
  if (format != LSM_FORMAT_RAW) {
    s->header_bytes = stream_header(s, v, header, sizeof header);
    if (s->header_bytes == 0)
      return lsm_fail(err, LSM_ERR_INTERNAL, s->path, "header does not fit in %d bytes", HEADER_CAP);
  }
  if (format == LSM_FORMAT_NII_GZ)
    return lsm_gzip_writer_open(s->path, NULL, 0, (const unsigned char *)header, s->header_bytes,
                                GZIP_LEVEL, &s->gz, err);
  if (format == LSM_FORMAT_NRRD_GZ)
    return lsm_gzip_writer_open(s->path, (const unsigned char *)header, s->header_bytes, NULL, 0,
                                GZIP_LEVEL, &s->gz, err);
  s->fp = fopen(s->path, "wb");
  if (!s->fp) return lsm_fail(err, LSM_ERR_IO, s->path, "cannot create: %s", strerror(errno));
  if (s->header_bytes && fwrite(header, 1, s->header_bytes, s->fp) != s->header_bytes)
    return lsm_fail(err, LSM_ERR_IO, s->path, "write failed: %s", strerror(errno));
  return LSM_OK;
}

lsm_status lsm_volume_writer_open(const char *dir, unsigned formats, lsm_values values, int nx,
                                  int ny, double sx, double sy, double sz, double ox, double oy,
                                  double oz, lsm_volume_writer **out, lsm_err *err) {
  if (out) *out = NULL;
  if (!dir || !out) return lsm_fail(err, LSM_ERR_INTERNAL, dir, "bad arguments to the volume writer");
  if (formats == 0 || (formats & ~(LSM_FORMAT_ALL | LSM_FORMAT_NRRD_GZ)) ||
      ((formats & LSM_FORMAT_NRRD) && (formats & LSM_FORMAT_NRRD_GZ)))
    return lsm_fail(err, LSM_ERR_INTERNAL, dir, "bad format set 0x%x", formats);
  if (values != LSM_VALUES_SDF && values != LSM_VALUES_MASK)
    return lsm_fail(err, LSM_ERR_INTERNAL, dir, "bad value kind %d", (int)values);
  LSM_TRY(lsm_volume_check_geometry(dir, nx, ny, sx, sy, sz, ox, oy, oz, err));
  if ((formats & LSM_FORMATS_NIFTI) && (nx > LSM_NIFTI_DIM_MAX || ny > LSM_NIFTI_DIM_MAX))
    return lsm_fail(err, LSM_ERR_LIMIT, dir,
                    "%s: NIfTI-1 holds at most %d samples along an axis, the slices are "
                    "%dx%d (choose another --format)", nifti_file(formats), LSM_NIFTI_DIM_MAX, nx, ny);
  const size_t bytes = (size_t)nx * (size_t)ny * 4;

  lsm_volume_writer *w = calloc(1, sizeof *w);
  if (!w) return lsm_fail(err, LSM_ERR_NOMEM, dir, "cannot allocate the volume writer");
  size_t dl = strlen(dir);
  w->dir = malloc(dl + 1);
  if (!w->dir) {
    free(w);
    return lsm_fail(err, LSM_ERR_NOMEM, dir, "cannot allocate the volume writer");
  }
  memcpy(w->dir, dir, dl + 1);
  w->formats = formats;
  w->samples = (size_t)nx * (size_t)ny;
  lsm_volume_info *v = &w->info;
  v->nx = nx;
  v->ny = ny;
  v->nz = 0;
  v->sx = sx;
  v->sy = sy;
  v->sz = sz;
  v->ox = ox;
  v->oy = oy;
  v->oz = oz;
  v->values = values;

  lsm_status st = LSM_OK;
  static const unsigned order[] = {LSM_FORMAT_NRRD, LSM_FORMAT_NRRD_GZ, LSM_FORMAT_MHA,
                                   LSM_FORMAT_VTK,  LSM_FORMAT_NII,     LSM_FORMAT_NII_GZ,
                                   LSM_FORMAT_RAW};
  for (size_t k = 0; st == LSM_OK && k < sizeof order / sizeof order[0]; ++k)
    if (formats & order[k]) st = stream_open(w, order[k], err);
  for (int k = 0; st == LSM_OK && k < w->nstreams; ++k) {
    vol_stream *s = &w->streams[k];
    if (s->nrrd || w->buf[s->enc]) continue;
    w->buf[s->enc] = malloc(s->enc == ENC_U8 ? w->samples : bytes);
    if (!w->buf[s->enc])
      st = lsm_fail(err, LSM_ERR_NOMEM, s->path, "cannot allocate %zu bytes for a slice", bytes);
  }
  if (st == LSM_OK && (formats & LSM_FORMAT_EXR)) {
    char *exr = join_path(dir, "exr");
    if (!exr)
      st = lsm_fail(err, LSM_ERR_NOMEM, dir, "cannot allocate a file name");
    else
      st = lsm_make_dir(exr, err);
    free(exr);
  }
  if (st != LSM_OK) {
    lsm_volume_writer_abort(&w);
    return st;
  }
  *out = w;
  return LSM_OK;
}

static void encode(sample_enc enc, const float *phi, size_t n, unsigned char *b) {
  switch (enc) {
  case ENC_U8:
    for (size_t k = 0; k < n; ++k) b[k] = phi[k] <= 0.0f ? 255 : 0;
    break;
  case ENC_F32_LE:
  case ENC_F32_BE:
    for (size_t k = 0; k < n; ++k) {
      uint32_t u;
      memcpy(&u, &phi[k], sizeof u);
      unsigned char *o = b + 4 * k;
      if (enc == ENC_F32_LE) {
        o[0] = (unsigned char)(u & 0xffu);
        o[1] = (unsigned char)((u >> 8) & 0xffu);
        o[2] = (unsigned char)((u >> 16) & 0xffu);
        o[3] = (unsigned char)((u >> 24) & 0xffu);
      } else {
        o[0] = (unsigned char)((u >> 24) & 0xffu);
        o[1] = (unsigned char)((u >> 16) & 0xffu);
        o[2] = (unsigned char)((u >> 8) & 0xffu);
        o[3] = (unsigned char)(u & 0xffu);
      }
    }
    break;
  default:
    break;
  }
}

lsm_status lsm_volume_writer_write_slice(lsm_volume_writer *w, const float *phi, double z,
                                         lsm_err *err) {
  if (!w || !phi)
    return lsm_fail(err, LSM_ERR_INTERNAL, w ? w->dir : NULL, "bad arguments to write a slice");
  if (w->failed) return lsm_fail(err, LSM_ERR_IO, w->dir, "an earlier write failed");
  if ((w->formats & LSM_FORMATS_NIFTI) && w->slices >= LSM_NIFTI_DIM_MAX) {
    w->failed = 1;
    return lsm_fail(err, LSM_ERR_LIMIT, w->dir,
                    "%s: NIfTI-1 holds at most %d slices, and a slice more came "
                    "(choose another --format)", nifti_file(w->formats), LSM_NIFTI_DIM_MAX);
  }
  int done[ENC_COUNT] = {0};
  for (int k = 0; k < w->nstreams; ++k) {
    vol_stream *s = &w->streams[k];
    lsm_status st = LSM_OK;
    if (s->nrrd) {
      st = lsm_nrrd_write_slice(s->nrrd, phi, err);
    } else {
      if (!done[s->enc]) {
        encode(s->enc, phi, w->samples, w->buf[s->enc]);
        done[s->enc] = 1;
      }
      size_t bytes = s->enc == ENC_U8 ? w->samples : 4 * w->samples;
      if (s->gz)
        st = lsm_gzip_writer_write(s->gz, w->buf[s->enc], bytes, err);
      else if (fwrite(w->buf[s->enc], 1, bytes, s->fp) != bytes)
        st = lsm_fail(err, LSM_ERR_IO, s->path, "write failed: %s", strerror(errno));
    }
    if (st != LSM_OK) {
      w->failed = 1;
      return st;
    }
  }
  if (w->formats & LSM_FORMAT_EXR) {
    char name[64];
    snprintf(name, sizeof name, "exr/%05zu.exr", w->slices + 1);
    char *path = join_path(w->dir, name);
    lsm_status st = path ? lsm_exr_write_slice(path, phi, &w->info, z, w->slices + 1, err)
                         : lsm_fail(err, LSM_ERR_NOMEM, w->dir, "cannot allocate a file name");
    free(path);
    if (st != LSM_OK) {
      w->failed = 1;
      return st;
    }
  }
  w->slices++;
  return LSM_OK;
}

size_t lsm_volume_writer_slices(const lsm_volume_writer *w) { return w ? w->slices : 0; }

/* Rewrites the fixed-length header of s for the final info and closes it. */
static lsm_status stream_finish(vol_stream *s, const lsm_volume_info *info, lsm_err *err) {
  lsm_status st = LSM_OK;
  if (s->header_bytes) {
    char header[HEADER_CAP];
    size_t len = stream_header(s, info, header, sizeof header);
    if (len != s->header_bytes)
      st = lsm_fail(err, LSM_ERR_INTERNAL, s->path, "header length changed (%zu, was %zu bytes)",
                    len, s->header_bytes);
    else if (s->gz && s->format == LSM_FORMAT_NRRD_GZ)
      st = lsm_gzip_writer_finish(&s->gz, (const unsigned char *)header, NULL, err);
    else if (s->gz)
      st = lsm_gzip_writer_finish(&s->gz, NULL, (const unsigned char *)header, err);
    else if (fseek(s->fp, 0, SEEK_SET) != 0 || fwrite(header, 1, len, s->fp) != len)
      st = lsm_fail(err, LSM_ERR_IO, s->path, "write failed: %s", strerror(errno));
  }
  return lsm_close_written(&s->fp, s->path, st, err); /* gzip: closed above, fp NULL */
}

lsm_status lsm_volume_writer_finish(lsm_volume_writer **wp, double sz, size_t count,
                                    lsm_err *err) {
  if (!wp || !*wp) return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "volume writer is not open");
  lsm_volume_writer *w = *wp;
  lsm_status st = LSM_OK;
  if (w->failed)
    st = lsm_fail(err, LSM_ERR_IO, w->dir, "an earlier write failed");
  else if (w->slices == 0)
    st = lsm_fail(err, LSM_ERR_INPUT, w->dir, "no slices were written");
  else if (count != w->slices)
    st = lsm_fail(err, LSM_ERR_INTERNAL, w->dir, "%zu slices announced, %zu written", count,
                  w->slices);
  else if (!finite_positive(sz))
    st = lsm_fail(err, LSM_ERR_INPUT, w->dir, "z spacing %g must be finite and positive", sz);
  if (st != LSM_OK) {
    lsm_volume_writer_abort(wp);
    return st;
  }
  w->info.nz = w->slices;
  w->info.sz = sz;
  for (int k = 0; k < w->nstreams; ++k) {
    vol_stream *s = &w->streams[k];
    lsm_status r;
    if (s->nrrd)
      r = lsm_nrrd_finish(&s->nrrd, sz, err);
    else
      r = stream_finish(s, &w->info, err);
    if (r == LSM_OK && s->format == LSM_FORMAT_RAW) {
      char *json = join_path(w->dir, "volume.json");
      r = json ? lsm_raw_write_json(json, "volume.raw", &w->info, err)
               : lsm_fail(err, LSM_ERR_NOMEM, w->dir, "cannot allocate a file name");
      free(json);
    }
    if (r != LSM_OK && st == LSM_OK) st = r;
  }
  lsm_volume_writer_abort(wp);
  return st;
}

void lsm_volume_writer_abort(lsm_volume_writer **wp) {
  if (!wp || !*wp) return;
  lsm_volume_writer *w = *wp;
  for (int k = 0; k < w->nstreams; ++k) {
    vol_stream *s = &w->streams[k];
    lsm_nrrd_abort(&s->nrrd);
    lsm_gzip_writer_abort(&s->gz);
    if (s->fp) fclose(s->fp);
    free(s->path);
  }
  for (int k = 0; k < ENC_COUNT; ++k) free(w->buf[k]);
  free(w->dir);
  free(w);
  *wp = NULL;
}
