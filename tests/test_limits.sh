#!/bin/sh
# Scratch and limits end to end.
#   sh tests/test_limits.sh BUILD_DIR
# - scratch: no file outside the output's temporary folder while a run works
#   (the reverse morph's slices wait in memory, counted; the mesh's scratch
#   files lie in the temporary folder beside the output, whatever TMPDIR says);
# - limits: the estimate of memory and disk before any work, refused with the
#   numbers and the folder when it does not fit (tiny --max-memory; a small
#   file system where root may mount one); the defaults a laptop survives
#   (--max-pixels 2^26, --max-voxels 2^30) and how to raise them.
# Prints "limits: N passed, N failed".
set -u
BUILD=${1:-build}
LSM="$BUILD/lsmorph"
PY=${PYTHON:-/usr/bin/python3}
SUITE=limits
. "$(dirname "$0")/harness.sh"
need "$LSM"
command -v "$PY" >/dev/null 2>&1 || PY=python3
work_in_tmp

# ---- scratch: nothing outside the output's temporary folder --------------------------------
# 40 slices of 512x512, every gap two-sided (the reverse morph's snapshots
# wait for their turn): every file the run holds open while it works lies in
# the output's temporary folder or is an input; an unlinked scratch file
# elsewhere (tmpfile() in /tmp, whatever TMPDIR said) is what issue 54 found.
"$PY" "$TESTS/make_stack.py" long 40 512 >/dev/null 2>&1 || bad "make_stack.py long"
mkdir -p scratch-here
TMPDIR="$TMP/scratch-here" "$LSM" reconstruct long -o long-out -q --spacing 3 --no-preview \
  --threads 1 --mesh >/dev/null 2>"$TMP/stderr-long" &
pid=$!
seen=0 outside="" machine=none
i=0
while [ $i -lt 400 ] && kill -0 $pid 2>/dev/null; do # up to 20 s
  for f in /proc/$pid/fd/*; do
    target=$(readlink "$f" 2>/dev/null) || continue
    case $target in
    "$TMP"/long-out.tmp-*) seen=1 machine=$(echo "$target" | sed -n 's/.*long-out\.tmp-[0-9]*\.[0-9]*\.\([0-9a-f]\{16\}\)-.*/\1/p') ;;
    *"(deleted)"*) outside="$outside $target" ;;
    esac
  done
  [ -n "$outside" ] && break
  i=$((i + 1))
  sleep 0.05
done
kill $pid 2>/dev/null
wait $pid 2>/dev/null
check "scratch: the run never opened a file in its temporary folder" [ $seen -eq 1 ]
check "scratch: a scratch file outside the output's folder:$outside" [ -z "$outside" ]
check "scratch: a file left in TMPDIR: $(ls -A scratch-here)" [ -z "$(ls -A scratch-here)" ]

# ---- the defaults a laptop survives, refused from the headers and heights ------------------------------
# two 9000 x 9000 slices (80 KB files): past --max-pixels 2^26, refused from the header (the
# default was 2^28: a 516 KB pair of 16382^2 cost 4.2 GB and 76 s)
"$PY" - <<'PYEOF' || bad "cannot write the 9000^2 slices"
import os, struct, zlib
def chunk(t, d):
    return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
n = 9000
raw = zlib.compress(b"\x00" * ((n + 1) * n), 9)
os.makedirs("wide", exist_ok=True)
for k in (1, 2):
    with open("wide/%d.png" % k, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", n, n, 8, 0, 0, 0, 0))
                + chunk(b"IDAT", raw) + chunk(b"IEND", b""))
PYEOF
# refused_fast DESC PHRASE ARG...: exit 1 with PHRASE within 20 s, nothing written
refused_fast() {
  what=$1 phrase=$2
  shift 2
  ( ulimit -f 20000; timeout 20 "$LSM" "$@" ) >"$TMP/stdout" 2>"$TMP/stderr"
  rc=$?
  check "$what: exit $rc, expected 1 ($(cat "$TMP/stderr"))" [ $rc -eq 1 ]
  check "$what: message does not say '$phrase': $(cat "$TMP/stderr")" grep -q -F -e "$phrase" "$TMP/stderr"
  check "$what: something was written: $(ls -d out* 2>/dev/null)" sh -c '! ls -d out* >/dev/null 2>&1'
}
refused_fast "9000^2 slices under the default --max-pixels" \
  "wide/1.png: image is 9000x9000 = 81000000 pixels, more than the limit of 67108864" \
  reconstruct wide -o out -q
