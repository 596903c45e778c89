#!/bin/sh
# Runs every test program of build/tests and the shell end-to-end tests, then
# prints one summary line "N passed, N failed".
set -u
BUILD=${1:-build}
pass=0
fail=0
failed=""
for t in "$BUILD"/tests/test_*; do
  [ -x "$t" ] || continue
  name=$(basename "$t")
  if "$t"; then pass=$((pass + 1)); else fail=$((fail + 1)); failed="$failed $name"; fi
done
for t in tests/test_*.sh; do
  [ -f "$t" ] || continue
  name=$(basename "$t")
  if sh "$t" "$BUILD"; then pass=$((pass + 1)); else fail=$((fail + 1)); failed="$failed $name"; fi
done
echo
[ -n "$failed" ] && echo "failed:$failed"
echo "test programs: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
