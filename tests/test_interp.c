/* Tests of the z-profile through the slices (--interp linear|cubic):
 * monotonicity (blend, ls, pls), exact input slices, C1 continuity across input slices on a
 * ball, stride-1 identity, per-iteration mode on empty and identical slices, a component
 * halfway, the slope at the first input slice, the cubic's morph weight and the path of
 * aligned pairs.  Slices come from an in-memory source; output slices are recorded by an
 * in-memory sink (tests/lsm_test_interp.h). */
#include "tests/lsm_test_interp.h"

/* A ball of radius 30 centred at z = 36, cut every 6 units: radii of the cross-sections. */
#define BALL_SLICES 11
static void ball(double *radius, double *z) {
  for (int k = 0; k < BALL_SLICES; ++k) {
    z[k] = 6.0 * k + 3.0;
    double h = z[k] - 33.0;
    radius[k] = 30.0 * 30.0 - h * h > 0 ? sqrt(30.0 * 30.0 - h * h) : 0.0;
  }
}

/* Every output cell of a gap between two non-empty slices lies within the
 * range of its two slices' values (no overshoot); returns the cells checked.
 * load reads slice k (phi_of); radius[k] <= 0 marks an empty slice (NULL:
 * none is empty). */
static size_t check_within_neighbours(const record *rec, const double *z, size_t n, load_fn load,
                                      void *src, const double *radius) {
  const size_t cells = (size_t)rec->w * rec->h;
  float *pa = malloc(cells * sizeof(float)), *pb = malloc(cells * sizeof(float));
  assert_non_null(pa);
  assert_non_null(pb);
  size_t checked = 0;
  for (size_t q = 0; q < rec->count; ++q) {
    if (rec->input[q] >= 0) continue;
    size_t k = 0;
    while (k + 1 < n && z[k + 1] < rec->z[q]) ++k;
    if (radius && (radius[k] <= 0 || radius[k + 1] <= 0)) continue; /* caps are not splines */
    phi_of(load, src, rec->w, k, pa);
    phi_of(load, src, rec->w, k + 1, pb);
    const float *p = rec->phi + q * cells;
    for (size_t c = 0; c < cells; ++c) {
      float lo = fminf(pa[c], pb[c]) - 1e-4f, hi = fmaxf(pa[c], pb[c]) + 1e-4f;
      if (p[c] < lo || p[c] > hi)
        fail_msg("slice z=%g cell %zu: %g outside [%g, %g]", rec->z[q], c, p[c], lo, hi);
      checked++;
    }
  }
  free(pa);
  free(pb);
  return checked;
}

/* Blend + cubic: every output pixel lies within the range of its two
 * neighbouring input slices' values (no overshoot). */
static void test_cubic_monotone(void **state) {
  (void)state;
  double radius[BALL_SLICES], z[BALL_SLICES];
  ball(radius, z);
  /* make the profile non-monotone in places (a waist) to exercise extrema */
  radius[5] *= 0.6;
  disc_source src = {80, radius, NULL};
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  o.method = LSM_METHOD_BLEND;
  o.interp = LSM_INTERP_CUBIC;
  o.align = LSM_ALIGN_NONE;
  record rec = {0};
  run_stack(&src, z, BALL_SLICES, &o, &rec);
  const size_t cells = (size_t)rec.w * rec.h;
  assert_true(check_within_neighbours(&rec, z, BALL_SLICES, disc_load, &src, radius) > 10 * cells);
  record_free(&rec);
}

/* ---- in-memory source: ellipses turning about the image centre ------------------ */

#define TURN_SLICES 9
typedef struct ellipse_source {
  int size;
  double a, b;  /* semi-axes (px) */
  double turn;  /* rotation per slice (radians) */
} ellipse_source;

