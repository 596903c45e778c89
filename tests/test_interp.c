/* Tests of the z-profile through the slices (--interp linear|cubic):
 * monotonicity (blend, ls, pls), exact input slices, C1 continuity across input slices on a
 * ball, stride-1 identity.  Slices come from an in-memory source; output
 * slices are recorded by an in-memory sink. */
#include "tests/lsm_test.h"

#include "solver/sdf/lsm_sdf.h"
#include "solver/recon/lsm_stack.h"

/* ---- in-memory source: discs of given radii (a ball's cross-sections) ------------ */

typedef struct disc_source {
  int size;
  const double *radius; /* per slice; <= 0 means empty */
  const double *cx;     /* per slice centre x (NULL: image centre) */
} disc_source;

static lsm_status disc_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
  disc_source *d = ctx;
  LSM_TRY(lsm_mask_create(d->size, d->size, out, err));
  const double c = 0.5 * (d->size - 1), r = d->radius[index];
  const double cx = d->cx ? d->cx[index] : c;
  for (int y = 0; y < d->size; ++y)
    for (int x = 0; x < d->size; ++x)
      out->pixels[(size_t)y * d->size + x] = r > 0 && hypot(x - cx, y - c) <= r;
  return LSM_OK;
}

/* ---- in-memory sink --------------------------------------------------------------- */

typedef struct record {
  size_t count, cap;
  int w, h;
  float *phi; /* count * w * h */
  double *z;
  long *input;
} record;

static lsm_status record_emit(void *ctx, const float *phi, int w, int h, double z, long input,
                              lsm_err *err) {
  record *r = ctx;
  (void)err;
  if (r->count == r->cap) {
    r->cap = r->cap ? 2 * r->cap : 64;
    r->phi = realloc(r->phi, r->cap * (size_t)w * h * sizeof(float));
    r->z = realloc(r->z, r->cap * sizeof(double));
    r->input = realloc(r->input, r->cap * sizeof(long));
    assert_non_null(r->phi);
  }
  memcpy(r->phi + r->count * (size_t)w * h, phi, (size_t)w * h * sizeof(float));
  r->z[r->count] = z;
  r->input[r->count] = input;
  r->w = w;
  r->h = h;
  r->count++;
  return LSM_OK;
}

static void record_free(record *r) {
  free(r->phi);
  free(r->z);
  free(r->input);
  memset(r, 0, sizeof *r);
}

/* Runs the stack over n slices of size x size read by load(ctx, k). */
typedef lsm_status (*load_fn)(void *ctx, size_t index, lsm_mask *out, lsm_err *err);
static void run_source(load_fn load, void *ctx, int size, const double *z, size_t n,
                       lsm_stack_opts *o, record *out) {
  lsm_slice_source s = {ctx, n, z, load, NULL};
  lsm_slice_sink sink = {out, record_emit};
  lsm_pair_stats *stats = calloc(n, sizeof *stats);
  assert_non_null(stats);
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = lsm_stack_run(&s, size, size, o, &sink, stats, NULL, &err);
  if (st != LSM_OK) fail_msg("stack failed: %s", err.msg);
  free(stats);
}

static void run_stack(disc_source *src, const double *z, size_t n, lsm_stack_opts *o, record *out) {
  run_source(disc_load, src, src->size, z, n, o, out);
}

/* Slice k's signed distance, as the stack computes it, from a source's load. */
static void phi_of(load_fn load, void *ctx, int size, size_t k, float *out) {
  lsm_mask m;
  lsm_grid *g = NULL;
  assert_int_equal(load(ctx, k, &m, NULL), LSM_OK);
  assert_int_equal(lsm_grid_create(size, size, 1.0f, 1.0f, &g, NULL), LSM_OK);
  assert_int_equal(lsm_sdf_from_mask(&m, g, NULL), LSM_OK);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) out[(size_t)y * size + x] = LSM_AT(g, x, y);
  lsm_grid_destroy(&g);
  lsm_mask_free(&m);
}

static void input_phi(disc_source *src, size_t k, float *out) {
  phi_of(disc_load, src, src->size, k, out);
}

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

/* Cells inside (phi <= 0) of output slice q, and their centroid x. */
static size_t slice_inside(const record *rec, size_t q, double *centroid_x) {
  const size_t cells = (size_t)rec->w * rec->h;
  size_t inside = 0;
  double sx = 0.0;
  for (size_t c = 0; c < cells; ++c)
    if (rec->phi[q * cells + c] <= 0.0f) {
      inside++;
      sx += (double)(c % (size_t)rec->w);
    }
  if (centroid_x) *centroid_x = inside ? sx / (double)inside : -1.0;
  return inside;
}

