/* Tests of the io room's file and text helpers: the natural sort of slice
 * names and the number a name ends with, heights lists (parsed from text and
 * read from files, good and bad), folder listing and creation, whole-file
 * reads with their limits, and the small JSON reader that reads run.json
 * (numbers, arrays of numbers, strings and their escapes). */
#include "tests/lsm_test_io.h"

#include <sys/stat.h>

#include "io/lsm_io.h"

/* ---- natural sort ------------------------------------------------------------- */

static int cmp_natural_qsort(const void *a, const void *b) {
  return lsm_natural_cmp(*(const char *const *)a, *(const char *const *)b);
}

static void test_natural_cmp(void **state) {
  (void)state;
  assert_true(lsm_natural_cmp("2.png", "10.png") < 0);
  assert_true(lsm_natural_cmp("10.png", "2.png") > 0);
  assert_true(lsm_natural_cmp("a2", "a10") < 0);
  assert_true(lsm_natural_cmp("a10", "b1") < 0);
  assert_true(lsm_natural_cmp("a2", "b1") < 0);
  assert_true(lsm_natural_cmp("slice_9.png", "slice_10.png") < 0);
  assert_true(lsm_natural_cmp("x99999999999999999999999", "x100000000000000000000000") < 0);
  assert_true(lsm_natural_cmp("abc", "abc") == 0);
  assert_true(lsm_natural_cmp("", "a") < 0);
  assert_true(lsm_natural_cmp("a", "a1") < 0);
  /* equal numbers with leading zeros: not 0, antisymmetric, stable */
  int c1 = lsm_natural_cmp("01.png", "1.png"), c2 = lsm_natural_cmp("1.png", "01.png");
  assert_true(c1 != 0);
  assert_true((c1 < 0) == (c2 > 0));
  assert_int_equal(c1, lsm_natural_cmp("01.png", "1.png"));
  assert_true(lsm_natural_cmp("001", "01") != 0);
  assert_true(lsm_natural_cmp("01.png", "2.png") < 0); /* value first */
  assert_true(lsm_natural_cmp("img007b", "img7a") > 0); /* 'b' > 'a' after equal 7 */

  const char *names[] = {"10.png", "2.png", "b1", "a10", "1.png", "a2", "01.png", "001.png", "0.png"};
  const char *want[] = {"0.png", "001.png", "01.png", "1.png", "2.png", "10.png", "a2", "a10", "b1"};
  size_t n = sizeof names / sizeof names[0];
  const char *sorted[sizeof names / sizeof names[0]];
  memcpy(sorted, names, sizeof names);
  qsort(sorted, n, sizeof sorted[0], cmp_natural_qsort);
  for (size_t i = 0; i < n; ++i) assert_string_equal(sorted[i], want[i]);
}

/* The number a slice's file name ends with (the note on numbered names). */
static void test_name_number(void **state) {
  (void)state;
  uint64_t n = 12345;
  assert_int_equal(lsm_name_number("dir/slice_0009.png", &n), 1);
  assert_true(n == 9);
  assert_int_equal(lsm_name_number("12b.png", &n), 1); /* the last run of digits */
  assert_true(n == 12);
  assert_int_equal(lsm_name_number("ct_2024_113.PNG", &n), 1);
  assert_true(n == 113);
  assert_int_equal(lsm_name_number("0000.png", &n), 1);
  assert_true(n == 0);
  assert_int_equal(lsm_name_number("x/7", &n), 1); /* no extension */
  assert_true(n == 7);
  assert_int_equal(lsm_name_number(".5.png", &n), 1);
  assert_true(n == 5);
  assert_int_equal(lsm_name_number("999999999999999999.png", &n), 1); /* 18 digits */
  assert_true(n == UINT64_C(999999999999999999));
  n = 42;
  assert_int_equal(lsm_name_number("1234567890123456789.png", &n), 0); /* 19 digits */
  assert_int_equal(lsm_name_number("slice.png", &n), 0);
  assert_int_equal(lsm_name_number("d1r/a.png", &n), 0); /* digits in the folder only */
  assert_int_equal(lsm_name_number("a.7z", &n), 0);     /* digits in the extension only */
  assert_true(n == 42); /* untouched when there is no number */
}

