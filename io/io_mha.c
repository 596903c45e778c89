/* io_mha: the MetaImage header of volume.mha (one file, ElementDataFile = LOCAL,
 * the samples follow the header directly).
 *
 * The slice count and z spacing are unknown until the last slice (per-iteration
 * mode), so they are printed in fixed-width, right-aligned fields ("%20zu",
 * "%24.17g": MetaIO reads numbers with >>, which skips the leading blanks); the
 * header length is then independent of them and lsm_volume_writer rewrites it
 * in place at the end.  Offset is the centre of the first sample, as ITK and
 * VTK expect; the direction matrix is the identity.
 */
#include "io/lsm_io.h"

#include <stdio.h>

size_t lsm_mha_header(char *out, size_t cap, const lsm_volume_info *info) {
  if (!out || !info || cap == 0) return 0;
  const char *type = info->values == LSM_VALUES_MASK ? "MET_UCHAR" : "MET_FLOAT";
  char sp[3][32], o[3][32];
  lsm_volume_geometry_text(info, sp, o);
  int len = snprintf(out, cap,
                     "ObjectType = Image\n"
                     "NDims = 3\n"
                     "BinaryData = True\n"
                     "BinaryDataByteOrderMSB = False\n"
                     "CompressedData = False\n"
                     "TransformMatrix = 1 0 0 0 1 0 0 0 1\n"
                     "Offset = %s %s %s\n"
                     "CenterOfRotation = 0 0 0\n"
                     "ElementSpacing = %s %s %24s\n"
                     "DimSize = %d %d %20zu\n"
                     "ElementNumberOfChannels = 1\n"
                     "ElementType = %s\n"
                     "ElementDataFile = LOCAL\n",
                     o[0], o[1], o[2], sp[0], sp[1], sp[2], info->nx, info->ny, info->nz, type);
  if (len < 0 || (size_t)len >= cap) return 0;
  return (size_t)len;
}
