/* lsm_inputs: the slices reconstruct reads: PNG or TIFF files of SLICE_DIR,
 * their heights, which pixels are foreground, and the notes on inputs that
 * are likely not what the user meant. */
#ifndef LSM_INPUTS_H
#define LSM_INPUTS_H

#include <stddef.h>

#include "io/lsm_io.h"
#include "solver/app/lsm_cli.h"
#include "solver/base/lsm_status.h"
#include "solver/recon/lsm_stack.h"

/* The PNG and TIFF files of SLICE_DIR, in natural order, and how they read. */
typedef struct lsm_slice_files {
  char **paths;
  size_t count;
  lsm_image_read_opts read;
  uint8_t *blank; /* NULL, or per slice once loaded: 1 blank, 2 not (lsm_inputs_note_blank) */
} lsm_slice_files;

/* Foreground rule for a stack (ro->nonzero): luminance >= 50 %, unless no
 * pixel of any slice reaches it while the stack has both zero and non-zero
 * pixels (label masks stored as 0/1): then any non-zero pixel (with invert:
 * any zero one), and a note says so unless quiet.  Reads slices only up to the
 * first non-empty one. */
lsm_status lsm_pick_foreground(char **paths, size_t count, lsm_image_read_opts *ro, int quiet,
                               const char *dir, lsm_err *err);

/* The input slices' heights: --heights FILE, the numbers the file names end
 * with times --spacing (--heights-from-names), or consecutive files --spacing
 * apart.  *z_out is malloc'd with count values. */
lsm_status lsm_input_heights(const lsm_cli *cli, char *const *paths, size_t count, double **z_out,
                             lsm_err *err);

/* Notes on stderr about inputs that look unintended: filled regions read as
 * outlines; file names numbered with gaps, or a heights.txt beside the
 * slices, when no option places the slices. */
void lsm_inputs_note(const lsm_cli *cli, const lsm_slice_files *src);

/* After a run: a note when blank slices lie between slices that are not (the
 * undrawn slices of a label volume exported as PNGs read as drawn empty), which
 * points to `lsmorph fill`. */
void lsm_inputs_note_blank(const lsm_slice_files *src, const char *dir);

/* Frees the paths and the blank flags. */
void lsm_slice_files_free(lsm_slice_files *src);

/* The files as the stack driver's source (it must outlive the run); each load
 * first checks for a stop signal. */
lsm_slice_source lsm_slice_files_source(lsm_slice_files *src, const double *z);

#endif
