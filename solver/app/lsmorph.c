/* lsmorph: the program.  main() and the command dispatch; each command lives
 * in its own module (lsm_reconstruct, lsm_score; `devices` in the backend). */
#include <errno.h>
#include <fcntl.h>
#if defined(__GLIBC__) || defined(__linux__)
#include <malloc.h>
#endif
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "solver/app/lsm_cli.h"
#include "solver/app/lsm_fill_cmd.h"
#include "solver/app/lsm_label_score.h"
#include "solver/app/lsm_mpi.h"
#include "solver/app/lsm_reconstruct.h"
#include "solver/app/lsm_score.h"
#include "solver/app/lsm_signals.h"
#include "solver/pde/lsm_backend.h"

/* Whatever went to standard output (help, version, the device list, the
 * scores) reached it. */
static lsm_status check_stdout(lsm_err *err) {
  if (fflush(stdout) != 0 || ferror(stdout))
    return lsm_fail(err, LSM_ERR_IO, "standard output", "write failed: %s", strerror(errno));
  return LSM_OK;
}

/* With file descriptor 0, 1 or 2 closed by the caller, the first file opened
 * would take its number, and stderr's progress lines would land in a volume
 * file: hold every one of them open (on /dev/null). */
static int hold_standard_fds(void) {
  for (int fd = 0; fd <= 2; ++fd) {
    if (fcntl(fd, F_GETFD) != -1) continue;
    const int got = open("/dev/null", fd == 0 ? O_RDONLY : O_WRONLY);
    if (got < 0) return -1;
    if (got != fd) { /* lower ones are open, so got > fd: should not happen */
      close(got);
      return -1;
    }
  }
  return 0;
}

/* `lsmorph fill` (and 3D Slicer's call of it): label volumes in and out. */
static int run_fill(int argc, char **argv) {
  lsm_err err;
  lsm_err_clear(&err);
  lsm_signals_install(1);
  const lsm_status st = lsm_fill_main(argc, argv, lsm_signals_flag(), &err);
  const int sig = lsm_signals_caught();
  if (st != LSM_OK && sig) {
    fprintf(stderr, "lsmorph: error: interrupted by %s; no result was written\n",
            lsm_signal_name(sig));
    return lsm_signals_reraise(sig);
  }
  if (st == LSM_OK) return check_stdout(&err) == LSM_OK ? 0 : 1;
  fprintf(stderr, "lsmorph: error: %s\n", err.msg[0] ? err.msg : lsm_status_name(st));
  return st == LSM_ERR_USAGE ? 2 : 1;
}

/* `lsmorph score` of two label volumes. */
static int run_label_score(int argc, char **argv) {
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = lsm_label_score_main(argc, argv, &err);
  if (st == LSM_OK) st = check_stdout(&err);
  if (st == LSM_OK) return 0;
  fprintf(stderr, "lsmorph: error: %s\n", err.msg[0] ? err.msg : lsm_status_name(st));
  return st == LSM_ERR_USAGE ? 2 : 1;
}

/* Runs the command; returns the exit status (0 success, 1 failure, 2 usage
 * error), or ends the process by the stop signal that interrupted it. */
static int run(int argc, char **argv, const lsm_mpi *mpi) {
  if (lsm_fill_wanted(argc, argv)) return lsm_mpi_rank(mpi) == 0 ? run_fill(argc, argv) : 0;
  if (lsm_label_score_wanted(argc, argv)) return lsm_mpi_rank(mpi) == 0 ? run_label_score(argc, argv) : 0;
  lsm_cli cli;
  lsm_err err;
  lsm_err_clear(&err);
  if (lsm_cli_parse(argc, argv, &cli, &err) != LSM_OK) {
    if (lsm_mpi_rank(mpi) == 0) fprintf(stderr, "lsmorph: error: %s\n", err.msg);
    return 2;
  }
  lsm_status st = LSM_OK;
  switch (cli.command) {
  case LSM_CMD_HELP:
    lsm_cli_help(stdout, cli.help_topic);
    st = check_stdout(&err);
    break;
  case LSM_CMD_VERSION:
    printf("lsmorph %s\n", LSM_VERSION);
    st = check_stdout(&err);
    break;
  case LSM_CMD_RECONSTRUCT:
    lsm_signals_install(0);
    st = lsm_reconstruct(argc, argv, &cli, mpi, &err);
    break;
  case LSM_CMD_DEVICES:
    st = lsm_backend_list_devices(stdout, &err);
    if (st == LSM_OK) st = check_stdout(&err);
    break;
  case LSM_CMD_SCORE:
    st = lsm_score(&cli, &err);
    if (st == LSM_OK) st = check_stdout(&err);
    break;
  default:
    lsm_cli_help(stderr, NULL);
    return 2;
  }
  const int sig = lsm_signals_caught();
  if (st != LSM_OK && sig) {
    /* whatever failed on the way out was caused by the signal: say so, then
     * end by it, so that a calling shell script stops too */
    fprintf(stderr, "lsmorph: error: %s: interrupted by %s; no result was written%s\n",
            cli.out_dir ? cli.out_dir : "lsmorph", lsm_signal_name(sig),
            cli.out_dir ? " (an earlier result there is unchanged)" : "");
    return lsm_signals_reraise(sig);
  }
  if (st != LSM_OK) {
    if (lsm_mpi_rank(mpi) == 0) /* other MPI ranks: rank 0 reports for all */
      fprintf(stderr, "lsmorph: error: %s\n", err.msg[0] ? err.msg : lsm_status_name(st));
    return st == LSM_ERR_USAGE ? 2 : 1;
  }
  return 0;
}

int main(int argc, char **argv) {
#if defined(M_MMAP_THRESHOLD)
  /* Keep freed grids in the heap: every gap allocates and frees tens of MB,
   * and memory returned to the kernel costs a page fault per page on the next
   * gap. */
  mallopt(M_MMAP_THRESHOLD, 1 << 30);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
  if (hold_standard_fds() != 0) return 1; /* no stderr to say so */
  lsm_mpi *mpi = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  if (lsm_mpi_init(&argc, &argv, &mpi, &err) != LSM_OK) {
    fprintf(stderr, "lsmorph: error: %s\n", err.msg);
    return 1;
  }
  const int rc = run(argc, argv, mpi);
  /* with several ranks, rank 0 has reported the error and removed its
   * temporary output: end the other ranks too (they may be waiting to send) */
  if (rc != 0 && lsm_mpi_size(mpi) > 1 && lsm_mpi_rank(mpi) == 0) lsm_mpi_abort(mpi, rc);
  lsm_mpi_finalize(&mpi);
  return rc;
}
