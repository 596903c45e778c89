/* End-to-end tests of the stack driver (solver/recon/lsm_stack.c) through an
 * in-memory slice source (synthetic shapes) and a sink that records every
 * output slice (tests/lsm_test_stack.h): the output heights and slice counts,
 * exact input slices, the cone of concentric discs, units and pixels that are
 * not square, nested outline contours, the per-iteration mode, a stop signal
 * past --max-iter and the driver's errors. */
#include "tests/lsm_test_stack.h"

#include <signal.h>

/* ------------------------------------------------------------------------ */
/* concentric discs: a cone                                                   */

static void check_cone(const run *r, const double *z_in, size_t n_in, double tol) {
  assert_int_equal(r->sink.n, 21);
  size_t next_input = 0;
  for (size_t k = 0; k < r->sink.n; ++k) {
    const out_slice *o = &r->sink.s[k];
    assert_close(o->z, (double)k, 1e-9);
    if (next_input < n_in && fabs(z_in[next_input] - o->z) < 1e-9) {
      check_exact_input(r, k, next_input++);
    } else {
      assert_int_equal(o->input_index, -1);
    }
    /* Radius from the area; the cone is r = 30 - z. */
    const double rad = sqrt((double)area(o->phi, W, H) / PI);
    if (fabs(rad - (30.0 - o->z)) > tol)
      fail_msg("slice z = %g: radius %.3f, expected %.3f +- %g", o->z, rad, 30.0 - o->z, tol);
    assert_int_equal(fg_components(o->phi, W, H), 1);
    assert_int_equal(holes(o->phi, W, H), 0);
  }
  assert_int_equal(next_input, n_in);
}

static void test_cone_default(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {disc(C, C, 30)}}, {1, {disc(C, C, 10)}}};
  const double z[2] = {0, 20};
  lsm_stack_opts o;
  default_opts(&o);
  run r;
  assert_int_equal(run_stack(&r, W, H, 0, defs, z, 2, &o), LSM_OK);
  check_cone(&r, z, 2, 0.5);
  /* One gap, 19 intermediate slices. */
  assert_int_equal(r.stats[0].source, 0);
  assert_int_equal(r.stats[0].target, 1);
  assert_int_equal(r.stats[0].slices, 19);
  assert_true(r.stats[0].iterations > 0);
  assert_true(r.stats[0].dt > 0);
  assert_int_equal(r.stats[0].hit_max_iter, 0);
  /* Printed for the report: the largest radius error. */
  double worst = 0;
  for (size_t k = 0; k < r.sink.n; ++k)
    worst = fmax(worst, fabs(sqrt(area(r.sink.s[k].phi, W, H) / PI) - (30.0 - r.sink.s[k].z)));
  print_message("cone ls: worst radius error %.3f px\n", worst);
  sink_free(&r.sink);
}

/* Heights 0, 5, 20 with discs of radius 30, 25, 10: still r = 30 - z. */
static void test_cone_nonuniform(void **state) {
  (void)state;
  const slice_def defs[3] = {{1, {disc(C, C, 30)}}, {1, {disc(C, C, 25)}}, {1, {disc(C, C, 10)}}};
  const double z[3] = {0, 5, 20};
  lsm_stack_opts o;
  default_opts(&o);
  run r;
  assert_int_equal(run_stack(&r, W, H, 0, defs, z, 3, &o), LSM_OK);
  check_cone(&r, z, 3, 0.5);
  assert_int_equal(r.sink.s[5].input_index, 1);
  assert_int_equal(r.stats[0].slices, 4);
  assert_int_equal(r.stats[1].slices, 14);
  sink_free(&r.sink);
}

/* Blend: (1 - s)(d - 30) + s (d - 10) = d - (30 - 20 s) exactly for circle
 * distances, so the cone is reproduced too, and the endpoints exactly. */
static void test_cone_blend(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {disc(C, C, 30)}}, {1, {disc(C, C, 10)}}};
  const double z[2] = {0, 20};
  lsm_stack_opts o;
  default_opts(&o);
  o.method = LSM_METHOD_BLEND;
  run r;
  assert_int_equal(run_stack(&r, W, H, 0, defs, z, 2, &o), LSM_OK);
  check_cone(&r, z, 2, 0.5);
  assert_int_equal(r.stats[0].iterations, 0);
  sink_free(&r.sink);
}

