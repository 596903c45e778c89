/* The command line parsed into options (solver/app/lsm_cli.h): the defaults the
 * README's option table states, the --name=value form, and help topics. */
#include "lsm_test.h"

#include "solver/app/lsm_cli.h"

static lsm_status parse(lsm_cli *cli, lsm_err *err, int argc, char **argv) {
  lsm_err_clear(err);
  return lsm_cli_parse(argc, argv, cli, err);
}

/* README: "--device N | first GPU, else first device"; -1 asks the OpenCL
 * backend for that search (kernels/opencl/lsm_backend_cl.c). */
static void test_reconstruct_defaults(void **state) {
  (void)state;
  char *argv[] = {"lsmorph", "reconstruct", "in", "-o", "out"};
  lsm_cli cli;
  lsm_err err;
  assert_int_equal(parse(&cli, &err, 5, argv), LSM_OK);
  assert_int_equal(cli.command, LSM_CMD_RECONSTRUCT);
  assert_int_equal(cli.device, -1);
  assert_string_equal(cli.backend, "c");
  assert_true(cli.spacing == 1.0);
  assert_int_equal(cli.threads, 0);
  assert_true(cli.max_pixels == (uint64_t)1 << 26);
  assert_true(cli.max_voxels == (uint64_t)1 << 30);
  assert_true(cli.max_memory == 0);
  assert_int_equal(cli.stack.max_iter, 100000);
  assert_true(cli.stack.morph.cfl == 0.75);
  assert_true(cli.stack.tol == 0.25);
  assert_int_equal(cli.heights_from_names, 0);
  assert_int_equal(cli.spacing_given, 0);
  assert_int_equal(cli.nrrd_encoding, LSM_NRRD_RAW);
  assert_int_equal(cli.nrrd_encoding_given, 0);
  assert_true(cli.stack.pixel_dx == 1.0 && cli.stack.pixel_dy == 1.0);
}

static void test_long_forms(void **state) {
  (void)state;
  char *argv[] = {"lsmorph", "reconstruct", "in", "--output=out", "--device=2", "--quiet",
                  "--max-iter", "7", "--nrrd-encoding=gzip"};
  lsm_cli cli;
  lsm_err err;
  assert_int_equal(parse(&cli, &err, 9, argv), LSM_OK);
  assert_string_equal(cli.out_dir, "out");
  assert_int_equal(cli.device, 2);
  assert_int_equal(cli.quiet, 1);
  assert_int_equal(cli.stack.max_iter, 7);
  assert_int_equal(cli.nrrd_encoding, LSM_NRRD_GZIP);
  assert_int_equal(cli.nrrd_encoding_given, 1);
  char *raw[] = {"lsmorph", "reconstruct", "in", "-o", "out", "--nrrd-encoding", "raw"};
  assert_int_equal(parse(&cli, &err, 7, raw), LSM_OK);
  assert_int_equal(cli.nrrd_encoding, LSM_NRRD_RAW);
  char *bad[] = {"lsmorph", "reconstruct", "in", "-o", "out", "--nrrd-encoding", "bzip2"};
  assert_int_equal(parse(&cli, &err, 7, bad), LSM_ERR_USAGE);
  assert_non_null(strstr(err.msg, "--nrrd-encoding: 'bzip2' is not one of raw, gzip"));
}

/* How the slices are placed: --spacing, --heights, --heights-from-names. */
static void test_placement(void **state) {
  (void)state;
  lsm_cli cli;
  lsm_err err;
  char *names[] = {"lsmorph", "reconstruct", "in", "-o", "out", "--heights-from-names",
                   "--spacing", "2.5"};
  assert_int_equal(parse(&cli, &err, 8, names), LSM_OK);
  assert_int_equal(cli.heights_from_names, 1);
  assert_int_equal(cli.spacing_given, 1);
  assert_true(cli.spacing == 2.5);
  char *both[] = {"lsmorph", "reconstruct", "in", "-o", "out", "--heights", "z.txt",
                  "--heights-from-names"};
  assert_int_equal(parse(&cli, &err, 8, both), LSM_ERR_USAGE);
  assert_non_null(strstr(err.msg, "give one"));
  char *valued[] = {"lsmorph", "reconstruct", "in", "-o", "out", "--heights-from-names=1"};
  assert_int_equal(parse(&cli, &err, 6, valued), LSM_ERR_USAGE);
  assert_non_null(strstr(err.msg, "takes no value"));
}

