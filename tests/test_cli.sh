#!/bin/sh
# End-to-end tests of the lsmorph command line.
#   sh tests/test_cli.sh BUILD_DIR
# Generates synthetic slices with BUILD_DIR/examples/gen_synthetic, runs
# BUILD_DIR/lsmorph on them and checks exit codes, messages and the files
# written.  Prints one line per failed check and "cli: N passed, N failed".
set -u
BUILD=${1:-build}
LSM="$BUILD/lsmorph"
GEN="$BUILD/examples/gen_synthetic"
SUITE=cli
. "$(dirname "$0")/harness.sh"

need "$LSM" "$GEN"
make_tmp

# file_size FILE: bytes.
file_size() { wc -c <"$1" | tr -d ' '; }
# lines FILE: number of lines.
lines() { wc -l <"$1" | tr -d ' '; }
# json_count FILE KEY: number of occurrences of "KEY": in FILE.
json_count() { grep -o "\"$2\":" "$1" | wc -l | tr -d ' '; }
# png_u32 FILE OFFSET: big-endian 32-bit number (IHDR width at 16, height at 20).
png_u32() { od -An -tu1 -j "$2" -N4 "$1" | awk '{ print (($1 * 256 + $2) * 256 + $3) * 256 + $4 }'; }

# ---- help and version ---------------------------------------------------------------
out=$("$LSM" --help 2>&1)
check "--help exits 0" [ $? -eq 0 ]
case $out in *reconstruct*) ok ;; *) bad "--help does not mention reconstruct" ;; esac
out=$("$LSM" help reconstruct 2>&1)
check "help reconstruct exits 0" [ $? -eq 0 ]
case $out in *--heights*) ok ;; *) bad "help reconstruct does not list --heights" ;; esac
out=$("$LSM" --help score 2>&1)
check "--help score exits 0" [ $? -eq 0 ]
case $out in "Usage: lsmorph score"*) ok ;; *) bad "--help score is not score's help: '$(printf '%s' "$out" | head -1)'" ;; esac
# every help topic fits 80 columns; reconstruct's two screens (90 lines) and
# names every option of reconstruct
for topic in "" fill reconstruct score devices rules; do
  "$LSM" help $topic >"$TMP/help" 2>&1
  wide=$(awk 'length > 80 { print NR ": " $0; exit }' "$TMP/help")
  check "help $topic: a line over 80 columns: $wide" [ -z "$wide" ]
done
"$LSM" help reconstruct >"$TMP/help" 2>&1
n=$(lines "$TMP/help")
check "help reconstruct has $n lines, more than 90" [ "$n" -le 90 ]
for opt in -o --output --input --invert --spacing --heights --heights-from-names --pixel-size \
    --max-pixels --max-voxels --max-memory --dz --per-iteration --format --values --nrrd-encoding --mesh \
    --no-slices --no-preview --method --interp --ends --align --scheme --time --cfl --max-iter \
    --reinit-every --reinit-iters --tol --particles-per-cell --pls-reseed --pls-radius-adjust \
    --seed --rules-off --threads --backend --device -q --quiet; do
  check "help reconstruct does not list $opt" grep -q -e "[ ,]$opt[ ,]" "$TMP/help"
done
check "help reconstruct lists the methods" grep -q -e "--method ls|pls|blend " "$TMP/help"
check "help reconstruct lists the formats" grep -q "nrrd, mha, vtk, exr, raw, nii, nii.gz" "$TMP/help"
out=$("$LSM" --version 2>&1)
check "--version exits 0" [ $? -eq 0 ]
case $out in "lsmorph "[0-9]*.[0-9]*) ok ;; *) bad "--version printed '$out'" ;; esac

# ---- usage errors: exit 2 and "lsmorph: error:" -------------------------------------
"$LSM" >"$TMP/o" 2>"$TMP/e"
rc=$?
check "no command exits 2 (got $rc)" [ $rc -eq 2 ]
"$LSM" reconstruct >"$TMP/o" 2>"$TMP/e"
rc=$?
check "reconstruct without arguments exits 2 (got $rc)" [ $rc -eq 2 ]
check "reconstruct without arguments says 'lsmorph: error:'" grep -q "lsmorph: error:" "$TMP/e"
"$LSM" reconstruct "$TMP" -o "$TMP/x" --no-such-option >"$TMP/o" 2>"$TMP/e"
rc=$?
check "unknown option exits 2 (got $rc)" [ $rc -eq 2 ]
check "unknown option says 'lsmorph: error:'" grep -q "lsmorph: error:" "$TMP/e"
check "unknown option is named in the message" grep -q -e "--no-such-option" "$TMP/e"
"$LSM" reconstruct "$TMP" -o "$TMP/x" --method nope >"$TMP/o" 2>"$TMP/e"
rc=$?
check "bad --method value exits 2 (got $rc)" [ $rc -eq 2 ]
"$LSM" reconstruct "$TMP" -o "$TMP/x" --ends middle >"$TMP/o" 2>"$TMP/e"
rc=$?
check "bad --ends value exits 2 (got $rc)" [ $rc -eq 2 ]
check "bad --ends value lists auto, tip, halfway" grep -q "not one of auto, tip, halfway" "$TMP/e"
"$LSM" reconstruct "$TMP" -o "$TMP/x" --scheme weno3 >"$TMP/o" 2>"$TMP/e"
rc=$?
check "bad --scheme value exits 2 (got $rc)" [ $rc -eq 2 ]
check "bad --scheme value lists upwind, roe-fix, weno5" grep -q "not one of upwind, roe-fix, weno5" "$TMP/e"
"$LSM" reconstruct "$TMP" -o "$TMP/x" --cfl -1 >"$TMP/o" 2>"$TMP/e"
rc=$?
check "negative --cfl exits 2 (got $rc)" [ $rc -eq 2 ]
"$LSM" frobnicate >"$TMP/o" 2>"$TMP/e"
rc=$?
check "unknown command exits 2 (got $rc)" [ $rc -eq 2 ]
check "usage errors created nothing" [ ! -e "$TMP/x" ]

# ---- synthetic slices -------------------------------------------------------------------
if ! "$GEN" pyramid "$TMP/syn" >"$TMP/o" 2>"$TMP/e"; then
  bad "gen_synthetic pyramid failed: $(cat "$TMP/e")"
  finish
fi
SET="$TMP/syn/pyramid"
N_IN=$(ls "$SET" | grep -c '\.png$')
check "gen_synthetic wrote 7 pyramid slices (got $N_IN)" [ "$N_IN" -eq 7 ]
check "heights.txt has 7 lines" [ "$(lines "$SET/heights.txt")" -eq 7 ]
W=$(png_u32 "$SET/001.png" 16)
H=$(png_u32 "$SET/001.png" 20)
check "pyramid slices are 100x70 (got ${W}x${H})" [ "${W}x${H}" = "100x70" ]

# ---- reconstruct the pyramid -------------------------------------------------------------
OUT="$TMP/out"
"$LSM" reconstruct "$SET" -o "$OUT" --input outline --heights "$SET/heights.txt" --dz 10 -q \
  >"$TMP/o" 2>"$TMP/e"
