#!/bin/sh
# The house rules of the tree and of its documentation (issue 52):
# tests/check_house.py (rooms without include cycles, includes named from the
# root, no source file over 800 lines, nothing referring to a folder outside the
# repository) and
# tests/check_docs.py (README.md at most 350 lines, every relative link of the
# Markdown files resolves).
#   sh tests/test_house.sh BUILD_DIR
SUITE=house
. tests/harness.sh
PY=/usr/bin/python3
for check in check_house check_docs; do
  if out=$("$PY" "tests/$check.py" . 2>&1); then ok; else bad "$check.py:
$out"; fi
done
finish
