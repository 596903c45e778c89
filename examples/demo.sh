#!/bin/sh
# make demo: generate the design document's Vase set (nested contours) and the
# Candlestick set (merging and splitting circles) as outline slices, reconstruct
# them with the default options, and say where the output is.
set -eu
BUILD=${1:-build}
OUT=${DEMO_OUT:-out/demo}
mkdir -p "$OUT"
"$BUILD"/examples/gen_synthetic all "$OUT/input" >/dev/null
for set in vase candlestick; do
  echo "lsmorph demo: reconstructing the $set set (outline input, heights from heights.txt)"
  "$BUILD"/lsmorph reconstruct "$OUT/input/$set" -o "$OUT/$set" --input outline \
    --heights "$OUT/input/$set/heights.txt"
done
echo
echo "lsmorph demo: done."
for set in vase candlestick; do
  n=$(wc -l < "$OUT/$set/heights.txt")
  echo "  $OUT/$set/volume.nrrd   ($n slices; signed distance, open in ParaView or 3D Slicer)"
  echo "  $OUT/$set/preview.png, preview3d.png   (a montage of slices and a rendering)"
  echo "  $OUT/$set/slices/       (one PNG mask per slice), heights.txt, run.json"
done
