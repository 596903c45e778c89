/* lsm_gap: a gap's working fields (see the header). */
#include "solver/recon/lsm_gap.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "solver/recon/lsm_ends.h"
#include "solver/recon/lsm_parts.h"
#include "solver/recon/lsm_unmatched.h"
#include "solver/recon/lsm_zprofile.h"

static int border_rule(const lsm_stack_opts *o) {
  return lsm_rule_on(&o->rules, LSM_RULE_BORDER_EXTENSION);
}

void lsm_gap_free(lsm_gap *g) {
  lsm_grid_destroy(&g->phi_a);
  lsm_grid_destroy(&g->phi_b);
  lsm_grid_destroy(&g->slope_a);
  lsm_grid_destroy(&g->slope_b);
  for (int k = 0; k < g->parts; ++k) {
    lsm_grid_destroy(&g->part_a[k]);
    lsm_grid_destroy(&g->part_b[k]);
  }
  g->parts = 0;
  if (g->moving) lsm_moving_free(&g->mv);
  g->moving = 0;
  lsm_grid_destroy(&g->carried);
}

const lsm_grid *lsm_gap_carry(lsm_gap *g, double s, lsm_grid *mix) {
  if (!g->moving) return mix;
  lsm_moving_carry(&g->mv, s, mix, g->carried);
  return g->carried;
}

/* --motion field: phi_a, phi_b into the mid frame of the pair's field (lsm_moving), where
 * the rules and the morph then run. */
static lsm_status gap_moving(const lsm_stack_opts *o, int width, int height, const lsm_window *w,
                             lsm_flows *flows, int threads, lsm_gap *g, lsm_err *err) {
  const lsm_motion_field *field = NULL;
  LSM_TRY(lsm_flows_get(flows, w->gap, w->s[1], w->s[2], o, width, height, threads, &field, err));
  if (!field) return LSM_OK; /* no part takes it: the gap stays in place */
  LSM_TRY(lsm_grid_clone(g->phi_a, &g->carried, err));
  LSM_TRY(lsm_moving_setup(&g->mv, field, g->phi_a, g->phi_b, threads, err));
  g->moving = 1;
  return LSM_OK;
}

/* A neighbour's phi (side 0: the slice before A, 1: after B) pulled into the mid frame
 * along its own pair's field. */
static lsm_status moving_neighbour(const lsm_stack_opts *o, int width, int height,
                                   const lsm_window *w, lsm_flows *flows, int threads, int side,
                                   lsm_gap *g, lsm_grid *phi, lsm_err *err) {
  const lsm_motion_field *field = NULL;
  if (side == 0)
    LSM_TRY(lsm_flows_get(flows, w->gap - 1, w->s[0], w->s[1], o, width, height, threads, &field,
                          err));
  else
    LSM_TRY(lsm_flows_get(flows, w->gap + 1, w->s[2], w->s[3], o, width, height, threads, &field,
                          err));
  /* a pair beyond that stays in place moves the neighbour by this gap's half map only */
  lsm_motion_field *none = NULL;
  if (!field) LSM_TRY(lsm_motion_field_zero(phi, g->mv.w->step, &none, err));
  const lsm_motion_field *beyond = field ? field : none;
  lsm_status st = lsm_moving_pull_neighbour(&g->mv, beyond, side, phi, err);
  const double H = w->z[2] - w->z[1], Hb = side ? w->z[3] - w->z[2] : w->z[1] - w->z[0];
  if (st == LSM_OK) st = lsm_moving_tangent(&g->mv, beyond, side, H, Hb, err);
  lsm_motion_field_destroy(&none);
  return st;
}

/* phi of one part on the window around it (bounding box + parts_margin_px,
 * within the image); *ox, *oy: the window's origin on the image.  Farther
 * out the output keeps the rest's phi (the zero level is exact either way). */
