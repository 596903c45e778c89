#include "solver/app/lsm_inputs.h"

#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>

#include "solver/app/lsm_signals.h"

/* A note when the first slice with foreground has black pixels and at
 * least as many that are non-zero but below 50 % as at or above it: not the
 * grey edge of a drawn mask (nor a dark grey background, with no black) but
 * a label map on 0 (labels 1, 2, ... with some at 128 or more), whose dark
 * labels read as background. */
static lsm_status note_dark_labels(const char *path, const lsm_image_read_opts *ro, size_t bright,
                                   lsm_err *err) {
  lsm_image_read_opts any = *ro;
  any.nonzero = 1;
  lsm_mask m = {0, 0, NULL};
  LSM_TRY(lsm_slice_read_mask(path, &any, &m, err));
  const size_t nonzero = lsm_mask_count(&m), all = (size_t)m.width * (size_t)m.height;
  lsm_mask_free(&m);
  if (nonzero < all && nonzero - bright >= bright)
    fprintf(stderr,
            "lsmorph: note: %s: %zu pixels are non-zero but below 50 %% luminance, as many "
            "as or more than the %zu at or above it; they read as background (for a label "
            "map, write a mask of the labels wanted)\n",
            path, nonzero - bright, bright);
  return LSM_OK;
}

/* A note when the first PNG slice with foreground holds several distinct
 * non-zero values: a label map, whose labels read as one object. */
static void note_merged_labels(char **paths, size_t count, const lsm_image_read_opts *ro) {
  for (size_t k = 0; k < count; ++k) {
    lsm_mask m = {0, 0, NULL};
    lsm_err ignored;
    lsm_err_clear(&ignored);
    if (lsm_slice_read_mask(paths[k], ro, &m, &ignored) != LSM_OK) return;
    const size_t inside = lsm_mask_count(&m);
    lsm_mask_free(&m);
    if (!inside) continue;
    unsigned levels = 0;
    if (lsm_is_tiff_name(paths[k]) || lsm_png_count_levels(paths[k], &levels) != LSM_OK ||
        levels < 2)
      return;
    fprintf(stderr,
            "lsmorph: note: %s holds %s%u distinct non-zero values: labels, read here as one "
            "object (merged). A label map goes to lsmorph fill as a NIfTI or NRRD volume, "
            "every label apart ('lsmorph help fill'); or write one mask per label\n",
            paths[k], levels >= 256 ? "at least " : "", levels);
    return;
  }
}

/* Pass 0 looks for a pixel at 50 %, pass 1 for zero and non-zero pixels.  A
 * stack uniformly dark but not black (no zero pixel) stays empty. */
lsm_status lsm_pick_foreground(char **paths, size_t count, lsm_image_read_opts *ro, int quiet,
                               const char *dir, lsm_err *err) {
  int none_reach_half = 1, some_zero = 0, some_nonzero = 0;
  for (int pass = 0; pass < 2 && none_reach_half; ++pass) {
    ro->nonzero = pass;
    for (size_t k = 0; k < count && !(some_zero && some_nonzero); ++k) {
      lsm_mask m = {0, 0, NULL};
      LSM_TRY(lsm_slice_read_mask(paths[k], ro, &m, err));
      const size_t inside = lsm_mask_count(&m), all = (size_t)m.width * (size_t)m.height;
      lsm_mask_free(&m);
      /* with --invert the mask holds the pixels below 50 %, or the zero ones */
      const size_t fg = ro->invert ? all - inside : inside;
      if (pass == 0 && fg > 0) { /* some pixel reaches 50 % */
        none_reach_half = 0;
        if (!quiet && !ro->invert) LSM_TRY(note_dark_labels(paths[k], ro, fg, err));
        break;
      }
      if (pass == 1) {
        some_nonzero |= fg > 0;
        some_zero |= fg < all;
      }
    }
  }
  ro->nonzero = none_reach_half && some_zero && some_nonzero;
  if (ro->nonzero && !quiet)
    fprintf(stderr,
            "lsmorph: note: %s: no pixel reaches 50 %% luminance in any slice; reading "
            "non-zero pixels as %s (label masks stored as 0/1)\n",
            dir, ro->invert ? "background" : "foreground");
  if (!quiet) note_merged_labels(paths, count, ro);
  return LSM_OK;
}

/* With --input outline, a note when the first non-empty slice looks filled
 * (most of its foreground pixels have all four neighbours in it): outlines
 * are thin contours, and a filled region read as one has no inside. */
