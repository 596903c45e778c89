# Shared by the shell test suites: sourced after SUITE (the name in messages)
# is set.  Counters, ok/bad/check, finish (prints "SUITE: N passed, N failed"
# and exits 0 only when nothing failed), need (programs that must exist) and
# make_tmp (a temporary folder $TMP removed on exit).

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
