/* End-to-end tests of the stack driver (solver/recon/lsm_stack.c) through an
 * in-memory slice source (synthetic shapes) and a sink that records every
 * output slice: output heights, exact input slices, the cone of concentric
 * discs, topology changes (merge, split, vanish, appear), alignment of
 * disjoint slices, nested outline contours and the per-iteration mode. */
#include "tests/lsm_test.h"

#include <signal.h>

#include "solver/base/lsm_grid.h"
#include "solver/sdf/lsm_sdf.h"
#include "solver/recon/lsm_stack.h"
#include "solver/base/lsm_status.h"

#define PI 3.14159265358979323846

/* ------------------------------------------------------------------------ */
/* synthetic slices                                                          */

enum { SH_DISC, SH_RECT };

typedef struct shape {
  int kind;      /* SH_DISC or SH_RECT */
  int hole;      /* cut out of the shape it lies in */
  double cx, cy; /* disc centre (pixels: column, row) */
  double r;      /* disc radius */
  int x0, y0, x1, y1; /* closed rectangle */
} shape;

typedef struct slice_def {
  int n;
  shape s[4];
} slice_def;

static shape disc(double cx, double cy, double r) {
  shape s = {SH_DISC, 0, cx, cy, r, 0, 0, 0, 0};
  return s;
}
static shape disc_hole(double cx, double cy, double r) {
  shape s = {SH_DISC, 1, cx, cy, r, 0, 0, 0, 0};
  return s;
}
static shape rect(int x0, int y0, int x1, int y1, int hole) {
  shape s = {SH_RECT, hole, 0, 0, 0, x0, y0, x1, y1};
  return s;
}

static int in_shape(const shape *s, int x, int y) {
  if (s->kind == SH_DISC) return (x - s->cx) * (x - s->cx) + (y - s->cy) * (y - s->cy) <= s->r * s->r;
  return x >= s->x0 && x <= s->x1 && y >= s->y0 && y <= s->y1;
}

/* Contour pixel of a primitive: inside it with a 4-neighbour outside it
 * (the rule of examples/gen_synthetic.c). */
static int on_contour(const shape *s, int x, int y) {
  return in_shape(s, x, y) && (!in_shape(s, x - 1, y) || !in_shape(s, x + 1, y) ||
                               !in_shape(s, x, y - 1) || !in_shape(s, x, y + 1));
}

typedef struct source_ctx {
  int width, height;
  int outline;          /* write contours instead of filled masks */
  int y_step;           /* row y samples the shapes at y_step * y (masks; 1: y) */
  const slice_def *defs;
  size_t count;
  int loads;
} source_ctx;

/* Mask: union of the outer shapes minus the strict inside of the holes. */
static void paint(const source_ctx *c, const slice_def *d, lsm_mask *m) {
  const int step = c->y_step;
  for (int row = 0; row < m->height; ++row)
    for (int x = 0; x < m->width; ++x) {
      const int y = row * step;
      uint8_t v = 0;
      if (c->outline) {
        for (int k = 0; k < d->n; ++k) v |= (uint8_t)on_contour(&d->s[k], x, y);
      } else {
        for (int k = 0; k < d->n; ++k)
          if (!d->s[k].hole) v |= (uint8_t)in_shape(&d->s[k], x, y);
        for (int k = 0; k < d->n; ++k)
          if (d->s[k].hole && in_shape(&d->s[k], x, y) && !on_contour(&d->s[k], x, y)) v = 0;
      }
      m->pixels[(size_t)row * m->width + x] = v;
    }
}

static lsm_status src_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
  source_ctx *c = ctx;
  LSM_TRY(lsm_mask_create(c->width, c->height, out, err));
  paint(c, &c->defs[index], out);
  c->loads++;
  return LSM_OK;
}

static const char *src_name(void *ctx, size_t index) {
  (void)ctx;
  static char buf[32];
  snprintf(buf, sizeof buf, "slice%zu", index);
  return buf;
}

/* Signed distance of input slice `index` computed directly (the reference
 * for "input slices come back exactly"). */
static float *input_phi(const source_ctx *c, size_t index) {
  lsm_mask m;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_mask_create(c->width, c->height, &m, &err), LSM_OK);
  paint(c, &c->defs[index], &m);
  lsm_grid *g = NULL;
  assert_int_equal(lsm_grid_create(c->width, c->height, 1.0f, 1.0f, &g, &err), LSM_OK);
  if (c->outline)
    assert_int_equal(lsm_sdf_from_outline(&m, g, &err), LSM_OK);
  else
    assert_int_equal(lsm_sdf_from_mask(&m, g, &err), LSM_OK);
  float *out = malloc((size_t)c->width * c->height * sizeof *out);
  assert_non_null(out);
  for (int y = 0; y < c->height; ++y)
    for (int x = 0; x < c->width; ++x) out[(size_t)y * c->width + x] = LSM_AT(g, x, y);
  lsm_grid_destroy(&g);
  lsm_mask_free(&m);
  return out;
}

/* ------------------------------------------------------------------------ */
/* recording sink                                                            */

typedef struct out_slice {
  float *phi;
  double z;
  long input_index;
} out_slice;

typedef struct sink_ctx {
  int width, height;
  out_slice *s;
  size_t n, cap;
} sink_ctx;

static lsm_status sink_emit(void *ctx, const float *phi, int width, int height, double z,
                            long input_index, lsm_err *err) {
  (void)err;
  sink_ctx *c = ctx;
  assert_int_equal(width, c->width);
  assert_int_equal(height, c->height);
  if (c->n == c->cap) {
    c->cap = c->cap ? 2 * c->cap : 16;
    c->s = realloc(c->s, c->cap * sizeof *c->s);
    assert_non_null(c->s);
  }
  const size_t bytes = (size_t)width * height * sizeof(float);
  out_slice *o = &c->s[c->n++];
  o->phi = malloc(bytes);
  assert_non_null(o->phi);
  memcpy(o->phi, phi, bytes);
  o->z = z;
  o->input_index = input_index;
  return LSM_OK;
}

static void sink_free(sink_ctx *c) {
  for (size_t k = 0; k < c->n; ++k) free(c->s[k].phi);
  free(c->s);
  memset(c, 0, sizeof *c);
}

