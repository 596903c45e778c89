/* The table of backends and opening one by name. */
#include "solver/pde/lsm_backend.h"

#include <stdlib.h>
#include <string.h>

/* The reference first: "auto" tries the others in this order and falls back to it. */
typedef struct row {
  const char *name;
  const lsm_backend_entry *entry;
} row;
#define ROW(name, entry) {name, &entry},
static const row backends[] = {LSM_BACKEND_TABLE(ROW)};
enum { BACKEND_COUNT = (int)(sizeof backends / sizeof *backends) };

static int find(const char *name) {
  for (int k = 0; name && k < BACKEND_COUNT; ++k)
    if (strcmp(name, backends[k].name) == 0) return k;
  return -1;
}

const lsm_backend_entry *lsm_backend_find(const char *name) {
  const int k = find(name);
  return k < 0 ? NULL : backends[k].entry;
}

void lsm_backend_names(char *buf, size_t size) {
  size_t used = 0;
  if (size == 0) return;
  buf[0] = '\0';
  for (int k = 0; k <= BACKEND_COUNT && used < size; ++k) {
    const int n = snprintf(buf + used, size - used, "%s%s", k ? ", " : "",
                           k < BACKEND_COUNT ? backends[k].name : "auto");
    if (n < 0) break;
    used += (size_t)n;
  }
}

static lsm_status open_row(int k, int device, int threads, lsm_backend *b, lsm_err *err) {
  b->name = backends[k].name;
  b->entry = backends[k].entry;
  b->ctx = NULL;
  return b->entry->open(device, threads, &b->ctx, err);
}

lsm_status lsm_backend_open(const char *name, int device, int threads, lsm_backend **out,
                            lsm_err *err) {
  *out = NULL;
  const int automatic = name && strcmp(name, "auto") == 0;
  int want = automatic ? 0 : find(name);
  if (want < 0) {
    char names[256];
    lsm_backend_names(names, sizeof names);
    return lsm_fail(err, LSM_ERR_USAGE, NULL, "backend '%s' is not one of %s",
                    name ? name : "(none)", names);
  }
  lsm_backend *b = calloc(1, sizeof *b);
  if (!b) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate a backend");
  lsm_status st;
  if (automatic) {
    for (int k = 1; k < BACKEND_COUNT; ++k) {
      lsm_err why;
      lsm_err_clear(&why);
      if (open_row(k, device, threads, b, &why) == LSM_OK) {
        *out = b;
        return LSM_OK;
      }
      snprintf(b->fallback, sizeof b->fallback, "%s", why.msg);
    }
  }
  st = open_row(want, device, threads, b, err);
  if (st != LSM_OK) {
    free(b);
    return st;
  }
  *out = b;
  return LSM_OK;
}

void lsm_backend_close(lsm_backend **backend) {
  if (!backend || !*backend) return;
  lsm_backend *b = *backend;
  if (b->entry) b->entry->ops->close(b->ctx);
  free(b);
  *backend = NULL;
}

const char *lsm_backend_name(const lsm_backend *b) { return b->name; }
const char *lsm_backend_fallback(const lsm_backend *b) { return b->fallback; }
int lsm_backend_host_threads(const lsm_backend *b) { return b->entry->host_threads; }

int lsm_backend_motion(const lsm_backend *b, struct lsm_motion_device *dev) {
  if (!b || !b->entry->ops->motion) return 0;
  b->entry->ops->motion(b->ctx, dev);
  return 1;
}

int lsm_backend_facts(const lsm_backend *b, lsm_backend_fact *facts, int max) {
  return b->entry->ops->facts(b->ctx, facts, max);
}

int lsm_backend_contract_facts(lsm_backend_fact *facts, int max, const char *device,
                               double build_seconds) {
  const lsm_backend_fact contract[] = {
      {"device", LSM_FACT_TEXT, device, 0.0, 0},
      {"build_seconds", LSM_FACT_NUMBER, NULL, build_seconds, 0},
      {"kernel_cache_hit", LSM_FACT_FLAG, NULL, 0.0, 0},
  };
  int n = 0;
  for (; n < max && n < (int)(sizeof contract / sizeof *contract); ++n) facts[n] = contract[n];
  return n;
}

const char *lsm_backend_device(const lsm_backend *b) {
  lsm_backend_fact facts[LSM_BACKEND_FACTS_MAX];
  const int n = lsm_backend_facts(b, facts, LSM_BACKEND_FACTS_MAX);
  for (int k = 0; k < n; ++k)
    if (facts[k].kind == LSM_FACT_TEXT && strcmp(facts[k].key, "device") == 0)
      return facts[k].text;
  return "?";
}

lsm_status lsm_backend_list_devices(FILE *f, lsm_err *err) {
  lsm_status st = lsm_fail(err, LSM_ERR_UNSUPPORTED, NULL, "no backend lists devices");
  for (int k = 0; k < BACKEND_COUNT; ++k)
    if (backends[k].entry->list_devices) {
      lsm_err_clear(err);
      st = backends[k].entry->list_devices(f, err);
      if (st != LSM_OK) return st;
    }
  return st;
}
