/* lsm_fill_cmd: the `fill` command (label volumes in, a label volume out), its
 * help, and its 3D Slicer command-line module description.
 *
 * 3D Slicer asks an executable in its module paths for `--xml`, and runs it as
 * `lsmorph [--flag value ...] fill LABELS OUT`: its flags come before the
 * positional arguments, the first of which is the hidden "fill".  lsmorph
 * therefore takes `--xml` alone, and a command line whose first argument is a
 * flag of fill and which names `fill` later, as fill's. */
#ifndef LSM_FILL_CMD_H
#define LSM_FILL_CMD_H

#include <signal.h>
#include <stdio.h>

#include "solver/base/lsm_status.h"

/* Whether argv is a fill command line: `fill ...`, `help fill`, `--help fill`,
 * `--xml`, or 3D Slicer's form (above). */
int lsm_fill_wanted(int argc, char **argv);

/* Runs it: help, the XML, or the fill.  stop: the flag a stop signal sets.
 * Returns LSM_OK, or an error in err (LSM_ERR_USAGE for a usage error). */
lsm_status lsm_fill_main(int argc, char **argv, const volatile sig_atomic_t *stop, lsm_err *err);

void lsm_fill_help(FILE *f);

/* The Slicer Execution Model description of fill. */
void lsm_fill_xml(FILE *f);

/* Parses a list of indices: N, A:B (A to B, both in), A:B:S (every S-th from A
 * up to B) or A-B, comma separated, into *out (malloc'd, *n of them).  With
 * allow_negative, values may be negative and only N and A:B[:S] are taken. */
lsm_status lsm_fill_parse_list(const char *opt, const char *text, int allow_negative,
                               long long **out, size_t *n, lsm_err *err);

#endif