/* Runs a stack; returns the status, the sink holds the slices. */
typedef struct run {
  source_ctx src;
  sink_ctx sink;
  lsm_pair_stats stats[8];
  lsm_err err;
} run;

/* Runs a stack whose row y samples the shapes at y_step * y (1: every row;
 * opts->pixel_dy says how far apart the rows are); returns the status, the
 * sink holds the slices. */
static lsm_status run_stack_rows(run *r, int w, int h, int outline, int y_step,
                                 const slice_def *defs, const double *z, size_t count,
                                 const lsm_stack_opts *opts) {
  memset(r, 0, sizeof *r);
  r->src = (source_ctx){w, h, outline, y_step, defs, count, 0};
  r->sink.width = w;
  r->sink.height = h;
  lsm_err_clear(&r->err);
  lsm_slice_source source = {&r->src, count, z, src_load, src_name};
  lsm_slice_sink sink = {&r->sink, sink_emit};
  return lsm_stack_run(&source, w, h, opts, &sink, r->stats, NULL, &r->err);
}

static lsm_status run_stack(run *r, int w, int h, int outline, const slice_def *defs,
                            const double *z, size_t count, const lsm_stack_opts *opts) {
  return run_stack_rows(r, w, h, outline, 1, defs, z, count, opts);
}

/* ------------------------------------------------------------------------ */
/* measurements on an output slice (inside: phi <= 0, as the CLI writes)     */

static size_t area(const float *phi, int w, int h) {
  size_t n = 0;
  for (int k = 0; k < w * h; ++k) n += phi[k] <= 0.0f;
  return n;
}

/* Connected components of the pixels with (phi <= 0) == fg, 8- or
 * 4-connected.  With skip_border, components touching the image border are
 * not counted.  Per component, centroid sums go to cx/cy if given (up to 8). */
static int components(const float *phi, int w, int h, int fg, int conn8, int skip_border,
                      double *cx, double *cy) {
  int *label = calloc((size_t)w * h, sizeof *label);
  int *stack = malloc((size_t)w * h * sizeof *stack);
  assert_non_null(label);
  assert_non_null(stack);
  int count = 0;
  for (int start = 0; start < w * h; ++start) {
    if (label[start] || (phi[start] <= 0.0f) != fg) continue;
    int top = 0, touches = 0;
    size_t npx = 0;
    double sx = 0, sy = 0;
    stack[top++] = start;
    label[start] = -1;
    while (top) {
      const int p = stack[--top], x = p % w, y = p / w;
      npx++;
      sx += x;
      sy += y;
      if (x == 0 || y == 0 || x == w - 1 || y == h - 1) touches = 1;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (!dx && !dy) continue;
          if (!conn8 && dx && dy) continue;
          const int xx = x + dx, yy = y + dy;
          if (xx < 0 || yy < 0 || xx >= w || yy >= h) continue;
          const int q = yy * w + xx;
          if (label[q] || (phi[q] <= 0.0f) != fg) continue;
          label[q] = -1;
          stack[top++] = q;
        }
    }
    if (skip_border && touches) continue;
    if (cx && count < 8) cx[count] = sx / npx, cy[count] = sy / npx;
    count++;
  }
  free(label);
  free(stack);
  return count;
}

static int fg_components(const float *phi, int w, int h) {
  return components(phi, w, h, 1, 1, 0, NULL, NULL);
}

/* Holes: 4-connected background components that do not touch the border. */
static int holes(const float *phi, int w, int h) { return components(phi, w, h, 0, 0, 1, NULL, NULL); }

static void check_exact_input(const run *r, size_t out_index, size_t input_index) {
  const out_slice *o = &r->sink.s[out_index];
  assert_int_equal(o->input_index, (long)input_index);
  float *want = input_phi(&r->src, input_index);
  const int n = r->src.width * r->src.height;
  /* an outline pixel lies on the contour (phi = 0): written a millionth of
   * a pixel below zero, as every tie on the surface (pixel size 1 here) */
  for (int k = 0; k < n; ++k)
    if (want[k] == 0.0f) want[k] = -1e-6f;
  for (int k = 0; k < n; ++k)
    if (o->phi[k] != want[k])
      fail_msg("output slice %zu (z = %g) differs from input %zu at pixel %d: %.9g vs %.9g",
               out_index, o->z, input_index, k, o->phi[k], want[k]);
  free(want);
}

static void default_opts(lsm_stack_opts *o) {
  lsm_stack_opts_default(o);
  o->morph.threads = 2;
}

/* ------------------------------------------------------------------------ */
/* concentric discs: a cone                                                   */

#define W 101
#define H 101
#define C 50.0 /* image centre */

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
/* topology                                                                  */

/* Component counts of the intermediate slices, printed as a string. */
static void counts(const run *r, int *c, char *text) {
  text[0] = '\0';
  for (size_t k = 0; k < r->sink.n; ++k) {
    c[k] = fg_components(r->sink.s[k].phi, W, H);
    sprintf(text + strlen(text), "%d", c[k]);
  }
}

/* Two discs merge into one.  A: discs r = 6 at x = 32, 68 (a 24 px gap: the
 * neck point (50, 50) is 12 px outside A); B: one disc r = 25 at the centre,
 * covering both (the neck is 25 px deep inside it).  While phi relaxes like
 * a distance function, phi(s) at the neck ~ (1 - s) 12 + s (-25) (exact for
 * the blend), so the neck closes near s = 12/37 = 0.32: at z = 1 (s = 0.1)
 * there are 2 components (phi ~ +8 there), at z = 9 one (phi ~ -21).  The
 * count never goes back up.  Split is the same pair in reverse order. */