/* The output slice at height z (dz = 1 here, so heights are whole). */
static size_t slice_at(const record *rec, double z) {
  for (size_t q = 0; q < rec->count; ++q)
    if (fabs(rec->z[q] - z) < 1e-9) return q;
  fail_msg("no output slice at z = %g", z);
  return 0;
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

/* The interior side of a last section (the object ends in the gap beyond
 * it) takes the three-point slope, as at the first input slice: a rounded
 * solid's radius profile is curved there, and the gap's secant (the rule
 * before) drew the sections between too small.  A ball of radius 25 centred
 * at z = 30, cut every 16 units with empty slices at z = 0 and 64 (sections
 * of radius 20.7, 24.9 and 17.3): the section halfway through each interior
 * gap, z = 24 and 40, has the ball's radius (24.3 and 22.9) within 0.5 px
 * with ls and blend; with the secant it was about 1 px small at z = 24. */
/* Radius of a ball of radius R centred at z = centre at height z (0 outside it). */
static double ball_radius(double R, double centre, double z) {
  const double h = z - centre;
  return R * R - h * h > 0 ? sqrt(R * R - h * h) : 0.0;
}

/* A ball of radius R centred at z = centre cut every 16 units from z = 0 (n
 * sections), run with ls (method 0) or blend (1) at dz = 1 into rec. */
static void run_cut_ball(double R, double centre, size_t n, int size, int method, record *rec) {
  double z[8], radius[8];
  assert_true(n <= 8);
  for (size_t k = 0; k < n; ++k) {
    z[k] = 16.0 * (double)k;
    radius[k] = ball_radius(R, centre, z[k]);
  }
  disc_source src = {size, radius, NULL};
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  o.method = method ? LSM_METHOD_BLEND : LSM_METHOD_LS;
  o.dz = 1.0;
  run_stack(&src, z, n, &o, rec);
}

/* The radius of the disc with the area of the output slice at height z. */
static double radius_at(const record *rec, double z) {
  return sqrt((double)slice_inside(rec, slice_at(rec, z), NULL) / acos(-1.0));
}

static void test_ball_beside_ends(void **state) {
  (void)state;
  for (int method = 0; method < 2; ++method) {
    record rec = {0};
    run_cut_ball(25.0, 30.0, 5, 80, method, &rec);
    const double at[2] = {24.0, 40.0};
    for (int k = 0; k < 2; ++k) {
      const double r = radius_at(&rec, at[k]), truth = ball_radius(25.0, 30.0, at[k]);
      print_message("%s, z = %g: radius %.2f, the ball's %.2f\n", method ? "blend" : "ls", at[k], r,
                    truth);
      assert_true(fabs(r - truth) < 0.5);
    }
    record_free(&rec);
  }
}

/* An object with two sections, each a last section: the slope at the
 * smaller one takes the three-point slope through the empty slice beyond the
 * larger one, counted as that section eroded by its largest depth (as at the
 * first or last input slice).  A ball of radius 20 centred at z = 26, cut
 * every 16 units (empty at z = 0 and 48, radii 17.3 and 19.1 at 16 and 32):
 * halfway, at z = 24, the ball's radius is 19.9, above both sections (its
 * equator lies between them), which no monotone profile passes; the
 * section there has an area-equivalent radius of 19.1 with ls and blend (18.3
 * with the secant, the slope when there was no third section). */
static void test_two_sections(void **state) {
  (void)state;
  for (int method = 0; method < 2; ++method) {
    record rec = {0};
    run_cut_ball(20.0, 26.0, 4, 64, method, &rec);
    const double r = radius_at(&rec, 24.0);
    print_message("%s, z = 24: radius %.2f (sections 17.32 and 19.08, the ball's 19.90)\n",
                  method ? "blend" : "ls", r);
    assert_true(r > 18.7 && r < 19.9);
    record_free(&rec);
  }
}

/* Next to an empty slice the slope at the last section is the one the end
 * gap continues with: 0 where the section grows toward the end.  Radii 20 at
 * z = 8 and 16 at z = 16 (the widest part between them, the object ending
 * below z = 8): the section just past z = 8 keeps its area (the secant would
 * shrink it straight toward z = 16, about 5 % of the area by z = 9).  The
 * same stack upside down (the empty slice above) gives the same areas at
 * every distance from F: the rule is symmetric in z. */
static void test_end_neighbour_flat(void **state) {
  (void)state;
  const double z[3] = {0.0, 8.0, 16.0}, radius[3] = {0.0, 20.0, 16.0};
  const double mirrored[3] = {16.0, 20.0, 0.0}; /* the same with the empty slice above */
  size_t areas[2][2][9]; /* [up][method][units from F]: the rule is symmetric in z */
  for (int up = 0; up < 2; ++up) {
    disc_source src = {96, up ? mirrored : radius, NULL};
    /* heights from the full section toward the narrower one */
    const double zf = 8.0, z1 = up ? 7.0 : 9.0, z4 = up ? 4.0 : 12.0, zn = up ? 0.0 : 16.0;
    for (int method = 0; method < 2; ++method) {
      lsm_stack_opts o;
      lsm_stack_opts_default(&o);
      o.method = method ? LSM_METHOD_BLEND : LSM_METHOD_LS;
      o.dz = 1.0;
      record rec = {0};
      run_stack(&src, z, 3, &o, &rec);
      const size_t a8 = slice_inside(&rec, slice_at(&rec, zf), NULL);
      const size_t a9 = slice_inside(&rec, slice_at(&rec, z1), NULL);
      const size_t a12 = slice_inside(&rec, slice_at(&rec, z4), NULL);
      const size_t a16 = slice_inside(&rec, slice_at(&rec, zn), NULL);
      print_message("%s, empty slice %s: area at 0, 1, 4, 8 units from F: %zu %zu %zu %zu\n",
                    method ? "blend" : "ls", up ? "above" : "below", a8, a9, a12, a16);
      assert_true((double)a9 >= 0.98 * (double)a8);
      assert_true(a9 <= a8 && a12 < a9 && a16 < a12); /* and no overshoot */
      for (int t = 0; t <= 8; ++t)
        areas[up][method][t] = slice_inside(&rec, slice_at(&rec, up ? 8.0 - t : 8.0 + t), NULL);
      record_free(&rec);
    }
  }
  for (int method = 0; method < 2; ++method)
    for (int t = 0; t <= 8; ++t)
      if (areas[0][method][t] != areas[1][method][t])
        fail_msg("%s, %d units from F: area %zu with the empty slice below, %zu above",
                 method ? "blend" : "ls", t, areas[0][method][t], areas[1][method][t]);
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

/* Where the object ends (default options, cubic): an empty slice at z = 0,
 * the last non-empty one F at z = 8, the slice N beyond it at z = 16 and,
 * where a third section is given, M at z = 24.
 *   flat end (F = N = M, a cylinder): F's section, whole, up to mid-gap; from there a tip
 *     whose radius shrinks linearly to 0 at the empty slice (a cone), area
 *     A_F (2 (1 - sigma))^2 at fraction sigma of the way from F; an end that
 *     narrows toward the empty slice closes faster, A_F (2 (1 - sigma))^3;
 *   paraboloid end (areas of N and F on a line that reaches 0 at z = 4): the
 *     area at z = 6 at most the line's, A_F / 2, and not far below it; past
 *     z = 4 a tenth of the cone's tip;
 *   no slice beyond F (a lone section): a flat end;
 *   moving end (N and F do not overlap): the section keeps moving at the
 *     centroid velocity of N -> F, 2 px per unit z;
 *   two sections only (F = N, no M): the area follows the parabola through
 *     the areas of N and F and zero at the empty slice, 5/8 of F's at mid-gap. */
static void test_object_ends(void **state) {
  (void)state;
  const double z[4] = {0.0, 8.0, 16.0, 24.0};
  const double r_flat[4] = {0.0, 20.0, 20.0, 20.0};
  const double r_para[3] = {0.0, 10.0, sqrt(300.0)};
  const double r_moving[4] = {0.0, 8.0, 8.0, 8.0}, cx_moving[4] = {0.0, 40.0, 56.0, 72.0};
  const double r_bulge[4] = {0.0, 20.0, 22.0, 24.0}; /* narrows by 21 % in area toward the end */
  struct {
    const char *name;
    const double *radius, *cx;
    size_t slices;
    double tip_power; /* 0: the area line closes the end by mid-gap */
  } cases[] = {{"flat", r_flat, NULL, 4, 2.0},
               {"paraboloid", r_para, NULL, 3, 0.0},
               {"no slice beyond", r_flat, NULL, 2, 2.0}, /* a lone section: a flat end */
               {"moving", r_moving, cx_moving, 4, 2.0},
               {"narrowing slowly", r_bulge, NULL, 4, 3.0}};
  for (size_t t = 0; t < sizeof cases / sizeof cases[0]; ++t) {
    disc_source src = {96, cases[t].radius, cases[t].cx};
    lsm_stack_opts o;
    lsm_stack_opts_default(&o);
    o.dz = 1.0;
    /* the moving end keeps moving with --align auto's frame (rule end-moves-on), which acts
     * with --motion none; the field does not carry an end */
    o.motion = LSM_MOTION_NONE;
    record rec = {0};
    run_stack(&src, z, cases[t].slices, &o, &rec);
    const size_t area_f = slice_inside(&rec, slice_at(&rec, 8.0), NULL);
    assert_int_equal(slice_inside(&rec, slice_at(&rec, 0.0), NULL), 0); /* the empty input */
    const double p = cases[t].tip_power;
    if (p > 0.0) { /* the tip past mid-gap: area A_F (zz / 4)^p, p = 2 (a cone)
                    * for an end that does not narrow, 3 for one that does */
      for (double zz = 1.0; zz <= 4.0; zz += 1.0) {
        const double tip = (double)area_f * pow(zz / 4.0, p);
        const size_t a = slice_inside(&rec, slice_at(&rec, zz), NULL);
        print_message("end %s: area at z = %.0f: %zu (tip %.1f)\n", cases[t].name, zz, a, tip);
        assert_true((double)a <= tip && (double)a >= 0.85 * tip - 4.0);
      }
    } else { /* narrowing fast: the area line closes the end by mid-gap; what
              * is left past it is a tenth of the cone's tip, A_F (zz / 4)^2 / 10
              * (give or take a ring of tied pixels), never nothing */
      for (double zz = 1.0; zz <= 3.0; zz += 1.0) {
        const double tenth = 0.1 * (double)area_f * pow(zz / 4.0, 2.0);
        const size_t a = slice_inside(&rec, slice_at(&rec, zz), NULL);
        print_message("end %s: area at z = %.0f: %zu (a tenth of the tip %.1f)\n", cases[t].name,
                      zz, a, tenth);
        assert_true(a >= 1 && fabs((double)a - tenth) <= 8.0);
      }
      assert_true(slice_inside(&rec, slice_at(&rec, 4.0), NULL) <= 0.1 * (double)area_f + 8.0);
    }
    double cx6 = 0.0;
    const size_t area5 = slice_inside(&rec, slice_at(&rec, 5.0), NULL);
    const size_t area6 = slice_inside(&rec, slice_at(&rec, 6.0), &cx6);
    const size_t area7 = slice_inside(&rec, slice_at(&rec, 7.0), NULL);
    print_message("end %s: area at z = 8, 7, 6, 5: %zu %zu %zu %zu, centroid x at 6: %.2f\n",
                  cases[t].name, area_f, area7, area6, area5, cx6);
    if (p == 2.0) { /* not narrowing: whole up to mid-gap */
      assert_int_equal(area5, area_f);
      assert_int_equal(area6, area_f);
      assert_int_equal(area7, area_f);
    } else { /* at most the line through the areas of N and F or, with M (the
              * slice beyond N), the parabola through the areas of M, N and F
              * instead, and not far below it */
      const double a_n = (double)slice_inside(&rec, slice_at(&rec, 16.0), NULL);
      const int has_m = cases[t].slices == 4;
      const double a_m = has_m ? (double)slice_inside(&rec, slice_at(&rec, 24.0), NULL) : 0.0;
      for (double zz = 5.0; zz <= 7.0; zz += 1.0) {
        const double d = 8.0 - zz, d1 = ((double)area_f - a_n) / 8.0, d0 = (a_n - a_m) / 8.0;
        const double cap = has_m ? (double)area_f + d1 * d + (d1 - d0) / 16.0 * d * (d + 8.0)
                                 : (double)area_f + d1 * d;
        const size_t a = slice_inside(&rec, slice_at(&rec, zz), NULL);
        print_message("end %s: area at z = %.0f: %zu (cap %.1f)\n", cases[t].name, zz, a, cap);
        assert_true((double)a <= cap && (double)a >= 0.85 * cap - 4.0);
      }
    }
    if (t == 3) assert_true(fabs(cx6 - 36.0) <= 0.5); /* 40 - 2 px per unit z * 2 */
    record_free(&rec);
  }
  {
    disc_source src = {96, r_flat, NULL};
    lsm_stack_opts o;
    lsm_stack_opts_default(&o);
    o.dz = 1.0;
    record rec = {0};
    run_stack(&src, z, 3, &o, &rec);
    const double area_f = (double)slice_inside(&rec, slice_at(&rec, 8.0), NULL);
    const double area4 = (double)slice_inside(&rec, slice_at(&rec, 4.0), NULL);
    print_message("end two sections: area at z = 4: %.0f (5/8 of F %.0f)\n", area4,
                  0.625 * area_f);
    assert_true(fabs(area4 - 0.625 * area_f) <= 0.05 * area_f);
    record_free(&rec);
  }
  /* Uneven gaps: N -> F moves 16 px in 1 unit, the end gap is 400 units long.
   * The extrapolated end stops at the image border (x = 0) instead of 6400 px
   * away, so the canvas stays bounded; at a quarter of the gap the centroid
   * is a quarter of the way from 40 to 0; the shape trend measured over 1
   * unit is not multiplied by 100. */
  const double z_long[4] = {0.0, 400.0, 401.0, 402.0};
  const double cx_long[4] = {0.0, 40.0, 56.0, 72.0};
  disc_source src = {96, r_moving, cx_long};
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  o.dz = 1.0;
  o.motion = LSM_MOTION_NONE; /* end-moves-on, as above */
  record rec = {0};
  run_stack(&src, z_long, 4, &o, &rec);
  double cx300 = 0.0;
  const size_t area300 = slice_inside(&rec, slice_at(&rec, 300.0), &cx300);
  print_message("end moving, long gap: area at z = 300: %zu, centroid x %.2f\n", area300, cx300);
  /* whole, but for the pixel by which the whole-pixel shifts of N and F
   * disagree (centroids 8.5 and -7.5 px from the centre, rounded apart) */
  assert_true((double)area300 >= 0.9 * (double)slice_inside(&rec, slice_at(&rec, 400.0), NULL));
  assert_true(fabs(cx300 - 30.0) <= 0.5);
  record_free(&rec);
}

/* --ends: the flat end of test_object_ends (a cylinder crossed by three
 * sections, an empty slice at z = 0).  halfway: the same as tip from F down
 * to mid-gap, whole, and nothing past it, where tip keeps its tip.  auto (the
 * default): tip where the empty slice is the first input slice, as here;
 * halfway when another empty slice lies below it (z = -8: a scan that
 * covers more than the object). */
static void test_object_ends_halfway(void **state) {
  (void)state;
  const double z[5] = {-8.0, 0.0, 8.0, 16.0, 24.0};
  const double r_flat[5] = {0.0, 0.0, 20.0, 20.0, 20.0};
  disc_source cut = {96, r_flat + 1, NULL}, scan = {96, r_flat, NULL};
  record tip = {0}, halfway = {0}, auto_cut = {0}, auto_scan = {0};
  lsm_stack_opts o;
  lsm_stack_opts_default(&o);
  assert_int_equal(o.ends, LSM_ENDS_AUTO);
  o.dz = 1.0;
  run_stack(&cut, z + 1, 4, &o, &auto_cut);
  run_stack(&scan, z, 5, &o, &auto_scan);
  o.ends = LSM_ENDS_TIP;
  run_stack(&cut, z + 1, 4, &o, &tip);
  o.ends = LSM_ENDS_HALFWAY;
  run_stack(&cut, z + 1, 4, &o, &halfway);
  const size_t area_f = slice_inside(&halfway, slice_at(&halfway, 8.0), NULL);
  for (double zz = 1.0; zz <= 8.0; zz += 1.0) {
    const size_t a = slice_inside(&halfway, slice_at(&halfway, zz), NULL);
    const size_t a_tip = slice_inside(&tip, slice_at(&tip, zz), NULL);
    print_message("end halfway: area at z = %.0f: %zu (tip rule %zu)\n", zz, a, a_tip);
    if (zz < 4.0) {
      assert_int_equal(a, 0);
      assert_true(a_tip > 0);
    } else {
      assert_int_equal(a, area_f);
      assert_int_equal(a, a_tip);
    }
    assert_int_equal(slice_inside(&auto_cut, slice_at(&auto_cut, zz), NULL), a_tip);
    assert_int_equal(slice_inside(&auto_scan, slice_at(&auto_scan, zz), NULL), a);
  }
  record_free(&tip);
  record_free(&halfway);
  record_free(&auto_cut);
  record_free(&auto_scan);
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
      cmocka_unit_test(test_object_ends),
      cmocka_unit_test(test_object_ends_halfway),
      cmocka_unit_test(test_first_slice_slope),
      cmocka_unit_test(test_end_neighbour_flat),
      cmocka_unit_test(test_ball_beside_ends),
      cmocka_unit_test(test_two_sections),
      cmocka_unit_test(test_morph_weight),
      cmocka_unit_test(test_aligned_path),
  };
  return cmocka_run_group_tests_name("interp", tests, NULL, NULL);
}
