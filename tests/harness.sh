# Shared by the shell test suites: sourced after SUITE (the name in messages)
# is set.  Counters, ok/bad/check, finish (prints "SUITE: N passed, N failed"
# and exits 0 only when nothing failed), need (programs that must exist),
# need_python (modules Debian's Python must import), run_checks (a helper
# printing "ok - " / "FAIL - " lines, counted), make_tmp (a temporary folder
# $TMP removed on exit), work_in_tmp (make_tmp, then cd into it) and
# lib_python (how to run Python over liblsmorph.so), python_suite (the set-up of the suites
# that drive lsmorph from Python).

pass=0
fail=0

ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "$SUITE: FAIL: $*"; }
check() { # check DESCRIPTION COMMAND...: passes when the command succeeds
  desc=$1
  shift
  if "$@"; then ok; else bad "$desc"; fi
}
finish() {
  echo "$SUITE: $pass passed, $fail failed"
  [ "$fail" -eq 0 ]
  exit
}
need() { # need PROGRAM...: ends the suite at once when one is missing
  for f in "$@"; do
    [ -x "$f" ] || { bad "$f is missing (run make first)"; finish; }
  done
}
make_tmp() { # sets TMP to a new folder, removed on exit (a suite may replace the EXIT trap)
  TMP=$(mktemp -d "${TMPDIR:-/tmp}/lsm-$SUITE.XXXXXX") || exit 1
  trap 'rm -rf "$TMP"' EXIT
  trap 'exit 1' INT TERM
}
work_in_tmp() { # make_tmp, then work in $TMP: LSM an absolute path, TESTS the tests folder
  TESTS=$(cd "$(dirname "$0")" && pwd)
  make_tmp
  cd "$TMP" || exit 1
  case $LSM in /*) ;; *) LSM="$OLDPWD/$LSM" ;; esac
}
need_python() { # need_python MODULES PACKAGES: ends the suite when $PY cannot import them
  "$PY" -c "import $1" 2>/dev/null || { bad "$PY cannot import $1 (Debian packages $2)"; finish; }
}
run_checks() { # run_checks LOG COMMAND...: runs a checker whose lines are "ok - ..." or
  # "FAIL - ...", counts them and prints the failures; a checker that exits non-zero
  # without a FAIL line fails once
  log=$1
  shift
  "$@" >"$log" 2>&1
  rc=$?
  grep '^FAIL - ' "$log" | sed "s/^FAIL - /$SUITE: FAIL: /"
  p=$(grep -c '^ok - ' "$log")
  f=$(grep -c '^FAIL - ' "$log")
  pass=$((pass + p))
  fail=$((fail + f))
  if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then
    bad "$1 exited with $rc:"
    tail -5 "$log"
  fi
}
lib_python() { # lib_python LIBRARY: after make_tmp, sets PYLIB (run it for $PY) and
  # SANFLAGS (for cc).  Under SANITIZE=1 the library carries ASan, whose runtime must
  # come first in a program that loads it: PYLIB is then $PY with it preloaded (the
  # interpreter's own allocations at exit are not the library's leaks) and SANFLAGS
  # links it into a C program.
  PYLIB=$PY
  SANFLAGS=
  if ldd "$1" 2>/dev/null | grep -q libasan; then
    PYLIB="$TMP/python"
    printf '#!/bin/sh\nLD_PRELOAD=%s ASAN_OPTIONS=detect_leaks=0 exec %s "$@"\n' \
      "$(cc -print-file-name=libasan.so)" "$PY" >"$PYLIB"
    chmod +x "$PYLIB"
    SANFLAGS="-fsanitize=address,undefined"
  fi
}

python_suite() { # python_suite MODULES PACKAGES: after BUILD, LSM, PY and SUITE are set: needs
  # lsmorph and the Python modules (from those Debian packages), makes $TMP, sets HERE (the
  # tests folder) and makes BUILD and LSM absolute paths.
  need "$LSM"
  need_python "$1" "$2"
  make_tmp
  HERE="$(cd "$(dirname "$0")" && pwd)"
  case $BUILD in /*) ;; *) BUILD="$PWD/$BUILD" ;; esac
  case $LSM in /*) ;; *) LSM="$PWD/$LSM" ;; esac
}
