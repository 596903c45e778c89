/* The narrow band (solver/pde/lsm_band.c, issue 56): what it holds and what the cells outside
 * it hold.
 *
 *   - the band covers every cell within travel + reach 4-neighbour steps of the kept levels,
 *     in whole aligned segments; the rim is every cell within reach of it, outside it;
 *   - a rebuild around a moved front covers the new front, and the cells that leave keep
 *     their value (phi outside = phi_target + a g is continuous in time);
 *   - a cell far from the front waits on the heap until its value comes near zero;
 *   - through lsm_morph: where the fronts are parallel (concentric discs) the band equals the
 *     full grid at the front and within 0.1 cell everywhere; on a general pair the volume is
 *     negative inside both slices and positive outside both far from the front, and
 *     continuous (no step much larger than a distance's across the band's edge); the band
 *     sweeps fewer cells than the grid. */
#include "tests/lsm_test.h"
#include "tests/lsm_test_pair.h"

#include "solver/pde/lsm_band.h"
#include "solver/pde/lsm_morph.h"

/* A disc's signed distance, centre (cx, cy) and radius r in cells, ghosts filled. */
static void fill_disc(lsm_grid *g, double cx, double cy, double r) {
  for (int j = 0; j < g->ny; ++j)
    for (int i = 0; i < g->nx; ++i) LSM_AT(g, i, j) = (float)(hypot(i - cx, j - cy) - r);
  lsm_grid_fill_ghosts(g);
}

/* The band's cells as a mask over the interior (nx ny bytes). */
static uint8_t *band_mask(const lsm_band *b, const lsm_grid *g) {
  uint8_t *m = calloc((size_t)g->nx * g->ny, 1);
  assert_non_null(m);
  const lsm_band_lists l = lsm_band_get(b);
  size_t cells = 0;
  for (size_t r = 0; r < l.runs; ++r) {
    const int j = (int)(l.run_start[r] / g->stride), i0 = (int)(l.run_start[r] % g->stride);
    assert_true(i0 % LSM_BAND_SEGMENT == 0); /* runs start on a segment */
    assert_true(i0 + l.run_length[r] <= g->nx);
    for (int i = i0; i < i0 + l.run_length[r]; ++i) m[(size_t)j * g->nx + i] = 1;
    cells += (size_t)l.run_length[r];
  }
  assert_int_equal(cells, l.cells);
  return m;
}

/* Every cell within `steps` 4-neighbour steps of a cell with |phi| <= level is in the mask. */
static void assert_covers(const uint8_t *m, const lsm_grid *phi, float level, int steps) {
  for (int j = 0; j < phi->ny; ++j)
    for (int i = 0; i < phi->nx; ++i) {
      if (fabsf(LSM_AT(phi, i, j)) > level) continue;
      for (int dj = -steps; dj <= steps; ++dj)
        for (int di = -steps + abs(dj); di <= steps - abs(dj); ++di) {
          const int x = i + di, y = j + dj;
          if (x < 0 || y < 0 || x >= phi->nx || y >= phi->ny) continue;
          if (!m[(size_t)y * phi->nx + x]) fail_msg("cell (%d, %d) near (%d, %d) is not in the band", x, y, i, j);
        }
    }
}