static lsm_status part_phi(const lsm_mask *part, const lsm_stack_opts *o, lsm_grid **phi, int *ox,
                           int *oy, lsm_err *err) {
  const int margin = (int)o->rules.parts_margin_px;
  int x0 = 0, y0 = 0, x1 = part->width - 1, y1 = part->height - 1;
  lsm_mask_bounds(part, &x0, &y0, &x1, &y1); /* a part is never empty */
  x0 = x0 - margin < 0 ? 0 : x0 - margin;
  y0 = y0 - margin < 0 ? 0 : y0 - margin;
  x1 = x1 + margin >= part->width ? part->width - 1 : x1 + margin;
  y1 = y1 + margin >= part->height ? part->height - 1 : y1 + margin;
  *ox = x0;
  *oy = y0;
  LSM_TRY(lsm_grid_create(x1 - x0 + 1, y1 - y0 + 1, (float)o->pixel_dx, (float)o->pixel_dy, phi,
                          err));
  return lsm_mask_phi(part, LSM_INPUT_MASK, border_rule(o), -x0, -y0, *phi, err);
}

/* Parts that moved (rule moving-parts; lsm_parts finds them): each pair is
 * taken out of phi_A and phi_B and moves on its own, at fraction s the blend
 * of A's part moved by s d and B's part moved back by (1 - s) d.  Unless both
 * slices have nothing else left, the rest must keep something on each side
 * (else nothing moves: the halfway rule handles a side with nothing). */
static lsm_status gap_parts(const lsm_stack_opts *o, int width, int height, const lsm_window *w,
                            lsm_gap *g, lsm_err *err) {
  const lsm_slice *a = w->s[1], *b = w->s[2];
  lsm_part_move mv[LSM_PARTS_MAX];
  int count = 0;
  LSM_TRY(lsm_parts_moved(&a->filled, &b->filled, &o->rules, mv, &count, err));
  if (count == 0) return LSM_OK;
  lsm_mask rest_a = {0, 0, NULL}, rest_b = {0, 0, NULL};
  lsm_status st = lsm_mask_create(width, height, &rest_a, err);
  if (st == LSM_OK) st = lsm_mask_create(width, height, &rest_b, err);
  size_t left_a = 0, left_b = 0;
  if (st == LSM_OK) {
    const size_t cells = (size_t)width * (size_t)height;
    for (size_t p = 0; p < cells; ++p) {
      uint8_t in_a = a->filled.pixels[p], in_b = b->filled.pixels[p];
      for (int k = 0; k < count; ++k) {
        in_a &= (uint8_t)!mv[k].part_a.pixels[p];
        in_b &= (uint8_t)!mv[k].part_b.pixels[p];
      }
      rest_a.pixels[p] = in_a;
      rest_b.pixels[p] = in_b;
      left_a += in_a;
      left_b += in_b;
    }
  }
  const int usable = st == LSM_OK && (left_a > 0) == (left_b > 0);
  for (int k = 0; usable && st == LSM_OK && k < count; ++k) {
    g->parts = k + 1;
    g->part_dx[k] = mv[k].dx;
    g->part_dy[k] = mv[k].dy;
    st = part_phi(&mv[k].part_a, o, &g->part_a[k], &g->part_ax[k], &g->part_ay[k], err);
    if (st == LSM_OK)
      st = part_phi(&mv[k].part_b, o, &g->part_b[k], &g->part_bx[k], &g->part_by[k], err);
  }
  if (usable && st == LSM_OK) {
    g->rest_empty = left_a == 0;
    const int border = border_rule(o);
    st = lsm_mask_phi(&rest_a, LSM_INPUT_MASK, border, g->f.pad, g->f.pad_y, g->phi_a, err);
    if (st == LSM_OK)
      st = lsm_mask_phi(&rest_b, LSM_INPUT_MASK, border, g->f.pad, g->f.pad_y, g->phi_b, err);
  }
  lsm_mask_free(&rest_a);
  lsm_mask_free(&rest_b);
  for (int k = 0; k < count; ++k) lsm_part_move_free(&mv[k]);
  return st;
}

