/* lsm_two_sided: the two-sided morph of a gap (see the header). */
#include "solver/recon/lsm_two_sided.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "kernels/lsm_cell.h"
#include "solver/base/lsm_clock.h"
#include "solver/recon/lsm_frame.h"
#include "solver/recon/lsm_park.h"
#include "solver/recon/lsm_pinholes.h"
#include "solver/recon/lsm_zprofile.h"

/* Adds a morph's particle counters to the pair's. */
void lsm_pair_stats_add_pls(lsm_pair_stats *ps, const lsm_morph *m) {
  const lsm_pls_stats *q = m ? lsm_morph_pls_stats(m) : NULL;
  if (!q) return;
  ps->pls_seeded += q->seeded;
  ps->pls_discarded += q->discarded + q->left_domain; /* left_domain includes the strays */
  ps->pls_escaped += q->escaped_total;
  ps->pls_corrected += q->corrected_total;
  ps->pls_steps += q->steps;
}

/* The two morphs of a gap joined at one cell: fwd = phi_AB(s), rev =
 * phi_BA(1 - s), a = phi_A, b = phi_B.  Each is used where its front
 * retreats, min(max(fwd, a), max(rev, b)), a union of the two insides; where
 * the cell lies less than thin_outside outside one slice and deeper inside
 * the other, the outsides are joined instead, max(min(fwd, a), min(rev, b)),
 * since the morph opens a thin outside (a notch, a hole) of the target as
 * late as it reaches a thin inside. */
static inline float two_sided(float fwd, float rev, float a, float b, float thin_outside) {
  const float insides = lsm_minf(lsm_maxf(fwd, a), lsm_maxf(rev, b));
  const float outsides = lsm_maxf(lsm_minf(fwd, a), lsm_minf(rev, b));
  const float out = lsm_maxf(a, b), in = lsm_minf(a, b);
  return (in < 0.0f && out > 0.0f && out < thin_outside && out < -in) ? outsides : insides;
}

/* The morph moves a front point with normal speed -phi_B: parts of A outside
 * B retreat toward B at their distance from it (linear in s under
 * t(s) = -ln(1 - s)), but parts of B outside A are reached only as fast as
 * the depth inside B allows, so a thin protrusion of the target arrives late:
 * hence both morphs (rule two-sided).  A pinhole of either slice takes the
 * blend (rule pinhole-blend), so with the cubic profile the monotone spline:
 * a drifting hole moves and resizes continuously.  The reverse snapshots are
 * needed in the opposite order: they are held in memory (lsm_park). */