static void test_band_covers_the_levels(void **state) {
  (void)state;
  lsm_grid *src = new_grid(100, 90, 1.0f, 1.0f), *dst = new_grid(100, 90, 1.0f, 1.0f);
  fill_disc(src, 40.3, 44.8, 17.0);
  fill_disc(dst, 52.1, 47.2, 21.0);
  lsm_band_params p;
  lsm_band_params_of(LSM_SCHEME_ROEFIX, 1.0f, 1.0f, &p);
  assert_int_equal(p.reach, 4);
  lsm_band *b = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_band_create(src, dst, &p, &b, &err), LSM_OK);
  uint8_t *m = band_mask(b, src);
  assert_covers(m, src, p.level, p.travel + p.reach);
  /* the band is narrow: well under half the grid */
  const lsm_band_lists l = lsm_band_get(b);
  assert_true(l.cells < (size_t)src->nx * src->ny / 2);
  /* the rim: outside the band, each within reach of it, every such cell listed */
  size_t expect = 0;
  for (int j = 0; j < src->ny; ++j)
    for (int i = 0; i < src->nx; ++i) {
      if (m[(size_t)j * src->nx + i]) continue;
      int near = 0;
      for (int dj = -p.reach; dj <= p.reach && !near; ++dj)
        for (int di = -p.reach + abs(dj); di <= p.reach - abs(dj) && !near; ++di) {
          const int x = i + di, y = j + dj;
          near = x >= 0 && y >= 0 && x < src->nx && y < src->ny && m[(size_t)y * src->nx + x];
        }
      expect += (size_t)near;
    }
  assert_int_equal(l.rim_cells, expect);
  for (size_t q = 0; q < l.rim_cells; ++q) {
    const int j = (int)(l.rim[q] / src->stride), i = (int)(l.rim[q] % src->stride);
    assert_false(m[(size_t)j * src->nx + i]);
    /* amplitude: phi_source - phi_target */
    assert_close(l.rim_amplitude[q], LSM_AT(src, i, j) - LSM_AT(dst, i, j), 1e-5);
  }
  free(m);
  lsm_band_destroy(&b);
  lsm_grid_destroy(&src);
  lsm_grid_destroy(&dst);
}

/* A rebuild around a front that moved: the band covers it, cells entering take the relaxed
 * value, cells leaving keep theirs. */
static void test_band_rebuild_follows(void **state) {
  (void)state;
  lsm_grid *src = new_grid(96, 96, 1.0f, 1.0f), *dst = new_grid(96, 96, 1.0f, 1.0f);
  lsm_grid *now = new_grid(96, 96, 1.0f, 1.0f), *out = new_grid(96, 96, 1.0f, 1.0f);
  fill_disc(src, 48, 48, 30.0);
  fill_disc(dst, 48, 48, 12.0);
  fill_disc(now, 48, 48, 26.0); /* the morph moved the front in by 4 cells */
  lsm_band_params p;
  lsm_band_params_of(LSM_SCHEME_UPWIND, 1.0f, 1.0f, &p);
  lsm_band *b = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_band_create(src, dst, &p, &b, &err), LSM_OK);
  uint8_t *before = band_mask(b, src);
  const double g = 0.75;
  assert_int_equal(lsm_band_rebuild(b, now, g, &err), LSM_OK);
  uint8_t *after = band_mask(b, now);
  assert_covers(after, now, p.level, p.travel + p.reach);
  lsm_band_materialize(b, now, g, out, 1);
  const lsm_band_lists l = lsm_band_get(b);
  size_t entered = 0, left = 0;
  for (int j = 0; j < 96; ++j)
    for (int i = 0; i < 96; ++i) {
      const size_t c = (size_t)j * 96 + i;
      if (after[c] && !before[c]) entered++;
      if (before[c] && !after[c]) {
        /* it left: outside, its value is the one the band held */
        assert_close(LSM_AT(out, i, j), LSM_AT(now, i, j), 1e-4 * (1.0 + fabsf(LSM_AT(now, i, j))));
        left++;
      }
      if (!after[c] && !before[c]) /* never in the band: the relaxed blend */
        assert_close(LSM_AT(out, i, j), LSM_AT(dst, i, j) + (float)g * (LSM_AT(src, i, j) - LSM_AT(dst, i, j)), 1e-4);
    }
  assert_true(entered > 0 && left > 0);
  assert_int_equal(l.entered, entered);
  for (size_t q = 0; q < l.entered; ++q) {
    const int j = (int)(l.enter[q] / now->stride), i = (int)(l.enter[q] % now->stride);
    assert_close(l.enter_value[q], LSM_AT(dst, i, j) + (float)g * (LSM_AT(src, i, j) - LSM_AT(dst, i, j)), 1e-4);
  }
  free(before);
  free(after);
  lsm_band_destroy(&b);
  lsm_grid_destroy(&src);
  lsm_grid_destroy(&dst);
  lsm_grid_destroy(&now);
  lsm_grid_destroy(&out);
}

