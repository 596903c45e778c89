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
make_tmp
cd "$TMP" || exit 1
case $LSM in /*) ;; *) LSM="$OLDPWD/$LSM" ;; esac
TESTS=$OLDPWD/tests

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
seen=0 outside=""
i=0
while [ $i -lt 400 ] && kill -0 $pid 2>/dev/null; do # up to 20 s
  for f in /proc/$pid/fd/*; do
    target=$(readlink "$f" 2>/dev/null) || continue
    case $target in
    "$TMP"/long-out.tmp-*) seen=1 ;;
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

finish
