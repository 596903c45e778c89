#!/bin/sh
# lsmorph validation suite: writes validation/report/REPORT.md.
#
#   sh validation/run.sh BUILD_DIR [STUDY ...]
#
# BUILD_DIR holds lsmorph, examples/gen_synthetic and validation/* (make
# validate builds them first).  STUDY is a number 1..6; without any, all six
# run and the report folder is started afresh.  With some, only those run and
# the sections of earlier runs of the others are kept in the report.
# Exits non-zero, with the failing step's message, when any step fails.
set -eu

BUILD=${1:-build}
[ $# -gt 0 ] && shift
STUDIES=${*:-1 2 3 4 5 6}
PY=/usr/bin/python3
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(dirname "$HERE")
REPORT=$HERE/report

fail() {
  echo "validate: FAILED: $*" >&2
  exit 1
}

cd "$ROOT"
case $BUILD in /*) ;; *) BUILD=$ROOT/$BUILD ;; esac
[ -x "$BUILD/lsmorph" ] || fail "$BUILD/lsmorph is missing: run 'make validate'"
for tool in convergence morphacc solids slicescore; do
  [ -x "$BUILD/validation/$tool" ] || fail "$BUILD/validation/$tool is missing: run 'make validate'"
done
[ -x "$BUILD/examples/gen_synthetic" ] || fail "$BUILD/examples/gen_synthetic is missing: run 'make'"
[ -x "$PY" ] || fail "$PY not found (Debian python3 with python3-numpy and python3-matplotlib)"
"$PY" -c 'import numpy, matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot' 2>/dev/null ||
  fail "$PY cannot import numpy and matplotlib: install the Debian packages python3-numpy python3-matplotlib (make deps)"

START=$("$PY" -c 'import time; print(time.time())')
mkdir -p "$REPORT"
if [ $# -eq 0 ]; then
  # A full run starts from an empty report folder.
  rm -rf "$REPORT/sections" "$REPORT/work"
  rm -f "$REPORT"/*.md "$REPORT"/*.csv "$REPORT"/*.png
fi
mkdir -p "$REPORT/sections"
cat /proc/loadavg > "$REPORT/sections/loadavg_start.txt" 2>/dev/null || :

# Snapshot the binaries: the whole run uses one build, even if the build folder
# is relinked meanwhile (a shared checkout).  Retried while a binary is being written.
SNAP=$REPORT/work/build
snapshot() {
  rm -rf "$SNAP" && mkdir -p "$SNAP/validation" "$SNAP/examples" &&
    cp "$BUILD/lsmorph" "$SNAP/" &&
    cp "$BUILD/examples/gen_synthetic" "$SNAP/examples/" &&
    for tool in convergence morphacc solids slicescore; do
      cp "$BUILD/validation/$tool" "$SNAP/validation/" || return 1
    done &&
    "$SNAP/lsmorph" --version >/dev/null 2>&1 &&
    "$SNAP/examples/gen_synthetic" >/dev/null 2>&1; [ $? -eq 2 ]
}
tries=0
until snapshot; do
  tries=$((tries + 1))
  [ $tries -lt 10 ] || fail "cannot copy a working set of binaries from $BUILD"
  sleep 3
done

export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
export PYTHONDONTWRITEBYTECODE=1  # no __pycache__ in the source tree
for s in $STUDIES; do
  case $s in
    1) script=study1_convergence.py ;;
    2) script=study2_morph.py ;;
    3) script=study3_solids.py ;;
    4) script=study4_synthetic.py ;;
    5) script=study5_bunny.py ;;
    6) script=study6_ablation.py ;;
    *) fail "unknown study '$s' (use 1..6)" ;;
  esac
  echo "validate: study $s ($script)" >&2
  "$PY" "$HERE/$script" "$SNAP" "$REPORT" || fail "study $s ($script)"
done

if [ $# -gt 0 ]; then VALIDATE_PARTIAL=$*; else VALIDATE_PARTIAL=; fi
export VALIDATE_PARTIAL
"$PY" "$HERE/report.py" "$SNAP" "$REPORT" "$START" "$BUILD" || fail "report assembly"
rm -rf "$REPORT/work"
echo "validate: report in $REPORT/REPORT.md" >&2
