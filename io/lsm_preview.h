/* lsm_preview: two pictures of a reconstruction, built while the slices
 * stream past, with bounded memory whatever the slice count.
 *
 *  preview.png    a montage of up to 16 evenly spaced output slices: grey
 *                 level = the fraction of each thumbnail pixel inside
 *                 (phi <= 0), input slices framed in orange, the others in
 *                 grey, each labelled with its slice number (as in slices/).
 *                 The sample is kept with a doubling stride: every stride-th
 *                 slice is kept, and when 64 are kept every other one is
 *                 dropped and the stride doubles (plus the last slice).
 *  preview3d.png  a shaded picture of the surface phi = 0, about 420 pixels
 *                 across: orthographic ray marching of a decimated copy of
 *                 the volume (at most LSM_PREVIEW_XY samples across, at most
 *                 LSM_PREVIEW_Z planes high: planes are resampled at a
 *                 regular height step, which doubles when they would exceed
 *                 the cap) seen obliquely from above with z up, Lambert
 *                 shading plus a little ambient and specular light, normals
 *                 from central differences.  The cells where a ray can first
 *                 meet the surface (both signs at their corners, and not
 *                 receding from the viewer; or an inside corner on the
 *                 volume's boundary) are splatted onto a depth buffer first:
 *                 a ray marches only from where it enters the first of them
 *                 to where it leaves the last, at 0.4 sample spacings (phi
 *                 need not be a distance), and a pixel that meets none is
 *                 background at once.  The object is closed at the volume's
 *                 boundary (the caps are drawn flat).
 */
#ifndef LSM_PREVIEW_H
#define LSM_PREVIEW_H

#include <stddef.h>

#include "solver/base/lsm_status.h"

#define LSM_PREVIEW_XY 160
#define LSM_PREVIEW_Z 128

typedef struct lsm_preview lsm_preview;

/* For nx x ny slices of pixel size sx x sy; dz is the nominal slice spacing
 * (used for the initial height step of the decimated copy). */
lsm_status lsm_preview_open(int nx, int ny, double sx, double sy, double dz, lsm_preview **out,
                            lsm_err *err);
/* The heights the slices will span, told before the first slice: the
 * rendering is then framed at once and drawn as the slices arrive (else all
 * at lsm_preview_write; it is also when the slices end up spanning more). */
lsm_status lsm_preview_expect(lsm_preview *p, double z_first, double z_last, lsm_err *err);
/* Adds the next slice (nx*ny floats, row-major, row 0 first) at height z
 * (increasing); input_index >= 0 marks a slice that reproduces an input. */
lsm_status lsm_preview_add_slice(lsm_preview *p, const float *phi, double z, long input_index,
                                 lsm_err *err);
/* Writes the montage to montage_path and the rendering to render_path
 * (either may be NULL to skip it). */
lsm_status lsm_preview_write(lsm_preview *p, const char *montage_path, const char *render_path,
                             lsm_err *err);
void lsm_preview_free(lsm_preview **p);

#endif
