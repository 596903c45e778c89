/* io_labels_impl: what io_labels.c shares with the format files
 * io_labels_nifti.c and io_labels_nrrd.c (private to the three). */
#ifndef IO_LABELS_IMPL_H
#define IO_LABELS_IMPL_H

#include <stdio.h>

#include "io/lsm_labels.h"

#define LSM_LABELS_NOTES_MAX 8

struct lsm_label_file {
  lsm_label_format format;
  char *path;
  lsm_voxels vox;        /* vox.data is the library structure's data buffer */
  void *native;          /* nifti_image * or Nrrd *, the header as read */
  double affine[3][4];   /* index to LPS world */
  int compressed;        /* the input's samples were compressed: gzip them on output */
  int nifti2;            /* a NIfTI-2 file (nifticlib 3.0.1 reports it as NIfTI-1) */
  /* notes set by lsm_labels_set_note, written into whichever header is written */
  char *note_key[LSM_LABELS_NOTES_MAX], *note_text[LSM_LABELS_NOTES_MAX];
  int notes;
};

/* Format readers: fill f (path set, the rest zero) or fail. */
lsm_status lsm_nifti_labels_read(lsm_label_file *f, uint64_t max_voxels, lsm_err *err);
lsm_status lsm_nrrd_labels_read(lsm_label_file *f, uint64_t max_voxels, lsm_err *err);

/* Where a writer puts bytes: a file, or one gzip member (zlib, level 6). */
typedef struct lsm_labels_sink {
  FILE *fp;
  void *gz;          /* gzFile when compressing */
  const char *name;  /* for messages */
} lsm_labels_sink;

/* Takes over fd (closed by lsm_labels_sink_close, also after a failure). */
lsm_status lsm_labels_sink_open(lsm_labels_sink *s, int fd, int gz, const char *name,
                                lsm_err *err);
lsm_status lsm_labels_sink_write(lsm_labels_sink *s, const void *data, size_t bytes,
                                 lsm_err *err);
/* Flushes and closes, checking both; returns st when st already failed. */
lsm_status lsm_labels_sink_close(lsm_labels_sink *s, lsm_status st, lsm_err *err);

/* Format writers: write f into the temporary file open on fd (named tmp; the
 * final name path decides the form: .nii or .nii.gz, .nrrd or .nhdr), closing
 * it.  A detached NRRD header's data goes to data_fd (named data_tmp, to be
 * renamed data_name beside path: the header names it). */
lsm_status lsm_nifti_labels_write(lsm_label_file *f, int fd, const char *tmp,
                                  const char *path, lsm_err *err);
lsm_status lsm_nrrd_labels_write(lsm_label_file *f, int fd, const char *tmp, int data_fd,
                                 const char *data_tmp, const char *data_name, const char *path,
                                 lsm_err *err);

/* Refuses data_out, an output file (OUT, or a detached header's data file),
 * when it is one of the data files the NRRD header input names. */
lsm_status lsm_nrrd_labels_check_data_output(const char *input, const char *data_out,
                                             lsm_err *err);

/* The data file written beside a detached header path (NAME.nhdr):
 * NAME.raw, or NAME.raw.gz when gz; *name_at: where its name starts. */
lsm_status lsm_labels_data_file(const char *path, int gz, char *out, size_t cap,
                                size_t *name_at, lsm_err *err);

/* A note read from the input's header (NULL when absent). */
const char *lsm_nifti_labels_note(const lsm_label_file *f, const char *key);
const char *lsm_nrrd_labels_note(const lsm_label_file *f, const char *key);

/* After f->vox.data or f->vox.type changed: the native header follows (the
 * old buffer, owned by the library structure, is freed). */
void lsm_nifti_labels_adopt(lsm_label_file *f, void *old_data);
void lsm_nrrd_labels_adopt(lsm_label_file *f, void *old_data);
/* Whether the NIfTI header scales the stored values (not a label map). */
int lsm_nifti_labels_scaled(const lsm_label_file *f, double *slope, double *inter);

void lsm_nifti_labels_free(lsm_label_file *f);
void lsm_nrrd_labels_free(lsm_label_file *f);

/* Sets f->vox.type and checks n[0] x n[1] x n[2] voxels of it: no overflow,
 * within max_voxels (0: no limit). */
lsm_status lsm_labels_sized(lsm_label_file *f, lsm_voxel_type type, uint64_t max_voxels,
                            lsm_err *err);

/* Sets f->vox.spacing from the affine's column lengths. */
void lsm_labels_spacing_from_affine(lsm_label_file *f);

/* Whether a name ends with suffix, any case. */
int lsm_labels_ends_with(const char *path, const char *suffix);

#endif