/* dz = 4 on heights 0..20: z = 0, 4, ..., 20; dz = 3: 0, 3, ..., 18 (the last
 * input, 20, is off the grid and not emitted). */
static void test_output_heights(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {disc(C, C, 30)}}, {1, {disc(C, C, 10)}}};
  const double z[2] = {0, 20};
  lsm_stack_opts o;
  default_opts(&o);
  o.method = LSM_METHOD_BLEND;
  o.dz = 4;
  run r;
  assert_int_equal(lsm_stack_output_count(z, 2, 4.0), 6);
  assert_int_equal(run_stack(&r, W, H, 0, defs, z, 2, &o), LSM_OK);
  assert_int_equal(r.sink.n, 6);
  for (size_t k = 0; k < 6; ++k) assert_close(r.sink.s[k].z, 4.0 * k, 1e-9);
  check_exact_input(&r, 0, 0);
  check_exact_input(&r, 5, 1);
  sink_free(&r.sink);
  o.dz = 3;
  assert_int_equal(lsm_stack_output_count(z, 2, 3.0), 7);
  assert_int_equal(run_stack(&r, W, H, 0, defs, z, 2, &o), LSM_OK);
  assert_int_equal(r.sink.n, 7);
  for (size_t k = 0; k < 7; ++k) {
    assert_close(r.sink.s[k].z, 3.0 * k, 1e-9);
    if (k) assert_int_equal(r.sink.s[k].input_index, -1);
  }
  check_exact_input(&r, 0, 0);
  sink_free(&r.sink);
}

/* The slice count, each gap's share of the grid and the input heights on it
 * are decided by the same two tests: a last height off the grid by more than
 * the tolerance (a millionth of the closest pair of heights, 0.25 here) is
 * not counted, and one within it is counted and is that input slice.  (The
 * count used a millionth of dz and the gaps the smaller tolerance: 11 slices
 * counted, 10 written, the last input slice lost.) */
static void test_output_count_matches_gaps(void **state) {
  (void)state;
  const slice_def defs[3] = {{1, {disc(C, C, 30)}}, {1, {disc(C, C, 28)}}, {1, {disc(C, C, 10)}}};
  lsm_stack_opts o;
  default_opts(&o);
  o.method = LSM_METHOD_BLEND;
  o.dz = 1;
  run r;
  const double off[3] = {0, 0.25, 9.9999995};
  assert_int_equal(lsm_stack_output_count(off, 3, 1.0), 10);
  assert_int_equal(run_stack(&r, W, H, 0, defs, off, 3, &o), LSM_OK);
  assert_int_equal(r.sink.n, 10);
  assert_close(r.sink.s[9].z, 9.0, 1e-12);
  sink_free(&r.sink);
  const double on[3] = {0, 0.25, 9.99999999};
  assert_int_equal(lsm_stack_output_count(on, 3, 1.0), 11);
  assert_int_equal(run_stack(&r, W, H, 0, defs, on, 3, &o), LSM_OK);
  assert_int_equal(r.sink.n, 11);
  check_exact_input(&r, 10, 2);
  sink_free(&r.sink);
}

/* ------------------------------------------------------------------------ */
/* units: the same stack in pixel sizes and spacings far apart in scale      */

/* The shape at a fraction of a gap does not depend on the units: with pixel
 * size p and heights scaled by q every output mask is that of p = q = 1, also
 * where p / q is far outside a float's range (the PCHIP slopes, held per unit
 * z, overflowed there: 1e19 / 1e-19 filled the cubic's slices). */
