/* lsm_temp: temporaries that say who made them (see the header). */
#define _XOPEN_SOURCE 700 /* nftw, readlink */
#include "io/lsm_temp.h"

#include <dirent.h>
#include <errno.h>
#include <ftw.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The first line of a small file into buf ("" when it cannot be read). */
static void read_line(const char *path, char *buf, size_t cap) {
  buf[0] = '\0';
  FILE *f = fopen(path, "r");
  if (!f) return;
  if (!fgets(buf, (int)cap, f)) buf[0] = '\0';
  fclose(f);
  buf[strcspn(buf, "\n")] = '\0';
}

/* The state letter and start time (field 22) of /proc/PID/stat.  1 when
 * read, 0 when there is no such process, -1 when it cannot be told. */
static int process_start(long pid, char *state, unsigned long long *start) {
  char path[64], text[1024];
  snprintf(path, sizeof path, "/proc/%ld/stat", pid);
  FILE *f = fopen(path, "r");
  if (!f) return errno == ENOENT ? 0 : -1;
  const size_t n = fread(text, 1, sizeof text - 1, f);
  fclose(f);
  text[n] = '\0';
  const char *p = strrchr(text, ')'); /* the command name may hold ')' and blanks */
  if (!p || p[1] != ' ') return -1;
  p += 2;
  *state = *p;
  for (int field = 3; field < 22; ++field) { /* to the 22nd field */
    p = strchr(p, ' ');
    if (!p) return -1;
    ++p;
  }
  char *end = NULL;
  errno = 0;
  *start = strtoull(p, &end, 10);
  return end != p && errno == 0 ? 1 : -1;
}

/* 64-bit FNV-1a of s, continuing from h. */
static uint64_t fnv1a(uint64_t h, const char *s) {
  for (; *s; ++s) {
    h ^= (unsigned char)*s;
    h *= 0x100000001b3ULL;
  }
  return h;
}

/* The machine part of a tag: 16 hex digits, "" where the system does not say. */
static void machine_id(char out[17]) {
  out[0] = '\0';
  char boot[128], ns[128];
  read_line("/proc/sys/kernel/random/boot_id", boot, sizeof boot);
  const ssize_t n = readlink("/proc/self/ns/pid", ns, sizeof ns - 1);
  if (!boot[0] || n <= 0) return;
  ns[n] = '\0';
  uint64_t h = fnv1a(0xcbf29ce484222325ULL, boot);
  h = fnv1a(fnv1a(h, "\n"), ns);
  snprintf(out, 17, "%016llx", (unsigned long long)h);
}

/* Whether /proc shows this pid namespace's processes: its "self" is getpid(). */
static int proc_is_ours(void) {
  char self[32];
  const ssize_t n = readlink("/proc/self", self, sizeof self - 1);
  if (n <= 0) return 0;
  self[n] = '\0';
  return strtol(self, NULL, 10) == (long)getpid();
}

void lsm_temp_tag(char tag[LSM_TEMP_TAG_MAX]) {
  tag[0] = '\0';
  char machine[17];
  machine_id(machine);
  const long pid = (long)getpid();
  char state = 0;
  unsigned long long start = 0;
  if (!machine[0] || !proc_is_ours() || process_start(pid, &state, &start) != 1) return;
  snprintf(tag, LSM_TEMP_TAG_MAX, "%ld.%llu.%s", pid, start, machine);
}

static int is_digit(char c) { return c >= '0' && c <= '9'; }
static int is_hex(char c) { return is_digit(c) || (c >= 'a' && c <= 'f'); }
static int is_alnum(char c) {
  return is_digit(c) || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}

/* The pid, start time and machine of a tag; 1 when it has that form. */
static int parse_tag(const char *tag, long *pid, unsigned long long *start, char machine[17]) {
  const char *p = tag;
  int k = 0;
  while (is_digit(p[k])) ++k;
  if (k == 0 || k > 9 || p[k] != '.') return 0;
  *pid = strtol(p, NULL, 10);
  p += k + 1;
  for (k = 0; is_digit(p[k]); ++k) {}
  if (k == 0 || k > 19 || p[k] != '.') return 0;
  *start = strtoull(p, NULL, 10);
  p += k + 1;
  for (k = 0; k < 16; ++k)
    if (!is_hex(p[k])) return 0;
  if (p[16] != '\0') return 0;
  memcpy(machine, p, 16);
  machine[16] = '\0';
  return *pid > 0;
}

