#!/bin/sh
# Replays every seed and regression input of tests/fuzz/corpus/NAME through
# the fuzz harness NAME (built by make test as BUILD/fuzz-replay/replay_NAME,
# without libFuzzer).  A harness check or a sanitizer report aborts the replay.
#   sh tests/test_fuzz_corpus.sh BUILD_DIR
set -u
BUILD=${1:-build}
pass=0
fail=0
for name in png tiff heights cli labels; do
  bin="$BUILD/fuzz-replay/replay_$name"
  if [ ! -x "$bin" ]; then
    echo "fuzz-corpus: FAIL: $bin is missing (make test builds it)"
    fail=$((fail + 1))
    continue
  fi
  if out=$("$bin" "tests/fuzz/corpus/$name" 2>&1); then
    pass=$((pass + 1))
  else
    fail=$((fail + 1))
    echo "fuzz-corpus: FAIL: $name: $out" | tail -n 20
  fi
done
echo "fuzz-corpus: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
