#!/bin/sh
# Output formats of lsmorph, checked with real readers:
#   sh tests/test_formats.sh BUILD_DIR
# A ball of radius 40 px (128 x 128 x 105 slices) is cut into slices, every 8th
# is kept and reconstructed with --format nrrd,mha,vtk,nii,nii.gz,exr,raw --mesh; then
# (tests/formats_check.py, run with Debian's /usr/bin/python3):
#   - VTK opens volume.nrrd, volume.mha and volume.vtk with the same values as
#     volume.raw (+ volume.json) and the right dimensions, spacing and origin
#   - VTK's NIfTI reader and nibabel open volume.nii and volume.nii.gz with the same values and
#     its affine diag(-sx, -sy, sz) + (0, 0, z0)
#   - OpenImageIO (oiiotool, iinfo) reads every exr/NNNNN.exr with the same
#     values, one channel, pixelSize and sliceHeight attributes
#   - VTK's flying edges at 0 encloses the ball's volume within 4 %
#   - surface.ply: no open or non-manifold edges (vtkFeatureEdges), volume
#     (vtkMassProperties) within 1 % of the isosurface's, outward winding and
#     normals
#   - preview.png and preview3d.png are pictures
# A second run checks --values mask with anisotropic physical spacing (pixels that are not
# square), per-iteration runs a mesh on pixels that are not square either, and a
# few bad options must fail cleanly.  Prints "formats: N passed, N failed".
set -u
BUILD=${1:-build}
LSM="$BUILD/lsmorph"
PY=/usr/bin/python3
HELPER="$(dirname "$0")/formats_check.py"
SUITE=formats
. "$(dirname "$0")/harness.sh"

need "$LSM"
[ -x "$PY" ] || { bad "$PY is missing (Debian package python3)"; finish; }
need_python "vtk, numpy, nibabel" "python3-vtk9, python3-numpy, python3-nibabel"
command -v oiiotool >/dev/null 2>&1 && command -v iinfo >/dev/null 2>&1 ||
  { bad "oiiotool / iinfo are missing (Debian package openimageio-tools)"; finish; }

# mask_matches_slices DIR: a --values mask volume.raw holds DIR/slices/*.png byte
# for byte (both 255 where phi <= 0).
mask_matches_slices() {
  check "--values mask: $(basename "$1")/volume.raw holds slices/*.png byte for byte" \
    "$PY" -c 'import sys, glob, numpy as np, vtk
from vtkmodules.util import numpy_support
d = sys.argv[1]
vol = np.fromfile(d + "/volume.raw", dtype=np.uint8)
files = sorted(glob.glob(d + "/slices/*.png"))
r = vtk.vtkPNGReader()
planes = []
for f in files:
    r.SetFileName(f); r.Update()
    img = r.GetOutput(); nx, ny, _ = img.GetDimensions()
    a = numpy_support.vtk_to_numpy(img.GetPointData().GetScalars()).reshape(ny, nx)
    planes.append(a[::-1])  # VTK reads the bottom row first
sys.exit(0 if len(files) and vol.size == sum(p.size for p in planes) and np.array_equal(vol, np.concatenate([p.ravel() for p in planes])) else 1)' "$1"
}

make_tmp

# ---- the ball, every 8th slice, every format, the mesh -------------------------------------
R=40
CX=63.3
CY=64.6
CZ=52.4
check "ball slices written" "$PY" "$HELPER" ball "$TMP/ball" 128 105 8 $R $CX $CY $CZ
"$LSM" reconstruct "$TMP/ball" -o "$TMP/out" --spacing 8 --format nrrd,mha,vtk,nii,nii.gz,exr,raw --mesh -q \
  >"$TMP/log" 2>&1
rc=$?
check "reconstruct --format nrrd,mha,vtk,nii,nii.gz,exr,raw --mesh exits 0 (got $rc: $(head -c 300 "$TMP/log"))" [ $rc -eq 0 ]
if [ $rc -eq 0 ]; then
  check "nothing printed with -q" [ ! -s "$TMP/log" ]
  run_checks "$TMP/check1" "$PY" "$HELPER" check "$TMP/out" --spacing 1 1 1 --values sdf \
    --ball $R $CX $CY $CZ
  grep -E 'error|volume' "$TMP/check1" | grep -E 'encloses|mesh volume' | sed 's/^ok - /formats: /'
  # headers were fixed in place: same layout as a header written for the final count
  check "volume.mha header says DimSize 128 128 105" grep -a -q '^DimSize = 128 128  *105$' "$TMP/out/volume.mha"
  check "volume.vtk header says DIMENSIONS 128 128 105" grep -a -q '^DIMENSIONS 128 128  *105$' "$TMP/out/volume.vtk"
  check "surface.ply is binary little endian" grep -a -q '^format binary_little_endian 1.0' "$TMP/out/surface.ply"
