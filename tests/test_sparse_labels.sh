#!/bin/sh
# examples/sparse_labels.py end to end: an ellipsoid labelled on every 4th slice
# of a NIfTI volume (0.8 x 0.8 x 2.5 mm, an oblique affine, a second label on
# every slice) is filled back into the volume's grid; then the same across
# axis 0 with --slices; then --label all on a multi-label atlas (touching,
# nested, one-slice and edge labels; labels far apart along the axis; one
# label alone against --label L); then the ellipsoid and the atlas as NRRD
# (raw and gzip, 3D Slicer-like key/value pairs) against the NIfTI runs, read
# back by the script's reader and VTK's vtkNrrdReader; a reused --keep folder;
# then the refusals (NIfTI and NRRD).  Needs nibabel (python3-nibabel); VTK
# (python3-vtk9) for the vtkNrrdReader checks, left out without it.
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

# make AXIS STEP OUT [SPACINGS]: the ellipsoid (label 3) on every STEP-th slice across AXIS,
# label 7 on every slice; OUT.truth.npy holds the whole ellipsoid; voxels 0.8 mm, 2.5 across
# AXIS, or SPACINGS (three, comma separated)
make() {
  "$PY" - "$1" "$2" "$3" "${4:-}" <<'PYEOF'
import sys, numpy as np, nibabel as nib
axis, step, out = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
shape, sp = [100, 90, 60], [0.8, 0.8, 0.8]
sp[axis] = 2.5
if sys.argv[4]:
    sp = [float(v) for v in sys.argv[4].split(",")]
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

# ---- pixels that are not square: slices across axis 0 of 2.5 x 0.8 x 1.6 mm voxels -------------
make 0 4 "$TMP/r.nii" 2.5,0.8,1.6
"$PY" "$SCRIPT" "$TMP/r.nii" "$TMP/r-out.nii" --label 3 --keep "$TMP/rk" --lsmorph "$LSM" -- -q \
  >"$TMP/o" 2>"$TMP/e"
rc=$?
check "pixels 0.8 x 1.6 mm: exit 0 (got $rc: $(tail -c 300 "$TMP/e"))" [ $rc -eq 0 ]
# (NIfTI holds spacings as float32: 0.800000011920929)
check "pixels 0.8 x 1.6 mm: lsmorph got both sizes" "$PY" -c '
import json, sys
o = json.load(open(sys.argv[1]))["options"]
sys.exit(abs(o["pixel_size"] - 0.8) > 1e-6 or abs(o["pixel_size_y"] - 1.6) > 1e-6)' \
  "$TMP/rk/out/run.json"
[ $rc -eq 0 ] && run_checks "$TMP/log" verify "$TMP/r.nii" "$TMP/r-out.nii" 0 4 0.99

# make_atlas DIR: label volumes drawn on every 4th slice across axis 2 (0.8 x 0.8 x 2.5 mm,
# an oblique affine), each with NAME.truth.npy holding the whole labels.  atlas.nii.gz: 1 a
# large ellipsoid (slices 13 .. 50), 2 touching it (3 .. 30), 3 nested inside 1, 4 on drawn
# slice 40 only (39 .. 41), 5 on the first drawn slice only (0 .. 1); apart.nii: 1 on slices
# 19 .. 50 and 2 on 1 .. 10, no label on the drawn slices 12 and 16 between them; one.nii:
# label 1 of the atlas alone; big.nii: the atlas with label 300 (int16); half.nii: the atlas
# with label 2.5 (float32)
make_atlas() {
  "$PY" - "$1" <<'PYEOF'
import os, sys, numpy as np, nibabel as nib
shape, sp = (100, 90, 60), (0.8, 0.8, 2.5)
g = np.mgrid[0:shape[0], 0:shape[1], 0:shape[2]].astype(float)
def ell(c, r):
    return sum(((g[a] - c[a]) * sp[a] / r[a]) ** 2 for a in (0, 1, 2)) < 1
c, s = np.cos(0.5), np.sin(0.5)
aff = np.array([[0.8, -0.6, 0, 0], [0.6 * c, 0.8 * c, -s, 0], [0.6 * s, 0.8 * s, c, 0],
                [0, 0, 0, 1.0]]) @ np.diag(sp + (1.0,))
aff[:3, 3] = (40, 30, -70)
def save(name, truth, dtype=np.int16, swap=None):
    lab = np.zeros(shape, dtype)
    lab[:, :, ::4] = truth[:, :, ::4]
    if swap:
        lab[lab == swap[0]] = swap[1]
    out = os.path.join(sys.argv[1], name)
    nib.save(nib.Nifti1Image(lab, aff), out)
    np.save(out + ".truth.npy", truth)
atlas = np.zeros(shape, np.uint8)
atlas[ell((40.3, 45.2, 31.4), (22.0, 20.0, 48.0))] = 1
atlas[ell((74.6, 40.1, 16.7), (12.0, 14.0, 35.0))] = 2  # painted over 1: they touch
atlas[ell((38.2, 47.7, 30.3), (6.0, 7.0, 16.0))] = 3    # a hole in 1
atlas[ell((72.4, 74.5, 40.0), (8.0, 6.0, 3.0))] = 4
atlas[ell((12.5, 14.5, 0.0), (5.0, 6.0, 3.5))] = 5
save("atlas.nii.gz", atlas)
save("one.nii", np.where(atlas == 1, 1, 0).astype(np.uint8))
save("big.nii", atlas, swap=(2, 300))
save("half.nii", atlas, np.float32, swap=(2, 2.5))
apart = np.zeros(shape, np.uint8)
apart[ell((40.3, 45.2, 34.4), (22.0, 20.0, 40.0))] = 1
apart[ell((70.6, 40.1, 6.0), (12.0, 14.0, 12.0))] = 2
save("apart.nii", apart)
PYEOF
}

# verify_all IN OUT L:MIN_DICE,... KEEP|- [IN OUT ...]: --label all's outputs against the
# truth, every 4th slice across axis 2 drawn; with KEEP (its --keep folder) also the combine
# rule against the kept signed distances
verify_all() {
  "$PY" - "$@" <<'PYEOF'
import json, os, sys, numpy as np, nibabel as nib
def rep(good, what): print(("ok - " if good else "FAIL - ") + what)
def combine(keep, shape, dz):
    """The label of the most negative kept signed distance (+inf outside a run), 0 where none
    is negative, and the count of voxels inside two labels' fills or more."""
    best, label, count = np.zeros(shape, np.float32), np.zeros(shape, np.uint8), np.zeros(shape, int)
    for d in sorted(os.listdir(keep)):
        out = os.path.join(keep, d, "out")
        meta = json.load(open(os.path.join(out, "volume.json")))
        nx, ny, nz = meta["sizes"]
        sdf = np.fromfile(os.path.join(out, "volume.raw"), "<f4").reshape(nz, ny, nx).transpose(2, 1, 0)
        z0 = int(round(meta["origin"][2] / dz))
        run = (slice(None), slice(None), slice(z0, z0 + nz))
        lower = sdf < best[run]
        best[run][lower] = sdf[lower]
        label[run][lower] = int(d.split("-")[1])
        count[run] += sdf < 0
    return label, int((count >= 2).sum())
for n in range(1, len(sys.argv), 4):
    src, out, keep = sys.argv[n], sys.argv[n + 1], sys.argv[n + 3]
    min_dice = dict((int(l), float(d)) for l, d in (p.split(":") for p in sys.argv[n + 2].split(",")))
    name = os.path.basename(src).split(".")[0]
    a, b = nib.load(src), nib.load(out)
    truth = np.load(src + ".truth.npy")
    got = np.asarray(b.dataobj)
    rep(got.shape == truth.shape and got.dtype == np.uint8, "%s: shape %s, %s" % (name, got.shape, got.dtype))
    rep(np.allclose(a.affine, b.affine), "%s: the input's affine kept" % name)
    values = np.unique(got).tolist()
    rep(set(values) <= set(np.unique(truth).tolist()), "%s: values %s among the labels" % (name, values))
    drawn_bad = [k for k in range(0, truth.shape[2], 4) if not np.array_equal(got[:, :, k], truth[:, :, k])]
    rep(not drawn_bad, "%s: every drawn slice back exactly, all labels%s"
        % (name, ": not %s" % drawn_bad if drawn_bad else ""))
    for label, least in sorted(min_dice.items()):
        f, t = got == label, truth == label
        dice = 2 * (f & t).sum() / (f.sum() + t.sum())
        rep(dice >= least, "%s: label %d Dice %.4f >= %g" % (name, label, dice, least))
    if keep != "-":
        want, both = combine(keep, got.shape, a.header.get_zooms()[2])
        filled = np.isin(got, [int(d.split("-")[1]) for d in os.listdir(keep)]) | (got == 0)
        rep(both > 0 and np.array_equal(got[filled], want[filled]) and not want[~filled].any(),
            "%s: each voxel the label of the most negative distance (%d voxels inside two fills)"
            % (name, both))
PYEOF
}

# ---- --label all: a multi-label atlas ----------------------------------------------------------
make_atlas "$TMP"
"$PY" "$SCRIPT" "$TMP/atlas.nii.gz" "$TMP/atlas-out.nii.gz" --label all --keep "$TMP/keep" --lsmorph "$LSM" \
  >"$TMP/o" 2>"$TMP/e"
rc=$?
check "all: exit 0 (got $rc: $(tail -c 300 "$TMP/e"))" [ $rc -eq 0 ]
check "all: says what it filled" grep -q "5 labels on 14 drawn slices (0 .. 52 along axis 2)" "$TMP/o"
check "all: a line per label" grep -q "label 3 (3 of 5): slices 20 .. 40" "$TMP/e"
check "all: a one-slice label within the drawn slices is filled" grep -q "label 4 (4 of 5): slices 36 .. 44" "$TMP/e"
check "all: a one-slice label at the edge is copied, with a warning" \
  grep -q "warning: label 5 (5 of 5) is on one drawn slice only, 0, with no drawn slice before it" "$TMP/e"
check "all: lsmorph quiet without options" [ "$(grep -c -v '^sparse_labels.py: ' "$TMP/e")" -eq 0 ]
rc_atlas=$rc

# labels far apart along the axis: each ends within one step of its last drawn slice, not at
# the other label's first one (slices 12 and 16 hold no label and come back empty)
"$PY" "$SCRIPT" "$TMP/apart.nii" "$TMP/apart-out.nii" --label all --lsmorph "$LSM" >"$TMP/o" 2>"$TMP/e"
rc=$?
check "apart: exit 0 (got $rc: $(tail -c 300 "$TMP/e"))" [ $rc -eq 0 ]
check "apart: label 2 on slices 0 .. 12" grep -q "label 2 (2 of 2): slices 0 .. 12" "$TMP/e"
# measured Dice: atlas 0.9925 0.9897 0.9600 0.4257 (4 spans 3 slices, filled over 7; 5 is
# copied); apart 0.9937 0.8857 (0.6782 when label 2 reached slice 20, halfway to label 1)
[ $rc_atlas -eq 0 ] && [ $rc -eq 0 ] && run_checks "$TMP/log" verify_all \
  "$TMP/atlas.nii.gz" "$TMP/atlas-out.nii.gz" 1:0.99,2:0.985,3:0.95,4:0.4 "$TMP/keep" \
  "$TMP/apart.nii" "$TMP/apart-out.nii" 1:0.99,2:0.88 -

# one label alone: --label all fills the same voxels as --label 1
"$PY" "$SCRIPT" "$TMP/one.nii" "$TMP/one-all.nii" --label all --lsmorph "$LSM" -- -q >"$TMP/o" 2>"$TMP/e" &&
  "$PY" "$SCRIPT" "$TMP/one.nii" "$TMP/one-1.nii" --label 1 --lsmorph "$LSM" -- -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "one label: exit 0 (got $rc: $(tail -c 300 "$TMP/e"))" [ $rc -eq 0 ]
check "one label: --label all fills what --label 1 fills" "$PY" -c '
import sys, numpy as np, nibabel as nib
a, b = (np.asarray(nib.load(f).dataobj) for f in sys.argv[1:])
sys.exit(not (np.array_equal(a, b) and (a == 1).sum() > 50000))' "$TMP/one-all.nii" "$TMP/one-1.nii"

# ---- NRRD (3D Slicer's .nrrd / .seg.nrrd) ----------------------------------------------------------
# make_nrrd SRC.nii OUT raw|gzip [4d|ascii|nhdr]: SRC's labels as a NRRD, written here independently of
# the script: int16 ("short", big-endian when gzip), the NIfTI's affine turned to LPS as oblique space
# directions and origin, a comment and Slicer-like key/value pairs (one SegmentN_LabelValue per label)
make_nrrd() {
  "$PY" - "$@" <<'PYEOF'
import gzip, sys, numpy as np, nibabel as nib
src, out, enc = sys.argv[1:4]
bad = sys.argv[4] if len(sys.argv) > 4 else ""
img = nib.load(src)
lab = np.asarray(img.dataobj).astype(np.int16)
aff = np.diag([-1.0, -1.0, 1.0, 1.0]) @ img.affine  # RAS -> LPS
vec = lambda v: "(" + ",".join(repr(float(x)) for x in v) + ")"
sizes = list(lab.shape)
dirs = " ".join(vec(aff[:3, a]) for a in (0, 1, 2))
if bad == "4d":
    lab, sizes, dirs = np.stack([lab, lab]), [2] + sizes, "none " + dirs
values = [int(v) for v in np.unique(lab) if v]
head = ["NRRD0004", "# a test volume", "type: %s" % ("int16" if enc == "raw" else "short"),
        "dimension: %d" % len(sizes), "space: left-posterior-superior",
        "sizes: " + " ".join(map(str, sizes)), "space directions: " + dirs,
        "kinds: " + ("list " if bad == "4d" else "") + "domain domain domain",
        "endian: " + ("little" if enc == "raw" else "big"),
        "encoding: " + ("ascii" if bad == "ascii" else enc), "space origin: " + vec(aff[:3, 3])]
head += ["Segment%d_ID:=Segment_%d" % (n, v) for n, v in enumerate(values)]
head += ["Segment%d_LabelValue:=%d" % (n, v) for n, v in enumerate(values)]
# Slicer's extents bound each segment's drawn voxels: the filled ones reach farther
box = lambda m: " ".join("%d %d" % (w.min(), w.max()) for w in np.nonzero(m)[-3:])
head += ["Segment%d_Extent:=%s" % (n, box(lab == v)) for n, v in enumerate(values)]
data = lab.astype("<i2" if enc == "raw" else ">i2").tobytes(order="F")
if bad == "nhdr":
    head.append("data file: " + out.rsplit("/", 1)[-1] + ".raw")
    open(out + ".raw", "wb").write(data)
    data = b""
elif bad == "ascii":
    data = " ".join(map(str, lab.ravel(order="F"))).encode()
elif enc == "gzip":
    data = gzip.compress(data)
open(out, "wb").write(("\n".join(head) + "\n\n").encode() + data)
PYEOF
}

# verify_nrrd IN.nrrd OUT.nrrd NIFTI_OUT: OUT's labels identical to the NIfTI run's (read by the
# script's reader and by VTK's vtkNrrdReader, with VTK's spacing and origin), its header IN's
# with type uint8, encoding gzip and endian little
verify_nrrd() {
  "$PY" - "$SCRIPT" "$@" <<'PYEOF'
import os, sys, numpy as np, nibabel as nib
sys.dont_write_bytecode = True  # no __pycache__ in examples/
sys.path.insert(0, os.path.dirname(sys.argv[1]))
import sparse_labels
src, out, ref = sys.argv[2:5]
name = os.path.basename(out)
def rep(good, what): print(("ok - " if good else "FAIL - ") + name + ": " + what)
def header(path):
    raw = open(path, "rb").read()
    end = raw.index(b"\n\n")
    return raw[:end].decode().split("\n"), raw[end + 2:]
want = np.asarray(nib.load(ref).dataobj)
hdr, got = sparse_labels.read_nrrd(out)
rep(got.dtype == np.uint8 and np.array_equal(got, want),
    "labels identical to the NIfTI run's (%d voxels labelled)" % (want > 0).sum())
a, _ = header(src)
b, _ = header(out)
same = lambda l: l.split(":")[0] not in ("type", "encoding", "endian") and "_Extent:=" not in l
rep([l for l in b if same(l)] == [l for l in a if same(l)],
    "the input's header lines, in order (space, directions, origin, key/value pairs)")
kv = dict(l.split(":=", 1) for l in b if ":=" in l)
extents = [(k, kv[k], kv[k[:-len("_Extent")] + "_LabelValue"]) for k in kv if k.endswith("_Extent")]
boxes = [" ".join("%d %d" % (w.min(), w.max()) if w.size else "0 -1" for w in np.nonzero(got == int(v)))
         for _, _, v in extents]
rep(extents and all(e == x for (_, e, _), x in zip(extents, boxes)) and any(e not in a for e in
    ["%s:=%s" % (k, e) for k, e, _ in extents]),
    "SegmentN_Extent recomputed as the filled segment's bounds (%s)" % ", ".join(e for _, e, _ in extents))
rep("type: uint8" in b and "encoding: gzip" in b and "endian: little" in b, "type uint8, encoding gzip")
rep(any(l.startswith("Segment0_LabelValue:=") for l in b), "Segment0_LabelValue kept")
# Debian's vtkNrrdReader is an MPI reader: it needs a controller (no VTK: these checks left out)
try:
    import vtk
except ImportError:
    sys.exit()
ctrl = vtk.vtkDummyController()
vtk.vtkMultiProcessController.SetGlobalController(ctrl)
r = vtk.vtkNrrdReader()
r.SetFileName(out)
r.Update()
img = r.GetOutput()
from vtk.util.numpy_support import vtk_to_numpy
dims = img.GetDimensions()
v = vtk_to_numpy(img.GetPointData().GetScalars()).reshape(dims[::-1]).transpose(2, 1, 0)
rep(tuple(dims) == want.shape and np.array_equal(v, want), "vtkNrrdReader reads the same labels")
lps = np.diag([-1.0, -1.0, 1.0, 1.0]) @ nib.load(ref).affine
rep(np.allclose(img.GetSpacing(), np.linalg.norm(lps[:3, :3], axis=0))
    and np.allclose(img.GetOrigin(), lps[:3, 3]), "vtkNrrdReader: spacing %s, origin %s"
    % (np.round(img.GetSpacing(), 4).tolist(), np.round(img.GetOrigin(), 4).tolist()))
PYEOF
}

make_nrrd "$TMP/z.nii.gz" "$TMP/z.nrrd" raw
make_nrrd "$TMP/z.nii.gz" "$TMP/z-gz.seg.nrrd" gzip
make_nrrd "$TMP/atlas.nii.gz" "$TMP/atlas.nrrd" raw
make_nrrd "$TMP/atlas.nii.gz" "$TMP/atlas.seg.nrrd" gzip
for f in z z-gz.seg atlas atlas.seg; do
  case $f in z*) opt=3 ref=z-out.nii.gz ;; *) opt=all ref=atlas-out.nii.gz ;; esac
  "$PY" "$SCRIPT" "$TMP/$f.nrrd" "$TMP/out-$f.nrrd" --label $opt --lsmorph "$LSM" >"$TMP/o" 2>"$TMP/e"
  rc=$?
  check "nrrd $f, --label $opt: exit 0 (got $rc: $(tail -c 300 "$TMP/e"))" [ $rc -eq 0 ]
  [ $rc -eq 0 ] && run_checks "$TMP/log" verify_nrrd "$TMP/$f.nrrd" "$TMP/out-$f.nrrd" "$TMP/$ref"