static lsm_status ellipse_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
  const ellipse_source *e = ctx;
  LSM_TRY(lsm_mask_create(e->size, e->size, out, err));
  const double c = 0.5 * (e->size - 1), th = e->turn * (double)index;
  for (int y = 0; y < e->size; ++y)
    for (int x = 0; x < e->size; ++x) {
      const double u = (cos(th) * (x - c) + sin(th) * (y - c)) / e->a;
      const double v = (-sin(th) * (x - c) + cos(th) * (y - c)) / e->b;
      out->pixels[(size_t)y * e->size + x] = u * u + v * v <= 1.0;
    }
  return LSM_OK;
}

/* ls and pls + cubic: the morph's departure from the straight line, added to
 * the cubic's, must not take a cell outside its two slices' range either.
 * A long ellipse turning by half a radian per slice, every 6th unit: without
 * the clamp of gap_add_cubic 72 cells leave it, by up to 0.08 px. */
static void test_cubic_monotone_morph(void **state) {
  (void)state;
  ellipse_source src = {64, 20.0, 8.0, 0.5};
  double z[TURN_SLICES];
  for (int k = 0; k < TURN_SLICES; ++k) z[k] = 6.0 * k;
  const lsm_method methods[] = {LSM_METHOD_LS, LSM_METHOD_PLS};
  for (int m = 0; m < 2; ++m) {
    lsm_stack_opts o;
    lsm_stack_opts_default(&o);
    o.method = methods[m];
    o.align = LSM_ALIGN_NONE; /* the range holds in the pair's frame, */
    o.motion = LSM_MOTION_NONE; /* per pixel in place (the field carries values along) */
    record rec = {0};
    run_source(ellipse_load, &src, src.size, z, TURN_SLICES, &o, &rec);
    const size_t cells = (size_t)rec.w * rec.h;
    assert_true(check_within_neighbours(&rec, z, TURN_SLICES, ellipse_load, &src, NULL) >
                30 * cells);
    record_free(&rec);
  }
}

/* Input heights on the output grid get their input slice back exactly. */
static void check_inputs_exact(lsm_method method, lsm_interp interp) {
  double radius[BALL_SLICES], z[BALL_SLICES];
  ball(radius, z);
  disc_source src = {80, radius, NULL};
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  o.method = method;
  o.interp = interp;
  record rec = {0};
  run_stack(&src, z, BALL_SLICES, &o, &rec);
  const size_t cells = (size_t)rec.w * rec.h;
  float *ref = malloc(cells * sizeof(float));
  int seen = 0;
  for (size_t q = 0; q < rec.count; ++q) {
    if (rec.input[q] < 0) continue;
    seen++;
    assert_close(rec.z[q], z[rec.input[q]], 1e-9);
    input_phi(&src, (size_t)rec.input[q], ref);
    const float clamp = (float)hypot(80.0, 80.0);
    for (size_t c = 0; c < cells; ++c) {
      float want = fminf(fmaxf(ref[c], -clamp), clamp);
      if (rec.phi[q * cells + c] != want)
        fail_msg("input slice %ld pixel %zu: %g != %g", rec.input[q], c, rec.phi[q * cells + c], want);
    }
  }
  assert_int_equal(seen, BALL_SLICES);
  assert_int_equal(rec.count, 61); /* z = 3 .. 63 */
  free(ref);
  record_free(&rec);
}

static void test_inputs_exact(void **state) {
  (void)state;
  check_inputs_exact(LSM_METHOD_LS, LSM_INTERP_CUBIC);
  check_inputs_exact(LSM_METHOD_BLEND, LSM_INTERP_CUBIC);
  check_inputs_exact(LSM_METHOD_LS, LSM_INTERP_LINEAR);
}

/* Radius of each output slice: the zero crossing of phi (linear interpolation
 * between pixel centres) along the four half-axes from the centre, averaged. */