rc=$?
check "reconstruct pyramid exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
check "-q prints nothing on stderr" [ ! -s "$TMP/e" ]
check "volume.nrrd exists" [ -f "$OUT/volume.nrrd" ]
check "heights.txt exists" [ -f "$OUT/heights.txt" ]
check "run.json exists" [ -f "$OUT/run.json" ]
if [ -f "$OUT/heights.txt" ] && [ -f "$OUT/volume.nrrd" ]; then
  N=$(lines "$OUT/heights.txt")
  # Input heights 0, 40, ..., 240 with --dz 10: z = 0, 10, ..., 240, 25 slices.
  check "heights.txt has 25 lines (got $N)" [ "$N" -eq 25 ]
  want=$((512 + W * H * N * 4))
  got=$(file_size "$OUT/volume.nrrd")
  check "volume.nrrd is 512 + W*H*N*4 = $want bytes (got $got)" [ "$got" -eq "$want" ]
  head -c 512 "$OUT/volume.nrrd" >"$TMP/hdr"
  check "volume.nrrd header: sizes $W $H $N" grep -a -q "^sizes: $W $H $N\$" "$TMP/hdr"
  check "volume.nrrd header: type float" grep -a -q "^type: float" "$TMP/hdr"
  check "volume.nrrd header: encoding raw" grep -a -q "^encoding: raw" "$TMP/hdr"
  check "heights are 0, 10, ..., 240" \
    awk -v n="$N" '{ if ($1 + 0 != (NR - 1) * 10) b = 1 } END { exit (b || NR != n) }' "$OUT/heights.txt"
  NS=$(ls "$OUT/slices" 2>/dev/null | grep -c '\.png$')
  check "slices/ has $N PNGs (got $NS)" [ "$NS" -eq "$N" ]
  check "slices/00001.png is a PNG" grep -q "PNG" "$OUT/slices/00001.png"
fi
J="$OUT/run.json"
if [ -f "$J" ]; then
  # 7 inputs -> 6 pairs, each an object with these fields (counted inside
  # the "pairs" list only: "totals" has "iterations" and "seconds" too).
  awk '/"pairs": *\[/ { on = 1 } on { print } on && /\]/ { exit }' "$J" >"$TMP/pairs"
  for key in source target iterations dt cp seconds cells aligned moving_parts; do
    c=$(json_count "$TMP/pairs" "$key")
    check "run.json has 6 \"$key\" entries (got $c)" [ "$c" -eq 6 ]
  done
  check "run.json has a \"pairs\" list" grep -q '"pairs": *\[' "$J"
  check "run.json totals say 6 pairs" grep -q '"totals": {"pairs": 6' "$J"
  check "run.json lists the 7 input files in order" \
    grep -q '"files": \["001.png", "002.png", "003.png", "004.png", "005.png", "006.png", "007.png"\]' "$J"
  check "run.json has the pair 006.png -> 007.png" \
    grep -q '"source": "006.png", "target": "007.png"' "$J"
  check "run.json: no pair hit max_iter" sh -c "! grep -q '\"hit_max_iter\": true' '$J'"
  check "run.json options say \"ends\": \"auto\" (the default)" grep -q '"ends": "auto"' "$J"
  if command -v python3 >/dev/null 2>&1; then
    check "run.json is valid JSON: 6 pairs, positive iterations, dt, cells, none aligned (nested, centred rectangles); 25 slices" python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
p = d["pairs"]
assert len(p) == 6, len(p)
for q in p:
    assert q["iterations"] > 0 and q["dt"] > 0 and q["cells"] > 0 and q["seconds"] >= 0, q
    assert q["aligned"] is False and q["moving_parts"] == 0, q
assert d["output"]["slices"] == 25 and d["output"]["evenly_spaced"] is True, d["output"]
' "$J"
  fi
fi
check "no temporary folder left next to OUT" sh -c "! ls -d '$OUT'.tmp-* >/dev/null 2>&1"

# ---- the fifth-order WENO scheme ---------------------------------------------------------------
"$LSM" reconstruct "$SET" -o "$TMP/weno" --input outline --heights "$SET/heights.txt" --dz 10 -q \
  --scheme weno5 --time rk3 >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--scheme weno5 --time rk3 exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
check "run.json records \"scheme\": \"weno5\"" grep -q '"scheme": "weno5"' "$TMP/weno/run.json"
check "run.json: no weno5 pair hit max_iter" sh -c "! grep -q '\"hit_max_iter\": true' '$TMP/weno/run.json'"
# the input slices (z = 0, 40, ..., 240: output slices 1, 5, ..., 25) come back exactly
for k in 00001 00005 00013 00025; do
  check "weno5: input slice $k.png as with upwind" cmp -s "$TMP/weno/slices/$k.png" "$OUT/slices/$k.png"
done
if command -v python3 >/dev/null 2>&1; then
  check "weno5 and upwind solve the same morph: the masks differ in < 2 % of the inside voxels" python3 -c '
import sys
def vol(p):
    d = open(p, "rb").read(); i = d.index(b"\n\n") + 2
    import array; a = array.array("f"); a.frombytes(d[i:]); return a
a, b = vol(sys.argv[1]), vol(sys.argv[2])
assert len(a) == len(b)
inside = sum(1 for v in a if v < 0)
differ = sum(1 for u, v in zip(a, b) if (u < 0) != (v < 0))
print("weno5 vs upwind: %d of %d inside voxels differ" % (differ, inside), file=sys.stderr)
assert 0 < inside and differ < 0.02 * inside, (differ, inside)
' "$TMP/weno/volume.nrrd" "$OUT/volume.nrrd"
fi

# ---- a --dz that does not divide the heights' range (0 .. 240) ------------------------------
"$LSM" reconstruct "$SET" -o "$TMP/out-dz7" --input outline --heights "$SET/heights.txt" --dz 7 \
  --no-preview --no-slices >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--dz 7 exits 0 (got $rc)" [ $rc -eq 0 ]
check "--dz 7: a note says the slices stop at 238, 2 below the last input slice" \
  grep -q "note: the output slices stop at height 238, 2 below the last input slice (240)" "$TMP/e"
check "--dz 7: the note names a --dz that ends on it (35 steps)" \
  grep -q -e "--dz 6.857142857142857 (35 steps) ends on it" "$TMP/e"
check "--dz 7: heights.txt ends at 238" [ "$(tail -n 1 "$TMP/out-dz7/heights.txt")" = "238" ]
"$LSM" reconstruct "$SET" -o "$TMP/out-dz" --input outline --heights "$SET/heights.txt" \
  --dz 6.85714285714286 --no-preview --no-slices >"$TMP/o" 2>"$TMP/e"
check "--dz 6.85714285714286 ends on the last input slice: no such note" \
  sh -c "! grep -q 'output slices stop at' '$TMP/e'"
check "--dz 6.85714285714286: 36 slices" [ "$(lines "$TMP/out-dz/heights.txt")" -eq 36 ]
"$LSM" reconstruct "$SET" -o "$TMP/out-dz" --input outline --heights "$SET/heights.txt" \
  --dz 10 --no-preview --no-slices >"$TMP/o" 2>"$TMP/e"
check "--dz 10 divides the range: no such note" sh -c "! grep -q 'output slices stop at' '$TMP/e'"

# Input heights far closer than --dz: the one output slice, at the first height, is the first
# input slice (the output grid gave it to a later slice when the gaps were under 1e-6 dz).
"$LSM" reconstruct "$SET" -o "$TMP/out-far" --input outline --spacing 1 --dz 1000 -q --no-preview \
  >"$TMP/o" 2>"$TMP/e" &&
  "$LSM" reconstruct "$SET" -o "$TMP/out-near" --input outline --spacing 1e-7 -q --no-preview \
    >"$TMP/o" 2>>"$TMP/e"
