#include "solver/app/lsm_progress_bar.h"

#include <stdio.h>
#include <unistd.h>

#include "solver/base/lsm_clock.h"

/* The bar on a terminal, ending with `note` (the line is cleared to its end). */
static void draw_bar(const lsm_progress_bar *p, const char *note) {
  const int percent = p->total ? (int)(100.0 * (double)p->done / (double)p->total) : 0;
  char bar[41];
  const int fill = percent * 40 / 100;
  for (int k = 0; k < 40; ++k) bar[k] = k < fill ? '#' : '.';
  bar[40] = '\0';
  fprintf(stderr, "\rlsmorph: [%s] %3d%%  slice %zu/%zu  %.1f s%s\033[K", bar, percent, p->done,
          p->total, lsm_clock_seconds() - p->start, note);
}

static void progress_update(void *ctx, size_t done, size_t total, size_t pair, size_t pairs) {
  lsm_progress_bar *p = ctx;
  (void)pair;
#pragma omp critical(lsm_progress_bar)
  {
    p->done = done;
    p->total = total;
    const int percent = total ? (int)(100.0 * (double)done / (double)total) : 0;
    if (total == 0) { /* --per-iteration: the slice count is not known ahead */
      if (p->tty) fprintf(stderr, "\rlsmorph: %zu slices written", done);
    } else if (p->tty) {
      draw_bar(p, "");
      if (done == total) fputc('\n', stderr);
    } else if (percent / 10 != p->last_percent / 10 || done == total) {
      fprintf(stderr, "lsmorph: %3d%% (%zu/%zu slices, %zu gaps, %.1f s)\n", percent, done, total,
              pairs, lsm_clock_seconds() - p->start);
    }
    p->last_percent = percent;
  }
}

/* --motion auto tries a pair: on a terminal the bar says so, with the time going on (a log
 * gets the count in the run's closing note instead). */
static void progress_trying(void *ctx, size_t pair, size_t pairs) {
  lsm_progress_bar *p = ctx;
  if (!p->tty) return;
#pragma omp critical(lsm_progress_bar)
  {
    char note[96];
    snprintf(note, sizeof note, "  (trying the field on gap %zu/%zu)", pair + 1, pairs);
    if (!p->total) /* before the first slice */
      fprintf(stderr, "\rlsmorph: %.1f s%s\033[K", lsm_clock_seconds() - p->start, note);
    else if (p->done < p->total)
      draw_bar(p, note);
  }
}

lsm_progress lsm_progress_bar_start(lsm_progress_bar *bar, double start) {
  bar->tty = isatty(fileno(stderr));
  bar->last_percent = -1;
  bar->start = start;
  bar->done = 0;
  bar->total = 0;
  lsm_progress progress = {bar, progress_update, progress_trying};
  return progress;
}
