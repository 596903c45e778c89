/* Tests for solver/recon/lsm_rules: the table of reconstruction rules and
 * constants, and --rules-off's list of names. */
#include "tests/lsm_test.h"

#include <ctype.h>

#include "solver/recon/lsm_rules.h"

/* Every rule has a distinct name of lowercase letters and hyphens, and a
 * list of every name switches every rule off. */
static void test_names(void **state) {
  (void)state;
  char all[4096] = "";
  for (int r = 0; r < LSM_RULE_COUNT; ++r) {
    const char *name = lsm_rule_name((lsm_rule)r);
    assert_non_null(name);
    assert_true(name[0] != '\0');
    for (const char *c = name; *c; ++c) assert_true(islower((unsigned char)*c) || *c == '-');
    for (int q = 0; q < r; ++q) assert_string_not_equal(name, lsm_rule_name((lsm_rule)q));
    if (r) strcat(all, ",");
    strcat(all, name);
  }
  assert_null(lsm_rule_name(LSM_RULE_COUNT));
  lsm_rules rules;
  lsm_rules_default(&rules);
  lsm_err err;
  lsm_err_clear(&err);
  for (int r = 0; r < LSM_RULE_COUNT; ++r) assert_true(lsm_rule_on(&rules, (lsm_rule)r));
  assert_int_equal(lsm_rules_switch_off(&rules, all, &err), LSM_OK);
  for (int r = 0; r < LSM_RULE_COUNT; ++r) assert_false(lsm_rule_on(&rules, (lsm_rule)r));
}

/* A list switches off what it names and nothing else; an unknown or empty
 * name is a usage error that names it; "" switches off nothing. */
static void test_switch_off(void **state) {
  (void)state;
  lsm_rules rules;
  lsm_err err;
  lsm_rules_default(&rules);
  lsm_err_clear(&err);
  assert_int_equal(lsm_rules_switch_off(&rules, "end-floor,moving-parts", &err), LSM_OK);
  for (int r = 0; r < LSM_RULE_COUNT; ++r)
    assert_int_equal(lsm_rule_on(&rules, (lsm_rule)r),
                     r != LSM_RULE_END_FLOOR && r != LSM_RULE_MOVING_PARTS);
  lsm_rules_default(&rules);
  assert_int_equal(lsm_rules_switch_off(&rules, "", &err), LSM_OK);
  assert_int_equal(rules.off, 0);
  const char *bad[] = {"end-flor", "end-floor,", ",end-floor", "end-floor,,omega", "END-FLOOR",
                       "end-floors", "end"};
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    lsm_err_clear(&err);
    assert_int_equal(lsm_rules_switch_off(&rules, bad[k], &err), LSM_ERR_USAGE);
    assert_non_null(strstr(err.msg, "is not a rule"));
  }
  /* a removed rule's name is taken and switches nothing off */
  lsm_rules_default(&rules);
  assert_int_equal(lsm_rules_switch_off(&rules, "parts-iou,parts-clear,align-best-shift", &err), LSM_OK);
  assert_int_equal(rules.off, 0);
  assert_int_equal(lsm_rules_switch_off(&rules, "align-in-place,omega", &err), LSM_OK);
  for (int r = 0; r < LSM_RULE_COUNT; ++r)
    assert_int_equal(lsm_rule_on(&rules, (lsm_rule)r), r != LSM_RULE_OMEGA);
  lsm_err_clear(&err);
  assert_int_equal(lsm_rules_switch_off(&rules, "parts-io", &err), LSM_ERR_USAGE);
  lsm_err_clear(&err);
  lsm_rules_switch_off(&rules, "omega,no-such-rule", &err);
  assert_non_null(strstr(err.msg, "'no-such-rule'"));
}

/* The defaults: every rule on, the constants as documented; NULL stands for
 * them. */
static void test_defaults(void **state) {
  (void)state;
  const lsm_rules *d = lsm_rules_defaults();
  assert_int_equal(d->off, 0);
  assert_true(lsm_rule_on(NULL, LSM_RULE_OMEGA));
  assert_close(d->align_alike_iou, 0.5, 0.0);
  assert_close(d->parts_area_ratio, 2.0, 0.0);
  assert_close(d->pinhole_fill_cells, 4.0, 0.0);
  assert_close(d->end_share_flat + d->end_share_ramp, 0.6, 1e-15);
  assert_close(d->end_floor, 0.1, 0.0);
  lsm_rules r;
  lsm_rules_default(&r);
  assert_memory_equal(&r, d, sizeof r);
}

/* The help topic lists every rule and every constant. */
static void test_print(void **state) {
  (void)state;
  char *text = NULL;
  size_t size = 0;
  FILE *f = open_memstream(&text, &size);
  assert_non_null(f);
  lsm_rules_print(f);
  fclose(f);
  for (int r = 0; r < LSM_RULE_COUNT; ++r) {
    char line[64];
    snprintf(line, sizeof line, "\n%s\n  what: ", lsm_rule_name((lsm_rule)r));
    if (!strstr(text, line)) fail_msg("rule %s is not listed", lsm_rule_name((lsm_rule)r));
  }
  assert_non_null(strstr(text, "  end_floor = 0.1 "));
  assert_non_null(strstr(text, "  parts_area_ratio = 2 "));
  assert_non_null(strstr(text, "\n  align-in-place, align-best-shift, parts-clear, parts-iou\n"));
  free(text);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_names),
      cmocka_unit_test(test_switch_off),
      cmocka_unit_test(test_defaults),
      cmocka_unit_test(test_print),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
