/* lsm_preview_render: the picture of preview3d.png, drawn cell by cell (part
 * of lsm_preview; see lsm_preview.h for what it shows).
 *
 * The camera is fixed when the renderer is made, for a volume of a given
 * number of planes; cells are then drawn in any order, as their planes
 * arrive, into a depth buffer: each pixel keeps the nearest point where its
 * ray first meets phi <= 0 in a cell.  Only cells with corners on both sides
 * of the surface (and not receding from the viewer), or with an inside
 * corner on the volume's boundary (a cap), can hold such a point.
 */
#ifndef LSM_PREVIEW_RENDER_H
#define LSM_PREVIEW_RENDER_H

#include <stddef.h>
#include <stdint.h>

/* The decimated volume: n[2] planes of n[0] x n[1] samples, row-major,
 * sample (0, 0, 0) at physical position o, spacings h. */
typedef struct lsm_render_volume {
  const float *vol;
  int n[3];
  double o[3], h[3];
} lsm_render_volume;

typedef struct lsm_render lsm_render;

/* A renderer framed for v (v->n[2] planes; the samples are not read), its
 * picture the background alone; NULL when out of memory. */
lsm_render *lsm_render_new(const lsm_render_volume *v);
/* Whether its framing was made for a volume of this many planes. */
int lsm_render_frames(const lsm_render *r, int planes);
/* Draws the cells between planes k and k + 1, k0 <= k < k1, of v (v->n[2]
 * planes so far, the cells' neighbours up to plane k1 + 1 among them);
 * complete: v->n[2] is the final count (its top plane bounds the volume).
 * threads > 1 split the picture into bands drawn in parallel. */
void lsm_render_cells(lsm_render *r, const lsm_render_volume *v, int k0, int k1, int complete,
                      int threads);
/* The picture: w * h RGB pixels. */
const uint8_t *lsm_render_pixels(const lsm_render *r, int *w, int *h);
void lsm_render_free(lsm_render **r);

#endif
