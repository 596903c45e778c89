#!/bin/sh
# OUT_DIR end to end: what reconstruct replaces, what it refuses before any
# work, how it writes where a folder cannot be replaced, and the temporary
# folders of interrupted runs.
#   sh tests/test_out_dir.sh BUILD_DIR
# - replaced only when provably an earlier lsmorph result: run.json lsmorph's,
#   and nothing in the folder lsmorph does not write (a folder holding a file
#   named run.json and the user's work is refused, untouched);
# - refused before any work: a symbolic link to nothing, a folder holding a
#   file this run would write; followed: a link to an earlier result (the link
#   stays); written in place, file by file: `-o .` and a mount point (a bind
#   mount in a user namespace, `unshare -rm`, where the system allows one);
# - a second Ctrl-C removes the temporary folder; a run killed by SIGKILL
#   leaves one, which the next run removes because its maker provably ended,
#   while those of live processes, other machines and older versions stay.
# Prints "out-dir: N passed, N failed".
set -u
BUILD=${1:-build}
LSM="$BUILD/lsmorph"
PY=${PYTHON:-/usr/bin/python3}
SUITE=out-dir
. "$(dirname "$0")/harness.sh"
need "$LSM"
command -v "$PY" >/dev/null 2>&1 || PY=python3
work_in_tmp

"$PY" "$TESTS/make_stack.py" good 3 32 >/dev/null 2>&1 || { bad "make_stack.py good"; finish; }
# fingerprint DIR: a checksum of every file under DIR (to see it unchanged).
fingerprint() { (cd "$1" && find . -type f | LC_ALL=C sort | xargs cksum) 2>/dev/null | cksum; }
# refused DESC PHRASE OUT ARG...: exit 1, the message says PHRASE, no work was
# started (no "N slices of" line), and no temporary folder is left.
refused() {
  what=$1 phrase=$2 out=$3
  shift 3
  "$LSM" reconstruct "$@" -o "$out" >"$TMP/stdout" 2>"$TMP/stderr"
  rc=$?
  check "$what: exit $rc, expected 1 ($(cat "$TMP/stderr"))" [ $rc -eq 1 ]
  check "$what: message does not say '$phrase': $(cat "$TMP/stderr")" grep -q -F -e "$phrase" "$TMP/stderr"
  check "$what: the work began before the refusal" sh -c "! grep -q 'slices of' '$TMP/stderr'"
  check "$what: a temporary folder was left" sh -c "! ls -d '$out'.tmp-* '$out'/.lsmorph.tmp-* >/dev/null 2>&1"
}
run_ok() { # run_ok DESC OUT ARG...: exit 0
  what=$1 out=$2
  shift 2
  "$LSM" reconstruct "$@" -o "$out" >"$TMP/stdout" 2>"$TMP/stderr"
  rc=$?
  check "$what: exit $rc ($(cat "$TMP/stderr"))" [ $rc -eq 0 ]
}

# ---- item 1: only an earlier lsmorph result is replaced ------------------------------------
mkdir -p p/data && echo '{}' >p/run.json && echo work >p/data/thesis.tex
sum=$(fingerprint p)
refused "a folder with another run.json and the user's work" \
  "p: exists, is not empty and is not an earlier lsmorph result (its run.json has no lsmorph_version and output.files)" \
  p good -q
check "the user's work beside a run.json was changed" [ "$(fingerprint p)" = "$sum" ]
mkdir -p e && : >e/run.json && echo x >e/notes.txt
refused "an empty run.json" "e: exists, is not empty and is not an earlier lsmorph result (its run.json is not JSON)" e good -q
check "a folder with an empty run.json was changed" [ "$(cat e/notes.txt)" = x ]
run_ok "a first result" r good -q --no-preview
sum=$(fingerprint r)
echo mine >r/notes.txt
refused "an earlier result holding the user's file" \
  "r: holds notes.txt, which lsmorph does not write: it is not only an earlier lsmorph result" r good -q