static void note_filled_outlines(const lsm_slice_files *src, const char *dir) {
  for (size_t k = 0; k < src->count; ++k) {
    lsm_mask m = {0, 0, NULL};
    lsm_err ignored;
    lsm_err_clear(&ignored);
    if (lsm_slice_read_mask(src->paths[k], &src->read, &m, &ignored) != LSM_OK) return;
    size_t fg = 0, interior = 0;
    for (int j = 0; j < m.height; ++j)
      for (int i = 0; i < m.width; ++i) {
        const uint8_t *p = m.pixels + (size_t)j * (size_t)m.width + (size_t)i;
        if (!*p) continue;
        fg++;
        interior += i > 0 && i + 1 < m.width && j > 0 && j + 1 < m.height && p[-1] && p[1] &&
                    p[-m.width] && p[m.width];
      }
    lsm_mask_free(&m);
    if (!fg) continue;
    if (2 * interior > fg)
      fprintf(stderr,
              "lsmorph: note: %s: --input outline, but %s looks filled (%.0f %% of its foreground "
              "pixels are interior): outlines are thin closed contours; filled regions need "
              "--input mask\n",
              dir, lsm_base_name(src->paths[k]), 100.0 * (double)interior / (double)fg);
    return;
  }
}

/* Rank 0 and the MPI workers each call this, so that all agree. */
lsm_status lsm_input_heights(const lsm_cli *cli, char *const *paths, size_t count, double **z_out,
                             lsm_err *err) {
  double *z = NULL;
  *z_out = NULL;
  if (cli->heights_file) {
    size_t nz = 0;
    LSM_TRY(lsm_heights_read(cli->heights_file, &z, &nz, err));
    if (nz != count) {
      free(z);
      return lsm_fail(err, LSM_ERR_INPUT, cli->heights_file, "%zu heights for %zu slices in %s",
                      nz, count, cli->slice_dir);
    }
    *z_out = z;
    return LSM_OK;
  }
  z = lsm_alloc(count, sizeof *z, err, "heights");
  if (!z) return err->status;
  uint64_t previous = 0;
  for (size_t k = 0; k < count; ++k) {
    if (!cli->heights_from_names) {
      z[k] = (double)k * cli->spacing;
      continue;
    }
    uint64_t n = 0;
    if (!lsm_name_number(paths[k], &n)) {
      free(z);
      return lsm_fail(err, LSM_ERR_INPUT, paths[k],
                      "--heights-from-names: the file name does not end with a number "
                      "(of at most 18 digits)");
    }
    if (k > 0 && n <= previous) {
      free(z);
      return lsm_fail(err, LSM_ERR_INPUT, paths[k],
                      "--heights-from-names: its number %" PRIu64 " does not follow %s's %" PRIu64
                      " (the numbers must increase in the files' natural order)",
                      n, lsm_base_name(paths[k - 1]), previous);
    }
    z[k] = (double)n * cli->spacing;
    if (k > 0 && !(z[k] > z[k - 1])) { /* numbers past 2^53 round together */
      free(z);
      return lsm_fail(err, LSM_ERR_INPUT, paths[k],
                      "--heights-from-names: its number %" PRIu64 " gives the same height as "
                      "%s's %" PRIu64 " in double precision (numbers above 2^53 round): "
                      "number the slices from a smaller start",
                      n, lsm_base_name(paths[k - 1]), previous);
    }
    previous = n;
  }
  *z_out = z;
  return LSM_OK;
}

/* Without --spacing or --heights, consecutive files are one unit apart.  A
 * note when the file names number the slices with gaps (001.png, 009.png,
 * ..., every 8th of a scan kept under its own names): that is most likely
 * where they lie (--heights-from-names), and the run would then fill nothing
 * between them.  Only when every name ends with a number and the numbers
 * increase. */
static void note_numbered_names(const lsm_slice_files *src, const char *dir) {
  uint64_t first = 0, previous = 0, step = 0;
  int even = 1;
  for (size_t k = 0; k < src->count; ++k) {
    uint64_t n;
    if (!lsm_name_number(src->paths[k], &n) || (k > 0 && n <= previous)) return;
    if (k == 0)
      first = n;
    else if (k == 1)
      step = n - previous;
    else if (n - previous != step)
      even = 0;
    previous = n;
  }
  if (even && step == 1) return; /* consecutive: what the default assumes */
  fprintf(stderr, "lsmorph: note: %s: the file names number the slices ", dir);
  if (even)
    fprintf(stderr, "%" PRIu64 ", %" PRIu64 ", ... %" PRIu64 " (steps of %" PRIu64 ")", first,
            first + step, previous, step);
  else
    fprintf(stderr, "%" PRIu64 " to %" PRIu64 " unevenly", first, previous);
  fputs(", but without --spacing, --heights or --heights-from-names consecutive files are 1 "
        "apart; if the numbers are the slices' indices in the scan, add --heights-from-names "
        "(each height is then the number times --spacing, the slice thickness)\n",
        stderr);
}