rc=$?
check "close heights run (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
check "heights 1e-7 apart: one output slice, the first input's" \
  sh -c "[ \$(ls '$TMP/out-near/slices' | wc -l) -eq 1 ] && cmp -s '$TMP/out-far/slices/00001.png' '$TMP/out-near/slices/00001.png'"

# The unit of z does not matter: heights and --dz scaled by 2^64 or by 2^-80 give the same
# slices, bit for bit (the PCHIP slopes multiplied secants and weights in floats, which under- or
# overflowed past about 1e17 and 1e-22 pixel sizes per gap and changed the result).
"$LSM" reconstruct "$SET" -o "$TMP/out-unit" --input outline --heights "$SET/heights.txt" --dz 5 \
  -q --no-preview >"$TMP/o" 2>"$TMP/e"
rc=$?
for scale in 18446744073709551616 8.271806125530277e-25; do
  awk -v f="$scale" '{ printf "%.17g\n", $1 * f }' "$SET/heights.txt" >"$TMP/heights-scaled.txt"
  dz=$(awk -v f="$scale" 'BEGIN { printf "%.17g", 5 * f }')
  [ $rc -eq 0 ] && "$LSM" reconstruct "$SET" -o "$TMP/out-scaled" --input outline \
    --heights "$TMP/heights-scaled.txt" --dz "$dz" -q --no-preview >"$TMP/o" 2>>"$TMP/e"
  rc=$?
  check "heights scaled by $scale run (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
  cat "$TMP/out-unit/slices/"*.png >"$TMP/unit.bin"
  cat "$TMP/out-scaled/slices/"*.png >"$TMP/scaled.bin" 2>/dev/null
  check "heights and --dz scaled by $scale: the same slices" \
    sh -c "[ \$(ls '$TMP/out-scaled/slices' | wc -l) -eq \$(ls '$TMP/out-unit/slices' | wc -l) ] && cmp -s '$TMP/unit.bin' '$TMP/scaled.bin'"
done

# The signed distance itself is in the unit too: every length scaled by 2^-30 or 2^30 scales
# every volume value and mesh vertex by the same factor exactly (normals and faces unchanged), the
# empty slice (filled with 1e6 pixels, not 1e6 units), the end cap past mid-gap (a millionth of a
# pixel beyond the depth) and the mesh's closing pad (at least a millionth of a pixel) included.
mkdir -p "$TMP/unit-end"
printf 'gray8 %s 32 8\ngray8 %s 32 6\nempty %s 32\n' \
  "$TMP/unit-end/1.png" "$TMP/unit-end/2.png" "$TMP/unit-end/3.png" | /usr/bin/python3 tests/make_png.py -
cat >"$TMP/scaled.py" <<'PY'
import array, sys
def ply(path):
    b = open(path, "rb").read()
    i = b.index(b"end_header\n") + 11
    head = b[:i].decode()
    nv = int(head.split("element vertex ")[1].split()[0])
    nprop = head.split("element vertex")[1].split("element face")[0].count("property")
    return array.array("f", b[i:i + 4 * nv * nprop]), nprop, b[i + 4 * nv * nprop:]
a, b, f = sys.argv[1], sys.argv[2], 2.0 ** int(sys.argv[3])
x = array.array("f", open(a + "/volume.raw", "rb").read())
y = array.array("f", open(b + "/volume.raw", "rb").read())
ok = len(x) == len(y) > 0 and all(u * f == v for u, v in zip(x, y))
(p, n, fp), (q, m, fq) = ply(a + "/surface.ply"), ply(b + "/surface.ply")
ok = ok and n == m == 6 and len(p) == len(q) > 0 and fp == fq and all(
    (u * f if k % 6 < 3 else u) == v for k, (u, v) in enumerate(zip(p, q)))
sys.exit(not ok)
PY
for interp in linear cubic; do
  "$LSM" reconstruct "$TMP/unit-end" -o "$TMP/out-unit-px" --spacing 8 --interp $interp \
    --format raw --mesh -q --no-preview >"$TMP/o" 2>"$TMP/e"
  rc=$?
  for e in -30 30; do
    [ $rc -eq 0 ] && "$LSM" reconstruct "$TMP/unit-end" -o "$TMP/out-unit-scaled" \
      --spacing "$(awk -v e=$e 'BEGIN { printf "%.17g", 8 * 2 ^ e }')" \
      --pixel-size "$(awk -v e=$e 'BEGIN { printf "%.17g", 2 ^ e }')" --interp $interp \
      --format raw --mesh -q --no-preview >"$TMP/o" 2>>"$TMP/e"
    rc=$?
    check "--interp $interp, pixel size 2^$e runs (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
    check "--interp $interp: all lengths times 2^$e give the volume and mesh times 2^$e" \
      /usr/bin/python3 "$TMP/scaled.py" "$TMP/out-unit-px" "$TMP/out-unit-scaled" $e
  done
done

# the 3D preview is drawn in the volume's own units: the same picture at any scale (its rays
# started one unit out, which lost all precision at pixel sizes of 1e-12 and below)
for e in 0 -60; do
  "$LSM" reconstruct "$TMP/unit-end" -o "$TMP/out-unit-prev$e" --no-slices -q \
    --spacing "$(awk -v e=$e 'BEGIN { printf "%.17g", 8 * 2 ^ e }')" \
    --pixel-size "$(awk -v e=$e 'BEGIN { printf "%.17g", 2 ^ e }')" >"$TMP/o" 2>&1
done
check "preview3d.png at pixel size 2^-60 is the one at 1" \
  cmp -s "$TMP/out-unit-prev0/preview3d.png" "$TMP/out-unit-prev-60/preview3d.png"

# An output height a rounding error away from an input height far from zero is that input
# slice: the grid tests compare offsets from the first height, not heights (a height of 7e7
# with --dz 0.01 gave a gap's last fraction as -7e-7 and ran the morph to --max-iter).
printf '74446402.1675301\n74446402.20753011\n74446402.24753012\n74446402.26753011\n' \
  >"$TMP/far-heights.txt"
mkdir -p "$TMP/far"
printf 'gray8 %s 32 8\ngray8 %s 32 5\ngray8 %s 32 9\ngray8 %s 32 7\n' "$TMP/far/1.png" \
  "$TMP/far/2.png" "$TMP/far/3.png" "$TMP/far/4.png" | /usr/bin/python3 tests/make_png.py -
"$LSM" reconstruct "$TMP/far" -o "$TMP/out-far-z" --heights "$TMP/far-heights.txt" --dz 0.01 \
  --no-preview --max-iter 2000 >"$TMP/o" 2>"$TMP/e"
rc=$?
check "heights near 7e7, --dz 0.01 runs (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
check "heights near 7e7: 11 slices, the last input's included" \
  sh -c "[ \$(ls '$TMP/out-far-z/slices' | wc -l) -eq 11 ]"
check "heights near 7e7: no gap stops at --max-iter" sh -c "! grep -q 'max-iter' '$TMP/e'"

# --reinit-every: a reinitialised phi can move faster than phi_0 did, so the CFL bound is taken
# again after each reinitialisation (a 51x3 bar morphing into scattered pixels on a 79x9 frame
# blew up at iteration 191 with the step fixed from phi_0)
mkdir -p "$TMP/reinit-cfl"
/usr/bin/python3 - "$TMP/reinit-cfl" "$(dirname "$0")" <<'PY'
import sys
sys.path.insert(0, sys.argv[2])
from make_png import write_drawn as png
W = 79
bar = ["." * W] * 3 + ["." * 12 + "#" * 51 + "." * 16] * 3 + ["." * W] * 3
dots = ["." * W] * 6 + ["...." + "#" + "." * 35 + "#" + "." * 38, "." * 39 + "#" + "." * 39,
                        "." * 38 + "#" + "." * 30 + "###" + "." * 7]
