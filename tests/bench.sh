#!/bin/sh
# make bench: speed of the upwind update against NumPy, Roe-Fix, threads,
# peak memory of a reconstruction with 10 and 60 slices, the share of the
# previews and slice PNGs in a default run, the narrow band against the full
# grid (tests/bench_morph.c, tests/bench_band.py), --motion none, auto and field
# (tests/bench_motion.py: the 2x bound, the registration's cells/s), and lsmorph fill on a
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
echo "== previews and slice PNGs: share of a default run (the bunny, every 8th slice kept) =="
# The same build with and without them, interleaved, median wall time of 9 runs each:
# the share is (default - --no-preview --no-slices) / default.
mkdir -p "$TMP/bunny8"
ls examples/data/bunny/*.png | awk 'NR % 8 == 1' | xargs -I{} cp {} "$TMP/bunny8/"
$PY - "$BUILD/lsmorph" "$TMP/bunny8" "$TMP/pv" <<'PYEOF'
import shutil, statistics, subprocess, sys, time
lsm, src, out = sys.argv[1:4]
modes = {"default": [], "--no-slices": ["--no-slices"], "--no-preview": ["--no-preview"],
         "neither": ["--no-preview", "--no-slices"]}
wall = {m: [] for m in modes}
for _ in range(9):
    for m, extra in modes.items():
        shutil.rmtree(out, ignore_errors=True)
        t = time.perf_counter()
        subprocess.run([lsm, "reconstruct", src, "-o", out, "--heights-from-names", "-q"] + extra, check=True)
        wall[m].append(time.perf_counter() - t)
med = {m: statistics.median(v) for m, v in wall.items()}
for m in modes:
    print("%-13s median %.3f s (min %.3f)" % (m, med[m], min(wall[m])))
share = (med["default"] - med["neither"]) / med["default"]
print("previews %.3f s, slice PNGs %.3f s; both: %.1f %% of the default run (target <= 10 %%): %s"
      % (med["--no-slices"] - med["neither"], med["--no-preview"] - med["neither"], 100 * share,
         "PASS" if share <= 0.10 else "FAIL"))
PYEOF

echo
echo "== the narrow band against the full grid (--band off), the same runs (issue 56) =="
echo "one pair morph, C path (mode N threads seconds steps cell_updates cells_per_second):"
"$BUILD"/bench/bench_morph 1
"$BUILD"/bench/bench_morph 2
# default runs end to end; LSMORPH_BENCH_BASE=path/to/lsmorph adds an older build (the build
# before the band) to the same interleaved runs; the stand-ins are made once into $BUILD/bench-band
# (with ITK's MCI when tests/bench_fill.sh has installed it)
MCI_DIR=${LSMORPH_MESH_CACHE:-$HOME/.cache/lsmorph-meshes}/mci
[ -f "$MCI_DIR/mci.mjs" ] && command -v node >/dev/null 2>&1 || MCI_DIR=
$PY tests/bench_band.py "$BUILD/lsmorph" "$BUILD/bench-band" \
  ${LSMORPH_BENCH_BASE:+--base "$LSMORPH_BENCH_BASE"} ${MCI_DIR:+--mci "$MCI_DIR"}

echo
echo "== the correspondence field (--motion none, auto (the default) and field; issue 53) =="
# the bunny every 8th slice and the two 512^2 stand-ins bench_band.py made
$PY tests/bench_motion.py "$BUILD/lsmorph" "$TMP/bunny8" "$BUILD"/bench-band/512/*/kept

echo
sh tests/bench_fill.sh "$BUILD"
echo
sh tests/bench_gaps.sh "$BUILD"
echo
sh tests/bench_pls.sh "$BUILD"
echo
echo "== OpenCL backend vs C (bench_opencl; load: $(uptime | sed 's/.*load average/load average/')) =="
"$BUILD"/bench/bench_opencl || echo "bench_opencl: no OpenCL device, skipped"
