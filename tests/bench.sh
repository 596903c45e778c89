#!/bin/sh
# make bench: speed of the upwind update against NumPy, Roe-Fix, threads, and
# peak memory of a reconstruction with 10 and 60 slices; lsmorph fill on a
# 512 x 512 x 200 label map against ITK's MorphologicalContourInterpolator.
set -eu
BUILD=${1:-build}
PY=/usr/bin/python3
TMP=$(mktemp -d /tmp/lsmorph-bench.XXXXXX)
trap 'rm -rf "$TMP"' EXIT INT TERM

echo "== update speed (cells/s, one Euler stage, C path) =="
"$BUILD"/bench/bench_scheme 1 | tee "$TMP/c1.txt"
"$BUILD"/bench/bench_scheme 2 | tee "$TMP/c2.txt"
np32=$($PY tests/bench_numpy.py 512 float32)
np64=$($PY tests/bench_numpy.py 512 float64)
c=$(awk '$1=="upwind" && $2==512 {print $4}' "$TMP/c1.txt")
echo "NumPy whole-array upwind, 512^2: float64 $np64 cells/s, float32 $np32 cells/s"
awk -v c="$c" -v a="$np64" -v b="$np32" 'BEGIN { printf "upwind C, one thread, 512^2: %.3g cells/s = %.1fx NumPy float64, %.1fx NumPy float32 (target >= 30x)\n", c, c / a, c / b }'

echo
echo "== peak memory: 10 vs 60 slices of 512x512, default options =="
$PY tests/make_stack.py "$TMP/s60" 60 512
mkdir -p "$TMP/s10"
for f in $(ls "$TMP/s60" | head -10); do cp "$TMP/s60/$f" "$TMP/s10/"; done
for n in 10 60; do
  $PY - "$BUILD/lsmorph" "$TMP/s$n" "$TMP/o$n" <<'PYEOF' > "$TMP/rss$n.txt"
import resource, subprocess, sys, time
t = time.time()
subprocess.run([sys.argv[1], "reconstruct", sys.argv[2], "-o", sys.argv[3], "--spacing", "4", "-q"], check=True)
print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, time.time() - t)
PYEOF
  read -r kb sec < "$TMP/rss$n.txt"
  echo "$n slices: peak RSS $kb KiB, $(printf %.2f "$sec") s"
done
awk -v a="$(cut -d' ' -f1 "$TMP/rss10.txt")" -v b="$(cut -d' ' -f1 "$TMP/rss60.txt")" 'BEGIN { r = b / a; printf "peak(60) / peak(10) = %.3f (target <= 1.25): %s\n", r, (r <= 1.25 ? "PASS" : "FAIL") }'

echo
sh tests/bench_fill.sh "$BUILD"
echo
sh tests/bench_gaps.sh "$BUILD"
echo
sh tests/bench_pls.sh "$BUILD"
echo
echo "== OpenCL backend vs C (bench_opencl; load: $(uptime | sed 's/.*load average/load average/')) =="
"$BUILD"/bench/bench_opencl || echo "bench_opencl: no OpenCL device, skipped"
