#!/bin/sh
# examples/sparse_labels.py end to end: an ellipsoid labelled on every 4th slice
# of a NIfTI volume (0.8 x 0.8 x 2.5 mm, an oblique affine, a second label on
# every slice) is filled back into the volume's grid; then the same across
# axis 0 with --slices; then the refusals.  Needs nibabel (python3-nibabel).
#   sh tests/test_sparse_labels.sh BUILD_DIR
# Prints "sparse-labels: N passed, N failed".
set -u
BUILD=${1:-build}
LSM="$BUILD/lsmorph"
PY=/usr/bin/python3
SUITE=sparse-labels
. "$(dirname "$0")/harness.sh"
need "$LSM"
need_python "nibabel, numpy" "python3-nibabel, python3-numpy"
make_tmp
case $LSM in /*) ;; *) LSM="$PWD/$LSM" ;; esac
SCRIPT="$(cd "$(dirname "$0")/.." && pwd)/examples/sparse_labels.py"

# make AXIS STEP OUT: the ellipsoid (label 3) on every STEP-th slice across AXIS,
# label 7 on every slice; OUT.truth.npy holds the whole ellipsoid
make() {
  "$PY" - "$1" "$2" "$3" <<'PYEOF'
import sys, numpy as np, nibabel as nib
axis, step, out = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
shape, sp = [100, 90, 60], [0.8, 0.8, 0.8]
sp[axis] = 2.5
shape[axis] = 60
for a in (0, 1, 2):
    if a != axis and shape[a] == 60: shape[a] = 100 if a != 1 else 90
g = np.mgrid[0:shape[0], 0:shape[1], 0:shape[2]].astype(float)
c = [s / 2 - 0.7 for s in shape]
r = [30.0, 25.0, 30.0]
r[axis] = 55.0
truth = sum(((g[a] - c[a]) * sp[a] / r[a]) ** 2 for a in (0, 1, 2)) < 1
lab = np.zeros(shape, np.int16)
sl = [slice(None)] * 3
for k in range(0, shape[axis], step):
    sl[axis] = k
    lab[tuple(sl)] = truth[tuple(sl)] * 3
lab[5:8, 5:8, 5:8] = 7
aff = np.array([[0.8, -0.6, 0, 0], [0.6, 0.8, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]) @ np.diag(sp + [1.0])
aff[:3, 3] = (40, 30, -70)
nib.save(nib.Nifti1Image(lab, aff), out)
np.save(out + ".truth.npy", truth)
PYEOF
}

# verify IN OUT AXIS STEP MIN_DICE: prints one "ok"/"FAIL" line per check
verify() {
  "$PY" - "$@" <<'PYEOF'
import sys, numpy as np, nibabel as nib
src, out, axis, step, min_dice = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), float(sys.argv[5])
a, b = nib.load(src), nib.load(out)
truth = np.load(src + ".truth.npy")
got = np.asarray(b.dataobj)
def rep(good, what): print(("ok - " if good else "FAIL - ") + what)
rep(got.shape == truth.shape and got.dtype == np.uint8, "shape %s, %s" % (got.shape, got.dtype))
rep(np.allclose(a.affine, b.affine), "the input's affine kept")
rep(set(np.unique(got).tolist()) <= {0, 3}, "values 0 and 3 only: %s" % np.unique(got).tolist())
filled = got == 3
sl = [slice(None)] * 3
drawn_bad = []
for k in range(0, truth.shape[axis], step):
    sl[axis] = k
    if truth[tuple(sl)].any() and not np.array_equal(filled[tuple(sl)], truth[tuple(sl)]):
        drawn_bad.append(k)
rep(not drawn_bad, "drawn slices back exactly%s" % (": not %s" % drawn_bad if drawn_bad else ""))
dice = 2 * (filled & truth).sum() / (filled.sum() + truth.sum())
rep(dice >= min_dice, "Dice over the volume %.4f >= %g" % (dice, min_dice))
PYEOF
}

# ---- slices across axis 2, found by the script (the label is present) --------------------------
make 2 4 "$TMP/z.nii.gz"
"$PY" "$SCRIPT" "$TMP/z.nii.gz" "$TMP/z-out.nii.gz" --label 3 --lsmorph "$LSM" -- -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "axis 2: exit 0 (got $rc: $(tail -c 300 "$TMP/e"))" [ $rc -eq 0 ]
check "axis 2: says what it filled" grep -q "drawn slices .* along axis 2" "$TMP/o"
[ $rc -eq 0 ] && run_checks "$TMP/log" verify "$TMP/z.nii.gz" "$TMP/z-out.nii.gz" 2 4 0.99

# ---- across axis 0 (its spacing is the largest), with --slices ----------------------------------
make 0 5 "$TMP/x.nii"
"$PY" "$SCRIPT" "$TMP/x.nii" "$TMP/x-out.nii" --label 3 --slices 0:59:5 --lsmorph "$LSM" -- -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "axis 0, --slices: exit 0 (got $rc: $(tail -c 300 "$TMP/e"))" [ $rc -eq 0 ]
check "axis 0 chosen by the spacing" grep -q "along axis 0" "$TMP/o"
[ $rc -eq 0 ] && run_checks "$TMP/log" verify "$TMP/x.nii" "$TMP/x-out.nii" 0 5 0.99

# ---- refusals -------------------------------------------------------------------------------------
expect_fail() { # DESC RC PHRASE ARGS...
  desc=$1 want=$2 phrase=$3
  shift 3
  "$PY" "$SCRIPT" "$@" --lsmorph "$LSM" >"$TMP/o" 2>"$TMP/e"
  rc=$?
  check "$desc: exit $want (got $rc)" [ $rc -eq "$want" ]
  check "$desc: says '$phrase'" grep -q -F -e "$phrase" "$TMP/e"
}
expect_fail "non-square pixels" 1 "is not square" "$TMP/z.nii.gz" "$TMP/no.nii" --axis 1
expect_fail "a label on no slice" 1 "the label is on 0 slices" "$TMP/z.nii.gz" "$TMP/no.nii" --label 9
expect_fail "bad --slices" 2 "--slices: 'x' is not a slice number" "$TMP/z.nii.gz" "$TMP/no.nii" --slices 4,x
expect_fail "--slices out of range" 2 "--slices: 60 is outside 0 .. 59" "$TMP/z.nii.gz" "$TMP/no.nii" --slices 4,60
expect_fail "missing file" 1 "cannot read" "$TMP/none.nii" "$TMP/no.nii"
check "no output after a refusal" [ ! -e "$TMP/no.nii" ]
finish
