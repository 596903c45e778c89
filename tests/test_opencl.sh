#!/bin/sh
# End-to-end tests of the OpenCL backend.
#   sh tests/test_opencl.sh BUILD_DIR
# Whole `lsmorph reconstruct` runs with --backend c and --backend opencl on
# generated stacks (the candlestick set, masks; the pyramid set, outlines) and
# on every 8th slice of the bunny (examples/data/bunny, when present), with
# --method ls and --method pls, must agree within 1e-3 in every voxel of
# volume.nrrd (and pls runs must report the same particle counters in
# run.json; with --motion field, the same registration iterations and largest displacements
# within 1e-3 px); `lsmorph devices` lists a device; a missing device index fails
# with exit 1 and a message; no kernel cache of lsmorph's own is written.  Prints one line per failed check and
# "opencl: N passed, N failed".  Without any OpenCL platform or device the
# checks are skipped (the Makefile installs PoCL, so on CI they run).
set -u
BUILD=${1:-build}
LSM="$BUILD/lsmorph"
GEN="$BUILD/examples/gen_synthetic"
PY=/usr/bin/python3
BUNNY=examples/data/bunny
TOL=1e-3
SUITE=opencl
. "$(dirname "$0")/harness.sh"

need "$LSM" "$GEN"
make_tmp
# XDG_CACHE_HOME is a temporary folder (lsmorph must write nothing there);
# PoCL's own cache (also under XDG_CACHE_HOME) stays where it was.
if [ -z "${POCL_CACHE_DIR:-}" ]; then
  case ${XDG_CACHE_HOME:-} in
  /*) POCL_CACHE_DIR="$XDG_CACHE_HOME/pocl/kcache" ;;
  *) [ -n "${HOME:-}" ] && POCL_CACHE_DIR="$HOME/.cache/pocl/kcache" ;;
  esac
  [ -n "${POCL_CACHE_DIR:-}" ] && export POCL_CACHE_DIR
fi
XDG_CACHE_HOME="$TMP/cache"
export XDG_CACHE_HOME
# Under SANITIZE=1: PoCL, its LLVM and the OpenCL loader keep allocations until
# exit; LeakSanitizer is told to ignore those (leaks of lsmorph's own code are
# still reported).
printf 'leak:libpocl.so\nleak:libLLVM\nleak:libOpenCL.so\nleak:libclang\n' >"$TMP/lsan.supp"
LSAN_OPTIONS="suppressions=$TMP/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
export LSAN_OPTIONS

# ---- devices -------------------------------------------------------------------------------
"$LSM" devices >"$TMP/dev" 2>"$TMP/e"
rc=$?
if [ $rc -ne 0 ]; then
  case $(cat "$TMP/e") in
  *"no platform"* | *"no device"*)
    echo "opencl: skipped: $(cat "$TMP/e")"
    finish
    ;;
  esac
fi
check "lsmorph devices exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
check "lsmorph devices lists device 0" grep -q '^  0: ' "$TMP/dev"
check "lsmorph devices gives type, compute units and memory" \
  grep -q 'type .*compute unit.*global memory' "$TMP/dev"

# The slice folder is read before the device is opened: use a real one.
"$GEN" candlestick "$TMP/syn" --mask >"$TMP/o" 2>"$TMP/e" || {
  bad "gen_synthetic candlestick failed: $(cat "$TMP/e")"
  finish
}
SET="$TMP/syn/candlestick"
"$LSM" reconstruct "$SET" -o "$TMP/d99" --backend opencl --device 99 -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--device 99 exits 1 (got $rc)" [ $rc -eq 1 ]
check "--device 99 says the device does not exist (got: $(cat "$TMP/e"))" \
  grep -q 'device 99 does not exist' "$TMP/e"
check "--device 99 writes nothing" [ ! -e "$TMP/d99/volume.nrrd" ]

# No OpenCL platform (an empty ICD vendor folder): a clear error, and auto falls back to C.
mkdir -p "$TMP/no-icd"
OCL_ICD_VENDORS="$TMP/no-icd" "$LSM" reconstruct "$SET" -o "$TMP/noplat" --backend opencl -q \
  --heights "$SET/heights.txt" --dz 10 >"$TMP/o" 2>"$TMP/e"
rc=$?
check "no platform: --backend opencl exits 1 (got $rc)" [ $rc -eq 1 ]
check "no platform: the message says so (got: $(cat "$TMP/e"))" grep -q 'OpenCL: no platform found' "$TMP/e"
OCL_ICD_VENDORS="$TMP/no-icd" "$LSM" reconstruct "$SET" -o "$TMP/noplat-auto" --backend auto -q \
  --heights "$SET/heights.txt" --dz 10 --no-preview >"$TMP/o" 2>"$TMP/e"
rc=$?
check "no platform: --backend auto exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
check "no platform: --backend auto ran on C" grep -q '"backend": {"name": "c"' "$TMP/noplat-auto/run.json"

# ---- C against OpenCL, voxel by voxel ------------------------------------------------------
# max_diff A B: the largest |a - b| over the float32 voxels after the 512-byte
# headers, or "size" when the volumes differ in size.
max_diff() {
  "$PY" - "$1" "$2" <<'EOF'
import sys
import numpy as np
a = np.fromfile(sys.argv[1], dtype="<f4", offset=512)
b = np.fromfile(sys.argv[2], dtype="<f4", offset=512)
if a.size != b.size or a.size == 0 or open(sys.argv[1], "rb").read(512) != open(sys.argv[2], "rb").read(512):
    print("size")
elif not (np.isfinite(a).all() and np.isfinite(b).all()):
    print("nan")
else:
    print("%.6g" % float(np.abs(a.astype(np.float64) - b).max()))
EOF
}

# compare NAME SLICE_DIR ARGS...: reconstructs with both backends and checks the volumes.
compare() {
  name=$1
  dir=$2
  shift 2
  for b in c opencl; do
    "$LSM" reconstruct "$dir" -o "$TMP/$name-$b" --backend "$b" -q --no-preview --no-slices "$@" \
      >"$TMP/o" 2>"$TMP/e"
    rc=$?
    check "$name: --backend $b exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
  done
  [ -f "$TMP/$name-c/volume.nrrd" ] && [ -f "$TMP/$name-opencl/volume.nrrd" ] || {
    bad "$name: a volume is missing"
    return
  }
  d=$(max_diff "$TMP/$name-c/volume.nrrd" "$TMP/$name-opencl/volume.nrrd")
  echo "opencl: $name: max |volume_opencl - volume_c| = $d"
  check "$name: volumes agree within $TOL (max diff $d)" \
    awk -v d="$d" -v t="$TOL" 'BEGIN { exit !(d != "size" && d != "nan" && d + 0 <= t + 0) }'
  check "$name: run.json names the opencl backend" \
    grep -q '"backend": {"name": "opencl"' "$TMP/$name-opencl/run.json"
  # CP of every pair: the residuals before and after the last step are summed on the host (in
  # double) on both backends (the device's float sum before it gave another CP)
  grep -o '"cp": [^,]*' "$TMP/$name-c/run.json" >"$TMP/$name-c.cp"
  grep -o '"cp": [^,]*' "$TMP/$name-opencl/run.json" >"$TMP/$name-opencl.cp"
  check "$name: run.json's cp agrees ($(diff "$TMP/$name-c.cp" "$TMP/$name-opencl.cp" | head -3))" \
    cmp -s "$TMP/$name-c.cp" "$TMP/$name-opencl.cp"
  case " $* " in
  *" --motion field "*)
    # The registration of every pair (on the device with opencl): the same iterations, and
    # the largest displacements within TOL pixels.
    grep -o '"registration_iterations": [0-9]*' "$TMP/$name-c/run.json" >"$TMP/$name-c.mit"
    grep -o '"registration_iterations": [0-9]*' "$TMP/$name-opencl/run.json" >"$TMP/$name-opencl.mit"
    check "$name: run.json has the registrations" [ -s "$TMP/$name-opencl.mit" ]
    check "$name: the registrations' iterations agree ($(diff "$TMP/$name-c.mit" "$TMP/$name-opencl.mit" | head -3))" \
      cmp -s "$TMP/$name-c.mit" "$TMP/$name-opencl.mit"
    grep -o '"max_displacement": [0-9.e+-]*' "$TMP/$name-c/run.json" | cut -d' ' -f2 >"$TMP/$name-c.mdp"
    grep -o '"max_displacement": [0-9.e+-]*' "$TMP/$name-opencl/run.json" | cut -d' ' -f2 >"$TMP/$name-opencl.mdp"
    d=$(paste "$TMP/$name-c.mdp" "$TMP/$name-opencl.mdp" |
      awk 'BEGIN { m = 0 } { d = $1 - $2; if (d < 0) d = -d; if (NF != 2) d = 1e30; if (d > m) m = d } END { print m }')
    echo "opencl: $name: max |max_displacement_opencl - max_displacement_c| = $d px"
    check "$name: the fields' largest displacements agree within $TOL px (max diff $d)" \
      awk -v d="$d" -v t="$TOL" 'BEGIN { exit !(d + 0 <= t + 0) }'
    ;;
  esac
  case " $* " in
  *" pls "*)
    # The particle counters of every pair, in order: the same on both backends.
    grep -o '"particles": {[^}]*}' "$TMP/$name-c/run.json" >"$TMP/$name-c.pcl"
    grep -o '"particles": {[^}]*}' "$TMP/$name-opencl/run.json" >"$TMP/$name-opencl.pcl"
    check "$name: run.json has particle counters" [ -s "$TMP/$name-opencl.pcl" ]
    check "$name: the particle counters agree ($(diff "$TMP/$name-c.pcl" "$TMP/$name-opencl.pcl" | head -3))" \
      cmp -s "$TMP/$name-c.pcl" "$TMP/$name-opencl.pcl"
    ;;
  esac
}

compare candlestick "$SET" --heights "$SET/heights.txt" --dz 10
check "run.json reports the program build (kernel_cache_hit false: no cache of our own)" \
  grep -q '"build_seconds": [0-9.e-]*, "kernel_cache_hit": false}' "$TMP/candlestick-opencl/run.json"
compare candlestick-roefix-rk3 "$SET" --heights "$SET/heights.txt" --dz 10 \
  --scheme roe-fix --time rk3 --reinit-every 10
check "no kernel cache of lsmorph's own" [ ! -e "$XDG_CACHE_HOME/lsmorph" ]
compare candlestick-weno5-rk3 "$SET" --heights "$SET/heights.txt" --dz 10 --scheme weno5 --time rk3
# The particle level set on the device (seeded on the host, stepped and
# corrected on the device), with and without host reseeding.
compare candlestick-pls "$SET" --heights "$SET/heights.txt" --dz 10 --method pls
compare candlestick-pls-reseed "$SET" --heights "$SET/heights.txt" --dz 10 --method pls \
  --scheme roe-fix --time rk3 --pls-reseed 7 --pls-radius-adjust
if "$GEN" pyramid "$TMP/syn" >"$TMP/o" 2>"$TMP/e"; then
  compare pyramid-pls "$TMP/syn/pyramid" --input outline --heights "$TMP/syn/pyramid/heights.txt" \
    --method pls --time rk2
else
  bad "gen_synthetic pyramid failed: $(cat "$TMP/e")"
fi
# pixels that are not square: the kernels' x and y steps differ (upwind, and the particles)
compare candlestick-pixel-1x1.5 "$SET" --heights "$SET/heights.txt" --dz 10 --pixel-size 1,1.5
compare candlestick-pixel-pls "$SET" --heights "$SET/heights.txt" --dz 10 --pixel-size 1.5,1 \
  --method pls --reinit-every 3
# lengths of 1e20: the device's float sum of (phi - phi_T)^2 overflows, the host's does not
compare candlestick-1e20 "$SET" --spacing 40e20 --pixel-size 1e20 --dz 10e20
"$LSM" reconstruct "$SET" -o "$TMP/blend" --backend opencl --method blend \
  --heights "$SET/heights.txt" --dz 10 -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--method blend --backend opencl (host path) exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]

# --motion field: the correspondence field registered on the device (kernels/motion.cl), the
# morph in its moving frame; a disc that moves more than its width per gap, the candlestick
# (parts that appear and vanish), with particles riding the flow.
mkdir -p "$TMP/moving"
/usr/bin/python3 - "$TMP/moving" "$(dirname "$0")" <<'PY'
import sys
sys.path.insert(0, sys.argv[2])
from make_png import write_drawn as png
W, H = 72, 60
for k in range(4):
    cx, cy = 14 + 14 * k, 24 + 4 * k
    png("%s/%d.png" % (sys.argv[1], k + 1),
        ["".join("#" if (x - cx) ** 2 + (y - cy) ** 2 <= 36 else "." for x in range(W))
         for y in range(H)])
PY
compare moving-disc-motion "$TMP/moving" --spacing 8 --motion field
compare candlestick-motion "$SET" --heights "$SET/heights.txt" --dz 10 --motion field
compare candlestick-motion-pls "$SET" --heights "$SET/heights.txt" --dz 10 --motion field \
  --method pls

compare candlestick-rk2-track "$SET" --scheme upwind --time rk2 --per-iteration --tol 2
# A --tol so fine that CP's last bits decide the stopping step: four pixels into a wedge, where the
# device's float reduction of ||phi - phi_T|| stopped the pair at 57 slices and the C backend at 55.
# With --per-iteration CP is summed on the host as the C backend sums it.
mkdir -p "$TMP/wedge"
/usr/bin/python3 - "$TMP/wedge" "$(dirname "$0")" <<'PY'
import sys
sys.path.insert(0, sys.argv[2])
from make_png import write_drawn as png
W, H = 36, 53
dots = [["."] * W for _ in range(H)]
for x, y in ((3, 12), (9, 14), (33, 26), (15, 51)):
    dots[y][x] = "#"
runs = [(0, 2), (0, 4), (0, 5), (0, 6), (0, 7), (0, 8), (0, 9), (0, 10), (0, 11), (0, 11), (0, 12),
        (0, 12), (0, 13), (0, 13), (1, 13), (2, 14), (3, 14), (4, 13), (6, 13)]
wedge = [["."] * W for _ in range(H)]
for y, (a, b) in enumerate(runs, start=34):
    wedge[y][a:b] = ["#"] * (b - a)
png(sys.argv[1] + "/1.png", ["".join(r) for r in dots])
png(sys.argv[1] + "/2.png", ["".join(r) for r in wedge])
PY
compare wedge-track-fine "$TMP/wedge" --spacing 49 --pixel-size 7 --per-iteration --tol 1e-6 \
  --max-iter 200 --reinit-every 2 --align hull --interp linear

if [ -d "$BUNNY" ]; then
  mkdir -p "$TMP/bunny"
  k=0
  for f in $(ls "$BUNNY" | grep '\.png$'); do
    [ $((k % 8)) -eq 0 ] && cp "$BUNNY/$f" "$TMP/bunny/"
    k=$((k + 1))
  done
  compare bunny "$TMP/bunny" --spacing 8 --dz 2
  compare bunny-pls "$TMP/bunny" --spacing 8 --dz 2 --method pls
  compare bunny-motion "$TMP/bunny" --spacing 8 --dz 2 --motion field
else
  echo "opencl: note: $BUNNY not found, bunny comparison not run"
fi

# auto picks OpenCL when a device is present.
"$LSM" reconstruct "$SET" -o "$TMP/auto" --backend auto -q --no-preview >"$TMP/o" 2>"$TMP/e"
check "--backend auto exits 0" [ $? -eq 0 ]
check "--backend auto ran on OpenCL" grep -q '"backend": {"name": "opencl"' "$TMP/auto/run.json"
# ... and when it cannot open the device asked for, runs on C and says why
"$LSM" reconstruct "$SET" -o "$TMP/auto99" --backend auto --device 99 --no-preview >"$TMP/o" 2>"$TMP/e"
check "--backend auto --device 99 exits 0" [ $? -eq 0 ]
check "--backend auto --device 99: a note says why it runs on C ($(cat "$TMP/e" | head -3))" \
  grep -q "note: --backend auto runs on C: OpenCL: device 99 does not exist" "$TMP/e"

finish