static void centre_profile(const record *rec, double *depth) {
  const int w = rec->w, c = w / 2;
  const int dir[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (size_t q = 0; q < rec->count; ++q) {
    const float *p = rec->phi + q * (size_t)w * rec->h;
    double sum = 0.0;
    for (int d = 0; d < 4; ++d) {
      double r = 0.0;
      for (int k = 0; k + 1 < c; ++k) {
        float a = p[(size_t)(c + dir[d][1] * k) * w + c + dir[d][0] * k];
        float b = p[(size_t)(c + dir[d][1] * (k + 1)) * w + c + dir[d][0] * (k + 1)];
        if (a <= 0.0f && b > 0.0f) {
          r = k + a / (a - b);
          break;
        }
      }
      sum += r;
    }
    depth[q] = 0.25 * sum;
  }
}

/* Largest jump between the one-sided slopes dr/dz just below and just above
 * an interior input slice (away from the caps), from output slices dz apart. */
static double slope_jump(const record *rec, const double *depth, const double *radius, double dz) {
  double worst = 0.0;
  for (size_t q = 1; q + 1 < rec->count; ++q) {
    long k = rec->input[q];
    if (k <= 1 || k >= BALL_SLICES - 2 || radius[k - 1] <= 0 || radius[k + 1] <= 0) continue;
    double left = (depth[q] - depth[q - 1]) / dz, right = (depth[q + 1] - depth[q]) / dz;
    worst = fmax(worst, fabs(right - left));
  }
  return worst;
}

static void test_c1_ball(void **state) {
  (void)state;
  double radius[BALL_SLICES], z[BALL_SLICES];
  ball(radius, z);
  disc_source src = {80, radius, NULL};
  double jumps[2][2];
  for (int m = 0; m < 2; ++m) {
    for (int i = 0; i < 2; ++i) {
      lsm_stack_opts o;
      lsm_stack_opts_default(&o);
      o.method = m ? LSM_METHOD_BLEND : LSM_METHOD_LS;
      o.interp = i ? LSM_INTERP_CUBIC : LSM_INTERP_LINEAR;
      o.dz = 0.05;
      record rec = {0};
      run_stack(&src, z, BALL_SLICES, &o, &rec);
      double *depth = malloc(rec.count * sizeof *depth);
      centre_profile(&rec, depth);
      jumps[m][i] = slope_jump(&rec, depth, radius, o.dz);
      free(depth);
      record_free(&rec);
    }
    print_message("%s: slope jump at input slices, linear %.4f, cubic %.4f px per unit z\n",
                  m ? "blend" : "ls", jumps[m][0], jumps[m][1]);
  }
  /* One-sided slopes 0.05 apart: a C1 profile jumps by about 0.05 |r''|
   * (|r''| stays below 1 px per unit z^2 for these cubics), while linear
   * interpolation jumps by the change of chord slope between gaps, 0.1 to
   * 0.8 px per unit z here. */
  for (int m = 0; m < 2; ++m) {
    assert_true(jumps[m][1] < 0.05);
    assert_true(jumps[m][1] < 0.2 * jumps[m][0]);
  }
}

/* Every slice given, dz = spacing: the output is the input. */
static void test_stride_one(void **state) {
  (void)state;
  double radius[BALL_SLICES], z[BALL_SLICES];
  ball(radius, z);
  for (int k = 0; k < BALL_SLICES; ++k) z[k] = 3.0 + k;
  disc_source src = {80, radius, NULL};
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  record rec = {0};
  run_stack(&src, z, BALL_SLICES, &o, &rec);
  assert_int_equal(rec.count, BALL_SLICES);
  for (size_t q = 0; q < rec.count; ++q) assert_int_equal(rec.input[q], (long)q);
  record_free(&rec);
}

/* Per-iteration mode with an empty slice and two identical slices: no
 * numerical failure, the object ends halfway next to the empty slice, and the
 * identical pair takes no iterations. */
static void test_per_iteration_empty_identical(void **state) {
  (void)state;
  const double radius[4] = {0.0, 20.0, 20.0, 10.0}, z[4] = {0.0, 8.0, 16.0, 24.0};
  disc_source src = {64, radius, NULL};
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  o.per_iteration = 1;
  record rec = {0};
  run_stack(&src, z, 4, &o, &rec);
  const size_t cells = (size_t)rec.w * rec.h;
  int inputs = 0;
  double last_empty = -1.0, first_full = 1e9;
  for (size_t q = 0; q < rec.count; ++q) {
    if (rec.input[q] >= 0) inputs++;
    if (q > 0) assert_true(rec.z[q] > rec.z[q - 1]);
    size_t inside = 0;
    for (size_t c = 0; c < cells; ++c) inside += rec.phi[q * cells + c] <= 0.0f;
    if (rec.z[q] < 8.0 && inside == 0) last_empty = fmax(last_empty, rec.z[q]);
    if (rec.z[q] < 8.0 && inside > 0) first_full = fmin(first_full, rec.z[q]);
  }
  assert_int_equal(inputs, 4);
  /* the object is absent up to mid-gap (z = 4) and present after it */
  assert_close(last_empty, 4.0, 1e-9);
  assert_true(first_full > 4.0);
  /* the identical pair (z 8 -> 16) adds no slice between its inputs */
  for (size_t q = 0; q < rec.count; ++q) assert_false(rec.z[q] > 8.0 && rec.z[q] < 16.0);
  record_free(&rec);
}

/* Two discs far apart, then only the big one: the small disc has no
 * counterpart and ends near mid-gap (the halfway rule per component); plain
 * interpolation of the signed distances would close it at s = r / (r + D),
 * here about 0.14. */
typedef struct two_disc_source {
  int size;
} two_disc_source;

static lsm_status two_disc_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
  two_disc_source *d = ctx;
  LSM_TRY(lsm_mask_create(d->size, d->size, out, err));
  for (int y = 0; y < d->size; ++y)
    for (int x = 0; x < d->size; ++x) {
      int big = hypot(x - 30.0, y - 48.0) <= 20.0;
      int small = index == 0 && hypot(x - 80.0, y - 48.0) <= 10.0;
      out->pixels[(size_t)y * d->size + x] = (uint8_t)(big || small);
    }
  return LSM_OK;
}

