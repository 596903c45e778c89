/* lsm_slice: input slices as a gap holds them (see the header). */
#include "solver/recon/lsm_slice.h"

#include <string.h>

#include "solver/sdf/lsm_sdf.h"

void lsm_slice_free(lsm_slice *s) {
  if (s->filled.pixels != s->raw.pixels) lsm_mask_free(&s->filled);
  lsm_mask_free(&s->raw);
  memset(s, 0, sizeof *s);
}

lsm_status lsm_slice_load(const lsm_slice_source *src, size_t index, int width, int height,
                          lsm_input_kind input, lsm_slice *s, lsm_err *err) {
  memset(s, 0, sizeof *s);
  LSM_TRY(src->load(src->ctx, index, &s->raw, err));
  const char *name = src->name ? src->name(src->ctx, index) : NULL;
  if (s->raw.width != width || s->raw.height != height) {
    lsm_status st = lsm_fail(err, LSM_ERR_INPUT, name,
                             "slice is %dx%d but the first slice is %dx%d", s->raw.width,
                             s->raw.height, width, height);
    lsm_slice_free(s);
    return st;
  }
  if (input == LSM_INPUT_OUTLINE) {
    lsm_status st = lsm_outline_fill(&s->raw, &s->filled, err);
    if (st != LSM_OK) {
      lsm_slice_free(s);
      return st;
    }
  } else {
    s->filled = s->raw;
  }
  int hull = lsm_hull_centroid(&s->filled, &s->cx, &s->cy);
  if (hull < 0) {
    lsm_slice_free(s);
    return lsm_fail(err, LSM_ERR_NOMEM, name, "cannot allocate the convex hull");
  }
  s->empty = hull == 0;
  s->loaded = 1;
  return LSM_OK;
}

static int clamp_index(int v, int n) { return v < 0 ? 0 : v >= n ? n - 1 : v; }

/* The margin repeats the image's border pixels (rule border-extension), so a
 * shape touching the border goes on straight across it and keeps its depth
 * there, as the input slices written out do (their signed distance is taken
 * on the image).  A shape clear of the border is unchanged.  Not for outlines
 * (a contour is closed inside the image), nor for a mask full of the image
 * (its canvas would have no boundary at all). */
lsm_status lsm_mask_phi(const lsm_mask *m, lsm_input_kind input, int border, int ox, int oy,
                        lsm_grid *phi, lsm_err *err) {
  lsm_mask canvas;
  LSM_TRY(lsm_mask_create(phi->nx, phi->ny, &canvas, err));
  const size_t full = (size_t)m->width * (size_t)m->height;
  const int extend = border && input == LSM_INPUT_MASK && lsm_mask_count(m) < full;
  for (int cy = 0; cy < canvas.height; ++cy) {
    const int y = cy - oy;
    if (!extend && (y < 0 || y >= m->height)) continue;
    const uint8_t *row = m->pixels + (size_t)clamp_index(y, m->height) * (size_t)m->width;
    uint8_t *out = canvas.pixels + (size_t)cy * (size_t)canvas.width;
    for (int cx = 0; cx < canvas.width; ++cx) {
      const int x = cx - ox;
      if (!extend && (x < 0 || x >= m->width)) continue;
      out[cx] = row[clamp_index(x, m->width)];
    }
  }
  lsm_status st = input == LSM_INPUT_OUTLINE ? lsm_sdf_from_outline(&canvas, phi, err)
                                             : lsm_sdf_from_mask(&canvas, phi, err);
  lsm_mask_free(&canvas);
  return st;
}

lsm_status lsm_slice_phi(const lsm_slice *s, const lsm_stack_opts *o, int ox, int oy, lsm_grid *phi,
                         lsm_err *err) {
  return lsm_mask_phi(&s->raw, o->input, lsm_rule_on(&o->rules, LSM_RULE_BORDER_EXTENSION), ox, oy,
                      phi, err);
}

/* A neighbour takes part in the spline only if it exists and is not empty. */
int lsm_window_usable(const lsm_window *w, int k) { return w->s[k] && w->s[k]->loaded && !w->s[k]->empty; }
