#!/bin/sh
# make fuzz: runs each libFuzzer harness for a fixed time on a working copy of
# its seed corpus and prints executions per second.
#   sh tests/fuzz/run.sh BUILD SECONDS NAME...
# The committed seeds (tests/fuzz/corpus/NAME) are only read; new corpus
# entries go to BUILD/fuzz/work/NAME, crashes to BUILD/fuzz/artifacts/NAME-*.
# A crash fails the run: minimise it, fix it, and add it to the seed corpus
# (then tests/test_fuzz_corpus.sh replays it in make test).
set -u
BUILD=$1
SECONDS_EACH=$2
shift 2
status=0
for name in "$@"; do
  bin="$BUILD/fuzz/fuzz_$name"
  work="$BUILD/fuzz/work/$name"
  art="$BUILD/fuzz/artifacts"
  log="$BUILD/fuzz/$name.log"
  mkdir -p "$work" "$art"
  echo "fuzz: $name for $SECONDS_EACH s (log: $log)"
  # -rss_limit_mb: the PNG harness caps images at 4 Mpixel; more is a leak or a bug.
  "$bin" -max_total_time="$SECONDS_EACH" -print_final_stats=1 -rss_limit_mb=2048 \
    -timeout=10 -max_len=65536 -artifact_prefix="$art/$name-" \
    "$work" "tests/fuzz/corpus/$name" >"$log" 2>&1
  rc=$?
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  secs=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -n 1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -n 1)
  corpus=$(find "$work" -type f | wc -l | tr -d ' ')
  if [ "$rc" -eq 0 ]; then
    echo "fuzz: $name: ${runs:-?} runs, ${secs:-?} exec/s, $cov, $corpus corpus files, no crash"
  else
    status=1
    echo "fuzz: $name: FAILED (exit $rc) after ${runs:-?} runs; see $log and $art/$name-*"
    grep -E '^(==[0-9]+==ERROR|SUMMARY|.*runtime error)' "$log" | head -n 5
  fi
done
exit $status