/* Adds the moving parts to an output slice at fraction s (union: min), over
 * the two parts' windows as moved to s. */
void lsm_gap_paste_parts(const lsm_gap *g, double s, float *out) {
  const lsm_frame *f = &g->f;
  for (int k = 0; k < g->parts; ++k) {
    const lsm_grid *pa = g->part_a[k], *pb = g->part_b[k];
    /* A's window moved forward by s d, B's back by (1 - s) d */
    const double ax = g->part_ax[k] + s * g->part_dx[k], ay = g->part_ay[k] + s * g->part_dy[k];
    const double bx = g->part_bx[k] - (1.0 - s) * g->part_dx[k];
    const double by = g->part_by[k] - (1.0 - s) * g->part_dy[k];
    int x0 = (int)floor(fmin(ax, bx)), y0 = (int)floor(fmin(ay, by));
    int x1 = (int)ceil(fmax(ax + pa->nx - 1, bx + pb->nx - 1));
    int y1 = (int)ceil(fmax(ay + pa->ny - 1, by + pb->ny - 1));
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 > f->width - 1) x1 = f->width - 1;
    if (y1 > f->height - 1) y1 = f->height - 1;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        float v = (float)((1.0 - s) * lsm_grid_sample(pa, x - ax, y - ay) +
                          s * lsm_grid_sample(pb, x - bx, y - by));
        if (v > f->clamp) v = f->clamp;
        float *o = &out[(size_t)y * f->width + x];
        if (v < *o) *o = v;
      }
  }
}

