/* lsm_voxels: a 3D array of voxels as label files hold them (NIfTI, NRRD, a
 * NumPy array): ni x nj x nk values, i fastest, of one integer or floating
 * type, in the machine's byte order, with the physical step along each index
 * axis.  Label maps are integer volumes; the floating types exist so that a
 * reader can hand over what a file holds and the caller decide. */
#ifndef LSM_VOXELS_H
#define LSM_VOXELS_H

#include <stddef.h>
#include <stdint.h>

#include "solver/base/lsm_names.h"
#include "solver/base/lsm_status.h"

/* Add new items at the end (lsm_names.h). */
#define LSM_VOXEL_TYPE_LIST(X)                                                  \
  X(LSM_VOXEL_U8, "uint8")                                                      \
  X(LSM_VOXEL_I8, "int8")                                                       \
  X(LSM_VOXEL_U16, "uint16")                                                    \
  X(LSM_VOXEL_I16, "int16")                                                     \
  X(LSM_VOXEL_U32, "uint32")                                                    \
  X(LSM_VOXEL_I32, "int32")                                                     \
  X(LSM_VOXEL_U64, "uint64")                                                    \
  X(LSM_VOXEL_I64, "int64")                                                     \
  X(LSM_VOXEL_F32, "float32")                                                   \
  X(LSM_VOXEL_F64, "float64")
LSM_ENUM(lsm_voxel_type, LSM_VOXEL, LSM_VOXEL_TYPE_LIST, lsm_voxel_type_name,
         lsm_voxel_type_from_name);

typedef struct lsm_voxels {
  size_t n[3];         /* voxels along i, j, k */
  lsm_voxel_type type;
  void *data;          /* n[0] * n[1] * n[2] values, i fastest, then j, then k */
  double spacing[3];   /* physical distance between neighbours along i, j, k */
} lsm_voxels;

/* Bytes of one value (0 for an unknown type). */
size_t lsm_voxel_size(lsm_voxel_type type);
int lsm_voxel_is_integer(lsm_voxel_type type);

/* The number of voxels of n[0] x n[1] x n[2] into *count, refusing
 * (LSM_ERR_LIMIT, "where: ...") a product or a byte count that overflows
 * size_t, and an empty axis (LSM_ERR_INPUT). */
lsm_status lsm_voxels_count(const size_t n[3], lsm_voxel_type type, size_t *count,
                            const char *where, lsm_err *err);

/* Value `index` as a double (exact for every integer type up to 2^53, and
 * for the floating types). */
double lsm_voxel_get(const lsm_voxels *v, size_t index);

/* Value `index` of an integer volume (an int64 above INT64_MAX is returned
 * as INT64_MAX: lsm_labels_check refuses such volumes). */
int64_t lsm_voxel_get_int(const lsm_voxels *v, size_t index);

/* Stores value at `index` of an integer volume (the caller has checked the
 * type holds it). */
void lsm_voxel_set_int(lsm_voxels *v, size_t index, int64_t value);

/* Whether an integer volume of this type holds value. */
int lsm_voxel_type_holds(lsm_voxel_type type, int64_t value);

/* Runs the statements that follow (__VA_ARGS__) with T the C type of the
 * integer voxel type vtype (uint8_t ... int64_t): a loop over voxels compiled
 * once per type, without a switch per voxel.  Nothing runs for other types. */
#define LSM_VOXEL_INT_CASE(id, ctype, ...) \
  case id: {                               \
    typedef ctype T;                       \
    __VA_ARGS__                            \
  } break;
#define LSM_VOXEL_INT_SWITCH(vtype, ...)                                        \
  switch (vtype) {                                                              \
    LSM_VOXEL_INT_CASE(LSM_VOXEL_U8, uint8_t, __VA_ARGS__)                      \
    LSM_VOXEL_INT_CASE(LSM_VOXEL_I8, int8_t, __VA_ARGS__)                       \
    LSM_VOXEL_INT_CASE(LSM_VOXEL_U16, uint16_t, __VA_ARGS__)                    \
    LSM_VOXEL_INT_CASE(LSM_VOXEL_I16, int16_t, __VA_ARGS__)                     \
    LSM_VOXEL_INT_CASE(LSM_VOXEL_U32, uint32_t, __VA_ARGS__)                    \
    LSM_VOXEL_INT_CASE(LSM_VOXEL_I32, int32_t, __VA_ARGS__)                     \
    LSM_VOXEL_INT_CASE(LSM_VOXEL_U64, uint64_t, __VA_ARGS__)                    \
    LSM_VOXEL_INT_CASE(LSM_VOXEL_I64, int64_t, __VA_ARGS__)                     \
  default:                                                                      \
    break;                                                                      \
  }

/* The smallest integer type a label map of values in [lo, hi] fits,
 * preferring the types viewers expect of labels: uint8, int16, uint16,
 * int32, uint32, int64. */
lsm_voxel_type lsm_voxel_type_for_range(int64_t lo, int64_t hi);

#endif
