/* CSV files of the validation drivers: open with a header line, close with
 * every write checked.  Shared by validation/convergence.c and morphacc.c. */
#ifndef LSM_VALIDATION_VCSV_H
#define LSM_VALIDATION_VCSV_H

#include <stdio.h>

#include "solver/base/lsm_status.h"

static inline FILE *open_csv(const char *dir, const char *name, const char *header, lsm_err *err) {
  char path[4200];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "w");
  if (!f) {
    lsm_fail(err, LSM_ERR_IO, path, "cannot create");
    return NULL;
  }
  fprintf(f, "%s\n", header);
  return f;
}

static inline lsm_status close_csv(FILE *f, lsm_status st, lsm_err *err) {
  if (!f) return st;
  int bad = ferror(f);
  if ((fclose(f) != 0 || bad) && st == LSM_OK) st = lsm_fail(err, LSM_ERR_IO, NULL, "write failed");
  return st;
}

#endif