static void test_scale_invariance(void **state) {
  (void)state;
  const slice_def defs[6] = {{0, {{0}}},
                             {1, {disc(C - 6, C, 8)}},
                             {1, {disc(C, C, 20)}},
                             {1, {disc(C + 4, C, 12)}},
                             {1, {disc(C + 6, C - 3, 6)}},
                             {0, {{0}}}};
  const double z1[6] = {0, 4, 9, 12, 18, 20};
  const double scales[3][2] = {{1.0, 1.0}, {1e19, 1e-19}, {1e-20, 1e20}}; /* pixel, height */
  const lsm_method methods[2] = {LSM_METHOD_LS, LSM_METHOD_BLEND};
  for (int m = 0; m < 2; ++m) {
    run ref;
    memset(&ref, 0, sizeof ref);
    for (int k = 0; k < 3; ++k) {
      double z[6];
      for (int i = 0; i < 6; ++i) z[i] = z1[i] * scales[k][1];
      lsm_stack_opts o;
      default_opts(&o);
      o.method = methods[m];
      o.pixel_dx = o.pixel_dy = scales[k][0];
      o.dz = scales[k][1];
      run r;
      assert_int_equal(run_stack(&r, W, H, 0, defs, z, 6, &o), LSM_OK);
      if (k == 0) {
        ref = r;
        assert_int_equal(ref.sink.n, 21);
        continue;
      }
      assert_int_equal(r.sink.n, ref.sink.n);
      size_t differ = 0;
      for (size_t i = 0; i < r.sink.n; ++i)
        for (int c = 0; c < W * H; ++c)
          differ += (r.sink.s[i].phi[c] <= 0.0f) != (ref.sink.s[i].phi[c] <= 0.0f);
      if (differ)
        fail_msg("%s, pixel %g, heights x %g: %zu cells differ from pixel 1, heights x 1",
                 m ? "blend" : "ls", scales[k][0], scales[k][1], differ);
      sink_free(&r.sink);
    }
    sink_free(&ref.sink);
  }
}

/* ------------------------------------------------------------------------ */
/* pixels that are not square                                                */

/* Cells where the stack sampled with rows y_step apart (pixel_dy = y_step)
 * and the same stack on square pixels disagree: row j of the first against
 * row y_step j of the second, over every output slice (both runs have the
 * same heights).  *phi_err: the largest |phi| difference at cells within
 * `band` of the surface. */
static size_t rows_disagree(const run *coarse, const run *fine, int y_step, float band,
                            float *phi_err) {
  assert_int_equal(coarse->sink.n, fine->sink.n);
  size_t differ = 0;
  *phi_err = 0.0f;
  for (size_t k = 0; k < coarse->sink.n; ++k) {
    const float *pc = coarse->sink.s[k].phi, *pf = fine->sink.s[k].phi;
    for (int j = 0; j < coarse->sink.height; ++j)
      for (int i = 0; i < W; ++i) {
        const float a = pc[(size_t)j * W + i], b = pf[(size_t)(y_step * j) * W + i];
        differ += (a <= 0.0f) != (b <= 0.0f);
        if (fabsf(b) < band && fabsf(a - b) > *phi_err) *phi_err = fabsf(a - b);
      }
  }
  return differ;
}

/* A pixel twice as tall as it is wide: discs (in physical units) sampled
 * every other row, with pixel_dy = 2, give the shapes and signed distances of
 * the same discs sampled on square pixels, read at every other row.  The
 * distances, the morph's speed and the ends' erosion are physical; taking the
 * pixel as square (pixel_dy = 1) draws ellipses that erode twice as fast
 * across the rows. */
static void test_pixel_not_square(void **state) {
  (void)state;
  const slice_def defs[5] = {{0, {{0}}},
                             {1, {disc(50, 50, 14)}},
                             {1, {disc(46, 52, 26)}},
                             {1, {disc(54, 46, 10)}},
                             {0, {{0}}}};
  const double z[5] = {0, 8, 16, 24, 32};
  const int hf = 101, hc = 51; /* rows: y = 0 .. 100, one in every two */
  for (int m = 0; m < 2; ++m) {
    lsm_stack_opts o;
    default_opts(&o);
    o.method = m ? LSM_METHOD_BLEND : LSM_METHOD_LS;
    o.dz = 1.0;
    run fine, coarse, square;
    assert_int_equal(run_stack(&fine, W, hf, 0, defs, z, 5, &o), LSM_OK);
    o.pixel_dy = 2.0;
    assert_int_equal(run_stack_rows(&coarse, W, hc, 0, 2, defs, z, 5, &o), LSM_OK);
    o.pixel_dy = 1.0;
    assert_int_equal(run_stack_rows(&square, W, hc, 0, 2, defs, z, 5, &o), LSM_OK);
    float err_right = 0.0f, err_square = 0.0f;
    const size_t right = rows_disagree(&coarse, &fine, 2, 6.0f, &err_right);
    const size_t wrong = rows_disagree(&square, &fine, 2, 6.0f, &err_square);
    print_message("%s: %zu cells disagree (pixel 1 x 2), %zu taken as square; |phi| error "
                  "near the surface %.3f, %.3f\n",
                  m ? "blend" : "ls", right, wrong, (double)err_right, (double)err_square);
    /* a coarse row's signed distance is off by up to half its height (1)
     * where the circle's edge falls between rows; taken as square, the
     * distances across the rows are half what they are */
    if (err_right > 1.5f) fail_msg("|phi| differs by %.3f near the surface", (double)err_right);
    /* the masks differ at a few cells of each slice's outline (33 slices) */
    if (right > 8 * coarse.sink.n)
      fail_msg("%zu cells disagree over %zu slices", right, coarse.sink.n);
    sink_free(&fine.sink);
    sink_free(&coarse.sink);
    sink_free(&square.sink);
  }
}

