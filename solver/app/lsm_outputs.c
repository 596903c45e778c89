#include "solver/app/lsm_outputs.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "solver/app/lsm_signals.h"

size_t lsm_output_file_names(const lsm_cli *cli, const char **names, size_t cap) {
  const char *vol[8];
  size_t nv = lsm_volume_file_names(cli->formats, vol, 8);
  size_t n = 0;
#define ADD(name)                  \
  do {                             \
    if (n < cap) names[n] = name;  \
    n++;                           \
  } while (0)
  for (size_t k = 0; k < nv && k < 8; ++k) ADD(vol[k]);
  ADD("heights.txt");
  if (cli->write_slices) ADD("slices/");
  if (cli->mesh) ADD("surface.ply");
  if (cli->preview) {
    ADD("preview.png");
    ADD("preview3d.png");
  }
  ADD("run.json");
#undef ADD
  return n;
}

size_t lsm_output_known_names(const char **names, size_t cap) {
  lsm_cli all;
  memset(&all, 0, sizeof all);
  all.formats = LSM_FORMAT_ALL;
  all.write_slices = all.mesh = all.preview = 1;
  return lsm_output_file_names(&all, names, cap);
}

double lsm_outputs_mean_step(const lsm_outputs *o) {
  return o->count > 1 ? (o->z_last - o->z_first) / (double)(o->count - 1) : 0.0;
}

int lsm_outputs_evenly_spaced(const lsm_outputs *o) {
  return o->count <= 2 || o->step_max - o->step_min <= 1e-6 * fabs(o->step_max);
}

lsm_status lsm_outputs_open(lsm_outputs *o, const lsm_cli *cli, const char *dir, int width,
                            int height, double z0, lsm_err *err) {
  memset(o, 0, sizeof *o);
  o->mask = malloc((size_t)width * (size_t)height);
  if (!o->mask) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the run");
  snprintf(o->dir, sizeof o->dir, "%s", dir);
  o->write_slices = cli->write_slices;
  o->max_voxels = cli->max_voxels;
  o->input = cli->slice_dir;
  o->per_iteration = cli->stack.per_iteration;
  o->dz = lsm_stack_output_dz(&cli->stack);
  const double pixel_dx = cli->stack.pixel_dx, pixel_dy = cli->stack.pixel_dy;
  /* --nrrd-encoding gzip: the writer's gzip NRRD in place of the raw one */
  const unsigned formats = cli->nrrd_encoding == LSM_NRRD_GZIP && (cli->formats & LSM_FORMAT_NRRD)
                               ? (cli->formats & ~LSM_FORMAT_NRRD) | LSM_FORMAT_NRRD_GZ
                               : cli->formats;
  LSM_TRY(lsm_volume_writer_open(dir, formats, cli->values, width, height, pixel_dx,
                                 pixel_dy, o->dz, 0.0, 0.0, z0, &o->volume, err));
  /* the mesh caps an object cut by the first or last slice half a step beyond
   * it: dz, or with --per-iteration (uneven heights) the step to the
   * neighbouring slice */
  if (cli->mesh)
    LSM_TRY(lsm_mesh_open(width, height, pixel_dx, pixel_dy, o->per_iteration ? 0.0 : o->dz,
                          dir, &o->mesh, err));
  if (cli->preview)
    LSM_TRY(lsm_preview_open(width, height, pixel_dx, pixel_dy, o->dz, &o->preview, err));
  char path[4200];
  snprintf(path, sizeof path, "%s/heights.txt", dir);
  o->heights = fopen(path, "w");
  if (!o->heights) return lsm_fail(err, LSM_ERR_IO, path, "cannot create: %s", strerror(errno));
  if (o->write_slices) {
    snprintf(path, sizeof path, "%s/slices", dir);
    LSM_TRY(lsm_make_dir(path, err));
  }
  return LSM_OK;
}

