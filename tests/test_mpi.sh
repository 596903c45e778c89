#!/bin/sh
# MPI: gaps spread over ranks give the same result as one process, byte for
# byte (volume, heights, slices), in default and per-iteration mode, for rank
# counts that do not divide the gap count; a bad slice on another rank ends
# every rank with one error and no result, and so does a rank that fails before
# it has computed anything (heights from a pipe only rank 0 reads).  Builds the MPI variant (make MPI=1)
# into build-mpi/.  Argument: the normal build folder.
set -u
BUILD=${1:-build}
MPIBUILD="${BUILD%/}-mpi" # its own folder per configuration (SANITIZE=1 passes through MAKEFLAGS)
pass=0
fail=0
check() { # name, command...
  name=$1; shift
  if "$@"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "mpi: FAIL: $name"; fi
}
if ! command -v mpirun >/dev/null 2>&1; then
  echo "mpi: mpirun not found (the Makefile installs openmpi-bin)"; echo "mpi: 0 passed, 1 failed"; exit 1
fi
make -s MPI=1 BUILD=$MPIBUILD "$MPIBUILD/lsmorph" >/dev/null || { echo "mpi: 0 passed, 1 failed (build)"; exit 1; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,vader \
       OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_btl_vader_single_copy_mechanism=none
TMP=$(mktemp -d /tmp/lsmorph-mpi.XXXXXX)
trap 'rm -rf "$TMP"' EXIT INT TERM
# 8 slices (7 gaps: divides by neither 2 nor 3), a moving, changing ellipse
/usr/bin/python3 tests/make_stack.py "$TMP/in" 8 96
"$BUILD"/examples/gen_synthetic pyramid "$TMP/syn" >/dev/null

same_result() { # a b: every file but run.json identical
  [ -d "$1" ] && [ -d "$2" ] || return 1
  (cd "$1" && find . -type f ! -name run.json | sort) > "$TMP/list1"
  (cd "$2" && find . -type f ! -name run.json | sort) > "$TMP/list2"
  cmp -s "$TMP/list1" "$TMP/list2" || return 1
  while read -r f; do cmp -s "$1/$f" "$2/$f" || { echo "mpi: $f differs"; return 1; }; done < "$TMP/list1"
}
# Open MPI's own allocations show up as leaks in a sanitizer build: not ours to
# fix.  This holds for a singleton run (MPI_Init without mpirun) too.
NOLEAK="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
run1() { ASAN_OPTIONS="$NOLEAK" "$MPIBUILD"/lsmorph reconstruct "$@" -q; }
runn() { n=$1; shift; ASAN_OPTIONS="$NOLEAK" timeout 300 mpirun -np "$n" "$MPIBUILD"/lsmorph reconstruct "$@" -q; }

run1 "$TMP/in" -o "$TMP/one" --spacing 5 --threads 1
check "one process (no mpirun): exit 0" [ $? -eq 0 ]
for n in 2 3; do
  runn "$n" "$TMP/in" -o "$TMP/np$n" --spacing 5 --threads 1
  check "default mode, $n ranks" same_result "$TMP/one" "$TMP/np$n"
done
check "run.json names the ranks" grep -q '"rank": 2' "$TMP/np3/run.json"
# --heights-from-names: every rank reads the heights from the names alike (uneven numbers)
mkdir "$TMP/named"
i=0
for n in 3 7 12 20 21 30 38 50; do i=$((i + 1)); cp "$TMP/in/$(printf %04d $i).png" "$TMP/named/s$n.png"; done
run1 "$TMP/named" -o "$TMP/named1" --heights-from-names --threads 1
check "--heights-from-names, one process: exit 0" [ $? -eq 0 ]
runn 3 "$TMP/named" -o "$TMP/named3" --heights-from-names --threads 1
check "--heights-from-names, 3 ranks" same_result "$TMP/named1" "$TMP/named3"
check "--heights-from-names: 48 slices" [ "$(wc -l <"$TMP/named3/heights.txt")" -eq 48 ]
run1 "$TMP/syn/pyramid" -o "$TMP/pone" --input outline --heights "$TMP/syn/pyramid/heights.txt" --per-iteration --threads 1
check "per-iteration, one process: exit 0" [ $? -eq 0 ]
for n in 2 3; do
  runn "$n" "$TMP/syn/pyramid" -o "$TMP/pnp$n" --input outline --heights "$TMP/syn/pyramid/heights.txt" --per-iteration --threads 1
  check "per-iteration mode, $n ranks" same_result "$TMP/pone" "$TMP/pnp$n"
done
# a corrupt slice handled by rank 1 (gap 2 and 3 touch slice 4)
cp -r "$TMP/in" "$TMP/bad"
head -c 200 "$TMP/in/0004.png" > "$TMP/bad/0004.png"
runn 2 "$TMP/bad" -o "$TMP/badout" --spacing 5 --threads 1 2> "$TMP/err.txt"
rc=$?
check "bad slice: exit 1" [ "$rc" -eq 1 ]
check "bad slice: one clear error" grep -q "lsmorph: error: .*0004.png" "$TMP/err.txt"
check "bad slice: no result" [ ! -e "$TMP/badout" ]
check "bad slice: no temporary folder" sh -c "! ls -d '$TMP'/badout.tmp-* >/dev/null 2>&1"
# heights from a pipe: mpirun gives standard input to rank 0 only, so rank 1 reads no heights
# before it has computed anything; it must not leave rank 0 waiting for its gaps for ever
seq 0 5 35 > "$TMP/h.txt"
cat "$TMP/h.txt" | runn 2 "$TMP/in" -o "$TMP/pipeout" --heights /dev/stdin --threads 1 2> "$TMP/err.txt"
rc=$?
check "heights pipe, 2 ranks: exit 1, not a hang (got $rc)" [ "$rc" -eq 1 ]
check "heights pipe: the worker's error is reported" grep -q "lsmorph: error: /dev/stdin: no heights" "$TMP/err.txt"
check "heights pipe: no temporary folder" sh -c "! ls -d '$TMP'/pipeout.tmp-* >/dev/null 2>&1"
# a rank that owns no gap (2 slices, 3 ranks) has nothing to read
mkdir -p "$TMP/two" && cp "$TMP/in/0001.png" "$TMP/in/0002.png" "$TMP/two/"
printf '0\n5\n' | runn 3 "$TMP/two" -o "$TMP/twoout" --heights /dev/stdin --threads 1 2> "$TMP/err.txt"
rc=$?
check "two slices, 3 ranks, heights pipe: exit 0 (got $rc: $(head -c 300 "$TMP/err.txt"))" [ "$rc" -eq 0 ]
check "two slices, 3 ranks: a result" [ -f "$TMP/twoout/volume.nrrd" ]
echo "mpi: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
