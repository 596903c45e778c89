/* lsm_labels: label volumes on disk, read and written with the formats'
 * reference libraries.
 *
 *   io_labels.c        names, checks, the integer conversion, atomic writing
 *   io_labels_nifti.c  NIfTI-1 and NIfTI-2, .nii and .nii.gz (nifticlib)
 *   io_labels_nrrd.c   NRRD, .nrrd, .seg.nrrd (3D Slicer's segmentations) and
 *                      .nhdr with its data file, raw, gzip or any encoding teem
 *                      reads (teem's nrrd)
 *
 * A file read keeps its whole header (the library's own structure): writing it
 * back changes only the voxels (and their type when a floating-point label
 * map is stored as integers), so the grid, the affine or space directions and
 * origin, every key/value pair and comment, NIfTI's description, intent and
 * extensions come back as they were.  A .seg.nrrd's segments keep their
 * names, colours and label values; their extents (SegmentN_Extent) are set
 * to the filled segments' bounds.  Written into a NIfTI file when read from a
 * NRRD file or the other way, the geometry is converted (NIfTI's RAS world,
 * NRRD's space: LPS for 3D Slicer) and the header fields with no counterpart
 * are left out.
 *
 * Headers are checked before any voxel is allocated: a 3D volume (4D only
 * as one layer of a .seg.nrrd, or with one time point), integer or floating
 * samples, sizes whose product and byte count do not overflow and stay
 * within max_voxels.  Damaged and hostile files are refused with
 * "<file>: <what>"; the libraries' own messages on stderr are silenced.
 * Output files are written beside their final name and renamed into place
 * only when complete (a data file before its detached header).
 */
#ifndef LSM_LABELS_H
#define LSM_LABELS_H

#include <stdint.h>

#include "solver/base/lsm_status.h"
#include "solver/base/lsm_voxels.h"

typedef enum lsm_label_format {
  LSM_LABELS_UNKNOWN = -1,
  LSM_LABELS_NIFTI,  /* .nii, .nii.gz */
  LSM_LABELS_NRRD    /* .nrrd, .seg.nrrd, .nhdr */
} lsm_label_format;

/* The format a file name asks for (its ending, any case). */
lsm_label_format lsm_labels_format_of(const char *path);

/* Whether a name ends like a label volume: .nii, .nii.gz, .nrrd, .nhdr. */
int lsm_labels_is_volume_name(const char *path);

typedef struct lsm_label_file lsm_label_file;

/* Reads a label volume (or any 3D volume of numbers: the caller checks that
 * it is a label map).  max_voxels: refuse larger volumes (0: no limit). */
lsm_status lsm_labels_read(const char *path, uint64_t max_voxels, lsm_label_file **out,
                           lsm_err *err);
void lsm_labels_free(lsm_label_file **f);

/* The voxels, owned by f (the caller may change their values, and their type
 * through lsm_labels_to_integer). */
lsm_voxels *lsm_labels_voxels(lsm_label_file *f);
lsm_label_format lsm_labels_format(const lsm_label_file *f);
const char *lsm_labels_path(const lsm_label_file *f);
/* Whether its samples were compressed (NRRD writes them back so; NIfTI by the
 * output's name, .nii.gz). */
int lsm_labels_compressed(const lsm_label_file *f);

/* Index to world: x = m[.][0] i + m[.][1] j + m[.][2] k + m[.][3], in LPS
 * (3D Slicer's and ITK's world: x to the left, y to the back), physical units
 * of the file.  Whether the index axes are orthogonal (a sheared grid, as a
 * tilted CT gantry gives, is not): *cosine the largest |cos| between two. */
void lsm_labels_affine(const lsm_label_file *f, double m[3][4]);
void lsm_labels_axes_cosine(const lsm_label_file *f, double *cosine);

/* A floating-point volume whose values are all whole numbers (labels stored
 * as floats) becomes the smallest integer type that holds them
 * (lsm_voxel_type_for_range); any other value (2.5, NaN, Inf) is refused as
 * "not a label map", naming the first such voxel.  Integer volumes are kept
 * as they are.  NIfTI files whose header scales their values (scl_slope
 * other than 0 and 1, or scl_inter not 0) are refused the same way.
 * *converted: 1 when the type changed. */
lsm_status lsm_labels_to_integer(lsm_label_file *f, int *converted, lsm_err *err);

/* A text kept in the header under key (a NRRD key/value pair; a NIfTI
 * comment extension "key: text"), replacing an earlier one of that key.
 * lsm_labels_note returns it (NULL when absent; valid until the next change). */
lsm_status lsm_labels_set_note(lsm_label_file *f, const char *key, const char *text, lsm_err *err);
const char *lsm_labels_note(const lsm_label_file *f, const char *key);

/* Checks, before any work, that path can take the output: a label-volume
 * name (its format may differ from the input's), in an existing folder that
 * can be written, not an existing folder itself, not the input file. */
lsm_status lsm_labels_check_output(const char *path, const char *input, lsm_err *err);

/* Writes f's header and voxels to path (format by its name), atomically. */
lsm_status lsm_labels_write(lsm_label_file *f, const char *path, lsm_err *err);

#endif
