#!/bin/sh
# Random stacks (tests/random_stacks.py): 100 seeded cases of 2 to 9 slices up to
# 63 px a side, each slice empty, full, a pixel, a row, a checkerboard, noise, a
# disc cut by the border, an annulus with an island or a smooth blob, uneven
# heights and random options.  lsmorph must finish or refuse with one error
# line, with no sanitizer report (make test SANITIZE=1), a finite volume and
# every input slice back exactly.  The seeds are fixed, so a failure repeats:
#   /usr/bin/python3 tests/random_stacks.py build/lsmorph /tmp/x 1 SEED 64
#   sh tests/test_random_stacks.sh BUILD_DIR
# Prints "random-stacks: N passed, N failed".
set -u
BUILD=${1:-build}
LSM="$BUILD/lsmorph"
PY=/usr/bin/python3
SUITE=random-stacks
. "$(dirname "$0")/harness.sh"
need "$LSM"
need_python numpy python3-numpy
make_tmp
case $LSM in /*) ;; *) LSM="$PWD/$LSM" ;; esac
run_checks "$TMP/log" "$PY" "$(dirname "$0")/random_stacks.py" "$LSM" "$TMP" 100 1000 64
finish