done

# --keep reused by a run with fewer slices: no stale slices left in KEEP/slices
"$PY" "$SCRIPT" "$TMP/z.nii.gz" "$TMP/k.nii" --label 3 --slices 0:59:2 --keep "$TMP/k" --lsmorph "$LSM" -- -q \
  >"$TMP/o" 2>"$TMP/e" &&
  "$PY" "$SCRIPT" "$TMP/z.nii.gz" "$TMP/k.nii" --label 3 --keep "$TMP/k" --lsmorph "$LSM" -- -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "--keep reused: exit 0 (got $rc: $(tail -c 300 "$TMP/e"))" [ $rc -eq 0 ]
n=$(ls "$TMP/k/slices" | wc -l)
check "--keep reused: $n slices in slices/, as many as drawn" grep -q "^sparse_labels.py: $n drawn slices" "$TMP/o"

# ---- refusals -------------------------------------------------------------------------------------
expect_fail() { # DESC RC PHRASE ARGS...
  desc=$1 want=$2 phrase=$3
  shift 3
  "$PY" "$SCRIPT" "$@" --lsmorph "$LSM" >"$TMP/o" 2>"$TMP/e"
  rc=$?
  check "$desc: exit $want (got $rc)" [ $rc -eq "$want" ]
  check "$desc: says '$phrase'" grep -q -F -e "$phrase" "$TMP/e"
}
expect_fail "a label on no slice" 1 "the label is on 0 slices" "$TMP/z.nii.gz" "$TMP/no.nii" --label 9
expect_fail "bad --slices" 2 "--slices: 'x' is not a slice number" "$TMP/z.nii.gz" "$TMP/no.nii" --slices 4,x
expect_fail "--slices out of range" 2 "--slices: 60 is outside 0 .. 59" "$TMP/z.nii.gz" "$TMP/no.nii" --slices 4,60
expect_fail "missing file" 1 "cannot read" "$TMP/none.nii" "$TMP/no.nii"
expect_fail "all: a label above 255" 1 "integers 1 .. 255 (the uint8 output), this volume has 300" \
  "$TMP/big.nii" "$TMP/no.nii" --label all