static void test_merge_split(void **state) {
  (void)state;
  const slice_def two = {2, {disc(32, C, 6), disc(68, C, 6)}};
  const slice_def one = {1, {disc(C, C, 25)}};
  const double z[2] = {0, 10};
  int c[16];
  char text[32];
  for (int method = 0; method < 2; ++method) {
    lsm_stack_opts o;
    default_opts(&o);
    o.method = method ? LSM_METHOD_BLEND : LSM_METHOD_LS;
    const slice_def merge[2] = {two, one}, split[2] = {one, two};
    run r;
    assert_int_equal(run_stack(&r, W, H, 0, merge, z, 2, &o), LSM_OK);
    assert_int_equal(r.sink.n, 11);
    counts(&r, c, text);
    print_message("merge (%s): components %s\n", lsm_method_name(o.method), text);
    assert_int_equal(c[0], 2);
    assert_int_equal(c[1], 2);
    assert_int_equal(c[9], 1);
    assert_int_equal(c[10], 1);
    for (int k = 1; k <= 10; ++k) {
      assert_true(c[k] == 1 || c[k] == 2);
      assert_true(c[k] <= c[k - 1]);
    }
    /* The area grows monotonically from two small discs to the big one. */
    for (int k = 1; k <= 10; ++k)
      assert_true(area(r.sink.s[k].phi, W, H) >= area(r.sink.s[k - 1].phi, W, H));
    sink_free(&r.sink);

    assert_int_equal(run_stack(&r, W, H, 0, split, z, 2, &o), LSM_OK);
    counts(&r, c, text);
    print_message("split (%s): components %s\n", lsm_method_name(o.method), text);
    assert_int_equal(c[0], 1);
    assert_int_equal(c[1], 1);
    assert_int_equal(c[9], 2);
    assert_int_equal(c[10], 2);
    for (int k = 1; k <= 10; ++k) {
      assert_true(c[k] == 1 || c[k] == 2);
      assert_true(c[k] >= c[k - 1]);
    }
    for (int k = 1; k <= 10; ++k)
      assert_true(area(r.sink.s[k].phi, W, H) <= area(r.sink.s[k - 1].phi, W, H));
    sink_free(&r.sink);
  }
}

/* Where an object ends, each part of its last section ends its own way.  At
 * z = 8: a disc r = 10 at x = 30 that narrows (at z = 16 it is r = sqrt(300),
 * so the line through its two areas reaches 0 at z = 4), and a disc r = 8 at
 * x = 75 that nothing at z = 16 continues (a lone part: a flat end); z = 0 is
 * empty.  Cubic profile (the default): the lone disc stays whole up to
 * mid-gap (z = 5, 6, 7), the narrowing one follows its own area line.  One
 * area line for the whole section (the rule before) took the narrowing of
 * the left disc for the whole section, and the right one lost its cells. */
static void test_end_parts(void **state) {
  (void)state;
  const slice_def defs[3] = {{0, {{0}}},
                             {2, {disc(30, C, 10), disc(75, C, 8)}},
                             {1, {disc(30, C, sqrt(300.0))}}};
  const double z[3] = {0, 8, 16};
  lsm_stack_opts o;
  default_opts(&o);
  run r;
  assert_int_equal(run_stack(&r, W, H, 0, defs, z, 3, &o), LSM_OK);
  assert_int_equal(r.sink.n, 17);
  size_t left[17], right[17];
  for (int k = 0; k <= 16; ++k) {
    left[k] = right[k] = 0;
    for (int p = 0; p < W * H; ++p)
      if (r.sink.s[k].phi[p] <= 0.0f) ++*(p % W < 52 ? &left[k] : &right[k]);
  }
  print_message("end parts: left (narrowing) at z = 4..8: %zu %zu %zu %zu %zu; right (lone): %zu %zu %zu %zu %zu\n",
                left[4], left[5], left[6], left[7], left[8], right[4], right[5], right[6], right[7], right[8]);
  assert_int_equal(right[16], 0);
  for (int k = 5; k <= 7; ++k) {
    assert_int_equal(right[k], right[8]);
    const double line = (double)left[8] - (8.0 - k) * ((double)left[16] - (double)left[8]) / 8.0;
    assert_true((double)left[k] <= line && (double)left[k] >= 0.85 * line - 4.0);
  }
  /* past the left disc's line (z = 4) a tenth of its cone tip is left; the
   * lone disc's tip, a cone's, A_F (3 / 4)^2 at z = 3, is far larger */
  const double tenth = 0.1 * (double)left[8] * pow(3.0 / 4.0, 2.0);
  assert_true(left[3] >= 1 && fabs((double)left[3] - tenth) <= 8.0);
  const double cone = (double)right[8] * pow(3.0 / 4.0, 2.0);
  assert_true((double)right[3] <= cone && (double)right[3] >= 0.85 * cone - 4.0);
  assert_true((double)right[3] > 2.0 * tenth);
  sink_free(&r.sink);
}

/* ------------------------------------------------------------------------ */
/* an end that moves on                                                      */

/* A disc drifting 2 px per unit z (an oblique vessel) and ending in the last
 * gap: with --align auto the end keeps moving along the drift, and run.json's
 * "aligned" says so for that gap as for the others. */
