/* morphacc: morph accuracy at convergence (validation study 2), in the style
 * of OpenVDB's level-set morph test.
 *
 * For each shape pair the morph phi_t + (phi - phi_T)|grad phi| = 0 runs from
 * phi_source until it has converged (CP, the change of ||phi - phi_T||_2 per
 * step, below 1e-6 px times sqrt(cells), i.e. an RMS change under 1e-6 px per
 * step) or t reaches T_MAX, and then measures |phi - phi_T| on the band
 * |phi_T| <= 2 px around the target front: max and mean.  Targets (the
 * validation brief's): max <= 0.5 px, mean <= 0.02 px.
 *
 * Pairs: a disc moving to an offset disc (analytic SDFs on 128 x 128, dx = 1)
 * and the consecutive slices of the document's synthetic sets (outline PNGs
 * from gen_synthetic, signed distance by lsm_sdf_from_outline, as the stack
 * builds them; the sets are centred so no alignment is needed).
 *
 * The band error is also recorded along the way (history) and at the first
 * step where the document's stopping rule CP <= 0.25 holds.
 *
 * Usage: morphacc SYNTH_DIR OUT_DIR [--threads T] [--quick]
 * Writes OUT_DIR/morph_accuracy.csv and OUT_DIR/morph_history.csv.
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/lsm_io.h"
#include "solver/base/lsm_grid.h"
#include "solver/pde/lsm_morph.h"
#include "solver/pde/lsm_scheme.h"
#include "solver/sdf/lsm_sdf.h"
#include "solver/base/lsm_status.h"
#include "validation/vcsv.h"

#define BAND 2.0
#define T_MAX 60.0
#define MAX_STEPS 200000
#define DOC_TOL 0.25

typedef struct band_error {
  double max, mean;
  long cells;
  int max_i, max_j;
} band_error;

static band_error measure_band(const lsm_grid *phi, const lsm_grid *target) {
  band_error e = {0.0, 0.0, 0, -1, -1};
  for (int j = 0; j < phi->ny; ++j)
    for (int i = 0; i < phi->nx; ++i) {
      const double t = LSM_AT(target, i, j);
      if (fabs(t) > BAND) continue;
      const double d = fabs((double)LSM_AT(phi, i, j) - t);
      e.mean += d;
      e.cells++;
      if (d > e.max) {
        e.max = d;
        e.max_i = i;
        e.max_j = j;
      }
    }
  if (e.cells) e.mean /= (double)e.cells;
  return e;
}

static lsm_status disc_field(int n, double cx, double cy, double r, lsm_grid **out,
                             lsm_err *err) {
  LSM_TRY(lsm_grid_create(n, n, 1.0f, 1.0f, out, err));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) LSM_AT(*out, i, j) = (float)(hypot(i - cx, j - cy) - r);
  return LSM_OK;
}

static lsm_status outline_field(const char *dir, const char *set, int index, lsm_grid **out,
                                lsm_err *err) {
  char path[4200];
  snprintf(path, sizeof path, "%s/%s/%03d.png", dir, set, index);
  lsm_image_read_opts ro = {0, (uint64_t)1 << 28, 0};
  lsm_mask m = {0, 0, NULL};
  LSM_TRY(lsm_slice_read_mask(path, &ro, &m, err));
  lsm_status st = lsm_grid_create(m.width, m.height, 1.0f, 1.0f, out, err);
  if (st == LSM_OK) st = lsm_sdf_from_outline(&m, *out, err);
  lsm_mask_free(&m);
  return st;
}

typedef struct pair_case {
  char name[64];
  const char *set; /* NULL: the analytic disc pair */
  int a, b;
} pair_case;