png(sys.argv[1] + "/1.png", bar)
png(sys.argv[1] + "/2.png", dots)
PY
"$LSM" reconstruct "$TMP/reinit-cfl" -o "$TMP/out-reinit-cfl" --spacing 100 --reinit-every 10 -q \
  --no-preview >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--reinit-every 10 on a bar into scattered pixels runs (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]

# --per-iteration: each pair has its own slice count, so the heights are uneven; the volume
# files hold one spacing, and run.json and a note say so.
"$LSM" reconstruct "$SET" -o "$TMP/out-iter" --input outline --heights "$SET/heights.txt" \
  --per-iteration --no-preview >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--per-iteration exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
check "--per-iteration: run.json says \"evenly_spaced\": false" grep -q '"evenly_spaced": false' "$TMP/out-iter/run.json"
check "--per-iteration: a note says the slices are not evenly spaced" grep -q "note: the output slices are not evenly spaced" "$TMP/e"
check "outline pyramid: no note that it looks filled" sh -c "! grep -q 'looks filled' '$TMP/e'"
for field in '"values": "sdf"' '"formats": ["nrrd"]' '"nrrd_encoding": "raw"' '"mesh": false' '"preview": false' \
  '"pixel_size": 1, "pixel_size_y": 1,' \
  '"particles_per_cell": 16' '"pls_reseed": 0' '"pls_radius_adjust": false' '"seed": '; do
  check "run.json options record $field" grep -qF "$field" "$TMP/out-iter/run.json"
done
check "--per-iteration: run.json records the linear profile it uses" grep -q '"interp": "linear", "ends": "halfway"' "$TMP/out-iter/run.json"
check "--per-iteration without --interp: no note about it" sh -c "! grep -q 'no effect' '$TMP/e'"
"$LSM" reconstruct "$SET" -o "$TMP/out-iter-cubic" --input outline --heights "$SET/heights.txt" \
  --per-iteration --interp cubic --ends tip --no-preview >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--per-iteration --interp cubic exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
check "--per-iteration --interp cubic: a note says it has no effect" grep -q "note: --per-iteration takes the linear profile" "$TMP/e"
check "--per-iteration --interp cubic: run.json says linear" grep -q '"interp": "linear", "ends": "halfway"' "$TMP/out-iter-cubic/run.json"
check "--per-iteration --interp cubic: the same volume" cmp -s "$TMP/out-iter/volume.nrrd" "$TMP/out-iter-cubic/volume.nrrd"

# Files numbered with gaps (every 8th slice kept under its own name) and no --spacing or
# --heights: a note says how to place them; none once placed, none for consecutive numbers.
mkdir -p "$TMP/numbered" "$TMP/numbered-uneven" "$TMP/numbered-consecutive"
for n in 1 2 3; do
  cp "$SET/00$n.png" "$TMP/numbered/slice_$(printf %03d $((8 * n - 7))).png"
  cp "$SET/00$n.png" "$TMP/numbered-consecutive/slice_$(printf %03d $((n + 4))).png"
done
cp "$SET/001.png" "$TMP/numbered-uneven/a1.png"
cp "$SET/002.png" "$TMP/numbered-uneven/a3.png"
cp "$SET/003.png" "$TMP/numbered-uneven/a10.png"
"$LSM" reconstruct "$TMP/numbered" -o "$TMP/out-numbered" --input outline --no-preview \
  >"$TMP/o" 2>"$TMP/e"
rc=$?
check "numbered 1, 9, 17 exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
check "numbered 1, 9, 17: a note suggests --heights-from-names" \
  grep -q "note: .*numbered: the file names number the slices 1, 9, ... 17 (steps of 8), .*add --heights-from-names" "$TMP/e"
check "numbered 1, 9, 17 without placement: 3 slices" [ "$(lines "$TMP/out-numbered/heights.txt")" -eq 3 ]
check "numbered, no heights.txt beside them: no note about one" sh -c "! grep -q 'is not read' '$TMP/e'"
"$LSM" reconstruct "$TMP/numbered" -o "$TMP/out-numbered-8" --input outline --no-preview \
  --spacing 8 >"$TMP/o" 2>"$TMP/e"
check "numbered, --spacing 8: no such note" sh -c "! grep -q 'file names number' '$TMP/e'"
check "numbered, --spacing 8: 17 slices" [ "$(lines "$TMP/out-numbered-8/heights.txt")" -eq 17 ]
"$LSM" reconstruct "$TMP/numbered" -o "$TMP/out-numbered-q" --input outline --no-preview -q \
  >"$TMP/o" 2>"$TMP/e"
check "numbered, -q: nothing on stderr" [ ! -s "$TMP/e" ]
"$LSM" reconstruct "$TMP/numbered-uneven" -o "$TMP/out-uneven" --input outline --no-preview \
  >"$TMP/o" 2>"$TMP/e"
check "numbered 1, 3, 10: a note suggests --heights-from-names" \
  grep -q "note: .*numbered-uneven: the file names number the slices 1 to 10 unevenly, .*add --heights-from-names" "$TMP/e"
"$LSM" reconstruct "$TMP/numbered-consecutive" -o "$TMP/out-consecutive" --input outline \
  --no-preview >"$TMP/o" 2>"$TMP/e"
check "numbered 5, 6, 7: no note about the names" sh -c "! grep -q 'file names number' '$TMP/e'"
# A heights.txt beside the slices is not read without --heights: a note says so.
"$LSM" reconstruct "$SET" -o "$TMP/out-beside" --input outline --no-preview >"$TMP/o" 2>"$TMP/e"
check "heights.txt beside the slices, no --heights: a note says it is not read" \
  grep -q "^lsmorph: note: .*pyramid/heights.txt is not read: the slices are 1 apart; give it with --heights" "$TMP/e"
check "heights.txt beside the slices: placed 1 apart (7 slices)" [ "$(lines "$TMP/out-beside/heights.txt")" -eq 7 ]
"$LSM" reconstruct "$SET" -o "$TMP/out-beside-h" --input outline --no-preview --dz 40 \
  --heights "$SET/heights.txt" >"$TMP/o" 2>"$TMP/e"
check "with --heights: no such note" sh -c "! grep -q 'is not read' '$TMP/e'"
# --heights-from-names: the numbers times --spacing are the heights.
"$LSM" reconstruct "$TMP/numbered" -o "$TMP/out-names" --input outline --no-preview \
  --heights-from-names >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--heights-from-names exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
check "--heights-from-names: no note about the names" sh -c "! grep -q 'file names number' '$TMP/e'"
# (the samples after the 512-byte header; the origin differs: z 1 against 0)
check "--heights-from-names on 1, 9, 17: the samples of --spacing 8" \
  cmp -s -i 512 "$TMP/out-names/volume.nrrd" "$TMP/out-numbered-8/volume.nrrd"
check "--heights-from-names: the origin at z 1" grep -aq "^space origin: (0,0,1)$" "$TMP/out-names/volume.nrrd"
check "--heights-from-names: heights.txt starts at 1" [ "$(head -1 "$TMP/out-names/heights.txt")" = 1 ]
check "--heights-from-names: run.json records it" grep -q '"heights_from_names": true' "$TMP/out-names/run.json"
check "without it run.json says false" grep -q '"heights_from_names": false' "$TMP/out-numbered-8/run.json"
"$LSM" reconstruct "$TMP/numbered-uneven" -o "$TMP/out-names-uneven" --input outline --no-preview \
  --heights-from-names --spacing 2.5 --dz 2.5 -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--heights-from-names --spacing 2.5 on 1, 3, 10 exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
