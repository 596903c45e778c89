/* The OpenCL backend against the C backend (the reference).
 *
 * For each scheme (upwind, roe-fix) and integrator (euler, rk2, rk3), with
 * and without reinitialisation every 10 steps (weno5 with euler and rk3, and
 * with rk3 and reinitialisation), a morph state like a real one
 * (disc SDF -> offset ellipse, 96x80 cells, dx = dy = 1) runs 200 steps on
 * both backends through lsm_fields (the same driver lsm_morph uses):
 *   max |phi_opencl - phi_c| <= 1e-4 * max(nx, ny) * dx,
 *   the masks phi <= 0 differ in <= 0.1 % of the cells,
 *   the CFL dt and the residual agree to 1e-5 relative (every step).
 * The particle level set (--method pls) the same way, through lsm_morph on
 * both backends (particles seeded on the host, then advected, detected and
 * corrected on the device): for each scheme and integrator, 240 steps, the
 * same limits on phi and the masks, and the same particle counters (seeded,
 * discarded, left the domain, strays, escaped, corrected, reseeding), with
 * reseeding and radius adjustment in two more cases.  One correction with
 * hand-placed particles (many escaped, some strays) against lsm_pls_correct,
 * and in reverse particle order (the device result must not depend on it).
 * Also: device listing, a missing device index, no kernel cache of our own
 * (nothing written under XDG_CACHE_HOME), ghost fill on download, upload, the
 * stage hook refusal.
 *
 * XDG_CACHE_HOME is a temporary folder.  Without an OpenCL platform or device
 * the tests print why and are skipped (the Makefile installs PoCL, so on CI
 * they run); a device that fails to build the program fails them. */
#include "tests/lsm_test.h"
#include "tests/lsm_test_io.h"
#include "tests/lsm_test_pair.h"

#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include "solver/pde/lsm_backend.h"
#include "solver/pde/lsm_fields.h"
#include "solver/base/lsm_grid.h"
#include "solver/pde/lsm_morph.h"
#include "solver/pde/lsm_particles.h"
#include "solver/pde/lsm_scheme.h"
#include "solver/base/lsm_status.h"

typedef struct fixture {
  lsm_backend *cl;     /* NULL when no device could be opened */
  lsm_err why;         /* ... and why */
  char cache[256];     /* temporary XDG_CACHE_HOME */
} fixture;

static fixture fx; /* the group's state: set up once, read by the tests */

/* Under SANITIZE=1: LeakSanitizer's default suppressions for this program.
 * The OpenCL loader, PoCL and its LLVM keep allocations until exit that they
 * never free; leaks of our own code are still reported. */
const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void) {
  return "leak:libpocl.so\nleak:libLLVM\nleak:libOpenCL.so\nleak:libclang\n";
}

/* ------------------------------------------------------------------------ */
/* helpers                                                                   */

/* Files in a folder: how many end in suffix, how many do not. */
static void scan_dir(const char *dir, const char *suffix, int *with, int *without) {
  *with = *without = 0;
  DIR *d = opendir(dir);
  if (!d) return;
  struct dirent *e;
  while ((e = readdir(d)) != NULL) {
    if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
    size_t n = strlen(e->d_name), m = strlen(suffix);
    if (n >= m && strcmp(e->d_name + n - m, suffix) == 0)
      (*with)++;
    else
      (*without)++;
  }
  closedir(d);
}

static int need_device(void) {
  if (fx.cl) return 1;
  print_message("opencl: skipped: %s\n", fx.why.msg[0] ? fx.why.msg : "no OpenCL device");
  return 0;
}

#define NEED_DEVICE() \
  do {                \
    if (!need_device()) skip(); \
  } while (0)

/* ------------------------------------------------------------------------ */
/* setup                                                                     */

