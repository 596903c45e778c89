/* Tests for solver/recon/lsm_parts.c: which parts of a slice count as moved. */
#include "tests/lsm_test_mask.h"

#include "solver/base/lsm_grid.h"
#include "solver/recon/lsm_parts.h"
#include "solver/base/lsm_status.h"


static int moved(const lsm_mask *a, const lsm_mask *b, lsm_part_move *mv) {
  lsm_err err;
  lsm_err_clear(&err);
  int count = -1;
  assert_int_equal(lsm_parts_moved(a, b, NULL, mv, &count, &err), LSM_OK);
  assert_true(count >= 0 && count <= LSM_PARTS_MAX);
  return count;
}

static void free_moves(lsm_part_move *mv, int n) {
  for (int k = 0; k < n; ++k) lsm_part_move_free(&mv[k]);
}

/* Two discs moving apart (a "vee"): two moves, each disc with its own
 * counterpart, shifts -20 and +21 px (the nearer first), and each part mask
 * is exactly its disc. */
static void test_two_parts_apart(void **state) {
  (void)state;
  lsm_mask a = lsm_test_mask(120, 100), b = lsm_test_mask(120, 100);
  lsm_test_paint_disc(&a, 45, 50, 4);
  lsm_test_paint_disc(&a, 65, 50, 4);
  lsm_test_paint_disc(&b, 25, 50, 4);
  lsm_test_paint_disc(&b, 86, 52, 4);
  lsm_part_move mv[LSM_PARTS_MAX];
  const int n = moved(&a, &b, mv);
  assert_int_equal(n, 2);
  assert_close(mv[0].dx, -20.0, 1e-9);
  assert_close(mv[0].dy, 0.0, 1e-9);
  assert_close(mv[1].dx, 21.0, 1e-9);
  assert_close(mv[1].dy, 2.0, 1e-9);
  lsm_mask one = lsm_test_mask(120, 100);
  lsm_test_paint_disc(&one, 45, 50, 4);
  assert_memory_equal(mv[0].part_a.pixels, one.pixels, 120 * 100);
  lsm_mask_free(&one);
  free_moves(mv, n);
  lsm_mask_free(&a);
  lsm_mask_free(&b);
}

/* Cases where nothing may move: discs (x, y, r; r = 0 ends the list) on A
 * and on B. */
typedef struct no_move_case {
  const char *what;
  double a[2][3], b[2][3];
} no_move_case;

static void test_nothing_moves(void **state) {
  (void)state;
  const no_move_case cases[] = {
      {"one disc splitting in two at equal distances", {{60, 50, 5}}, {{40, 50, 5}, {80, 50, 5}}},
      {"two discs merging from equal distances", {{40, 50, 5}, {80, 50, 5}}, {{60, 50, 5}}},
      {"overlapping in place", {{60, 50, 8}}, {{66, 50, 8}}},
      {"areas more than x2 apart", {{30, 50, 8}}, {{60, 50, 5}}},
      {"touching the border", {{2, 50, 5}}, {{22, 50, 5}}},
      {"A empty", {{0}}, {{60, 50, 5}}},
      {"B empty", {{60, 50, 5}}, {{0}}},
      {"both empty", {{0}}, {{0}}},
  };
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
    lsm_mask a = lsm_test_mask(120, 100), b = lsm_test_mask(120, 100);
    for (int k = 0; k < 2; ++k) {
      if (cases[c].a[k][2] > 0) lsm_test_paint_disc(&a, cases[c].a[k][0], cases[c].a[k][1], cases[c].a[k][2]);
      if (cases[c].b[k][2] > 0) lsm_test_paint_disc(&b, cases[c].b[k][0], cases[c].b[k][1], cases[c].b[k][2]);
    }
    lsm_part_move mv[LSM_PARTS_MAX];
    const int n = moved(&a, &b, mv);
    if (n != 0) fail_msg("%s: %d moves (want 0)", cases[c].what, n);
    lsm_mask_free(&a);
    lsm_mask_free(&b);
  }
}

/* A noisy slice (more than 256 components) is left alone: a disc that moves
 * 20 px, far from a field of 361 single-pixel specks, moves when the specks
 * are fewer than 256 and not when there are more. */
static void test_noise_left_alone(void **state) {
  (void)state;
  for (int step = 4; step >= 3; --step) {
    lsm_mask a = lsm_test_mask(200, 200), b = lsm_test_mask(200, 200);
    int specks = 0;
    for (int y = 140; y < 197; y += step)
      for (int x = 140; x < 197; x += step, ++specks) a.pixels[(size_t)y * 200 + (size_t)x] = 1;
    lsm_test_paint_disc(&a, 100, 100, 4);
    lsm_test_paint_disc(&b, 120, 100, 4);
    lsm_part_move mv[LSM_PARTS_MAX];
    const int n = moved(&a, &b, mv);
    print_message("%d specks: %d moves\n", specks, n);
    assert_int_equal(n, specks + 1 <= 256 ? 1 : 0);
    free_moves(mv, n);
    lsm_mask_free(&a);
    lsm_mask_free(&b);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_two_parts_apart),
      cmocka_unit_test(test_nothing_moves),
      cmocka_unit_test(test_noise_left_alone),
  };
  return cmocka_run_group_tests_name("parts", tests, NULL, NULL);
}
