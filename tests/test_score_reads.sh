#!/bin/sh
# score reads the truth as reconstruct read the result's inputs (run.json's options).
#   sh tests/test_score_reads.sh BUILD_DIR
# - a result made from outlines (--input outline): the truth slices are outlines
#   too, filled by parity, so the kept slices come back and the held-out ones are
#   scored against filled regions (refused as "differs from the truth slice" before).
# Prints "score-reads: N passed, N failed".
set -u
BUILD=${1:-build}
LSM="$BUILD/lsmorph"
PY=${PYTHON:-/usr/bin/python3}
SUITE=score-reads
. "$(dirname "$0")/harness.sh"
need "$LSM"
command -v "$PY" >/dev/null 2>&1 || PY=python3
work_in_tmp

# truth: 9 slices of 32x32, rings of radius 4 .. 10 between two empty slices;
# kept: slices 1, 3, 5 and 9 under their own names
"$PY" - "$TESTS" <<'EOF' || bad "writing the outline stacks failed"
import os, sys
sys.path.insert(0, sys.argv[1])
from formats_check import write_png
os.makedirs("truth"), os.makedirs("kept")
for i in range(9):
    rows = []
    for y in range(32):
        row = bytearray(32)
        for x in range(32):
            d2 = (x - 15.5) ** 2 + (y - 15.5) ** 2
            row[x] = 255 if 0 < i < 8 and (3 + i) ** 2 <= d2 < (4 + i) ** 2 else 0
        rows.append(bytes(row))
    for folder in ("truth", "kept") if i in (0, 2, 4, 8) else ("truth",):
        write_png(f"{folder}/{i + 1:02d}.png", rows, 32, 32)
EOF
"$LSM" reconstruct kept -o out --input outline --heights-from-names -q --no-preview 2>"$TMP/e"
check "outlines reconstructed ($(cat "$TMP/e"))" [ $? -eq 0 ]
"$LSM" score truth out --per-slice >"$TMP/o" 2>"$TMP/e"
check "score of an outline result: exit 0 ($(cat "$TMP/e"))" [ $? -eq 0 ]
check "score of an outline result: 5 held out ($(cat "$TMP/o"))" grep -q '"held_out": 5' "$TMP/o"
# truth slice 4, a ring of radius 6 to 7, filled: the pixels within radius 7
area=$("$PY" -c "print(sum((x - 15.5) ** 2 + (y - 15.5) ** 2 < 49 for x in range(32) for y in range(32)))")
check "score of an outline result: truth slice 4 counted filled, $area pixels ($(cat "$TMP/o"))" \
  grep -q "\"truth\": 4, [^}]*\"area_truth\": $area}" "$TMP/o"
finish