static int group_setup(void **state) {
  (void)state;
  memset(&fx, 0, sizeof fx);
  snprintf(fx.cache, sizeof fx.cache, "%s/lsm-opencl-test.XXXXXX",
           getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
  if (!mkdtemp(fx.cache)) return -1;
  /* PoCL keeps its own compiled kernels under XDG_CACHE_HOME too: leave those
   * where they were (a warm PoCL cache), unless POCL_CACHE_DIR says otherwise. */
  if (!getenv("POCL_CACHE_DIR")) {
    char pocl[512];
    const char *xdg = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");
    if (xdg && xdg[0] == '/')
      snprintf(pocl, sizeof pocl, "%s/pocl/kcache", xdg);
    else if (home && home[0] == '/')
      snprintf(pocl, sizeof pocl, "%s/.cache/pocl/kcache", home);
    else
      pocl[0] = '\0';
    if (pocl[0] && setenv("POCL_CACHE_DIR", pocl, 1) != 0) return -1;
  }
  if (setenv("XDG_CACHE_HOME", fx.cache, 1) != 0) return -1;
  lsm_err_clear(&fx.why);
  const lsm_status st = lsm_backend_open("opencl", -1, 1, &fx.cl, &fx.why);
  if (st == LSM_OK || st == LSM_ERR_UNSUPPORTED) return 0; /* no platform or no device: skip */
  print_error("opencl: %s\n", fx.why.msg); /* a device that cannot build the program fails */
  return -1;
}

static int group_teardown(void **state) {
  (void)state;
  lsm_backend_close(&fx.cl);
  if (fx.cache[0]) rm_rf(fx.cache);
  return 0;
}

/* ------------------------------------------------------------------------ */
/* backend plumbing                                                          */

static void test_list_devices(void **state) {
  (void)state;
  NEED_DEVICE();
  char *buf = NULL;
  size_t size = 0;
  FILE *f = open_memstream(&buf, &size);
  assert_non_null(f);
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_backend_list_devices(f, &err), LSM_OK);
  fclose(f);
  assert_non_null(strstr(buf, "  0: "));
  assert_non_null(strstr(buf, "compute unit"));
  assert_non_null(strstr(buf, "global memory"));
  /* one device is marked the default, and it is the one opened without --device */
  const char *mark = strstr(buf, ", the default\n");
  assert_non_null(mark);
  assert_null(strstr(mark + 1, ", the default"));
  const char *line = mark;
  while (line > buf && line[-1] != '\n') --line;
  const char *name = strstr(line, ": ");
  assert_non_null(name);
  name += 2;
  const char *name_end = strstr(name, " (");
  assert_true(name_end && name_end < mark);
  lsm_backend *b = NULL;
  assert_int_equal(lsm_backend_open("opencl", -1, 1, &b, &err), LSM_OK);
  char want[256];
  snprintf(want, sizeof want, "%.*s", (int)(name_end - name), name);
  if (!strstr(lsm_backend_device(b), want))
    fail_msg("default device '%s', opened '%s'", want, lsm_backend_device(b));
  lsm_backend_close(&b);
  free(buf);
}

static void test_missing_device(void **state) {
  (void)state;
  NEED_DEVICE();
  lsm_backend *b = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_backend_open("opencl", 99, 1, &b, &err), LSM_ERR_INPUT);
  assert_null(b);
  assert_non_null(strstr(err.msg, "device 99 does not exist"));
  /* auto falls back to C */
  lsm_err_clear(&err);
  assert_int_equal(lsm_backend_open("auto", 99, 1, &b, &err), LSM_OK);
  assert_string_equal(lsm_backend_name(b), "c");
  assert_non_null(strstr(lsm_backend_fallback(b), "device 99 does not exist"));
  lsm_backend_close(&b);
}

/* The program is built from source at every open: no cache of lsmorph's own
 * is written (PoCL's stays where POCL_CACHE_DIR says), and run.json's
 * kernel_cache_hit is false. */
static void test_no_kernel_cache(void **state) {
  (void)state;
  NEED_DEVICE();
  lsm_backend_fact facts[LSM_BACKEND_FACTS_MAX];
  const int n = lsm_backend_facts(fx.cl, facts, LSM_BACKEND_FACTS_MAX);
  assert_true(n >= 3);
  assert_string_equal(facts[0].key, "device");
  assert_int_equal(facts[0].kind, LSM_FACT_TEXT);
  assert_non_null(strchr(facts[0].text, '('));
  assert_string_equal(facts[1].key, "build_seconds");
  assert_int_equal(facts[1].kind, LSM_FACT_NUMBER);
  assert_true(facts[1].number >= 0.0);
  assert_string_equal(facts[2].key, "kernel_cache_hit");
  assert_int_equal(facts[2].kind, LSM_FACT_FLAG);
  assert_int_equal(facts[2].flag, 0);
  assert_string_equal(lsm_backend_name(fx.cl), "opencl");
  assert_int_equal(lsm_backend_host_threads(fx.cl), 0);
  char dir[512];
  int files = 0, others = 0;
  snprintf(dir, sizeof dir, "%s/lsmorph", fx.cache);
  struct stat sb;
  assert_int_not_equal(stat(dir, &sb), 0);
  scan_dir(fx.cache, "", &files, &others);
  assert_int_equal(files, 0);
}

/* upload / download round trip, ghosts filled on download, residual of
 * phi == target is 0, an empty particle set. */
