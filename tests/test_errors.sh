#!/bin/sh
# Bad input, limits, interruption and write errors, end to end.
#   sh tests/test_errors.sh BUILD_DIR
# Every failing run must exit 1 (bad input, runtime failure) or 2 (usage),
# print "lsmorph: error: <file>: <what>" naming the file and the problem, and
# leave neither OUT nor a temporary folder OUT.tmp-* behind; an earlier OUT must
# survive any failed or interrupted run unchanged.  Slices come from
# tests/make_png.py (every PNG colour type and bit depth, and broken files) and
# tests/make_stack.py.  Prints one line per failed check and
# "errors: N passed, N failed".
set -u
BUILD=${1:-build}
LSM="$BUILD/lsmorph"
PY=${PYTHON:-/usr/bin/python3}
SUITE=errors
. "$(dirname "$0")/harness.sh"

need "$LSM"
command -v "$PY" >/dev/null 2>&1 || PY=python3
command -v "$PY" >/dev/null 2>&1 || { bad "python3 is needed to make test PNGs"; finish; }

TMP=$(mktemp -d "${TMPDIR:-/tmp}/lsm-errors.XXXXXX") || exit 1
FULL="" # a tiny tmpfs for the disk-full test (root only)
trap '[ -n "$FULL" ] && umount "$FULL" 2>/dev/null; rm -rf "$TMP"' EXIT
trap 'exit 1' INT TERM
cd "$TMP" || exit 1
case $LSM in /*) ;; *) LSM="$OLDPWD/$LSM" ;; esac
TESTS=$OLDPWD/tests

# png KIND OUT [SIZE [RADIUS]]: queues a test PNG; make_pngs writes the queue
# with one Python start-up (about 0.1 s each otherwise).
png() { echo "$*" >>"$TMP/png-queue"; }
make_pngs() {
  for f in $(awk '{ print $2 }' "$TMP/png-queue"); do mkdir -p "$(dirname "$f")"; done
  "$PY" "$TESTS/make_png.py" - <"$TMP/png-queue" || bad "make_png.py failed"
  : >"$TMP/png-queue"
}
# leftovers: true when a temporary result folder is left anywhere in TMP.
leftovers() {
  for f in "$TMP"/*.tmp-* "$TMP"/*/*.tmp-*; do
    [ -e "$f" ] && return 0
  done
  return 1
}
# fingerprint DIR: a checksum of every file under DIR (to see it unchanged).
fingerprint() { (cd "$1" && find . -type f | LC_ALL=C sort | xargs cksum) 2>/dev/null | cksum; }
# inside NRRD: cells with phi <= 0 over the whole volume (float32 after 512 bytes).
inside() {
  od -An -v -tf4 -j 512 "$1" | awk '{ for (i = 1; i <= NF; i++) if ($i + 0 <= 0) n++ } END { print n + 0 }'
}

