/* io_labels_nifti: NIfTI-1 and NIfTI-2 label volumes (.nii, .nii.gz) through
 * nifticlib (Debian libnifti2-dev), which reads either version.
 *
 * nifticlib parses, validates and byte-swaps; its own writer does not report a
 * failed data write or close, so lsmorph builds the header with nifticlib
 * (nifti_convert_nim2n*hdr) and writes the header, the extensions and the
 * samples itself, checking every write.
 *
 * World coordinates: NIfTI's are RAS; lsm_label_file holds LPS (x and y
 * negated), as 3D Slicer and ITK read a NIfTI affine.  The affine is the
 * sform where its code is set, else the qform, else the voxel sizes (method 1),
 * as nibabel reads it. */
#include "io/io_labels_impl.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <nifti2_io.h>
#include <zlib.h>

static nifti_image *nim_of(const lsm_label_file *f) { return (nifti_image *)f->native; }

static lsm_voxel_type voxel_type_of(int datatype) {
  switch (datatype) {
  case DT_UINT8: return LSM_VOXEL_U8;
  case DT_INT8: return LSM_VOXEL_I8;
  case DT_UINT16: return LSM_VOXEL_U16;
  case DT_INT16: return LSM_VOXEL_I16;
  case DT_UINT32: return LSM_VOXEL_U32;
  case DT_INT32: return LSM_VOXEL_I32;
  case DT_UINT64: return LSM_VOXEL_U64;
  case DT_INT64: return LSM_VOXEL_I64;
  case DT_FLOAT32: return LSM_VOXEL_F32;
  case DT_FLOAT64: return LSM_VOXEL_F64;
  default: return LSM_VOXEL_UNKNOWN;
  }
}

static int datatype_of(lsm_voxel_type type) {
  static const int codes[] = {DT_UINT8,  DT_INT8,  DT_UINT16, DT_INT16,   DT_UINT32,
                              DT_INT32,  DT_UINT64, DT_INT64, DT_FLOAT32, DT_FLOAT64};
  return (int)type >= 0 && (int)type < (int)(sizeof codes / sizeof *codes) ? codes[type]
                                                                           : DT_UNKNOWN;
}

/* An integer of `bytes` bytes at p, little endian or not. */
static int64_t int_at(const unsigned char *p, int bytes, int little) {
  uint64_t u = 0;
  for (int k = 0; k < bytes; ++k) u |= (uint64_t)p[little ? k : bytes - 1 - k] << (8 * k);
  if (bytes < 8 && (u >> (8 * bytes - 1))) u |= ~(uint64_t)0 << (8 * bytes); /* sign */
  return (int64_t)u;
}

/* Reads the first bytes of the header (through zlib: plain or gzip) and
 * checks what nifticlib 3.0.1 trusts: the header size says NIfTI-1 (348) or
 * NIfTI-2 (540) in either byte order, and dim[0], the dimension count that it
 * loops over its fixed arrays with, lies in 1 .. 7 (a larger one overran its
 * stack).  *version: 1 or 2. */
