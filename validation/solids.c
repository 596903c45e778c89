/* solids: full-resolution binary slices of analytic solids (validation study 3).
 *
 * Writes OUT_DIR/<solid>/001.png ... (8-bit grayscale, 255 inside) for each
 * solid, one slice per z = 0, 1, ..., SLICES - 1, on SIZE x SIZE pixels with
 * isotropic unit voxels: pixel (column x, row y) of slice n covers the point
 * (x, y, n - 1), and it is inside when that point is inside the closed solid
 * (point sampling at voxel centres: the exact rasterised truth).  Also writes
 * OUT_DIR/solids.csv: name, voxel count, analytic volume, z extent.
 *
 * With SIZE = 128 and SLICES = 129 the centre is (63.5, 63.5, 64) and every
 * 4th, 8th and 16th slice (the 1st, K+1-th, ...) includes the last one.
 *
 *  ball       radius 40
 *  ellipsoid  semi-axes 50, 30, 40 (x, y, z), tilted 30 degrees about the y
 *             axis, so its cross-sections drift sideways from slice to slice
 *  cone       vertical axis, flat base of radius 44 at z = 20, apex at z = 116
 *  torus      major radius 36, minor 14, axis along y (perpendicular to the
 *             slice normal): sections are two blobs for |z - 64| < 22 and one
 *             ring-like blob beyond (a topology change in every sampling)
 *  two-balls  radius 30, centres at the centre -+ (21, 0, 21): 59.4 apart, so
 *             they just touch; sections: one disc, then two, then one
 *
 * Usage: solids OUT_DIR [--size N] [--slices M]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/lsm_io.h"
#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_status.h"

#define PI 3.14159265358979323846

typedef enum solid_kind { BALL, ELLIPSOID, CONE, TORUS, TWO_BALLS, SOLID_COUNT } solid_kind;

static const char *const k_names[SOLID_COUNT] = {"ball", "ellipsoid", "cone", "torus",
                                                 "two-balls"};

typedef struct frame3 {
  double cx, cy, cz;
} frame3;

/* 1 when the point (x, y, z) is inside the closed solid. */
static int inside(solid_kind kind, const frame3 *c, double x, double y, double z) {
  const double dx = x - c->cx, dy = y - c->cy, dz = z - c->cz;
  switch (kind) {
  case BALL:
    return dx * dx + dy * dy + dz * dz <= 40.0 * 40.0;
  case ELLIPSOID: {
    const double th = PI / 6.0, u = cos(th) * dx + sin(th) * dz, w = -sin(th) * dx + cos(th) * dz;
    return (u / 50.0) * (u / 50.0) + (dy / 30.0) * (dy / 30.0) + (w / 40.0) * (w / 40.0) <= 1.0;
  }
  case CONE: {
    if (z < 20.0 || z > 116.0) return 0;
    const double r = 44.0 * (116.0 - z) / 96.0;
    return dx * dx + dy * dy <= r * r;
  }
  case TORUS: {
    const double q = hypot(dx, dz) - 36.0;
    return q * q + dy * dy <= 14.0 * 14.0;
  }
  case TWO_BALLS: {
    const double r2 = 30.0 * 30.0;
    const double ax = dx + 21.0, az = dz + 21.0, bx = dx - 21.0, bz = dz - 21.0;
    return ax * ax + dy * dy + az * az <= r2 || bx * bx + dy * dy + bz * bz <= r2;
  }
  default:
    return 0;
  }
}

