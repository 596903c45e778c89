/* The z-profile tests' bench, shared by test_interp.c and test_interp_ends.c:
 * an in-memory source of discs (a ball's cross-sections), a sink that records
 * every output slice, stack runs over them, the slices' signed distances, and
 * the inside cells of an output slice. */
#ifndef LSM_TEST_INTERP_H
#define LSM_TEST_INTERP_H

#include "tests/lsm_test.h"

#include "solver/sdf/lsm_sdf.h"
#include "solver/recon/lsm_stack.h"

/* ---- in-memory source: discs of given radii (a ball's cross-sections) ------------ */

typedef struct disc_source {
  int size;
  const double *radius; /* per slice; <= 0 means empty */
  const double *cx;     /* per slice centre x (NULL: image centre) */
} disc_source;

static inline lsm_status disc_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
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

static inline lsm_status record_emit(void *ctx, const float *phi, int w, int h, double z, long input,
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

static inline void record_free(record *r) {
  free(r->phi);
  free(r->z);
  free(r->input);
  memset(r, 0, sizeof *r);
}

/* Runs the stack over n slices of size x size read by load(ctx, k). */
typedef lsm_status (*load_fn)(void *ctx, size_t index, lsm_mask *out, lsm_err *err);
static inline void run_source(load_fn load, void *ctx, int size, const double *z, size_t n,
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

static inline void run_stack(disc_source *src, const double *z, size_t n, lsm_stack_opts *o, record *out) {
  run_source(disc_load, src, src->size, z, n, o, out);
}

/* Slice k's signed distance, as the stack computes it, from a source's load. */
static inline void phi_of(load_fn load, void *ctx, int size, size_t k, float *out) {
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

static inline void input_phi(disc_source *src, size_t k, float *out) {
  phi_of(disc_load, src, src->size, k, out);
}

/* Cells inside (phi <= 0) of output slice q, and their centroid x. */
static inline size_t slice_inside(const record *rec, size_t q, double *centroid_x) {
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
static inline size_t slice_at(const record *rec, double z) {
  for (size_t q = 0; q < rec->count; ++q)
    if (fabs(rec->z[q] - z) < 1e-9) return q;
  fail_msg("no output slice at z = %g", z);
  return 0;
}

#endif