/* --pixel-size S (square) or SX,SY (x, then y); each part a length. */
static void test_pixel_size(void **state) {
  (void)state;
  lsm_cli cli;
  lsm_err err;
  char *square[] = {"lsmorph", "reconstruct", "in", "-o", "out", "--pixel-size", "0.7"};
  assert_int_equal(parse(&cli, &err, 7, square), LSM_OK);
  assert_true(cli.stack.pixel_dx == 0.7 && cli.stack.pixel_dy == 0.7);
  char *two[] = {"lsmorph", "reconstruct", "in", "-o", "out", "--pixel-size=0.5,2e0"};
  assert_int_equal(parse(&cli, &err, 6, two), LSM_OK);
  assert_true(cli.stack.pixel_dx == 0.5 && cli.stack.pixel_dy == 2.0);
  const char *bad[][2] = {{"1,", "--pixel-size: '' is not a number"},
                          {",1", "--pixel-size: '' is not a number"},
                          {"1,2,3", "is not one size S or two sizes SX,SY"},
                          {"1,0", "--pixel-size: 0 must be positive"},
                          {"1;2", "--pixel-size: '1;2' is not a number"},
                          {"1,1e40", "--pixel-size: 1e40 is outside"}};
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    char *argv[] = {"lsmorph", "reconstruct", "in", "-o", "out", "--pixel-size", (char *)bad[k][0]};
    assert_int_equal(parse(&cli, &err, 7, argv), LSM_ERR_USAGE);
    if (!strstr(err.msg, bad[k][1]))
      fail_msg("--pixel-size %s: '%s', expected '%s'", bad[k][0], err.msg, bad[k][1]);
  }
}

/* score: --stride and --first are optional (run.json places the inputs). */
static void test_score_options(void **state) {
  (void)state;
  lsm_cli cli;
  lsm_err err;
  char *bare[] = {"lsmorph", "score", "truth", "out"};
  assert_int_equal(parse(&cli, &err, 4, bare), LSM_OK);
  assert_int_equal(cli.command, LSM_CMD_SCORE);
  assert_int_equal(cli.stride, 0);
  assert_int_equal(cli.first, 0);
  char *both[] = {"lsmorph", "score", "--first=5", "truth", "out", "--stride", "8"};
  assert_int_equal(parse(&cli, &err, 7, both), LSM_OK);
  assert_int_equal(cli.first, 5);
  assert_int_equal(cli.stride, 8);
  assert_int_equal(cli.per_slice, 0);
  char *per[] = {"lsmorph", "score", "truth", "--per-slice", "out"};
  assert_int_equal(parse(&cli, &err, 5, per), LSM_OK);
  assert_int_equal(cli.per_slice, 1);
  assert_string_equal(cli.result_dir, "out");
  char *bad[] = {"lsmorph", "score", "truth", "out", "--first", "x"};
  assert_int_equal(parse(&cli, &err, 6, bad), LSM_ERR_USAGE);
  assert_non_null(strstr(err.msg, "--first"));
}

/* reconstruct in -o out OPT VALUE parsed into *cli (LSM_OK). */
static void parse_option(lsm_cli *cli, const char *opt, const char *value) {
  lsm_err err;
  char *argv[] = {"lsmorph", "reconstruct", "in", "-o", "out", (char *)opt, (char *)value};
  assert_int_equal(parse(cli, &err, 7, argv), LSM_OK);
}

/* Every name of an enum list (COUNT of them, NAME_OF each) given to OPT
 * gives its value in FIELD. */
#define EVERY_NAME(opt, count, name_of, field)                                 \
  for (int k = 0; k < (count); ++k) {                                          \
    parse_option(&cli, opt, name_of(k));                                       \
    assert_int_equal(cli.field, k);                                            \
  }