static lsm_status nifti_precheck(const char *path, int *version, double *vox_offset,
                                 lsm_err *err) {
  gzFile gz = gzopen(path, "rb");
  unsigned char h[540];
  const int got = gz ? gzread(gz, h, sizeof h) : -1;
  int zerr = Z_OK;
  if (gz) gzerror(gz, &zerr);
  if (gz) gzclose(gz);
  if (zerr == Z_DATA_ERROR)
    return lsm_fail(err, LSM_ERR_INPUT, path, "cannot read: its compressed data is damaged");
  if (got < 348) return lsm_fail(err, LSM_ERR_INPUT, path, "cannot read: too short for a NIfTI header");
  const int64_t le = int_at(h, 4, 1), be = int_at(h, 4, 0);
  *version = le == 540 || be == 540 ? 2 : 1;
  const int little = *version == 2 ? le == 540 : le == 348;
  if (!(le == 348 || be == 348 || le == 540 || be == 540))
    return lsm_fail(err, LSM_ERR_INPUT, path,
                    "cannot read: not a NIfTI-1 or NIfTI-2 file (its header size is %lld)",
                    (long long)le);
  if (*version == 2 && got < 540)
    return lsm_fail(err, LSM_ERR_INPUT, path, "cannot read: too short for a NIfTI-2 header");
  const int64_t dims = *version == 2 ? int_at(h + 16, 8, little) : int_at(h + 40, 2, little);
  if (dims < 1 || dims > 7)
    return lsm_fail(err, LSM_ERR_INPUT, path, "damaged header: %lld dimensions (dim[0])",
                    (long long)dims);
  for (int64_t d = 1; d <= dims; ++d) { /* (nifticlib prints its own message for these) */
    const int64_t n = *version == 2 ? int_at(h + 16 + 8 * d, 8, little) : int_at(h + 40 + 2 * d, 2, little);
    if (n < 1)
      return lsm_fail(err, LSM_ERR_INPUT, path, "damaged header: dimension %lld has size %lld",
                      (long long)d, (long long)n);
  }
  if (*version == 2) {
    *vox_offset = (double)int_at(h + 168, 8, little);
  } else {
    const int64_t bits = int_at(h + 108, 4, little);
    uint32_t u = (uint32_t)bits;
    float x;
    memcpy(&x, &u, sizeof x);
    *vox_offset = x;
  }
  /* the voxel sizes, where the affine is made of them (no sform): nifticlib
   * takes a NaN or infinite one as 1 without a word */
  const int64_t sform = *version == 2 ? int_at(h + 348, 4, little) : int_at(h + 254, 2, little);
  for (int a = 0; a < 3 && sform <= 0; ++a) {
    double size;
    if (*version == 2) {
      const uint64_t u = (uint64_t)int_at(h + 112 + 8 * a, 8, little);
      memcpy(&size, &u, sizeof size);
    } else {
      const uint32_t u = (uint32_t)int_at(h + 80 + 4 * a, 4, little);
      float x;
      memcpy(&x, &u, sizeof x);
      size = x;
    }
    if (!isfinite(size))
      return lsm_fail(err, LSM_ERR_INPUT, path, "the voxel spacing along %c is %g (pixdim[%d]): "
                      "not a length", "ijk"[a], size, a + 1);
  }
  const int datatype = (int)int_at(h + (*version == 2 ? 12 : 70), 2, little);
  if (voxel_type_of(datatype) == LSM_VOXEL_UNKNOWN)
    return lsm_fail(err, LSM_ERR_INPUT, path,
                    "not a label map: its samples are %s (labels are integers, or floats "
                    "holding whole numbers)",
                    nifti_datatype_string(datatype));
  return LSM_OK;
}

/* Index to RAS world as the header says it (see the file comment). */
static void ras_affine(const nifti_image *nim, double m[3][4]) {
  const nifti_dmat44 *x = nim->sform_code > 0 ? &nim->sto_xyz
                          : nim->qform_code > 0 ? &nim->qto_xyz
                                                : NULL;
  memset(m, 0, 12 * sizeof(double));
  if (x) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) m[r][c] = x->m[r][c];
    return;
  }
  m[0][0] = nim->dx;
  m[1][1] = nim->dy;
  m[2][2] = nim->dz;
}

/* nifticlib sets NaN and Inf float samples to 0 as it loads them: they are put
 * back from the file, so that the label-map check (lsm_labels_to_integer)
 * refuses them as it does in NRRD files, instead of a damaged voxel becoming
 * background. */
