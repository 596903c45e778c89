#include "solver/app/lsm_checks.h"

#include <math.h>
#include <stdint.h>

#include "solver/app/lsm_signals.h"

/* Longest slice side accepted: keeps every canvas of the stack driver (the
 * image plus alignment margins, at most three times a side) within an int. */
#define LSM_SIDE_MAX (1 << 24)

/* Increasing, finite heights whose gaps and output steps the floats and
 * doubles of the run resolve. */
static lsm_status check_heights(const lsm_cli *cli, const lsm_slice_files *src, const double *z,
                                lsm_err *err) {
  const char *heights_name = cli->heights_file ? cli->heights_file : cli->slice_dir;
  for (size_t k = 0; k < src->count; ++k) {
    if (!isfinite(z[k]))
      return lsm_fail(err, LSM_ERR_INPUT, heights_name,
                      "height of slice %zu is not finite (--spacing %g)", k + 1, cli->spacing);
    if (k > 0 && !(z[k] > z[k - 1]))
      return lsm_fail(err, LSM_ERR_INPUT, heights_name,
                      "heights of slices %zu and %zu are not increasing", k, k + 1);
    if (k > 0 && !lsm_length_in_range(z[k] - z[k - 1]))
      return lsm_fail(err, LSM_ERR_INPUT, heights_name,
                      "slices %zu and %zu are %g apart, outside %g to %g (lengths are held as "
                      "floats; choose a unit that brings it into range)",
                      k, k + 1, z[k] - z[k - 1], LSM_LENGTH_MIN, LSM_LENGTH_MAX);
  }
  /* output heights are doubles: steps too small for them repeat heights */
  const double z_mag = fmax(fabs(z[0]), fabs(z[src->count - 1]));
  if (cli->stack.per_iteration) {
    for (size_t k = 0; k + 1 < src->count; ++k) {
      const double step = (z[k + 1] - z[k]) / ((double)cli->stack.max_iter + 1.0);
      if (!lsm_output_step_resolved(step, z_mag))
        return lsm_fail(err, LSM_ERR_INPUT, heights_name,
                        "slices %zu and %zu are %g apart at heights near %g: --per-iteration's "
                        "up to --max-iter %d steps between them would repeat heights (double "
                        "precision); subtract an offset from the heights or lower --max-iter",
                        k + 1, k + 2, z[k + 1] - z[k], z_mag, cli->stack.max_iter);
    }
  } else {
    const double dz = lsm_stack_output_dz(&cli->stack);
    if (!lsm_output_step_resolved(dz, z_mag))
      return lsm_fail(err, LSM_ERR_INPUT, heights_name,
                      "output steps of %g (%s) at heights near %g would repeat heights (double "
                      "precision); subtract an offset from the heights or raise --dz",
                      dz, cli->stack.dz > 0 ? "--dz" : "the pixel size", z_mag);
  }
  return LSM_OK;
}

/* Every slice header: the first within --max-pixels and LSM_SIDE_MAX, the
 * others the first's size. */
static lsm_status check_slice_sizes(const lsm_cli *cli, const lsm_slice_files *src, int *width,
                                    int *height, lsm_err *err) {
  int w = 0, h = 0;
  for (size_t k = 0; k < src->count; ++k) {
    LSM_TRY(lsm_signals_check(err));
    int wk = 0, hk = 0;
    LSM_TRY(lsm_slice_read_header(src->paths[k], cli->max_pixels, &wk, &hk, err));
    if (k == 0) {
      w = wk;
      h = hk;
      const uint64_t pixels = (uint64_t)w * (uint64_t)h; /* both < 2^31: no overflow */
      if (pixels > cli->max_pixels)
        return lsm_fail(err, LSM_ERR_LIMIT, src->paths[0],
                        "%dx%d = %llu pixels is more than --max-pixels %llu", w, h,
                        (unsigned long long)pixels, (unsigned long long)cli->max_pixels);
      if (w > LSM_SIDE_MAX || h > LSM_SIDE_MAX)
        return lsm_fail(err, LSM_ERR_LIMIT, src->paths[0],
                        "%dx%d: a side longer than %d pixels is not supported", w, h,
                        LSM_SIDE_MAX);
    } else if (wk != w || hk != h) {
      return lsm_fail(err, LSM_ERR_INPUT, src->paths[k], "slice is %dx%d but %s is %dx%d", wk,
                      hk, lsm_base_name(src->paths[0]), w, h);
    }
  }
  *width = w;
  *height = h;
  return LSM_OK;
}