static double analytic_volume(solid_kind kind) {
  switch (kind) {
  case BALL:
    return 4.0 / 3.0 * PI * 40.0 * 40.0 * 40.0;
  case ELLIPSOID:
    return 4.0 / 3.0 * PI * 50.0 * 30.0 * 40.0;
  case CONE:
    return PI * 44.0 * 44.0 * 96.0 / 3.0;
  case TORUS:
    return 2.0 * PI * PI * 36.0 * 14.0 * 14.0;
  case TWO_BALLS: {
    /* Two balls of radius r at distance d < 2r overlap in a lens of volume
     * pi (2r - d)^2 (d^2 + 4 d r) / (12 d). */
    const double r = 30.0, d = sqrt(2.0) * 42.0;
    const double lens = d < 2 * r ? PI * (2 * r - d) * (2 * r - d) * (d * d + 4 * d * r) / (12 * d) : 0;
    return 2.0 * 4.0 / 3.0 * PI * r * r * r - lens;
  }
  default:
    return 0;
  }
}

static lsm_status write_solid(const char *out_dir, solid_kind kind, int size, int slices,
                              FILE *summary, lsm_err *err) {
  char dir[4200];
  snprintf(dir, sizeof dir, "%s/%s", out_dir, k_names[kind]);
  LSM_TRY(lsm_make_dir(dir, err));
  lsm_mask m;
  LSM_TRY(lsm_mask_create(size, size, &m, err));
  const frame3 c = {0.5 * (size - 1), 0.5 * (size - 1), 0.5 * (slices - 1)};
  long long voxels = 0;
  int zmin = -1, zmax = -1;
  lsm_status st = LSM_OK;
  for (int n = 0; st == LSM_OK && n < slices; ++n) {
    size_t count = 0;
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        uint8_t v = (uint8_t)inside(kind, &c, x, y, n);
        m.pixels[(size_t)y * size + x] = v;
        count += v;
      }
    if (count) {
      if (zmin < 0) zmin = n;
      zmax = n;
    }
    voxels += (long long)count;
    char path[4300];
    snprintf(path, sizeof path, "%s/%03d.png", dir, n + 1);
    st = lsm_png_write_mask(path, &m, err);
  }
  lsm_mask_free(&m);
  if (st == LSM_OK) {
    fprintf(summary, "%s,%lld,%.6f,%d,%d\n", k_names[kind], voxels, analytic_volume(kind), zmin + 1,
            zmax + 1);
    if (ferror(summary)) st = lsm_fail(err, LSM_ERR_IO, NULL, "write failed");
  }
  return st;
}

int main(int argc, char **argv) {
  const char *out = NULL;
  int size = 128, slices = 129;
  for (int k = 1; k < argc; ++k) {
    if (strcmp(argv[k], "--size") == 0 && k + 1 < argc)
      size = atoi(argv[++k]);
    else if (strcmp(argv[k], "--slices") == 0 && k + 1 < argc)
      slices = atoi(argv[++k]);
    else if (argv[k][0] != '-' && !out)
      out = argv[k];
    else
      out = NULL, k = argc;
  }
  if (!out || size < 8 || size > 8192 || slices < 2 || slices > 8192) {
    fprintf(stderr, "usage: solids OUT_DIR [--size N] [--slices M]\n");
    return 2;
  }
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = lsm_make_dir(out, &err);
  char path[4200];
  snprintf(path, sizeof path, "%s/solids.csv", out);
  FILE *summary = st == LSM_OK ? fopen(path, "w") : NULL;
  if (st == LSM_OK && !summary) st = lsm_fail(&err, LSM_ERR_IO, path, "cannot create");
  if (st == LSM_OK) fprintf(summary, "solid,voxels,analytic_volume,first_slice,last_slice\n");
  for (int k = 0; st == LSM_OK && k < SOLID_COUNT; ++k)
    st = write_solid(out, (solid_kind)k, size, slices, summary, &err);
  if (summary) {
    int bad = ferror(summary);
    if ((fclose(summary) != 0 || bad) && st == LSM_OK)
      st = lsm_fail(&err, LSM_ERR_IO, path, "write failed");
  }
  if (st != LSM_OK) {
    fprintf(stderr, "solids: error: %s\n", err.msg[0] ? err.msg : lsm_status_name(st));
    return 1;
  }
  return 0;
}