static lsm_status run_pair(const pair_case *c, const char *synth, lsm_scheme scheme,
                           lsm_time time, int threads, FILE *facc, FILE *fhist, lsm_err *err) {
  lsm_grid *pa = NULL, *pb = NULL;
  lsm_morph *m = NULL;
  lsm_status st;
  if (c->set) {
    st = outline_field(synth, c->set, c->a, &pa, err);
    if (st == LSM_OK) st = outline_field(synth, c->set, c->b, &pb, err);
  } else {
    st = disc_field(128, 48.0, 64.0, 20.0, &pa, err);
    if (st == LSM_OK) st = disc_field(128, 76.0, 58.0, 16.0, &pb, err);
  }
  lsm_morph_opts mo;
  lsm_morph_opts_default(&mo);
  mo.scheme = scheme;
  mo.time = time;
  mo.threads = threads;
  if (st == LSM_OK) st = lsm_morph_create(pa, pb, &mo, &m, err);
  if (st != LSM_OK) goto done;
  const double tol = 1e-6 * sqrt((double)pa->nx * (double)pa->ny);
  const char *sn = lsm_scheme_name(scheme), *tn = lsm_time_name(time);
  band_error e0 = measure_band(pa, pb), doc = {NAN, NAN, 0, -1, -1};
  double t_doc = NAN;
  int it_doc = -1;
  fprintf(fhist, "%s,%s,%s,0,0,%.8g,%.8g,\n", c->name, sn, tn, e0.max, e0.mean);
  double next_log = 0.125;
  while (st == LSM_OK) {
    st = lsm_morph_step(m, INFINITY, err);
    if (st != LSM_OK) break;
    const double t = lsm_morph_time(m), cp = lsm_morph_cp(m);
    if (it_doc < 0 && cp <= DOC_TOL) {
      doc = measure_band(lsm_morph_phi(m), pb);
      t_doc = t;
      it_doc = lsm_morph_iterations(m);
    }
    const int done = cp <= tol || t >= T_MAX || lsm_morph_iterations(m) >= MAX_STEPS;
    if (t >= next_log || done) {
      band_error e = measure_band(lsm_morph_phi(m), pb);
      fprintf(fhist, "%s,%s,%s,%.8g,%d,%.8g,%.8g,%.8g\n", c->name, sn, tn, t,
              lsm_morph_iterations(m), e.max, e.mean, cp);
      while (next_log <= t) next_log *= 1.25;
    }
    if (done) break;
  }
  if (st == LSM_OK) {
    band_error e = measure_band(lsm_morph_phi(m), pb);
    const int pass = e.max <= 0.5 && e.mean <= 0.02;
    fprintf(facc,
            "%s,%s,%s,%d,%d,%.8g,%d,%.8g,%.8g,%ld,%.8g,%.8g,%d,%d,%.6g,%.8g,%.8g,%d,%.8g,%.8g,%.8g,%d\n",
            c->name, sn, tn, pa->nx, pa->ny, lsm_morph_dt(m), lsm_morph_iterations(m),
            lsm_morph_time(m), lsm_morph_cp(m), e.cells, e.max, e.mean, e.max_i, e.max_j,
            (double)LSM_AT(pb, e.max_i < 0 ? 0 : e.max_i, e.max_j < 0 ? 0 : e.max_j), e0.max,
            e0.mean, it_doc, t_doc, doc.max, doc.mean, pass);
    fprintf(stderr, "morphacc: %-16s %-7s %-5s %6d steps t=%6.2f  band max %.4g mean %.4g  %s\n",
            c->name, sn, tn, lsm_morph_iterations(m), lsm_morph_time(m), e.max, e.mean,
            pass ? "pass" : "FAIL");
    if (ferror(facc) || ferror(fhist)) st = lsm_fail(err, LSM_ERR_IO, NULL, "write failed");
  }
done:
  lsm_morph_destroy(&m);
  lsm_grid_destroy(&pa);
  lsm_grid_destroy(&pb);
  return st;
}

int main(int argc, char **argv) {
  const char *synth = NULL, *out = NULL;
  int threads = omp_get_num_procs(), quick = 0;
  for (int k = 1; k < argc; ++k) {
    if (strcmp(argv[k], "--threads") == 0 && k + 1 < argc) {
      threads = atoi(argv[++k]);
    } else if (strcmp(argv[k], "--quick") == 0) {
      quick = 1;
    } else if (argv[k][0] != '-' && !synth) {
      synth = argv[k];
    } else if (argv[k][0] != '-' && !out) {
      out = argv[k];
    } else {
      synth = NULL;
      break;
    }
  }
  if (!synth || !out || threads < 1) {
    fprintf(stderr, "usage: morphacc SYNTH_DIR OUT_DIR [--threads T] [--quick]\n");
    return 2;
  }
  pair_case cases[16];
  int n = 0;
  memset(cases, 0, sizeof cases);
  snprintf(cases[n].name, sizeof cases[n].name, "disc-offset");
  n++;
  const struct {
    const char *set;
    int slices;
  } sets[3] = {{"pyramid", 7}, {"candlestick", 4}, {"vase", 3}};
  for (int s = 0; s < 3; ++s)
    for (int a = 1; a < sets[s].slices; ++a) {
      snprintf(cases[n].name, sizeof cases[n].name, "%s-%d-%d", sets[s].set, a, a + 1);
      cases[n].set = sets[s].set;
      cases[n].a = a;
      cases[n].b = a + 1;
      n++;
    }
  const struct {
    lsm_scheme scheme;
    lsm_time time;
  } combos[4] = {{LSM_SCHEME_UPWIND, LSM_TIME_EULER},
                 {LSM_SCHEME_UPWIND, LSM_TIME_RK3},
                 {LSM_SCHEME_ROEFIX, LSM_TIME_EULER},
                 {LSM_SCHEME_ROEFIX, LSM_TIME_RK3}};
  lsm_err err;
  lsm_err_clear(&err);
  FILE *facc = open_csv(out, "morph_accuracy.csv",
                        "case,scheme,time,nx,ny,dt,iterations,t_final,cp_final,band_cells,"
                        "band_max,band_mean,max_i,max_j,max_phi_target,initial_max,initial_mean,"
                        "doc_iterations,doc_t,doc_band_max,doc_band_mean,pass",
                        &err);
  FILE *fhist = facc ? open_csv(out, "morph_history.csv",
                                "case,scheme,time,t,iterations,band_max,band_mean,cp", &err)
                     : NULL;
  lsm_status st = facc && fhist ? LSM_OK : LSM_ERR_IO;
  for (int k = 0; st == LSM_OK && k < (quick ? 1 : 4); ++k)
    for (int c = 0; st == LSM_OK && c < n; ++c)
      st = run_pair(&cases[c], synth, combos[k].scheme, combos[k].time, threads, facc, fhist, &err);
  st = close_csv(facc, st, &err);
  st = close_csv(fhist, st, &err);
  if (st != LSM_OK) {
    fprintf(stderr, "morphacc: error: %s\n", err.msg[0] ? err.msg : lsm_status_name(st));
    return 1;
  }
  return 0;
}