rm r/notes.txt && echo mine >r/slices/notes.txt
refused "an earlier result holding the user's file in slices/" "r: holds slices/notes.txt, which lsmorph does not write" r good -q
rm r/slices/notes.txt && ln -s ../p/data/thesis.tex r/volume.vtk
refused "an earlier result holding a symbolic link" "r: holds volume.vtk (a symbolic link), which lsmorph does not write" r good -q
rm r/volume.vtk
check "a refused earlier result was changed" [ "$(fingerprint r)" = "$sum" ]
run_ok "an earlier result is replaced" r good -q --mesh
check "the earlier result was not replaced" [ -f r/surface.ply ]

# ---- item 6: links, the current folder, mount points: decided before the work --------------
ln -s nowhere dangling
refused "a symbolic link to nothing" "dangling: is a symbolic link to nothing (nowhere)" dangling good
check "the link to nothing was changed" [ -L dangling ] && [ "$(readlink dangling)" = nowhere ]
ln -s r to-r
run_ok "a symbolic link to an earlier result" to-r good --no-preview --no-slices
check "a link to an earlier result: no note says it is followed: $(cat "$TMP/stderr")" \
  grep -q -F "lsmorph: note: to-r is a symbolic link: the result goes to the folder it names" "$TMP/stderr"
check "a link to an earlier result was replaced by a folder" [ -L to-r ]
check "the folder a link names did not get the result" sh -c '[ -f r/run.json ] && [ ! -e r/slices ] && [ ! -e r/surface.ply ]'
# -o .: the current folder cannot be renamed (the shell stands in it): written in place
mkdir here && cd here || exit 1
echo mine >notes.txt
"$LSM" reconstruct ../good -o . >"$TMP/stdout" 2>"$TMP/stderr"
rc=$?
check "-o .: exit $rc ($(cat "$TMP/stderr"))" [ $rc -eq 0 ]
check "-o .: no note says it is written in place: $(cat "$TMP/stderr")" \
  grep -q -F "lsmorph: note: . is the current folder or holds it, which is not replaced as a whole: its files are replaced one by one" "$TMP/stderr"
check "-o .: the result is not in the folder" sh -c '[ -f run.json ] && [ -f volume.nrrd ] && [ -f slices/00003.png ]'
check "-o .: the user's file is gone" [ "$(cat notes.txt)" = mine ]
"$LSM" reconstruct ../good -o . -q --no-slices --mesh --format nrrd,mha >"$TMP/stdout" 2>"$TMP/stderr"
rc=$?
check "-o . again: exit $rc ($(cat "$TMP/stderr"))" [ $rc -eq 0 ]
check "-o . again: the earlier result's slices/ stayed, or the new files are missing" \
  sh -c '[ ! -e slices ] && [ -f surface.ply ] && [ -f volume.mha ] && [ -f notes.txt ]'
check "-o . again: a temporary folder was left" sh -c '! ls -d .lsmorph.tmp-* >/dev/null 2>&1'
cd .. || exit 1
mkdir there && echo 0 >there/heights.txt
(cd there && "$LSM" reconstruct ../good -o . >"$TMP/stdout" 2>"$TMP/stderr")
check "-o . over the user's heights.txt: exit 1 and the reason ($(cat "$TMP/stderr"))" \
  grep -q -F "lsmorph: error: .: holds heights.txt, which this run would write, and is not an earlier lsmorph result" "$TMP/stderr"
check "-o . over the user's heights.txt: it was changed" [ "$(cat there/heights.txt)" = 0 ]
(cd good && "$LSM" reconstruct . -o . >"$TMP/stdout" 2>"$TMP/stderr")
check "-o . in the input folder: not refused ($(cat "$TMP/stderr"))" \
  grep -q -F "lsmorph: error: .: is or contains the input folder ., which writing into it would delete" "$TMP/stderr"
# a mount point (the container pattern -v out:/out ... -o /out): a bind mount in a user
# namespace, where the system allows one
mkdir -p bound mnt
if unshare -rm sh -c 'mount --bind bound mnt' 2>/dev/null; then
  unshare -rm sh -c "mount --bind bound mnt && '$LSM' reconstruct good -o mnt --no-preview && \
    '$LSM' reconstruct good -o mnt -q --mesh" >"$TMP/stdout" 2>"$TMP/stderr"
  rc=$?
  check "a mount point: exit $rc ($(cat "$TMP/stderr"))" [ $rc -eq 0 ]
  check "a mount point: no note says it is written in place: $(cat "$TMP/stderr")" \
    grep -q -F "lsmorph: note: mnt is a mount point, which cannot be replaced as a whole" "$TMP/stderr"
  check "a mount point: the result is not in the mounted folder" \
    sh -c '[ -f bound/run.json ] && [ -f bound/surface.ply ] && [ -f bound/preview.png ] && [ ! -e mnt/run.json ]'
