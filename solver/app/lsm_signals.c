#define _XOPEN_SOURCE 700 /* SA_RESETHAND */
#include "solver/app/lsm_signals.h"

#include <errno.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* The one file-scope mutable variable of the program: a signal handler gets no
 * context, and all C (C17 7.14.1.1) and POSIX let it do with program state is
 * store to a volatile sig_atomic_t. */
static volatile sig_atomic_t stop_signal = 0;

/* The first stop signal is kept as it is; a second one (of any of the
 * three) makes it negative: a guard (below) is then to clean up and end the
 * process. */
static void on_stop_signal(int sig) {
  const int first = stop_signal;
  stop_signal = first == 0 ? sig : first > 0 ? -first : first;
}

/* Catches the stop signals that are not ignored: reset_hand 1 lets a second
 * one take the default action at once (nothing to clean up), 0 leaves it to
 * a guard. */
static void catch_stop_signals(int restart, int reset_hand) {
  const int sigs[3] = {SIGINT, SIGTERM, SIGHUP};
  for (int k = 0; k < 3; ++k) {
    struct sigaction old, sa;
    if (sigaction(sigs[k], NULL, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = (restart ? SA_RESTART : 0) | (reset_hand ? SA_RESETHAND : 0);
    sigaction(sigs[k], &sa, NULL);
  }
}

/* SA_RESETHAND: a second signal of the same kind takes the default action at
 * once, so a stuck run can still be killed (while a temporary result exists a
 * guard takes the second signal instead).  A signal ignored at start (a
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
  catch_stop_signals(restart, 1);
}

int lsm_signals_caught(void) {
  const int sig = stop_signal;
  return sig < 0 ? -sig : sig;
}

const volatile sig_atomic_t *lsm_signals_flag(void) { return &stop_signal; }

const char *lsm_signal_name(int sig) {
  return sig == SIGINT    ? "SIGINT"
         : sig == SIGTERM ? "SIGTERM"
         : sig == SIGHUP  ? "SIGHUP"
                          : "a signal";
}

lsm_status lsm_signals_check(lsm_err *err) {
  const int sig = lsm_signals_caught();
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

/* ---- the guard of a temporary result ------------------------------------------------------ */

/* Wakes every 50 ms: a second stop signal is acted on within that, however
 * long the thread that took the first one needs to reach a check. */
static void *guard_main(void *arg) {
  lsm_signal_guard *g = arg;
  pthread_mutex_lock(&g->lock);
  while (!g->done) {
    if (stop_signal < 0) {
      pthread_mutex_unlock(&g->lock);
      const int sig = -stop_signal;
      g->cleanup(g->ctx);
      /* said only where it cannot block (stderr a full pipe nobody reads) */
      char msg[160];
      const int n = snprintf(msg, sizeof msg, "lsmorph: error: interrupted again by %s: the "
                                              "temporary result is removed; no result was "
                                              "written\n", lsm_signal_name(sig));
      struct pollfd out = {STDERR_FILENO, POLLOUT, 0};
      if (n > 0 && poll(&out, 1, 0) == 1 && (out.revents & POLLOUT))
        (void)!write(STDERR_FILENO, msg, (size_t)n);
      lsm_signals_reraise(sig);
      _exit(128 + sig); /* not reached: the default action of sig ends the process */
    }
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until);
    until.tv_nsec += 50 * 1000 * 1000;
    if (until.tv_nsec >= 1000 * 1000 * 1000) {
      until.tv_sec += 1;
      until.tv_nsec -= 1000 * 1000 * 1000;
    }
    pthread_cond_timedwait(&g->wake, &g->lock, &until);
  }
  pthread_mutex_unlock(&g->lock);
  return NULL;
}

lsm_status lsm_signals_guard_start(lsm_signal_guard *g, void (*cleanup)(void *ctx), void *ctx,
                                   lsm_err *err) {
  memset(g, 0, sizeof *g);
  g->cleanup = cleanup;
  g->ctx = ctx;
  if (pthread_mutex_init(&g->lock, NULL) != 0) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot start the signal guard");
  if (pthread_cond_init(&g->wake, NULL) != 0) {
    pthread_mutex_destroy(&g->lock);
    return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot start the signal guard");
  }
  const int e = pthread_create(&g->thread, NULL, guard_main, g);
  if (e != 0) {
    pthread_cond_destroy(&g->wake);
    pthread_mutex_destroy(&g->lock);
    return lsm_fail(err, LSM_ERR_IO, NULL, "cannot start the signal guard: %s", strerror(e));
  }
  g->started = 1;
  catch_stop_signals(1, 0);
  return LSM_OK;
}

void lsm_signals_guard_stop(lsm_signal_guard *g) {
  if (!g->started) return;
  catch_stop_signals(1, 1);
  pthread_mutex_lock(&g->lock);
  g->done = 1;
  pthread_cond_signal(&g->wake);
  pthread_mutex_unlock(&g->lock);
  pthread_join(g->thread, NULL);
  pthread_cond_destroy(&g->wake);
  pthread_mutex_destroy(&g->lock);
  g->started = 0;
}
