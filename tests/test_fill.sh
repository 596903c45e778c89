#!/bin/sh
# lsmorph fill end to end: a multi-label volume (two touching ellipsoids, an
# oblique tube, a label nested in another, a label on one drawn slice; an
# oblique affine, voxels 0.9 x 0.8 x 2 mm) drawn on every 4th slice, filled as
# NIfTI-1 .nii.gz, NIfTI-2 .nii, NRRD raw, .seg.nrrd gzip with 3D Slicer's
# segment key/value pairs, and .nhdr with a detached data file; OUT read back
# by nibabel and VTK's vtkNrrdReader with the input's geometry; drawn slices
# exact, labels kept; --labels, --slices on the full volume, --threads, the
# other axes; then every error case.  Needs nibabel and VTK (python3-nibabel,
# python3-vtk9).
#   sh tests/test_fill.sh BUILD_DIR
# Prints "fill: N passed, N failed".
set -u
BUILD=${1:-build}
LSM="$BUILD/lsmorph"
PY=/usr/bin/python3
SUITE=fill
. "$(dirname "$0")/harness.sh"
python_suite "nibabel, numpy, vtk" "python3-nibabel, python3-numpy, python3-vtk9"

# The volumes: $TMP/truth.nii.gz (every slice) and the drawn ones in every format
"$PY" "$HERE/fill_check.py" make "$TMP" >"$TMP/make.log" 2>&1 || { bad "making the volumes: $(tail -3 "$TMP/make.log")"; finish; }

# fill IN OUT [OPTIONS]: runs lsmorph fill, checks exit 0
fill() {
  in=$1 out=$2
  shift 2
  "$LSM" fill "$TMP/$in" -o "$TMP/$out" "$@" >"$TMP/o" 2>"$TMP/e"
  rc=$?
  check "fill $in -> $out $*: exit 0 (got $rc: $(tail -c 300 "$TMP/e"))" [ $rc -eq 0 ]
}

for f in drawn.nii.gz drawn2.nii drawn.nrrd drawn.seg.nrrd drawn.nhdr; do
  out="out-$f"
  fill "$f" "$out"
  run_checks "$TMP/log" "$PY" "$HERE/fill_check.py" verify "$TMP" "$f" "$out"
done
check "the note lists the drawn slices" grep -q "taken as drawn: the 9 slices holding labels (4, 8, ..., 36 (every 4th)), and 0 and 40" "$TMP/e"
check "the note on the gaps --motion auto tried (the oblique tube moves)" grep -q "note: --motion auto tried [0-9]* gaps of the labels by leaving their drawn slices out; [0-9]* follow" "$TMP/e"
check "no temporary file left" [ -z "$(ls -A "$TMP" | grep '\.tmp-')" ]
# NIfTI in, NRRD out and back: the geometry converted
fill drawn.nii.gz cross.seg.nrrd
run_checks "$TMP/log" "$PY" "$HERE/fill_check.py" verify "$TMP" drawn.nii.gz cross.seg.nrrd

# the same result for any thread count, and for the full volume with the same slices
fill drawn.nii.gz t1.nii.gz --threads 1
fill drawn.nii.gz t3.nii.gz --threads 3
fill truth.nii.gz given.nii.gz --slices 0:40:4
run_checks "$TMP/log" "$PY" "$HERE/fill_check.py" same "$TMP" out-drawn.nii.gz t1.nii.gz t3.nii.gz given.nii.gz
# a NIfTI-1 whose vox_offset is 0: its samples read from byte 352, as nibabel reads them
fill offset0.nii offset0.nii.gz
run_checks "$TMP/log" "$PY" "$HERE/fill_check.py" same "$TMP" out-drawn.nii.gz offset0.nii.gz
# --labels 2,3: the others as drawn
fill drawn.nii.gz some.nii.gz --labels 2,3
run_checks "$TMP/log" "$PY" "$HERE/fill_check.py" labels "$TMP" drawn.nii.gz some.nii.gz out-drawn.nii.gz 2,3
# across another axis: the tube drawn every 3rd slice across i
fill drawn-i.nii.gz out-i.nii.gz --axis i
run_checks "$TMP/log" "$PY" "$HERE/fill_check.py" verify "$TMP" drawn-i.nii.gz out-i.nii.gz
# options of reconstruct, in both spellings (3D Slicer's flags take '_')
fill drawn.nii.gz field.nii.gz --motion field
run_checks "$TMP/log" "$PY" "$HERE/fill_check.py" verify "$TMP" drawn.nii.gz field.nii.gz
fill drawn.nii.gz blend.nii.gz --method blend --interp linear --max_iter 500 -q
check "-q: nothing on stderr" [ ! -s "$TMP/e" ]

