/* lsm_signals: stopping a command on SIGINT, SIGTERM or SIGHUP.
 *
 * A stop signal only records itself; the command notices it between slices
 * (lsm_signals_check), and a long gap between its steps (lsm_signals_flag in
 * lsm_morph_opts.stop), and unwinds through its normal error path, which
 * removes what it had begun to write.  The caller then ends the process by
 * that signal (lsm_signals_reraise). */
#ifndef LSM_SIGNALS_H
#define LSM_SIGNALS_H

#include <pthread.h>
#include <signal.h>

#include "solver/base/lsm_status.h"
#include "solver/recon/lsm_stack.h"

/* Catches SIGINT, SIGTERM and SIGHUP (those not ignored when the program
 * started) and ignores SIGPIPE and SIGXFSZ.  restart 0 while the input is
 * read (a signal interrupts a blocking open of a FIFO); 1 from the first
 * output on (writes in progress are not cut short by EINTR). */
void lsm_signals_install(int restart);

/* The stop signal that has arrived, 0 while none has. */
int lsm_signals_caught(void);

/* The flag a long loop polls: non-zero once a stop signal has arrived. */
const volatile sig_atomic_t *lsm_signals_flag(void);

/* "SIGINT", "SIGTERM", "SIGHUP", or "a signal". */
const char *lsm_signal_name(int sig);

/* LSM_ERR_INTERRUPTED ("interrupted by SIGINT") once a stop signal has arrived. */
lsm_status lsm_signals_check(lsm_err *err);

/* A sink that checks for a stop signal before handing each slice to *inner
 * (which must outlive it). */
lsm_slice_sink lsm_signals_stoppable(lsm_slice_sink *inner);

/* While a temporary result exists: a second stop signal (Ctrl-C pressed
 * again while the first is still on its way to a check) calls cleanup(ctx)
 * on the guard's own thread within 50 ms, then ends the process by the
 * first signal.  Outside a guard a second signal ends the process at once.
 * cleanup must be safe to call while the other threads run on. */
typedef struct lsm_signal_guard {
  pthread_t thread;
  pthread_mutex_t lock;
  pthread_cond_t wake;
  int started, done;
  void (*cleanup)(void *ctx);
  void *ctx;
} lsm_signal_guard;

lsm_status lsm_signals_guard_start(lsm_signal_guard *g, void (*cleanup)(void *ctx), void *ctx,
                                   lsm_err *err);
/* Ends the guard (harmless when it did not start). */
void lsm_signals_guard_stop(lsm_signal_guard *g);

/* Ends the process by signal sig (its default action: exit status 128 + sig
 * in a shell), so that a calling script stops too; returns 128 + sig only if
 * the signal did not end it. */
int lsm_signals_reraise(int sig);

#endif