static lsm_status restore_nonfinite(lsm_label_file *f, const nifti_image *nim, lsm_err *err) {
  const lsm_voxels *v = &f->vox;
  if (v->type != LSM_VOXEL_F32 && v->type != LSM_VOXEL_F64) return LSM_OK;
  const size_t size = lsm_voxel_size(v->type), count = v->n[0] * v->n[1] * v->n[2];
  gzFile gz = gzopen(f->path, "rb");
  if (!gz || nim->iname_offset < 0 || gzseek(gz, (z_off_t)nim->iname_offset, SEEK_SET) < 0) {
    if (gz) gzclose(gz);
    return lsm_fail(err, LSM_ERR_INPUT, f->path, "cannot read the samples again");
  }
  const int swap = nim->byteorder != nifti_short_order();
  unsigned char buf[1 << 16];
  lsm_status st = LSM_OK;
  for (size_t done = 0; st == LSM_OK && done < count;) {
    const size_t n = count - done < sizeof buf / size ? count - done : sizeof buf / size;
    if (gzread(gz, buf, (unsigned)(n * size)) != (int)(n * size)) {
      st = lsm_fail(err, LSM_ERR_INPUT, f->path, "cannot read the samples again: truncated");
      break;
    }
    if (swap) nifti_swap_Nbytes((int64_t)n, (int)size, buf);
    for (size_t k = 0; k < n; ++k) {
      float x32;
      double x64;
      if (size == 4) memcpy(&x32, buf + k * size, size);
      else memcpy(&x64, buf + k * size, size);
      if (!isfinite(size == 4 ? (double)x32 : x64))
        memcpy((unsigned char *)v->data + (done + k) * size, buf + k * size, size);
    }
    done += n;
  }
  gzclose(gz);
  return st;
}

lsm_status lsm_nifti_labels_read(lsm_label_file *f, uint64_t max_voxels, lsm_err *err) {
  nifti_set_debug_level(0);
  int version = 1;
  double vox_offset = 0.0;
  LSM_TRY(nifti_precheck(f->path, &version, &vox_offset, err));
  nifti_image *nim = nifti_image_read(f->path, 0);
  if (!nim)
    return lsm_fail(err, LSM_ERR_INPUT, f->path,
                    "cannot read: not a NIfTI-1 or NIfTI-2 file, or its header is damaged");
  f->native = nim;
  /* where the samples start: nifticlib reads a vox_offset below the header's
   * end (0, negative) or past 2^31 (or NaN) from byte 348, inside the header;
   * a .nii file's samples start at 352 (NIfTI-2: 544) at the earliest, where
   * nibabel reads them then, and one past the end is refused below */
  const double first = version == 2 ? 544.0 : 352.0;
  if (!(vox_offset == floor(vox_offset)) || !(fabs(vox_offset) < 9.0e15))
    return lsm_fail(err, LSM_ERR_INPUT, f->path, "damaged header: vox_offset is %g", vox_offset);
  nim->iname_offset = vox_offset < first ? (int64_t)first : (int64_t)vox_offset;
  /* 1 to 3 dimensions, or more of size 1 (a volume with one time point) */
  const int64_t ndim = nim->dim[0];
  if (ndim < 1 || ndim > 7)
    return lsm_fail(err, LSM_ERR_INPUT, f->path, "damaged header: %lld dimensions",
                    (long long)ndim);
  for (int64_t d = 1; d <= ndim; ++d)
    if (nim->dim[d] < 1)
      return lsm_fail(err, LSM_ERR_INPUT, f->path, "damaged header: dimension %lld has size %lld",
                      (long long)d, (long long)nim->dim[d]);
  for (int64_t d = 4; d <= ndim; ++d)
    if (nim->dim[d] != 1)
      return lsm_fail(err, LSM_ERR_INPUT, f->path,
                      "a %lld-dimensional image (dimension %lld has size %lld): a label volume "
                      "is 3D",
                      (long long)ndim, (long long)d, (long long)nim->dim[d]);
  for (int a = 0; a < 3; ++a) {
    const int64_t n = a < ndim ? nim->dim[a + 1] : 1;
    if ((uint64_t)n > (uint64_t)SIZE_MAX)
      return lsm_fail(err, LSM_ERR_LIMIT, f->path, "%lld voxels along an axis", (long long)n);
    f->vox.n[a] = (size_t)n;
  }
  const lsm_voxel_type type = voxel_type_of(nim->datatype);
  if (type == LSM_VOXEL_UNKNOWN || (int64_t)lsm_voxel_size(type) != nim->nbyper)
    return lsm_fail(err, LSM_ERR_INPUT, f->path,
                    "not a label map: its samples are %s (labels are integers, or floats "
                    "holding whole numbers)",
                    nifti_datatype_string(nim->datatype));
  LSM_TRY(lsm_labels_sized(f, type, max_voxels, err));
  const size_t count = f->vox.n[0] * f->vox.n[1] * f->vox.n[2]; /* checked */
  /* an uncompressed file must hold its samples (a short one is damaged) */
  struct stat sb;
  const size_t bytes = count * lsm_voxel_size(type);
  if (!nifti_is_gzfile(f->path) && stat(f->path, &sb) == 0 &&
      (nim->iname_offset < 0 || (uint64_t)sb.st_size < (uint64_t)nim->iname_offset ||
       (uint64_t)sb.st_size - (uint64_t)nim->iname_offset < bytes))
    return lsm_fail(err, LSM_ERR_INPUT, f->path,
                    "truncated: %lld bytes, but its header puts %zu bytes of samples at byte %lld",
                    (long long)sb.st_size, bytes, (long long)nim->iname_offset);
  if (nifti_image_load(nim) != 0 || !nim->data)
    return lsm_fail(err, LSM_ERR_INPUT, f->path,
                    "cannot read the samples: the file is truncated or its compressed data is "
                    "damaged");
  f->vox.data = nim->data;
  LSM_TRY(restore_nonfinite(f, nim, err));
  f->compressed = nifti_is_gzfile(f->path);
  f->nifti2 = version == 2;
  /* lsmorph's own notes ("lsmorph...: text") travel to an output of the other format too */
  lsm_status st = LSM_OK;
  for (int k = 0; st == LSM_OK && k < nim->num_ext; ++k) {
    const nifti1_extension *e = &nim->ext_list[k];
    const size_t len = e->edata && e->esize > 8 ? (size_t)(e->esize - 8) : 0;
    const char *end = len ? memchr(e->edata, '\0', len) : NULL;
    const char *colon = end && strncmp(e->edata, "lsmorph", 7) == 0 ? strstr(e->edata, ": ") : NULL;
    if (e->ecode != NIFTI_ECODE_COMMENT || !colon || (size_t)(colon - e->edata) >= 64 ||
        f->notes >= LSM_LABELS_NOTES_MAX)
      continue;
    char key[64];
    memcpy(key, e->edata, (size_t)(colon - e->edata));
    key[colon - e->edata] = '\0';
    st = lsm_labels_set_note(f, key, colon + 2, err);
  }
  if (st != LSM_OK) return st;
  double ras[3][4];
  ras_affine(nim, ras);
  for (int c = 0; c < 4; ++c) {
    f->affine[0][c] = 0.0 - ras[0][c];
    f->affine[1][c] = 0.0 - ras[1][c];
    f->affine[2][c] = ras[2][c];
  }
  return LSM_OK;
}

