/* The backend interface (solver/pde/lsm_backend.h) and its driver (lsm_fields.h), on the C
 * reference: the table by name and an unknown name, the required ops of every row, the facts
 * run.json prints, and the driver's tableaux, reinitialisation loop and CFL step against the C
 * reference's own sweeps called by hand (bit for bit).  OpenCL against C: test_opencl.c. */
#include "tests/lsm_test.h"
#include "tests/lsm_test_pair.h"

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"
#include "solver/pde/lsm_backend.h"
#include "solver/pde/lsm_fields.h"
#include "solver/pde/lsm_reinit.h"
#include "solver/pde/lsm_scheme.h"

static void assert_same_interior(const lsm_grid *a, const lsm_grid *b) {
  for (int j = 0; j < a->ny; ++j)
    assert_memory_equal(&LSM_AT(a, 0, j), &LSM_AT(b, 0, j), (size_t)a->nx * sizeof(float));
}

/* The table: rows by name, "auto", the list of names, an unknown name refused. */
static void test_table(void **state) {
  (void)state;
  const lsm_backend_entry *c = lsm_backend_find("c");
  assert_non_null(c);
  assert_int_equal(c->host_threads, 1);
  const lsm_backend_entry *cl = lsm_backend_find("opencl");
  assert_non_null(cl);
  assert_int_equal(cl->host_threads, 0);
  assert_non_null(cl->list_devices);
  assert_null(lsm_backend_find("auto")); /* a choice among the rows, not a row */
  assert_null(lsm_backend_find("cuda"));
  assert_null(lsm_backend_find(NULL));
  char names[64];
  lsm_backend_names(names, sizeof names);
  assert_string_equal(names, "c, opencl, auto");
  lsm_backend_names(names, 5); /* truncated, still terminated */
  assert_int_equal(strlen(names), 4);

  lsm_backend *b = (lsm_backend *)1;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_backend_open("cuda", -1, 1, &b, &err), LSM_ERR_USAGE);
  assert_null(b);
  assert_non_null(strstr(err.msg, "backend 'cuda' is not one of c, opencl, auto"));
}

/* Every row has every required op; the optional particle ops come as a whole or not at all. */
static void test_required_ops(void **state) {
  (void)state;
  const char *rows[] = {"c", "opencl"};
  for (size_t r = 0; r < sizeof rows / sizeof *rows; ++r) {
    const lsm_backend_entry *e = lsm_backend_find(rows[r]);
    assert_non_null(e);
    assert_non_null(e->open);
    const lsm_backend_ops *o = e->ops;
    assert_non_null(o);
    const int required = !!o->facts + !!o->close + !!o->create + !!o->destroy +
                         !!o->fill_ghosts + !!o->copy + !!o->swap + !!o->stage + !!o->max_rate +
                         !!o->residual + !!o->reinit_sweep + !!o->read_phi + !!o->upload;
    assert_int_equal(required, 13);
    const int particles = !!o->pls_load + !!o->pls_stage + !!o->pls_correct;
    assert_true(particles == 0 || particles == 3);
  }
}

/* The C backend's facts: the run.json contract's three, in order, with its values. */
static void test_c_facts(void **state) {
  (void)state;
  lsm_backend *b = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_backend_open("c", 99, 3, &b, &err), LSM_OK); /* no devices: ignored */
  assert_string_equal(lsm_backend_name(b), "c");
  assert_string_equal(lsm_backend_fallback(b), "");
  assert_int_equal(lsm_backend_host_threads(b), 1);
  lsm_backend_fact f[LSM_BACKEND_FACTS_MAX];
  assert_int_equal(lsm_backend_facts(b, f, LSM_BACKEND_FACTS_MAX), 3);
  assert_string_equal(f[0].key, "device");
  assert_int_equal(f[0].kind, LSM_FACT_TEXT);
  assert_string_equal(f[0].text, "C (3 threads)");
  assert_string_equal(f[1].key, "build_seconds");
  assert_int_equal(f[1].kind, LSM_FACT_NUMBER);
  assert_true(f[1].number == 0.0);
  assert_string_equal(f[2].key, "kernel_cache_hit");
  assert_int_equal(f[2].kind, LSM_FACT_FLAG);
  assert_int_equal(f[2].flag, 0);
  assert_int_equal(lsm_backend_facts(b, f, 1), 1); /* no more than asked for */
  assert_string_equal(lsm_backend_device(b), "C (3 threads)");
  lsm_backend_close(&b);
  assert_null(b);
  assert_int_equal(lsm_backend_open("c", -1, 1, &b, &err), LSM_OK);
  assert_string_equal(lsm_backend_device(b), "C (1 thread)");
  lsm_backend_close(&b);
  lsm_backend_close(&b); /* a closed backend: nothing */
}

/* One step of each integrator through the driver's tableau against the Shu–Osher stages
 * called by hand on the C reference's sweeps; the CFL step; the reinitialisation loop
 * against its sweeps by hand. */