static void test_plumbing(void **state) {
  (void)state;
  NEED_DEVICE();
  const int nx = 37, ny = 23;
  lsm_grid *a = new_grid(nx, ny, 1.0f, 1.0f), *t = new_grid(nx, ny, 1.0f, 1.0f);
  lsm_grid *back = new_grid(nx, ny, 1.0f, 1.0f);
  fill_pair(a, t);
  lsm_fields *f = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_fields_create(fx.cl, a, t, 1, &f, &err), LSM_OK);
  assert_string_equal(lsm_fields_backend_name(f), "opencl");
  /* Garbage in the ghosts of the upload: download must return them filled. */
  for (int j = 0; j < ny; ++j) LSM_AT(a, -2, j) = 1e6f;
  assert_int_equal(lsm_fields_upload(f, a, &err), LSM_OK);
  assert_int_equal(lsm_fields_download(f, back, &err), LSM_OK);
  lsm_grid_fill_ghosts(a);
  assert_memory_equal(a->base, back->base,
                      (size_t)(ny + 2 * LSM_GHOST) * (size_t)a->stride * sizeof(float));
  /* Residual: phi = target gives 0. */
  assert_int_equal(lsm_fields_upload(f, t, &err), LSM_OK);
  double norm = -1.0, dt = 0.0;
  assert_int_equal(lsm_fields_residual(f, &norm, &err), LSM_OK);
  assert_true(norm == 0.0);
  assert_int_equal(lsm_fields_cfl_dt(f, LSM_SCHEME_UPWIND, 0.75, &dt, &err), LSM_OK);
  assert_true(isinf(dt));
  /* A correction before any set is loaded is refused; an empty set does nothing but count
   * the step. */
  lsm_pls_stats q;
  memset(&q, 0, sizeof q);
  assert_int_equal(lsm_fields_pls_correct(f, &q, &err), LSM_ERR_INTERNAL);
  assert_true(lsm_fields_has_particles(f));
  lsm_pls_view none = {0, NULL, NULL, NULL, NULL};
  lsm_err_clear(&err);
  assert_int_equal(lsm_fields_pls_load(f, &none, 1, &err), LSM_OK);
  assert_int_equal(lsm_fields_pls_correct(f, &q, &err), LSM_OK);
  assert_true(q.left_domain == 0 && q.stray == 0 && q.escaped_total == 0 &&
              q.corrected_total == 0 && q.steps == 1);
  assert_int_equal(lsm_fields_step(f, LSM_SCHEME_UPWIND, LSM_TIME_RK3, 0.1f, &err), LSM_OK);
  /* Reinit with 0 iterations is a no-op. */
  assert_int_equal(lsm_fields_reinit(f, 0, &err), LSM_OK);
  lsm_fields_destroy(&f);
  assert_null(f);
  lsm_grid_destroy(&a);
  lsm_grid_destroy(&t);
  lsm_grid_destroy(&back);
}

static double rel_diff(double a, double b);

/* A grid large enough that the reduction work-items loop over several rows
 * and the rows span several work-groups: CFL, residual and a few steps. */
static void test_large_grid(void **state) {
  (void)state;
  NEED_DEVICE();
  const int nx = 1500, ny = 1100;
  lsm_grid *src = new_grid(nx, ny, 1.0f, 1.0f), *dst = new_grid(nx, ny, 1.0f, 1.0f);
  lsm_grid *got = new_grid(nx, ny, 1.0f, 1.0f), *ref = new_grid(nx, ny, 1.0f, 1.0f);
  fill_pair(src, dst);
  lsm_fields *cs = NULL, *gs = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_fields_create(NULL, src, dst, 1, &cs, &err), LSM_OK);
  assert_int_equal(lsm_fields_create(fx.cl, src, dst, 1, &gs, &err), LSM_OK);
  double dt_c, dt_g, res_c, res_g;
  assert_int_equal(lsm_fields_cfl_dt(cs, LSM_SCHEME_ROEFIX, 0.75, &dt_c, &err), LSM_OK);
  assert_int_equal(lsm_fields_cfl_dt(gs, LSM_SCHEME_ROEFIX, 0.75, &dt_g, &err), LSM_OK);
  assert_true(dt_c == dt_g);
  assert_int_equal(lsm_fields_cfl_dt(cs, LSM_SCHEME_UPWIND, 0.75, &dt_c, &err), LSM_OK);
  assert_int_equal(lsm_fields_cfl_dt(gs, LSM_SCHEME_UPWIND, 0.75, &dt_g, &err), LSM_OK);
  assert_true(dt_c == dt_g);
  for (int n = 0; n < 4; ++n) {
    assert_int_equal(lsm_fields_step(cs, LSM_SCHEME_UPWIND, LSM_TIME_RK3, (float)dt_c, &err), LSM_OK);
    assert_int_equal(lsm_fields_step(gs, LSM_SCHEME_UPWIND, LSM_TIME_RK3, (float)dt_c, &err), LSM_OK);
  }
  assert_int_equal(lsm_fields_residual(cs, &res_c, &err), LSM_OK);
  assert_int_equal(lsm_fields_residual(gs, &res_g, &err), LSM_OK);
  assert_true(rel_diff(res_c, res_g) <= 1e-5);
  assert_int_equal(lsm_fields_download(cs, ref, &err), LSM_OK);
  assert_int_equal(lsm_fields_download(gs, got, &err), LSM_OK);
  double max_diff = 0.0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      double d = fabs((double)LSM_AT(ref, i, j) - (double)LSM_AT(got, i, j));
      if (d > max_diff) max_diff = d;
    }
  print_message("opencl: %dx%d, 4 rk3 steps: max|phi_cl - phi_c| = %.3g, residual rel %.2g\n", nx,
                ny, max_diff, rel_diff(res_c, res_g));
  assert_true(max_diff <= 1e-4 * nx);
  lsm_fields_destroy(&cs);
  lsm_fields_destroy(&gs);
  lsm_grid_destroy(&src);
  lsm_grid_destroy(&dst);
  lsm_grid_destroy(&got);
  lsm_grid_destroy(&ref);
}

/* ------------------------------------------------------------------------ */
/* the morph on both backends                                                */

