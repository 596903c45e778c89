/* lsm_gap_run: one gap's output slices (see the header). */
#include "solver/recon/lsm_gap_run.h"

#include <math.h>
#include <stdlib.h>

#include "solver/base/lsm_clock.h"
#include "solver/recon/lsm_ends.h"
#include "solver/recon/lsm_park.h"
#include "solver/recon/lsm_pinholes.h"
#include "solver/recon/lsm_two_sided.h"
#include "solver/recon/lsm_zprofile.h"

/* A gap with exactly one empty side: the object ends inside it (lsm_ends),
 * in the frame of the pair, which keeps moving at the N -> F centroid
 * velocity when that pair is aligned (lsm_frame_setup). */
static lsm_status run_gap_cap(lsm_run *r, const lsm_window *w, lsm_gap *g, int a_empty,
                              const double *zs, const double *fs, size_t n, lsm_pair_stats *ps,
                              lsm_err *err) {
  const lsm_stack_opts *o = r->opts;
  const lsm_grid *full = a_empty ? g->phi_b : g->phi_a;
  const int kn = a_empty ? 3 : 0, kf = a_empty ? 2 : 1; /* beyond, and the full slice */
  /* --ends auto (rule ends-auto): the tip where the empty slice is the
   * stack's first or last, nothing past mid-gap where more slices lie beyond */
  const int outermost = a_empty ? w->at_start : w->at_end;
  const int halfway =
      o->ends == LSM_ENDS_HALFWAY ||
      (o->ends == LSM_ENDS_AUTO && !outermost && lsm_rule_on(&o->rules, LSM_RULE_ENDS_AUTO));
  /* with no slice beyond F the cubic end is a flat end (rule end-lone-flat) */
  const int lone = !lsm_window_usable(w, kn) && !lsm_rule_on(&o->rules, LSM_RULE_END_LONE_FLAT);
  const lsm_end_profile profile =
      o->interp == LSM_INTERP_CUBIC && !lone
          ? (halfway ? LSM_END_TREND_HALFWAY : LSM_END_TREND)
      : o->method == LSM_METHOD_BLEND ? LSM_END_BLEND
                                      : LSM_END_PARABOLOID;
  lsm_grid *work = NULL, *beyond = NULL;
  lsm_end *end = NULL;
  LSM_TRY(lsm_grid_clone(full, &work, err));
  lsm_status st = LSM_OK;
  if (lsm_end_profile_is_trend(profile) && lsm_window_usable(w, kn)) {
    st = lsm_grid_clone(full, &beyond, err);
    if (st == LSM_OK)
      st = lsm_slice_phi(w->s[kn], o, g->f.pad - g->f.dx[kn], g->f.pad_y - g->f.dy[kn],
                         beyond, err);
  }
  lsm_grid *farther = NULL;
  if (st == LSM_OK && beyond && w->farther && w->farther->loaded && !w->farther->empty) {
    /* M in the frame: centred on its own centroid where the end is aligned */
    int dx = 0, dy = 0;
    if (g->f.aligned || g->f.end_aligned) {
      dx = lsm_pixel_shift(w->farther->cx - 0.5 * (g->f.width - 1));
      dy = lsm_pixel_shift(w->farther->cy - 0.5 * (g->f.height - 1));
    }
    st = lsm_grid_clone(full, &farther, err);
    if (st == LSM_OK)
      st = lsm_slice_phi(w->farther, o, g->f.pad - dx, g->f.pad_y - dy, farther, err);
  }
  if (st == LSM_OK)
    st = lsm_end_create(full, beyond, fabs(w->z[kn] - w->z[kf]), farther,
                        fabs(w->z_farther - w->z[kn]), g->f.H, profile, &o->rules, &end, err);
  lsm_grid_destroy(&beyond);
  lsm_grid_destroy(&farther);
  /* the linear profiles' R: F's depth on its own image, not the canvas margin */
  if (st == LSM_OK && !lsm_end_profile_is_trend(profile))
    lsm_end_set_depth(end, lsm_end_depth_in(full, g->f.pad - g->f.dx[kf], g->f.pad_y - g->f.dy[kf],
                                            g->f.width, g->f.height));
  for (size_t k = 0; st == LSM_OK && k < n; ++k) {
    lsm_end_at(end, a_empty ? 1.0 - fs[k] : fs[k], work);
    lsm_frame_extract(&g->f, work, fs[k], r->out);
    st = lsm_emit(r, zs[k], -1, err);
    ps->slices++;
  }
  lsm_end_destroy(&end);
  lsm_grid_destroy(&work);
  return st;
}

