#!/bin/sh
# End-to-end tests of the narrow band (issue 56): a part appearing in an empty region, a hole
# opening inside, and the Candlestick's three candles from two, reconstructed with and
# without the band (tests/band_check.py).  Prints one line per failed check and
# "band: N passed, N failed".
#   sh tests/test_band.sh BUILD_DIR
set -u
BUILD=${1:-build}
LSM="$BUILD/lsmorph"
GEN="$BUILD/examples/gen_synthetic"
PY=/usr/bin/python3
SUITE=band
. "$(dirname "$0")/harness.sh"

need "$LSM" "$GEN"
need_python "numpy, PIL" "python3-numpy python3-pil"
make_tmp
"$GEN" candlestick "$TMP/syn" >"$TMP/o" 2>"$TMP/e" || {
  bad "gen_synthetic candlestick failed: $(cat "$TMP/e")"
  finish
}
run_checks "$TMP/log" "$PY" tests/band_check.py "$LSM" "$TMP/syn/candlestick" "$TMP"
finish