/* ------------------------------------------------------------------------ */
/* outline input, nested contours                                            */

static void check_one_hole(const run *r, const char *what) {
  char text[512] = ""; /* " c/h" per slice; bounded (it overflowed 64 bytes: ASan) */
  for (size_t k = 0; k < r->sink.n; ++k) {
    const float *phi = r->sink.s[k].phi;
    const int nh = holes(phi, W, H), nc = fg_components(phi, W, H);
    const size_t used = strlen(text);
    snprintf(text + used, sizeof text - used, " %d/%d", nc, nh);
    if (nh != 1 || nc != 1)
      fail_msg("%s: slice z = %g has %d components and %d holes (want 1 and 1)", what,
               r->sink.s[k].z, nc, nh);
  }
  print_message("%s: components/holes%s\n", what, text);
}

static void test_outline_ring(void **state) {
  (void)state;
  /* Ring: outer r = 35.25, hole r = 15.5  ->  outer r = 30.25, hole r = 20.5. */
  const slice_def defs[2] = {{2, {disc(C, C, 35.25), disc_hole(C, C, 15.5)}},
                             {2, {disc(C, C, 30.25), disc_hole(C, C, 20.5)}}};
  const double z[2] = {0, 10};
  lsm_stack_opts o;
  default_opts(&o);
  o.input = LSM_INPUT_OUTLINE;
  run r;
  assert_int_equal(run_stack(&r, W, H, 1, defs, z, 2, &o), LSM_OK);
  assert_int_equal(r.sink.n, 11);
  check_exact_input(&r, 0, 0);
  check_exact_input(&r, 10, 1);
  check_one_hole(&r, "ring");
  /* The hole radius grows from ~15.5 to ~20.5 monotonically (hole area). */
  size_t prev = 0;
  for (size_t k = 0; k < r.sink.n; ++k) {
    const float *phi = r.sink.s[k].phi;
    size_t hole_px = 0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x)
        if (hypot(x - C, y - C) < 25.0 && phi[y * W + x] > 0.0f) hole_px++;
    assert_true(hole_px >= prev);
    prev = hole_px;
  }
  sink_free(&r.sink);
}

/* The vase: circle (r = 40.25) with a 21 x 21 square hole -> 81 x 81 square
 * with a circular hole (r = 11.5) -> back. */
static void test_outline_vase(void **state) {
  (void)state;
  const slice_def a = {2, {disc(C, C, 40.25), rect(40, 40, 60, 60, 1)}};
  const slice_def b = {2, {rect(10, 10, 90, 90, 0), disc_hole(C, C, 11.5)}};
  const slice_def defs[3] = {a, b, a};
  const double z[3] = {0, 8, 16};
  lsm_stack_opts o;
  default_opts(&o);
  o.input = LSM_INPUT_OUTLINE;
  run r;
  assert_int_equal(run_stack(&r, W, H, 1, defs, z, 3, &o), LSM_OK);
  assert_int_equal(r.sink.n, 17);
  check_exact_input(&r, 0, 0);
  check_exact_input(&r, 8, 1);
  check_exact_input(&r, 16, 2);
  check_one_hole(&r, "vase");
  /* Symmetric stack: slice z and 16 - z are the same shape (the two gaps are
   * mirror images), up to the solver being deterministic. */
  for (size_t k = 1; k < 8; ++k)
    assert_memory_equal(r.sink.s[k].phi, r.sink.s[16 - k].phi, sizeof(float) * W * H);
  sink_free(&r.sink);
}