typedef struct morph_case {
  lsm_scheme scheme;
  lsm_time time;
  int reinit_every;
  int nx, ny;
  float dx, dy;
} morph_case;

static double rel_diff(double a, double b) {
  double m = fabs(a) > fabs(b) ? fabs(a) : fabs(b);
  return m > 0.0 ? fabs(a - b) / m : 0.0;
}

/* band: both run the narrow band (lsm_fields_band_start, rebuilt by lsm_fields_band_maintain
 * after every step, as lsm_morph does). */
static void morph_matches_c(const morph_case *mc, int band) {
  NEED_DEVICE();
  const int nx = mc->nx, ny = mc->ny, steps = 200;
  lsm_grid *src = new_grid(nx, ny, mc->dx, mc->dy), *dst = new_grid(nx, ny, mc->dx, mc->dy);
  lsm_grid *got = new_grid(nx, ny, mc->dx, mc->dy), *ref = new_grid(nx, ny, mc->dx, mc->dy);
  fill_pair(src, dst);
  lsm_fields *cs = NULL, *gs = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_fields_create(NULL, src, dst, 1, &cs, &err), LSM_OK);
  assert_int_equal(lsm_fields_create(fx.cl, src, dst, 1, &gs, &err), LSM_OK);
  lsm_band_params bp;
  lsm_band_params_of(mc->scheme, mc->dx, mc->dy, &bp);
  if (band) {
    assert_int_equal(lsm_fields_band_start(cs, dst, &bp, &err), LSM_OK);
    if (lsm_fields_band_start(gs, dst, &bp, &err) != LSM_OK) fail_msg("%s", err.msg);
  }

  double dt_c = 0.0, dt_g = 0.0, res_c = 0.0, res_g = 0.0;
  double worst_dt = 0.0, worst_res = 0.0, res0 = 0.0;
  int rebuilds = 0;
  assert_int_equal(lsm_fields_cfl_dt(cs, mc->scheme, 0.75, &dt_c, &err), LSM_OK);
  assert_int_equal(lsm_fields_cfl_dt(gs, mc->scheme, 0.75, &dt_g, &err), LSM_OK);
  worst_dt = rel_diff(dt_c, dt_g);
  assert_int_equal(lsm_fields_residual(cs, &res0, &err), LSM_OK);
  assert_true(dt_c > 0.0 && isfinite(dt_c));
  for (int n = 1; n <= steps; ++n) {
    assert_int_equal(lsm_fields_step(cs, mc->scheme, mc->time, (float)dt_c, &err), LSM_OK);
    assert_int_equal(lsm_fields_step(gs, mc->scheme, mc->time, (float)dt_c, &err), LSM_OK);
    if (mc->reinit_every > 0 && n % mc->reinit_every == 0) {
      assert_int_equal(lsm_fields_reinit(cs, 10, &err), LSM_OK);
      assert_int_equal(lsm_fields_reinit(gs, 10, &err), LSM_OK);
    }
    int rebuilt_c = 0, rebuilt_g = 0;
    assert_int_equal(lsm_fields_band_maintain(cs, &rebuilt_c, &err), LSM_OK);
    assert_int_equal(lsm_fields_band_maintain(gs, &rebuilt_g, &err), LSM_OK);
    assert_int_equal(rebuilt_c, rebuilt_g);
    rebuilds += rebuilt_c;
    assert_int_equal(lsm_fields_residual(cs, &res_c, &err), LSM_OK);
    assert_int_equal(lsm_fields_residual(gs, &res_g, &err), LSM_OK);
    double r = rel_diff(res_c, res_g);
    if (r > worst_res) worst_res = r;
  }
  /* The CFL reduction on the evolved state as well. */
  assert_int_equal(lsm_fields_cfl_dt(cs, mc->scheme, 0.75, &dt_c, &err), LSM_OK);
  assert_int_equal(lsm_fields_cfl_dt(gs, mc->scheme, 0.75, &dt_g, &err), LSM_OK);
  if (rel_diff(dt_c, dt_g) > worst_dt) worst_dt = rel_diff(dt_c, dt_g);

  assert_int_equal(lsm_fields_download(cs, ref, &err), LSM_OK);
  assert_int_equal(lsm_fields_download(gs, got, &err), LSM_OK);
  double max_diff = 0.0;
  long mask_diff = 0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      float a = LSM_AT(ref, i, j), b = LSM_AT(got, i, j);
      assert_true(isfinite(b));
      double d = fabs((double)a - (double)b);
      if (d > max_diff) max_diff = d;
      mask_diff += (a <= 0.0f) != (b <= 0.0f);
    }
  const double extent = (nx > ny ? nx : ny) * (double)mc->dx;
  print_message("opencl: %-7s %-5s reinit %-2d %dx%d%s: max|phi_cl - phi_c| = %.3g (limit %.3g), "
                "masks differ in %ld cells, dt rel %.2g, residual rel %.2g (final %.6g)\n",
                lsm_scheme_name(mc->scheme), lsm_time_name(mc->time), mc->reinit_every, nx, ny,
                band ? " band" : "", max_diff, 1e-4 * extent, mask_diff, worst_dt, worst_res,
                res_c);
  assert_true(max_diff <= 1e-4 * extent);
  assert_true((double)mask_diff <= 0.001 * nx * ny);
  assert_true(worst_dt <= 1e-5);
  assert_true(worst_res <= 1e-5);
  /* The morph moved: the residual fell (with the band, over the whole grid); the band was
   * rebuilt and covers less than the grid. */
  if (band) {
    assert_true(lsm_grid_diff_norm(ref, dst, 1) < 0.5 * lsm_grid_diff_norm(src, dst, 1));
    assert_true(rebuilds > 0 && lsm_fields_cells(cs) < (long long)nx * ny);
  } else {
    assert_true(res_c < 0.5 * res0);
  }
  lsm_fields_destroy(&cs);
  lsm_fields_destroy(&gs);
  lsm_grid_destroy(&src);
  lsm_grid_destroy(&dst);
  lsm_grid_destroy(&got);
  lsm_grid_destroy(&ref);
}

