#include "solver/base/lsm_voxels.h"

#include <math.h>

LSM_NAME_FUNCTIONS(lsm_voxel_type, LSM_VOXEL_TYPE_LIST, lsm_voxel_type_name,
                   lsm_voxel_type_from_name)

size_t lsm_voxel_size(lsm_voxel_type type) {
  switch (type) {
  case LSM_VOXEL_U8: case LSM_VOXEL_I8: return 1;
  case LSM_VOXEL_U16: case LSM_VOXEL_I16: return 2;
  case LSM_VOXEL_U32: case LSM_VOXEL_I32: case LSM_VOXEL_F32: return 4;
  case LSM_VOXEL_U64: case LSM_VOXEL_I64: case LSM_VOXEL_F64: return 8;
  default: return 0;
  }
}

int lsm_voxel_is_integer(lsm_voxel_type type) {
  return type >= LSM_VOXEL_U8 && type <= LSM_VOXEL_I64;
}

lsm_status lsm_voxels_count(const size_t n[3], lsm_voxel_type type, size_t *count,
                            const char *where, lsm_err *err) {
  if (n[0] == 0 || n[1] == 0 || n[2] == 0)
    return lsm_fail(err, LSM_ERR_INPUT, where, "%zu x %zu x %zu voxels: an axis is empty", n[0],
                    n[1], n[2]);
  size_t voxels, bytes;
  if (!lsm_size_mul3(n[0], n[1], n[2], &voxels) ||
      !lsm_size_mul(voxels, lsm_voxel_size(type) ? lsm_voxel_size(type) : 1, &bytes))
    return lsm_fail(err, LSM_ERR_LIMIT, where, "%zu x %zu x %zu voxels: the size overflows",
                    n[0], n[1], n[2]);
  *count = voxels;
  return LSM_OK;
}

double lsm_voxel_get(const lsm_voxels *v, size_t index) {
  switch (v->type) {
  case LSM_VOXEL_U64: return (double)((const uint64_t *)v->data)[index]; /* past INT64_MAX too */
  case LSM_VOXEL_F32: return ((const float *)v->data)[index];
  case LSM_VOXEL_F64: return ((const double *)v->data)[index];
  default: return lsm_voxel_is_integer(v->type) ? (double)lsm_voxel_get_int(v, index) : NAN;
  }
}

int64_t lsm_voxel_get_int(const lsm_voxels *v, size_t index) {
  const void *p = v->data;
  switch (v->type) {
  case LSM_VOXEL_U8: return ((const uint8_t *)p)[index];
  case LSM_VOXEL_I8: return ((const int8_t *)p)[index];
  case LSM_VOXEL_U16: return ((const uint16_t *)p)[index];
  case LSM_VOXEL_I16: return ((const int16_t *)p)[index];
  case LSM_VOXEL_U32: return ((const uint32_t *)p)[index];
  case LSM_VOXEL_I32: return ((const int32_t *)p)[index];
  case LSM_VOXEL_U64: {
    const uint64_t u = ((const uint64_t *)p)[index];
    return u > (uint64_t)INT64_MAX ? INT64_MAX : (int64_t)u;
  }
  case LSM_VOXEL_I64: return ((const int64_t *)p)[index];
  default: return 0;
  }
}

void lsm_voxel_set_int(lsm_voxels *v, size_t index, int64_t value) {
  void *p = v->data;
  switch (v->type) {
  case LSM_VOXEL_U8: ((uint8_t *)p)[index] = (uint8_t)value; break;
  case LSM_VOXEL_I8: ((int8_t *)p)[index] = (int8_t)value; break;
  case LSM_VOXEL_U16: ((uint16_t *)p)[index] = (uint16_t)value; break;
  case LSM_VOXEL_I16: ((int16_t *)p)[index] = (int16_t)value; break;
  case LSM_VOXEL_U32: ((uint32_t *)p)[index] = (uint32_t)value; break;
  case LSM_VOXEL_I32: ((int32_t *)p)[index] = (int32_t)value; break;
  case LSM_VOXEL_U64: ((uint64_t *)p)[index] = (uint64_t)value; break;
  case LSM_VOXEL_I64: ((int64_t *)p)[index] = value; break;
  default: break;
  }
}

int lsm_voxel_type_holds(lsm_voxel_type type, int64_t value) {
  switch (type) {
  case LSM_VOXEL_U8: return value >= 0 && value <= UINT8_MAX;
  case LSM_VOXEL_I8: return value >= INT8_MIN && value <= INT8_MAX;
  case LSM_VOXEL_U16: return value >= 0 && value <= UINT16_MAX;
  case LSM_VOXEL_I16: return value >= INT16_MIN && value <= INT16_MAX;
  case LSM_VOXEL_U32: return value >= 0 && value <= (int64_t)UINT32_MAX;
  case LSM_VOXEL_I32: return value >= INT32_MIN && value <= INT32_MAX;
  case LSM_VOXEL_U64: return value >= 0;
  case LSM_VOXEL_I64: return 1;
  default: return 0;
  }
}

lsm_voxel_type lsm_voxel_type_for_range(int64_t lo, int64_t hi) {
  static const lsm_voxel_type order[] = {LSM_VOXEL_U8,  LSM_VOXEL_I16, LSM_VOXEL_U16,
                                         LSM_VOXEL_I32, LSM_VOXEL_U32, LSM_VOXEL_I64};
  for (size_t k = 0; k < sizeof order / sizeof *order; ++k)
    if (lsm_voxel_type_holds(order[k], lo) && lsm_voxel_type_holds(order[k], hi)) return order[k];
  return LSM_VOXEL_I64;
}