# score of two label volumes: the slices from the record in OUT's header, against numpy
"$LSM" score "$TMP/truth.nii.gz" "$TMP/out-drawn.nii.gz" >"$TMP/score.json" 2>"$TMP/e"
rc=$?
check "score: exit 0 (got $rc: $(tail -c 300 "$TMP/e"))" [ $rc -eq 0 ]
run_checks "$TMP/log" "$PY" "$HERE/fill_check.py" score "$TMP" truth.nii.gz out-drawn.nii.gz score.json
"$LSM" score "$TMP/truth.nii.gz" "$TMP/truth.nii.gz" >"$TMP/o" 2>"$TMP/e"
rc=$?
check "score without a record: exit 2 (got $rc)" [ $rc -eq 2 ]
check "score without a record: asks for --slices" grep -q "give --slices LIST and --axis" "$TMP/e"
"$LSM" score "$TMP/truth.nii.gz" "$TMP/truth.nii.gz" --slices 0:40:4 --axis k >"$TMP/o" 2>"$TMP/e"
check "score of the truth against itself: Dice 1" grep -q '"mean": {"dice": 1,' "$TMP/o"
"$LSM" score "$TMP/truth.nii.gz" "$TMP/out-i.nii.gz" >"$TMP/o" 2>"$TMP/e"
rc=$?
check "score of volumes of other sizes: exit 1 (got $rc)" [ $rc -eq 1 ]
"$LSM" score "$TMP/truth-moved.nii.gz" "$TMP/out-drawn.nii.gz" >"$TMP/o" 2>"$TMP/e"
rc=$?
check "score of volumes on other grids: exit 1 (got $rc)" [ $rc -eq 1 ]
check "score of volumes on other grids: says so (said: $(head -c 300 "$TMP/e"))" grep -q "out-drawn.nii.gz: not on .*truth-moved.nii.gz's grid: the same voxel counts, but its origin" "$TMP/e"
check "score of volumes on other grids: prints no scores" [ ! -s "$TMP/o" ]
# a damaged lsmorph_fill record in OUT's header: exit 1, naming OUT
for rec in "axis=k drawn=1,99999999999999999999 labels=1" "axis=k drawn=4,400 labels=1" "axis=kk drawn=4,8"; do
  sed "s/^lsmorph_fill:=.*/lsmorph_fill:=$rec/" "$TMP/out-drawn.nrrd" >"$TMP/record.nrrd"
  "$LSM" score "$TMP/drawn.nrrd" "$TMP/record.nrrd" >"$TMP/o" 2>"$TMP/e"
  rc=$?
  check "score, record '$rec': exit 1 (got $rc)" [ $rc -eq 1 ]
  check "score, record '$rec': names OUT's record (said: $(head -c 300 "$TMP/e"))" grep -q "^lsmorph: error: $TMP/record.nrrd: its lsmorph_fill record" "$TMP/e"
done
# NRRD in, NIfTI out: the same grid, scored
"$LSM" score "$TMP/drawn.nrrd" "$TMP/out-drawn.nii.gz" >"$TMP/o" 2>"$TMP/e"
rc=$?
check "score of a NRRD against a NIfTI on its grid: exit 0 (got $rc: $(tail -c 300 "$TMP/e"))" [ $rc -eq 0 ]