/* A heights.txt among the slices (as examples/gen_synthetic writes them) is
 * not read unless given with --heights: a note says so. */
static void note_heights_beside(const char *dir) {
  char path[4096];
  struct stat sb;
  const int n = snprintf(path, sizeof path, "%s/heights.txt", dir);
  if (n > 0 && (size_t)n < sizeof path && stat(path, &sb) == 0 && S_ISREG(sb.st_mode))
    fprintf(stderr, "lsmorph: note: %s is not read: the slices are 1 apart; give it with "
                    "--heights to place them by it\n", path);
}

void lsm_inputs_note(const lsm_cli *cli, const lsm_slice_files *src) {
  if (cli->stack.input == LSM_INPUT_OUTLINE) note_filled_outlines(src, cli->slice_dir);
  if (!cli->heights_file && !cli->spacing_given && !cli->heights_from_names) {
    note_numbered_names(src, cli->slice_dir);
    note_heights_beside(cli->slice_dir);
  }
}

static lsm_status slice_files_load(void *ctx, size_t index, lsm_mask *out, lsm_err *err) {
  lsm_slice_files *ps = ctx;
  LSM_TRY(lsm_signals_check(err));
  LSM_TRY(lsm_slice_read_mask(ps->paths[index], &ps->read, out, err));
  if (ps->blank) { /* gaps load their slices side by side */
    uint8_t blank = lsm_mask_count(out) ? 2 : 1;
#pragma omp atomic write
    ps->blank[index] = blank;
    (void)blank;
  }
  return LSM_OK;
}

void lsm_slice_files_free(lsm_slice_files *src) {
  free(src->blank);
  lsm_path_list_free(src->paths, src->count);
  src->blank = NULL;
  src->paths = NULL;
  src->count = 0;
}

/* A note on the first slice read as blank that holds zero and non-zero
 * pixels, all below 50 %, while other slices reach it (a 0/1 mask among
 * 0/255 ones): the object vanishes there although the slice draws it. */
static void note_dim_blank(const lsm_slice_files *src, const char *dir) {
  lsm_image_read_opts any = src->read;
  any.nonzero = 1;
  for (size_t k = 0; k < src->count; ++k) {
    if (src->blank[k] != 1) continue;
    lsm_mask m = {0, 0, NULL};
    lsm_err ignored;
    lsm_err_clear(&ignored);
    if (lsm_slice_read_mask(src->paths[k], &any, &m, &ignored) != LSM_OK) return;
    const size_t nonzero = lsm_mask_count(&m), all = (size_t)m.width * (size_t)m.height;
    lsm_mask_free(&m);
    if (!nonzero || nonzero == all) continue; /* black, or a uniform dim background */
    fprintf(stderr,
            "lsmorph: note: %s: %s read as blank (the object absent), yet %zu of its pixels are "
            "non-zero, all below 50 %% luminance, while other slices reach it: a mask stored as "
            "0/1 among 0/255 ones? Save every slice with the same values\n",
            dir, lsm_base_name(src->paths[k]), nonzero);
    return;
  }
}

void lsm_inputs_note_blank(const lsm_slice_files *src, const char *dir) {
  if (!src->blank) return;
  if (!src->read.nonzero && !src->read.invert) note_dim_blank(src, dir);
  size_t first = SIZE_MAX, last = 0, between = 0, example = 0;
  for (size_t k = 0; k < src->count; ++k)
    if (src->blank[k] == 2) {
      if (first == SIZE_MAX) first = k;
      last = k;
    }
  for (size_t k = first + 1; first != SIZE_MAX && k < last; ++k)
    if (src->blank[k] == 1 && !between++) example = k;
  if (between)
    fprintf(stderr,
            "lsmorph: note: %s: %zu blank slice%s (%s, ...) lie%s between slices that are not; "
            "a blank slice says the object is absent there. If they are the undrawn slices of "
            "a segmentation, fill the label volume itself: lsmorph fill LABELS -o OUT fills "
            "the blank slices between drawn ones ('lsmorph help fill')\n",
            dir, between, between == 1 ? "" : "s", lsm_base_name(src->paths[example]),
            between == 1 ? "s" : "");
}

static const char *slice_files_name(void *ctx, size_t index) {
  lsm_slice_files *ps = ctx;
  return ps->paths[index];
}

lsm_slice_source lsm_slice_files_source(lsm_slice_files *src, const double *z) {
  lsm_slice_source source = {src, src->count, z, slice_files_load, slice_files_name};
  return source;
}