lsm_status lsm_two_sided_run(lsm_run *r, lsm_gap *g, const double *zs, const double *fs,
                             size_t n, lsm_pair_stats *ps, lsm_err *err) {
  const lsm_morph_opts *mo = &r->morph;
  const lsm_rules *rules = &r->opts->rules;
  const int max_iter = r->opts->max_iter;
  const int both = lsm_rule_on(rules, LSM_RULE_TWO_SIDED);
  const lsm_grid *pa = g->phi_a, *pb = g->phi_b;
  const size_t cells = (size_t)pa->nx * (size_t)pa->ny;
  lsm_morph *fwd = NULL, *rev = NULL;
  lsm_grid *mix = NULL;
  float *row = NULL;
  uint8_t *pinhole = NULL; /* NULL where neither slice has a pinhole */
  lsm_park *park = NULL;
  double t0 = lsm_clock_seconds(), solver = 0.0;
  lsm_status st = lsm_morph_create(pb, pa, mo, &rev, err);
  if (st == LSM_OK) st = lsm_grid_clone(pa, &mix, err);
  if (st == LSM_OK && !(row = lsm_alloc(cells, sizeof(float), err, "morph snapshot")))
    st = err ? err->status : LSM_ERR_NOMEM;
  if (st == LSM_OK && both && lsm_rule_on(rules, LSM_RULE_PINHOLE_BLEND))
    st = lsm_pinholes_find(pa, pb, (float)rules->join_thin_px, &pinhole, err);
  if (st == LSM_OK) st = lsm_park_open(cells, n, r->opts->held_max, &park, err);
  /* Reverse morph, latest output first; snapshot k goes to slot k.  Past
   * --max-iter no step polls the stop flag: each slot does. */
  for (size_t q = n; st == LSM_OK && q-- > 0;) {
    st = lsm_run_check_stop(r, err);
    if (st != LSM_OK) break;
    const double t = lsm_morph_time_of_fraction(1.0 - fs[q]);
    st = lsm_morph_advance_to(rev, t, max_iter, err);
    if (st != LSM_OK) break;
    if (lsm_morph_time(rev) < t * (1.0 - 1e-9)) ps->hit_max_iter = 1;
    const lsm_grid *p = lsm_morph_phi(rev);
    if (!p) {
      st = lsm_fail(err, lsm_morph_error(rev)->status, NULL, "%s", lsm_morph_error(rev)->msg);
      break;
    }
    for (int j = 0; j < p->ny; ++j) memcpy(row + (size_t)j * p->nx, &LSM_AT(p, 0, j), (size_t)p->nx * sizeof(float));
    st = lsm_park_put(park, q, row, err);
  }
  if (st == LSM_OK) st = lsm_morph_create(pa, pb, mo, &fwd, err);
  for (size_t k = 0; st == LSM_OK && k < n; ++k) {
    const double t = lsm_morph_time_of_fraction(fs[k]);
    st = lsm_morph_advance_to(fwd, t, max_iter, err);
    if (st != LSM_OK) break;
    if (lsm_morph_time(fwd) < t * (1.0 - 1e-9)) ps->hit_max_iter = 1;
    st = lsm_park_get(park, k, row, err);
    if (st != LSM_OK) break;
    const lsm_grid *pf = lsm_morph_phi(fwd);
    if (!pf) {
      st = lsm_fail(err, lsm_morph_error(fwd)->status, NULL, "%s", lsm_morph_error(fwd)->msg);
      break;
    }
    const float thin_outside = lsm_rule_on(rules, LSM_RULE_THIN_JOIN)
                                   ? (float)rules->join_thin_px * fmaxf(mix->dx, mix->dy)
                                   : 0.0f;
    for (int j = 0; j < mix->ny; ++j) {
      const float *f = &LSM_AT(pf, 0, j), *a = &LSM_AT(pa, 0, j), *b = &LSM_AT(pb, 0, j);
      const float *rv = row + (size_t)j * mix->nx;
      float *o = &LSM_AT(mix, 0, j);
      /* lsm_minf / lsm_maxf vectorise (fminf / fmaxf are library calls) and
       * differ only for NaN, which the morph never holds */
      if (both)
        for (int i = 0; i < mix->nx; ++i) o[i] = two_sided(f[i], rv[i], a[i], b[i], thin_outside);
      else
        memcpy(o, f, (size_t)mix->nx * sizeof *o);
      if (pinhole) {
        const uint8_t *pin = pinhole + (size_t)j * mix->nx;
        const float s = (float)fs[k];
        for (int i = 0; i < mix->nx; ++i)
          if (pin[i]) o[i] = (1.0f - s) * a[i] + s * b[i];
      }
    }
    /* cubic profile: the morph's departure from the straight line weighted
     * by omega(s) (rule omega), plus the spline's */
    if (g->slope_a && lsm_rule_on(rules, LSM_RULE_OMEGA)) lsm_zprofile_weight(pa, pb, fs[k], mix);
    lsm_zprofile_add_cubic(pa, pb, g->slope_a, g->slope_b, fs[k], rules, mix);
    lsm_frame_extract(&g->f, lsm_gap_carry(g, fs[k], mix), fs[k], r->out);
    lsm_gap_paste_parts(g, fs[k], r->out);
    solver += lsm_clock_seconds() - t0;
    st = lsm_emit(r, zs[k], -1, err);
    t0 = lsm_clock_seconds();
    ps->slices++;
  }
  lsm_pair_stats_add_pls(ps, fwd);
  lsm_pair_stats_add_pls(ps, rev);
  if (fwd && rev) {
    ps->iterations = lsm_morph_iterations(fwd) + lsm_morph_iterations(rev);
    ps->cell_updates = lsm_morph_cell_updates(fwd) + lsm_morph_cell_updates(rev);
    ps->dt = lsm_morph_dt(fwd);
    ps->cp = lsm_morph_iterations(fwd) ? lsm_morph_cp(fwd) : 0.0;
    ps->t_final = lsm_morph_time(fwd);
  }
  ps->seconds = solver;
  lsm_park_close(&park);
  free(row);
  free(pinhole);
  lsm_grid_destroy(&mix);
  lsm_morph_destroy(&fwd);
  lsm_morph_destroy(&rev);
  return st;
}