/* The working grid of a gap and the output volume, for w x h slices. */
static lsm_status check_limits(const lsm_cli *cli, const lsm_slice_files *src, const double *z,
                               int w, int h, lsm_err *err) {
  const char *heights_name = cli->heights_file ? cli->heights_file : cli->slice_dir;
  /* an aligned gap pads each axis by the largest centroid shift along it (at
   * most half the side) plus 2 cells */
  const uint64_t canvas = cli->stack.align == LSM_ALIGN_NONE
                              ? (uint64_t)w * (uint64_t)h
                              : ((uint64_t)w + 2 * ((uint64_t)w / 2 + 2)) *
                                    ((uint64_t)h + 2 * ((uint64_t)h / 2 + 2));
  if (canvas > (uint64_t)LSM_GRID_CELLS_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, src->paths[0],
                    "%dx%d slices need a working grid of up to %llu cells%s, more than the %lld "
                    "supported", w, h, (unsigned long long)canvas,
                    cli->stack.align != LSM_ALIGN_NONE &&
                            (uint64_t)w * (uint64_t)h <= (uint64_t)LSM_GRID_CELLS_MAX
                        ? " (use --align none)"
                        : "",
                    (long long)LSM_GRID_CELLS_MAX);
  if (cli->stack.align != LSM_ALIGN_NONE && canvas / 4 > cli->max_pixels)
    return lsm_fail(err, LSM_ERR_LIMIT, src->paths[0],
                    "%dx%d slices need a working canvas of up to %llu cells with --align %s, "
                    "more than 4 x --max-pixels %llu (use --align none or raise --max-pixels)",
                    w, h, (unsigned long long)canvas, lsm_align_name(cli->stack.align),
                    (unsigned long long)cli->max_pixels);
  const char *nifti = (cli->formats & LSM_FORMAT_NII) ? "volume.nii" : "volume.nii.gz";
  if ((cli->formats & LSM_FORMATS_NIFTI) && (w > LSM_NIFTI_DIM_MAX || h > LSM_NIFTI_DIM_MAX))
    return lsm_fail(err, LSM_ERR_LIMIT, src->paths[0],
                    "%dx%d slices do not fit %s: NIfTI-1 holds at most %d samples along "
                    "an axis (choose another --format)", w, h, nifti, LSM_NIFTI_DIM_MAX);
  if (cli->stack.per_iteration) return LSM_OK; /* its volume is checked as it is written */
  const double dz = lsm_stack_output_dz(&cli->stack);
  const size_t count = lsm_stack_output_count(z, src->count, dz);
  const double slices = (double)count;
  if ((cli->formats & LSM_FORMATS_NIFTI) && count > LSM_NIFTI_DIM_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, heights_name,
                    "the output would have %s%zu slices, more than the %d %s holds "
                    "(NIfTI-1 sizes are 16-bit: raise --dz or choose another --format)",
                    count >= LSM_OUTPUT_COUNT_MAX ? "at least " : "", count, LSM_NIFTI_DIM_MAX,
                    nifti);
  const double voxels = slices * (double)w * (double)h;
  if (!(voxels <= (double)cli->max_voxels))
    return lsm_fail(err, LSM_ERR_LIMIT, heights_name,
                    "the output would have %s%.4g slices of %dx%d = %.4g voxels, more than "
                    "--max-voxels %llu (raise --dz or --max-voxels)",
                    count >= LSM_OUTPUT_COUNT_MAX ? "at least " : "", slices, w, h, voxels,
                    (unsigned long long)cli->max_voxels);
  return LSM_OK;
}

lsm_status lsm_check_inputs(const lsm_cli *cli, const lsm_slice_files *src, const double *z,
                            int *width, int *height, lsm_err *err) {
  int w = 0, h = 0;
  LSM_TRY(check_heights(cli, src, z, err));
  LSM_TRY(check_slice_sizes(cli, src, &w, &h, err));
  LSM_TRY(check_limits(cli, src, z, w, h, err));
  *width = w;
  *height = h;
  return LSM_OK;
}