static void test_end_moves_on(void **state) {
  (void)state;
  const slice_def defs[5] = {{1, {disc(20, C, 5)}}, {1, {disc(36, C, 5)}}, {1, {disc(52, C, 5)}},
                             {1, {disc(68, C, 5)}}, {0, {{0}}}};
  const double z[5] = {0, 8, 16, 24, 32};
  lsm_stack_opts o;
  default_opts(&o);
  o.motion = LSM_MOTION_NONE; /* --align auto's rules act with --motion none */
  run r;
  assert_int_equal(run_stack(&r, W, H, 0, defs, z, 5, &o), LSM_OK);
  assert_int_equal(r.sink.n, 33);
  for (int k = 0; k < 4; ++k)
    if (!r.stats[k].aligned) fail_msg("gap %d: aligned = 0", k + 1);
  double cx[8], cy[8];
  assert_int_equal(components(r.sink.s[27].phi, W, H, 1, 1, 0, cx, cy), 1);
  print_message("end moves on: centroid at z = 27: %.1f (the last section's 68, the drift's 74)\n",
                cx[0]);
  assert_true(fabs(cx[0] - 74.0) <= 1.0);
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
/* thin features of the outside move like those of the inside                */

/* The last inside pixel's column along row y, from x_from rightward (-1: none). */
static int last_inside(const float *phi, int w, int y, int x_from) {
  int last = -1;
  for (int x = x_from; x < w; ++x)
    if (phi[(size_t)y * w + x] <= 0.0f) last = x;
  return last;
}

/* The morph equation is unchanged under phi -> -phi, so a notch 3 px wide
 * cut into a disc that deepens from 4 to 20 px (a sulcus) should open as
 * fast as a bar 3 px wide on a disc lengthens from 4 to 20 px.  The
 * two-sided join was made for the bar (the union of the two insides); at
 * cells less than two cells outside one slice and deeper inside the other it
 * joins the outsides instead, and the notch keeps up with the bar. */
static void test_thin_outside(void **state) {
  (void)state;
  const double z[2] = {0.0, 8.0};
  /* notch: disc centre (40, 50), r 30 (right edge at x = 70), cut by the
   * strict inside of a rect (rows 49..51) from x = 67 or 51 outward */
  const slice_def notch[2] = {{2, {disc(40, 50, 30), rect(66, 48, 100, 52, 1)}},
                              {2, {disc(40, 50, 30), rect(50, 48, 100, 52, 1)}}};
  /* bar: disc centre (40, 50), r 20, rows 49..51 from x = 40 to 64 or 80 */
  const slice_def bar[2] = {{2, {disc(40, 50, 20), rect(40, 49, 64, 51, 0)}},
                            {2, {disc(40, 50, 20), rect(40, 49, 80, 51, 0)}}};
  lsm_stack_opts o;
  default_opts(&o);
  o.dz = 1.0;
  run rn, rb;
  assert_int_equal(run_stack(&rn, W, H, 0, notch, z, 2, &o), LSM_OK);
  assert_int_equal(run_stack(&rb, W, H, 0, bar, z, 2, &o), LSM_OK);
  for (size_t k = 1; k < 8; ++k) {
    const int depth = 70 - last_inside(rn.sink.s[k].phi, W, 50, 40);
    const int length = last_inside(rb.sink.s[k].phi, W, 50, 40) - 60;
    print_message("z %zu: notch depth %d px, bar length %d px (both 4 -> 20)\n", k, depth, length);
    if (k >= 5) assert_true(depth >= length);
  }
  sink_free(&rn.sink);
  sink_free(&rb.sink);
}

/* A pinhole: an oblique sulcus cuts each section as a hole of a pixel or two
 * that moves from slice to slice.  Here a 2x2 hole inside a disc moves 2 px
 * every 2 units of z (x = 38..39, 40..41, 42..43, 44..45 at z = 0, 2, 4, 6;
 * rows 50..51), so half-way between two slices (z = 1, 3, 5) the truth's
 * hole is the 2x2 cells at x = 39..40, 41..42, 43..44: cells where the two
 * slices tie (+1/2 outside one, -1/2 inside the other).  The morph of so
 * small a hole is numerical diffusion; the union of the two insides left 2
 * of the 4 cells at z = 1 and 5.  At a pinhole's cells the profile is the
 * monotone cubic of the signed distances, which follows the hole. */
/* The image border is not the object's boundary: a band across the whole
 * image, 11 rows thick and then 21, is the same in every column of every
 * output slice, its two border columns included (a margin of background
 * around the image made them lag: 11 -> 13 rows where the band was 17 rows
 * thick inside).  For ls and blend. */
static void test_border_band(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {rect(0, 45, W - 1, 55, 0)}}, {1, {rect(0, 40, W - 1, 60, 0)}}};
  const double z[2] = {0, 8};
  for (int method = 0; method < 2; ++method) {
    lsm_stack_opts o;
    default_opts(&o);
    o.method = method ? LSM_METHOD_BLEND : LSM_METHOD_LS;
    run r;
    assert_int_equal(run_stack(&r, W, H, 0, defs, z, 2, &o), LSM_OK);
    assert_int_equal(r.sink.n, 9);
    for (size_t k = 0; k < r.sink.n; ++k) {
      const float *phi = r.sink.s[k].phi;
      int rows = 0;
      for (int y = 0; y < H; ++y) {
        const float middle = phi[y * W + W / 2];
        rows += middle <= 0.0f;
        for (int x = 0; x < W; ++x)
          if (fabsf(phi[y * W + x] - middle) > 1e-5f)
            fail_msg("%s slice %zu: phi(%d, %d) = %g, %g in the middle column",
                     method ? "blend" : "ls", k, x, y, phi[y * W + x], middle);
      }
      print_message("%s z = %g: %d rows\n", method ? "blend" : "ls", r.sink.s[k].z, rows);
      assert_true(rows >= 11 && rows <= 21);
    }
    sink_free(&r.sink);
  }
}

static void test_pinhole(void **state) {
  (void)state;
  const double z[4] = {0.0, 2.0, 4.0, 6.0};
  slice_def defs[4]; /* holes cut by the strict insides of the rects */
  for (int k = 0; k < 4; ++k) {
    defs[k].n = 2;
    defs[k].s[0] = disc(C, C, 30);
    defs[k].s[1] = rect(37 + 2 * k, 49, 40 + 2 * k, 52, 1);
  }
  lsm_stack_opts o;
  default_opts(&o);
  o.dz = 1.0;
  for (int m = 0; m < 2; ++m) {
    o.method = m ? LSM_METHOD_PLS : LSM_METHOD_LS;
    run r;
    assert_int_equal(run_stack(&r, W, H, 0, defs, z, 4, &o), LSM_OK);
    assert_int_equal(r.sink.n, 7);
    for (int k = 1; k <= 5; k += 2) {
      const float *mid = r.sink.s[k].phi;
      const int x0 = 38 + k; /* the truth's hole: x0, x0 + 1; rows 50, 51 */
      size_t outside = 0, misplaced = 0;
      for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
          if ((i - C) * (i - C) + (j - C) * (j - C) <= 25.0 * 25.0 && mid[(size_t)j * W + i] > 0.0f) {
            ++outside;
            misplaced += !(i >= x0 && i <= x0 + 1 && j >= 50 && j <= 51);
          }
      print_message("pinhole (%s) z = %d: %zu outside cells, %zu of them off the truth's hole\n",
                    lsm_method_name(o.method), k, outside, misplaced);
      assert_int_equal(outside, 4);
      assert_int_equal(misplaced, 0);
    }
    sink_free(&r.sink);
  }
}