# ---- errors: exit 1 (2 for usage), a message, no output, before any work -------------------
expect() { # expect RC PHRASE ARGS...
  want=$1 phrase=$2
  shift 2
  "$LSM" fill "$@" >"$TMP/o" 2>"$TMP/e"
  rc=$?
  check "fill $*: exit $want (got $rc)" [ $rc -eq "$want" ]
  check "fill $*: says '$phrase' (said: $(head -c 300 "$TMP/e"))" grep -q -F -e "$phrase" "$TMP/e"
  check "fill $*: no output" [ ! -e "$TMP/none.nii" ] && [ ! -e "$TMP/none.nrrd" ]
}
expect 1 "not a label map: voxel" "$TMP/half.nii" -o "$TMP/none.nii"
check "the file is named once" grep -q "^lsmorph: error: $TMP/half.nii: not a label map" "$TMP/e"
expect 1 "nan.nii: not a label map: voxel (30, 20, 8) holds nan" "$TMP/nan.nii" -o "$TMP/none.nii"
expect 1 "inf.nii.gz: not a label map: voxel (31, 21, 12) holds -inf" "$TMP/inf.nii.gz" -o "$TMP/none.nii"
expect 1 "offnan.nii: damaged header: vox_offset is nan" "$TMP/offnan.nii" -o "$TMP/none.nii"
expect 1 "pixnan.nii: the voxel spacing along k is nan (pixdim[3]): not a length" "$TMP/pixnan.nii" -o "$TMP/none.nii"
expect 1 "parallel.nrrd: the grid's voxel axes are parallel" "$TMP/parallel.nrrd" -o "$TMP/none.nrrd"
expect 1 "big.nii: not a label map: voxel (30, 20, 8) holds 10000000000000000, past the labels a floating-point volume holds exactly" "$TMP/big.nii" -o "$TMP/none.nii"
expect 1 "far.nii: the voxel spacing along i is 1e+29, and" "$TMP/far.nii" -o "$TMP/none.nii"
expect 1 "'byte skip' inside bzip2-encoded data is not supported" "$HERE/fuzz/corpus/labels/leak-teem-bzip2-skip.nrrd" -o "$TMP/none.nrrd"
expect 1 "export the segmentation as a labelmap" "$TMP/layers.seg.nrrd" -o "$TMP/none.nrrd"
expect 1 "only slice 20 holds labels" "$TMP/one.nii.gz" -o "$TMP/none.nii"
expect 1 "no such folder" "$TMP/drawn.nii.gz" -o "$TMP/missing/none.nii"
expect 1 "is the input file" "$TMP/drawn.nii.gz" -o "$TMP/drawn.nii.gz"
expect 1 "cannot read" "$TMP/absent.nii" -o "$TMP/none.nii"
expect 1 "is a folder" "$TMP" -o "$TMP/none.nii"
expect 1 "--labels: 9 is not in the volume" "$TMP/drawn.nii.gz" -o "$TMP/none.nii" --labels 9
expect 2 "--slices: 99 is past the last slice" "$TMP/drawn.nii.gz" -o "$TMP/none.nii" --slices 0,99
expect 2 "--dz does not apply to fill" "$TMP/drawn.nii.gz" -o "$TMP/none.nii" --dz 1
expect 2 "unknown option '--bogus'" "$TMP/drawn.nii.gz" -o "$TMP/none.nii" --bogus
# a .nii.gz whose compressed header is damaged: said so, not "too short for a NIfTI header"
"$PY" -c "import sys; b = bytearray(open(sys.argv[1], 'rb').read()); b[30:60] = bytes(x ^ 0x5a for x in b[30:60]); open(sys.argv[2], 'wb').write(b)" "$TMP/drawn.nii.gz" "$TMP/damaged.nii.gz"
expect 1 "damaged.nii.gz: cannot read: its compressed data is damaged" "$TMP/damaged.nii.gz" -o "$TMP/none.nii"
expect 2 "--method: 'x' is not one of" "$TMP/drawn.nii.gz" -o "$TMP/none.nii" --method x
expect 2 "--axis: 'q' is not one of i, j, k, auto" "$TMP/drawn.nii.gz" -o "$TMP/none.nii" --axis q
expect 2 "end it in .nii" "$TMP/drawn.nii.gz" -o "$TMP/none.png"
expect 2 "fill: missing -o OUT" "$TMP/drawn.nii.gz"
expect 2 "a NIfTI name ending in mixed case" "$TMP/drawn.nii.gz" -o "$TMP/none.Nii"
expect 2 "a .nhdr name holding '%'" "$TMP/drawn.nii.gz" -o "$TMP/none%d.nhdr"
check "no data file beside the refused .nhdr" [ ! -e "$TMP/none%d.raw.gz" ]
cp "$TMP/drawn.nii.gz" "$TMP/mixed.Nii.gz"
expect 1 "mixed.Nii.gz: cannot read a NIfTI name ending in mixed case" "$TMP/mixed.Nii.gz" -o "$TMP/none.nii"
"$LSM" fill "$TMP/drawn.nii.gz" -o "$TMP/UPPER.NII.GZ" -q --motion none >"$TMP/o" 2>"$TMP/e" &&
  "$LSM" fill "$TMP/UPPER.NII.GZ" -o "$TMP/upper.nrrd" -q --motion none >"$TMP/o" 2>"$TMP/e"
