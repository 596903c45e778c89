/* io_labels: what label volumes of either format share: names, the output's
 * checks, the integer conversion, notes, and atomic writing. */
#define _XOPEN_SOURCE 700
#include "io/io_labels_impl.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include "io/lsm_io.h"
#include "io/lsm_temp.h"

int lsm_labels_ends_with(const char *path, const char *suffix) {
  const size_t n = strlen(path), m = strlen(suffix);
  if (n < m) return 0;
  for (size_t k = 0; k < m; ++k)
    if (tolower((unsigned char)path[n - m + k]) != tolower((unsigned char)suffix[k])) return 0;
  return 1;
}

lsm_label_format lsm_labels_format_of(const char *path) {
  if (!path) return LSM_LABELS_UNKNOWN;
  if (lsm_labels_ends_with(path, ".nii") || lsm_labels_ends_with(path, ".nii.gz"))
    return LSM_LABELS_NIFTI;
  if (lsm_labels_ends_with(path, ".nrrd") || lsm_labels_ends_with(path, ".nhdr"))
    return LSM_LABELS_NRRD;
  return LSM_LABELS_UNKNOWN;
}

/* nifticlib takes a NIfTI name only when its ending is all lower or all upper
 * case (.nii.gz, .NII.GZ; not .Nii.Gz). */
static int nifti_case_ok(const char *path) {
  const size_t n = strlen(path), m = lsm_labels_ends_with(path, ".gz") ? 7 : 4;
  int lower = 0, upper = 0;
  for (size_t k = n >= m ? n - m : 0; k < n; ++k) {
    lower |= islower((unsigned char)path[k]) != 0;
    upper |= isupper((unsigned char)path[k]) != 0;
  }
  return !(lower && upper);
}

int lsm_labels_is_volume_name(const char *path) {
  return lsm_labels_format_of(path) != LSM_LABELS_UNKNOWN;
}

lsm_status lsm_labels_read(const char *path, uint64_t max_voxels, lsm_label_file **out,
                           lsm_err *err) {
  *out = NULL;
  struct stat sb;
  if (stat(path, &sb) != 0)
    return lsm_fail(err, LSM_ERR_INPUT, path, "cannot read: %s", strerror(errno));
  if (S_ISDIR(sb.st_mode))
    return lsm_fail(err, LSM_ERR_INPUT, path,
                    "is a folder, not a label volume (.nii, .nii.gz, .nrrd, .seg.nrrd, .nhdr; "
                    "folders of PNG or TIFF slices go to 'lsmorph reconstruct')");
  const lsm_label_format format = lsm_labels_format_of(path);
  if (format == LSM_LABELS_UNKNOWN)
    return lsm_fail(err, LSM_ERR_INPUT, path,
                    "not a label volume name: .nii, .nii.gz, .nrrd, .seg.nrrd or .nhdr");
  if (format == LSM_LABELS_NIFTI && !nifti_case_ok(path))
    return lsm_fail(err, LSM_ERR_INPUT, path,
                    "cannot read a NIfTI name ending in mixed case: nifticlib reads .nii and "
                    ".nii.gz in lower or in upper case (.NII.GZ); rename the file");
  /* a pipe or a device would block the read, or be read twice (header, then samples) */
  if (!S_ISREG(sb.st_mode))
    return lsm_fail(err, LSM_ERR_INPUT, path, "not a regular file (a pipe, a socket or a device)");
  lsm_label_file *f = calloc(1, sizeof *f);
  if (!f) return lsm_fail(err, LSM_ERR_NOMEM, path, "cannot allocate the header");
  f->format = format;
  f->path = malloc(strlen(path) + 1);
  if (!f->path) {
    free(f);
    return lsm_fail(err, LSM_ERR_NOMEM, path, "cannot allocate the header");
  }
  strcpy(f->path, path);
  const lsm_status st = format == LSM_LABELS_NIFTI ? lsm_nifti_labels_read(f, max_voxels, err)
                                                   : lsm_nrrd_labels_read(f, max_voxels, err);
  if (st != LSM_OK) {
    lsm_labels_free(&f);
    return st;
  }
  lsm_labels_spacing_from_affine(f);
  for (int a = 0; a < 3; ++a)
    if (!(f->vox.spacing[a] > 0.0) || !isfinite(f->vox.spacing[a])) {
      lsm_fail(err, LSM_ERR_INPUT, path, "the voxel spacing along %c is %g: not a length",
               "ijk"[a], f->vox.spacing[a]);
      lsm_labels_free(&f);
      return LSM_ERR_INPUT;
    }
  /* parallel voxel axes (a singular index-to-world map) put the volume on a
   * plane or a line: a damaged header, not a sheared grid */
  double (*m)[4] = f->affine;
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                     m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  const double *sp = f->vox.spacing;
  if (!(fabs(det) / sp[0] / sp[1] / sp[2] > 1e-6)) {
    lsm_fail(err, LSM_ERR_INPUT, path,
             "the grid's voxel axes are parallel (its index-to-world matrix is singular): a "
             "damaged header");
    lsm_labels_free(&f);
    return LSM_ERR_INPUT;
  }
  *out = f;
  return LSM_OK;
}

