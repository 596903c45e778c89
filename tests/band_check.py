"""Checks of the narrow band (issue 56) against the full grid, end to end: tests/test_band.sh.

    /usr/bin/python3 tests/band_check.py LSMORPH CANDLESTICK_DIR WORK_DIR

Stacks where a front must appear away from the current one (nucleation):
  appear   a disc beside another, present in the target only (a part appearing in an empty
           region of the source);
  hole     a disc, then the same disc with a hole in its middle (an outside appearing deep
           inside the source);
  candles  the design document's Candlestick (examples/gen_synthetic: two feet, one stem, two
           arms, three candles), outlines;
each reconstructed with --band on and --band off, also with --rules-off two-sided (the
forward morph alone).  Prints "ok - ..." or "FAIL - ..." lines (tests/harness.sh run_checks).
"""
import json
import os
import subprocess
import sys

import numpy as np
from PIL import Image

LSM, CANDLES, WORK = sys.argv[1:4]
results = []


def check(ok, text):
    print(("ok - " if ok else "FAIL - ") + text)
    results.append(ok)


def disc(w, h, cx, cy, r):
    y, x = np.mgrid[0:h, 0:w]
    return (x - cx) ** 2 + (y - cy) ** 2 <= r * r


def write(path, mask):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    Image.fromarray(mask.astype(np.uint8) * 255).save(path)


def volume(out):
    """The volume's float32 samples as (slices, rows, columns)."""
    data = open(os.path.join(out, "volume.nrrd"), "rb").read()
    head, _, body = data.partition(b"\n\n")
    fields = dict(line.split(":", 1) for line in head.decode().splitlines()[1:] if ":" in line)
    sizes = [int(v) for v in fields["sizes"].split()]
    return np.frombuffer(body, dtype="<f4").reshape(sizes[::-1])


def parts(mask, least=5):
    """8-connected components of a 2D mask of at least `least` pixels (flood fill; small
    images): a speck of a pixel or two where parts merge or split is not a part."""
    seen = np.zeros(mask.shape, bool)
    count = 0
    h, w = mask.shape
    for y0, x0 in zip(*np.nonzero(mask)):
        if seen[y0, x0]:
            continue
        stack = [(y0, x0)]
        seen[y0, x0] = True
        size = 0
        while stack:
            y, x = stack.pop()
            size += 1
            for dy in (-1, 0, 1):
                for dx in (-1, 0, 1):
                    v, u = y + dy, x + dx
                    if 0 <= v < h and 0 <= u < w and mask[v, u] and not seen[v, u]:
                        seen[v, u] = True
                        stack.append((v, u))
        count += size >= least
    return count


def run(name, folder, args):
    """{band: (volume, run.json)} with the band on and off."""
    got = {}
    for band in ("on", "off"):
        out = os.path.join(WORK, "%s-%s" % (name, band))
        p = subprocess.run([LSM, "reconstruct", folder, "-o", out, "-q", "--no-preview",
                            "--no-slices", "--band", band] + args, capture_output=True, text=True)
        if p.returncode != 0:
            check(False, "%s: --band %s exits 0 (%s)" % (name, band, p.stderr.strip()))
            return None
        got[band] = (volume(out), json.load(open(os.path.join(out, "run.json"))))
    return got


def compare(name, got, limit):
    """Voxels on different sides with the band and without, against limit x inside voxels."""
    a, b = got["off"][0] < 0, got["on"][0] < 0
    flips, inside = int((a != b).sum()), int(a.sum())
    check(flips <= limit * inside, "%s: %d of %d inside voxels change sides with the band "
          "(limit %.2g %%)" % (name, flips, inside, 100 * limit))
    on, off = got["on"][1]["totals"], got["off"][1]["totals"]
    check(on["cell_updates"] < off["cell_updates"] and on["band_share"] < 1.0,
          "%s: the band updates fewer cells (%d against %d, share %.3f)"
          % (name, on["cell_updates"], off["cell_updates"], on["band_share"]))
    return a, b


W, H = 120, 80
two = os.path.join(WORK, "appear")
write(os.path.join(two, "001.png"), disc(W, H, 30, 40, 14))
write(os.path.join(two, "017.png"), disc(W, H, 30, 40, 14) | disc(W, H, 92, 40, 10))
hole = os.path.join(WORK, "hole")
write(os.path.join(hole, "001.png"), disc(W, H, 60, 40, 30))
write(os.path.join(hole, "017.png"), disc(W, H, 60, 40, 30) & ~disc(W, H, 60, 40, 8))

# A part appearing in an empty region: both runs grow it from the same slice on.
got = run("appear", two, ["--heights-from-names"])
if got:
    a, b = compare("appear", got, 0.0005)
    first = [next((z for z in range(len(m)) if parts(m[z]) == 2), None) for m in (a, b)]
    check(first[0] is not None and first[0] == first[1],
          "appear: the new part shows from output slice %s (full grid) and %s (band)" % tuple(first))

# A hole opening inside: it opens within one output slice of the full grid's.
got = run("hole", hole, ["--heights-from-names"])
if got:
    a, b = compare("hole", got, 0.0005)
    centre = [next((z for z in range(len(m)) if not m[z][40, 60]), None) for m in (a, b)]
    check(None not in centre and abs(centre[0] - centre[1]) <= 1,
          "hole: the hole opens at output slice %s (full grid) and %s (band)" % tuple(centre))

# Three candles from two: the stack's last gap splits two arms into three candles.
heights = os.path.join(CANDLES, "heights.txt")
got = run("candles", CANDLES, ["--input", "outline", "--heights", heights])
if got:
    a, b = compare("candles", got, 0.0005)
    counts = [[parts(m[z]) for z in range(len(m))] for m in (a, b)]
    same = sum(x == y for x, y in zip(*counts))
    check(same >= 0.99 * len(a), "candles: %d of %d output slices have as many parts with the "
          "band as without" % (same, len(a)))
    check(counts[0][-2] == counts[1][-2] == 3 and counts[1][len(b) // 3] == 1,
          "candles: two feet merge into one stem and end as three candles (%d, %d, %d parts)"
          % (counts[1][0], counts[1][len(b) // 3], counts[1][-2]))

# The forward morph alone (no two-sided rule): the band follows the full grid there too.
for name, folder in (("appear", two), ("hole", hole)):
    got = run(name + "-forward", folder, ["--heights-from-names", "--rules-off", "two-sided"])
    if got:
        compare(name + " (forward morph alone)", got, 0.0005)

sys.exit(0 if all(results) else 1)
