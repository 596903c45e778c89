#!/bin/sh
# liblsmorph and the Python package lsmorph: lsmorph.fill returns the CLI's volume voxel for
# voxel (Fortran- and C-ordered arrays, big-endian input, options, --slices, --labels),
# lsmorph.reconstruct the signed distances of `reconstruct`, errors raise lsmorph.Error; then
# `make install` into a temporary prefix: a C program built with pkg-config against the
# shared and the static library gives the CLI's volume, and the installed package imports.
#   sh tests/test_python.sh BUILD_DIR
# Prints "python: N passed, N failed".
set -u
BUILD=${1:-build}
LSM="$BUILD/lsmorph"
PY=/usr/bin/python3
SUITE=python
. "$(dirname "$0")/harness.sh"
python_suite "nibabel, numpy" "python3-nibabel, python3-numpy"
[ -f "$BUILD/python/lsmorph/__init__.py" ] || { bad "$BUILD/python/lsmorph is missing (make builds it)"; finish; }
lib_python "$BUILD/liblsmorph.so"

"$PY" "$HERE/fill_check.py" make "$TMP" >"$TMP/make.log" 2>&1 || { bad "making the volumes"; finish; }
"$LSM" fill "$TMP/drawn.nii.gz" -o "$TMP/cli.nii.gz" -q &&
  "$LSM" fill "$TMP/drawn.nii.gz" -o "$TMP/cli-opts.nii.gz" -q --method blend --interp linear \
    --labels 2,3 --slices 0:40:4 &&
  "$LSM" fill "$TMP/drawn.seg.nrrd" -o "$TMP/cli-seg.nrrd" -q &&
  "$LSM" fill "$TMP/drawn.nii.gz" -o "$TMP/cli-field.nii.gz" -q --motion field
check "the CLI's fills" [ $? -eq 0 ]

run_checks "$TMP/log" env PYTHONPATH="$BUILD/python" "$PYLIB" - "$TMP" "$LSM" <<'PYEOF'
import os, subprocess, sys
import numpy as np, nibabel as nib
import lsmorph
d, lsm = sys.argv[1], sys.argv[2]
def report(good, what): print(("ok - " if good else "FAIL - ") + what)
img = nib.load(os.path.join(d, "drawn.nii.gz"))
drawn = np.asarray(img.dataobj)
spacing = [float(z) for z in img.header.get_zooms()[:3]]
cli = np.asarray(nib.load(os.path.join(d, "cli.nii.gz")).dataobj)
f = lsmorph.fill(drawn, spacing=spacing)
report(f.dtype == drawn.dtype and (f == cli).all(), "fill: the CLI's volume voxel for voxel (%d voxels labelled)" % (f > 0).sum())
report((drawn == np.asarray(img.dataobj)).all(), "fill: the input array is left as it was")
c = lsmorph.fill(np.ascontiguousarray(drawn), spacing=spacing)
report(c.flags.c_contiguous and (c == cli).all(), "fill: a C-ordered array, the same voxels")
big = drawn.astype(">i2")
report((lsmorph.fill(big, spacing=spacing) == cli).all(), "fill: big-endian labels, the same voxels")
inplace = np.array(drawn, order="F")
out = lsmorph.fill(inplace, spacing=spacing, out=inplace)
report(out is inplace and (inplace == cli).all(), "fill: out=labels fills in place")
opts = lsmorph.fill(drawn, spacing=spacing, method="blend", interp="linear", fill_labels=[2, 3],
                    slices=range(0, 41, 4), threads=1)
report((opts == np.asarray(nib.load(os.path.join(d, "cli-opts.nii.gz")).dataobj)).all(),
       "fill: options, slices and labels as the CLI's --method blend --interp linear --labels 2,3 --slices 0:40:4")
field = lsmorph.fill(drawn, spacing=spacing, motion="field")
report((field == np.asarray(nib.load(os.path.join(d, "cli-field.nii.gz")).dataobj)).all(),
       "fill: motion='field' as the CLI's --motion field")
try:
    lsmorph.fill(drawn, spacing=spacing, method="bogus")
    report(False, "fill: a bad option raises lsmorph.Error")