/* Default mode, one gap: the output heights zs (fractions fs) strictly inside it. */
lsm_status lsm_gap_run(lsm_run *r, const lsm_window *w, const double *zs,
                       const double *fs, size_t n, lsm_pair_stats *ps, lsm_err *err) {
  if (n == 0) return LSM_OK;
  const lsm_slice *a = w->s[1], *b = w->s[2];
  const size_t cells = (size_t)r->width * (size_t)r->height;
  lsm_pinhole_fill fill = {a, b, NULL, NULL, NULL, NULL};
  fill.cls = lsm_alloc(cells, sizeof *fill.cls, err, "hole marks");
  fill.queue = fill.cls ? lsm_alloc(cells, sizeof *fill.queue, err, "hole queue") : NULL;
  if (!fill.queue) {
    free(fill.cls);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  /* (not for blend: it stays the textbook, holes and all) */
  if (lsm_rule_on(&r->opts->rules, LSM_RULE_PINHOLE_FILL) && r->opts->method != LSM_METHOD_BLEND &&
      !lsm_mask_has_hole(&a->filled, fill.cls, fill.queue) &&
      !lsm_mask_has_hole(&b->filled, fill.cls, fill.queue))
    r->fill = &fill;
  lsm_gap g;
  lsm_status st = lsm_gap_setup(r->opts, r->width, r->height, w, r->flows, r->morph.threads, &g, err);
  if (st != LSM_OK) {
    r->fill = NULL;
    free(fill.cls);
    free(fill.queue);
    return st;
  }
  ps->cells = (long long)g.phi_a->nx * g.phi_a->ny;
  ps->aligned = g.f.aligned || g.f.end_aligned; /* an end moving on with the pair beyond */
  ps->moving_parts = g.parts;
  ps->motion_tests = g.choice.tests;
  ps->motion_field = g.moving;
  ps->motion_missed_field = g.choice.missed_field;
  ps->motion_missed_in_place = g.choice.missed_in_place;
  if (g.moving) {
    ps->motion_iterations = g.mv.w->iterations;
    ps->motion_seconds = g.mv.w->seconds;
    ps->motion_max_px = g.mv.w->max_displacement;
  }
  /* no more parts than the slices' overlap groups allow (rule one-piece; not
   * for blend, the textbook) */
  lsm_specks specks = {0, fill.cls, fill.queue};
  if (!a->empty && !b->empty && !g.rest_empty && r->opts->method != LSM_METHOD_BLEND &&
      lsm_rule_on(&r->opts->rules, LSM_RULE_ONE_PIECE)) {
    st = lsm_specks_allowed(&a->filled, &b->filled, g.f.dx[2] - g.f.dx[1], g.f.dy[2] - g.f.dy[1],
                            fill.cls, fill.queue, &specks.allowed, err);
    r->specks = &specks;
  }
  if (st == LSM_OK && ((a->empty && b->empty) || g.rest_empty)) {
    lsm_grid_fill(g.phi_a, g.f.clamp);
    for (size_t k = 0; st == LSM_OK && k < n; ++k) {
      lsm_frame_extract(&g.f, g.phi_a, fs[k], r->out);
      lsm_gap_paste_parts(&g, fs[k], r->out);
      st = lsm_emit(r, zs[k], -1, err);
      ps->slices++;
    }
  } else if (st == LSM_OK && a->empty != b->empty) {
    st = run_gap_cap(r, w, &g, a->empty, zs, fs, n, ps, err);
  } else if (st == LSM_OK && r->opts->method == LSM_METHOD_BLEND) {
    lsm_grid *mix = NULL;
    st = lsm_grid_clone(g.phi_a, &mix, err);
    for (size_t k = 0; st == LSM_OK && k < n; ++k) {
      const float s = (float)fs[k];
      for (int j = 0; j < mix->ny; ++j)
        for (int i = 0; i < mix->nx; ++i)
          LSM_AT(mix, i, j) = (1.0f - s) * LSM_AT(g.phi_a, i, j) + s * LSM_AT(g.phi_b, i, j);
      lsm_zprofile_add_cubic(g.phi_a, g.phi_b, g.slope_a, g.slope_b, fs[k], &r->opts->rules, mix);
      lsm_frame_extract(&g.f, lsm_gap_carry(&g, fs[k], mix), fs[k], r->out);
      st = lsm_emit(r, zs[k], -1, err);
      ps->slices++;
    }
    lsm_grid_destroy(&mix);
  } else if (st == LSM_OK) {
    st = lsm_two_sided_run(r, &g, zs, fs, n, ps, err);
  }
  lsm_gap_free(&g);
  r->fill = NULL;
  r->specks = NULL;
  lsm_grid_destroy(&fill.phi_a);
  lsm_grid_destroy(&fill.phi_b);
  free(fill.cls);
  free(fill.queue);
  return st;
}

/* Per-iteration mode, one gap: run to convergence once to count the
 * iterations k, then again emitting iterate n at height linspace(z_A, z_B, k+2)[n]. */
lsm_status lsm_gap_run_iterations(lsm_run *r, const lsm_window *w, lsm_pair_stats *ps,
                                  lsm_err *err) {
  const double za = w->z[1], zb = w->z[2];
  lsm_gap g;
  LSM_TRY(lsm_gap_setup(r->opts, r->width, r->height, w, NULL, r->morph.threads, &g, err));
  ps->cells = (long long)g.phi_a->nx * g.phi_a->ny;
  ps->aligned = g.f.aligned || g.f.end_aligned; /* an end moving on with the pair beyond */
  ps->moving_parts = g.parts;
  /* An empty source has no front to move: morph the target into the empty
   * slice instead (it shrinks to nothing) and emit its iterates in reverse.
   * With one empty side the object ends halfway (as in default mode): the
   * morph stops when the shape has vanished, and its iterates fill the half
   * of the gap next to the non-empty slice. */
  const int reverse = w->s[1]->empty && !w->s[2]->empty;
  const int cap = w->s[1]->empty != w->s[2]->empty;
  const lsm_grid *from = reverse ? g.phi_b : g.phi_a, *to = reverse ? g.phi_a : g.phi_b;
  lsm_morph *m = NULL;
  const double t0 = lsm_clock_seconds();
  lsm_status st = lsm_morph_create(from, to, &r->morph, &m, err);
  int k = 0;
  const int still = st == LSM_OK && !isfinite(lsm_morph_dt(m)); /* nothing can move */
  while (st == LSM_OK && !still && k < r->opts->max_iter) {
    st = lsm_run_check_stop(r, err);
    if (st == LSM_OK) st = lsm_morph_step(m, INFINITY, err);
    ++k;
    if (st == LSM_OK && lsm_morph_cp(m) <= r->opts->tol) break;
    if (st == LSM_OK && cap) {
      const lsm_grid *pm = lsm_morph_phi(m);
      if (!pm) st = lsm_fail(err, lsm_morph_error(m)->status, NULL, "%s", lsm_morph_error(m)->msg);
      else if (lsm_grid_min(pm) > 0.0f) break; /* vanished */
    }
  }
  if (st == LSM_OK) {
    ps->iterations = k;
    ps->dt = isfinite(lsm_morph_dt(m)) ? lsm_morph_dt(m) : 0.0;
    ps->cp = still ? 0.0 : lsm_morph_cp(m);
    ps->t_final = lsm_morph_time(m);
    ps->hit_max_iter = k >= r->opts->max_iter && lsm_morph_cp(m) > r->opts->tol;
  }
  lsm_morph_destroy(&m);
  double solver = lsm_clock_seconds() - t0;
  const size_t cells = (size_t)r->width * (size_t)r->height;
  lsm_park *park = NULL;
  if (st == LSM_OK && reverse && k > 0)
    st = lsm_park_open(cells, (size_t)k, r->opts->held_max, &park, err);
  if (st == LSM_OK && k > 0) st = lsm_morph_create(from, to, &r->morph, &m, err);
  for (int n = 1; st == LSM_OK && n <= k; ++n) {
    double t1 = lsm_clock_seconds();
    st = lsm_run_check_stop(r, err);
    if (st == LSM_OK) st = lsm_morph_step(m, INFINITY, err);
    if (st != LSM_OK) break;
    const double span = cap ? 0.5 * (double)(k + 1) / (double)k : 1.0; /* last iterate at 1/2 */
    const double s = reverse ? 1.0 - span * (double)n / (double)(k + 1)
                             : span * (double)n / (double)(k + 1);
    const lsm_grid *pm = lsm_morph_phi(m);
    if (!pm) {
      st = lsm_fail(err, lsm_morph_error(m)->status, NULL, "%s", lsm_morph_error(m)->msg);
      break;
    }
    lsm_frame_extract(&g.f, pm, s, r->out);
    solver += lsm_clock_seconds() - t1;
    if (reverse) {
      /* iterate n is output k - n: park it in slot k - n */
      st = lsm_park_put(park, (size_t)(k - n), r->out, err);
    } else {
      st = lsm_emit(r, za + s * (zb - za), -1, err);
      ps->slices++;
    }
  }
  for (int q = 0; st == LSM_OK && reverse && q < k; ++q) {
    /* slot q holds iterate k - q, at s = 1 - span (k - q) / (k + 1) */
    const double span = 0.5 * (double)(k + 1) / (double)k;
    const double s = 1.0 - span * (double)(k - q) / (double)(k + 1);
    st = lsm_park_get(park, (size_t)q, r->out, err);
    if (st != LSM_OK) break;
    st = lsm_emit(r, za + s * (zb - za), -1, err);
    ps->slices++;
  }
  lsm_park_close(&park);
  ps->seconds = solver;
  if (m) ps->cell_updates = lsm_morph_cell_updates(m); /* the emitting pass, as iterations */
  lsm_pair_stats_add_pls(ps, m);
  lsm_morph_destroy(&m);
  lsm_gap_free(&g);
  return st;
}
