/* convergence: grid convergence of the morph solver (validation study 1).
 *
 * Runs lsm_morph directly on analytic signed distance functions, with no PNG
 * in between, on the fixed physical domain [-32, 32]^2 with N x N cells
 * (dx = 64 / N, cell centres at -32 + (i + 1/2) dx).
 *
 *  circles   phi_0 = |x| - r1, phi_T = |x| - r2.  While phi stays a signed
 *            distance function the morph is phi(t) = phi_T + (phi_0 - phi_T) e^-t,
 *            so the front radius is exactly r(t) = r2 + (r1 - r2) e^-t
 *            (solver/README.md §2).  Error: |r_front - r(t)| over every zero crossing
 *            found by linear interpolation along the grid rows and columns;
 *            L1 = mean, Linf = max.  Cases "shrink" (20 -> 10) and "grow" (10 -> 20).
 *  squares   concentric axis-aligned squares, half-side 20 -> 10, exact
 *            Euclidean SDFs (rounded outside the corners).  Measured: the
 *            zero-level position on the x axis (bilinear sample of the line y = 0),
 *            on the diagonal (cells (i, i) lie on it) and the area of {phi < 0}
 *            (cells split into two triangles, phi linear on each).  The
 *            reference is a Richardson extrapolation done by the report script.
 *            On the axis, away from the corners, both SDFs are distances to
 *            parallel faces, so the axis position also has the exact value
 *            10 + 10 e^-t.
 *
 * Usage: convergence OUT_DIR [--max-n N] [--roefix-max-n N] [--threads T]
 * Writes OUT_DIR/convergence_circles.csv and OUT_DIR/convergence_squares.csv.
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "solver/base/lsm_grid.h"
#include "solver/pde/lsm_morph.h"
#include "solver/pde/lsm_scheme.h"
#include "solver/base/lsm_status.h"
#include "validation/vcsv.h"

#define DOMAIN_HALF 32.0
#define N_TIMES 3

static const double k_times[N_TIMES] = {0.5, 1.0, 2.0};

typedef struct options {
  const char *out_dir;
  int max_n, roefix_max_n, threads;
} options;

typedef struct front_error {
  double l1, linf;
  long count;
} front_error;

typedef struct square_measure {
  double axis, diag, area;
} square_measure;

static double wall_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double centre(int i, double h) { return -DOMAIN_HALF + ((double)i + 0.5) * h; }

static double sdf_circle(double x, double y, double r) { return hypot(x, y) - r; }

/* Exact Euclidean signed distance of the square |x|, |y| <= a. */
static double sdf_square(double x, double y, double a) {
  double qx = fabs(x) - a, qy = fabs(y) - a;
  double ox = qx > 0 ? qx : 0, oy = qy > 0 ? qy : 0;
  double in = qx > qy ? qx : qy;
  return hypot(ox, oy) + (in < 0 ? in : 0);
}

static lsm_status make_field(int n, int square, double size, lsm_grid **out, lsm_err *err) {
  const double h = 2.0 * DOMAIN_HALF / n;
  LSM_TRY(lsm_grid_create(n, n, (float)h, (float)h, out, err));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      double x = centre(i, h), y = centre(j, h);
      LSM_AT(*out, i, j) = (float)(square ? sdf_square(x, y, size) : sdf_circle(x, y, size));
    }
  return LSM_OK;
}

static void add_crossing(front_error *e, double x, double y, double r_exact) {
  double d = fabs(hypot(x, y) - r_exact);
  e->l1 += d;
  if (d > e->linf) e->linf = d;
  e->count++;
}

/* Zero crossings between neighbouring cells along rows and columns. */
static front_error circle_error(const lsm_grid *phi, double r_exact) {
  front_error e = {0.0, 0.0, 0};
  const double h = phi->dx;
  for (int j = 0; j < phi->ny; ++j)
    for (int i = 0; i < phi->nx; ++i) {
      const double a = LSM_AT(phi, i, j), x = centre(i, h), y = centre(j, h);
      if (a == 0.0) {
        add_crossing(&e, x, y, r_exact);
        continue;
      }
      if (i + 1 < phi->nx) {
        const double b = LSM_AT(phi, i + 1, j);
        if (a * b < 0.0) add_crossing(&e, x + h * a / (a - b), y, r_exact);
      }
      if (j + 1 < phi->ny) {
        const double b = LSM_AT(phi, i, j + 1);
        if (a * b < 0.0) add_crossing(&e, x, y + h * a / (a - b), r_exact);
      }
    }
  if (e.count) e.l1 /= (double)e.count;
  return e;
}