fi

# ---- a mask volume with anisotropic physical spacing (pixels 0.5 x 0.75, slices 1 apart) -----
# (heights from 5.5 on, so every format's z origin is checked against a value other than 0)
n_ball=$(ls "$TMP/ball"/*.png | wc -l)
awk -v n="$n_ball" 'BEGIN { for (k = 0; k < n; ++k) print 5.5 + 4 * k }' >"$TMP/heights55.txt"
"$LSM" reconstruct "$TMP/ball" -o "$TMP/mask" --heights "$TMP/heights55.txt" --pixel-size 0.5,0.75 --dz 1 \
  --values mask --format raw,exr,vtk,nii.gz,nii,mha,nrrd -q >"$TMP/log" 2>&1
rc=$?
check "reconstruct --values mask exits 0 (got $rc: $(head -c 300 "$TMP/log"))" [ $rc -eq 0 ]
if [ $rc -eq 0 ]; then
  check "heights from 5.5: heights.txt starts at 5.5" [ "$(head -n 1 "$TMP/mask/heights.txt")" = "5.5" ]
  run_checks "$TMP/check2" "$PY" "$HELPER" check "$TMP/mask" --spacing 0.5 0.75 1 --values mask
  mask_matches_slices "$TMP/mask"
fi

# ---- --nrrd-encoding gzip: the same volume.nrrd, its samples one gzip stream ------------------
# The mask run again (every format, VTK reading volume.nrrd against volume.raw, spacing and
# origin), and a signed-distance run: VTK reads the gzip volume.nrrd as the raw one's values.
"$LSM" reconstruct "$TMP/ball" -o "$TMP/maskgz" --heights "$TMP/heights55.txt" --pixel-size 0.5,0.75 --dz 1 \
  --values mask --format raw,exr,vtk,nii.gz,nii,mha,nrrd --nrrd-encoding gzip -q >"$TMP/log" 2>&1
rc=$?
check "--values mask --nrrd-encoding gzip exits 0 (got $rc: $(head -c 300 "$TMP/log"))" [ $rc -eq 0 ]
if [ $rc -eq 0 ]; then
  check "--nrrd-encoding gzip: the header says encoding: gzip" grep -a -q "^encoding: gzip$" "$TMP/maskgz/volume.nrrd"
  run_checks "$TMP/check2gz" "$PY" "$HELPER" check "$TMP/maskgz" --spacing 0.5 0.75 1 --values mask
  check "--nrrd-encoding gzip: a mask shrinks more than 10x" \
    [ $(($(wc -c <"$TMP/mask/volume.nrrd") / $(wc -c <"$TMP/maskgz/volume.nrrd"))) -ge 10 ]
fi
"$LSM" reconstruct "$TMP/ball" -o "$TMP/sdfgz" --spacing 8 --format nrrd,raw --nrrd-encoding gzip \
  --no-slices --no-preview -q >"$TMP/log" 2>&1
rc=$?
check "signed distance --nrrd-encoding gzip exits 0 (got $rc: $(head -c 300 "$TMP/log"))" [ $rc -eq 0 ]
[ $rc -eq 0 ] && check "--nrrd-encoding gzip: VTK reads the signed distance of volume.raw" env PYTHONPATH="$(dirname "$HELPER")" "$PY" -c 'import sys, numpy as np
from formats_check import vtk_modules, read_image
vtk, vtk_to_numpy, controller = vtk_modules()
img = read_image(vtk, vtk.vtkNrrdReader(), sys.argv[1] + "/volume.nrrd")
raw = np.fromfile(sys.argv[1] + "/volume.raw", dtype="<f4")
a = vtk_to_numpy(img.GetPointData().GetScalars()).ravel()
sys.exit(0 if img.GetDimensions() == (128, 128, 105) and np.array_equal(a, raw) else 1)' "$TMP/sdfgz"

# ---- per-iteration mode: slice count and z spacing known only at the end ---------------------
# (a ball cut by the first and last slices, so no slice is empty; its heights
# are not symmetric, so no two input slices are equal)
check "per-iteration slices written" "$PY" "$HELPER" ball "$TMP/pi" 64 41 8 24 31.5 32.2 18.7
"$LSM" reconstruct "$TMP/pi" -o "$TMP/piout" --spacing 8 --pixel-size 0.5,0.6 --per-iteration \
  --format nrrd,mha,vtk,nii,nii.gz,exr,raw --mesh --no-slices -q >"$TMP/log" 2>&1
rc=$?
check "reconstruct --per-iteration exits 0 (got $rc: $(head -c 300 "$TMP/log"))" [ $rc -eq 0 ]
if [ $rc -eq 0 ]; then
  run_checks "$TMP/check3" "$PY" "$HELPER" check "$TMP/piout" --spacing 0.5 0.6 auto --values sdf --mesh \
    --caps
fi
# --dz does nothing with --per-iteration: not to the mesh either (its caps are half a slice step out)
"$LSM" reconstruct "$TMP/pi" -o "$TMP/piout2" --spacing 8 --pixel-size 0.5,0.6 --per-iteration --dz 5 \
  --mesh --no-slices --no-preview -q >"$TMP/log" 2>&1
check "--per-iteration --dz 5 gives the same mesh" cmp -s "$TMP/piout/surface.ply" "$TMP/piout2/surface.ply"

# ---- outlines: phi is exactly 0 on the contour pixels; the mesh has no degenerate triangles --------
check "outline slices written" "$PY" "$HELPER" outline "$TMP/pi" "$TMP/pi-outline"
"$LSM" reconstruct "$TMP/pi-outline" -o "$TMP/olout" --input outline --spacing 8 \
  --format nrrd,mha,vtk,nii,nii.gz,exr,raw --mesh --no-slices -q >"$TMP/log" 2>&1
rc=$?
check "reconstruct --input outline --mesh exits 0 (got $rc: $(head -c 300 "$TMP/log"))" [ $rc -eq 0 ]
if [ $rc -eq 0 ]; then
  run_checks "$TMP/check4" "$PY" "$HELPER" check "$TMP/olout" --spacing 1 1 1 --values sdf --mesh --caps
  # outlines: phi is exactly 0 on the contour pixels, which are inside
  "$LSM" reconstruct "$TMP/pi-outline" -o "$TMP/olmask" --input outline --spacing 8 --values mask \
    --format raw --no-preview -q >"$TMP/log" 2>&1
  rc=$?
  check "outline --values mask exits 0 (got $rc: $(head -c 300 "$TMP/log"))" [ $rc -eq 0 ]
  mask_matches_slices "$TMP/olmask"
fi

# ---- heights far from 0: the mesh's vertices, float32 in the PLY, stay apart --------------------
# (at 1e5 a float step is 1/128: a vertex kept 1/256 of a unit z edge from an outline's contour
# node, where phi is 0, rounded onto it: 58 zero-area triangles on two rings before float_least)
n_pi=$(ls "$TMP/pi-outline"/*.png | wc -l)
awk -v n="$n_pi" 'BEGIN { for (k = 0; k < n; ++k) print 100000 + 8 * k }' >"$TMP/heights1e5.txt"
"$LSM" reconstruct "$TMP/pi-outline" -o "$TMP/olfar" --input outline --heights "$TMP/heights1e5.txt" \
  --format nrrd,mha,vtk,nii,nii.gz,exr,raw --mesh --no-slices -q >"$TMP/log" 2>&1
rc=$?
check "reconstruct --input outline --mesh at heights from 1e5 exits 0 (got $rc: $(head -c 300 "$TMP/log"))" [ $rc -eq 0 ]
if [ $rc -eq 0 ]; then
  run_checks "$TMP/check5" "$PY" "$HELPER" check "$TMP/olfar" --spacing 1 1 1 --values sdf --mesh --caps
fi

# ---- the mesh streams: its memory does not grow with the slice count ------------------------
# Three 256 x 256 slices of dots (radius 1.6 px, 6 px apart), 16 apart in height: 33 output
# slices and a surface.ply of about 135 MB.  The run needs about 60 MB of address space with the
# mesh streamed to scratch files, over 250 MB with the mesh held until written: it must pass
# under a cap of 200 MB (left out under AddressSanitizer, which reserves terabytes).
if grep -q -a "__asan_init" "$LSM"; then
  echo "formats: note: the mesh memory check is left out under AddressSanitizer"
else
  check "dot slices written" "$PY" -c 'import sys, numpy as np
from PIL import Image
yy, xx = np.mgrid[0:256, 0:256]
for k in range(3):
    gx, gy = (xx - k) % 6 - 3, (yy - 2 * k) % 6 - 3
    Image.fromarray(((gx * gx + gy * gy <= 2.6) * 255).astype(np.uint8)).save("%s/%d.png" % (sys.argv[1], k + 1))' "$(mkdir -p "$TMP/dots" && echo "$TMP/dots")"
  (ulimit -v 200000 && exec "$LSM" reconstruct "$TMP/dots" -o "$TMP/dotsout" --spacing 16 --mesh \
    --no-preview --no-slices --threads 2 -q) >"$TMP/log" 2>&1
  rc=$?
  check "--mesh on 33 slices of dots within 200 MB of address space exits 0 (got $rc: $(head -c 300 "$TMP/log"))" [ $rc -eq 0 ]
  vertices=$(sed -n 's/^element vertex //p' "$TMP/dotsout/surface.ply" 2>/dev/null | head -n 1)
  check "the dots' mesh is large: ${vertices:-no} vertices, over 2 million" [ "${vertices:-0}" -gt 2000000 ]
  check "no mesh scratch file is left in OUT_DIR" sh -c '! ls -A "$1" 2>/dev/null | grep -q mesh-' _ "$TMP/dotsout"
  rm -rf "$TMP/dotsout"
fi

# ---- defaults: volume.nrrd and the previews only; --no-preview ------------------------------
"$LSM" reconstruct "$TMP/ball" -o "$TMP/def" --spacing 8 --no-slices -q >/dev/null 2>&1
check "default run exits 0" [ $? -eq 0 ]
check "default run writes volume.nrrd" [ -f "$TMP/def/volume.nrrd" ]
check "default run writes no other volume" sh -c '[ ! -e "$1/volume.mha" ] && [ ! -e "$1/volume.vtk" ] && [ ! -e "$1/volume.nii" ] && [ ! -e "$1/volume.nii.gz" ] && [ ! -e "$1/volume.raw" ] && [ ! -e "$1/exr" ]' _ "$TMP/def"
check "default run writes no mesh" [ ! -e "$TMP/def/surface.ply" ]
check "--no-slices: no slices/ folder" [ ! -e "$TMP/def/slices" ]
check "default run writes preview.png and preview3d.png" sh -c '[ -f "$1/preview.png" ] && [ -f "$1/preview3d.png" ]' _ "$TMP/def"
"$LSM" reconstruct "$TMP/ball" -o "$TMP/nop" --spacing 8 --no-slices --no-preview -q >/dev/null 2>&1
check "--no-preview run exits 0" [ $? -eq 0 ]
check "--no-preview writes no pictures" sh -c '[ ! -e "$1/preview.png" ] && [ ! -e "$1/preview3d.png" ]' _ "$TMP/nop"

# ---- bad options and unwritable places fail cleanly ------------------------------------------
for args in "--format nrrd,tiff" "--format ," "--format" "--values float" "--mesh=1" "--nrrd-encoding zip"; do
  # shellcheck disable=SC2086
  "$LSM" reconstruct "$TMP/ball" -o "$TMP/bad" $args >"$TMP/o" 2>"$TMP/e"
  rc=$?
  check "'$args' exits 2 (got $rc)" [ $rc -eq 2 ]
  check "'$args' says lsmorph: error:" grep -q '^lsmorph: error: ' "$TMP/e"
done
check "usage errors leave no output" [ ! -e "$TMP/bad" ]
"$LSM" reconstruct "$TMP/ball" -o /proc/lsm-no-such-place/out --format exr,raw --mesh -q >"$TMP/o" 2>"$TMP/e"
rc=$?
check "unwritable output exits 1 (got $rc)" [ $rc -eq 1 ]
check "unwritable output says lsmorph: error:" grep -q '^lsmorph: error: ' "$TMP/e"
help=$("$LSM" help reconstruct 2>&1)
for opt in --format --values --mesh --no-preview; do
  case $help in *"$opt"*) ok ;; *) bad "help reconstruct does not list $opt" ;; esac
done

finish
