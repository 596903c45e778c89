/* The correspondence field's registration on the OpenCL backend against the C path.
 *
 * lsm_motion_register runs twice on the same pair of signed distances: on the host (the
 * reference) and with its levels on the device the backend gives (lsm_backend_motion;
 * kernels/motion.cl over kernels/lsm_motion_cell.h).  For a translated disc, a turning and
 * drifting ellipse, unequal pixels on a canvas that is no multiple of the node spacing, a part
 * present on one side only, and an empty slice:
 *   every level ran on the device (a counting shim around its run_level),
 *   the iterations are the same (the stop test's sums are taken on the host in double, rows
 *   in order, on both paths: no work-group shape can change them),
 *   max |w_opencl - w_c| <= 1e-4 max(nx, ny) node units (the bound test_opencl.c puts on
 *   phi: room for a device that rounds differently; PoCL gives 0),
 *   the largest displacements agree to 1e-5 relative.
 * A kernel that diverged from the C path's per-node code (a sign, a tap, a clamp) moves the
 * field by far more than that bound.  Without an OpenCL platform or device the tests print
 * why and are skipped. */
#include "tests/lsm_test.h"

#include <math.h>

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/motion/lsm_motion.h"
#include "solver/pde/lsm_backend.h"

/* Under SANITIZE=1: the OpenCL loader, PoCL and its LLVM keep allocations until exit. */
const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void) {
  return "leak:libpocl.so\nleak:libLLVM\nleak:libOpenCL.so\nleak:libclang\n";
}

typedef struct fixture {
  lsm_backend *cl; /* NULL when no device could be opened */
  lsm_err why;
  lsm_motion_device device; /* the backend's, as lsm_backend_motion gives it */
  int levels_run;           /* levels the shim passed to the device */
} fixture;

static fixture fx; /* the group's state: set up once, read by the tests */

static lsm_status counting_level(void *ctx, const lsm_motion_level *lv, int *taken,
                                 lsm_err *err) {
  fx.levels_run++;
  return fx.device.run_level(ctx, lv, taken, err);
}

static int group_setup(void **state) {
  (void)state;
  memset(&fx, 0, sizeof fx);
  lsm_err_clear(&fx.why);
  const lsm_status st = lsm_backend_open("opencl", -1, 1, &fx.cl, &fx.why);
  if (st == LSM_ERR_UNSUPPORTED) return 0; /* no platform or no device: skip */
  if (st != LSM_OK) {
    print_error("opencl: %s\n", fx.why.msg); /* a device that cannot build the program fails */
    return -1;
  }
  if (!lsm_backend_motion(fx.cl, &fx.device) || !fx.device.run_level) {
    print_error("opencl: the backend has no motion op\n");
    return -1;
  }
  return 0;
}

static int group_teardown(void **state) {
  (void)state;
  lsm_backend_close(&fx.cl);
  return 0;
}

/* An ellipse (half axes r along angle t, q across; q 0: a disc), as a signed distance of
 * the pixel centres' inside test (distance to the outline, negative inside; exact enough
 * for a registration's input and the same on both paths). */
typedef struct shape {
  double cx, cy, r, q, t;
} shape;

static double ellipse_level(const shape *s, double x, double y) {
  const double q = s->q > 0.0 ? s->q : s->r, c = cos(s->t), n = sin(s->t);
  const double u = x - s->cx, v = y - s->cy, along = c * u + n * v, across = -n * u + c * v;
  /* a level function with |grad| about 1 near the outline */
  return (sqrt(along * along / (s->r * s->r) + across * across / (q * q)) - 1.0) *
         (s->r < q ? s->r : q);
}

/* phi = min over the shapes (their union); no shapes: +far everywhere (an empty slice). */
static lsm_grid *union_phi(int nx, int ny, float dx, float dy, const shape *s, int count) {
  lsm_err err;
  lsm_err_clear(&err);
  lsm_grid *g = NULL;
  assert_int_equal(lsm_grid_create(nx, ny, dx, dy, &g, &err), LSM_OK);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      double v = 1e3;
      for (int k = 0; k < count; ++k) {
        const double e = ellipse_level(&s[k], i, j);
        if (e < v) v = e;
      }
      LSM_AT(g, i, j) = (float)(v * (dx < dy ? dx : dy));
    }
  lsm_grid_fill_ghosts(g);
  return g;
}

typedef struct motion_case {
  int nx, ny;
  float dx, dy;
  shape a[2], b[2];
  int na, nb;
} motion_case;