/* ------------------------------------------------------------------------ */
/* per-iteration mode                                                        */

/* CP of pair p of a per-iteration run, by its definition (solver/README.md,
 * section 12): | ||phi^n - phi_B|| - ||phi^(n-1) - phi_B|| | over all cells of the
 * working grid, the pair stopping at the first n with CP <= tol.  The working
 * grid is rebuilt here: the slices on a canvas with a 2-cell margin (the
 * frame's margin, the largest whole-pixel alignment shift + 2, with no shift
 * for these concentric discs), their signed distances, the morph stepped as
 * the stack steps it; every iterate's image window must be the slice the run
 * emitted, bit for bit, so the rebuilt grid is the run's own.  The norms are
 * summed here in double, from the iterates, not taken from lsm_morph_cp. */
static void check_cp_by_definition(const run *r, const lsm_stack_opts *o, int p,
                                  size_t first_out) {
  enum { PAD = 2 };
  const int nx = W + 2 * PAD, ny = H + 2 * PAD;
  lsm_err err;
  lsm_err_clear(&err);
  lsm_grid *phi[2] = {NULL, NULL};
  for (int side = 0; side < 2; ++side) {
    lsm_mask img, canvas;
    assert_int_equal(lsm_mask_create(W, H, &img, &err), LSM_OK);
    assert_int_equal(lsm_mask_create(nx, ny, &canvas, &err), LSM_OK);
    paint(&r->src, &r->src.defs[p + side], &img);
    for (int y = 0; y < H; ++y)
      memcpy(&canvas.pixels[(size_t)(y + PAD) * nx + PAD], &img.pixels[(size_t)y * W], W);
    assert_int_equal(lsm_grid_create(nx, ny, 1.0f, 1.0f, &phi[side], &err), LSM_OK);
    assert_int_equal(lsm_sdf_from_mask(&canvas, phi[side], &err), LSM_OK);
    lsm_mask_free(&img);
    lsm_mask_free(&canvas);
  }
  lsm_morph_opts mo = o->morph;
  mo.track_cp = 1;
  mo.band = 0; /* per-iteration mode runs the full grid */
  lsm_morph *m = NULL;
  assert_int_equal(lsm_morph_create(phi[0], phi[1], &mo, &m, &err), LSM_OK);
  double prev = 0.0, cp = INFINITY;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double d = (double)LSM_AT(phi[0], i, j) - LSM_AT(phi[1], i, j);
      prev += d * d;
    }
  prev = sqrt(prev);
  int n = 0;
  while (cp > o->tol) {
    assert_true(n < 1000); /* CP falls by about 7 % a step: 90 or so */
    assert_int_equal(lsm_morph_step(m, INFINITY, &err), LSM_OK);
    ++n;
    const lsm_grid *g = lsm_morph_phi(m);
    double sum = 0.0;
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const double d = (double)LSM_AT(g, i, j) - LSM_AT(phi[1], i, j);
        sum += d * d;
      }
    cp = fabs(sqrt(sum) - prev);
    prev = sqrt(sum);
    if (n <= r->stats[p].iterations) {
      const float *out = r->sink.s[first_out + (size_t)n - 1].phi;
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
          if (out[(size_t)y * W + x] != LSM_AT(g, x + PAD, y + PAD))
            fail_msg("pair %d iterate %d at (%d, %d): emitted %.9g, rebuilt %.9g", p, n, x, y,
                     out[(size_t)y * W + x], LSM_AT(g, x + PAD, y + PAD));
    }
  }
  print_message("per-iteration pair %d: CP by definition <= %g after %d steps (CP %.6f), the "
                "run %d (CP %.6f)\n",
                p, o->tol, n, cp, r->stats[p].iterations, r->stats[p].cp);
  assert_int_equal(r->stats[p].iterations, n);
  /* both sums in double over 11025 cells: equal to about 1e-12 of the norm */
  assert_close(r->stats[p].cp, cp, 1e-9);
  lsm_morph_destroy(&m);
  lsm_grid_destroy(&phi[0]);
  lsm_grid_destroy(&phi[1]);
}

