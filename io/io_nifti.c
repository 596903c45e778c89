/* io_nifti: the NIfTI-1 header of volume.nii (single file, "n+1": the 348-byte
 * header, a 4-byte extension flag of zeros, then the samples from byte 352).
 *
 * Everything is little endian, as the samples are; readers tell the byte
 * order from sizeof_hdr.  The header is binary with fixed offsets, so its
 * length never depends on the slice count and lsm_volume_writer rewrites it
 * in place at the end, like the text headers.
 *
 * Geometry.  NIfTI's world is RAS+ (x to the right, y to the front); ITK and
 * 3D Slicer work in LPS+ and turn a NIfTI affine into LPS by negating its x and
 * y rows.  volume.nrrd and volume.mha have the identity direction with origin
 * (ox, oy, oz) in those tools, so volume.nii gets the affine that ITK turns
 * into the same: diag(-sx, -sy, sz) with offset (-ox, -oy, oz).  All three then
 * load at the same place in 3D Slicer or ITK-SNAP.  The qform (a half turn
 * about z: quaternion b = c = 0, d = 1, qfac 1) and the sform say the same, both
 * with code 1 (scanner-based coordinates: lsmorph's own physical frame).
 * NIfTI-1 holds spacings and offsets as float32 and sizes as 16-bit integers:
 * at most LSM_NIFTI_DIM_MAX samples along each axis (the caller refuses more).
 * The length unit is left unknown (xyzt_units 0): lsmorph's unit is whatever
 * --pixel-size was given in.
 */
#include "io/lsm_io.h"

#include <string.h>

static void put_i16(unsigned char *p, int v) {
  const unsigned u = (unsigned)(v & 0xffff);
  p[0] = (unsigned char)(u & 0xffu);
  p[1] = (unsigned char)(u >> 8);
}

static void put_i32(unsigned char *p, long v) {
  const unsigned long u = (unsigned long)v & 0xfffffffful;
  for (int k = 0; k < 4; ++k) p[k] = (unsigned char)((u >> (8 * k)) & 0xffu);
}

static void put_f32(unsigned char *p, double v) {
  const float f = (float)v;
  uint32_t u;
  memcpy(&u, &f, sizeof u);
  for (int k = 0; k < 4; ++k) p[k] = (unsigned char)((u >> (8 * k)) & 0xffu);
}

size_t lsm_nifti_header(unsigned char *out, size_t cap, const lsm_volume_info *info) {
  if (!out || !info || cap < LSM_NIFTI_HEADER_BYTES) return 0;
  if (info->nx < 1 || info->ny < 1 || info->nx > LSM_NIFTI_DIM_MAX ||
      info->ny > LSM_NIFTI_DIM_MAX || info->nz > LSM_NIFTI_DIM_MAX)
    return 0;
  const int mask = info->values == LSM_VALUES_MASK;
  unsigned char *h = out;
  memset(h, 0, LSM_NIFTI_HEADER_BYTES);
  put_i32(h + 0, 348);                 /* sizeof_hdr */
  h[38] = 'r';                         /* regular */
  put_i16(h + 40, 3);                  /* dim[0]: three dimensions */
  put_i16(h + 42, info->nx);
  put_i16(h + 44, info->ny);
  put_i16(h + 46, (int)info->nz);      /* 0 in the provisional header */
  for (int k = 4; k < 8; ++k) put_i16(h + 40 + 2 * k, 1);
  put_i16(h + 70, mask ? 2 : 16);      /* datatype: DT_UINT8 or DT_FLOAT32 */
  put_i16(h + 72, mask ? 8 : 32);      /* bitpix */
  put_f32(h + 76, 1.0);                /* pixdim[0] = qfac */
  put_f32(h + 80, info->sx);
  put_f32(h + 84, info->sy);
  put_f32(h + 88, info->sz);
  put_f32(h + 108, (double)LSM_NIFTI_HEADER_BYTES); /* vox_offset */
  put_f32(h + 112, 1.0);               /* scl_slope: the samples as they are */
  if (mask) put_f32(h + 124, 255.0);   /* cal_max (cal_min stays 0) */
  const char *descrip = mask ? "lsmorph mask: 255 inside, 0 outside"
                             : "lsmorph signed distance, negative inside";
  memcpy(h + 148, descrip, strlen(descrip)); /* descrip[80], NUL padded */
  put_i16(h + 252, 1);                 /* qform_code: scanner-based */
  put_i16(h + 254, 1);                 /* sform_code */
  put_f32(h + 264, 1.0);               /* quatern_d: a half turn about z */
  put_f32(h + 268, 0.0 - info->ox);    /* qoffset_x, y, z (0 - o: no -0) */
  put_f32(h + 272, 0.0 - info->oy);
  put_f32(h + 276, info->oz);
  put_f32(h + 280, -info->sx);         /* srow_x = (-sx, 0, 0, -ox) */
  put_f32(h + 292, 0.0 - info->ox);
  put_f32(h + 300, -info->sy);         /* srow_y = (0, -sy, 0, -oy) */
  put_f32(h + 308, 0.0 - info->oy);
  put_f32(h + 320, info->sz);          /* srow_z = (0, 0, sz, oz) */
  put_f32(h + 324, info->oz);
  memcpy(h + 344, "n+1", 4);           /* magic, with its NUL */
  /* bytes 348..351: the extension flag, zero: no extensions */
  return LSM_NIFTI_HEADER_BYTES;
}
