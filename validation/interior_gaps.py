"""Inside the object only: the gaps between two non-empty kept slices, where
no end rule is involved, lsmorph against a monotone cubic of plain signed
distances (padded.py's pchip-R).

Nine analytic solids on 128 x 128 slices, each whole inside its stack with
empty slices around it (a hollow ball, a ball, a tilted ellipsoid, a torus
about z and one about x, two overlapping balls, a cone, a bent tube, a cup).
Every k-th slice is kept from the first; the held-out slices of the gaps whose
two kept slices are both non-empty are scored (pooled Dice over them), so the
numbers say how well the z-profile follows the solid between sections,
including the gaps beside a last section, and nothing of how the object ends.

    /usr/bin/python3 validation/interior_gaps.py [BUILD_DIR] [--strides 8,16]
        [-- EXTRA LSMORPH OPTIONS]

Prints per solid and stride the count of interior held-out slices and the
pooled Dice of lsmorph and of pchip-R; then the means.  Under a minute.
"""
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

import end_offsets as eo
import padded
import vlib


def grid(depth):
    z, y, x = np.mgrid[0:depth, 0:128, 0:128].astype(float)
    return z, y - 63.5, x - 63.5


def solids():
    """(name, boolean (depth, 128, 128) volume) of each solid."""
    z, y, x = grid(65)
    r = np.sqrt(x * x + y * y + (z - 32) ** 2)
    yield "shell", (r < 28) & (r >= 18)
    yield "ball", r < 25
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
    xr, zr = c * x + s * (z - 32), -s * x + c * (z - 32)
    yield "ellipsoid", (xr / 35) ** 2 + (y / 18) ** 2 + (zr / 12) ** 2 < 1
    yield "torus-z", (np.sqrt(x * x + y * y) - 32) ** 2 + (z - 32) ** 2 < 12 ** 2
    yield "two-balls", (((x + 18) ** 2 + y ** 2 + (z - 26) ** 2 < 400)
                        | ((x - 18) ** 2 + y ** 2 + (z - 40) ** 2 < 400))
    yield "cone", (np.sqrt(x * x + y * y) < 30 * (58 - z) / 48) & (z > 10) & (z < 58)
    bend = 20 * np.sin((z - 32) / 15)
    yield "bent-tube", ((x - bend) ** 2 + y ** 2 < 10 ** 2) & (z > 4) & (z < 60)
    rho2 = x * x + y * y
    yield "cup", (z > 8) & (z < 58) & (rho2 / 40 + 8 < z) & (rho2 / 40 + 8 > z - 10)
    z, y, x = grid(81)
    yield "torus-x", (np.sqrt(y * y + (z - 40) ** 2) - 24) ** 2 + x ** 2 < 10 ** 2


def interior(truth, k):
    """Held-out slice indices of the gaps whose two kept slices are non-empty."""
    kept = range(0, len(truth), k)
    return [z for a, b in zip(kept, kept[1:]) if truth[a].any() and truth[b].any()
            for z in range(a + 1, b)]


def dice(truth, result, slices):
    a, b = truth[slices], result[slices]
    total = a.sum() + b.sum()
    return 2.0 * (a & b).sum() / total if total else 1.0


def reconstruct(lsm, stack, k, extra, work):
    kept, out = os.path.join(work, "kept"), os.path.join(work, "out")
    for d in (kept, out):
        shutil.rmtree(d, ignore_errors=True)
    os.makedirs(kept)
    for i in range(0, len(stack), k):
        vlib.write_mask(os.path.join(kept, "%04d.png" % i), stack[i])
    subprocess.run([lsm, "reconstruct", kept, "-o", out, "--spacing", str(k), "-q",
                    "--no-preview"] + extra, check=True)
    return np.array([vlib.read_mask(f) for f in vlib.list_pngs(os.path.join(out, "slices"))])


def main():
    opts = {"--strides": "8,16"}
    lsm, opts, extra = eo.parse_args(sys.argv[1:], opts, "interior_gaps")
    strides = [int(k) for k in opts["--strides"].split(",")]
    print("| solid | kept | interior slices | ls | pchip-R |")
    print("|---|---|---|---|---|")
    sums = {k: [0, 0.0, 0.0] for k in strides}
    with tempfile.TemporaryDirectory() as work:
        for name, volume in solids():
            for k in strides:
                truth = volume[:(len(volume) - 1) // k * k + 1]  # up to the last kept slice
                slices = interior(truth, k)
                if not slices:
                    continue
                ls = dice(truth, reconstruct(lsm, truth, k, extra, work), slices)
                ref = dice(truth, padded.reference(truth, k, "R"), slices)
                print("| %s | every %d | %d | %.4f | %.4f |" % (name, k, len(slices), ls, ref),
                      flush=True)
                sums[k][0] += 1
                sums[k][1] += ls
                sums[k][2] += ref
    for k in strides:
        n, ls, ref = sums[k]
        if n:
            print("| **mean** | every %d | %d solids | %.4f | %.4f |" % (k, n, ls / n, ref / n))


if __name__ == "__main__":
    main()
