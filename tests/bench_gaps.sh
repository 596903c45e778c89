#!/bin/sh
# Gaps in parallel on one machine: a 40-gap stack of 512x512 slices, spacing 4
# (3 intermediate slices per gap), one thread against all threads; the two
# volumes must be byte-identical.
set -eu
BUILD=${1:-build}
TMP=$(mktemp -d /tmp/lsmorph-bench-gaps.XXXXXX)
trap 'rm -rf "$TMP"' EXIT INT TERM
/usr/bin/python3 tests/make_stack.py "$TMP/s" 41 512
T=$(nproc)
best() {
  for r in 1 2 3; do
    /usr/bin/time -f "%e" "$@" 2>&1 >/dev/null | tail -1
  done | sort -n | head -1
}
t1=$(best "$BUILD"/lsmorph reconstruct "$TMP/s" -o "$TMP/o1" --spacing 4 -q --threads 1 --no-slices --no-preview)
tn=$(best "$BUILD"/lsmorph reconstruct "$TMP/s" -o "$TMP/on" --spacing 4 -q --threads "$T" --no-slices --no-preview)
same=identical
cmp -s "$TMP/o1/volume.nrrd" "$TMP/on/volume.nrrd" || same=DIFFERENT
echo "== gaps in parallel: 40 gaps of 512x512, spacing 4 (best of 3 wall seconds) =="
awk -v a="$t1" -v b="$tn" -v t="$T" -v s="$same" 'BEGIN { printf "1 thread %.2f s, %d threads over gaps %.2f s: speed-up %.2fx (target >= 1.7x on 2 cores); volumes %s\n", a, t, b, a / b, s }'
if command -v mpirun >/dev/null 2>&1 && make -s MPI=1 BUILD=build-mpi build-mpi/lsmorph >/dev/null 2>&1; then
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,vader \
         OMPI_MCA_btl_vader_single_copy_mechanism=none
  tm=$(best mpirun -np "$T" build-mpi/lsmorph reconstruct "$TMP/s" -o "$TMP/om" --spacing 4 -q --threads 1 --no-slices --no-preview)
  same=identical
  cmp -s "$TMP/o1/volume.nrrd" "$TMP/om/volume.nrrd" || same=DIFFERENT
  awk -v a="$t1" -v b="$tm" -v t="$T" -v s="$same" 'BEGIN { printf "mpirun -np %d (one thread each) %.2f s: speed-up %.2fx; volume %s\n", t, b, a / b, s }'
fi