/* A cell away from the band waits on the heap until phi_target + a g comes within the kept
 * levels, at g = (level - t) / a: concentric discs r 10 -> 30 (the fronts parallel, so only
 * the heap brings the cell in when the band itself does not move). */
static void test_band_nucleation_g(void **state) {
  (void)state;
  const int n = 120;
  lsm_grid *src = new_grid(n, n, 1.0f, 1.0f), *dst = new_grid(n, n, 1.0f, 1.0f);
  fill_disc(src, 60, 60, 10.0);
  fill_disc(dst, 60, 60, 30.0);
  lsm_band_params p;
  lsm_band_params_of(LSM_SCHEME_UPWIND, 1.0f, 1.0f, &p);
  lsm_band *b = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_band_create(src, dst, &p, &b, &err), LSM_OK);
  uint8_t *m = band_mask(b, src);
  double want = 0.0;
  int wi = -1, wj = -1;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const float t = LSM_AT(dst, i, j), a = LSM_AT(src, i, j) - t;
      if (m[(size_t)j * n + i] || t > p.level) continue;
      if (((double)p.level - t) / a > want) {
        want = ((double)p.level - t) / a;
        wi = i;
        wj = j;
      }
    }
  free(m);
  const double next = lsm_band_next_g(b);
  print_message("band: next entry at g = %.6f: cell (%d, %d) at %.6f\n", next, wi, wj, want);
  assert_true(wi >= 0 && want < 1.0);
  assert_close(next, want, 1e-9);
  /* rebuilt just past that g (the band itself not moved), the cell is in the band */
  lsm_grid *phi = new_grid(n, n, 1.0f, 1.0f);
  const double g = want * 0.999;
  lsm_band_materialize(b, src, g, phi, 1);
  lsm_grid_fill_ghosts(phi);
  assert_int_equal(lsm_band_rebuild(b, phi, g, &err), LSM_OK);
  m = band_mask(b, phi);
  assert_true(m[(size_t)wj * n + wi]);
  assert_true(lsm_band_next_g(b) < g);
  free(m);
  lsm_grid_destroy(&phi);
  lsm_band_destroy(&b);
  lsm_grid_destroy(&src);
  lsm_grid_destroy(&dst);
}

/* lsm_morph with and without the band to t(s). */
static void morph_pair(const lsm_grid *src, const lsm_grid *dst, double s, lsm_grid *full,
                       lsm_grid *band, long long *updates) {
  for (int on = 0; on < 2; ++on) {
    lsm_morph_opts o;
    lsm_morph_opts_default(&o);
    o.band = on;
    o.track_cp = 0;
    lsm_morph *m = NULL;
    lsm_err err;
    lsm_err_clear(&err);
    assert_int_equal(lsm_morph_create(src, dst, &o, &m, &err), LSM_OK);
    assert_int_equal(lsm_morph_banded(m), on);
    assert_int_equal(lsm_morph_advance_to(m, lsm_morph_time_of_fraction(s), 100000, &err), LSM_OK);
    const lsm_grid *phi = lsm_morph_phi(m);
    assert_non_null(phi);
    lsm_grid_copy(on ? band : full, phi);
    updates[on] = lsm_morph_cell_updates(m);
    if (!on) assert_int_equal(updates[0], (long long)lsm_morph_iterations(m) * lsm_morph_grid_cells(m));
    lsm_morph_destroy(&m);
  }
}

/* Concentric discs: phi stays a distance, F is the same everywhere, so the band's step is the
 * full grid's and every cell outside the band holds what the full grid computes, up to
 * rounding. */