else
  echo "out-dir: note: mount-point test skipped (no user namespace with mounts: unshare -rm failed)"
fi

# ---- item 7: a second Ctrl-C; temporary folders of runs that ended -----------------------------
"$PY" "$TESTS/make_stack.py" long 40 512 >/dev/null 2>&1 || bad "make_stack.py long"
# start_long OUT: a long run in the background (about 15 s), SIGINT at its default, $pid;
# returns when it has begun writing slices
start_long() {
  "$PY" -c 'import os, signal, sys
signal.signal(signal.SIGINT, signal.SIG_DFL)
os.execv(sys.argv[1], sys.argv[1:])' "$LSM" reconstruct long -o "$1" -q --spacing 3 --no-preview \
    --threads 1 --time rk3 --reinit-every 2 >/dev/null 2>"$TMP/stderr-long" &
  pid=$!
  i=0
  while [ $i -lt 1200 ] && kill -0 $pid 2>/dev/null; do
    for f in "$1".tmp-*/slices/*.png; do
      [ -e "$f" ] && return 0
      break
    done
    sleep 0.05
    i=$((i + 1))
  done
  bad "the long run into $1 never began writing slices"
}
# Ctrl-C pressed again and again (every 0.5 ms for 0.1 s): the second used to end the
# process at once, before the first was acted on, leaving OUT.tmp-*
start_long twice
"$PY" -c 'import os, signal, sys, time
for _ in range(200):
    try:
        os.kill(int(sys.argv[1]), signal.SIGINT)
    except ProcessLookupError:
        break
    time.sleep(0.0005)' $pid
wait $pid
rc=$?
check "SIGINT again and again: exit $rc, expected 130 ($(cat "$TMP/stderr-long"))" [ $rc -eq 130 ]
check "SIGINT again and again: a temporary folder was left: $(ls -d twice.tmp-* 2>/dev/null)" \
  sh -c '! ls -d twice.tmp-* >/dev/null 2>&1'
# SIGKILL: nothing can clean up; the next run into the same OUT removes what is provably dead
start_long killed
kill -s KILL $pid
wait $pid 2>/dev/null
left=$(ls -d killed.tmp-* 2>/dev/null)
check "SIGKILL left no temporary folder to test with" [ -n "$left" ]
machine=$(echo "$left" | sed -n 's/^killed\.tmp-[0-9]*\.[0-9]*\.\([0-9a-f]\{16\}\)-.*/\1/p')
check "the temporary folder's name does not carry its maker ($left)" [ -n "$machine" ]
sleep 300 &
live=$!
start=$(awk '{ print $22 }' /proc/$live/stat 2>/dev/null)
mkdir "killed.tmp-$live.$start.$machine-Alive1" "killed.tmp-$live.$((start + 1)).$machine-Reused" \
  "killed.tmp-$live.$start.0123456789abcdef-Other1" killed.tmp-Older1
run_ok "a run after one killed" killed good --no-preview
kill $live 2>/dev/null
check "the killed run's temporary folder was not removed" [ ! -e "$left" ]
check "a temporary folder whose pid was reused was not removed" [ ! -e "killed.tmp-$live.$((start + 1)).$machine-Reused" ]
check "a live run's temporary folder was removed" [ -d "killed.tmp-$live.$start.$machine-Alive1" ]
check "another machine's temporary folder was removed" [ -d "killed.tmp-$live.$start.0123456789abcdef-Other1" ]
check "an older lsmorph's temporary folder was removed" [ -d killed.tmp-Older1 ]
check "no note names the folders removed: $(cat "$TMP/stderr")" \
  grep -q -F "lsmorph: note: removed 2 temporary folders of earlier runs that ended without finishing" "$TMP/stderr"
check "no note names a folder left: $(cat "$TMP/stderr")" \
  grep -q -F "left by a run that cannot be shown to have ended" "$TMP/stderr"
finish