check "--heights-from-names --spacing 2.5: input heights 2.5, 7.5, 25" \
  grep -q '"heights": \[2.5, 7.5, 25\]' "$TMP/out-names-uneven/run.json"
check "--heights-from-names --spacing 2.5 --dz 2.5: 10 slices, 2.5 to 25" \
  [ "$(tr '\n' ' ' <"$TMP/out-names-uneven/heights.txt")" = "2.5 5 7.5 10 12.5 15 17.5 20 22.5 25 " ]
# names_refused FOLDER FIRST SECOND ERROR WHAT: two slices named FIRST, SECOND are refused
# with --heights-from-names, the error naming SECOND, and nothing is written.
names_refused() {
  mkdir -p "$TMP/$1"
  cp "$SET/001.png" "$TMP/$1/$2"
  cp "$SET/002.png" "$TMP/$1/$3"
  "$LSM" reconstruct "$TMP/$1" -o "$TMP/out-$1" --input outline --heights-from-names \
    >"$TMP/o" 2>"$TMP/e"
  rc=$?
  check "--heights-from-names, $5: exit 1 (got $rc)" [ $rc -eq 1 ]
  check "--heights-from-names, $5: the error says so" \
    grep -q "^lsmorph: error: .*$1/$3: --heights-from-names: $4" "$TMP/e"
  check "--heights-from-names, $5: nothing written" [ ! -e "$TMP/out-$1" ]
}
names_refused names-bad s1.png top.png "the file name does not end with a number" \
  "a name without a number"
names_refused names-down a_12.png b_3.png "its number 3 does not follow a_12.png's 12" \
  "numbers falling in name order"
"$LSM" reconstruct "$TMP/numbered" -o "$TMP/out-names-both" --heights "$SET/heights.txt" \
  --heights-from-names >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--heights with --heights-from-names: usage error, exit 2 (got $rc)" [ $rc -eq 2 ]
check "--heights with --heights-from-names: the error says give one" \
  grep -q "^lsmorph: error: --heights and --heights-from-names both place the slices: give one" "$TMP/e"
"$LSM" reconstruct "$TMP/numbered" -o "$TMP/out-names-value" --heights-from-names=yes >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--heights-from-names=yes: usage error, exit 2 (got $rc)" [ $rc -eq 2 ]

# --ends changes only gaps next to an empty slice: the pyramid has none.
"$LSM" reconstruct "$SET" -o "$TMP/out-halfway" --input outline --heights "$SET/heights.txt" \
  --dz 10 --ends halfway -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--ends halfway exits 0 (got $rc)" [ $rc -eq 0 ]
check "run.json options say \"ends\": \"halfway\"" grep -q '"ends": "halfway"' "$TMP/out-halfway/run.json"
check "--ends halfway: the same volume without empty slices" cmp -s "$OUT/volume.nrrd" "$TMP/out-halfway/volume.nrrd"

# Options that do not apply to the run: a note each, the result unchanged; run.json records the
# end rule the linear profile uses (mid-gap: halfway).
"$LSM" reconstruct "$TMP/unit-end" -o "$TMP/out-lin-half" --spacing 8 --interp linear \
  --ends halfway --format raw --no-preview >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--interp linear --ends halfway exits 0 (got $rc)" [ $rc -eq 0 ]
check "--interp linear --ends halfway: no note about --ends" sh -c "! grep -q 'ends tip|auto have no effect' '$TMP/e'"
check "no --nrrd-encoding: no note about it" sh -c "! grep -q 'nrrd-encoding' '$TMP/e'"
"$LSM" reconstruct "$TMP/unit-end" -o "$TMP/out-lin-tip" --spacing 8 --interp linear \
  --ends tip --format raw --no-preview --tol 0.1 --seed 7 --device 1 --nrrd-encoding gzip >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--interp linear --ends tip exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
check "--interp linear --ends tip: a note says --ends has no effect" grep -q "note: --interp linear ends an object at mid-gap: --ends tip|auto have no effect" "$TMP/e"
check "--interp linear --ends tip: run.json records halfway" grep -q '"interp": "linear", "ends": "halfway"' "$TMP/out-lin-tip/run.json"
check "--interp linear: --ends tip gives the same volume as halfway" cmp -s "$TMP/out-lin-half/volume.raw" "$TMP/out-lin-tip/volume.raw"
check "--tol without --per-iteration: a note" grep -q "note: --tol has no effect without --per-iteration" "$TMP/e"
check "--seed with ls: a note" grep -q "note: --seed has no effect without --method pls" "$TMP/e"
check "--device with the C backend: a note" grep -q "note: --device has no effect with --backend c" "$TMP/e"
check "--nrrd-encoding without nrrd: a note" grep -q "note: --nrrd-encoding has no effect without nrrd in --format" "$TMP/e"
check "--nrrd-encoding gzip: run.json records it" grep -q '"nrrd_encoding": "gzip"' "$TMP/out-lin-tip/run.json"
check "--cfl at its default: no note about monotonicity" sh -c "! grep -q 'is above 1' '$TMP/e'"
"$LSM" reconstruct "$TMP/unit-end" -o "$TMP/out-cfl" --spacing 8 --cfl 1.2 --format raw \
  --no-preview >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--cfl 1.2 exits 0 (got $rc)" [ $rc -eq 0 ]
check "--cfl 1.2: a note says the schemes are monotone only up to 1" \
  grep -q "note: --cfl 1.2 is above 1, where the schemes are no longer monotone" "$TMP/e"
"$LSM" reconstruct "$TMP/unit-end" -o "$TMP/out-blend" --spacing 8 --method blend --format raw \
  --no-preview >"$TMP/o" 2>"$TMP/e"
"$LSM" reconstruct "$TMP/unit-end" -o "$TMP/out-blend-cfl" --spacing 8 --method blend --format raw \
  --no-preview --time rk3 --cfl 0.3 >"$TMP/o" 2>"$TMP/e2"
rc=$?
check "blend --time rk3 --cfl 0.3 exits 0 (got $rc)" [ $rc -eq 0 ]
check "blend --time rk3: a note names --time" grep -q "note: --time has no effect with --method blend" "$TMP/e2"
check "blend without solver options: no such note" sh -c "! grep -q 'has no effect' '$TMP/e'"
check "blend: the solver options change nothing" cmp -s "$TMP/out-blend/volume.raw" "$TMP/out-blend-cfl/volume.raw"
"$LSM" reconstruct "$TMP/unit-end" -o "$TMP/out-pls-seed" --spacing 8 --method pls --seed 7 \
  --no-preview --format raw >"$TMP/o" 2>"$TMP/e"