/* Area of {f < 0} in a triangle of area A with linear f and vertex values f. */
static double tri_negative_area(double A, double f0, double f1, double f2) {
  const double f[3] = {f0, f1, f2};
  int neg = (f0 < 0) + (f1 < 0) + (f2 < 0);
  if (neg == 0) return 0.0;
  if (neg == 3) return A;
  /* The lone vertex: the negative one when neg == 1, the other one when neg == 2. */
  int lone = 0;
  for (int k = 0; k < 3; ++k)
    if ((f[k] < 0) == (neg == 1)) lone = k;
  const double a = f[lone], b = f[(lone + 1) % 3], c = f[(lone + 2) % 3];
  const double corner = A * (a / (a - b)) * (a / (a - c));
  return neg == 1 ? corner : A - corner;
}

static square_measure square_measures(const lsm_grid *phi) {
  square_measure m = {NAN, NAN, 0.0};
  const int n = phi->nx;
  const double h = phi->dx;
  /* Axis: the line y = 0 lies halfway between rows n/2 - 1 and n/2. */
  for (int i = n / 2; i + 1 < n; ++i) {
    double a = 0.5 * ((double)LSM_AT(phi, i, n / 2 - 1) + (double)LSM_AT(phi, i, n / 2));
    double b = 0.5 * ((double)LSM_AT(phi, i + 1, n / 2 - 1) + (double)LSM_AT(phi, i + 1, n / 2));
    if (a < 0.0 && b >= 0.0) {
      m.axis = centre(i, h) + h * a / (a - b);
      break;
    }
  }
  /* Diagonal: cells (i, i); reported as the x coordinate of the crossing. */
  for (int i = n / 2; i + 1 < n; ++i) {
    double a = LSM_AT(phi, i, i), b = LSM_AT(phi, i + 1, i + 1);
    if (a < 0.0 && b >= 0.0) {
      m.diag = centre(i, h) + h * a / (a - b);
      break;
    }
  }
  const double A = 0.5 * h * h;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      double f00 = LSM_AT(phi, i, j), f10 = LSM_AT(phi, i + 1, j);
      double f01 = LSM_AT(phi, i, j + 1), f11 = LSM_AT(phi, i + 1, j + 1);
      m.area += tri_negative_area(A, f00, f10, f11) + tri_negative_area(A, f00, f11, f01);
    }
  return m;
}

typedef struct run_case {
  const char *name;
  int square;
  double size0, size1; /* radius or half-side: source, target */
} run_case;

static lsm_status run_one(const run_case *c, lsm_scheme scheme, lsm_time time, int n,
                          int threads, FILE *out, lsm_err *err) {
  lsm_grid *p0 = NULL, *pt = NULL;
  lsm_morph *m = NULL;
  lsm_morph_opts mo;
  lsm_morph_opts_default(&mo);
  mo.scheme = scheme;
  mo.time = time;
  mo.threads = threads;
  lsm_status st = make_field(n, c->square, c->size0, &p0, err);
  if (st == LSM_OK) st = make_field(n, c->square, c->size1, &pt, err);
  if (st == LSM_OK) st = lsm_morph_create(p0, pt, &mo, &m, err);
  const double start = wall_seconds();
  for (int k = 0; st == LSM_OK && k < N_TIMES; ++k) {
    st = lsm_morph_advance_to(m, k_times[k], 100000000, err);
    if (st != LSM_OK) break;
    if (fabs(lsm_morph_time(m) - k_times[k]) > 1e-9) {
      st = lsm_fail(err, LSM_ERR_INTERNAL, c->name, "did not reach t = %g", k_times[k]);
      break;
    }
    const double secs = wall_seconds() - start;
    const lsm_grid *phi = lsm_morph_phi(m);
    const double h = phi->dx;
    if (c->square) {
      square_measure q = square_measures(phi);
      fprintf(out, "%s,%s,%s,%d,%.10g,%g,%.10g,%.10g,%.10g,%d,%.10g,%.4f\n", c->name,
              lsm_scheme_name(scheme), lsm_time_name(time), n, h, k_times[k], q.axis, q.diag,
              q.area, lsm_morph_iterations(m), lsm_morph_dt(m), secs);
    } else {
      const double r = c->size1 + (c->size0 - c->size1) * exp(-k_times[k]);
      front_error e = circle_error(phi, r);
      /* the measurement's own error: the same crossings of the exact SDF of
       * radius r, stored in float on this grid (linear interpolation between
       * cells is second order: a floor under any scheme's error) */
      lsm_grid *exact = NULL;
      st = make_field(n, 0, r, &exact, err);
      if (st != LSM_OK) break;
      const front_error floor = circle_error(exact, r);
      /* and the error of phi itself near the front, where it stays the
       * exact SDF |x| - r (the speed is uniform): no interpolation */
      double band = 0.0;
      long band_cells = 0;
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const double want = hypot(centre(i, h), centre(j, h)) - r;
          if (fabs(want) > 2.0 * h) continue;
          band += fabs((double)LSM_AT(phi, i, j) - want);
          ++band_cells;
        }
      if (band_cells) band /= (double)band_cells;
      lsm_grid_destroy(&exact);
      fprintf(out, "%s,%s,%s,%d,%.10g,%g,%.10g,%.10g,%.10g,%ld,%d,%.10g,%.4f,%.10g,%.10g\n",
              c->name, lsm_scheme_name(scheme), lsm_time_name(time), n, h, k_times[k], r, e.l1,
              e.linf, e.count, lsm_morph_iterations(m), lsm_morph_dt(m), secs, floor.l1, band);
    }
    if (ferror(out)) st = lsm_fail(err, LSM_ERR_IO, NULL, "write failed");
  }
  if (st == LSM_OK) {
    fprintf(stderr, "convergence: %-13s %-7s %-5s N=%4d  %6d steps  %7.2f s\n", c->name,
            lsm_scheme_name(scheme), lsm_time_name(time), n, lsm_morph_iterations(m),
            wall_seconds() - start);
    fflush(out);
  }
  lsm_morph_destroy(&m);
  lsm_grid_destroy(&p0);
  lsm_grid_destroy(&pt);
  return st;
}