/* Two balls of radius 20 (centres (46, 63.5, 26) and (82, 63.5, 40)) cut
 * every 8th unit: their sections merge between z = 24 and z = 32 and split
 * again between 32 and 40.  The outside between them (a ridge of phi in the
 * morph) sank below zero unevenly and left holes of one or two pixels on
 * the neck (6 in all, at z = 27, 36 and 37); no section has a hole and
 * neither has the truth.  Every output slice must be free of holes. */
enum { BALLS_N = 8, BALLS_SIDE = 128 };

/* The sections of those two balls, every 8th unit from z = 0. */
static void merging_balls(slice_def defs[BALLS_N], double z[BALLS_N]) {
  for (int k = 0; k < BALLS_N; ++k) {
    z[k] = 8.0 * k;
    defs[k].n = 0;
    const double r1 = 400.0 - (z[k] - 26.0) * (z[k] - 26.0);
    const double r2 = 400.0 - (z[k] - 40.0) * (z[k] - 40.0);
    if (r1 > 0.0) defs[k].s[defs[k].n++] = disc(46.0, 63.5, sqrt(r1));
    if (r2 > 0.0) defs[k].s[defs[k].n++] = disc(82.0, 63.5, sqrt(r2));
  }
}

static void test_merge_no_pinholes(void **state) {
  (void)state;
  enum { N = BALLS_N, SIDE = BALLS_SIDE };
  slice_def defs[N];
  double z[N];
  merging_balls(defs, z);
  for (int m = 0; m < 2; ++m) {
    lsm_stack_opts o;
    default_opts(&o);
    o.interp = m ? LSM_INTERP_LINEAR : LSM_INTERP_CUBIC;
    run r;
    assert_int_equal(run_stack(&r, SIDE, SIDE, 0, defs, z, N, &o), LSM_OK);
    assert_int_equal(r.sink.n, 57);
    int total = 0;
    size_t beyond = 0;
    for (size_t k = 0; k < r.sink.n; ++k) {
      const int h = holes(r.sink.s[k].phi, SIDE, SIDE);
      if (h) print_message("merge (%s): %d holes at z = %g\n", lsm_interp_name(o.interp), h, r.sink.s[k].z);
      total += h;
      /* and the filled cells, as every other, within the range of the
       * slices around them (gaps between two non-empty slices) */
      const size_t below = k - k % 8, above = below + 8;
      if (k % 8 == 0 || defs[below / 8].n == 0 || defs[above / 8].n == 0) continue;
      const float *pa = r.sink.s[below].phi, *pb = r.sink.s[above].phi, *p = r.sink.s[k].phi;
      for (int c = 0; c < SIDE * SIDE; ++c)
        beyond += p[c] < fminf(pa[c], pb[c]) - 1e-4f || p[c] > fmaxf(pa[c], pb[c]) + 1e-4f;
    }
    assert_int_equal(total, 0);
    assert_int_equal(beyond, 0);
    sink_free(&r.sink);
  }
}

/* Inside cells with x >= x0 (the right-hand piece below). */
static size_t area_right_of(const float *phi, int w, int h, int x0) {
  size_t n = 0;
  for (int j = 0; j < h; ++j)
    for (int i = x0; i < w; ++i) n += phi[(size_t)j * w + i] <= 0.0f;
  return n;
}

/* A small piece of A (r 4 at x = 86) that B (z = 20) does not continue, next
 * to a body (r 15, then 10, at the centre) that goes on.  Where the slice
 * before A (z = 0) joins it to that body (a bar from the body to it), it is a
 * branch splitting off the body: it recedes toward the body's section on B
 * and is gone by z = 13.  Where it is its own piece at z = 0 too, it is an
 * object ending in the gap (the halfway rule): still there at z = 13. */
static void test_branch_recedes(void **state) {
  (void)state;
  const double z[3] = {0.0, 10.0, 20.0};
  const slice_def a = {2, {disc(C, C, 15), disc(86, C, 4)}}, b = {1, {disc(C, C, 10)}};
  const slice_def joined = {3, {disc(C, C, 20), rect(60, 46, 92, 54, 0), disc(86, C, 6)}};
  const slice_def apart = {2, {disc(C, C, 20), disc(86, C, 5)}};
  lsm_stack_opts o;
  default_opts(&o);
  o.dz = 1.0;
  for (int branch = 0; branch < 2; ++branch) {
    const slice_def defs[3] = {branch ? joined : apart, a, b};
    run r;
    assert_int_equal(run_stack(&r, W, H, 0, defs, z, 3, &o), LSM_OK);
    assert_int_equal(r.sink.n, 21);
    size_t piece[21];
    for (int k = 0; k <= 20; ++k) piece[k] = area_right_of(r.sink.s[k].phi, W, H, 78);
    print_message("%s: piece areas z = 10..20: %zu %zu %zu %zu %zu %zu %zu %zu %zu %zu %zu\n",
                  branch ? "branch" : "own piece", piece[10], piece[11], piece[12], piece[13], piece[14],
                  piece[15], piece[16], piece[17], piece[18], piece[19], piece[20]);
    assert_true(piece[10] > 40);
    if (branch) assert_int_equal(piece[13], 0);
    else assert_true(piece[13] > 0);
    for (int k = 18; k <= 20; ++k) assert_int_equal(piece[k], 0);
    sink_free(&r.sink);
  }
}

/* A disc next to an empty slice, with no slice beyond it (a lone section).
 * Linear profile: the object closes by mid-gap.  Vanishing (disc at z = 0,
 * empty at z = 10): areas strictly decrease while non-empty, the last
 * non-empty slice is at z <= 5, and the disc is still there just after the
 * input (z = 1).  Cubic profile: nothing tells how a lone section ends, so it
 * is a flat end: whole up to mid-gap, then a cone's tip to the empty slice,
 * A_F (2 (1 - z / 10))^2, non-empty up to z = 9.  Appearing
 * (the reverse): the mirror image. */