except lsmorph.Error as e:
    report(e.status == 1 and "method: 'bogus'" in str(e), "fill: a bad option raises lsmorph.Error (%s)" % e)
try:
    lsmorph.fill(drawn, spacing=spacing, axis=1, slices=[20])
    report(False, "fill: one drawn slice raises lsmorph.Error")
except lsmorph.Error as e:
    report(e.status == 2, "fill: one drawn slice raises lsmorph.Error (%s)" % e)
one = np.zeros_like(drawn)
one[:, :, 20] = drawn[:, :, 20]
for order in ("F", "C"):  # the axis named as the caller sees it, whatever the memory order
    try:
        lsmorph.fill(np.asarray(one, order=order), spacing=spacing)
        report(False, "fill: one drawn slice across k (%s order) raises lsmorph.Error" % order)
    except lsmorph.Error as e:
        report("across k only slice 20" in str(e), "fill: one drawn slice, %s order: the message names k (%s)" % (order, e))
    try:  # a bad spacing named by its axis, as the caller sees it
        lsmorph.fill(np.asarray(drawn, order=order), spacing=(0.0, spacing[1], spacing[2]))
        report(False, "fill: a zero spacing (%s order) raises lsmorph.Error" % order)
    except lsmorph.Error as e:
        report("spacing 0 along i is not a length" in str(e), "fill: a zero spacing, %s order: the message names i (%s)" % (order, e))
for bad, kind in ((drawn.astype(np.float32), TypeError), (drawn[0], ValueError), (drawn[:0], ValueError)):
    try:
        lsmorph.fill(bad)
        report(False, "fill: %s raised" % kind.__name__)
    except kind:
        report(True, "fill: %s raised for %s" % (kind.__name__, "2D" if bad.ndim != 3 else "no voxels" if not bad.size else "floats"))
try:
    lsmorph.fill(drawn, colour="red")
    report(False, "fill: an unknown option raises TypeError")
except TypeError:
    report(True, "fill: an unknown option raises TypeError")
# reconstruct: the signed distances of `lsmorph reconstruct`
os.makedirs(os.path.join(d, "stack"))
masks = np.zeros((3, 40, 50), np.uint8)
yy, xx = np.mgrid[0:40, 0:50]
for k, r in enumerate((6, 12, 9)):
    masks[k] = (xx - 25) ** 2 + (yy - 20) ** 2 < r * r
from PIL import Image
for k in range(3):
    Image.fromarray(masks[k] * 255).save(os.path.join(d, "stack", "%d.png" % k))
subprocess.run([lsm, "reconstruct", os.path.join(d, "stack"), "-o", os.path.join(d, "rec"), "--spacing", "4",
                "--pixel-size", "0.5,0.75", "--dz", "1", "-q", "--no-preview"], check=True)
phi, z = lsmorph.reconstruct(masks, spacing=4, pixel_size=(0.5, 0.75), dz=1)
raw = open(os.path.join(d, "rec", "volume.nrrd"), "rb").read()
vol = np.frombuffer(raw[512:], "<f4").reshape(phi.shape)
report(phi.shape == (9, 40, 50) and np.array_equal(phi, vol) and np.allclose(z, np.arange(9.0)),
       "reconstruct: the signed distances of lsmorph reconstruct (%d slices)" % phi.shape[0])
wide, _ = lsmorph.reconstruct(masks.astype(np.uint16) * 256, spacing=4, pixel_size=(0.5, 0.75), dz=1)
report(np.array_equal(wide, phi), "reconstruct: masks of 0 and 256 (uint16) are the same masks")
for kw, kind, says in ((dict(dz=0), ValueError, "dz must be a positive length"),
                       (dict(pixel_size=(float("nan"), 1)), lsmorph.Error, "pixel size nan x 1")):
    try:
        lsmorph.reconstruct(masks, **kw)
        report(False, "reconstruct %s raises %s" % (kw, kind.__name__))
    except kind as e:
        report(says in str(e), "reconstruct %s raises %s (%s)" % (kw, kind.__name__, e))
PYEOF