static void test_component_halfway(void **state) {
  (void)state;
  const double z[2] = {0.0, 16.0};
  two_disc_source src = {96};
  for (int method = 0; method < 2; ++method) {
    lsm_stack_opts o;
    lsm_stack_opts_default(&o);
    o.method = method ? LSM_METHOD_PLS : LSM_METHOD_LS;
    record rec = {0};
    run_source(two_disc_load, &src, src.size, z, 2, &o, &rec);
    double last_present = -1.0;
    for (size_t q = 0; q < rec.count; ++q) {
      const float *p = rec.phi + q * (size_t)96 * 96;
      int present = 0;
      for (int y = 30; y < 66; ++y)
        for (int x = 62; x < 96; ++x) present |= p[(size_t)y * 96 + x] <= 0.0f;
      if (present) last_present = rec.z[q];
    }
    print_message("%s: small disc last present at z = %g of 16\n", method ? "pls" : "ls",
                  last_present);
    assert_true(last_present >= 6.0);  /* s >= 0.375 */
    assert_true(last_present <= 11.0); /* s <= 0.69 */
    record_free(&rec);
  }
}

/* Slopes where the data end (blend + cubic, so each output pixel is the
 * Hermite cubic of its own values).  At the first input slice the slope is
 * PCHIP's non-centred three-point one, ((2H + H) d0 - H d1) / 2H for even
 * heights H, exact for a quadratic profile, not the secant d0: radii 10, 22,
 * 26 at z = 0, 16, 32 are r = 10 + z - z^2/64, and the two slopes put the
 * section at z = 4 about 0.56 px apart. */