static void test_driver_by_hand(void **state) {
  (void)state;
  const int nx = 53, ny = 41;
  lsm_grid *src = new_grid(nx, ny, 0.5f, 0.75f), *dst = new_grid(nx, ny, 0.5f, 0.75f);
  lsm_grid *got = new_grid(nx, ny, 0.5f, 0.75f), *phi = new_grid(nx, ny, 0.5f, 0.75f);
  lsm_grid *s1 = new_grid(nx, ny, 0.5f, 0.75f), *s2 = new_grid(nx, ny, 0.5f, 0.75f);
  lsm_grid *phi0 = new_grid(nx, ny, 0.5f, 0.75f);
  fill_pair(src, dst);
  lsm_err err;
  lsm_err_clear(&err);
  for (int scheme = 0; scheme < LSM_SCHEME_COUNT; ++scheme) {
    lsm_fields *f = NULL;
    assert_int_equal(lsm_fields_create(NULL, src, dst, 2, &f, &err), LSM_OK);
    assert_string_equal(lsm_fields_backend_name(f), "c");
    double dt, want;
    assert_int_equal(lsm_fields_cfl_dt(f, (lsm_scheme)scheme, 0.75, &dt, &err), LSM_OK);
    lsm_grid_copy(phi, src);
    lsm_cfl_dt(phi, dst, (lsm_scheme)scheme, 0.75, 1, &want);
    assert_true(dt == want && dt > 0.0 && isfinite(dt));
    const float h = (float)dt;
    /* Euler, RK2, RK3 in turn, each on the result of the one before */
    assert_int_equal(lsm_fields_step(f, (lsm_scheme)scheme, LSM_TIME_EULER, h, &err), LSM_OK);
    lsm_scheme_stage((lsm_scheme)scheme, s1, phi, phi, dst, 0.0f, 1.0f, h, 1);
    lsm_grid_copy(phi, s1);
    assert_int_equal(lsm_fields_step(f, (lsm_scheme)scheme, LSM_TIME_RK2, h, &err), LSM_OK);
    lsm_scheme_stage((lsm_scheme)scheme, s1, phi, phi, dst, 0.0f, 1.0f, h, 1);
    lsm_scheme_stage((lsm_scheme)scheme, phi, phi, s1, dst, 0.5f, 0.5f, h, 1);
    assert_int_equal(lsm_fields_step(f, (lsm_scheme)scheme, LSM_TIME_RK3, h, &err), LSM_OK);
    lsm_scheme_stage((lsm_scheme)scheme, s1, phi, phi, dst, 0.0f, 1.0f, h, 1);
    lsm_scheme_stage((lsm_scheme)scheme, s2, phi, s1, dst, 0.75f, 0.25f, h, 1);
    lsm_scheme_stage((lsm_scheme)scheme, phi, phi, s2, dst, 1.0f / 3.0f, 2.0f / 3.0f, h, 1);
    assert_int_equal(lsm_fields_download(f, got, &err), LSM_OK);
    assert_same_interior(got, phi);
    double norm;
    assert_int_equal(lsm_fields_residual(f, &norm, &err), LSM_OK);
    assert_true(norm == lsm_grid_diff_norm(phi, dst, 1));
    /* three reinitialisation steps */
    assert_int_equal(lsm_fields_reinit(f, 3, &err), LSM_OK);
    lsm_grid_fill_ghosts(phi);
    lsm_grid_copy(phi0, phi);
    for (int it = 0; it < 3; ++it) {
      lsm_grid_fill_ghosts(phi);
      lsm_reinit_sweep(s1, phi, phi0, 1);
      lsm_grid_copy(phi, s1);
    }
    assert_int_equal(lsm_fields_download(f, got, &err), LSM_OK);
    assert_same_interior(got, phi);
    /* an upload replaces phi */
    assert_int_equal(lsm_fields_upload(f, dst, &err), LSM_OK);
    assert_int_equal(lsm_fields_residual(f, &norm, &err), LSM_OK);
    assert_true(norm == 0.0);
    assert_int_equal(lsm_fields_cfl_dt(f, (lsm_scheme)scheme, 0.75, &dt, &err), LSM_OK);
    assert_true(isinf(dt)); /* phi == phi_target: nothing moves */
    lsm_fields_destroy(&f);
    assert_null(f);
  }
  /* a grid of another size is refused by download */
  lsm_fields *f = NULL;
  lsm_grid *small = new_grid(nx - 1, ny, 0.5f, 0.75f);
  assert_int_equal(lsm_fields_create(NULL, src, dst, 1, &f, &err), LSM_OK);
  assert_int_equal(lsm_fields_download(f, small, &err), LSM_ERR_INTERNAL);
  lsm_fields_destroy(&f);
  assert_int_equal(lsm_fields_create(NULL, src, small, 1, &f, &err), LSM_ERR_INTERNAL);
  assert_null(f);
  lsm_grid *grids[] = {src, dst, got, phi, s1, s2, phi0, small};
  for (size_t k = 0; k < sizeof grids / sizeof *grids; ++k) lsm_grid_destroy(&grids[k]);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_table),
      cmocka_unit_test(test_required_ops),
      cmocka_unit_test(test_c_facts),
      cmocka_unit_test(test_driver_by_hand),
  };
  return cmocka_run_group_tests_name("test_backend", tests, NULL, NULL);
}