int lsm_nifti_labels_scaled(const lsm_label_file *f, double *slope, double *inter) {
  const nifti_image *nim = nim_of(f);
  *slope = nim->scl_slope;
  *inter = nim->scl_inter;
  /* a slope of 0 (or NaN) means no scaling; the intercept then counts for nothing */
  if (!(nim->scl_slope == nim->scl_slope) || nim->scl_slope == 0.0) return 0;
  return nim->scl_slope != 1.0 || nim->scl_inter != 0.0;
}

void lsm_nifti_labels_adopt(lsm_label_file *f, void *old_data) {
  nifti_image *nim = nim_of(f);
  free(old_data);
  nim->data = f->vox.data;
  nim->datatype = datatype_of(f->vox.type);
  nim->nbyper = (int)lsm_voxel_size(f->vox.type);
  nim->swapsize = nim->nbyper > 1 ? nim->nbyper : 0;
  /* the calibrated display range was the float values': still right */
}

void lsm_nifti_labels_free(lsm_label_file *f) {
  nifti_image *nim = nim_of(f);
  if (nim) nifti_image_free(nim);
  f->native = NULL;
  f->vox.data = NULL;
}

/* ---- notes: comment extensions "key: text" -------------------------------------------- */

/* The extension holding key's note, or -1. */
static int note_index(const nifti_image *nim, const char *key) {
  const size_t n = strlen(key);
  for (int k = 0; k < nim->num_ext; ++k) {
    const nifti1_extension *e = &nim->ext_list[k];
    if (e->ecode == NIFTI_ECODE_COMMENT && e->edata && e->esize - 8 > (int)n + 1 &&
        strncmp(e->edata, key, n) == 0 && e->edata[n] == ':' && e->edata[n + 1] == ' ')
      return k;
  }
  return -1;
}

