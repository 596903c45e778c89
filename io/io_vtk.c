/* io_vtk: the header of volume.vtk, a legacy VTK file (version 3.0, BINARY,
 * DATASET STRUCTURED_POINTS).  The legacy format stores binary samples big
 * endian; the writer (io_volume.c) swaps them.
 *
 * As for MetaImage, the slice count (in DIMENSIONS and POINT_DATA) and the z
 * spacing are printed in fixed-width right-aligned fields so the header can be
 * rewritten in place at the end; VTK's reader parses numbers with >>, which
 * skips the blanks.  ORIGIN is the centre of the first sample.
 */
#include "io/lsm_io.h"

#include <stdio.h>

size_t lsm_vtk_header(char *out, size_t cap, const lsm_volume_info *info) {
  if (!out || !info || cap == 0) return 0;
  const int mask = info->values == LSM_VALUES_MASK;
  size_t points = (size_t)info->nx * (size_t)info->ny * info->nz;
  char sp[3][32], o[3][32];
  lsm_volume_geometry_text(info, sp, o);
  int len = snprintf(out, cap,
                     "# vtk DataFile Version 3.0\n"
                     "lsmorph %s (%s), physical units\n"
                     "BINARY\n"
                     "DATASET STRUCTURED_POINTS\n"
                     "DIMENSIONS %d %d %20zu\n"
                     "SPACING %s %s %24s\n"
                     "ORIGIN %s %s %s\n"
                     "POINT_DATA %20zu\n"
                     "SCALARS %s %s 1\n"
                     "LOOKUP_TABLE default\n",
                     mask ? "mask" : "signed distance",
                     mask ? "255 inside, 0 outside" : "negative inside", info->nx, info->ny,
                     info->nz, sp[0], sp[1], sp[2], o[0], o[1], o[2],
                     points, mask ? "mask" : "sdf", mask ? "unsigned_char" : "float");
  if (len < 0 || (size_t)len >= cap) return 0;
  return (size_t)len;
}