static void test_vanish_appear(void **state) {
  (void)state;
  const slice_def full = {1, {disc(C, C, 15)}}, none = {0, {{0}}};
  const double z[2] = {0, 10};
  for (int variant = 0; variant < 4; ++variant) {
    lsm_stack_opts o;
    default_opts(&o);
    o.method = variant & 1 ? LSM_METHOD_BLEND : LSM_METHOD_LS;
    if (variant & 2) o.interp = LSM_INTERP_LINEAR;
    const slice_def vanish[2] = {full, none}, appear[2] = {none, full};
    run r;
    size_t a[11];
    assert_int_equal(run_stack(&r, W, H, 0, vanish, z, 2, &o), LSM_OK);
    assert_int_equal(r.sink.n, 11);
    check_exact_input(&r, 0, 0);
    int last = -1;
    for (int k = 0; k <= 10; ++k) {
      a[k] = area(r.sink.s[k].phi, W, H);
      if (a[k]) last = k;
    }
    print_message("vanish (%s, %s): areas %zu %zu %zu %zu %zu %zu ...\n",
                  lsm_method_name(o.method), lsm_interp_name(o.interp), a[0], a[1], a[2], a[3],
                  a[4], a[5]);
    const int cubic = o.interp == LSM_INTERP_CUBIC;
    if (cubic) {
      assert_int_equal(last, 9);
      for (int k = 1; k <= 5; ++k) assert_int_equal(a[k], a[0]);
      for (int k = 6; k <= 9; ++k) {
        const double tip = (double)a[0] * pow(2.0 * (1.0 - k / 10.0), 2.0);
        assert_true(a[k] < a[k - 1] && (double)a[k] <= tip && (double)a[k] >= 0.85 * tip - 4.0);
      }
    } else {
      assert_true(last >= 1 && last <= 5);
      for (int k = 1; k <= last; ++k) assert_true(a[k] < a[k - 1]);
    }
    for (int k = last + 1; k <= 10; ++k) assert_int_equal(a[k], 0);
    /* The empty input slice: everything outside. */
    assert_int_equal(r.sink.s[10].input_index, 1);
    for (int p = 0; p < W * H; ++p) assert_true(r.sink.s[10].phi[p] > 0.0f);
    /* What remains stays one disc around the centre. */
    for (int k = 1; k <= last; ++k) assert_int_equal(fg_components(r.sink.s[k].phi, W, H), 1);
    sink_free(&r.sink);

    assert_int_equal(run_stack(&r, W, H, 0, appear, z, 2, &o), LSM_OK);
    assert_int_equal(r.sink.n, 11);
    check_exact_input(&r, 10, 1);
    int first = 11;
    for (int k = 10; k >= 0; --k) {
      a[k] = area(r.sink.s[k].phi, W, H);
      if (a[k]) first = k;
    }
    print_message("appear (%s, %s): first non-empty z = %d\n", lsm_method_name(o.method),
                  lsm_interp_name(o.interp), first);
    if (cubic) {
      assert_int_equal(first, 1);
      for (int k = 1; k <= 4; ++k) assert_true(a[k] > 0 && a[k] < a[k + 1]);
      for (int k = 5; k <= 10; ++k) assert_int_equal(a[k], a[10]);
    } else {
      assert_true(first >= 5 && first <= 9);
      for (int k = first + 1; k <= 10; ++k) assert_true(a[k] > a[k - 1]);
    }
    for (int k = 0; k < first; ++k) assert_int_equal(a[k], 0);
    sink_free(&r.sink);
  }
}

/* ------------------------------------------------------------------------ */
/* alignment                                                                 */

/* Disc r = 10 at (25, 50) at z = 0 and the same disc at (75, 50) at z = 7.
 * align hull: both are moved to the centre (identical there: no motion), and
 * slice z is moved back by the linear interpolation of the two shifts, so it is
 * one disc centred at (25 + 50 z / 7, 50) (fractional shifts: bilinear).
 * align none: the discs do not overlap; the morph alone would erode the left
 * disc in place and grow the right one late in the gap (the object absent in
 * the middle, as the blend's zero set of (1 - s) phi_A + s phi_B, whose
 * minimum is 50 s - 10 at the left centre, is empty for 0.2 < s < 0.8), but
 * the two discs are a moving part (lsm_parts) and travel (observed: one
 * component per slice).  test_parts_apart checks that rule; here only the
 * exact endpoints and a clean run are asserted. */
static void test_align(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {disc(25, C, 10)}}, {1, {disc(75, C, 10)}}};
  const double z[2] = {0, 7};
  lsm_stack_opts o;
  run r;
  /* hull, and auto (which must choose hull here: moving A onto B's centroid
   * takes the overlap from 0 to the whole disc). */
  for (int mode = 0; mode < 2; ++mode) {
    default_opts(&o);
    o.motion = LSM_MOTION_NONE; /* --align auto acts with --motion none */
    o.align = mode ? LSM_ALIGN_AUTO : LSM_ALIGN_HULL;
    assert_int_equal(run_stack(&r, W, H, 0, defs, z, 2, &o), LSM_OK);
    assert_int_equal(r.sink.n, 8);
    check_exact_input(&r, 0, 0);
    check_exact_input(&r, 7, 1);
    const size_t a0 = area(r.sink.s[0].phi, W, H);
    double worst = 0;
    for (size_t k = 1; k < 7; ++k) {
      double cx[8], cy[8];
      const float *phi = r.sink.s[k].phi;
      assert_int_equal(components(phi, W, H, 1, 1, 0, cx, cy), 1);
      const double ex = 25.0 + 50.0 * k / 7.0, ey = C;
      const double d = hypot(cx[0] - ex, cy[0] - ey);
      worst = fmax(worst, d);
      if (d > 1.5)
        fail_msg("z = %zu: centroid (%.2f, %.2f), expected (%.2f, %.2f)", k, cx[0], cy[0], ex,
                 ey);
      /* Same disc: the area stays within a perimeter's worth of pixels. */
      const double ak = (double)area(phi, W, H);
      assert_true(fabs(ak - (double)a0) <= 2.0 * PI * 10.0);
    }
    print_message("align %s: worst centroid offset %.3f px\n", lsm_align_name(o.align), worst);
    sink_free(&r.sink);
  }

  o.align = LSM_ALIGN_NONE;
  assert_int_equal(run_stack(&r, W, H, 0, defs, z, 2, &o), LSM_OK);
  assert_int_equal(r.sink.n, 8);
  check_exact_input(&r, 0, 0);
  check_exact_input(&r, 7, 1);
  char text[64] = "";
  for (size_t k = 0; k < 8; ++k) {
    double cx[8], cy[8];
    const int n = components(r.sink.s[k].phi, W, H, 1, 1, 0, cx, cy);
    sprintf(text + strlen(text), " %d", n);
    for (int q = 0; q < n && q < 8; ++q) assert_true(isfinite(cx[q]) && isfinite(cy[q]));
  }
  print_message("align none: components per slice%s\n", text);
  sink_free(&r.sink);
}