static const motion_case cases[] = {
    /* a disc moved by (10, 4) */
    {96, 96, 1.0f, 1.0f, {{40, 44, 10, 0, 0}}, {{50, 48, 10, 0, 0}}, 1, 1},
    /* a thin ellipse turning 30 degrees while it drifts */
    {112, 96, 1.0f, 1.0f, {{50, 48, 22, 5, 0.2}}, {{56, 50, 22, 5, 0.72}}, 1, 1},
    /* unequal pixels, a canvas no multiple of 8 nodes */
    {101, 77, 0.5f, 0.75f, {{45, 38, 12, 7, 0.0}}, {{55, 35, 12, 7, 0.3}}, 1, 1},
    /* a part on one side only (a second disc appears in B) */
    {96, 80, 1.0f, 1.0f, {{30, 40, 9, 0, 0}}, {{36, 42, 9, 0, 0}, {72, 30, 6, 0, 0}}, 1, 2},
    /* B empty (no boundary): only A's band informs the field */
    {64, 64, 1.0f, 1.0f, {{32, 32, 8, 0, 0}}, {{0, 0, 1, 0, 0}}, 1, 0},
};

static void test_field_matches_c(void **state) {
  const motion_case *mc = *state;
  if (!fx.cl) {
    print_message("opencl: skipped: %s\n", fx.why.msg[0] ? fx.why.msg : "no OpenCL device");
    skip();
  }
  lsm_grid *a = union_phi(mc->nx, mc->ny, mc->dx, mc->dy, mc->a, mc->na);
  lsm_grid *b = union_phi(mc->nx, mc->ny, mc->dx, mc->dy, mc->b, mc->nb);
  lsm_motion_params p;
  lsm_motion_params_default(&p);
  lsm_err err;
  lsm_err_clear(&err);
  lsm_motion_field *ref = NULL, *got = NULL;
  assert_int_equal(lsm_motion_register(a, b, &p, 2, &ref, &err), LSM_OK);
  p.device.ctx = fx.device.ctx;
  p.device.run_level = counting_level;
  fx.levels_run = 0;
  const lsm_status st = lsm_motion_register(a, b, &p, 2, &got, &err);
  if (st != LSM_OK) fail_msg("%s", err.msg);
  assert_int_equal(fx.levels_run, p.levels);
  assert_int_equal(got->nx, ref->nx);
  assert_int_equal(got->ny, ref->ny);
  assert_int_equal(got->iterations, ref->iterations);
  double most = 0.0, size = 0.0;
  for (size_t k = 0; k < (size_t)ref->nx * (size_t)ref->ny; ++k) {
    most = fmax(most, fabs((double)got->vx[k] - ref->vx[k]));
    most = fmax(most, fabs((double)got->vy[k] - ref->vy[k]));
    size = fmax(size, hypot(ref->vx[k], ref->vy[k]));
  }
  const double bound = 1e-4 * (ref->nx > ref->ny ? ref->nx : ref->ny);
  print_message("opencl motion %dx%d: %d iterations, max |w| %.3g, max |w_cl - w_c| = %.3g "
                "(bound %.3g), max displacement %.6g px (C %.6g)\n",
                mc->nx, mc->ny, ref->iterations, size, most, bound, got->max_displacement,
                ref->max_displacement);
  assert_true(most <= bound);
  const double rel = fabs(got->max_displacement - ref->max_displacement) /
                     fmax(1e-12, fabs(ref->max_displacement));
  assert_true(ref->max_displacement == 0.0 ? got->max_displacement == 0.0 : rel <= 1e-5);
  if (mc->nb > 0) assert_true(ref->max_displacement > 1.0); /* the case moves something */
  lsm_motion_field_destroy(&ref);
  lsm_motion_field_destroy(&got);
  lsm_grid_destroy(&a);
  lsm_grid_destroy(&b);
}

#define CASE(k, name) {name, test_field_matches_c, NULL, NULL, (void *)&cases[k]}

int main(void) {
  const struct CMUnitTest tests[] = {
      CASE(0, "field: disc moved by (10, 4)"),
      CASE(1, "field: ellipse turning 30 degrees"),
      CASE(2, "field: 101x77, dx 0.5 dy 0.75"),
      CASE(3, "field: a part on one side only"),
      CASE(4, "field: an empty slice"),
  };
  return cmocka_run_group_tests_name("test_opencl_motion", tests, group_setup, group_teardown);
}