lsm_status lsm_gap_setup(const lsm_stack_opts *o, int width, int height, const lsm_window *w,
                         lsm_flows *flows, int threads, lsm_gap *g, lsm_err *err) {
  memset(g, 0, sizeof *g);
  const lsm_slice *a = w->s[1], *b = w->s[2];
  /* --motion field or auto: whether this pair takes the field (auto: lsm_choose); a pair
   * that does runs unaligned, one that does not as with --motion none */
  lsm_grid *chosen_a = NULL, *chosen_b = NULL; /* the choice's phi, when it made them */
  if (flows && !a->empty && !b->empty && !o->per_iteration)
    LSM_TRY(lsm_flows_choice(flows, w->gap, a, b, o, width, height, threads, &g->choice,
                             &chosen_a, &chosen_b, err));
  const lsm_align align = g->choice.field && o->align == LSM_ALIGN_AUTO ? LSM_ALIGN_NONE : o->align;
  lsm_status st = lsm_frame_setup(&g->f, w, align, o->interp, width, height, o->pixel_dx,
                                  o->pixel_dy, &o->rules, err);
  const lsm_frame *f = &g->f;
  /* on the fields' canvas, unshifted, the gap's phi are the choice's */
  if (st == LSM_OK && chosen_a && f->pad == LSM_FLOWS_PAD && f->pad_y == LSM_FLOWS_PAD &&
      !f->dx[1] && !f->dy[1] && !f->dx[2] && !f->dy[2]) {
    g->phi_a = chosen_a;
    g->phi_b = chosen_b;
    chosen_a = chosen_b = NULL;
  }
  lsm_grid_destroy(&chosen_a);
  lsm_grid_destroy(&chosen_b);
  if (st != LSM_OK) {
    lsm_gap_free(g);
    return st;
  }
  const int nx = width + 2 * f->pad, ny = height + 2 * f->pad_y;
  if (o->canvas_max > 0.0 && (double)nx * (double)ny > o->canvas_max) {
    st = lsm_fail(err, LSM_ERR_LIMIT, NULL,
                  "the gap from height %g to %g: its shape moved by %d x %d px, and aligned it "
                  "is worked on a canvas of %dx%d cells, more than the %.0f cells the memory "
                  "left allows (--max-memory): --align none works in place, or allow more "
                  "with --max-memory BYTES",
                  w->z[1], w->z[2], f->dx[2] - f->dx[1], f->dy[2] - f->dy[1], nx, ny,
                  o->canvas_max);
    lsm_gap_free(g);
    return st;
  }
  const float hx = (float)o->pixel_dx, hy = (float)o->pixel_dy;
  if (!g->phi_a) {
    st = lsm_grid_create(nx, ny, hx, hy, &g->phi_a, err);
    if (st == LSM_OK) st = lsm_grid_create(nx, ny, hx, hy, &g->phi_b, err);
    if (st == LSM_OK)
      st = lsm_slice_phi(a, o, f->pad - f->dx[1], f->pad_y - f->dy[1], g->phi_a, err);
    if (st == LSM_OK)
      st = lsm_slice_phi(b, o, f->pad - f->dx[2], f->pad_y - f->dy[2], g->phi_b, err);
  }
  if (st == LSM_OK && g->choice.field && f->pad == LSM_FLOWS_PAD && f->pad_y == LSM_FLOWS_PAD)
    st = gap_moving(o, width, height, w, flows, threads, g, err);
  if (st == LSM_OK && !g->moving && !a->empty && !b->empty && o->method != LSM_METHOD_BLEND &&
      o->input == LSM_INPUT_MASK && !o->per_iteration && !f->aligned &&
      lsm_rule_on(&o->rules, LSM_RULE_MOVING_PARTS))
    st = gap_parts(o, width, height, w, g, err);
  /* (blend stays the classic baseline, without the unmatched rule) */
  const int caps = !a->empty && !b->empty && o->method != LSM_METHOD_BLEND && !g->rest_empty &&
                   lsm_rule_on(&o->rules, LSM_RULE_UNMATCHED);
  const int slopes = o->interp == LSM_INTERP_CUBIC && !a->empty && !b->empty && !o->per_iteration &&
                     !g->rest_empty;
  /* phi of the non-empty neighbours, prev in A's place and next in B's: read
   * by the branch test of the unmatched rule, then made secants for the
   * slopes */
  lsm_grid *beyond[2] = {NULL, NULL};
  for (int side = 0; side < 2 && st == LSM_OK && (caps || slopes); ++side) {
    const int k = side ? 3 : 0;
    if (!lsm_window_usable(w, k)) continue;
    st = lsm_grid_create(nx, ny, hx, hy, &beyond[side], err);
    if (st == LSM_OK)
      st = lsm_slice_phi(w->s[k], o, f->pad - f->dx[k], f->pad_y - f->dy[k], beyond[side], err);
    if (st == LSM_OK && g->moving)
      st = moving_neighbour(o, width, height, w, flows, threads, side, g, beyond[side], err);
  }
  if (st == LSM_OK && caps) {
    /* both directions see the original sets: lowering phi_b inside A's
     * unmatched components leaves it positive there, so B's inside is
     * unchanged for the second */
    st = lsm_cap_unmatched(g->phi_a, g->phi_b, beyond[0], &o->rules, err);
    if (st == LSM_OK) st = lsm_cap_unmatched(g->phi_b, g->phi_a, beyond[1], &o->rules, err);
  }
  if (st == LSM_OK && slopes)
    st = lsm_zprofile_slopes(w, f->H, g->phi_a, g->phi_b, beyond, &o->rules, &g->slope_a,
                             &g->slope_b, err);
  lsm_grid_destroy(&beyond[0]);
  lsm_grid_destroy(&beyond[1]);
  if (st != LSM_OK) {
    lsm_gap_free(g);
    return st;
  }
  /* the halfway rule's constant for an empty side (per-iteration mode) */
  if (a->empty != b->empty && lsm_rule_on(&o->rules, LSM_RULE_EMPTY_DEPTH)) {
    lsm_grid *full = a->empty ? g->phi_b : g->phi_a, *none = a->empty ? g->phi_a : g->phi_b;
    const double depth = lsm_end_depth(full);
    const double c = o->method == LSM_METHOD_BLEND ? depth : depth / log(2.0);
    lsm_grid_fill(none, (float)c);
  }
  return LSM_OK;
}
