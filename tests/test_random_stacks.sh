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
"$PY" -c 'import numpy' 2>/dev/null || { bad "$PY cannot import numpy (Debian package python3-numpy)"; finish; }
make_tmp
case $LSM in /*) ;; *) LSM="$PWD/$LSM" ;; esac
"$PY" "$(dirname "$0")/random_stacks.py" "$LSM" "$TMP" 100 1000 64 >"$TMP/log" 2>&1
rc=$?
grep '^FAIL - ' "$TMP/log" | sed "s/^FAIL - /$SUITE: FAIL: /"
pass=$(grep -c '^ok - ' "$TMP/log")
fail=$(grep -c '^FAIL - ' "$TMP/log")
if [ "$rc" -ne 0 ] && [ "$fail" -eq 0 ]; then
  bad "random_stacks.py exited with $rc:"
  tail -5 "$TMP/log"
fi
finish
