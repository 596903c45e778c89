/* The decisions behind OUT_DIR and its temporaries, without a file system
 * to stage: how each kind of OUT_DIR is written (lsm_out_dir_decide); the
 * names that carry their maker (io/lsm_temp.h) and when a maker has provably
 * ended (this process, a child that ended, a child that runs, a pid reused,
 * another machine); and the signal guard: a second stop signal while the
 * main thread is stuck (here: asleep) cleans up and ends the process by the
 * first signal within a fraction of a second.  End to end: test_out_dir.sh. */
#define _XOPEN_SOURCE 700
#include "lsm_test.h"

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "io/lsm_temp.h"
#include "solver/app/lsm_out_dir.h"
#include "solver/app/lsm_signals.h"

static lsm_out_mode decide(int exists, int link, int folder, int mount, int cwd, int locked) {
  const lsm_out_facts f = {exists, link, folder, mount, cwd, locked};
  const char *why = NULL;
  const lsm_out_mode m = lsm_out_dir_decide(&f, &why);
  assert_true((m == LSM_OUT_NEW || m == LSM_OUT_REPLACE) == (why == NULL));
  return m;
}

static void test_decide(void **state) {
  (void)state;
  assert_int_equal(decide(0, 0, 0, 0, 0, 0), LSM_OUT_NEW);
  assert_int_equal(decide(0, 1, 0, 0, 0, 0), LSM_OUT_REFUSE);   /* a link to nothing */
  assert_int_equal(decide(1, 0, 0, 0, 0, 0), LSM_OUT_REFUSE);   /* a file */
  assert_int_equal(decide(1, 1, 0, 0, 0, 0), LSM_OUT_REFUSE);   /* a link to a file */
  assert_int_equal(decide(1, 0, 1, 0, 0, 0), LSM_OUT_REPLACE);  /* a folder */
  assert_int_equal(decide(1, 1, 1, 0, 0, 0), LSM_OUT_REPLACE);  /* a link to one: followed */
  assert_int_equal(decide(1, 0, 1, 1, 0, 0), LSM_OUT_IN_PLACE); /* a mount point */
  assert_int_equal(decide(1, 1, 1, 1, 0, 0), LSM_OUT_IN_PLACE); /* a link to one */
  assert_int_equal(decide(1, 0, 1, 0, 1, 0), LSM_OUT_IN_PLACE); /* -o . */
  assert_int_equal(decide(1, 0, 1, 0, 0, 1), LSM_OUT_IN_PLACE); /* a parent not writable */
  assert_int_equal(decide(1, 0, 1, 1, 1, 1), LSM_OUT_IN_PLACE);
}

static void test_names(void **state) {
  (void)state;
  char tag[LSM_TEMP_TAG_MAX];
  assert_int_equal(lsm_temp_name_tag("out.tmp-12.345.0123456789abcdef-Ab3dE9", "out.tmp-", tag), 1);
  assert_string_equal(tag, "12.345.0123456789abcdef");
  assert_int_equal(lsm_temp_name_tag("out.tmp-Ab3dE9", "out.tmp-", tag), 0); /* an older lsmorph */
  assert_int_equal(lsm_temp_name_tag("out.tmp--Ab3dE9", "out.tmp-", tag), 1); /* no tag */
  assert_string_equal(tag, "");
  /* the earlier result set aside while publishing is never a temporary */
  assert_int_equal(lsm_temp_name_tag("out.tmp-1.2.0123456789abcdef-Ab3dE9.old-Xy12Zw", "out.tmp-", tag), 0);
  assert_int_equal(lsm_temp_name_tag("out.tmp-1.2.0123456789abcdef-Ab3d!9", "out.tmp-", tag), 0);
  assert_int_equal(lsm_temp_name_tag("other.tmp-1.2.0123456789abcdef-Ab3dE9", "out.tmp-", tag), 0);
  char path[256];
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_temp_template(path, sizeof path, "dir/out.tmp-", &err), LSM_OK);
  assert_int_equal(lsm_temp_name_tag(path + 4, "out.tmp-", tag), 1);
  char mine[LSM_TEMP_TAG_MAX];
  lsm_temp_tag(mine);
  assert_string_equal(tag, mine);
  char longest[300];
  memset(longest, 'a', 250);
  strcpy(longest + 250, ".tmp-");
  assert_int_equal(lsm_temp_template(path, sizeof path, longest, &err), LSM_ERR_INPUT);
}