/* Runs a two-slice stack (z = 0 and z_b, one output slice per unit) with
 * --align auto, none and hull, and counts the cells of the intermediate slices
 * where auto, and hull, differ from none. */
static void align_modes_differ(const slice_def defs[2], double z_b, size_t *differ_auto,
                               size_t *differ_hull) {
  const double z[2] = {0, z_b};
  const size_t n = (size_t)z_b + 1;
  lsm_stack_opts o;
  run by_mode[3];
  const lsm_align modes[3] = {LSM_ALIGN_AUTO, LSM_ALIGN_NONE, LSM_ALIGN_HULL};
  for (int m = 0; m < 3; ++m) {
    default_opts(&o);
    o.align = modes[m];
    assert_int_equal(run_stack(&by_mode[m], W, H, 0, defs, z, 2, &o), LSM_OK);
    assert_int_equal(by_mode[m].sink.n, n);
  }
  *differ_auto = *differ_hull = 0;
  for (size_t k = 1; k + 1 < n; ++k)
    for (int p = 0; p < W * H; ++p) {
      *differ_auto += by_mode[0].sink.s[k].phi[p] != by_mode[1].sink.s[k].phi[p];
      *differ_hull += by_mode[2].sink.s[k].phi[p] != by_mode[1].sink.s[k].phi[p];
    }
  for (int m = 0; m < 3; ++m) sink_free(&by_mode[m].sink);
}

/* A pair auto must leave unaligned: auto gives exactly --align none's slices,
 * while hull gives others (so the case is one where alignment matters). */
static void assert_auto_leaves_in_place(const char *what, const slice_def defs[2], double z_b) {
  size_t differ_auto, differ_hull;
  align_modes_differ(defs, z_b, &differ_auto, &differ_hull);
  print_message("%s: cells differing from none: auto %zu, hull %zu\n", what, differ_auto,
                differ_hull);
  assert_int_equal(differ_auto, 0);
  assert_true(differ_hull > 0);
}

/* --align auto when a part grows out of a shape that stays: a disc (r = 12)
 * becomes a bar (9 px wide) reaching from it to the right edge.  The hull
 * centroid moves ~35 px right and moving the disc by that much would overlap
 * the bar more than in place (so a centroid-only rule would align), but the
 * translation of largest overlap is only ~8 px (the disc just inside the bar):
 * nothing moved, and auto must morph in place, exactly as --align none. */
static void test_align_auto_growth(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {disc(20, C, 12)}}, {2, {disc(20, C, 4), rect(16, 46, 95, 54, 0)}}};
  assert_auto_leaves_in_place("growth", defs, 6);
}

/* --align auto when a small section meets a large, different one: a disc
 * (r = 6) at x = 30 becomes a disc (r = 22) at x = 72 with a bar (5 px wide)
 * reaching left to x = 28, which covers about half of the small disc in place
 * (a narrow part of an organ or a mesh next to its wide body).  The centroid
 * moves ~38 px; the small disc fits whole only inside the large one, about 20
 * px away, nearer the centroid difference than no shift, so the centroid and
 * registration tests alone would align.  But at that shift the two are not
 * alike (IoU ~0.07: one is a small part of the other), so nothing moved and
 * auto must morph in place, exactly as --align none. */
static void test_align_auto_inside(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {disc(30, C, 6)}}, {2, {disc(72, C, 22), rect(28, 48, 72, 52, 0)}}};
  assert_auto_leaves_in_place("inside", defs, 8);
}

/* --align auto when a small section lies apart from a large, different one:
 * a disc (r = 5) at (18, 18) and, on the next slice, a disc (r = 22) at
 * (66, 66), touching nothing in place (one part of an object ends while
 * another begins).  The centroid moves (48, 48) px and the small disc fits
 * whole inside the large one around that shift, so the centroid and
 * registration tests align, and the two barely touch in place.  But at the
 * best shift they are not alike (IoU ~0.05 < 1/4): nothing moved, and auto
 * must morph in place, exactly as --align none. */
static void test_align_auto_apart_unlike(void **state) {
  (void)state;
  const slice_def defs[2] = {{1, {disc(18, 18, 5)}}, {1, {disc(66, 66, 22)}}};
  assert_auto_leaves_in_place("apart, unlike", defs, 8);
}

/* Parts moving apart (lsm_parts): two discs r = 5 at x = 40 and 60 (z = 0)
 * are at x = 20 and 80 at z = 8.  Neither overlaps itself across the gap and
 * the slice's centroid stays, so alignment cannot help; each disc must
 * travel its own straight line (centroid within 1 px of 40 - 2.5 z and
 * 60 + 2.5 z) and keep its area, for ls and pls, cubic and linear.  Blend
 * stays the classic baseline. */