#define CASE(s, t, r) {s, t, r, 96, 80, 1.0f, 1.0f}
static const morph_case cases[] = {
    CASE(LSM_SCHEME_UPWIND, LSM_TIME_EULER, 0), CASE(LSM_SCHEME_UPWIND, LSM_TIME_RK2, 0),
    CASE(LSM_SCHEME_UPWIND, LSM_TIME_RK3, 0),   CASE(LSM_SCHEME_ROEFIX, LSM_TIME_EULER, 0),
    CASE(LSM_SCHEME_ROEFIX, LSM_TIME_RK2, 0),   CASE(LSM_SCHEME_ROEFIX, LSM_TIME_RK3, 0),
    CASE(LSM_SCHEME_UPWIND, LSM_TIME_EULER, 10), CASE(LSM_SCHEME_UPWIND, LSM_TIME_RK2, 10),
    CASE(LSM_SCHEME_UPWIND, LSM_TIME_RK3, 10),   CASE(LSM_SCHEME_ROEFIX, LSM_TIME_EULER, 10),
    CASE(LSM_SCHEME_ROEFIX, LSM_TIME_RK2, 10),   CASE(LSM_SCHEME_ROEFIX, LSM_TIME_RK3, 10),
    /* Unequal spacing and a size that is no multiple of any work-group. */
    {LSM_SCHEME_ROEFIX, LSM_TIME_RK2, 10, 53, 131, 0.5f, 0.75f},
    CASE(LSM_SCHEME_WENO5, LSM_TIME_EULER, 0),   CASE(LSM_SCHEME_WENO5, LSM_TIME_RK3, 0),
    CASE(LSM_SCHEME_WENO5, LSM_TIME_RK3, 10),
    {LSM_SCHEME_WENO5, LSM_TIME_RK3, 10, 53, 131, 0.5f, 0.75f},
};

static void test_morph_matches_c(void **state) { morph_matches_c(*state, 0); }
static void test_band_matches_c(void **state) { morph_matches_c(*state, 1); }

#define MORPH(k, name) {name, test_morph_matches_c, NULL, NULL, (void *)&cases[k]}
#define BAND(k, name) {name " band", test_band_matches_c, NULL, NULL, (void *)&cases[k]}

/* ------------------------------------------------------------------------ */
/* particles                                                                 */

static lsm_particles *new_pls(const lsm_grid *phi) {
  lsm_particles *p = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  if (lsm_pls_create(phi, NULL, &p, &err) != LSM_OK) fail_msg("lsm_pls_create: %s", err.msg);
  return p;
}

/* One correction with hand-placed particles: 3000 particles at random
 * positions, signs and radii on a disc SDF (about half on the wrong side:
 * escaped, some farther than 1.5 cells: strays), corrected by lsm_pls_correct
 * on the host and by pls_correct on the device, in the given order and in
 * reverse: the same phi and the same counts. */