void lsm_labels_free(lsm_label_file **f) {
  if (!f || !*f) return;
  if ((*f)->format == LSM_LABELS_NIFTI)
    lsm_nifti_labels_free(*f);
  else
    lsm_nrrd_labels_free(*f);
  for (int k = 0; k < (*f)->notes; ++k) {
    free((*f)->note_key[k]);
    free((*f)->note_text[k]);
  }
  free((*f)->path);
  free(*f);
  *f = NULL;
}

lsm_voxels *lsm_labels_voxels(lsm_label_file *f) { return &f->vox; }
lsm_label_format lsm_labels_format(const lsm_label_file *f) { return f->format; }
const char *lsm_labels_path(const lsm_label_file *f) { return f->path; }

int lsm_labels_compressed(const lsm_label_file *f) { return f->compressed; }

void lsm_labels_affine(const lsm_label_file *f, double m[3][4]) {
  memcpy(m, f->affine, sizeof f->affine);
}

lsm_status lsm_labels_sized(lsm_label_file *f, lsm_voxel_type type, uint64_t max_voxels,
                            lsm_err *err) {
  f->vox.type = type;
  size_t count = 0;
  LSM_TRY(lsm_voxels_count(f->vox.n, type, &count, f->path, err));
  if (max_voxels && count > max_voxels)
    return lsm_fail(err, LSM_ERR_LIMIT, f->path,
                    "%zu x %zu x %zu = %zu voxels, more than --max-voxels %llu", f->vox.n[0],
                    f->vox.n[1], f->vox.n[2], count, (unsigned long long)max_voxels);
  return LSM_OK;
}

void lsm_labels_spacing_from_affine(lsm_label_file *f) {
  for (int a = 0; a < 3; ++a) {
    const double x = f->affine[0][a], y = f->affine[1][a], z = f->affine[2][a];
    f->vox.spacing[a] = sqrt(x * x + y * y + z * z);
  }
}

void lsm_labels_axes_cosine(const lsm_label_file *f, double *cosine) {
  double worst = 0.0;
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b) {
      double dot = 0.0;
      for (int r = 0; r < 3; ++r) dot += f->affine[r][a] * f->affine[r][b];
      const double la = f->vox.spacing[a], lb = f->vox.spacing[b];
      if (la > 0 && lb > 0 && fabs(dot) / (la * lb) > worst) worst = fabs(dot) / (la * lb);
    }
  *cosine = worst;
}

