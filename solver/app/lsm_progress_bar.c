#include "solver/app/lsm_progress_bar.h"

#include <stdio.h>
#include <unistd.h>

#include "solver/base/lsm_clock.h"

static void progress_update(void *ctx, size_t done, size_t total, size_t pair, size_t pairs) {
  lsm_progress_bar *p = ctx;
  (void)pair;
  if (total == 0) { /* --per-iteration: the slice count is not known ahead */
    if (p->tty) fprintf(stderr, "\rlsmorph: %zu slices written", done);
    return;
  }
  int percent = (int)(100.0 * (double)done / (double)total);
  double elapsed = lsm_clock_seconds() - p->start;
  if (p->tty) {
    char bar[41];
    int fill = percent * 40 / 100;
    for (int k = 0; k < 40; ++k) bar[k] = k < fill ? '#' : '.';
    bar[40] = '\0';
    fprintf(stderr, "\rlsmorph: [%s] %3d%%  slice %zu/%zu  %.1f s", bar, percent, done, total,
            elapsed);
    if (done == total) fputc('\n', stderr);
  } else if (percent / 10 != p->last_percent / 10 || done == total) {
    fprintf(stderr, "lsmorph: %3d%% (%zu/%zu slices, %zu gaps, %.1f s)\n", percent, done, total,
            pairs, elapsed);
  }
  p->last_percent = percent;
}

lsm_progress lsm_progress_bar_start(lsm_progress_bar *bar, double start) {
  bar->tty = isatty(fileno(stderr));
  bar->last_percent = -1;
  bar->start = start;
  lsm_progress progress = {bar, progress_update};
  return progress;
}
