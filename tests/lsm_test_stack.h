/* The stack driver's test bench, shared by test_stack.c, test_stack_topology.c
 * and test_stack_align.c: synthetic slices (discs, rectangles, holes, as
 * masks or outlines) from an in-memory source, a sink that records every
 * output slice, runs of lsm_stack_run, and measurements on the output slices
 * (area, components, holes, exact input slices). */
#ifndef LSM_TEST_STACK_H
#define LSM_TEST_STACK_H

#include "tests/lsm_test.h"

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

static inline shape disc(double cx, double cy, double r) {
  shape s = {SH_DISC, 0, cx, cy, r, 0, 0, 0, 0};
  return s;
}
static inline shape disc_hole(double cx, double cy, double r) {
  shape s = {SH_DISC, 1, cx, cy, r, 0, 0, 0, 0};
  return s;
}
static inline shape rect(int x0, int y0, int x1, int y1, int hole) {
  shape s = {SH_RECT, hole, 0, 0, 0, x0, y0, x1, y1};
  return s;
}

static inline int in_shape(const shape *s, int x, int y) {
  if (s->kind == SH_DISC) return (x - s->cx) * (x - s->cx) + (y - s->cy) * (y - s->cy) <= s->r * s->r;
  return x >= s->x0 && x <= s->x1 && y >= s->y0 && y <= s->y1;
}

/* Contour pixel of a primitive: inside it with a 4-neighbour outside it
 * (the rule of examples/gen_synthetic.c). */
static inline int on_contour(const shape *s, int x, int y) {
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
static inline void paint(const source_ctx *c, const slice_def *d, lsm_mask *m) {
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

static inline lsm_status src_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
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
static inline float *input_phi(const source_ctx *c, size_t index) {
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

static inline lsm_status sink_emit(void *ctx, const float *phi, int width, int height, double z,
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

static inline void sink_free(sink_ctx *c) {
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
static inline lsm_status run_stack_rows(run *r, int w, int h, int outline, int y_step,
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

static inline lsm_status run_stack(run *r, int w, int h, int outline, const slice_def *defs,
                            const double *z, size_t count, const lsm_stack_opts *opts) {
  return run_stack_rows(r, w, h, outline, 1, defs, z, count, opts);
}

/* ------------------------------------------------------------------------ */
/* measurements on an output slice (inside: phi <= 0, as the CLI writes)     */

static inline size_t area(const float *phi, int w, int h) {
  size_t n = 0;
  for (int k = 0; k < w * h; ++k) n += phi[k] <= 0.0f;
  return n;
}

/* Connected components of the pixels with (phi <= 0) == fg, 8- or
 * 4-connected.  With skip_border, components touching the image border are
 * not counted.  Per component, centroid sums go to cx/cy if given (up to 8). */
static inline int components(const float *phi, int w, int h, int fg, int conn8, int skip_border,
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

static inline int fg_components(const float *phi, int w, int h) {
  return components(phi, w, h, 1, 1, 0, NULL, NULL);
}

/* Holes: 4-connected background components that do not touch the border. */
static inline int holes(const float *phi, int w, int h) { return components(phi, w, h, 0, 0, 1, NULL, NULL); }

static inline void check_exact_input(const run *r, size_t out_index, size_t input_index) {
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

static inline void default_opts(lsm_stack_opts *o) {
  lsm_stack_opts_default(o);
  o->morph.threads = 2;
}

/* The image of most tests: W x H pixels, centre C. */
#define W 101
#define H 101
#define C 50.0 /* image centre */

/* Component counts of the intermediate slices, printed as a string. */
static inline void counts(const run *r, int *c, char *text) {
  text[0] = '\0';
  for (size_t k = 0; k < r->sink.n; ++k) {
    c[k] = fg_components(r->sink.s[k].phi, W, H);
    sprintf(text + strlen(text), "%d", c[k]);
  }
}

/* Two balls of radius 20 (centres (46, 63.5, 26) and (82, 63.5, 40)) whose
 * sections merge and split again (test_merge_no_pinholes, test_rules_off). */
enum { BALLS_N = 8, BALLS_SIDE = 128 };

/* The sections of those two balls, every 8th unit from z = 0. */
static inline void merging_balls(slice_def defs[BALLS_N], double z[BALLS_N]) {
  for (int k = 0; k < BALLS_N; ++k) {
    z[k] = 8.0 * k;
    defs[k].n = 0;
    const double r1 = 400.0 - (z[k] - 26.0) * (z[k] - 26.0);
    const double r2 = 400.0 - (z[k] - 40.0) * (z[k] - 40.0);
    if (r1 > 0.0) defs[k].s[defs[k].n++] = disc(46.0, 63.5, sqrt(r1));
    if (r2 > 0.0) defs[k].s[defs[k].n++] = disc(82.0, 63.5, sqrt(r2));
  }
}

#endif