/* Puts note "key: text" into nim, replacing an earlier one of that key. */
static lsm_status set_note(nifti_image *nim, const char *key, const char *text, const char *path,
                           lsm_err *err) {
  const int old = note_index(nim, key);
  if (old >= 0) { /* drop the earlier note */
    free(nim->ext_list[old].edata);
    memmove(&nim->ext_list[old], &nim->ext_list[old + 1],
            (size_t)(nim->num_ext - old - 1) * sizeof *nim->ext_list);
    nim->num_ext--;
  }
  const size_t len = strlen(key) + 2 + strlen(text) + 1; /* with its NUL */
  char *note = malloc(len);
  if (!note || len > (size_t)1 << 20) {
    free(note);
    return lsm_fail(err, LSM_ERR_NOMEM, path, "cannot add a header note");
  }
  const size_t nk = strlen(key);
  memcpy(note, key, nk);
  memcpy(note + nk, ": ", 2);
  memcpy(note + nk + 2, text, strlen(text) + 1);
  const int rc = nifti_add_extension(nim, note, (int)len, NIFTI_ECODE_COMMENT);
  free(note);
  if (rc != 0) return lsm_fail(err, LSM_ERR_NOMEM, path, "cannot add a header note");
  return LSM_OK;
}

const char *lsm_nifti_labels_note(const lsm_label_file *f, const char *key) {
  const nifti_image *nim = nim_of(f);
  const int k = note_index(nim, key);
  if (k < 0) return NULL;
  const nifti1_extension *e = &nim->ext_list[k];
  /* the text must end inside the extension */
  if (!memchr(e->edata, '\0', (size_t)(e->esize - 8))) return NULL;
  return e->edata + strlen(key) + 2;
}

/* ---- writing -------------------------------------------------------------------------- */

/* A header for f's voxels when f was read from a NRRD file: geometry from the
 * affine, everything else NIfTI's defaults.  Its data is f's (not owned). */
static nifti_image *new_header(const lsm_label_file *f) {
  const int64_t dims[8] = {3, (int64_t)f->vox.n[0], (int64_t)f->vox.n[1], (int64_t)f->vox.n[2],
                           1, 1, 1, 1};
  nifti_image *nim = nifti_make_new_nim(dims, datatype_of(f->vox.type), 0);
  if (!nim) return NULL;
  nifti_dmat44 r;
  memset(&r, 0, sizeof r);
  for (int c = 0; c < 4; ++c) {
    r.m[0][c] = 0.0 - f->affine[0][c];
    r.m[1][c] = 0.0 - f->affine[1][c];
    r.m[2][c] = f->affine[2][c];
  }
  r.m[3][3] = 1.0;
  nim->sform_code = nim->qform_code = NIFTI_XFORM_SCANNER_ANAT;
  nim->sto_xyz = r;
  nim->sto_ijk = nifti_dmat44_inverse(r);
  double dx, dy, dz, qfac;
  nifti_dmat44_to_quatern(r, &nim->quatern_b, &nim->quatern_c, &nim->quatern_d, &nim->qoffset_x,
                          &nim->qoffset_y, &nim->qoffset_z, &dx, &dy, &dz, &qfac);
  nim->qfac = qfac;
  nim->dx = nim->pixdim[1] = f->vox.spacing[0];
  nim->dy = nim->pixdim[2] = f->vox.spacing[1];
  nim->dz = nim->pixdim[3] = f->vox.spacing[2];
  nim->qto_xyz = nifti_quatern_to_dmat44(nim->quatern_b, nim->quatern_c, nim->quatern_d,
                                         nim->qoffset_x, nim->qoffset_y, nim->qoffset_z, nim->dx,
                                         nim->dy, nim->dz, nim->qfac);
  nim->qto_ijk = nifti_dmat44_inverse(nim->qto_xyz);
  nim->xyz_units = NIFTI_UNITS_MM; /* 3D Slicer's NRRD lengths */
  return nim;
}