# two lines of heights asking for 4 million slices of 64^2 (16 G voxels, 64 GiB of float32 and
# 4 million PNG files: under the old default 2^34)
"$PY" "$TESTS/make_stack.py" small 2 64 >/dev/null 2>&1 || bad "make_stack.py small"
printf '0\n4000000\n' >far.txt
refused_fast "4 million output slices under the default --max-voxels" \
  "far.txt: the output would have 4e+06 slices of 64x64 = 1.638e+10 voxels, more than --max-voxels 1073741824 (raise --dz or --max-voxels)" \
  reconstruct small -o out -q --heights far.txt
# ---- the estimate of memory and disk, before any work -----------------------------------------------------
refused_fast "memory past --max-memory" \
  "small: the run needs about" reconstruct small -o out -q --spacing 40 --max-memory 1000000
check "memory past --max-memory: the message lacks the numbers: $(cat "$TMP/stderr")" \
  grep -q -F "of memory (1 gap at a time, working on 68x68 cells and holding up to" "$TMP/stderr"
check "memory past --max-memory: the message lacks the way out: $(cat "$TMP/stderr")" \
  grep -q -F "more than --max-memory 1000000: lower --threads" "$TMP/stderr"
# the correspondence field (--motion field, and auto, the default) adds to what a gap holds;
# the blend never registers one
estimate_bytes() {
  "$LSM" reconstruct ${STACK:-small} -o out -q --spacing ${SPACING:-40} --max-memory 1000 "$@" 2>&1 |
    sed -n 's/.*needs about \([0-9.]*\) \([A-Za-z]*\) of memory.*/\1 \2/p' |
    awk '{ m = $2 == "KiB" ? 1024 : $2 == "MiB" ? 1048576 : $2 == "GiB" ? 1073741824 : 1; print $1 * m }'
}
in_place=$(estimate_bytes --motion none) with_field=$(estimate_bytes) blend_field=$(estimate_bytes --method blend)
check "the estimate: no numbers ($in_place, $with_field)" [ -n "$in_place" ] && [ -n "$with_field" ]
check "the estimate does not count the field: $with_field bytes by default, $in_place with --motion none" \
  awk "BEGIN { exit !($with_field > $in_place) }"
check "the estimate counts a field for the blend: $blend_field bytes, $in_place in place" \
  awk "BEGIN { exit !($blend_field == $in_place) }"
# a disc that jumps from one corner to the other: the aligned pair pads its canvas by the shift
# (3.4 times the cells), which the estimate before the work cannot know; with memory for the
# estimate and little more, the gap refuses before it allocates, and says what to do
"$PY" - <<'PYEOF' || bad "corners: writing the stack"
import os, struct, zlib
def chunk(t, d):
    return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