/* Every name of every choice option's enum list is accepted and gives its
 * value; a name outside the list is refused with the list. */
static void test_choices(void **state) {
  (void)state;
  lsm_cli cli;
  lsm_err err;
  EVERY_NAME("--method", LSM_METHOD_COUNT, lsm_method_name, stack.method)
  EVERY_NAME("--align", LSM_ALIGN_COUNT, lsm_align_name, stack.align)
  EVERY_NAME("--ends", LSM_ENDS_COUNT, lsm_end_rule_name, stack.ends)
  EVERY_NAME("--scheme", LSM_SCHEME_COUNT, lsm_scheme_name, stack.morph.scheme)
  EVERY_NAME("--values", LSM_VALUES_COUNT, lsm_values_name, values)
  static const char *const backends[] = {LSM_BACKEND_TABLE(LSM_BACKEND_NAME) "auto"};
  for (size_t k = 0; k < sizeof backends / sizeof *backends; ++k) {
    parse_option(&cli, "--backend", backends[k]);
    assert_string_equal(cli.backend, backends[k]);
  }
  char *rk3[] = {"lsmorph", "reconstruct", "in", "-o", "out", "--time", "rk3"};
  assert_int_equal(parse(&cli, &err, 7, rk3), LSM_OK);
  assert_int_equal(cli.stack.morph.time, LSM_TIME_RK3);
  char *interp[] = {"lsmorph", "reconstruct", "in", "-o", "out", "--interp=linear"};
  assert_int_equal(parse(&cli, &err, 6, interp), LSM_OK);
  assert_int_equal(cli.stack.interp, LSM_INTERP_LINEAR);
  assert_int_equal(cli.interp_given, 1);
  char *input[] = {"lsmorph", "reconstruct", "in", "-o", "out", "--input", "outline"};
  assert_int_equal(parse(&cli, &err, 7, input), LSM_OK);
  assert_int_equal(cli.stack.input, LSM_INPUT_OUTLINE);
  char *bad[] = {"lsmorph", "reconstruct", "in", "-o", "out", "--method", "magic"};
  assert_int_equal(parse(&cli, &err, 7, bad), LSM_ERR_USAGE);
  assert_string_equal(err.msg, "--method: 'magic' is not one of ls, pls, blend");
  char *bad_align[] = {"lsmorph", "reconstruct", "in", "-o", "out", "--align", ""};
  assert_int_equal(parse(&cli, &err, 7, bad_align), LSM_ERR_USAGE);
  assert_string_equal(err.msg, "--align: '' is not one of auto, hull, none");
}

static void test_help_topics(void **state) {
  (void)state;
  const char *topics[] = {"reconstruct", "score", "devices"};
  for (size_t k = 0; k < sizeof topics / sizeof topics[0]; ++k) {
    char *argv[] = {"lsmorph", "help", (char *)topics[k]};
    lsm_cli cli;
    lsm_err err;
    assert_int_equal(parse(&cli, &err, 3, argv), LSM_OK);
    assert_int_equal(cli.command, LSM_CMD_HELP);
    assert_string_equal(cli.help_topic, topics[k]);
  }
  char *devices_help[] = {"lsmorph", "devices", "--help"};
  lsm_cli cli;
  lsm_err err;
  assert_int_equal(parse(&cli, &err, 3, devices_help), LSM_OK);
  assert_int_equal(cli.command, LSM_CMD_HELP);
  assert_string_equal(cli.help_topic, "devices");
  char *unknown[] = {"lsmorph", "help", "nothing"};
  assert_int_equal(parse(&cli, &err, 3, unknown), LSM_ERR_USAGE);
  assert_non_null(strstr(err.msg, "help devices"));
  char *extra[] = {"lsmorph", "devices", "0"};
  assert_int_equal(parse(&cli, &err, 3, extra), LSM_ERR_USAGE);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_reconstruct_defaults),
      cmocka_unit_test(test_long_forms),
      cmocka_unit_test(test_placement),
      cmocka_unit_test(test_pixel_size),
      cmocka_unit_test(test_score_options),
      cmocka_unit_test(test_choices),
      cmocka_unit_test(test_help_topics),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