check "--seed with pls: no note" sh -c "! grep -q 'has no effect' '$TMP/e'"
# image files of another format in the slice folder are left out, with a note counting them
mkdir -p "$TMP/with-tif"
cp "$TMP/unit-end/"*.png "$TMP/with-tif/"
printf 'x' >"$TMP/with-tif/4.bmp"
printf 'x' >"$TMP/with-tif/5.JPG"
printf 'x' >"$TMP/with-tif/notes.txt"
"$LSM" reconstruct "$TMP/with-tif" -o "$TMP/out-with-tif" --spacing 8 --no-preview >"$TMP/o" 2>"$TMP/e"
rc=$?
check "a folder with .bmp and .jpg files besides the PNGs exits 0 (got $rc)" [ $rc -eq 0 ]
check "a note counts the 2 image files of another format" grep -q "with-tif: 2 image files in another format than PNG or TIFF" "$TMP/e"
"$LSM" reconstruct "$TMP/unit-end" -o "$TMP/out-no-tif" --spacing 8 --no-preview >"$TMP/o" 2>"$TMP/e"
check "PNG slices only: no such note" sh -c "! grep -q 'another format than PNG' '$TMP/e'"
# TIFF slices (Pillow writes them): 8-bit LZW, 1-bit CCITT G4, 16-bit 0/1 labels, and PNG
# and TIFF mixed, each give the PNG stack's volume byte for byte
/usr/bin/python3 - "$TMP/unit-end" "$TMP" <<'PY'
import glob, os, sys
import numpy as np
from PIL import Image
src, tmp = sys.argv[1], sys.argv[2]
for kind in ("tiff8", "tiff1", "tiff16", "mixed"):
    os.makedirs(os.path.join(tmp, kind), exist_ok=True)
for i, path in enumerate(sorted(glob.glob(os.path.join(src, "*.png")))):
    a = np.array(Image.open(path).convert("L"))
    name = os.path.basename(path)[:-4]
    Image.fromarray(a).save(os.path.join(tmp, "tiff8", name + ".tif"), compression="tiff_lzw")
    Image.fromarray(a >= 128).save(os.path.join(tmp, "tiff1", name + ".TIFF"), compression="group4")
    Image.fromarray((a >= 128).astype(np.uint16)).save(os.path.join(tmp, "tiff16", name + ".tif"))
    Image.fromarray(a).save(os.path.join(tmp, "mixed", name + (".tif" if i % 2 else ".png")))
PY
for kind in tiff8 tiff1 tiff16 mixed; do
  "$LSM" reconstruct "$TMP/$kind" -o "$TMP/out-$kind" --spacing 8 --no-preview >"$TMP/o" 2>"$TMP/e"
  rc=$?
  check "$kind slices exit 0 (got $rc: $(head -c 200 "$TMP/e"))" [ $rc -eq 0 ]
  check "$kind slices give the PNG stack's volume" cmp -s "$TMP/out-$kind/volume.nrrd" "$TMP/out-no-tif/volume.nrrd"
  [ $kind = tiff16 ] && check "16-bit 0/1 label TIFFs: the note on label masks" grep -q "(label masks stored as 0/1)" "$TMP/e"
done

# --motion auto (the default): a thin ellipse turning 40 degrees per slice is tried pair by
# pair (run.json pairs[].motion: left_out, field) and the run says so; --motion none does not
/usr/bin/python3 - "$TMP/turning" <<'PY'
import os, sys
import numpy as np
from PIL import Image
os.makedirs(sys.argv[1], exist_ok=True)
y, x = np.mgrid[0:64, 0:96] - np.array([32, 48])[:, None, None]
for k in range(5):
    t = np.radians(40 * k)
    u, v = x * np.cos(t) + y * np.sin(t), -x * np.sin(t) + y * np.cos(t)
    Image.fromarray(((u / 16) ** 2 + (v / 3) ** 2 <= 1).astype(np.uint8) * 255).save(
        os.path.join(sys.argv[1], "%d.png" % k))
PY
"$LSM" reconstruct "$TMP/turning" -o "$TMP/out-turning" --spacing 8 --no-preview >"$TMP/o" 2>"$TMP/e"
check "turning ellipse: the auto note ($(grep auto "$TMP/e"))" grep -q "note: --motion auto tried 4 of 4 pairs" "$TMP/e"
check "turning ellipse: run.json has each pair's left_out" [ "$(json_count "$TMP/out-turning/run.json" left_out)" -eq 4 ]
check "turning ellipse: the pairs follow the field" grep -q '"field": true' "$TMP/out-turning/run.json"
"$LSM" reconstruct "$TMP/turning" -o "$TMP/out-turning-none" --spacing 8 --no-preview --motion none \
  >"$TMP/o" 2>"$TMP/e"
check "--motion none: no auto note" sh -c "! grep -q 'motion auto' '$TMP/e'"
check "--motion none: no motion in run.json's pairs" [ "$(json_count "$TMP/out-turning-none/run.json" left_out)" -eq 0 ]

# The same command into an existing OUT replaces it.
"$LSM" reconstruct "$SET" -o "$OUT" --input outline --heights "$SET/heights.txt" --dz 40 -q \
  >"$TMP/o" 2>"$TMP/e"
rc=$?
check "re-running into an existing OUT exits 0 (got $rc)" [ $rc -eq 0 ]
N2=$(lines "$OUT/heights.txt")
check "re-run replaced OUT (7 slices with --dz 40, got $N2)" [ "$N2" -eq 7 ]
NS2=$(ls "$OUT/slices" | grep -c '\.png$')
check "re-run left no stale slices (got $NS2)" [ "$NS2" -eq 7 ]

# ---- failures: exit 1, nothing created --------------------------------------------------
"$LSM" reconstruct "$TMP/does-not-exist" -o "$TMP/out-missing" -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "missing folder exits 1 (got $rc)" [ $rc -eq 1 ]
check "missing folder says 'lsmorph: error:'" grep -q "lsmorph: error:" "$TMP/e"
check "missing folder leaves no OUT" [ ! -e "$TMP/out-missing" ]
check "missing folder leaves no temporary folder" sh -c "! ls -d '$TMP'/out-missing.tmp-* >/dev/null 2>&1"

printf '0\n10\n' >"$TMP/h2.txt"
"$LSM" reconstruct "$SET" -o "$TMP/out-h" --input outline --heights "$TMP/h2.txt" -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "2 heights for 7 slices exits 1 (got $rc)" [ $rc -eq 1 ]
check "2 heights for 7 slices leaves no OUT" [ ! -e "$TMP/out-h" ]

mkdir "$TMP/one" && cp "$SET/001.png" "$TMP/one/"
"$LSM" reconstruct "$TMP/one" -o "$TMP/out-one" -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "a single slice exits 1 (got $rc)" [ $rc -eq 1 ]
check "a single slice leaves no OUT" [ ! -e "$TMP/out-one" ]

# ---- natural sort end to end -------------------------------------------------------------
# 1.png, 2.png, 10.png: natural order 1, 2, 10 (byte order would be 1, 10, 2).
NAT="$TMP/nat"
mkdir "$NAT"
cp "$SET/001.png" "$NAT/1.png"
cp "$SET/002.png" "$NAT/2.png"
cp "$SET/003.png" "$NAT/10.png"
"$LSM" reconstruct "$NAT" -o "$TMP/out-nat" --input outline --spacing 4 --method blend -q \
  >"$TMP/o" 2>"$TMP/e"
rc=$?
check "natural-sort run exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
if [ -f "$TMP/out-nat/run.json" ]; then
  check "run.json files in natural order 1, 2, 10" \
    grep -q '"files": \["1.png", "2.png", "10.png"\]' "$TMP/out-nat/run.json"
  check "run.json pair 1.png -> 2.png" \
    grep -q '"source": "1.png", "target": "2.png"' "$TMP/out-nat/run.json"
  check "run.json pair 2.png -> 10.png" \
    grep -q '"source": "2.png", "target": "10.png"' "$TMP/out-nat/run.json"
  # Heights 0, 4, 8 with dz 1: 9 slices.
  check "natural-sort run wrote 9 slices" [ "$(lines "$TMP/out-nat/heights.txt")" -eq 9 ]