static void test_per_iteration(void **state) {
  (void)state;
  const slice_def defs[3] = {{1, {disc(C, C, 30)}}, {1, {disc(C, C, 22)}}, {1, {disc(C, C, 14)}}};
  const double z[3] = {0, 10, 30};
  lsm_stack_opts o;
  default_opts(&o);
  o.per_iteration = 1;
  run r;
  assert_int_equal(run_stack(&r, W, H, 0, defs, z, 3, &o), LSM_OK);
  const size_t iters = (size_t)r.stats[0].iterations + (size_t)r.stats[1].iterations;
  print_message("per-iteration: %d + %d iterations, %zu slices\n", r.stats[0].iterations,
                r.stats[1].iterations, r.sink.n);
  assert_true(r.stats[0].iterations > 0 && r.stats[1].iterations > 0);
  assert_int_equal(r.sink.n, iters + 3);
  assert_int_equal(r.stats[0].slices, (size_t)r.stats[0].iterations);
  /* The stop: CP <= tol at the last step alone would hold for any CP (it is
   * the loop's own exit condition); the count and the CP are checked against
   * CP computed from the iterates.  (CP falls by about 7 % a step here: a CP
   * reported at half its value stopped these pairs at 76 and 74 steps, not 90
   * and 87.) */
  for (int p = 0; p < 2; ++p) {
    check_cp_by_definition(&r, &o, p, p == 0 ? 1 : (size_t)r.stats[0].iterations + 2);
    assert_int_equal(r.stats[p].hit_max_iter, 0);
  }
  for (size_t k = 1; k < r.sink.n; ++k) assert_true(r.sink.s[k].z > r.sink.s[k - 1].z);
  assert_close(r.sink.s[0].z, 0.0, 0.0);
  assert_close(r.sink.s[r.sink.n - 1].z, 30.0, 1e-9);
  /* Inputs: first, after pair 0's iterations, last; all exact. */
  check_exact_input(&r, 0, 0);
  const size_t i1 = (size_t)r.stats[0].iterations + 1;
  assert_close(r.sink.s[i1].z, 10.0, 1e-9);
  check_exact_input(&r, i1, 1);
  check_exact_input(&r, r.sink.n - 1, 2);
  size_t inputs = 0;
  for (size_t k = 0; k < r.sink.n; ++k) inputs += r.sink.s[k].input_index >= 0;
  assert_int_equal(inputs, 3);
  /* Heights within a pair: linspace(z_A, z_B, k + 2). */
  const int k0 = r.stats[0].iterations;
  for (int n = 1; n <= k0; ++n) assert_close(r.sink.s[n].z, 10.0 * n / (k0 + 1), 1e-9);
  /* The area decreases monotonically (each iterate shrinks the disc). */
  for (size_t k = 1; k < r.sink.n; ++k)
    assert_true(area(r.sink.s[k].phi, W, H) <= area(r.sink.s[k - 1].phi, W, H));
  sink_free(&r.sink);
}

/* ------------------------------------------------------------------------ */
/* a stop signal where no solver step polls                                   */

/* A sink that raises the stop flag at its second slice, as a signal would. */
typedef struct stopping_sink {
  sink_ctx inner;
  volatile sig_atomic_t *stop;
} stopping_sink;

static lsm_status stopping_emit(void *ctx, const float *phi, int width, int height, double z,
                                long input_index, lsm_err *err) {
  stopping_sink *c = ctx;
  if (c->inner.n == 1) *c->stop = SIGINT;
  return sink_emit(&c->inner, phi, width, height, z, input_index, err);
}

/* Past --max-iter no solver step polls the stop flag: one long gap (199
 * slices) at --max-iter 1 ran to its end after the signal (in issue 54, with
 * four million slices, for minutes).  Every slice polls it now: the run stops
 * after the slice during which it came, in either mode. */