/* ---- heights ----------------------------------------------------------------------- */

static void test_heights_good(void **state) {
  (void)state;
  const char *text =
      "\xEF\xBB\xBF# slice heights in mm, after a UTF-8 byte order mark\n"
      "\n"
      "  -3.5 # the first slice\n"
      "-1e-1\r\n"
      "\t0#no space before the comment\n"
      "# comment in the middle\n"
      "   \n"
      "2.5E+1  \n"
      "+26\n"
      "1.25e2"; /* no final newline */
  double *z = NULL;
  size_t n = 0;
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st = lsm_heights_parse(text, strlen(text), "heights.txt", &z, &n, &err);
  if (st != LSM_OK) fail_msg("%s", err.msg);
  const double want[] = {-3.5, -0.1, 0.0, 25.0, 26.0, 125.0};
  assert_int_equal(n, sizeof want / sizeof want[0]);
  for (size_t i = 0; i < n; ++i) assert_true(z[i] == want[i]);
  free(z);
}

static void test_heights_bad(void **state) {
  (void)state;
  static const struct {
    const char *text;
    const char *needle;
  } cases[] = {
      {"1\nnan\n", "line 2: \"nan\" is not a number"},
      {"1\n2\ninf\n", "line 3: \"inf\" is not a number"},
      {"-infinity\n", "line 1:"},
      {"1\n2\nabc\n", "line 3: \"abc\" is not a number"},
      {"1\n2 x\n", "line 2: \"2 x\" is not a number"},
      {"1\n2.5mm\n", "line 2:"},
      {"0x10\n", "line 1:"},
      {"1\n1e999\n", "line 2:"},
      {"1\n3\n\n2\n", "line 4: 2 is not greater than the previous height 3"},
      {"# c\n0.5\n0.5\n", "line 3: 0.5 is not greater than the previous height 0.5"},
      {"0\n75\n50\n", "line 3: 50 is not greater than the previous height 75"},
      {"100\n120\n120\n", "line 3: 120 is not greater than the previous height 120"},
      {"1e-400\n1\n", "line 1: \"1e-400\" is out of range"},
      {"0\n-1e-400\n1\n", "line 2: \"-1e-400\" is out of range"},
      {"1\n2 3 # two values\n", "line 2: \"2 3\" is not a number"},
      {"\xEF\xBB" "1\n", "line 1:"}, /* half a byte order mark */
      {"", "no heights"},
      {"# only a comment\n\n   \n", "no heights"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
    double *z = (double *)&z; /* must be reset to NULL */
    size_t n = 99;
    lsm_err err;
    lsm_err_clear(&err);
    lsm_status st = lsm_heights_parse(cases[i].text, strlen(cases[i].text), "heights.txt", &z, &n, &err);
    if (st != LSM_ERR_INPUT) fail_msg("case %zu: status %d (%s)", i, (int)st, err.msg);
    assert_null(z);
    assert_int_equal(n, 0);
    assert_true(strncmp(err.msg, "heights.txt: ", 13) == 0);
    assert_msg_contains(err, cases[i].needle);
  }
  /* a NUL byte inside the text is refused, not silently cut */
  const char nul_text[] = {'1', '\n', '2', '\0', '5', '\n'};
  double *z = NULL;
  size_t n = 0;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_heights_parse(nul_text, sizeof nul_text, "h", &z, &n, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, "line 2");
}

static void test_heights_read(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  join(path, sizeof path, f->dir, "heights.txt");
  const char *text = "0\n1.5\n3\n";
  write_bytes(path, text, strlen(text));
  double *z = NULL;
  size_t n = 0;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_heights_read(path, &z, &n, &err), LSM_OK);
  assert_int_equal(n, 3);
  assert_true(z[0] == 0.0 && z[1] == 1.5 && z[2] == 3.0);
  free(z);

  write_bytes(path, "1\n0\n", 4);
  lsm_err_clear(&err);
  assert_int_equal(lsm_heights_read(path, &z, &n, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, path);
  assert_msg_contains(err, "line 2");

  join(path, sizeof path, f->dir, "missing.txt");
  lsm_err_clear(&err);
  assert_int_equal(lsm_heights_read(path, &z, &n, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, path);
}

/* ---- folders --------------------------------------------------------------------------- */

static void test_dir_list(void **state) {
  tmp_fixture *f = *state;
  const char *files[] = {"10.png", "2.png",   "1.PNG",  "notes.txt", ".hidden.png",
                         "png",    "x.png.txt", "3.TIF", "4.jpeg",    ".5.tif",
                         "6.tiff", "7.bmp"};
  char path[256];
  for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
    join(path, sizeof path, f->dir, files[i]);
    write_bytes(path, "x", 1);
  }
  join(path, sizeof path, f->dir, "subdir.png");
  assert_int_equal(mkdir(path, 0755), 0);

  char **list = NULL;
  size_t n = 0;
  lsm_err err;
  lsm_err_clear(&err);
  size_t others = 99;
  assert_int_equal(lsm_dir_list_slices(f->dir, &list, &n, &others, &err), LSM_OK);
  assert_int_equal(n, 5);
  /* images of other formats: 4.jpeg and 7.bmp (not the hidden .5.tif, nor
   * notes.txt, png, x.png.txt) */
  assert_int_equal(others, 2);
  const char *want[] = {"1.PNG", "2.png", "3.TIF", "6.tiff", "10.png"};
  for (size_t i = 0; i < 5; ++i) {
    join(path, sizeof path, f->dir, want[i]);
    assert_string_equal(list[i], path);
  }
  lsm_path_list_free(list, n);

  /* a trailing slash does not double up */
  char slashed[256];
  snprintf(slashed, sizeof slashed, "%s/", f->dir);
  assert_int_equal(lsm_dir_list_slices(slashed, &list, &n, NULL, &err), LSM_OK);
  assert_int_equal(n, 5);
  join(path, sizeof path, f->dir, "1.PNG");
  assert_string_equal(list[0], path);
  lsm_path_list_free(list, n);

  /* an empty folder lists nothing */
  join(path, sizeof path, f->dir, "empty");
  assert_int_equal(mkdir(path, 0755), 0);
  assert_int_equal(lsm_dir_list_slices(path, &list, &n, NULL, &err), LSM_OK);
  assert_int_equal(n, 0);
  lsm_path_list_free(list, n);
}

static void test_dir_errors(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  char **list = (char **)&list;
  size_t n = 5;
  lsm_err err;
  join(path, sizeof path, f->dir, "nope");
  lsm_err_clear(&err);
  assert_int_equal(lsm_dir_list_slices(path, &list, &n, NULL, &err), LSM_ERR_INPUT);
  assert_null(list);
  assert_int_equal(n, 0);
  assert_msg_contains(err, path);
  assert_msg_contains(err, "no such folder");

  join(path, sizeof path, f->dir, "file.png");
  write_bytes(path, "x", 1);
  lsm_err_clear(&err);
  assert_int_equal(lsm_dir_list_slices(path, &list, &n, NULL, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, "not a folder");
}

static void test_make_dir(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  lsm_err err;
  lsm_err_clear(&err);
  join(path, sizeof path, f->dir, "out");
  assert_int_equal(lsm_make_dir(path, &err), LSM_OK);
  struct stat sb;
  assert_int_equal(stat(path, &sb), 0);
  assert_true(S_ISDIR(sb.st_mode));
  assert_int_equal(lsm_make_dir(path, &err), LSM_OK); /* exists: fine */

  join(path, sizeof path, f->dir, "plain");
  write_bytes(path, "x", 1);
  assert_int_equal(lsm_make_dir(path, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, path);

  join(path, sizeof path, f->dir, "a/b/c");
  lsm_err_clear(&err);
  assert_int_equal(lsm_make_dir(path, &err), LSM_ERR_IO); /* one level only */
  assert_msg_contains(err, path);
}

static void test_read_file(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  join(path, sizeof path, f->dir, "data.bin");
  uint8_t bytes[10000];
  uint64_t seed = 5;
  for (size_t k = 0; k < sizeof bytes; ++k) bytes[k] = (uint8_t)lsm_test_rand(&seed);
  write_bytes(path, bytes, sizeof bytes);

  char *data = NULL;
  size_t len = 0;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_read_file(path, sizeof bytes, &data, &len, &err), LSM_OK);
  assert_int_equal(len, sizeof bytes);
  assert_memory_equal(data, bytes, sizeof bytes);
  assert_int_equal(data[len], '\0');
  free(data);

  assert_int_equal(lsm_read_file(path, sizeof bytes - 1, &data, &len, &err), LSM_ERR_LIMIT);
  assert_null(data);
  assert_msg_contains(err, path);

  join(path, sizeof path, f->dir, "empty.txt");
  write_bytes(path, "", 0);
  lsm_err_clear(&err);
  assert_int_equal(lsm_read_file(path, 0, &data, &len, &err), LSM_OK);
  assert_int_equal(len, 0);
  assert_int_equal(data[0], '\0');
  free(data);

  join(path, sizeof path, f->dir, "missing.txt");
  assert_int_equal(lsm_read_file(path, 100, &data, &len, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, path);

  lsm_err_clear(&err);
  assert_int_equal(lsm_read_file(f->dir, 100, &data, &len, &err), LSM_ERR_INPUT);
  assert_msg_contains(err, "folder");
}

/* lsm_json_find_number: a member path through any valid formatting; invalid
 * JSON is refused wherever it breaks, not only on the way to the member. */
static void test_json_find_number(void **state) {
  (void)state;
  static const char *const path[] = {"input", "slices"};
  double v = 0.0;
  size_t at = 0;
  assert_int_equal(lsm_json_find_number("{\"input\": {\"folder\": \"a\", \"slices\": 15}}", path, 2, &v, &at), 1);
  assert_true(v == 15.0);
  /* indented, reordered, with arrays, escapes and literals around it */
  const char *pretty =
      "{\n  \"pairs\": [ {\"slices\": 7}, [1, 2.5e-3, -0, true, false, null] ],\n"
      "  \"name\": \"a \\\"quoted\\\" \\u00e9 \\\\ name\",\n"
      "  \"input\": {\n    \"slices\": 3E+1\n  }\n}\n";
  assert_int_equal(lsm_json_find_number(pretty, path, 2, &v, &at), 1);
  assert_true(v == 30.0);
  /* a later duplicate wins; the key must match whole and at its level */
  assert_int_equal(lsm_json_find_number("{\"input\":{\"slices\":1,\"slices\":2}}", path, 2, &v, &at), 1);
  assert_true(v == 2.0);
  assert_int_equal(lsm_json_find_number("{\"input\":{\"slice\":1},\"slices\":4}", path, 2, &v, &at), 0);
  assert_int_equal(lsm_json_find_number("{\"x\":{\"input\":{\"slices\":4}}}", path, 2, &v, &at), 0);
  assert_int_equal(lsm_json_find_number("{\"input\":{\"slices\":\"4\"}}", path, 2, &v, &at), 0);
  assert_int_equal(lsm_json_find_number("[1, {\"input\":{\"slices\":4}}]", path, 2, &v, &at), 0);
  /* invalid: where it breaks */
  static const struct { const char *text; size_t at; } bad[] = {
      {"{", 1},
      {"{\"input\": {\"slices\": 3}", 23},
      {"{\"input\": {\"slices\": 3},}", 24},
      {"{\"input\": {\"slices\": 03}}", 22},
      {"{\"input\": {\"slices\": 3.}}", 23},
      {"{\"input\": {\"slices\": 3}} x", 25},
      {"{\"a\": tru}", 6},
      {"{\"a\": \"\\x\"}", 7},
      {"{\"a\": \"\\u12g4\"}", 7},
      {"{\"a\": \"line\nbreak\"}", 11},
      {"", 0},
  };
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    at = 999;
    assert_int_equal(lsm_json_find_number(bad[k].text, path, 2, &v, &at), -1);
    assert_int_equal(at, bad[k].at);
  }
  /* nesting: 256 levels read, 300 refused (no stack overflow on deeper) */
  char deep[1000];
  for (int depth = 256; depth <= 300; depth += 44) {
    size_t n = 0;
    for (int k = 0; k < depth; ++k) deep[n++] = '[';
    for (int k = 0; k < depth; ++k) deep[n++] = ']';
    deep[n] = '\0';
    assert_int_equal(lsm_json_find_number(deep, path, 2, &v, &at), depth <= 256 ? 0 : -1);
  }
}

/* lsm_json_find_numbers: an array of numbers by its member path, in any
 * formatting; its length without a buffer; only arrays of numbers count. */
static void test_json_find_numbers(void **state) {
  (void)state;
  static const char *const path[] = {"input", "heights"};
  double v[4] = {0.0, 0.0, 0.0, 0.0};
  size_t n = 99, at = 0;
  const char *run = "{\"input\": {\"files\": [\"1.png\", \"9.png\"], \"heights\":\n"
                    "  [ 1 ,9,\t-2.5e1 ]}, \"options\": {\"heights\": [7]}}";
  assert_int_equal(lsm_json_find_numbers(run, path, 2, NULL, 0, &n, &at), 1);
  assert_int_equal(n, 3);
  assert_int_equal(lsm_json_find_numbers(run, path, 2, v, 4, &n, &at), 1);
  assert_int_equal(n, 3);
  assert_true(v[0] == 1.0 && v[1] == 9.0 && v[2] == -25.0 && v[3] == 0.0);
  /* a buffer shorter than the array: its first elements, and the length */
  v[0] = v[1] = 0.0;
  assert_int_equal(lsm_json_find_numbers(run, path, 2, v, 1, &n, &at), 1);
  assert_int_equal(n, 3);
  assert_true(v[0] == 1.0 && v[1] == 0.0);
  /* empty; a later duplicate wins, also when it is not an array of numbers */
  assert_int_equal(lsm_json_find_numbers("{\"input\":{\"heights\":[ ]}}", path, 2, v, 4, &n, &at), 1);
  assert_int_equal(n, 0);
  assert_int_equal(lsm_json_find_numbers("{\"input\":{\"heights\":[1],\"heights\":[2,3]}}", path, 2,
                                         v, 4, &n, &at), 1);
  assert_true(n == 2 && v[0] == 2.0 && v[1] == 3.0);
  assert_int_equal(lsm_json_find_numbers("{\"input\":{\"heights\":[1],\"heights\":4}}", path, 2, v,
                                         4, &n, &at), 0);
  assert_int_equal(n, 0);
  /* not an array of numbers, or not there */
  static const char *const none[] = {
      "{\"input\":{\"heights\":[1,\"2\"]}}", "{\"input\":{\"heights\":[1,[2]]}}",
      "{\"input\":{\"heights\":[null]}}",   "{\"input\":{\"heights\":{\"a\":1}}}",
      "{\"input\":{\"height\":[1]}}",      "{\"heights\":[1]}",
      "[{\"input\":{\"heights\":[1]}}]",
  };
  for (size_t k = 0; k < sizeof none / sizeof none[0]; ++k) {
    n = 99;
    assert_int_equal(lsm_json_find_numbers(none[k], path, 2, v, 4, &n, &at), 0);
    assert_int_equal(n, 0);
  }
  /* invalid JSON, wherever it breaks */
  at = 0;
  assert_int_equal(lsm_json_find_numbers("{\"input\":{\"heights\":[1,]}}", path, 2, v, 4, &n, &at), -1);
  assert_int_equal(at, 23);
}

/* lsm_json_find_strings and lsm_json_unescape: run.json's input.files read
 * back as the names lsm_json_string wrote, whatever the bytes. */
static void test_json_find_strings(void **state) {
  (void)state;
  static const char *const path[] = {"input", "files"};
  const char *raw[4] = {NULL, NULL, NULL, NULL};
  size_t len[4] = {0, 0, 0, 0}, n = 99, at = 0;
  const char *run = "{\"input\": {\"heights\": [1, 9], \"files\":\n"
                    "  [ \"001.png\" ,\"a\\\"b\\\\c.png\",\t\"\" ]}, \"options\": {\"files\": [\"x\"]}}";
  assert_int_equal(lsm_json_find_strings(run, path, 2, NULL, NULL, 0, &n, &at), 1);
  assert_int_equal(n, 3);
  assert_int_equal(lsm_json_find_strings(run, path, 2, raw, len, 4, &n, &at), 1);
  assert_int_equal(n, 3);
  assert_true(len[0] == 7 && memcmp(raw[0], "001.png", 7) == 0);
  assert_true(len[1] == 11 && memcmp(raw[1], "a\\\"b\\\\c.png", 11) == 0);
  assert_true(len[2] == 0 && raw[3] == NULL);
  char out[32];
  assert_int_equal(lsm_json_unescape(raw[1], len[1], out), 9);
  assert_string_equal(out, "a\"b\\c.png");
  /* a buffer shorter than the array: its first elements, and the length */
  raw[0] = raw[1] = NULL;
  assert_int_equal(lsm_json_find_strings(run, path, 2, raw, len, 1, &n, &at), 1);
  assert_true(n == 3 && raw[0] && raw[1] == NULL);
  /* not an array of strings, or not there; invalid JSON */
  static const char *const none[] = {"{\"input\":{\"files\":[\"a\",1]}}",
                                     "{\"input\":{\"files\":\"a\"}}", "{\"files\":[\"a\"]}"};
  for (size_t k = 0; k < sizeof none / sizeof none[0]; ++k) {
    n = 99;
    assert_int_equal(lsm_json_find_strings(none[k], path, 2, raw, len, 4, &n, &at), 0);
    assert_int_equal(n, 0);
  }
  assert_int_equal(lsm_json_find_strings("{\"input\":{\"files\":[\"a]}}", path, 2, raw, len, 4, &n, &at),
                   -1);

  /* a name with bytes that are not UTF-8 and a control byte comes back as it
   * was written; other escapes as JSON means them */
  const char name[] = "s\xe9\x01\xc3\xa9/\xff.png";
  char *text = NULL;
  size_t size = 0;
  FILE *f = open_memstream(&text, &size);
  assert_non_null(f);
  lsm_json_string(f, name);
  assert_int_equal(fclose(f), 0);
  assert_true(size >= 2 && text[0] == '"' && text[size - 1] == '"');
  assert_int_equal(lsm_json_unescape(text + 1, size - 2, out), strlen(name));
  assert_string_equal(out, name);
  free(text);
  static const struct {
    const char *raw, *want;
  } cases[] = {{"\\u20ac \\n\\t\\/", "\xe2\x82\xac \n\t/"},
               {"\\ud83d\\ude00", "\xf0\x9f\x98\x80"}};
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
    assert_int_equal(lsm_json_unescape(cases[k].raw, strlen(cases[k].raw), out), strlen(cases[k].want));
    assert_string_equal(out, cases[k].want);
  }
  static const char *const bad[] = {"\\u0000", "\\ud83d", "\\ude00", "\\ud83dx", "\\q", "\\", "\\u12"};
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k)
    assert_true(lsm_json_unescape(bad[k], strlen(bad[k]), out) == (size_t)-1);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_natural_cmp),
      cmocka_unit_test(test_name_number),
      cmocka_unit_test(test_json_find_number),
      cmocka_unit_test(test_json_find_numbers),
      cmocka_unit_test(test_json_find_strings),
      cmocka_unit_test(test_heights_good),
      cmocka_unit_test(test_heights_bad),
      cmocka_unit_test_setup_teardown(test_heights_read, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_dir_list, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_dir_errors, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_make_dir, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_read_file, setup_tmp, teardown_tmp),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