static void test_pls_correct_matches_c(void **state) {
  (void)state;
  NEED_DEVICE();
  const int nx = 45, ny = 38;
  const float dx = 0.8f, dy = 1.1f;
  lsm_grid *phi = new_grid(nx, ny, dx, dy), *ref = new_grid(nx, ny, dx, dy);
  lsm_grid *got = new_grid(nx, ny, dx, dy);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      LSM_AT(phi, i, j) = (float)(hypot((i - 21.3) * dx, (j - 17.6) * dy) - 11.0);
  lsm_grid_fill_ghosts(phi);
  lsm_grid_copy(ref, phi);
  enum { N = 3000 };
  static float x[N], y[N], r[N], rx[N], ry[N], rr[N];
  static int8_t sg[N], rs[N];
  uint64_t seed = 0x9e3779b97f4a7c15ULL;
  for (int k = 0; k < N; ++k) {
    /* near the front (radius 11 around the centre), +-3 physical units */
    const double a = (double)(lsm_test_rand(&seed) % 100000) * (6.283185307179586 / 100000.0);
    const double d = 11.0 + ((double)(lsm_test_rand(&seed) % 10000) / 10000.0 - 0.5) * 6.0;
    x[k] = (float)(21.3 + d * cos(a) / dx);
    y[k] = (float)(17.6 + d * sin(a) / dy);
    sg[k] = (lsm_test_rand(&seed) & 1) ? 1 : -1;
    r[k] = 0.08f + 0.4f * (float)(lsm_test_rand(&seed) % 1000) / 1000.0f;
    rx[N - 1 - k] = x[k];
    ry[N - 1 - k] = y[k];
    rr[N - 1 - k] = r[k];
    rs[N - 1 - k] = sg[k];
  }
  lsm_particles *p = new_pls(ref);
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_pls_set(p, N, x, y, sg, r, &err), LSM_OK);
  const lsm_pls_view set = lsm_pls_view_get(p);
  const lsm_pls_view rev = {N, rx, ry, rr, rs};
  lsm_fields *st = NULL;
  assert_int_equal(lsm_fields_create(fx.cl, phi, phi, 1, &st, &err), LSM_OK);
  lsm_pls_stats c[2];
  for (int pass = 0; pass < 2; ++pass) {
    memset(&c[pass], 0, sizeof c[pass]);
    assert_int_equal(lsm_fields_upload(st, phi, &err), LSM_OK);
    assert_int_equal(lsm_fields_pls_load(st, pass ? &rev : &set, 0, &err), LSM_OK);
    assert_int_equal(lsm_fields_pls_correct(st, &c[pass], &err), LSM_OK);
    if (pass == 0) {
      /* the host set is read by pls_load only: correct it now */
      assert_int_equal(lsm_pls_correct(p, ref, &err), LSM_OK);
    }
    assert_int_equal(lsm_fields_download(st, got, &err), LSM_OK);
    double max_diff = 0.0;
    long changed = 0;
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const double d = fabs((double)LSM_AT(ref, i, j) - (double)LSM_AT(got, i, j));
        if (d > max_diff) max_diff = d;
        changed += LSM_AT(ref, i, j) != LSM_AT(phi, i, j);
      }
    const lsm_pls_stats *q = lsm_pls_stats_get(p);
    print_message("opencl: pls correction (%s order): %lld escaped, %lld strays, %lld corrected "
                  "(C: %lld, %lld, %lld); max|phi_cl - phi_c| = %.3g\n",
                  pass ? "reverse" : "seeded", c[pass].escaped_last, c[pass].stray,
                  c[pass].corrected_last, q->escaped_last, q->stray, q->corrected_last, max_diff);
    assert_true(max_diff == 0.0);
    assert_int_equal(c[pass].escaped_last, q->escaped_last);
    assert_int_equal(c[pass].stray, q->stray);
    assert_int_equal(c[pass].corrected_last, q->corrected_last);
    assert_int_equal(c[pass].left_domain, 0);
    assert_int_equal(c[pass].steps, 1);
    assert_int_equal(c[pass].corrected_last, changed);
    assert_true(q->escaped_last > 100 && q->stray > 10 && q->corrected_last > 100);
  }
  /* The strays go at the next correction. */
  lsm_pls_stats next;
  memset(&next, 0, sizeof next);
  assert_int_equal(lsm_fields_pls_correct(st, &next, &err), LSM_OK);
  assert_int_equal(next.left_domain, c[1].stray);
  lsm_fields_destroy(&st);
  lsm_pls_destroy(&p);
  lsm_grid_destroy(&phi);
  lsm_grid_destroy(&ref);
  lsm_grid_destroy(&got);
}

typedef struct pls_case {
  lsm_scheme scheme;
  lsm_time time;
  int reseed_every, radius_adjust;
  int nx, ny;
  float dx, dy;
  int harsh; /* 1: fill_pls_pair, else fill_pair */
} pls_case;

/* A pair that works the particles harder than fill_pair: the source is the
 * SDF of a box (sharp corners: particles escape there, some far enough to be
 * strays), the target a disc that runs past the right edge of the grid (the
 * front moves out to the edge: particles leave the domain). */
static void fill_pls_pair(lsm_grid *src, lsm_grid *dst) {
  const int nx = src->nx, ny = src->ny;
  const double w = nx * (double)src->dx, h = ny * (double)src->dy;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double x = (i + 0.5) * src->dx, y = (j + 0.5) * src->dy;
      const double qx = fabs(x - 0.4 * w) - 0.22 * w, qy = fabs(y - 0.5 * h) - 0.3 * h;
      const double out = hypot(qx > 0 ? qx : 0, qy > 0 ? qy : 0);
      const double in = qx > qy ? qx : qy;
      LSM_AT(src, i, j) = (float)(in < 0 ? in : out);
      LSM_AT(dst, i, j) = (float)(hypot(x - 0.8 * w, y - 0.45 * h) - 0.36 * h);
    }
  lsm_grid_fill_ghosts(src);
  lsm_grid_fill_ghosts(dst);
}

/* The pls morph through lsm_morph on both backends (as the pair driver runs
 * it), 240 steps. */