/* The tag of process pid with its start time moved by `shift` ticks, on
 * machine (NULL: this one). */
static void tag_of(pid_t pid, long long shift, const char *machine, char tag[LSM_TEMP_TAG_MAX]) {
  char path[64], text[1024], mine[LSM_TEMP_TAG_MAX];
  snprintf(path, sizeof path, "/proc/%d/stat", (int)pid);
  FILE *f = fopen(path, "r");
  assert_non_null(f);
  const size_t n = fread(text, 1, sizeof text - 1, f);
  fclose(f);
  text[n] = '\0';
  const char *p = strrchr(text, ')') + 2;
  for (int field = 3; field < 22; ++field) p = strchr(p, ' ') + 1;
  const long long start = strtoll(p, NULL, 10);
  lsm_temp_tag(mine);
  snprintf(tag, LSM_TEMP_TAG_MAX, "%d.%lld.%s", (int)pid, start + shift,
           machine ? machine : strrchr(mine, '.') + 1);
}

static void test_owner_ended(void **state) {
  (void)state;
  char mine[LSM_TEMP_TAG_MAX], tag[LSM_TEMP_TAG_MAX];
  lsm_temp_tag(mine);
  if (!mine[0]) skip(); /* no /proc: nothing is ever shown to have ended */
  assert_int_equal(lsm_temp_owner_ended(mine), 0);
  const pid_t child = fork();
  if (child == 0) {
    pause();
    _exit(0);
  }
  assert_true(child > 0);
  char alive[LSM_TEMP_TAG_MAX];
  tag_of(child, 0, NULL, alive);
  assert_int_equal(lsm_temp_owner_ended(alive), 0);          /* running */
  tag_of(child, 1, NULL, tag);
  assert_int_equal(lsm_temp_owner_ended(tag), 1);            /* its pid, another start: reused */
  tag_of(child, 0, "0123456789abcdef", tag);
  assert_int_equal(lsm_temp_owner_ended(tag), 0);            /* another machine: never judged */
  kill(child, SIGKILL);
  const struct timespec pause_ = {0, 50 * 1000 * 1000};
  nanosleep(&pause_, NULL);
  assert_int_equal(lsm_temp_owner_ended(alive), 1);          /* a zombie */
  waitpid(child, NULL, 0);
  assert_int_equal(lsm_temp_owner_ended(alive), 1);          /* gone */
  assert_int_equal(lsm_temp_owner_ended("garbage"), 0);
}

static void mark_cleaned(void *ctx) {
  FILE *f = fopen(ctx, "w");
  if (f) fclose(f);
}

/* A second SIGINT while the main thread sleeps (a long loop that does not
 * poll): the guard cleans up and the process ends by SIGINT, at once. */
static void test_guard(void **state) {
  (void)state;
  char marker[] = "/tmp/lsm-test-guard-XXXXXX";
  const int fd = mkstemp(marker);
  assert_true(fd >= 0);
  close(fd);
  unlink(marker);
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  const pid_t child = fork();
  if (child == 0) {
    lsm_err err;
    lsm_err_clear(&err);
    lsm_signals_install(1);
    lsm_signal_guard guard;
    if (lsm_signals_guard_start(&guard, mark_cleaned, marker, &err) != LSM_OK) _exit(3);
    raise(SIGINT);
    if (lsm_signals_caught() != SIGINT) _exit(4);
    raise(SIGINT);
    sleep(10);
    _exit(5);
  }
  assert_true(child > 0);
  int status = 0;
  waitpid(child, &status, 0);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  const double seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
  struct stat sb;
  const int cleaned = stat(marker, &sb) == 0;
  unlink(marker);
  assert_true(WIFSIGNALED(status));
  assert_int_equal(WTERMSIG(status), SIGINT);
  assert_true(cleaned);
  assert_true(seconds < 5.0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_decide),
      cmocka_unit_test(test_names),
      cmocka_unit_test(test_owner_ended),
      cmocka_unit_test(test_guard),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