static lsm_status outputs_emit(void *ctx, const float *phi, int width, int height, double z,
                               long input_index, lsm_err *err) {
  lsm_outputs *s = ctx;
  /* the slice count of --per-iteration is not known ahead: its volume is held
   * to --max-voxels as it grows (any other run was checked before it began) */
  if ((double)(s->count + 1) * (double)width * (double)height > (double)s->max_voxels)
    return lsm_fail(err, LSM_ERR_LIMIT, s->input,
                    "%zu output slices of %dx%d written; one more would pass --max-voxels %llu "
                    "(with --per-iteration every solver step is a slice: raise --tol, lower "
                    "--max-iter or raise --max-voxels)",
                    s->count, width, height, (unsigned long long)s->max_voxels);
  /* the mesh and the previews need increasing heights: a repeated one adds nothing */
  const int higher = s->count == 0 || z > s->z_last;
  LSM_TRY(lsm_volume_writer_write_slice(s->volume, phi, z, err));
  if (s->mesh && higher) LSM_TRY(lsm_mesh_add_slice(s->mesh, phi, z, err));
  if (s->preview && higher) LSM_TRY(lsm_preview_add_slice(s->preview, phi, z, input_index, err));
  char z_text[40]; /* the shortest form that reads back as z: 0.8, not 0.80000000000000004 */
  lsm_shortest_number(z_text, sizeof z_text, z);
  if (fprintf(s->heights, "%s\n", z_text) < 0)
    return lsm_fail(err, LSM_ERR_IO, NULL, "%s/heights.txt: write failed: %s", s->dir,
                    strerror(errno));
  if (s->count == 0) {
    s->z_first = z;
  } else {
    const double step = z - s->z_last;
    if (s->count == 1 || step < s->step_min) s->step_min = step;
    if (s->count == 1 || step > s->step_max) s->step_max = step;
  }
  s->z_last = z;
  s->count++;
  if (s->write_slices) {
    const size_t n = (size_t)width * (size_t)height;
    for (size_t k = 0; k < n; ++k) s->mask[k] = phi[k] <= 0.0f ? 255 : 0;
    char path[4200];
    snprintf(path, sizeof path, "%s/slices/%05zu.png", s->dir, s->count);
    LSM_TRY(lsm_png_write_gray8(path, s->mask, width, height, err));
  }
  return LSM_OK;
}

lsm_slice_sink lsm_outputs_sink(lsm_outputs *o) {
  lsm_slice_sink sink = {o, outputs_emit};
  return sink;
}

lsm_status lsm_outputs_finish(lsm_outputs *o, lsm_status st, lsm_err *err) {
  if (st == LSM_OK) {
    /* uneven --per-iteration heights: the volume files hold their mean step */
    const double sz = o->per_iteration && o->count > 1 ? lsm_outputs_mean_step(o) : o->dz;
    st = lsm_volume_writer_finish(&o->volume, sz, o->count, err);
  }
  /* the mesh and the previews take a while on large runs: a stop signal first */
  if (st == LSM_OK && (o->mesh || o->preview)) st = lsm_signals_check(err);
  if (st == LSM_OK && o->mesh) {
    char path[4200];
    snprintf(path, sizeof path, "%s/surface.ply", o->dir);
    st = lsm_mesh_close(o->mesh, err);
    if (st == LSM_OK) st = lsm_mesh_write_ply(o->mesh, path, err);
  }
  lsm_mesh_free(&o->mesh);
  if (st == LSM_OK && o->preview) st = lsm_signals_check(err);
  if (st == LSM_OK && o->preview) {
    char montage[4200], render[4200];
    snprintf(montage, sizeof montage, "%s/preview.png", o->dir);
    snprintf(render, sizeof render, "%s/preview3d.png", o->dir);
    st = lsm_preview_write(o->preview, montage, render, err);
  }
  lsm_preview_free(&o->preview);
  if (o->heights) {
    int bad = ferror(o->heights);
    if ((fclose(o->heights) != 0 || bad) && st == LSM_OK)
      st = lsm_fail(err, LSM_ERR_IO, NULL, "%s/heights.txt: write failed: %s", o->dir,
                    bad ? "stream error" : strerror(errno));
    o->heights = NULL;
  }
  return st;
}

void lsm_outputs_free(lsm_outputs *o) {
  lsm_volume_writer_abort(&o->volume);
  lsm_mesh_free(&o->mesh);
  lsm_preview_free(&o->preview);
  if (o->heights) fclose(o->heights);
  o->heights = NULL;
  free(o->mask);
  o->mask = NULL;
}