static void pls_matches_c(const pls_case *pc, int band) {
  NEED_DEVICE();
  const int nx = pc->nx, ny = pc->ny, steps = 240;
  lsm_grid *src = new_grid(nx, ny, pc->dx, pc->dy), *dst = new_grid(nx, ny, pc->dx, pc->dy);
  if (pc->harsh)
    fill_pls_pair(src, dst);
  else
    fill_pair(src, dst);
  lsm_morph_opts o;
  lsm_morph_opts_default(&o);
  o.scheme = pc->scheme;
  o.time = pc->time;
  o.particles = 1;
  o.pls.reseed_every = pc->reseed_every;
  o.pls.radius_adjust = pc->radius_adjust;
  o.band = band;
  lsm_morph *mc = NULL, *mg = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_morph_create(src, dst, &o, &mc, &err), LSM_OK);
  o.backend = fx.cl;
  if (lsm_morph_create(src, dst, &o, &mg, &err) != LSM_OK) fail_msg("%s", err.msg);
  assert_true(lsm_morph_dt(mc) == lsm_morph_dt(mg));
  for (int n = 0; n < steps; ++n) {
    if (lsm_morph_step(mc, INFINITY, &err) != LSM_OK) fail_msg("C: %s", err.msg);
    if (lsm_morph_step(mg, INFINITY, &err) != LSM_OK) fail_msg("OpenCL: %s", err.msg);
  }
  const lsm_grid *ref = lsm_morph_phi(mc), *got = lsm_morph_phi(mg);
  assert_non_null(ref);
  assert_non_null(got);
  double max_diff = 0.0;
  long mask_diff = 0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const float a = LSM_AT(ref, i, j), b = LSM_AT(got, i, j);
      assert_true(isfinite(b));
      const double d = fabs((double)a - (double)b);
      if (d > max_diff) max_diff = d;
      mask_diff += (a <= 0.0f) != (b <= 0.0f);
    }
  const lsm_pls_stats *qc = lsm_morph_pls_stats(mc), *qg = lsm_morph_pls_stats(mg);
  assert_non_null(qc);
  assert_non_null(qg);
  const long long live_c = qc->seeded - qc->discarded - qc->left_domain - qc->reseed_dropped;
  const long long live_g = qg->seeded - qg->discarded - qg->left_domain - qg->reseed_dropped;
  const double extent = (nx > ny ? nx * (double)pc->dx : ny * (double)pc->dy);
  print_message("opencl: pls %-7s %-5s reseed %d radius %d %s %dx%d%s: max|phi_cl - phi_c| = %.3g "
                "(limit %.3g), masks differ in %ld cells; particles C/CL: seeded %lld/%lld, "
                "live %lld/%lld, left %lld/%lld (strays %lld/%lld), escaped %lld/%lld, "
                "corrected %lld/%lld\n",
                lsm_scheme_name(pc->scheme), lsm_time_name(pc->time), pc->reseed_every,
                pc->radius_adjust, pc->harsh ? "box" : "disc", nx, ny, band ? " band" : "",
                max_diff, 1e-4 * extent, mask_diff, qc->seeded,
                qg->seeded, live_c, live_g, qc->left_domain, qg->left_domain, qc->stray,
                qg->stray, qc->escaped_total, qg->escaped_total, qc->corrected_total,
                qg->corrected_total);
  assert_true(max_diff <= 1e-4 * extent);
  assert_true((double)mask_diff <= 0.001 * nx * ny);
  assert_int_equal(qg->steps, steps);
  assert_int_equal(qc->steps, qg->steps);
  assert_int_equal(qc->seeded, qg->seeded);
  assert_int_equal(qc->discarded, qg->discarded);
  assert_int_equal(qc->left_domain, qg->left_domain);
  assert_int_equal(qc->stray, qg->stray);
  assert_int_equal(qc->reseed_dropped, qg->reseed_dropped);
  assert_int_equal(qc->reseeds, qg->reseeds);
  assert_int_equal(qc->band_cells, qg->band_cells);
  assert_int_equal(qc->escaped_total, qg->escaped_total);
  assert_int_equal(qc->corrected_total, qg->corrected_total);
  assert_int_equal(live_c, live_g);
  assert_int_equal((long long)0 + live_c, 0 + (long long)qc->seeded - qc->discarded -
                                              qc->left_domain - qc->reseed_dropped);
  /* the particles did work: escaped and corrected; on the harsh pair also
   * left the domain, and strayed (Euler and RK2 without radius adjustment; with the band
   * and reseeding every 60 steps none stray: its strays are exercised without reseeding) */
  assert_true(qc->escaped_total > 0 && qc->corrected_total > 0);
  if (pc->harsh) assert_true(qc->left_domain > qc->stray);
  if (pc->harsh && pc->time != LSM_TIME_RK3 && !pc->radius_adjust && !(band && pc->reseed_every))
    assert_true(qc->stray > 0);
  if (pc->reseed_every > 0) assert_int_equal(qg->reseeds, steps / pc->reseed_every);
  lsm_morph_destroy(&mc);
  lsm_morph_destroy(&mg);
  lsm_grid_destroy(&src);
  lsm_grid_destroy(&dst);
}