static void test_stop_past_max_iter(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {disc(C, C, 10)}}, {1, {disc(C, C, 20)}}};
  const double z[2] = {0, 200};
  for (int per_iteration = 0; per_iteration < 2; ++per_iteration) {
    volatile sig_atomic_t stop = 0;
    lsm_stack_opts o;
    default_opts(&o);
    o.max_iter = per_iteration ? 100 : 1;
    o.per_iteration = per_iteration;
    o.morph.stop = &stop;
    stopping_sink sink_ctx_ = {{W, H, NULL, 0, 0}, &stop};
    lsm_err err;
    lsm_err_clear(&err);
    lsm_pair_stats stats[1];
    source_ctx src = {W, H, 0, 1, defs, 2, 0};
    lsm_slice_source source = {&src, 2, z, src_load, src_name};
    lsm_slice_sink sink = {&sink_ctx_, stopping_emit};
    assert_int_equal(lsm_stack_run(&source, W, H, &o, &sink, stats, NULL, &err),
                     LSM_ERR_INTERRUPTED);
    assert_int_equal(sink_ctx_.inner.n, 2);
    sink_free(&sink_ctx_.inner);
  }
}

/* ------------------------------------------------------------------------ */
/* errors                                                                    */

static void test_errors(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {disc(C, C, 10)}}, {1, {disc(C, C, 12)}}};
  lsm_stack_opts o;
  default_opts(&o);
  run r;
  const double z1[1] = {0};
  assert_int_equal(run_stack(&r, W, H, 0, defs, z1, 1, &o), LSM_ERR_INPUT);
  assert_true(strlen(r.err.msg) > 0);
  assert_int_equal(r.sink.n, 0);
  const double zbad[2] = {5, 5};
  assert_int_equal(run_stack(&r, W, H, 0, defs, zbad, 2, &o), LSM_ERR_INPUT);
  assert_int_equal(r.sink.n, 0);
  const double zdown[2] = {5, 1};
  assert_int_equal(run_stack(&r, W, H, 0, defs, zdown, 2, &o), LSM_ERR_INPUT);
  /* output heights double precision cannot tell apart: near 2^33 a unit in
   * the last place is 2^-19, and a step must be at least 8 of them */
  const double zfar[2] = {8589934592.0, 8589934592.0 + 0.0009765625};
  o.dz = 0x1p-18;
  assert_int_equal(run_stack(&r, W, H, 0, defs, zfar, 2, &o), LSM_ERR_INPUT);
  assert_int_equal(r.sink.n, 0);
  o.dz = 0x1p-14;
  o.method = LSM_METHOD_BLEND;
  assert_int_equal(run_stack(&r, W, H, 0, defs, zfar, 2, &o), LSM_OK);
  assert_int_equal(r.sink.n, 17);
  for (size_t k = 1; k < r.sink.n; ++k) assert_true(r.sink.s[k].z > r.sink.s[k - 1].z);
  sink_free(&r.sink);
  default_opts(&o);
  /* A slice of another size. */
  const double z[2] = {0, 4};
  lsm_slice_source source;
  memset(&r, 0, sizeof r);
  r.src.width = W;
  r.src.height = H;
  r.src.defs = defs;
  r.sink.width = W;
  r.sink.height = H;
  source.ctx = &r.src;
  source.count = 2;
  source.z = z;
  source.load = src_load;
  source.name = src_name;
  lsm_slice_sink sink = {&r.sink, sink_emit};
  lsm_err_clear(&r.err);
  assert_int_equal(lsm_stack_run(&source, W + 1, H, &o, &sink, r.stats, NULL, &r.err),
                   LSM_ERR_INPUT);
  sink_free(&r.sink);
  /* Blend in per-iteration mode is a usage error. */
  o.per_iteration = 1;
  o.method = LSM_METHOD_BLEND;
  assert_int_equal(run_stack(&r, W, H, 0, defs, z, 2, &o), LSM_ERR_USAGE);
  sink_free(&r.sink);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_cone_default),
      cmocka_unit_test(test_cone_nonuniform),
      cmocka_unit_test(test_cone_blend),
      cmocka_unit_test(test_output_heights),
      cmocka_unit_test(test_output_count_matches_gaps),
      cmocka_unit_test(test_scale_invariance),
      cmocka_unit_test(test_pixel_not_square),
      cmocka_unit_test(test_outline_ring),
      cmocka_unit_test(test_outline_vase),
      cmocka_unit_test(test_per_iteration),
      cmocka_unit_test(test_stop_past_max_iter),
      cmocka_unit_test(test_errors),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