static void test_first_slice_slope(void **state) {
  (void)state;
  const double z[3] = {0.0, 16.0, 32.0}, radius[3] = {10.0, 22.0, 26.0};
  disc_source src = {96, radius, NULL};
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  o.method = LSM_METHOD_BLEND;
  o.dz = 1.0;
  record rec = {0};
  run_stack(&src, z, 3, &o, &rec);
  const size_t cells = (size_t)rec.w * rec.h;
  float *p0 = malloc(cells * sizeof(float)), *p1 = malloc(cells * sizeof(float)),
        *p2 = malloc(cells * sizeof(float));
  input_phi(&src, 0, p0);
  input_phi(&src, 1, p1);
  input_phi(&src, 2, p2);
  const double H = 16.0, s = 4.0 / H;
  const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s;
  const double h01 = -2 * s * s * s + 3 * s * s, h11 = s * s * s - s * s;
  const float *out = rec.phi + (size_t)4 * cells; /* z = 4 */
  assert_close(rec.z[4], 4.0, 1e-9);
  double worst = 0.0, apart = 0.0;
  for (size_t c = 0; c < cells; ++c) {
    const double d0 = (p1[c] - p0[c]) / H, d1 = (p2[c] - p1[c]) / H;
    double m0 = (3.0 * d0 - d1) / 2.0; /* the three-point slope, limited */
    if (m0 * d0 <= 0.0) m0 = 0.0;
    else if (d0 * d1 < 0.0 && fabs(m0) > 3.0 * fabs(d0)) m0 = 3.0 * d0;
    const double m1 = d0 * d1 <= 0.0 ? 0.0 : 2.0 / (1.0 / d0 + 1.0 / d1); /* Fritsch-Carlson */
    const double want = h00 * p0[c] + h10 * H * m0 + h01 * p1[c] + h11 * H * m1;
    const double secant = want - h10 * H * (m0 - d0);
    worst = fmax(worst, fabs(out[c] - want));
    if (fabs(p0[c]) < 2.0) apart = fmax(apart, fabs(want - secant)); /* near the outline */
  }
  print_message("first slice: worst |phi - cubic| %.2e, three-point vs secant %.3f\n", worst, apart);
  assert_true(worst < 1e-3);
  assert_true(apart > 0.3);
  free(p0);
  free(p1);
  free(p2);
  record_free(&rec);
}

/* The cubic profile's morph weight, on a lone gap (two slices: the spline is
 * the straight line, so only the weight is left): at fraction s the cubic
 * slice is lin + omega(s) (morph - lin), lin the blend of the two slices, morph
 * the linear profile's slice, omega(s) = 16 s^2 (1 - s)^2 (1 at mid-gap, 0
 * with zero slope at the slices).  Two discs of different size and centre, so
 * the morph departs from the blend. */
static void test_morph_weight(void **state) {
  (void)state;
  const double z[2] = {0.0, 8.0}, radius[2] = {20.0, 13.0}, cx[2] = {42.0, 52.0};
  disc_source src = {96, radius, cx};
  record rec[2] = {{0}, {0}};
  for (int cubic = 0; cubic < 2; ++cubic) {
    lsm_stack_opts o;
    lsm_stack_opts_default(&o);
    o.interp = cubic ? LSM_INTERP_CUBIC : LSM_INTERP_LINEAR;
    o.align = LSM_ALIGN_NONE;
    o.dz = 1.0;
    run_stack(&src, z, 2, &o, &rec[cubic]);
  }
  const size_t cells = (size_t)rec[0].w * rec[0].h;
  float *pa = malloc(cells * sizeof(float)), *pb = malloc(cells * sizeof(float));
  assert_non_null(pa);
  assert_non_null(pb);
  input_phi(&src, 0, pa);
  input_phi(&src, 1, pb);
  assert_int_equal(rec[0].count, 9);
  assert_int_equal(rec[1].count, 9);
  double departure = 0.0;
  for (size_t q = 1; q < 8; ++q) {
    const double s = rec[0].z[q] / 8.0, omega = 16.0 * s * s * (1.0 - s) * (1.0 - s);
    const float *lin_out = rec[0].phi + q * cells, *cub_out = rec[1].phi + q * cells;
    for (size_t c = 0; c < cells; ++c) {
      const double lin = (1.0 - s) * pa[c] + s * pb[c];
      const double want = lin + omega * (lin_out[c] - lin);
      if (fabs(cub_out[c] - want) > 1e-4 * (1.0 + fabs(want)))
        fail_msg("z = %g cell %zu: cubic %g, want %g (lin %g, morph %g, omega %g)", rec[0].z[q], c,
                 cub_out[c], want, lin, lin_out[c], omega);
      if (q == 4) departure = fmax(departure, fabs(lin_out[c] - lin));
    }
  }
  print_message("morph departs from the blend by up to %.3f at mid-gap\n", departure);
  assert_true(departure > 0.5); /* the weight is visible */
  free(pa);
  free(pb);
  record_free(&rec[0]);
  record_free(&rec[1]);
}

