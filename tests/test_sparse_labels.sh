#!/bin/sh
# examples/sparse_labels.py, the example of lsmorph's Python API: it fills a NIfTI label map
# (tests/fill_check.py's volumes: touching labels, an oblique affine) as `lsmorph fill` does,
# voxel for voxel, with the input's affine and header; --labels, --axis, --slices and --method
# as the CLI's; errors say what is wrong.  Needs nibabel (python3-nibabel).
#   sh tests/test_sparse_labels.sh BUILD_DIR
# Prints "sparse-labels: N passed, N failed".
set -u
BUILD=${1:-build}
LSM="$BUILD/lsmorph"
PY=/usr/bin/python3
SUITE=sparse-labels
. "$(dirname "$0")/harness.sh"
python_suite "nibabel, numpy" "python3-nibabel, python3-numpy"
SCRIPT="$HERE/../examples/sparse_labels.py"
lib_python "$BUILD/liblsmorph.so"
"$PY" "$HERE/fill_check.py" make "$TMP" >"$TMP/make.log" 2>&1 || { bad "making the volumes"; finish; }

# same CLI_ARGS -- SCRIPT_ARGS: the example's output against lsmorph fill's
same() {
  cli=
  while [ "$1" != "--" ]; do cli="$cli $1"; shift; done
  shift
  "$LSM" fill "$TMP/drawn.nii.gz" -o "$TMP/cli.nii.gz" -q $cli >"$TMP/o" 2>"$TMP/e"
  check "lsmorph fill$cli: exit 0" [ $? -eq 0 ]
  PYTHONPATH="$BUILD/python" "$PYLIB" "$SCRIPT" "$TMP/drawn.nii.gz" "$TMP/py.nii.gz" "$@" >"$TMP/o" 2>"$TMP/e"
  check "sparse_labels.py $*: exit 0 ($(tail -c 200 "$TMP/e"))" [ $? -eq 0 ]
  "$PY" -c "
import nibabel as nib, numpy as np, sys
a, b = nib.load('$TMP/cli.nii.gz'), nib.load('$TMP/py.nii.gz')
sys.exit(0 if np.array_equal(np.asarray(a.dataobj), np.asarray(b.dataobj)) and np.allclose(a.affine, b.affine)
         and a.get_data_dtype() == b.get_data_dtype() else 1)"
  check "sparse_labels.py $*: lsmorph fill's voxels, affine and type" [ $? -eq 0 ]
}
same --
same --labels 2,3 --method blend -- --labels 2,3 --method blend
same --axis k --slices 0,4,8,12,16,20,24,28,32,36,40 -- --axis 2 --slices 0,4,8,12,16,20,24,28,32,36,40

PYTHONPATH="$BUILD/python" "$PYLIB" "$SCRIPT" "$TMP/drawn.nii.gz" "$TMP/no.nii.gz" --labels 9 >"$TMP/o" 2>"$TMP/e"
check "a label that is not there: exit 1" [ $? -eq 1 ]
check "a label that is not there: says so" grep -q "sparse_labels.py: error: .*--labels: 9 is not in the volume" "$TMP/e"
PYTHONPATH="$BUILD/python" "$PYLIB" "$SCRIPT" "$TMP/half.nii" "$TMP/no.nii.gz" >"$TMP/o" 2>"$TMP/e"
check "floats: exit 1 with a message" grep -q "labels must be integers" "$TMP/e"
finish