/* The voxel (i, j, k) of a linear index, for messages. */
static void voxel_ijk(const lsm_voxels *v, size_t index, size_t ijk[3]) {
  ijk[0] = index % v->n[0];
  ijk[1] = index / v->n[0] % v->n[1];
  ijk[2] = index / v->n[0] / v->n[1];
}

lsm_status lsm_labels_to_integer(lsm_label_file *f, int *converted, lsm_err *err) {
  lsm_voxels *v = &f->vox;
  *converted = 0;
  double slope = 1.0, inter = 0.0;
  if (f->format == LSM_LABELS_NIFTI && lsm_nifti_labels_scaled(f, &slope, &inter))
    return lsm_fail(err, LSM_ERR_INPUT, f->path,
                    "not a label map: its header scales the stored values (scl_slope %g, "
                    "scl_inter %g), as intensity images do; a label map stores its labels as "
                    "they are",
                    slope, inter);
  size_t count = 0;
  LSM_TRY(lsm_voxels_count(v->n, v->type, &count, f->path, err));
  if (v->type == LSM_VOXEL_U64) {
    const uint64_t *p = v->data;
    for (size_t k = 0; k < count; ++k)
      if (p[k] > (uint64_t)INT64_MAX) {
        size_t at[3];
        voxel_ijk(v, k, at);
        return lsm_fail(err, LSM_ERR_INPUT, f->path,
                        "not a label map: voxel (%zu, %zu, %zu) holds %llu, past the labels "
                        "lsmorph keeps (up to 2^63 - 1)",
                        at[0], at[1], at[2], (unsigned long long)p[k]);
      }
  }
  if (lsm_voxel_is_integer(v->type)) return LSM_OK;
  /* labels stored as floats: every value a whole number within int64 */
  double lo = 0.0, hi = 0.0;
  for (size_t k = 0; k < count; ++k) {
    const double x = lsm_voxel_get(v, k);
    if (!(x == floor(x)) || !(fabs(x) <= 9.0e15)) {
      size_t at[3];
      voxel_ijk(v, k, at);
      const int whole = isfinite(x) && x == floor(x); /* whole, but too large */
      return lsm_fail(err, LSM_ERR_INPUT, f->path,
                      "not a label map: voxel (%zu, %zu, %zu) holds %.17g, %s", at[0], at[1],
                      at[2], x,
                      whole ? "past the labels a floating-point volume holds exactly (up to "
                              "9e15; store labels as integers)"
                            : "and labels are whole numbers (an intensity image, or labels "
                              "resampled with interpolation: resample label maps with nearest "
                              "neighbour)");
    }
    lo = x < lo ? x : lo;
    hi = x > hi ? x : hi;
  }
  const lsm_voxel_type type = lsm_voxel_type_for_range((int64_t)lo, (int64_t)hi);
  lsm_voxels out = *v;
  out.type = type;
  out.data = lsm_alloc(count, lsm_voxel_size(type), err, "label volume");
  if (!out.data) return err ? err->status : LSM_ERR_NOMEM;
  for (size_t k = 0; k < count; ++k) lsm_voxel_set_int(&out, k, (int64_t)lsm_voxel_get(v, k));
  void *old = v->data;
  *v = out;
  if (f->format == LSM_LABELS_NIFTI)
    lsm_nifti_labels_adopt(f, old);
  else
    lsm_nrrd_labels_adopt(f, old);
  *converted = 1;
  return LSM_OK;
}

/* A malloc'd copy of s. */
static char *copy_of(const char *s) {
  char *c = malloc(strlen(s) + 1);
  if (c) strcpy(c, s);
  return c;
}