/* Aligned pairs (--align hull) move their slices back along a monotone cubic
 * through the centroids.  A disc accelerating along x (centroids 30, 40, 60,
 * 90 px at z = 0, 8, 16, 24): in the gap 8 -> 16 the PCHIP slopes are 5/3
 * px per unit z at z = 8 (secants 1.25 and 2.5) and 3 at z = 16 (2.5 and
 * 3.75), so the centroid at fraction s is the Hermite cubic of 40, 60 with
 * those slopes.  The straight line, or the two slopes swapped, are 1 to 1.6
 * px off inside the gap. */
static void test_aligned_path(void **state) {
  (void)state;
  const double z[4] = {0.0, 8.0, 16.0, 24.0}, radius[4] = {12.0, 12.0, 12.0, 12.0};
  const double cx[4] = {30.0, 40.0, 60.0, 90.0};
  disc_source src = {128, radius, cx};
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  o.align = LSM_ALIGN_HULL;
  o.dz = 1.0;
  record rec = {0};
  run_stack(&src, z, 4, &o, &rec);
  const double H = 8.0, m0 = 2.0 / (1.0 / 1.25 + 1.0 / 2.5), m1 = 2.0 / (1.0 / 2.5 + 1.0 / 3.75);
  double worst = 0.0;
  for (int zq = 9; zq < 16; ++zq) {
    const double s = (zq - 8.0) / H;
    const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s;
    const double h01 = -2 * s * s * s + 3 * s * s, h11 = s * s * s - s * s;
    const double want = h00 * 40.0 + h10 * H * m0 + h01 * 60.0 + h11 * H * m1;
    /* the disc's centre on row 63: midway between the zero crossings of phi */
    const float *row = rec.phi + slice_at(&rec, zq) * (size_t)rec.w * rec.h + (size_t)63 * rec.w;
    double cross[2];
    int found = 0;
    for (int x = 0; x + 1 < rec.w && found < 2; ++x)
      if ((row[x] > 0.0f) != (row[x + 1] > 0.0f))
        cross[found++] = x + (double)row[x] / ((double)row[x] - (double)row[x + 1]);
    assert_int_equal(found, 2);
    const double got = 0.5 * (cross[0] + cross[1]);
    print_message("z = %d: disc centre x %.3f, cubic path %.3f\n", zq, got, want);
    worst = fmax(worst, fabs(got - want));
  }
  assert_true(worst < 0.05);
  record_free(&rec);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_cubic_monotone),
      cmocka_unit_test(test_cubic_monotone_morph),
      cmocka_unit_test(test_inputs_exact),
      cmocka_unit_test(test_c1_ball),
      cmocka_unit_test(test_stride_one),
      cmocka_unit_test(test_per_iteration_empty_identical),
      cmocka_unit_test(test_component_halfway),
      cmocka_unit_test(test_first_slice_slope),
      cmocka_unit_test(test_morph_weight),
      cmocka_unit_test(test_aligned_path),
  };
  return cmocka_run_group_tests_name("interp", tests, NULL, NULL);
}