int lsm_temp_name_tag(const char *name, const char *prefix, char tag[LSM_TEMP_TAG_MAX]) {
  tag[0] = '\0';
  const size_t np = strlen(prefix), n = strlen(name);
  if (n < np + 7 || strncmp(name, prefix, np) != 0 || name[n - 7] != '-') return 0;
  for (size_t k = n - 6; k < n; ++k)
    if (!is_alnum(name[k])) return 0;
  const size_t len = n - 7 - np;
  if (len >= LSM_TEMP_TAG_MAX) return 0;
  memcpy(tag, name + np, len);
  tag[len] = '\0';
  long pid = 0;
  unsigned long long start = 0;
  char machine[17];
  if (len == 0 || parse_tag(tag, &pid, &start, machine)) return 1;
  tag[0] = '\0';
  return 0;
}

int lsm_temp_owner_ended(const char *tag) {
  long pid = 0;
  unsigned long long start = 0, now_start = 0;
  char machine[17], mine[17], state = 0;
  if (!parse_tag(tag, &pid, &start, machine)) return 0;
  machine_id(mine);
  if (!mine[0] || strcmp(machine, mine) != 0) return 0; /* another kernel or pid namespace */
  if (!proc_is_ours()) return 0; /* a /proc of another namespace: its pids are not these */
  if (pid == (long)getpid()) return 0;
  const int found = process_start(pid, &state, &now_start);
  if (found == 0) return 1;  /* no such process */
  if (found < 0) return 0;   /* cannot tell */
  return now_start != start || state == 'Z' || state == 'X'; /* pid reused, or a zombie */
}

lsm_status lsm_temp_template(char *path, size_t cap, const char *stem, lsm_err *err) {
  char tag[LSM_TEMP_TAG_MAX];
  lsm_temp_tag(tag);
  const int n = snprintf(path, cap, "%s%s-XXXXXX", stem, tag);
  const char *slash = strrchr(path, '/');
  const size_t name = n < 0 ? 0 : strlen(slash ? slash + 1 : path);
  if (n < 0 || (size_t)n >= cap || name > 255)
    return lsm_fail(err, LSM_ERR_INPUT, stem, "the path is too long for a temporary beside it");
  return LSM_OK;
}

void lsm_temp_sweep(const char *dir, const char *prefix, const char *own_tag,
                    lsm_temp_sweep_result *r) {
  memset(r, 0, sizeof *r);
  DIR *d = opendir(dir);
  if (!d) return;
  const size_t np = strlen(prefix);
  char mine[17];
  machine_id(mine);
  for (struct dirent *e; (e = readdir(d)) != NULL;) {
    if (strncmp(e->d_name, prefix, np) != 0) continue;
    char tag[LSM_TEMP_TAG_MAX];
    const int formed = lsm_temp_name_tag(e->d_name, prefix, tag);
    const int remove_it = formed && tag[0] &&
                          (own_tag ? strcmp(tag, own_tag) == 0 : lsm_temp_owner_ended(tag));
    if (remove_it) {
      char path[4400];
      if (snprintf(path, sizeof path, "%s/%s", dir, e->d_name) >= (int)sizeof path) continue;
      if (lsm_remove_tree(path) == 0 && r->removed++ == 0)
        snprintf(r->first_removed, sizeof r->first_removed, "%s", e->d_name);
      continue;
    }
    if (own_tag) continue;
    /* a live run of this machine is no surprise; anything else is noted */
    long pid = 0;
    unsigned long long start = 0;
    char machine[17];
    const int live_here = formed && parse_tag(tag, &pid, &start, machine) && mine[0] &&
                          strcmp(machine, mine) == 0;
    if (!live_here && r->unproven++ == 0)
      snprintf(r->first_unproven, sizeof r->first_unproven, "%s", e->d_name);
  }
  closedir(d);
}

static int remove_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw) {
  (void)sb;
  (void)flag;
  (void)ftw;
  remove(path); /* go on past a failure: what is left is reported by the caller's lstat */
  return 0;
}

int lsm_remove_tree(const char *path) {
  if (!path || !*path) return -1;
  struct stat sb;
  if (lstat(path, &sb) != 0) return errno == ENOENT ? 0 : -1;
  if (!S_ISDIR(sb.st_mode)) return remove(path) == 0 || errno == ENOENT ? 0 : -1;
  nftw(path, remove_entry, 16, FTW_DEPTH | FTW_PHYS | FTW_MOUNT);
  return lstat(path, &sb) != 0 && errno == ENOENT ? 0 : -1;
}