check "all: a label above 255: one error line" [ "$(wc -l <"$TMP/e")" -eq 1 ]
expect_fail "all: a label 2.5" 1 "this volume has 2.5" "$TMP/half.nii" "$TMP/no.nii" --label all
expect_fail "bad --label" 2 "--label: 'x' is not a label number or 'all'" "$TMP/z.nii.gz" "$TMP/no.nii" --label x
make_nrrd "$TMP/z.nii.gz" "$TMP/d.nhdr" raw nhdr
make_nrrd "$TMP/z.nii.gz" "$TMP/a.nrrd" raw ascii
make_nrrd "$TMP/z.nii.gz" "$TMP/l.seg.nrrd" raw 4d
expect_fail "nrrd: a detached header" 1 "a detached NRRD header (.nhdr) is not supported" "$TMP/d.nhdr" "$TMP/no.nrrd"
expect_fail "nrrd: ascii encoding" 1 "NRRD encoding 'ascii' is not supported" "$TMP/a.nrrd" "$TMP/no.nrrd"
expect_fail "nrrd: 4D layers" 1 "export the segmentation as a labelmap" "$TMP/l.seg.nrrd" "$TMP/no.nrrd"
expect_fail "nrrd in, nifti out" 1 "write OUT with the input's format: .nrrd / .seg.nrrd" "$TMP/z.nrrd" "$TMP/no.nii"
check "nrrd in, nifti out: one error line" [ "$(wc -l <"$TMP/e")" -eq 1 ]
expect_fail "nifti in, nrrd out" 1 "write OUT with the input's format: .nii" "$TMP/z.nii.gz" "$TMP/no.nrrd"
check "no output after a refusal" [ ! -e "$TMP/no.nii" -a ! -e "$TMP/no.nrrd" ]
finish