lsm_status lsm_labels_set_note(lsm_label_file *f, const char *key, const char *text,
                               lsm_err *err) {
  int k = 0;
  while (k < f->notes && strcmp(f->note_key[k], key) != 0) ++k;
  if (k == LSM_LABELS_NOTES_MAX)
    return lsm_fail(err, LSM_ERR_INTERNAL, f->path, "too many header notes");
  char *t = copy_of(text), *key_copy = k < f->notes ? f->note_key[k] : copy_of(key);
  if (!t || !key_copy) {
    free(t);
    if (k == f->notes) free(key_copy);
    return lsm_fail(err, LSM_ERR_NOMEM, f->path, "cannot add a header note");
  }
  if (k < f->notes) free(f->note_text[k]);
  f->note_key[k] = key_copy;
  f->note_text[k] = t;
  if (k == f->notes) f->notes++;
  return LSM_OK;
}

const char *lsm_labels_note(const lsm_label_file *f, const char *key) {
  for (int k = 0; k < f->notes; ++k)
    if (strcmp(f->note_key[k], key) == 0) return f->note_text[k];
  return f->format == LSM_LABELS_NIFTI ? lsm_nifti_labels_note(f, key)
                                       : lsm_nrrd_labels_note(f, key);
}

/* The folder part of path ("." when it has none) into dir. */
static lsm_status folder_of(const char *path, char *dir, size_t cap, lsm_err *err) {
  const char *slash = strrchr(path, '/');
  const size_t n = slash ? (slash == path ? 1 : (size_t)(slash - path)) : 1;
  if (n + 1 > cap) return lsm_fail(err, LSM_ERR_INPUT, path, "the path is too long");
  if (slash)
    memcpy(dir, path, n);
  else
    dir[0] = '.';
  dir[n] = '\0';
  return LSM_OK;
}

lsm_status lsm_labels_data_file(const char *path, int gz, char *out, size_t cap,
                                size_t *name_at, lsm_err *err) {
  const char *slash = strrchr(path, '/');
  const size_t base = slash ? (size_t)(slash + 1 - path) : 0, len = strlen(path);
  const int n = snprintf(out, cap, "%.*s.raw%s", (int)(len - 5), path, gz ? ".gz" : "");
  if (len < 5 || n < 0 || (size_t)n >= cap)
    return lsm_fail(err, LSM_ERR_INPUT, path, "the path is too long");
  *name_at = base;
  return LSM_OK;
}

lsm_status lsm_labels_check_output(const char *path, const char *input, lsm_err *err) {
  if (!lsm_labels_is_volume_name(path))
    return lsm_fail(err, LSM_ERR_USAGE, path,
                    "the output's name says no label-volume format: end it in .nii, .nii.gz, "
                    ".nrrd, .seg.nrrd or .nhdr");
  if (lsm_labels_format_of(path) == LSM_LABELS_NIFTI && !nifti_case_ok(path))
    return lsm_fail(err, LSM_ERR_USAGE, path,
                    "a NIfTI name ending in mixed case, which nifticlib (and so lsmorph) cannot "
                    "read back: end it in .nii or .nii.gz, in lower or in upper case");
  struct stat sb, in;
  if (stat(path, &sb) == 0) {
    if (S_ISDIR(sb.st_mode))
      return lsm_fail(err, LSM_ERR_INPUT, path, "is a folder: name the output file");
    /* OUT is written beside its name and renamed into place: that would replace
     * a pipe or a device node by a plain file */
    if (!S_ISREG(sb.st_mode))
      return lsm_fail(err, LSM_ERR_INPUT, path,
                      "is not a regular file (a pipe, a socket or a device), which the result "
                      "would replace: name a file");
    if (input && stat(input, &in) == 0 && in.st_dev == sb.st_dev && in.st_ino == sb.st_ino)
      return lsm_fail(err, LSM_ERR_INPUT, path,
                      "is the input file: write the result to another file (the drawn slices "
                      "would be lost)");
  }
  /* a detached header names its data file on one line; teem reads a '%' in it
   * as a template of numbered files */
  const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
  if (lsm_labels_ends_with(path, ".nhdr"))
    for (const char *c = base; *c; ++c)
      if (*c == '%' || iscntrl((unsigned char)*c))
        return lsm_fail(err, LSM_ERR_USAGE, path,
                        "a .nhdr name holding '%%' or a control character (a line break), which "
                        "its header's 'data file' line cannot hold: rename OUT");
  /* neither OUT nor a detached header's data file may be the input's data file */
  if (input && lsm_labels_format_of(input) == LSM_LABELS_NRRD)
    LSM_TRY(lsm_nrrd_labels_check_data_output(input, path, err));
  if (input && lsm_labels_ends_with(path, ".nhdr") &&
      lsm_labels_format_of(input) == LSM_LABELS_NRRD)
    for (int gz = 0; gz < 2; ++gz) {
      char data[4200];
      size_t name_at = 0;
      LSM_TRY(lsm_labels_data_file(path, gz, data, sizeof data, &name_at, err));
      LSM_TRY(lsm_nrrd_labels_check_data_output(input, data, err));
    }
  char dir[4096];
  LSM_TRY(folder_of(path, dir, sizeof dir, err));
  if (stat(dir, &sb) != 0 || !S_ISDIR(sb.st_mode))
    return lsm_fail(err, LSM_ERR_INPUT, path, "no such folder: %s", dir);
  if (access(dir, W_OK | X_OK) != 0)
    return lsm_fail(err, LSM_ERR_INPUT, path, "cannot write in the folder %s: %s", dir,
                    strerror(errno));
  return LSM_OK;
}