static void test_parts_apart(void **state) {
  (void)state;
  const slice_def defs[2] = {{2, {disc(40, C, 5), disc(60, C, 5)}},
                             {2, {disc(20, C, 5), disc(80, C, 5)}}};
  const double z[2] = {0, 8};
  for (int variant = 0; variant < 3; ++variant) {
    lsm_stack_opts o;
    default_opts(&o);
    o.motion = LSM_MOTION_NONE; /* the moving-parts rule acts with --motion none */
    if (variant == 1) o.interp = LSM_INTERP_LINEAR;
    if (variant == 2) o.method = LSM_METHOD_PLS;
    run r;
    assert_int_equal(run_stack(&r, W, H, 0, defs, z, 2, &o), LSM_OK);
    assert_int_equal(r.sink.n, 9);
    check_exact_input(&r, 0, 0);
    check_exact_input(&r, 8, 1);
    const double a0 = (double)area(r.sink.s[0].phi, W, H);
    double worst = 0.0;
    for (size_t k = 1; k < 8; ++k) {
      double cx[8], cy[8];
      const float *phi = r.sink.s[k].phi;
      const int n = components(phi, W, H, 1, 1, 0, cx, cy);
      if (n != 2) fail_msg("z = %zu: %d components (want 2)", k, n);
      const double left = cx[0] < cx[1] ? cx[0] : cx[1], right = cx[0] < cx[1] ? cx[1] : cx[0];
      const double el = 40.0 - 2.5 * (double)k, er = 60.0 + 2.5 * (double)k;
      worst = fmax(worst, fmax(fabs(left - el), fabs(right - er)));
      worst = fmax(worst, fmax(fabs(cy[0] - C), fabs(cy[1] - C)));
      assert_true(fabs((double)area(phi, W, H) - a0) <= 2.0 * 2.0 * PI * 5.0);
    }
    print_message("parts apart (%s, %s): worst centroid offset %.3f px\n",
                  lsm_method_name(o.method), lsm_interp_name(o.interp), worst);
    assert_true(worst <= 1.0);
    sink_free(&r.sink);
  }
}

/* Rules switched off (lsm_rules.h) fall back to what the table says: moving
 * parts morph in place, the morph's pinholes stay, the canvas margin is
 * background, a moved pair is not aligned.  And with every rule off at once
 * a stack with ends, parts and a merge still runs. */
static void switch_off(lsm_stack_opts *o, const char *names) {
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_rules_switch_off(&o->rules, names, &err), LSM_OK);
}

/* The first gap's statistics of a two-slice stack, with the rule `off`
 * switched off (NULL: the defaults). */
static lsm_pair_stats first_gap(const slice_def defs[2], const char *off) {
  const double z2[2] = {0, 8};
  lsm_stack_opts o;
  default_opts(&o);
  o.motion = LSM_MOTION_NONE; /* the rules below act in place */
  if (off) switch_off(&o, off);
  run r;
  assert_int_equal(run_stack(&r, W, H, 0, defs, z2, 2, &o), LSM_OK);
  sink_free(&r.sink);
  return r.stats[0];
}

static void test_rules_off(void **state) {
  (void)state;
  const double z2[2] = {0, 8};
  lsm_stack_opts o;
  run r;
  /* moving-parts: two discs moving apart */
  const slice_def apart[2] = {{2, {disc(40, C, 5), disc(60, C, 5)}},
                              {2, {disc(20, C, 5), disc(80, C, 5)}}};
  assert_int_equal(first_gap(apart, NULL).moving_parts, 2);
  assert_int_equal(first_gap(apart, "moving-parts").moving_parts, 0);
  /* align-auto: a disc that moved by more than its width */
  const slice_def moved[2] = {{1, {disc(30, C, 10)}}, {1, {disc(70, C, 10)}}};
  assert_int_equal(first_gap(moved, NULL).aligned, 1);
  assert_int_equal(first_gap(moved, "align-auto").aligned, 0);
  /* border-extension: a band across the image lags at its border columns */
  const slice_def band[2] = {{1, {rect(0, 45, W - 1, 55, 0)}}, {1, {rect(0, 40, W - 1, 60, 0)}}};
  default_opts(&o);
  switch_off(&o, "border-extension");
  assert_int_equal(run_stack(&r, W, H, 0, band, z2, 2, &o), LSM_OK);
  int lagging = 0;
  for (int y = 0; y < H; ++y) {
    const float *phi = r.sink.s[4].phi;
    lagging += (phi[y * W] <= 0.0f) != (phi[y * W + W / 2] <= 0.0f);
  }
  assert_true(lagging > 0);
  sink_free(&r.sink);
  /* pinhole-fill: two balls merging (test_merge_no_pinholes) keep holes */
  enum { N = BALLS_N, SIDE = BALLS_SIDE };
  slice_def balls[N];
  double z[N];
  merging_balls(balls, z);
  default_opts(&o);
  switch_off(&o, "pinhole-fill");
  assert_int_equal(run_stack(&r, SIDE, SIDE, 0, balls, z, N, &o), LSM_OK);
  int total = 0;
  for (size_t k = 0; k < r.sink.n; ++k) total += holes(r.sink.s[k].phi, SIDE, SIDE);
  print_message("rules off: pinhole-fill off leaves %d holes\n", total);
  assert_true(total > 0);
  sink_free(&r.sink);
  /* every rule off, for each method */
  for (int m = 0; m < 3; ++m) {
    default_opts(&o);
    o.method = m == 0 ? LSM_METHOD_LS : m == 1 ? LSM_METHOD_PLS : LSM_METHOD_BLEND;
    o.rules.off = ~(uint64_t)0;
    assert_int_equal(run_stack(&r, SIDE, SIDE, 0, balls, z, N, &o), LSM_OK);
    assert_int_equal(r.sink.n, 57);
    sink_free(&r.sink);
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
      cmocka_unit_test(test_merge_split),
      cmocka_unit_test(test_thin_outside),
      cmocka_unit_test(test_pinhole),
      cmocka_unit_test(test_merge_no_pinholes),
      cmocka_unit_test(test_border_band),
      cmocka_unit_test(test_scale_invariance),
      cmocka_unit_test(test_pixel_not_square),
      cmocka_unit_test(test_end_moves_on),
      cmocka_unit_test(test_branch_recedes),
      cmocka_unit_test(test_end_parts),
      cmocka_unit_test(test_vanish_appear),
      cmocka_unit_test(test_align),
      cmocka_unit_test(test_align_auto_growth),
      cmocka_unit_test(test_align_auto_inside),
      cmocka_unit_test(test_align_auto_apart_unlike),
      cmocka_unit_test(test_parts_apart),
      cmocka_unit_test(test_rules_off),
      cmocka_unit_test(test_outline_ring),
      cmocka_unit_test(test_outline_vase),
      cmocka_unit_test(test_per_iteration),
      cmocka_unit_test(test_stop_past_max_iter),
      cmocka_unit_test(test_errors),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