#define PCASE(s, t, harsh) {s, t, 0, 0, 96, 80, 1.0f, 1.0f, harsh}
static const pls_case pls_cases[] = {
    PCASE(LSM_SCHEME_UPWIND, LSM_TIME_EULER, 1), PCASE(LSM_SCHEME_UPWIND, LSM_TIME_RK2, 1),
    PCASE(LSM_SCHEME_UPWIND, LSM_TIME_RK3, 1),   PCASE(LSM_SCHEME_ROEFIX, LSM_TIME_EULER, 1),
    PCASE(LSM_SCHEME_ROEFIX, LSM_TIME_RK2, 1),   PCASE(LSM_SCHEME_ROEFIX, LSM_TIME_RK3, 1),
    PCASE(LSM_SCHEME_ROEFIX, LSM_TIME_RK2, 0),
    /* reseeding (a host round trip) and radius adjustment */
    {LSM_SCHEME_UPWIND, LSM_TIME_RK2, 25, 1, 96, 80, 1.0f, 1.0f, 1},
    /* unequal spacing, no multiple of any work-group */
    {LSM_SCHEME_ROEFIX, LSM_TIME_RK3, 40, 1, 53, 131, 0.5f, 0.75f, 1},
    /* reseeding on a step whose correction found strays: the backend's set
     * still holds them, the C path removes them as it reseeds (left the
     * domain, not dropped by the reseed) */
    {LSM_SCHEME_UPWIND, LSM_TIME_EULER, 60, 0, 96, 80, 1.0f, 1.0f, 1},
};

static void test_pls_matches_c(void **state) { pls_matches_c(*state, 0); }
static void test_pls_band_matches_c(void **state) { pls_matches_c(*state, 1); }

#define PLS(k, name) {name, test_pls_matches_c, NULL, NULL, (void *)&pls_cases[k]}
#define PLSB(k, name) {name " band", test_pls_band_matches_c, NULL, NULL, (void *)&pls_cases[k]}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_list_devices),
      cmocka_unit_test(test_missing_device),
      cmocka_unit_test(test_no_kernel_cache),
      cmocka_unit_test(test_plumbing),
      cmocka_unit_test(test_large_grid),
      MORPH(0, "morph upwind euler"),
      MORPH(1, "morph upwind rk2"),
      MORPH(2, "morph upwind rk3"),
      MORPH(3, "morph roe-fix euler"),
      MORPH(4, "morph roe-fix rk2"),
      MORPH(5, "morph roe-fix rk3"),
      MORPH(6, "morph upwind euler reinit"),
      MORPH(7, "morph upwind rk2 reinit"),
      MORPH(8, "morph upwind rk3 reinit"),
      MORPH(9, "morph roe-fix euler reinit"),
      MORPH(10, "morph roe-fix rk2 reinit"),
      MORPH(11, "morph roe-fix rk3 reinit"),
      MORPH(12, "morph roe-fix rk2 reinit 53x131 dx 0.5 dy 0.75"),
      MORPH(13, "morph weno5 euler"),
      MORPH(14, "morph weno5 rk3"),
      MORPH(15, "morph weno5 rk3 reinit"),
      MORPH(16, "morph weno5 rk3 reinit 53x131 dx 0.5 dy 0.75"),
      BAND(0, "morph upwind euler"),
      BAND(1, "morph upwind rk2"),
      BAND(2, "morph upwind rk3"),
      BAND(3, "morph roe-fix euler"),
      BAND(4, "morph roe-fix rk2"),
      BAND(5, "morph roe-fix rk3"),
      BAND(6, "morph upwind euler reinit"),
      BAND(8, "morph upwind rk3 reinit"),
      BAND(11, "morph roe-fix rk3 reinit"),
      BAND(12, "morph roe-fix rk2 reinit 53x131 dx 0.5 dy 0.75"),
      BAND(13, "morph weno5 euler"),
      BAND(14, "morph weno5 rk3"),
      BAND(16, "morph weno5 rk3 reinit 53x131 dx 0.5 dy 0.75"),
      cmocka_unit_test(test_pls_correct_matches_c),
      PLS(0, "pls upwind euler"),
      PLS(1, "pls upwind rk2"),
      PLS(2, "pls upwind rk3"),
      PLS(3, "pls roe-fix euler"),
      PLS(4, "pls roe-fix rk2"),
      PLS(5, "pls roe-fix rk3"),
      PLS(6, "pls roe-fix rk2 disc to ellipse"),
      PLS(7, "pls upwind rk2 reseed 25 radius adjust"),
      PLS(8, "pls roe-fix rk3 reseed 40 radius adjust 53x131 dx 0.5 dy 0.75"),
      PLS(9, "pls upwind euler reseed 60 (strays on a reseed step)"),
      PLSB(0, "pls upwind euler"),
      PLSB(2, "pls upwind rk3"),
      PLSB(4, "pls roe-fix rk2"),
      PLSB(6, "pls roe-fix rk2 disc to ellipse"),
      PLSB(7, "pls upwind rk2 reseed 25 radius adjust"),
      PLSB(8, "pls roe-fix rk3 reseed 40 radius adjust 53x131 dx 0.5 dy 0.75"),
      PLSB(9, "pls upwind euler reseed 60 (strays on a reseed step)"),
  };
  return cmocka_run_group_tests_name("test_opencl", tests, group_setup, group_teardown);
}