/* A temporary file beside final, "<dir>/.<name>.tmp-<tag>-XXXXXX" (lsm_temp.h),
 * with the permissions of a new file (mkstemp makes it private); those of
 * earlier runs that provably ended (killed while writing) are removed first. */
static lsm_status make_temp(const char *final, char *tmp, size_t cap, int *fd, lsm_err *err) {
  char dir[4096], prefix[300], stem[4400];
  LSM_TRY(folder_of(final, dir, sizeof dir, err));
  const char *slash = strrchr(final, '/');
  const char *name = slash ? slash + 1 : final;
  const int n = snprintf(prefix, sizeof prefix, ".%s.tmp-", name);
  if (n < 0 || (size_t)n >= sizeof prefix)
    return lsm_fail(err, LSM_ERR_INPUT, final, "the file name is too long");
  snprintf(stem, sizeof stem, "%s/%s", dir, prefix);
  lsm_temp_sweep_result swept;
  lsm_temp_sweep(dir, prefix, NULL, &swept);
  LSM_TRY(lsm_temp_template(tmp, cap, stem, err));
  *fd = mkstemp(tmp);
  if (*fd < 0)
    return lsm_fail(err, LSM_ERR_IO, final, "cannot create a file beside it: %s", strerror(errno));
  const mode_t mask = umask(0);
  umask(mask);
  if (fchmod(*fd, 0666 & ~mask) != 0) {
    const int e = errno;
    close(*fd);
    unlink(tmp);
    return lsm_fail(err, LSM_ERR_IO, tmp, "cannot set permissions: %s", strerror(e));
  }
  return LSM_OK;
}