static int parse_int(const char *s, int *v) {
  char *end = NULL;
  long x = strtol(s, &end, 10);
  if (!end || *end || x < 1 || x > 1 << 20) return 0;
  *v = (int)x;
  return 1;
}

static int parse_args(int argc, char **argv, options *o) {
  o->out_dir = NULL;
  o->max_n = 1024;
  o->roefix_max_n = 512;
  o->threads = omp_get_num_procs();
  for (int k = 1; k < argc; ++k) {
    if (strcmp(argv[k], "--max-n") == 0 && k + 1 < argc) {
      if (!parse_int(argv[++k], &o->max_n)) return 0;
    } else if (strcmp(argv[k], "--roefix-max-n") == 0 && k + 1 < argc) {
      if (!parse_int(argv[++k], &o->roefix_max_n)) return 0;
    } else if (strcmp(argv[k], "--threads") == 0 && k + 1 < argc) {
      if (!parse_int(argv[++k], &o->threads)) return 0;
    } else if (argv[k][0] != '-' && !o->out_dir) {
      o->out_dir = argv[k];
    } else {
      return 0;
    }
  }
  return o->out_dir != NULL;
}

int main(int argc, char **argv) {
  options o;
  if (!parse_args(argc, argv, &o)) {
    fprintf(stderr, "usage: convergence OUT_DIR [--max-n N] [--roefix-max-n N] [--threads T]\n");
    return 2;
  }
  lsm_err err;
  lsm_err_clear(&err);
  const run_case circles[2] = {{"circle-shrink", 0, 20.0, 10.0}, {"circle-grow", 0, 10.0, 20.0}};
  const run_case square = {"square-shrink", 1, 20.0, 10.0};
  FILE *fc = open_csv(o.out_dir, "convergence_circles.csv",
                      "case,scheme,time,N,dx,t,r_exact,l1,linf,crossings,steps,dt,seconds,l1_measure,"
                      "band_l1",
                      &err);
  FILE *fs = fc ? open_csv(o.out_dir, "convergence_squares.csv",
                           "case,scheme,time,N,dx,t,axis,diag,area,steps,dt,seconds", &err)
                : NULL;
  lsm_status st = fc && fs ? LSM_OK : LSM_ERR_IO;
  for (int s = 0; st == LSM_OK && s < LSM_SCHEME_COUNT; ++s)
    for (int t = 0; st == LSM_OK && t < LSM_TIME_COUNT; ++t) {
      const int nmax = s == LSM_SCHEME_ROEFIX ? o.roefix_max_n : o.max_n;
      for (int n = 32; st == LSM_OK && n <= nmax; n *= 2) {
        for (int c = 0; st == LSM_OK && c < 2; ++c)
          st = run_one(&circles[c], (lsm_scheme)s, (lsm_time)t, n, o.threads, fc, &err);
        if (st == LSM_OK) st = run_one(&square, (lsm_scheme)s, (lsm_time)t, n, o.threads, fs, &err);
      }
    }
  st = close_csv(fc, st, &err);
  st = close_csv(fs, st, &err);
  if (st != LSM_OK) {
    fprintf(stderr, "convergence: error: %s\n", err.msg[0] ? err.msg : lsm_status_name(st));
    return 1;
  }
  return 0;
}
