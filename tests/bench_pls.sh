#!/bin/sh
# Cost of --method pls against --method ls on the same jobs (one thread, best
# of five, wall seconds): the design document's Pyramid set,
# the bunny kept every 8th slice, and a 512x512 synthetic stack.
set -eu
BUILD=${1:-build}
TMP=$(mktemp -d /tmp/lsmorph-bench-pls.XXXXXX)
trap 'rm -rf "$TMP"' EXIT INT TERM
PY=/usr/bin/python3
"$BUILD"/examples/gen_synthetic pyramid "$TMP/syn" >/dev/null
mkdir -p "$TMP/bunny8" "$TMP/e4"
for i in $(seq 1 8 120); do cp "examples/data/bunny/$(printf %03d "$i").png" "$TMP/bunny8/" 2>/dev/null || true; done
$PY tests/make_stack.py "$TMP/e60" 41 512
for f in $(ls "$TMP/e60" | awk 'NR % 4 == 1'); do cp "$TMP/e60/$f" "$TMP/e4/"; done

best() { # best of five wall-clock runs, in seconds (nanosecond clock)
  for r in 1 2 3 4 5; do
    t0=$(date +%s%N)
    OMP_NUM_THREADS=1 "$@" >/dev/null 2>&1
    t1=$(date +%s%N)
    echo $(((t1 - t0) / 1000))
  done | sort -n | head -1 | awk '{ printf "%.4f", $1 / 1e6 }'
}
job() { # name, args...
  name=$1; shift
  ls_t=$(best "$BUILD"/lsmorph reconstruct "$@" --method ls -q --threads 1 --no-slices --no-preview -o "$TMP/o")
  pls_t=$(best "$BUILD"/lsmorph reconstruct "$@" --method pls -q --threads 1 --no-slices --no-preview -o "$TMP/o")
  echo "$name $ls_t $pls_t" | awk '{ printf "%-28s ls %7.3f s | pls %7.3f s | ratio %.2fx wall (target <= 4x)\n", $1, $2, $3, $3 / $2 }'
}
echo "== particle level set cost (one thread, best of 5, wall clock) =="
job pyramid-70x100 "$TMP/syn/pyramid" --input outline --heights "$TMP/syn/pyramid/heights.txt"
[ -f "$TMP/bunny8/001.png" ] && job bunny-128-every-8th "$TMP/bunny8" --spacing 8
job ellipses-512-every-4th "$TMP/e4" --spacing 4