# make install into a temporary prefix: pkg-config, the shared and the static library, the package
make -s install BUILD="$BUILD" PREFIX="$TMP/inst" >"$TMP/install.log" 2>&1
check "make install PREFIX=...: exit 0 ($(tail -c 200 "$TMP/install.log"))" [ $? -eq 0 ]
cat >"$TMP/prog.c" <<'CEOF'
/* fills a raw uint8 volume (argv[1], 60 x 50 x 41, spacing argv[3..5]) into argv[2] */
#include <lsmorph.h>
#include <stdio.h>
#include <stdlib.h>
int main(int argc, char **argv) {
  if (argc < 6) return 2;
  const size_t n[3] = {60, 50, 41}, count = 60 * 50 * 41;
  const double spacing[3] = {atof(argv[3]), atof(argv[4]), atof(argv[5])};
  unsigned char *v = malloc(count);
  FILE *f = fopen(argv[1], "rb");
  if (!v || !f || fread(v, 1, count, f) != count) return 1;
  fclose(f);
  lsmorph_options o;
  lsmorph_options_default(&o);
  char msg[512];
  const int st = lsmorph_fill(v, LSMORPH_UINT8, n, spacing, -1, NULL, 0, NULL, 0, &o, NULL, msg, sizeof msg);
  if (st != LSMORPH_OK) { fprintf(stderr, "%s: %s\n", lsmorph_status_name(st), msg); return 1; }
  f = fopen(argv[2], "wb");
  if (!f || fwrite(v, 1, count, f) != count || fclose(f) != 0) return 1;
  free(v);
  return 0;
}
CEOF
"$PY" -c "
import nibabel as nib, numpy as np
open('$TMP/drawn.raw', 'wb').write(np.asarray(nib.load('$TMP/drawn.nii.gz').dataobj).astype(np.uint8).tobytes(order='F'))
open('$TMP/cli.raw', 'wb').write(np.asarray(nib.load('$TMP/cli.nii.gz').dataobj).astype(np.uint8).tobytes(order='F'))
open('$TMP/spacing', 'w').write(' '.join(repr(float(z)) for z in nib.load('$TMP/drawn.nii.gz').header.get_zooms()[:3]))"
PC="env PKG_CONFIG_PATH=$TMP/inst/lib/pkgconfig pkg-config"
cc $SANFLAGS "$TMP/prog.c" -o "$TMP/prog-shared" $($PC --cflags --libs lsmorph) -Wl,-rpath,"$TMP/inst/lib" 2>"$TMP/e"
check "a C program built with pkg-config --libs lsmorph ($(tail -c 200 "$TMP/e"))" [ $? -eq 0 ]
cc $SANFLAGS "$TMP/prog.c" -o "$TMP/prog-static" $($PC --cflags lsmorph) "$TMP/inst/lib/liblsmorph.a" $($PC --static --libs lsmorph | sed 's/-llsmorph//') 2>"$TMP/e"
check "a C program built with the static library and pkg-config --static ($(tail -c 200 "$TMP/e"))" [ $? -eq 0 ]
for kind in shared static; do
  "$TMP/prog-$kind" "$TMP/drawn.raw" "$TMP/$kind.raw" $(cat "$TMP/spacing") 2>"$TMP/e"
  check "the $kind library's fill: exit 0 ($(tail -c 200 "$TMP/e"))" [ $? -eq 0 ]
  check "the $kind library's fill: the CLI's volume, byte for byte" cmp -s "$TMP/$kind.raw" "$TMP/cli.raw"
done
check "the shared program uses the installed liblsmorph.so.0" sh -c "ldd '$TMP/prog-shared' | grep -q '$TMP/inst/lib/liblsmorph.so.0'"
SITE=$(ls -d "$TMP"/inst/lib/python3*/dist-packages)
(cd "$TMP" && PYTHONPATH="$SITE" "$PYLIB" -c "import lsmorph, sys; sys.exit(0 if lsmorph.__file__.startswith('$SITE') and lsmorph.version() else 1)") 2>"$TMP/e"
check "the installed package imports and finds the installed library ($(tail -c 200 "$TMP/e"))" [ $? -eq 0 ]
finish