lsm_status lsm_labels_write(lsm_label_file *f, const char *path, lsm_err *err) {
  const lsm_label_format format = lsm_labels_format_of(path);
  if (format == LSM_LABELS_UNKNOWN)
    return lsm_fail(err, LSM_ERR_USAGE, path, "not a label volume name");
  char tmp[4200], data_tmp[4200] = "", data_name[4200] = "", data_final[4200] = "";
  int fd = -1, data_fd = -1;
  const int detached = lsm_labels_ends_with(path, ".nhdr");
  if (detached) {
    /* the data file beside the header: NAME.raw or NAME.raw.gz */
    size_t name_at = 0;
    LSM_TRY(lsm_labels_data_file(path, f->compressed, data_final, sizeof data_final, &name_at,
                                 err));
    snprintf(data_name, sizeof data_name, "%s", data_final + name_at);
    /* a file of that name that the header now at path does not name is the user's */
    struct stat sb;
    if (lstat(data_final, &sb) == 0 &&
        lsm_nrrd_labels_check_data_output(path, data_final, NULL) == LSM_OK)
      return lsm_fail(err, LSM_ERR_INPUT, data_final,
                      "exists, and %s does not name it as its data file: the result's data "
                      "would replace it; move it away or name the output otherwise",
                      path);
    LSM_TRY(make_temp(data_final, data_tmp, sizeof data_tmp, &data_fd, err));
  }
  lsm_status st = make_temp(path, tmp, sizeof tmp, &fd, err);
  if (st != LSM_OK) {
    if (data_fd >= 0) {
      close(data_fd);
      unlink(data_tmp);
    }
    return st;
  }
  if (format == LSM_LABELS_NIFTI)
    st = lsm_nifti_labels_write(f, fd, tmp, path, err);
  else
    st = lsm_nrrd_labels_write(f, fd, tmp, data_fd, data_tmp, data_name, path, err);
  /* the data file first: a header never names data that is not there */
  if (st == LSM_OK && detached && rename(data_tmp, data_final) != 0)
    st = lsm_fail(err, LSM_ERR_IO, data_final, "cannot move into place: %s", strerror(errno));
  if (st == LSM_OK && rename(tmp, path) != 0)
    st = lsm_fail(err, LSM_ERR_IO, path, "cannot move into place: %s", strerror(errno));
  if (st != LSM_OK) {
    unlink(tmp);
    if (detached) unlink(data_tmp);
  }
  return st;
}

/* ---- sinks -------------------------------------------------------------------------- */

lsm_status lsm_labels_sink_open(lsm_labels_sink *s, int fd, int gz, const char *name,
                                lsm_err *err) {
  memset(s, 0, sizeof *s);
  s->name = name;
  if (gz) {
    s->gz = gzdopen(fd, "wb6");
    if (!s->gz) {
      close(fd);
      return lsm_fail(err, LSM_ERR_NOMEM, name, "cannot start the gzip stream");
    }
    return LSM_OK;
  }
  s->fp = fdopen(fd, "wb");
  if (!s->fp) {
    const int e = errno;
    close(fd);
    return lsm_fail(err, LSM_ERR_IO, name, "cannot write: %s", strerror(e));
  }
  return LSM_OK;
}

lsm_status lsm_labels_sink_write(lsm_labels_sink *s, const void *data, size_t bytes,
                                 lsm_err *err) {
  const char *p = data;
  while (bytes > 0) {
    /* gzwrite takes an unsigned count: pieces of 1 GiB */
    const size_t piece = bytes < ((size_t)1 << 30) ? bytes : ((size_t)1 << 30);
    if (s->gz) {
      if (gzwrite(s->gz, p, (unsigned)piece) != (int)piece) {
        int zerr = Z_OK;
        const char *what = gzerror(s->gz, &zerr);
        return lsm_fail(err, LSM_ERR_IO, s->name, "write failed: %s",
                        zerr == Z_ERRNO ? strerror(errno) : what);
      }
    } else if (fwrite(p, 1, piece, s->fp) != piece) {
      return lsm_fail(err, LSM_ERR_IO, s->name, "write failed: %s", strerror(errno));
    }
    p += piece;
    bytes -= piece;
  }
  return LSM_OK;
}

lsm_status lsm_labels_sink_close(lsm_labels_sink *s, lsm_status st, lsm_err *err) {
  if (s->gz) {
    const int rc = gzclose(s->gz);
    s->gz = NULL;
    if (rc != Z_OK && st == LSM_OK)
      st = lsm_fail(err, LSM_ERR_IO, s->name, "write failed: %s",
                    rc == Z_ERRNO ? strerror(errno) : "gzip stream error");
    return st;
  }
  return lsm_close_written(&s->fp, s->name, st, err);
}