check "an upper-case .NII.GZ written and read back (said: $(head -c 300 "$TMP/e"))" [ $? -eq 0 ]
check "the missing folder was not made" [ ! -e "$TMP/missing" ]
# a .nhdr whose data file is the one OUT's header would write beside it: refused, the data kept
mkdir "$TMP/pair"
sed 's/^data file: .*/data file: b.raw.gz/' "$TMP/drawn.nhdr" >"$TMP/pair/a.nhdr"
cp "$TMP/$(sed -n 's/^data file: //p' "$TMP/drawn.nhdr")" "$TMP/pair/b.raw.gz"
sum=$(cksum <"$TMP/pair/b.raw.gz")
"$LSM" fill "$TMP/pair/a.nhdr" -o "$TMP/pair/b.nhdr" >"$TMP/o" 2>"$TMP/e"
rc=$?
check "OUT's data file is the input's: exit 1 (got $rc)" [ $rc -eq 1 ]
check "OUT's data file is the input's: says so (said: $(head -c 300 "$TMP/e"))" grep -q "b.raw.gz: is the input's data file" "$TMP/e"
check "OUT's data file is the input's: the input's data unchanged" [ "$(cksum <"$TMP/pair/b.raw.gz")" = "$sum" ]
check "OUT's data file is the input's: no header written" [ ! -e "$TMP/pair/b.nhdr" ]
# ... and OUT itself the input's data file (a data file named like a volume)
sed 's/^data file: .*/data file: c.nii/' "$TMP/drawn.nhdr" >"$TMP/pair/c.nhdr"
cp "$TMP/pair/b.raw.gz" "$TMP/pair/c.nii"
"$LSM" fill "$TMP/pair/c.nhdr" -o "$TMP/pair/c.nii" >"$TMP/o" 2>"$TMP/e"
rc=$?
check "OUT is the input's data file: exit 1 (got $rc)" [ $rc -eq 1 ]
check "OUT is the input's data file: the data unchanged" [ "$(cksum <"$TMP/pair/c.nii")" = "$sum" ]
# a .nhdr OUT whose data file's name is taken by a file no header there names: refused, kept
echo "the user's" >"$TMP/keep.raw"
"$LSM" fill "$TMP/drawn2.nii" -o "$TMP/keep.nhdr" -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "a .nhdr OUT over another NAME.raw: exit 1 (got $rc)" [ $rc -eq 1 ]
check "a .nhdr OUT over another NAME.raw: says so (said: $(head -c 300 "$TMP/e"))" grep -q "keep.raw: exists, and .*keep.nhdr does not name it" "$TMP/e"
check "a .nhdr OUT over another NAME.raw: that file kept, no header" [ "$(cat "$TMP/keep.raw")" = "the user's" ] && [ ! -e "$TMP/keep.nhdr" ]
"$LSM" fill "$TMP/drawn2.nii" -o "$TMP/again.nhdr" -q && "$LSM" fill "$TMP/drawn2.nii" -o "$TMP/again.nhdr" -q
check "a .nhdr OUT written twice (its own data file replaced): exit 0" [ $? -eq 0 ] && [ -e "$TMP/again.raw" ]
# a pipe as LABELS or as a detached header's data file: refused, not waited on (timeout: a hang fails)
mkfifo "$TMP/pipe.nii" "$TMP/pipe.raw"
# ... and as OUT: refused, not replaced by a plain file
timeout 30 "$LSM" fill "$TMP/drawn.nii.gz" -o "$TMP/pipe.nii" >"$TMP/o" 2>"$TMP/e"
rc=$?
check "fill -o a pipe: exit 1 (got $rc)" [ $rc -eq 1 ]
check "fill -o a pipe: says so (said: $(head -c 300 "$TMP/e"))" grep -q "pipe.nii: is not a regular file" "$TMP/e"
check "fill -o a pipe: the pipe is still there" [ -p "$TMP/pipe.nii" ]
printf 'NRRD0004\ntype: short\ndimension: 3\nsizes: 4 4 4\nencoding: raw\ndata file: pipe.raw\n' >"$TMP/pipe.nhdr"
printf 'NRRD0004\ntype: short\ndimension: 3\nsizes: 4 4 4\nencoding: raw\ndata file: LIST\n/dev/zero\n' >"$TMP/dev.nhdr"
printf 'NRRD0004\ntype: short\ndimension: 3\nsizes: 4 4 4\nendian: little\nencoding: raw\ndata file: -\n' >"$TMP/stdin.nhdr"
: | timeout 30 "$LSM" fill "$TMP/stdin.nhdr" -o "$TMP/none.nii" >"$TMP/o" 2>"$TMP/e"
rc=$?
check "fill a .nhdr reading standard input: exit 1 (got $rc)" [ $rc -eq 1 ]
check "fill a .nhdr reading standard input: says so (said: $(head -c 300 "$TMP/e"))" grep -q "is '-' (standard input)" "$TMP/e"
for f in pipe.nii pipe.nhdr dev.nhdr; do
  timeout 30 "$LSM" fill "$TMP/$f" -o "$TMP/none.nii" >"$TMP/o" 2>"$TMP/e"
  rc=$?
  check "fill $f: exit 1 (got $rc)" [ $rc -eq 1 ]
  check "fill $f: says it is not a regular file (said: $(head -c 300 "$TMP/e"))" grep -q "not a regular file" "$TMP/e"