fi
# ---- run.json: any file name, heights as given ------------------------------------------------
# Names that are not UTF-8 (a Latin-1 e-acute, byte 0xe9) still make valid JSON
# (as \u00e9), and heights keep every digit of the heights file.
ODD="$TMP/odd"
mkdir "$ODD"
cp "$SET/001.png" "$ODD/$(printf 'a\351')1.png"
cp "$SET/002.png" "$ODD/$(printf 'a\351')2.png"
printf '1000000.1234567\n1000001.1234567\n' >"$TMP/odd-heights"
"$LSM" reconstruct "$ODD" -o "$TMP/out-odd" --input outline --heights "$TMP/odd-heights" \
  --method blend --no-preview -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "non-UTF-8 names run exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
if command -v python3 >/dev/null 2>&1 && [ -f "$TMP/out-odd/run.json" ]; then
  check "run.json is valid JSON with non-UTF-8 names (Latin-1), heights to every digit" python3 -c '
import json, sys
d = json.load(open(sys.argv[1], encoding="utf-8"))
assert d["input"]["files"] == ["a\u00e91.png", "a\u00e92.png"], d["input"]["files"]
assert d["input"]["heights"] == [1000000.1234567, 1000001.1234567], d["input"]["heights"]
assert d["output"]["first_height"] == 1000000.1234567, d["output"]
' "$TMP/out-odd/run.json"
fi
# "--" ends the options: a folder whose name starts with '-'
cp -r "$ODD" "$TMP/-dash"
ABS_LSM=$(cd "$(dirname "$LSM")" && pwd)/$(basename "$LSM")
(cd "$TMP" && "$ABS_LSM" reconstruct -o out-dash --method blend --no-preview -q -- -dash) >"$TMP/o" 2>"$TMP/e"
rc=$?
check "reconstruct -- -dash exits 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
(cd "$TMP" && "$ABS_LSM" score --stride 2 -- -dash out-dash) >"$TMP/o" 2>"$TMP/e"
check "score --stride 2 -- -dash OUT reads -dash as the truth folder" grep -q -- "-dash: 2 slice images" "$TMP/e"
# --seed takes any 64-bit unsigned value
"$LSM" reconstruct "$NAT" -o "$TMP/out-seed" --input outline --spacing 4 --method pls \
  --seed 18446744073709551615 --no-preview -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--seed 2^64 - 1 runs (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
check "run.json options record --seed 2^64 - 1 exactly" grep -qF '"seed": 18446744073709551615}' "$TMP/out-seed/run.json"
# The rectangles shrink in natural order (1.png: 86x56, 2.png: 64x42, 10.png:
# 48x30); byte order (1, 10, 2) would not.  With dz 1 the output slices at
# z = 0, 4, 8 are those inputs exactly: count their inside cells (phi <= 0)
# in volume.nrrd (little-endian float32 after the 512-byte header).
inside() { # inside NRRD K: cells with phi <= 0 in slice K (0-based)
  od -An -v -tf4 -j $((512 + $2 * W * H * 4)) -N $((W * H * 4)) "$1" |
    awk '{ for (i = 1; i <= NF; i++) if ($i + 0 <= 0) n++ } END { print n + 0 }'
}
V="$TMP/out-nat/volume.nrrd"
if [ -f "$V" ]; then
  a0=$(inside "$V" 0)
  a4=$(inside "$V" 4)
  a8=$(inside "$V" 8)
  check "natural order: inside areas decrease over z = 0, 4, 8 (got $a0, $a4, $a8)" \
    awk -v a="$a0" -v b="$a4" -v c="$a8" 'BEGIN { exit !(a > b && b > c && c > 0) }'
else
  bad "natural-sort run wrote no volume.nrrd"
fi

# Discs of radius 9 and 10 blended at mid-gap: the ring between them is half a
# pixel outside one and inside the other, so the blend ties at exactly 0 on
# the surface (48 samples before ties were broken).  No sample is exactly 0:
# phi < 0 and phi <= 0 give the same inside (ties count as inside).
mkdir -p "$TMP/ties"
printf 'gray8 %s 48 9\ngray8 %s 48 10\n' "$TMP/ties/1.png" "$TMP/ties/2.png" |
  /usr/bin/python3 tests/make_png.py -
"$LSM" reconstruct "$TMP/ties" -o "$TMP/out-ties" --spacing 2 --method blend --no-preview -q
ties=$(od -An -v -tf4 -j $((512 + 48 * 48 * 4)) -N $((48 * 48 * 4)) "$TMP/out-ties/volume.nrrd" |
  awk '{ for (i = 1; i <= NF; i++) { if ($i + 0 == 0) z++; if ($i + 0 < 0) n++ } } END { print z + 0, n + 0 }')
"$LSM" reconstruct "$TMP/ties" -o "$TMP/out-ties-mask" --spacing 2 --method blend --values mask \
  --no-preview -q
masked=$(od -An -v -tu1 -j $((512 + 48 * 48)) -N $((48 * 48)) "$TMP/out-ties-mask/volume.nrrd" |
  awk '{ for (i = 1; i <= NF; i++) if ($i == 255) n++ } END { print n + 0 }')
check "blend of discs r 9 and 10 at mid-gap: no sample exactly 0, and phi < 0 is the mask's inside (got zeros, inside: $ties; mask $masked)" \
  [ "$ties" = "0 $masked" ]

# label masks stored as 0/1: read as non-zero foreground (with a note), the
# same volume as the 0/255 version of the same discs
mkdir -p "$TMP/lab01" "$TMP/lab255"
printf 'label01 %s 48 14\nlabel01 %s 48 9\ngray8 %s 48 14\ngray8 %s 48 9\n' \
  "$TMP/lab01/1.png" "$TMP/lab01/2.png" "$TMP/lab255/1.png" "$TMP/lab255/2.png" |
  /usr/bin/python3 tests/make_png.py -
"$LSM" reconstruct "$TMP/lab01" -o "$TMP/out-lab01" --spacing 4 --no-preview 2>"$TMP/lab.err"
check "0/1 label masks: exit 0" [ $? -eq 0 ]
check "0/1 label masks: a note says non-zero pixels are foreground" grep -q "non-zero pixels as foreground" "$TMP/lab.err"
"$LSM" reconstruct "$TMP/lab255" -o "$TMP/out-lab255" --spacing 4 --no-preview -q
check "0/1 label masks: same volume as 0/255 masks" cmp -s "$TMP/out-lab01/volume.nrrd" "$TMP/out-lab255/volume.nrrd"
# score reads 0/1 label truth as reconstruct read the kept slices: decided
# over the kept ones, so a bright pixel in a held-out slice changes nothing
mkdir -p "$TMP/labtruth" "$TMP/labkept"
printf 'label01 %s 32 5\nlabel01_speck %s 32 6\nlabel01 %s 32 7\nlabel01 %s 32 8\nlabel01 %s 32 9\n' \
  "$TMP/labtruth/1.png" "$TMP/labtruth/2.png" "$TMP/labtruth/3.png" "$TMP/labtruth/4.png" \
  "$TMP/labtruth/5.png" | /usr/bin/python3 tests/make_png.py -
cp "$TMP/labtruth/1.png" "$TMP/labtruth/3.png" "$TMP/labtruth/5.png" "$TMP/labkept/"
"$LSM" reconstruct "$TMP/labkept" -o "$TMP/out-labkept" --spacing 2 --no-preview -q
"$LSM" score "$TMP/labtruth" "$TMP/out-labkept" --stride 2 >"$TMP/o" 2>"$TMP/e"
rc=$?
check "score of 0/1 label truth with a bright pixel held out: exit 0 (got $rc: $(cat "$TMP/e"))" [ $rc -eq 0 ]
check "score of 0/1 label truth with a bright pixel held out: Dice above 0.9 ($(cat "$TMP/o"))" \
  awk -F'"dice_volume": ' '{ split($2, v, ","); exit !(v[1] > 0.9) }' "$TMP/o"
# score's distances are in pixel widths: a row step counts pixel_size_y / pixel_size of them
# (run.json).  A held-out slice left empty counts the image size for each boundary pixel of
# the truth: 48 columns, or 40 rows of pixels twice as tall.
mkdir -p "$TMP/rowtruth" "$TMP/rowkept"
printf 'empty %s 48x40\ngray8 %s 48x40 9\nempty %s 48x40\n' "$TMP/rowtruth/1.png" \
  "$TMP/rowtruth/2.png" "$TMP/rowtruth/3.png" | /usr/bin/python3 tests/make_png.py -
cp "$TMP/rowtruth/1.png" "$TMP/rowtruth/3.png" "$TMP/rowkept/"
for px in 1 1,2; do
  "$LSM" reconstruct "$TMP/rowkept" -o "$TMP/out-row$px" --spacing 2 --pixel-size $px --no-preview -q
  "$LSM" score "$TMP/rowtruth" "$TMP/out-row$px" --stride 2 >"$TMP/row$px.json" 2>"$TMP/e"
  check "score of pixels $px: exit 0 ($(cat "$TMP/e"))" [ $? -eq 0 ]
done
check "score: an empty slice costs 48 pixel widths on square pixels ($(cat "$TMP/row1.json"))" \
  grep -q '"hd95_pooled": 48,' "$TMP/row1.json"
check "score: and 80 on pixels 1 x 2 ($(cat "$TMP/row1,2.json"))" grep -q '"hd95_pooled": 80,' "$TMP/row1,2.json"
# --per-slice: the same scores, and each held-out slice's, which the means come from
"$LSM" score "$TMP/labtruth" "$TMP/out-labkept" --stride 2 --per-slice >"$TMP/o2" 2>"$TMP/e"
check "score --per-slice: exit 0 ($(cat "$TMP/e"))" [ $? -eq 0 ]
check "score --per-slice: slices 2 and 4 between their inputs, the means theirs, the rest as without ($(cat "$TMP/o2"))" \
  /usr/bin/python3 -c '
import json, sys
plain, per = (json.load(open(f)) for f in sys.argv[1:3])
rows = per.pop("slices")
assert per == plain, (per, plain)
assert [r["truth"] for r in rows] == [2, 4] and [r["file"] for r in rows] == ["2.png", "4.png"]
assert [r["between"] for r in rows] == [[1, 3], [3, 5]]
assert abs(sum(r["dice"] for r in rows) / 2 - plain["dice"]) < 1e-12
assert abs(sum(r["hd95"] for r in rows) / 2 - plain["hd95"]) < 1e-12
assert all(r["area_truth"] > 0 and r["area_result"] > 0 for r in rows)
' "$TMP/o" "$TMP/o2"
# a label map (labels 1 and 200): the dark label reads as background, and a note says so;
# a drawn mask (0/255 with no dark grey) gets no such note
mkdir -p "$TMP/labmap"
printf 'labels %s 48 14\nlabels %s 48 9\n' "$TMP/labmap/1.png" "$TMP/labmap/2.png" |
  /usr/bin/python3 tests/make_png.py -
"$LSM" reconstruct "$TMP/labmap" -o "$TMP/out-labmap" --spacing 4 --no-preview 2>"$TMP/lab.err"
check "label map: exit 0" [ $? -eq 0 ]
check "label map: a note says the dark labels read as background" \
  grep -q "labmap/1.png: [0-9]* pixels are non-zero but below 50 % luminance" "$TMP/lab.err"
"$LSM" reconstruct "$TMP/lab255" -o "$TMP/out-lab255b" --spacing 4 --no-preview 2>"$TMP/lab.err"
check "0/255 masks: no label-map note" sh -c "! grep -q 'below 50 % luminance' '$TMP/lab.err'"
# also when the only non-empty 0/1 slice is full (no slice has a boundary): it read as empty
mkdir -p "$TMP/labfull01" "$TMP/labfull255"
printf 'label01 %s 24 0.1\nlabel01 %s 24 99\nlabel01 %s 24 0.1\nempty %s 24\ngray8 %s 24 99\nempty %s 24\n' \
  "$TMP/labfull01/1.png" "$TMP/labfull01/2.png" "$TMP/labfull01/3.png" \
  "$TMP/labfull255/1.png" "$TMP/labfull255/2.png" "$TMP/labfull255/3.png" |
  /usr/bin/python3 tests/make_png.py -
"$LSM" reconstruct "$TMP/labfull01" -o "$TMP/out-labfull01" --no-preview 2>"$TMP/lab.err"
check "full 0/1 slice: exit 0" [ $? -eq 0 ]
check "full 0/1 slice: a note says non-zero pixels are foreground" grep -q "non-zero pixels as foreground" "$TMP/lab.err"
"$LSM" reconstruct "$TMP/labfull255" -o "$TMP/out-labfull255" --no-preview -q
check "full 0/1 slice: same volume as the 0/255 stack" cmp -s "$TMP/out-labfull01/volume.nrrd" "$TMP/out-labfull255/volume.nrrd"
check "full 0/255 slice: its output slice is full" sh -c "! cmp -s '$TMP/out-labfull255/slices/00002.png' '$TMP/out-labfull255/slices/00001.png'"


# ---- reconstruction rules: help rules, --rules-off, run.json's options.rules_off ----------
out=$("$LSM" help rules 2>&1)
check "help rules exits 0" [ $? -eq 0 ]
case $out in *"
moving-parts
  what: "*"
end-floor
  what: "*) ok ;; *) bad "help rules does not list moving-parts and end-floor" ;; esac
check "default run.json: options.rules_off is []" grep -q '"rules_off": \[\]' "$OUT/run.json"
"$LSM" reconstruct "$SET" -o "$TMP/out-rules" --input outline --heights "$SET/heights.txt" \
  --dz 10 -q --no-preview --rules-off end-floor,pinhole-fill 2>"$TMP/e"
check "--rules-off: exit 0 ($(cat "$TMP/e"))" [ $? -eq 0 ]
check "--rules-off: run.json lists them in table order" \
  grep -q '"rules_off": \["pinhole-fill", "end-floor"\]' "$TMP/out-rules/run.json"
"$LSM" reconstruct "$SET" -o "$TMP/x" --rules-off end-floor,no-such-rule >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--rules-off with an unknown name exits 2 (got $rc)" [ $rc -eq 2 ]
check "--rules-off names the unknown rule" grep -q "'no-such-rule' is not a rule" "$TMP/e"
missing=$("$LSM" help rules | awk '/^constants/ { exit } /^[a-z][a-z-]*$/ { print }' |
  while read -r rule; do grep -q "^| \`$rule\` |" solver/recon/README.md || printf '%s ' "$rule"; done)
check "solver/recon/README.md lists every rule of 'help rules' (missing: $missing)" [ -z "$missing" ]

finish
