/* lsm_rules: the table of reconstruction rules and constants (see the header). */
#include "solver/recon/lsm_rules.h"

#include <string.h>

_Static_assert(LSM_RULE_COUNT <= 64, "lsm_rules.off has 64 bits");

typedef struct rule_text {
  const char *name, *what, *why, *off;
} rule_text;

#define LSM_RULE_TEXT(id, name, what, why, off) {name, what, why, off},
static const rule_text rule_texts[LSM_RULE_COUNT] = {LSM_RULE_LIST(LSM_RULE_TEXT)};
#undef LSM_RULE_TEXT

/* Removed rules: their fallback is how lsmorph works, so --rules-off takes
 * their names (scripts pass them) and has nothing to switch off. */
static const char *const removed_rules[] = {"align-in-place", "align-best-shift", "parts-clear",
                                            "parts-iou"};
#define REMOVED_RULES (sizeof removed_rules / sizeof removed_rules[0])

static const lsm_rules defaults = {
    0,
#define LSM_CONSTANT_VALUE(field, value, what) value,
    LSM_CONSTANT_LIST(LSM_CONSTANT_VALUE)
#undef LSM_CONSTANT_VALUE
};

void lsm_rules_default(lsm_rules *rules) { *rules = defaults; }

const lsm_rules *lsm_rules_defaults(void) { return &defaults; }

const char *lsm_rule_name(lsm_rule rule) {
  return (unsigned)rule < LSM_RULE_COUNT ? rule_texts[rule].name : NULL;
}

lsm_status lsm_rules_switch_off(lsm_rules *rules, const char *names, lsm_err *err) {
  if (!*names) return LSM_OK;
  for (const char *p = names;;) {
    const char *end = strchr(p, ',');
    const size_t len = end ? (size_t)(end - p) : strlen(p);
    int found = 0;
    for (int r = 0; r < LSM_RULE_COUNT && !found; ++r)
      if (strlen(rule_texts[r].name) == len && strncmp(rule_texts[r].name, p, len) == 0) {
        rules->off |= (uint64_t)1 << r;
        found = 1;
      }
    for (size_t r = 0; r < REMOVED_RULES && !found; ++r)
      found = strlen(removed_rules[r]) == len && strncmp(removed_rules[r], p, len) == 0;
    if (!found)
      return lsm_fail(err, LSM_ERR_USAGE, NULL,
                      "--rules-off: '%.*s' is not a rule (see 'lsmorph help rules')",
                      (int)(len > 64 ? 64 : len), p);
    if (!end) break;
    p = end + 1;
  }
  return LSM_OK;
}

/* Prints text after a label of `indent` columns, wrapped at 79 columns. */
static void print_wrapped(FILE *f, const char *label, int indent, const char *text) {
  int col = fprintf(f, "%-*s", indent, label);
  for (const char *p = text; *p;) {
    while (*p == ' ') ++p;
    const size_t len = strcspn(p, " ");
    if (col > indent && col + 1 + (int)len > 79) col = fprintf(f, "\n%*s", indent, "") - 1;
    else if (col > indent) col += fprintf(f, " ");
    col += fprintf(f, "%.*s", (int)len, p);
    p += len;
  }
  fputc('\n', f);
}

void lsm_rules_print(FILE *f) {
  fputs("lsmorph reconstruction rules\n\n"
        "Each rule is on by default; 'lsmorph reconstruct ... --rules-off NAME[,NAME...]'\n"
        "switches rules off, for experiments (run.json: options.rules_off).  Their\n"
        "effect on the validation's test split: validation/measurements/ablation.md.\n\n",
        f);
  for (int r = 0; r < LSM_RULE_COUNT; ++r) {
    fprintf(f, "%s\n", rule_texts[r].name);
    print_wrapped(f, "  what:", 8, rule_texts[r].what);
    print_wrapped(f, "  why:", 8, rule_texts[r].why);
    print_wrapped(f, "  off:", 8, rule_texts[r].off);
  }
  fputs("\nremoved (--rules-off still takes the names; they are always off now)\n", f);
  char names[256] = "";
  for (size_t r = 0; r < REMOVED_RULES; ++r) {
    const size_t n = strlen(names);
    snprintf(names + n, sizeof names - n, "%s%s", r ? ", " : "", removed_rules[r]);
  }
  print_wrapped(f, "", 2, names);
  fputs("\nconstants (defaults)\n", f);
  char label[64];
#define LSM_CONSTANT_PRINT(field, value, what)                     \
  snprintf(label, sizeof label, "  %s = %.4g", #field, defaults.field); \
  print_wrapped(f, label, 32, what);
  LSM_CONSTANT_LIST(LSM_CONSTANT_PRINT)
#undef LSM_CONSTANT_PRINT
}