n, r = 512, 30
os.makedirs("corners", exist_ok=True)
for k, c in ((1, 40), (2, n - 40)):
    rows = b"".join(b"\x00" + bytes(255 if (x - c) ** 2 + (y - c) ** 2 <= r * r else 0 for x in range(n))
                    for y in range(n))
    with open("corners/%d.png" % k, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", n, n, 8, 0, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(rows, 6)) + chunk(b"IEND", b""))
PYEOF
corners=$(STACK=corners SPACING=4 estimate_bytes --no-preview)
just_above=$(awk "BEGIN { printf \"%d\", $corners * 1.2 }")
refused_fast "an aligned canvas past --max-memory" "--align none works in place" \
  reconstruct corners -o out -q --spacing 4 --no-preview --max-memory "$just_above"
"$LSM" reconstruct corners -o out -q --spacing 4 --no-preview --max-memory "$just_above" \
  --align none 2>"$TMP/stderr"
check "the same in place: exit $? ($(cat "$TMP/stderr"))" [ -f out/volume.nrrd ]
rm -rf out
mkdir -p full
if unshare -rm sh -c 'mount -t tmpfs -o size=256k tmpfs full' 2>/dev/null; then
  unshare -rm sh -c "mount -t tmpfs -o size=256k tmpfs full && '$LSM' reconstruct long -o full/out --spacing 20" \
    >"$TMP/stdout" 2>"$TMP/stderr"
  rc=$?
  check "a full disk: exit $rc, expected 1 ($(cat "$TMP/stderr"))" [ $rc -eq 1 ]
  check "a full disk: not refused up front with the numbers and the folder: $(cat "$TMP/stderr")" \
    grep -q -F "lsmorph: error: full/out: the result needs at least 784 MiB on the file system of full (781 slices: 781 MiB of nrrd and slice PNGs), which has 256 KiB free" "$TMP/stderr"
  check "a full disk: the work began before the refusal" sh -c "! grep -q 'slices of 512x512' '$TMP/stderr'"
else
  echo "limits: note: disk test skipped (no user namespace with mounts: unshare -rm failed)"
fi

# ---- fill: its OUT file gets the same guarantees ---------------------------------------------------------
if "$PY" -c "import nibabel, numpy" 2>/dev/null && mkdir -p labels &&
  "$PY" "$TESTS/fill_check.py" make "$TMP/labels" >/dev/null 2>&1; then
  IN=labels/drawn.nii.gz
  "$LSM" fill $IN -o first.nii -q 2>"$TMP/stderr" || bad "fill: a first result: $(cat "$TMP/stderr")"
  ln -s first.nii to-first.nii
  "$LSM" fill $IN -o to-first.nii --threads 1 >"$TMP/stdout" 2>"$TMP/stderr"
  rc=$?
  check "fill into a link to a file: exit $rc ($(cat "$TMP/stderr"))" [ $rc -eq 0 ]
  check "fill into a link to a file: the link was replaced by a file" [ -L to-first.nii ]
  check "fill into a link to a file: no note says it is followed: $(cat "$TMP/stderr")" \
    grep -q -F "lsmorph: note: to-first.nii is a symbolic link: the result replaces the file it names" "$TMP/stderr"
  ln -s nowhere.nii dangling.nii
  refused_fast "fill into a link to nothing" "dangling.nii: is a symbolic link to nothing (nowhere.nii)" \
    fill $IN -o dangling.nii -q
  check "fill into a link to nothing: the link was changed" [ "$(readlink dangling.nii)" = nowhere.nii ]
  refused_fast "fill past --max-memory" "filling needs about" fill $IN -o out.nii -q --max-memory 100000
  # temporary files beside OUT: of a run that ended (a pid gone, on this kernel: the machine
  # part of the tag the scratch test saw), of another machine, of an older lsmorph
  sh -c 'exit 0' &
  gone=$!
  wait $gone
  cp first.nii second.nii
  touch ".second.nii.tmp-$gone.1.$machine-Ended1" ".second.nii.tmp-$gone.1.0123456789abcdef-Other1" \
    .second.nii.tmp-Older1
  "$LSM" fill $IN -o second.nii >"$TMP/stdout" 2>"$TMP/stderr"
  check "fill: the temporary file of a run that ended was not removed ($machine)" \
    [ ! -e ".second.nii.tmp-$gone.1.$machine-Ended1" ]
  check "fill: a temporary file of another machine was removed" [ -e ".second.nii.tmp-$gone.1.0123456789abcdef-Other1" ]
  check "fill: an older lsmorph's temporary file was removed" [ -e .second.nii.tmp-Older1 ]
  check "fill: no note names the temporary files left: $(cat "$TMP/stderr")" \
    grep -q -F "left by a run that cannot be shown to have ended" "$TMP/stderr"
  mkdir -p fill-full
  if unshare -rm sh -c 'mount -t tmpfs -o size=16k tmpfs fill-full' 2>/dev/null; then
    unshare -rm sh -c "mount -t tmpfs -o size=16k tmpfs fill-full && '$LSM' fill $IN -o fill-full/out.nii" \
      >"$TMP/stdout" 2>"$TMP/stderr"
    check "fill into a full disk: not refused up front with the numbers and the folder: $(cat "$TMP/stderr")" \
      grep -q -F "lsmorph: error: $IN: the result needs 240 KiB on the file system of fill-full, which has 16 KiB free" "$TMP/stderr"
    check "fill into a full disk: the work began before the refusal" sh -c "! grep -q 'label slices' '$TMP/stderr'"
    : >bound.nii
    unshare -rm sh -c "mount --bind first.nii bound.nii && '$LSM' fill $IN -o bound.nii" >"$TMP/stdout" 2>"$TMP/stderr"
    check "fill into a mount point: not refused up front: $(cat "$TMP/stderr")" \
      grep -q -F "lsmorph: error: bound.nii: is a mount point (a file bound into a container?)" "$TMP/stderr"
    check "fill into a mount point: the work began before the refusal" sh -c "! grep -q 'label slices' '$TMP/stderr'"
  else
    echo "limits: note: fill's disk and mount-point tests skipped (unshare -rm failed)"
  fi
else
  echo "limits: note: fill tests skipped (python3-nibabel missing)"
fi

finish