static void test_band_equals_full_where_parallel(void **state) {
  (void)state;
  lsm_grid *src = new_grid(96, 96, 1.0f, 1.0f), *dst = new_grid(96, 96, 1.0f, 1.0f);
  lsm_grid *full = new_grid(96, 96, 1.0f, 1.0f), *band = new_grid(96, 96, 1.0f, 1.0f);
  fill_disc(src, 47.5, 47.5, 10.0);
  fill_disc(dst, 47.5, 47.5, 20.0);
  long long updates[2];
  morph_pair(src, dst, 0.5, full, band, updates);
  double worst = 0.0, worst_front = 0.0;
  for (int j = 0; j < 96; ++j)
    for (int i = 0; i < 96; ++i) {
      const double d = fabs((double)LSM_AT(full, i, j) - LSM_AT(band, i, j));
      worst = fmax(worst, d);
      if (fabsf(LSM_AT(full, i, j)) < 2.0f) worst_front = fmax(worst_front, d);
    }
  print_message("band: concentric discs at s = 1/2: max |band - full| = %.3g (%.3g within 2 of "
                "the front); cell updates %lld against %lld\n",
                worst, worst_front, updates[1], updates[0]);
  /* near the front the same scheme; away from it the band's cells relax as a distance does,
   * (1 - dt)^n, where the full grid's discrete gradient of a disc's distance is not quite 1 */
  assert_true(worst_front <= 1e-4);
  assert_true(worst <= 0.1);
  assert_true(updates[1] < updates[0] / 2);
  lsm_grid_destroy(&src);
  lsm_grid_destroy(&dst);
  lsm_grid_destroy(&full);
  lsm_grid_destroy(&band);
}

/* A general pair: negative inside both slices, positive outside both, and continuous: no step
 * between 4-neighbours much larger than the full grid's largest, anywhere (the band's edge
 * included). */
static void test_band_outside_values(void **state) {
  (void)state;
  const int nx = 110, ny = 90;
  lsm_grid *src = new_grid(nx, ny, 1.0f, 1.0f), *dst = new_grid(nx, ny, 1.0f, 1.0f);
  lsm_grid *full = new_grid(nx, ny, 1.0f, 1.0f), *band = new_grid(nx, ny, 1.0f, 1.0f);
  fill_pair(src, dst);
  const double fractions[] = {0.2, 0.5, 0.8};
  for (size_t q = 0; q < sizeof fractions / sizeof fractions[0]; ++q) {
    long long updates[2];
    morph_pair(src, dst, fractions[q], full, band, updates);
    double step_full = 0.0, step_band = 0.0;
    long wrong_sign = 0, flips = 0;
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const float a = LSM_AT(src, i, j), t = LSM_AT(dst, i, j), v = LSM_AT(band, i, j);
        if ((a < -12.0f && t < -12.0f && v >= 0.0f) || (a > 12.0f && t > 12.0f && v <= 0.0f))
          wrong_sign++;
        flips += (v < 0.0f) != (LSM_AT(full, i, j) < 0.0f);
        if (i + 1 < nx) {
          step_full = fmax(step_full, fabs(LSM_AT(full, i + 1, j) - LSM_AT(full, i, j)));
          step_band = fmax(step_band, fabs(LSM_AT(band, i + 1, j) - v));
        }
        if (j + 1 < ny) {
          step_full = fmax(step_full, fabs(LSM_AT(full, i, j + 1) - LSM_AT(full, i, j)));
          step_band = fmax(step_band, fabs(LSM_AT(band, i, j + 1) - v));
        }
      }
    print_message("band: s = %.1f: largest step between neighbours %.3f (full grid %.3f), %ld "
                  "cells of the wrong sign, %ld cells change sides; updates %lld against %lld\n",
                  fractions[q], step_band, step_full, wrong_sign, flips, updates[1], updates[0]);
    assert_int_equal(wrong_sign, 0);
    assert_true(step_band <= fmax(step_full, 1.0) * 1.2);
    assert_true(flips <= 2);
    assert_true(updates[1] < updates[0]);
  }
  lsm_grid_destroy(&src);
  lsm_grid_destroy(&dst);
  lsm_grid_destroy(&full);
  lsm_grid_destroy(&band);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_band_covers_the_levels),
      cmocka_unit_test(test_band_rebuild_follows),
      cmocka_unit_test(test_band_nucleation_g),
      cmocka_unit_test(test_band_equals_full_where_parallel),
      cmocka_unit_test(test_band_outside_values),
  };
  return cmocka_run_group_tests_name("test_band", tests, NULL, NULL);
}