lsm_status lsm_nifti_labels_write(lsm_label_file *f, int fd, const char *tmp, const char *path,
                                  lsm_err *err) {
  nifti_set_debug_level(0);
  const int own = f->format != LSM_LABELS_NIFTI;
  nifti_image *nim = own ? new_header(f) : nim_of(f);
  lsm_labels_sink sink;
  lsm_status st = lsm_labels_sink_open(&sink, fd, lsm_labels_ends_with(path, ".gz"), tmp, err);
  if (st != LSM_OK) {
    if (own && nim) nifti_image_free(nim);
    return st;
  }
  if (!nim) st = lsm_fail(err, LSM_ERR_NOMEM, path, "cannot make a NIfTI header");
  /* one file, NIfTI-2 where it was, or where NIfTI-1's 16-bit sizes do not hold it */
  int version = 1;
  for (int k = 0; st == LSM_OK && k < f->notes; ++k)
    st = set_note(nim, f->note_key[k], f->note_text[k], path, err);
  if (st == LSM_OK) {
    const int big = f->vox.n[0] > 32767 || f->vox.n[1] > 32767 || f->vox.n[2] > 32767;
    version = big || (!own && f->nifti2) ? 2 : 1;
    nim->nifti_type = version == 2 ? NIFTI_FTYPE_NIFTI2_1 : NIFTI_FTYPE_NIFTI1_1;
    nim->data = f->vox.data;
    if (!valid_nifti_extensions(nim)) nim->num_ext = 0;
    /* the samples start after the header, the extender and the extensions, on a
     * multiple of 16 (nifticlib 3.0.1's nifti_set_iname_offset forgets NIfTI-2) */
    int64_t offset = (version == 2 ? 540 : 348) + 4;
    for (int k = 0; k < nim->num_ext; ++k) offset += nim->ext_list[k].esize;
    nim->iname_offset = (offset + 15) / 16 * 16;
  }
  nifti_1_header h1;
  nifti_2_header h2;
  if (st == LSM_OK && (version == 2 ? nifti_convert_nim2n2hdr(nim, &h2)
                                    : nifti_convert_nim2n1hdr(nim, &h1)) != 0)
    st = lsm_fail(err, LSM_ERR_INPUT, path, "nifticlib cannot make a header of these voxels");
  int64_t at = 0;
  if (st == LSM_OK) {
    st = version == 2 ? lsm_labels_sink_write(&sink, &h2, sizeof h2, err)
                      : lsm_labels_sink_write(&sink, &h1, sizeof h1, err);
    at = version == 2 ? (int64_t)sizeof h2 : (int64_t)sizeof h1;
  }
  /* the extender (1: extensions follow), each extension, then zeros up to the samples */
  const char extender[4] = {nim && nim->num_ext > 0 ? 1 : 0, 0, 0, 0};
  if (st == LSM_OK) st = lsm_labels_sink_write(&sink, extender, 4, err);
  at += 4;
  for (int k = 0; st == LSM_OK && k < nim->num_ext; ++k) {
    const nifti1_extension *e = &nim->ext_list[k];
    st = lsm_labels_sink_write(&sink, &e->esize, sizeof e->esize, err);
    if (st == LSM_OK) st = lsm_labels_sink_write(&sink, &e->ecode, sizeof e->ecode, err);
    if (st == LSM_OK) st = lsm_labels_sink_write(&sink, e->edata, (size_t)(e->esize - 8), err);
    at += e->esize;
  }
  static const char zeros[16] = {0};
  if (st == LSM_OK && (at > nim->iname_offset || nim->iname_offset - at > 16))
    st = lsm_fail(err, LSM_ERR_INTERNAL, path, "the extensions do not end at the samples");
  if (st == LSM_OK) st = lsm_labels_sink_write(&sink, zeros, (size_t)(nim->iname_offset - at), err);
  size_t count = 0;
  if (st == LSM_OK) st = lsm_voxels_count(f->vox.n, f->vox.type, &count, path, err);
  if (st == LSM_OK)
    st = lsm_labels_sink_write(&sink, f->vox.data, count * lsm_voxel_size(f->vox.type), err);
  st = lsm_labels_sink_close(&sink, st, err);
  if (own && nim) {
    nim->data = NULL; /* f's */
    nifti_image_free(nim);
  }
  return st;
}