# expect DESC RC PHRASE OUT ARG...: "lsmorph ARG..." exits RC, its message
# starts with "lsmorph: error: " and contains PHRASE (a fixed string, usually
# "<file>: <what>"), and it leaves no OUT (unless OUT is "-") and no temporary folder.
expect() {
  desc=$1 want=$2 phrase=$3 out=$4
  shift 4
  "$LSM" "$@" >"$TMP/stdout" 2>"$TMP/stderr"
  rc=$?
  msg=$(cat "$TMP/stderr")
  if [ "$rc" -eq "$want" ]; then ok; else bad "$desc: exit $rc, expected $want ($msg)"; fi
  if grep -q "^lsmorph: error: " "$TMP/stderr" && grep -q -F -e "$phrase" "$TMP/stderr"; then
    ok
  else
    bad "$desc: message does not say '$phrase': $msg"
  fi
  if [ "$out" != "-" ]; then
    if [ -e "$out" ]; then bad "$desc: $out was created"; else ok; fi
  fi
  if leftovers; then bad "$desc: a temporary folder was left: $(ls -d "$TMP"/*.tmp-* 2>&1)"; else ok; fi
  rm -rf "$TMP"/*.tmp-*
}

# ---- all test PNGs -------------------------------------------------------------------------
# good: 3 discs of 32x32; b-KIND: a good slice and a broken one; k-KIND: 3 discs
# in each colour type and bit depth; the rest as named below.
for i in 1 2 3; do png gray8 "good/$i.png" 32 $((3 + 2 * i)); done
for i in 1 2 3 4; do png gray8 "late/$i.png" 128 5; done # late: only the last gap moves
png gray8 late/5.png 128 40
for i in 1 2 3 4 5 6 7 8 9; do # tall: 9 discs; tall40: the same on 40x40
  png gray8 "tall/$i.png" 32 $((4 + i))
  png gray8 "tall40/$i.png" 40 $((4 + i))
done
for kind in text zero truncated no_iend bad_crc bad_idat_crc bad_zlib text_liar palette_short; do
  png gray8 "b-$kind/1.png" 32 5
  png "$kind" "b-$kind/2.png" 32
done
png gray8 big18/123456789012345678.png 32 5 && png gray8 big18/123456789012345679.png 32 7
png gray8 dim/1.png 32 5 && png label01 dim/2.png 32 7 && png gray8 dim/3.png 32 5 # a 0/1 mask among 0/255
png gray8 sizes/1.png 32 5 && png gray8 sizes/2.png 32 7 && png gray8 sizes/3.png 40
png huge huge/1.png && png huge huge/2.png
png huge_idat huge2/1.png && png huge_idat huge2/2.png
png gray8 strip/1.png 20000x1 3 && png gray8 strip/2.png 20000x1 5
png gray8 wide/1.png 32800x1 3 && png gray8 wide/2.png 32800x1 5 # wider than NIfTI-1 holds
KINDS="gray16 gray1 graya8 rgb8 rgb16 rgba8 rgba16 palette palette_trns palette2 interlaced text_chunks"
for kind in $KINDS; do
  for i in 1 2 3; do png "$kind" "k-$kind/$i.png" 32 $((3 + 2 * i)); done
done
for i in 1 2 3; do png empty "k-empty/$i.png" 32; done
make_pngs

# ---- folders -------------------------------------------------------------------------------
expect "missing folder" 1 "nope: no such folder" out reconstruct nope -o out -q
mkdir empty
expect "empty folder" 1 "empty: no PNG or TIFF files" out reconstruct empty -o out -q
mkdir textonly && echo "not slices" >textonly/notes.txt
expect "folder without PNG files" 1 "textonly: no PNG or TIFF files" out reconstruct textonly -o out -q
echo "a file" >afile
expect "SLICE_DIR is a file" 1 "afile: not a folder" out reconstruct afile -o out -q
echo "a label volume" >seg.nii.gz
expect "SLICE_DIR is a label volume" 1 "seg.nii.gz: not a folder (a label volume? 'lsmorph fill seg.nii.gz -o OUT'" out reconstruct seg.nii.gz -o out -q
expect "a label volume as the command" 2 "to fill a label volume, 'lsmorph fill seg.nii.gz -o OUT'" - seg.nii.gz
mkdir one && cp good/1.png one/
expect "a single slice" 1 "one: only one slice" out reconstruct one -o out -q
mkdir linked && cp good/1.png good/3.png linked/ && ln -s nothing-here.png linked/2.png
expect "a broken link among the slices" 1 "linked/2.png: cannot access: a link to nothing" out \
  reconstruct linked -o out -q

# ---- broken PNG files: each the second of two slices -------------------------------------------
broken() { # broken KIND PHRASE
  expect "PNG $1" 1 "b-$1/2.png: $2" out reconstruct "b-$1" -o out -q
}
broken text "not a PNG file"
broken zero "empty file, not a PNG file"
broken truncated "truncated PNG file"
broken no_iend "truncated PNG file"
broken bad_crc "corrupt PNG: IHDR: CRC error"
broken bad_idat_crc "corrupt PNG: IDAT: CRC error"
broken bad_zlib "corrupt PNG"
broken palette_short "corrupt PNG: pixel (13, 8) has palette index 1, but the palette has 1 entry"
# a text chunk that claims 2 GB in a 44-byte file is skipped unread (libpng allocated the 2 GB
# first); the address-space cap is left out under AddressSanitizer, which reserves terabytes
if grep -q -a "__asan_init" "$LSM"; then
  broken text_liar "truncated PNG file"
else
  printf '#!/bin/sh\nulimit -v 400000\nexec "%s" "$@"\n' "$LSM" >capped.sh && chmod +x capped.sh
  real=$LSM LSM=$TMP/capped.sh
  broken text_liar "truncated PNG file"
  LSM=$real
fi

expect "slices of different sizes" 1 "sizes/3.png: slice is 40x40 but 1.png is 32x32" out reconstruct sizes -o out -q

# ---- TIFF slices that cannot be read: each the second of two slices -----------------------------
mkdir t-text t-cut t-pages t-float t-g4cut
for d in t-text t-cut t-pages t-float t-g4cut; do cp good/1.png "$d/1.png"; done
printf 'not a tiff' >t-text/2.tif
/usr/bin/python3 - <<'PY'
import numpy as np
from PIL import Image
a = np.zeros((32, 32), np.uint8)
a[8:24, 8:24] = 255
Image.fromarray(a).save("t-cut/2.tif", compression="tiff_lzw")
data = open("t-cut/2.tif", "rb").read()
open("t-cut/2.tif", "wb").write(data[: len(data) // 2])
Image.fromarray(a).save("t-pages/2.tif", save_all=True, append_images=[Image.fromarray(a)])
Image.fromarray(a.astype(np.float32)).save("t-float/2.tif")
# a CCITT G4 slice cut in half, laid out directory first (as tifffile writes):
# the directory stays readable and its byte count says what is left
Image.fromarray(a).convert("1").save("t-g4cut/g4.tif", compression="group4")
g4 = Image.open("t-g4cut/g4.tif")
raw = open("t-g4cut/g4.tif", "rb").read()
strip = b"".join(raw[o:o + n] for o, n in zip(g4.tag_v2[273], g4.tag_v2[279]))
strip = strip[: len(strip) // 2]
import struct
tags = [(256, 4, 32), (257, 4, 32), (258, 3, 1), (259, 3, 4), (262, 3, 1), (273, 4, 0),
        (277, 3, 1), (278, 4, 32), (279, 4, len(strip))]
data_at = 8 + 2 + 12 * len(tags) + 4
ifd = struct.pack("<H", len(tags)) + b"".join(
    struct.pack("<HHI", t, k, 1) + (struct.pack("<HH", v, 0) if k == 3 else
                                    struct.pack("<I", data_at if t == 273 else v))
    for t, k, v in tags) + struct.pack("<I", 0)
open("t-g4cut/2.tif", "wb").write(b"II*\0" + struct.pack("<I", 8) + ifd + strip)
g4.close()
PY
rm -f t-g4cut/g4.tif
expect "TIFF: not a TIFF" 1 "t-text/2.tif: cannot read as TIFF" out reconstruct t-text -o out -q
expect "TIFF: cut in half" 1 "t-cut/2.tif: " out reconstruct t-cut -o out -q
expect "TIFF: two pages" 1 "t-pages/2.tif: TIFF with several pages: give one slice a file" out reconstruct t-pages -o out -q
expect "TIFF: float samples" 1 "t-float/2.tif: TIFF samples are floating point" out reconstruct t-float -o out -q
expect "TIFF: cut CCITT G4 strip" 1 "t-g4cut/2.tif: corrupt TIFF: Premature EOF" out reconstruct t-g4cut -o out -q

# ---- resource limits ----------------------------------------------------------------------------
# A valid signature and IHDR of 200000 x 200000 pixels (CRC right) and nothing else:
# refused from the header, at once, with the limit message.
t0=$(date +%s)
expect "200000x200000 header" 1 "huge/1.png: image is 200000x200000 = 40000000000 pixels, more than the limit" out reconstruct huge -o out -q
t1=$(date +%s)
if [ $((t1 - t0)) -le 2 ]; then ok; else bad "200000x200000 header took $((t1 - t0)) s to refuse"; fi
# the same header followed by a short IDAT and IEND
expect "200000x200000 with IDAT" 1 "huge2/1.png: image is 200000x200000" out reconstruct huge2 -o out -q
# past --max-pixels, the working grid's cells are counted with 32-bit indices: refused
expect "grid over 2^31 cells" 1 "huge2/1.png: 200000x200000 slices need a working grid of up to 40000000000 cells, more than the 2147483647 supported" \
  out reconstruct huge2 -o out -q --max-pixels 40000000000 --align none
expect "--max-pixels" 1 "good/1.png: image is 32x32 = 1024 pixels, more than the limit of 1000" out \
  reconstruct good -o out -q --max-pixels 1000
expect "--max-voxels" 1 "more than --max-voxels 3000" out reconstruct good -o out -q --max-voxels 3000
# --per-iteration's slice count is not known ahead: held to the limit as it is written
expect "--max-voxels, per iteration" 1 "good: 2 output slices of 32x32 written; one more would pass --max-voxels 3000" out \
  reconstruct good -o out -q --per-iteration --max-voxels 3000
expect "2e13 output slices" 1 "the output would have 2e+13 slices of 32x32" out reconstruct good -o out -q --spacing 1e10 --dz 1e-3
# NIfTI-1 sizes are 16-bit: refused before the run, not after it
expect "--format nii, slices wider than 32767" 1 "wide/1.png: 32800x1 slices do not fit volume.nii:" out \
  reconstruct wide -o out -q --format nrrd,nii
expect "--format nii.gz, slices wider than 32767" 1 "wide/1.png: 32800x1 slices do not fit volume.nii.gz:" out \
  reconstruct wide -o out -q --format nii.gz
expect "--format nii, 40001 output slices" 1 "good: the output would have 40001 slices, more than the 32767 volume.nii holds" \
  out reconstruct good -o out -q --format nii --spacing 2 --dz 1e-4
expect "--format nii.gz, 40001 output slices" 1 "good: the output would have 40001 slices, more than the 32767 volume.nii.gz holds" \
  out reconstruct good -o out -q --format nii.gz --spacing 2 --dz 1e-4
expect "--format nifti" 2 "--format: 'nifti' is not one of nrrd, mha, vtk, nii, nii.gz, exr, raw" out reconstruct good -o out --format nifti
# a 20000x1 strip: an aligned gap pads each axis by up to half its side, a
# canvas of up to 40004 x 5 cells, more than 4 x --max-pixels 20000
expect "aligned canvas of a long strip" 1 "strip/1.png: 20000x1 slices need a working canvas" out \
  reconstruct strip -o out -q --max-pixels 20000 --align hull
for args in "--max-pixels 20000 --align none" "--max-pixels 100000 --align hull"; do
  # shellcheck disable=SC2086
  "$LSM" reconstruct strip -o out-strip -q $args >/dev/null 2>"$TMP/stderr"
  rc=$?
  if [ $rc -eq 0 ]; then ok; else bad "the strip with $args: exit $rc ($(cat "$TMP/stderr"))"; fi
  rm -rf out-strip
done

# ---- heights --------------------------------------------------------------------------------------
heights() { # heights DESC TEXT PHRASE [OPTION...]
  printf '%b' "$2" >h.txt
  desc=$1 phrase=$3
  shift 3
  expect "heights: $desc" 1 "h.txt: $phrase" out reconstruct good -o out -q --heights h.txt "$@"
}
heights "wrong count" '0\n1\n' "2 heights for 3 slices"
heights "too many" '0\n1\n2\n3\n' "4 heights for 3 slices"
heights "not increasing" '0\n2\n1\n' "line 3: 1 is not greater than the previous height 2"
heights "repeated" '0\n1\n1\n' "line 3: 1 is not greater than the previous height 1"
heights "nan" '0\nnan\n2\n' 'line 2: "nan" is not a number'
heights "inf" '0\n1\ninf\n' 'line 3: "inf" is not a number'
heights "junk" '0\n1 mm\n2\n' 'line 2: "1 mm" is not a number'
heights "out of range" '0\n1e999\n2e999\n' 'line 2: "1e999" is out of range'
heights "empty" '# only a comment\n\n' "no heights"
expect "heights file missing" 1 "nothere.txt: cannot open" out reconstruct good -o out -q --heights nothere.txt
heights "gap below the float range" '0\n1e-35\n1\n' "slices 1 and 2 are 1e-35 apart, outside 1e-30 to 1e+30"
heights "gap above the float range" '0\n1\n1e31\n' "slices 2 and 3 are 1e+31 apart, outside 1e-30 to 1e+30"
# output heights that double precision cannot tell apart (heights.txt repeated them)
heights "output steps below double precision" '1e10\n1.00000001e10\n1.00000002e10\n' \
  "output steps of 1e-07 (--dz) at heights near 1e+10 would repeat heights" --dz 1e-7
heights "per-iteration steps below double precision" \
  '8388609\n8388610.125\n8388610.125000002\n' "slices 2 and 3 are 1.86265e-09 apart at heights near 8.38861e+06: --per-iteration's up to --max-iter 300 steps" \
  --per-iteration --max-iter 300

# ---- usage errors: exit 2 -------------------------------------------------------------------------------
expect "--spacing 0" 2 "--spacing: 0 must be positive" out reconstruct good -o out --spacing 0
expect "--spacing -1" 2 "--spacing: -1 must be positive" out reconstruct good -o out --spacing -1
expect "--spacing nan" 2 "--spacing: 'nan' is not a number" out reconstruct good -o out --spacing nan
expect "--spacing inf" 2 "--spacing: 'inf' is not a number" out reconstruct good -o out --spacing inf
expect "--spacing junk" 2 "--spacing: '2mm' is not a number" out reconstruct good -o out --spacing 2mm
expect "--motion field --align hull" 2 "--motion field works in default mode with --align auto or none, not with --align hull" out reconstruct good -o out -q --motion field --align hull
expect "--motion field --per-iteration" 2 "not with --per-iteration" out reconstruct good -o out -q --motion field --per-iteration
expect "--motion field --method blend" 2 "not with --method blend" out reconstruct good -o out -q --motion field --method blend
expect "--spacing hexadecimal" 2 "--spacing: '0x10' is not a number" out reconstruct good -o out --spacing 0x10
expect "--spacing underflows" 2 "--spacing: '5e-324' is out of range" out reconstruct good -o out --spacing 5e-324
expect "--spacing too large for floats" 2 "--spacing: 1e308 is outside 1e-30 to 1e+30" out reconstruct good -o out --spacing 1e308
expect "--pixel-size too large for floats" 2 "--pixel-size: 1e36 is outside 1e-30 to 1e+30" out reconstruct good -o out --pixel-size 1e36
expect "--pixel-size too small for floats" 2 "--pixel-size: 1e-40 is outside 1e-30 to 1e+30" out reconstruct good -o out --pixel-size 1e-40
expect "--dz too small for floats" 2 "--dz: 1e-31 is outside 1e-30 to 1e+30" out reconstruct good -o out --dz 1e-31
expect "--pixel-size 0" 2 "--pixel-size: 0 must be positive" out reconstruct good -o out --pixel-size 0
expect "--pixel-size -0.5" 2 "--pixel-size: -0.5 must be positive" out reconstruct good -o out --pixel-size=-0.5
expect "--pixel-size with three sizes" 2 "--pixel-size: '1,2,3' is not one size S or two sizes SX,SY" out reconstruct good -o out --pixel-size 1,2,3
expect "--pixel-size SX, without SY" 2 "--pixel-size: '' is not a number" out reconstruct good -o out --pixel-size 1,
expect "--pixel-size SY too large" 2 "--pixel-size: 1e36 is outside 1e-30 to 1e+30" out reconstruct good -o out --pixel-size 1,1e36
expect "--dz 0" 2 "--dz: 0 must be positive" out reconstruct good -o out --dz 0
expect "--dz -1" 2 "--dz: -1 must be positive" out reconstruct good -o out --dz -1
expect "unknown option" 2 "unknown option '--frobnicate'" out reconstruct good -o out --frobnicate
expect "unknown option value" 2 "--method: 'magic' is not one of" out reconstruct good -o out --method magic
expect "bad --threads" 2 "--threads: 0 is out of range" out reconstruct good -o out --threads 0
expect "bad --max-pixels" 2 "--max-pixels: '1.5' is not a whole number" out reconstruct good -o out --max-pixels 1.5
expect "bad --max-voxels" 2 "--max-voxels: -3 must be positive" out reconstruct good -o out --max-voxels -3
expect "--max-voxels past 9e15" 2 "--max-voxels: 1e16 is more than 9e15" out reconstruct good -o out --max-voxels 1e16
# integers are digits with an optional '-': no blanks, no '+' (as the number options)
expect "--threads with a blank" 2 "--threads: ' 4' is not an integer" out reconstruct good -o out --threads " 4"
expect "--threads with a plus" 2 "--threads: '+4' is not an integer" out reconstruct good -o out --threads +4
expect "--threads past long" 2 "--threads: 99999999999999999999 is out of range [1, 4096]" out \
  reconstruct good -o out --threads 99999999999999999999
expect "--seed -1" 2 "--seed: '-1' is not a whole number" out reconstruct good -o out --method pls --seed -1
expect "--seed 2^64" 2 "--seed: 18446744073709551616 is out of range" out \
  reconstruct good -o out --method pls --seed 18446744073709551616
expect "flag with a value" 2 "--invert takes no value" out reconstruct good -o out --invert=yes
expect "option without its value" 2 "-o needs a value" - reconstruct good -o
expect "missing -o" 2 "missing -o OUT_DIR" - reconstruct good
expect "unknown command" 2 "unknown command 'rebuild'" - rebuild good -o out
expect "help on no command" 2 "help: no command 'bogus'" - help bogus
expect "--help on no command" 2 "--help: no command 'bogus'" - --help bogus
expect "help with two commands" 2 "help takes one command at most, not 'score'" - help reconstruct score
expect "--version with an argument" 2 "--version takes no arguments" - --version reconstruct
expect "devices with an argument" 2 "devices takes no arguments" - devices 0
expect "empty -o" 2 "-o: the output folder name is empty" - reconstruct good -o ""
# filled discs given as outlines: run, but a note says they look filled
"$LSM" reconstruct good -o out-outline --input outline --no-preview >/dev/null 2>"$TMP/stderr"
if [ $? -eq 0 ] && grep -q "note: good: --input outline, but 1.png looks filled" "$TMP/stderr"; then
  ok
else
  bad "filled slices as outlines: no note ($(cat "$TMP/stderr"))"
fi

# names numbered past 2^53: increasing, but one height in double precision
expect "--heights-from-names: numbers that round together" 1 \
  "big18/123456789012345679.png: --heights-from-names: its number 123456789012345679 gives the same height as 123456789012345678.png's" \
  out reconstruct big18 -o out --heights-from-names -q

# --spacing beside --heights places nothing: a note says so
printf '0\n2\n5\n' >good-z.txt
"$LSM" reconstruct good -o out-z --heights good-z.txt --spacing 3 --no-preview >/dev/null 2>"$TMP/stderr"
if [ $? -eq 0 ] && grep -q "note: --spacing has no effect with --heights" "$TMP/stderr"; then ok; else
  bad "--heights with --spacing: no note ($(cat "$TMP/stderr"))"
fi

# a 0/1 mask among 0/255 ones reads as blank: a note says it is not black
"$LSM" reconstruct dim -o out-dim --no-preview >/dev/null 2>"$TMP/stderr"
if [ $? -eq 0 ] && grep -q "note: dim: 2.png read as blank (the object absent), yet .* non-zero" "$TMP/stderr"; then
  ok
else
  bad "a 0/1 slice among 0/255 ones: no note ($(cat "$TMP/stderr"))"
fi

# ---- score ----------------------------------------------------------------------------------------------
expect "score: no truth slices" 1 "empty: 0 slice images: --stride 2 needs at least 3" - score empty good --stride 2
expect "score: nothing held out" 1 "good: 3 slice images: --stride 3 needs at least 4" - score good good --stride 3
expect "score: missing result" 1 "nothing: no such folder" - score good nothing --stride 2
expect "score: missing result, no --stride" 1 "nothing: no such folder" - score good nothing
expect "score: a file as the result" 1 "good/1.png: not a folder" - score good good/1.png
expect "score: a result without slices/ (--no-slices)" 1 "empty/slices: no such folder: score reads the result's slices (a reconstruct run with --no-slices has none)" - score good empty --stride 2
expect "score: bad --stride" 2 "--stride: 1 is out of range" - score good ref --stride 1
# a result scored with another stride than it was made with, or against another stack
mkdir -p tall2 tall4 && cp tall/1.png tall/3.png tall/5.png tall/7.png tall/9.png tall2/ &&
  cp tall/1.png tall/5.png tall/9.png tall4/
"$LSM" reconstruct tall2 -o r2 --spacing 2 -q --no-preview >/dev/null 2>"$TMP/stderr" &&
  "$LSM" reconstruct tall4 -o r4 --spacing 4 -q --no-preview >/dev/null 2>>"$TMP/stderr" &&
  "$LSM" score tall r2 --stride 2 >/dev/null 2>>"$TMP/stderr" &&
  "$LSM" score tall r4 --stride 4 >/dev/null 2>>"$TMP/stderr"
if [ $? -eq 0 ]; then ok; else bad "score of the right strides: $(cat "$TMP/stderr")"; fi
expect "score: stride 4 on a stride-2 result" 1 \
  "r2: was made from 5 slices (run.json), but --stride 4 keeps 3 of the 9 truth slices" - score tall r2 --stride 4
expect "score: stride 2 on a stride-4 result" 1 \
  "r4: was made from 3 slices (run.json), but --stride 2 keeps 5 of the 9 truth slices" - score tall r4 --stride 2
# a result made with --invert: its truth is dark inside too, read so (run.json's options.invert)
"$LSM" reconstruct tall4 -o r4-inv --spacing 4 --invert -q --no-preview >/dev/null 2>"$TMP/stderr" &&
  "$LSM" score tall r4-inv --stride 4 >"$TMP/stdout" 2>>"$TMP/stderr" &&
  "$LSM" score tall r4-inv >>"$TMP/stdout" 2>>"$TMP/stderr"
if [ $? -eq 0 ] && [ "$(grep -c '"held_out": 6' "$TMP/stdout")" -eq 2 ]; then ok; else
  bad "score of an --invert result: $(cat "$TMP/stderr")"
fi
cp -r r4 r4-bare && rm r4-bare/run.json # without run.json the inputs still tell
expect "score: stride 2 on a stride-4 result without run.json" 1 \
  "r4-bare/slices/00003.png: differs from the truth slice tall/3.png, which --stride 2 makes an input" - \
  score tall r4-bare --stride 2
cp -r r4 r4-damaged && printf '{' >r4-damaged/run.json # a run.json cut short: damaged
expect "score: a run.json that is not JSON" 1 \
  "r4-damaged/run.json: not valid JSON (at byte 1): the result is damaged" - \
  score tall r4-damaged --stride 4
cp -r r4 r4-uncounted && printf '{"input": {"folder": "tall4"}, "slices": 3}\n' >r4-uncounted/run.json
expect "score: a run.json without the input count" 1 \
  "r4-uncounted/run.json: does not say how many input slices the result was made from" - \
  score tall r4-uncounted --stride 4
# run.json's counts are checked against the truth before they size anything: an
# input count of 10^12 is refused at once (it once allocated 8 TB), and so are
# more input heights than truth slices
cp -r r4 r4-huge && sed 's/"slices": 3,/"slices": 1000000000000,/' r4/run.json >r4-huge/run.json
expect "score: run.json's input count far above the truth's" 1 \
  "r4-huge: was made from 1000000000000 slices (run.json), more than the 9 truth slices" - \
  score tall r4-huge --stride 2
cp -r r4 r4-heights && /usr/bin/python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
d["input"]["heights"] = [float(k) for k in range(12)]
json.dump(d, open(sys.argv[1], "w"))' r4-heights/run.json
expect "score: more input heights than truth slices" 1 \
  "r4-heights/run.json: gives 12 input heights, more than the 9 truth slices: the result was not made from slices of tall" - score tall r4-heights
# run.json is read as JSON: saved again by another tool (indented, members
# reordered, the input count last) it still tells the stride
cp -r r4 r4-resaved && /usr/bin/python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
d["input"]["slices"] = d["input"].pop("slices")
json.dump(dict(reversed(list(d.items()))), open(sys.argv[1], "w"), indent=2)' r4-resaved/run.json
expect "score: a re-saved run.json still tells a stride-4 result from stride 2" 1 \
  "r4-resaved: was made from 3 slices (run.json), but --stride 2 keeps 5 of the 9 truth slices" - \
  score tall r4-resaved --stride 2
"$LSM" score tall r4-resaved --stride 4 >/dev/null 2>"$TMP/stderr"
if [ $? -eq 0 ]; then ok; else bad "score of a re-saved run.json: $(cat "$TMP/stderr")"; fi
expect "score: stride 3 on a stride-2 result" 1 \
  "r2/slices: 9 slices, but slices 1, 4, 7, ... of the 9 truth slices, reconstructed with --spacing 3" - \
  score tall r2 --stride 3
expect "score: another size" 1 "r2/slices/00001.png: slice is 32x32 but the truth slice tall40/1.png is 40x40" - \
  score tall40 r2 --stride 2
# truth slices past the last kept one are not scored, and a note says so
mkdir -p tall3 && cp tall/1.png tall/4.png tall/7.png tall3/
"$LSM" reconstruct tall3 -o r3 --spacing 3 -q --no-preview >/dev/null 2>"$TMP/stderr" &&
  "$LSM" score tall r3 --stride 3 >"$TMP/stdout" 2>"$TMP/stderr"
rc=$?
if [ $rc -eq 0 ] && grep -q '"held_out": 4,' "$TMP/stdout" &&
  grep -q -F "lsmorph: note: truth slices 8 to 9 lie past the last kept slice (7) and are not scored" "$TMP/stderr"; then
  ok
else
  bad "score past the last kept slice: exit $rc: $(cat "$TMP/stdout" "$TMP/stderr")"
fi
# without --stride, run.json's input heights say which slices were the inputs,
# evenly or not, from slice 1 or from --first
"$LSM" score tall r4 >"$TMP/stdout" 2>"$TMP/stderr" && "$LSM" score tall r4 --stride 4 >"$TMP/stdout4" 2>>"$TMP/stderr"
rc=$?
if [ $rc -eq 0 ] && grep -q '"held_out": 6,' "$TMP/stdout" && cmp -s "$TMP/stdout" "$TMP/stdout4"; then
  ok
else
  bad "score of a stride-4 result from its run.json: exit $rc: $(cat "$TMP/stdout" "$TMP/stdout4" "$TMP/stderr")"
fi
mkdir -p tall-odd tall-even && cp tall/1.png tall/2.png tall/6.png tall/9.png tall-odd/ &&
  cp tall/2.png tall/4.png tall/6.png tall/8.png tall-even/
"$LSM" reconstruct tall-odd -o r-odd --heights-from-names -q --no-preview >/dev/null 2>"$TMP/stderr" &&
  "$LSM" score tall r-odd >"$TMP/stdout" 2>>"$TMP/stderr"
rc=$?
if [ $rc -eq 0 ] && grep -q '"held_out": 5,' "$TMP/stdout" && ! grep -q "note" "$TMP/stderr"; then
  ok
else
  bad "score of uneven kept slices 1, 2, 6, 9: exit $rc: $(cat "$TMP/stdout" "$TMP/stderr")"
fi
"$LSM" reconstruct tall-even -o r-even --heights-from-names -q --no-preview >/dev/null 2>"$TMP/stderr" &&
  "$LSM" score tall r-even --first 2 >"$TMP/stdout" 2>>"$TMP/stderr" &&
  "$LSM" score tall r-even --first 2 --stride 2 >"$TMP/stdout2" 2>>"$TMP/stderr"
rc=$?
if [ $rc -eq 0 ] && grep -q '"held_out": 3,' "$TMP/stdout" && cmp -s "$TMP/stdout" "$TMP/stdout2" &&
  [ "$(grep -c -F "lsmorph: note: truth slice 1 lies before the first kept slice (2) and is not scored" "$TMP/stderr")" -eq 2 ] &&
  [ "$(grep -c -F "lsmorph: note: truth slice 9 lies past the last kept slice (8) and is not scored" "$TMP/stderr")" -eq 2 ]; then
  ok
else
  bad "score of slices 2, 4, 6, 8 with --first 2: exit $rc: $(cat "$TMP/stdout" "$TMP/stdout2" "$TMP/stderr")"
fi
# without --first, the inputs' names (run.json's input.files) say where they lie
"$LSM" score tall r-even >"$TMP/stdout2" 2>"$TMP/stderr" &&
  "$LSM" score tall r-even --stride 2 >"$TMP/stdout3" 2>>"$TMP/stderr"
rc=$?
if [ $rc -eq 0 ] && cmp -s "$TMP/stdout" "$TMP/stdout2" && cmp -s "$TMP/stdout" "$TMP/stdout3" &&
  [ "$(grep -c -F "lsmorph: note: the inputs are named as truth slices 2, 4, 6, ... of tall (run.json's input.files), so the first input is truth slice 2 (--first 1 counts from the first truth slice instead)" "$TMP/stderr")" -eq 2 ]; then
  ok
else
  bad "score of slices 2, 4, 6, 8 kept under their names, no --first: exit $rc: $(cat "$TMP/stdout2" "$TMP/stdout3" "$TMP/stderr")"
fi
# the same truth kept as TIFF (tall's PNGs as .tif): the names match but for the extension
mkdir -p tall-tif && /usr/bin/python3 -c 'import glob, os, sys
from PIL import Image
for f in glob.glob("tall/*.png"): Image.open(f).save("tall-tif/" + os.path.basename(f)[:-4] + ".tif")'
"$LSM" score tall-tif r-even >"$TMP/stdout4" 2>"$TMP/stderr"
rc=$?
if [ $rc -eq 0 ] && cmp -s "$TMP/stdout" "$TMP/stdout4" &&
  grep -q -F "lsmorph: note: the inputs are named as truth slices 2, 4, 6, ... of tall-tif" "$TMP/stderr"; then
  ok
else
  bad "score of PNG inputs against a TIFF truth, no --first: exit $rc: $(cat "$TMP/stdout4" "$TMP/stderr")"
fi
expect "score: an offset result taken from slice 1" 1 \
  "r-even/slices/00001.png: differs from the truth slice tall/1.png, which run.json's input heights make an input, the first input taken as truth slice 1 (--first N if it is slice N)" - \
  score tall r-even --first 1
expect "score: an offset result with --stride from slice 1" 1 \
  "r-even/slices: 7 slices, but slices 1, 3, 5, ... of the 9 truth slices, reconstructed with --spacing 2 and the default --dz, give 9" - \
  score tall r-even --stride 2 --first 1
# renamed inputs (tall's 2, 4, 6, 8 as 1.png to 4.png): the names say nothing, the first input
# is taken as truth slice 1, and its slice does not come back
mkdir -p tall-renamed && cp tall/2.png tall-renamed/1.png && cp tall/4.png tall-renamed/2.png &&
  cp tall/6.png tall-renamed/3.png && cp tall/8.png tall-renamed/4.png &&
  "$LSM" reconstruct tall-renamed -o r-renamed --spacing 2 -q --no-preview >/dev/null 2>&1 || bad "reconstruct tall-renamed"
expect "score: renamed inputs" 1 \
  "r-renamed/slices/00001.png: differs from the truth slice tall/1.png, which run.json's input heights make an input, the first input taken as truth slice 1 (--first N if it is slice N)" - \
  score tall r-renamed
expect "score: an offset result from the wrong --first" 1 \
  "r-even/slices/00001.png: differs from the truth slice tall/3.png, which run.json's input heights make an input, the first input taken as truth slice 3" - \
  score tall r-even --first 3
expect "score: --stride from a late --first" 1 "tall: 9 slice images: --stride 2 from slice 8 needs at least 10" - \
  score tall r-even --stride 2 --first 8
expect "score: bad --first" 2 "--first: 0 is out of range" - score tall r4 --first 0
expect "score: no --stride and no run.json" 2 \
  "r4-bare: has no run.json to say which slices were its inputs: give --stride K" - score tall r4-bare
expect "score: the folders swapped" 2 \
  "tall: has no run.json to say which slices were its inputs: give --stride K (or swap the folders: the truth comes first, then the result)" - \
  score r-even tall
expect "score: no --stride and a run.json without heights" 1 \
  "r4-uncounted/run.json: does not give the input heights (input.heights): give --stride K" - score tall r4-uncounted
cp -r r4 r4-half && /usr/bin/python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
d["input"]["heights"][1] += 0.5
json.dump(d, open(sys.argv[1], "w"))' r4-half/run.json
expect "score: input heights not whole output steps apart" 1 \
  "r4-half/run.json: input slice 2 lies 4.5 output steps (options.dz 1) above the first: its inputs are not whole steps apart" - \
  score tall r4-half
"$LSM" reconstruct tall4 -o r4-fine --spacing 4 --dz 0.5 -q --no-preview >/dev/null 2>"$TMP/stderr" || bad "reconstruct --dz 0.5: $(cat "$TMP/stderr")"
expect "score: an output step finer than the truth's" 1 \
  "r4-fine: its last input lies at truth slice 17 (run.json's heights and dz, the first at slice 1), but tall has 9 slices (score needs --dz equal to the truth's slice spacing)" - \
  score tall r4-fine
"$LSM" reconstruct tall -o r-all -q --no-preview >/dev/null 2>"$TMP/stderr" || bad "reconstruct tall: $(cat "$TMP/stderr")"
expect "score: every truth slice an input" 1 "r-all: its inputs are truth slices 1 to 9, every one: none is held out to score" - \
  score tall r-all

# ---- output path ------------------------------------------------------------------------------------------
expect "OUT under a regular file" 1 "afile/out: cannot create a folder next to it: Not a directory" \
  afile/out reconstruct good -o afile/out -q
sum=$(cksum <afile)
expect "OUT is a regular file" 1 "afile: exists and is not a folder" - reconstruct good -o afile -q
if [ "$(cksum <afile)" = "$sum" ]; then ok; else bad "OUT as a regular file was changed"; fi
if [ "$(id -u)" -ne 0 ]; then
  mkdir locked && chmod 555 locked
  expect "OUT not writable" 1 "locked/out: cannot create a folder next to it: Permission denied" \
    locked/out reconstruct good -o locked/out -q
  chmod 755 locked
else # root may write anywhere; /proc takes no new folders even from root
  expect "OUT not writable" 1 "/proc/lsmorph-out: cannot create a folder next to it" \
    /proc/lsmorph-out reconstruct good -o /proc/lsmorph-out -q
fi
sum=$(fingerprint good)
expect "OUT is the input folder" 1 "good: is or contains the input folder" - reconstruct good -o good -q
mkdir -p holder && cp -r good holder/in
expect "OUT contains the input folder" 1 "holder: is or contains the input folder holder/in" - \
  reconstruct holder/in -o holder -q
if [ "$(fingerprint good)" = "$sum" ]; then ok; else bad "the input folder was changed"; fi
# a folder that is not an earlier result is never replaced: nor one holding the heights file
mkdir -p mine && echo precious >mine/notes.txt && printf '0\n1\n2\n' >mine/z.txt
sum=$(fingerprint mine)
expect "OUT is a foreign folder" 1 "mine: exists, is not empty and is not an earlier lsmorph result" - \
  reconstruct good -o mine -q
expect "OUT contains the heights file" 1 "mine: contains the heights file mine/z.txt" - \
  reconstruct good -o mine --heights mine/z.txt -q
if [ "$(fingerprint mine)" = "$sum" ]; then ok; else bad "a foreign OUT folder was changed"; fi
mkdir -p empty-out
"$LSM" reconstruct good -o empty-out -q --no-preview >/dev/null 2>"$TMP/stderr" &&
  "$LSM" reconstruct good -o empty-out -q --no-preview >/dev/null 2>>"$TMP/stderr"
if [ $? -eq 0 ] && [ -f empty-out/run.json ]; then ok; else bad "an empty OUT, then an earlier result: $(cat "$TMP/stderr")"; fi

# ---- numerical blow-up: named with the pair and the iteration ------------------------------------------------
expect "CFL blow-up" 1 "good/1.png -> 2.png (gap 1 of 2): iteration" out \
  reconstruct good -o out -q --per-iteration --cfl 50
if grep -q -F "is no longer finite" "$TMP/stderr"; then ok; else bad "CFL blow-up: $(cat "$TMP/stderr")"; fi
# gaps side by side (the default) or one by one: the gap that failed is named, not the one before
for threads in 1 3; do
  expect "CFL blow-up in the last gap, --threads $threads" 1 "late/4.png -> 5.png (gap 4 of 4): iteration" out \
    reconstruct late -o out -q --spacing 40 --cfl 1000 --threads $threads
done

# ---- every colour type and bit depth still works; all-empty slices too ---------------------------------------
"$LSM" reconstruct good -o ref -q >/dev/null 2>"$TMP/stderr" || bad "reference run: $(cat "$TMP/stderr")"
ref=$(inside ref/volume.nrrd)
if [ "$ref" -gt 0 ]; then ok; else bad "reference run has no inside cells"; fi
for kind in $KINDS; do
  "$LSM" reconstruct "k-$kind" -o "out-$kind" -q --no-preview >/dev/null 2>"$TMP/stderr"
  rc=$?
  if [ $rc -eq 0 ]; then
    n=$(inside "out-$kind/volume.nrrd")
    if [ "$n" -eq "$ref" ]; then ok; else bad "$kind slices: $n inside cells, 8-bit gray gives $ref"; fi
  else
    bad "$kind slices: exit $rc ($(cat "$TMP/stderr"))"
  fi
done
"$LSM" reconstruct k-empty -o out-empty -q >/dev/null 2>"$TMP/stderr"
rc=$?
if [ $rc -eq 0 ] && [ "$(inside out-empty/volume.nrrd)" -eq 0 ] &&
  [ "$(wc -l <out-empty/heights.txt | tr -d ' ')" -eq 3 ]; then
  ok
else
  bad "all-empty slices: exit $rc ($(cat "$TMP/stderr"))"
fi
# score prints strict JSON: undefined scores (no boundary anywhere, an empty truth) are null, not nan;
# a held-out slice empty on both sides has no boundary: hd95 and mean_surface leave it out
mkdir -p e13 && cp k-empty/1.png k-empty/3.png e13/
"$LSM" reconstruct e13 -o out-e13 --spacing 2 -q --no-preview >/dev/null 2>"$TMP/stderr" &&
  "$LSM" score k-empty out-e13 --stride 2 >"$TMP/stdout" 2>>"$TMP/stderr"
rc=$?
if [ $rc -eq 0 ] && "$PY" -c 'import json, sys
def reject(c): raise ValueError(c)
j = json.load(open(sys.argv[1]), parse_constant=reject)
sys.exit(not (j["held_out"] == 1 and j["hd95_pooled"] is None and j["volume_error"] is None and j["dice"] == 1
              and j["hd95"] is None and j["mean_surface"] is None))' \
  "$TMP/stdout"; then
  ok
else
  bad "score of empty slices: exit $rc, not strict JSON with nulls: $(cat "$TMP/stdout" "$TMP/stderr")"
fi

# ---- closed standard streams, and standard output that cannot be written -----------------------------------
# with stderr closed, the first file opened would take descriptor 2 and the progress lines would land in it
"$LSM" reconstruct good -o fd-ref --no-preview >/dev/null 2>&1 &&
  "$LSM" reconstruct good -o fd-closed --no-preview >/dev/null 2>&- </dev/null
rc=$?
if [ $rc -eq 0 ] && cmp -s fd-ref/volume.nrrd fd-closed/volume.nrrd; then ok; else
  bad "stderr closed: exit $rc, or volume.nrrd differs from a run with stderr open"
fi
if [ -w /dev/full ]; then
  for args in "--help" "--version" "help score" "devices"; do
    # shellcheck disable=SC2086 # the words are the arguments
    "$LSM" $args >/dev/full 2>"$TMP/stderr"
    rc=$?
    if [ $rc -eq 1 ] && grep -q "^lsmorph: error: standard output: write failed" "$TMP/stderr"; then ok; else
      # devices without OpenCL fails before writing anything
      if [ "$args" = devices ] && grep -q "OpenCL" "$TMP/stderr"; then ok; else
        bad "lsmorph $args >/dev/full: exit $rc, $(cat "$TMP/stderr")"
      fi
    fi
  done
fi
expect "empty --heights name" 2 "--heights: the file name is empty" out reconstruct good -o out --heights ""
expect "empty TRUTH_DIR" 2 "score: TRUTH_DIR is empty" - score "" ref --stride 2
expect "empty OUT_DIR of score" 2 "score: OUT_DIR is empty" - score good "" --stride 2

# ---- write errors: a file-size limit makes write() fail with EFBIG ----------------------------------------------
"$PY" "$TESTS/make_stack.py" med 6 128 || bad "make_stack.py med"
"$LSM" reconstruct med -o prev -q --no-preview >/dev/null 2>"$TMP/stderr" || bad "med run: $(cat "$TMP/stderr")"
sum=$(fingerprint prev)
(
  trap '' XFSZ # without this the kernel's SIGXFSZ would kill lsmorph; ignored, write() fails
  ulimit -f 40 # 20 or 40 KB: far less than one 128x128 float slice set
  "$LSM" reconstruct med -o prev -q >"$TMP/stdout" 2>"$TMP/stderr"
)
rc=$?
if [ $rc -eq 1 ]; then ok; else bad "file-size limit: exit $rc, expected 1 ($(cat "$TMP/stderr"))"; fi
if grep -q "^lsmorph: error: prev/.*File too large" "$TMP/stderr"; then ok; else bad "file-size limit: message $(cat "$TMP/stderr")"; fi
if [ "$(fingerprint prev)" = "$sum" ]; then ok; else bad "file-size limit: the earlier OUT was changed"; fi
if leftovers; then bad "file-size limit: a temporary folder was left"; else ok; fi
(
  trap '' XFSZ
  ulimit -f 40
  "$LSM" reconstruct med -o fresh -q >"$TMP/stdout" 2>"$TMP/stderr"
)
rc=$?
if [ $rc -eq 1 ] && [ ! -e fresh ] && ! leftovers; then ok; else bad "file-size limit, new OUT: exit $rc, fresh exists: $([ -e fresh ] && echo yes)"; fi
# the same without ignoring SIGXFSZ first: its default action (exit 153) would
# leave the temporary folder; lsmorph ignores it and fails the write instead
(
  ulimit -f 40
  "$LSM" reconstruct med -o fresh2 -q >"$TMP/stdout" 2>"$TMP/stderr"
)
rc=$?
if [ $rc -eq 1 ] && [ ! -e fresh2 ] && ! leftovers; then ok; else bad "file-size limit, SIGXFSZ not ignored: exit $rc, fresh2 exists: $([ -e fresh2 ] && echo yes), left: $(ls -d ./*.tmp-* 2>/dev/null)"; fi

# ---- disk full: ENOSPC on a 64 KB tmpfs (only where root may mount one) ------------------------------------
# the uncompressed volume and the slice PNGs are refused before any work (tests/test_limits.sh);
# a compressed volume's size is not known ahead: its writes meet the full disk
if [ "$(id -u)" -eq 0 ] && mkdir full && mount -t tmpfs -o size=64k tmpfs full 2>/dev/null; then
  FULL="$TMP/full"
  expect "disk full" 1 "full/out/" full/out reconstruct med -o full/out -q --format nii.gz --no-slices
  if grep -q -F "No space left on device" "$TMP/stderr"; then ok; else bad "disk full: $(cat "$TMP/stderr")"; fi
  if [ -z "$(ls -A full)" ]; then ok; else bad "disk full: left $(ls -A full)"; fi
  umount full && FULL=""
else
  echo "errors: note: disk-full test skipped (needs root and a tmpfs mount)"
fi

# ---- interruption: SIGINT / SIGTERM while slices are being written ---------------------------------------------
# 40 slices of 512x512 at spacing 3, one thread, RK3 with reinitialisation every
# other step: about 15 s for the whole run (far longer with sanitizers), so it is
# surely still running when the signal comes; the previous result
# (a complete run of 3 slices) must survive, and no temporary folder may remain.
"$PY" "$TESTS/make_stack.py" long 40 512 || bad "make_stack.py long"
interrupt() { # interrupt SIGNAL EXPECTED_RC
  rm -rf "$TMP"/long-out.tmp-*
  # A shell without job control starts background commands with SIGINT
  # ignored (and lsmorph keeps an ignored SIGINT ignored): restore the default.
  "$PY" -c 'import os, signal, sys
signal.signal(signal.SIGINT, signal.SIG_DFL)
os.execv(sys.argv[1], sys.argv[1:])' "$LSM" reconstruct long -o long-out -q --spacing 3 --no-preview \
    --threads 1 --time rk3 --reinit-every 2 \
    >/dev/null 2>"$TMP/stderr-$1" &
  pid=$!
  i=0
  started=0
  while [ $i -lt 1200 ]; do # up to 60 s (sanitizer builds are slow)
    for f in "$TMP"/long-out.tmp-*/slices/*.png; do
      [ -e "$f" ] && started=1
      break
    done
    [ $started -eq 1 ] && break
    kill -0 $pid 2>/dev/null || break
    sleep 0.05
    i=$((i + 1))
  done
  if [ $started -eq 1 ]; then ok; else bad "$1: the run never started writing slices"; fi
  kill -s "$1" $pid 2>/dev/null
  t0=$(date +%s)
  wait $pid 2>/dev/null
  rc=$?
  t1=$(date +%s)
  if [ $rc -eq "$2" ]; then ok; else bad "$1: exit $rc, expected $2 ($(cat "$TMP/stderr-$1"))"; fi
  if grep -q -F "lsmorph: error: long-out: interrupted by SIG$1" "$TMP/stderr-$1"; then ok; else bad "$1: message $(cat "$TMP/stderr-$1")"; fi
  if [ $((t1 - t0)) -le 20 ]; then ok; else bad "$1: took $((t1 - t0)) s to stop"; fi
  if leftovers; then bad "$1: a temporary folder was left"; else ok; fi
  if [ "$(fingerprint long-out)" = "$sum_long" ]; then ok; else bad "$1: the earlier result was changed"; fi
  if [ "$(wc -l <long-out/heights.txt | tr -d ' ')" -eq 3 ]; then ok; else bad "$1: the earlier result is not whole"; fi
}
mkdir long-small && cp long/0001.png long/0002.png long-small/
"$LSM" reconstruct long-small -o long-out -q --spacing 2 --method blend --no-preview >/dev/null 2>"$TMP/stderr" ||
  bad "long-small run: $(cat "$TMP/stderr")"
sum_long=$(fingerprint long-out)
interrupt INT 130
interrupt TERM 143

# ---- interruption while waiting for the input ----------------------------------------------
# --heights on a FIFO that nobody writes (`--heights <(cmd)` whose cmd failed): open() blocks.
# The first SIGTERM must end it (it used to be restarted, and only a second signal killed it).
rm -f heights.fifo
if mkfifo heights.fifo 2>/dev/null; then
  "$LSM" reconstruct good -o fifo-out -q --heights heights.fifo >/dev/null 2>"$TMP/stderr-fifo" &
  pid=$!
  sleep 1
  kill -s TERM $pid 2>/dev/null
  i=0
  while kill -0 $pid 2>/dev/null && [ $i -lt 100 ]; do sleep 0.05; i=$((i + 1)); done
  if kill -0 $pid 2>/dev/null; then
    bad "FIFO heights: still waiting 5 s after SIGTERM"
    kill -s KILL $pid 2>/dev/null
  else
    ok
  fi
  wait $pid 2>/dev/null
  rc=$?
  if [ $rc -eq 143 ]; then ok; else bad "FIFO heights: exit $rc, expected 143 ($(cat "$TMP/stderr-fifo"))"; fi
  if grep -q -F "lsmorph: error: fifo-out: interrupted by SIGTERM" "$TMP/stderr-fifo"; then ok; else bad "FIFO heights: message $(cat "$TMP/stderr-fifo")"; fi
  if [ -e fifo-out ]; then bad "FIFO heights: fifo-out was created"; else ok; fi
  rm -f heights.fifo
fi

# ---- interruption inside one long gap --------------------------------------------------------
# One gap of 1024x1024 (a disc into a distant ellipse, RK3, reinitialisation
# every other step, the full grid: the band takes about 1 s): about 30 s on one
# thread before its first slice, so a signal after 1 s arrives inside the morph.  The morph checks the flag before
# every step: the run must end within 5 s of the signal, not at the gap's end.
"$PY" - <<'PYEOF' || bad "long gap: cannot write its slices"
import os, struct, zlib
def png(path, inside):
    n = 1024
    raw = b"".join(b"\x00" + bytes(255 if inside(i, j) else 0 for i in range(n)) for j in range(n))
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", n, n, 8, 0, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
os.makedirs("gap", exist_ok=True)
png("gap/1.png", lambda i, j: (i - 300) ** 2 + (j - 300) ** 2 < 150 ** 2)
png("gap/2.png", lambda i, j: ((i - 700) / 300) ** 2 + ((j - 650) / 200) ** 2 < 1)
PYEOF
"$PY" -c 'import os, signal, sys
signal.signal(signal.SIGINT, signal.SIG_DFL)
os.execv(sys.argv[1], sys.argv[1:])' "$LSM" reconstruct gap -o gap-out -q --spacing 2 --no-preview \
  --threads 1 --time rk3 --reinit-every 2 --band off >/dev/null 2>"$TMP/stderr-gap" &
pid=$!
sleep 1
kill -s INT $pid 2>/dev/null
t0=$(date +%s)
wait $pid 2>/dev/null
rc=$?
t1=$(date +%s)
if [ $rc -eq 130 ]; then ok; else bad "long gap: exit $rc, expected 130 ($(cat "$TMP/stderr-gap"))"; fi
if grep -q -F "interrupted by SIGINT" "$TMP/stderr-gap"; then ok; else bad "long gap: message $(cat "$TMP/stderr-gap")"; fi
if [ $((t1 - t0)) -le 5 ]; then ok; else bad "long gap: took $((t1 - t0)) s to stop (the morph does not check the signal)"; fi
if [ -e gap-out ]; then bad "long gap: an output folder was left"; else ok; fi

# ---- a CFL step that underflowed names no cure that cannot help (a smaller --cfl) ----------------------------------------
expect "zero CFL step" 1 "the CFL time step is 0" zero-cfl-out reconstruct good -o zero-cfl-out -q \
  --pixel-size 1e20,1e-20 --per-iteration
if grep -q -F "smaller --cfl" "$TMP/stderr"; then bad "zero CFL step: suggests a smaller --cfl"; else ok; fi

# ---- a complete run replaces an earlier result as a whole ---------------------------------------------------------------
"$LSM" reconstruct good -o long-out -q --no-slices >/dev/null 2>"$TMP/stderr"
rc=$?
if [ $rc -eq 0 ] && [ ! -e long-out/slices ] && [ "$(wc -l <long-out/heights.txt | tr -d ' ')" -eq 3 ] &&
  ! leftovers; then
  ok
else
  bad "replacing an earlier result: exit $rc ($(cat "$TMP/stderr"))"
fi

finish
