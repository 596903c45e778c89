#define _XOPEN_SOURCE 700 /* SA_RESETHAND */
#include "solver/app/lsm_signals.h"

#include <string.h>

/* The one file-scope mutable variable of the program: a signal handler gets no
 * context, and all C (C17 7.14.1.1) and POSIX let it do with program state is
 * store to a volatile sig_atomic_t. */
static volatile sig_atomic_t stop_signal = 0;

static void on_stop_signal(int sig) { stop_signal = sig; }

/* SA_RESETHAND: a second signal of the same kind takes the default action at
 * once, so a stuck run can still be killed.  A signal ignored at start (a
 * background job's SIGINT, nohup's SIGHUP) stays ignored.  SIGPIPE: progress
 * piped into a reader that quit is not worth a half-written result.  SIGXFSZ:
 * past a file-size limit the write fails with EFBIG and the error path cleans
 * up, where the default action would leave the temporary folder behind. */
void lsm_signals_install(int restart) {
  struct sigaction ign;
  memset(&ign, 0, sizeof ign);
  ign.sa_handler = SIG_IGN;
  sigemptyset(&ign.sa_mask);
  sigaction(SIGPIPE, &ign, NULL);
  sigaction(SIGXFSZ, &ign, NULL);
  const int sigs[3] = {SIGINT, SIGTERM, SIGHUP};
  for (int k = 0; k < 3; ++k) {
    struct sigaction old, sa;
    if (sigaction(sigs[k], NULL, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = (restart ? SA_RESTART : 0) | SA_RESETHAND;
    sigaction(sigs[k], &sa, NULL);
  }
}

int lsm_signals_caught(void) { return stop_signal; }

const volatile sig_atomic_t *lsm_signals_flag(void) { return &stop_signal; }

const char *lsm_signal_name(int sig) {
  return sig == SIGINT    ? "SIGINT"
         : sig == SIGTERM ? "SIGTERM"
         : sig == SIGHUP  ? "SIGHUP"
                          : "a signal";
}

lsm_status lsm_signals_check(lsm_err *err) {
  const int sig = stop_signal;
  if (!sig) return LSM_OK;
  return lsm_fail(err, LSM_ERR_INTERRUPTED, NULL, "interrupted by %s", lsm_signal_name(sig));
}

static lsm_status stoppable_emit(void *ctx, const float *phi, int width, int height, double z,
                                 long input_index, lsm_err *err) {
  const lsm_slice_sink *inner = ctx;
  LSM_TRY(lsm_signals_check(err));
  return inner->emit(inner->ctx, phi, width, height, z, input_index, err);
}

lsm_slice_sink lsm_signals_stoppable(lsm_slice_sink *inner) {
  lsm_slice_sink stoppable = {inner, stoppable_emit};
  return stoppable;
}

int lsm_signals_reraise(int sig) {
  signal(sig, SIG_DFL);
  raise(sig);
  return 128 + sig;
}