done
# every slice drawn: a note, the volume copied
"$LSM" fill "$TMP/truth.nii.gz" -o "$TMP/copy.nii.gz" >"$TMP/o" 2>"$TMP/e"
rc=$?
check "every slice drawn: exit 0 (got $rc)" [ $rc -eq 0 ]
check "every slice drawn: says nothing to fill" grep -q "nothing to fill" "$TMP/e"
run_checks "$TMP/log" "$PY" "$HERE/fill_check.py" same "$TMP" truth.nii.gz copy.nii.gz

# ---- the PNG route's traps: reconstruct says where fill is the tool ---------------------------
mkdir "$TMP/png"
"$PY" -c "
import numpy as np, zlib, struct
def png(path, a):
    raw = b''.join(b'\\x00' + bytes(r) for r in a)
    chunk = lambda t, d: struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
    open(path, 'wb').write(b'\\x89PNG\\r\\n\\x1a\\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', a.shape[1], a.shape[0], 8, 0, 0, 0, 0))
                          + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))
for k in range(6):
    a = np.zeros((30, 30), np.uint8)
    if k in (0, 2, 3, 5):
        a[5:25, 5:15] = 1
        a[5:25, 15:25] = 2
    png('$TMP/png/%02d.png' % k, a)
"
"$LSM" reconstruct "$TMP/png" -o "$TMP/png-out" --no-preview >"$TMP/o" 2>"$TMP/e"
check "PNG labels 1 and 2: reconstruct says they were merged and points to fill" \
  grep -q "00.png holds 2 distinct non-zero values: labels, read here as one object (merged).*lsmorph fill" "$TMP/e"
check "blank slices between non-blank ones: reconstruct points to fill" \
  grep -q "2 blank slices (01.png, ...) lie between slices that are not.*lsmorph fill LABELS -o OUT" "$TMP/e"
finish
