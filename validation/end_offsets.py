"""Where objects end: held-out scores with the object's ends at every offset
inside a gap.

The halfway rule decides what lsmorph draws between a non-empty slice and an
empty one.  How well that works depends on where, inside that gap, the true
object ends, which a single stack fixes by accident (the bunny's flat base sits
one slice above an empty slice).  This script moves the ends through every
offset: for m = 0 .. k-1 it puts m empty slices below the truth stack (and
enough above it that the last kept slice is empty), keeps every k-th slice,
reconstructs, and scores the held-out slices with `lsmorph score`.  It prints
the scores averaged over the offsets, per shape and method.

    /usr/bin/python3 validation/end_offsets.py [BUILD_DIR] [--strides 8,16]
        [--shapes bunny,ball,ellipsoid,tilted,cylinder,cone] [--methods ls,blend]
        [-- EXTRA LSMORPH OPTIONS]

Shapes: the bunny (../shared/data/bunny, when present) and analytic solids on
128 x 128 slices, 100 slices tall (also smallball, tube, fork, torus: small,
slanted and branching structures).  Takes a few minutes.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

import vlib


def solid(name):
    z, y, x = np.mgrid[0:100, 0:128, 0:128].astype(float)
    z -= 49.7
    y -= 63.6
    x -= 64.3
    if name == "ball":
        return x ** 2 + y ** 2 + z ** 2 < 46 ** 2
    if name == "ellipsoid":
        return (x / 50) ** 2 + (y / 30) ** 2 + (z / 47) ** 2 < 1
    if name == "tilted":  # an ellipsoid tilted by 0.6 rad out of the slice plane
        c, s = np.cos(0.6), np.sin(0.6)
        xr, zr = c * x + s * z, -s * x + c * z
        return (xr / 55) ** 2 + (y / 28) ** 2 + (zr / 30) ** 2 < 1
    if name == "cylinder":  # flat ends
        return (x ** 2 + y ** 2 < 40 ** 2) & (abs(z) < 45)
    if name == "cone":  # a flat base and a pointed tip
        return (np.sqrt(x ** 2 + y ** 2) < 0.9 * (45 - z)) & (z > -45) & (z < 45)
    if name == "smallball":  # a structure a few pixels across
        return x ** 2 + y ** 2 + (z / 4) ** 2 < 7 ** 2
    if name == "tube":  # a thin vessel crossing the slices at a slant (1.2 px per slice)
        return (x - 1.2 * z) ** 2 + y ** 2 < 5 ** 2
    if name == "fork":  # one tube splitting into two
        left = (x + 0.5 * np.maximum(z, 0)) ** 2 + y ** 2 < 6 ** 2
        right = (x - 0.5 * np.maximum(z, 0)) ** 2 + y ** 2 < 6 ** 2
        return (left | right) & (abs(z) < 45)
    if name == "torus":  # a ring lying across the slices
        r = np.sqrt(x ** 2 + z ** 2)
        return (r - 32) ** 2 + y ** 2 < 12 ** 2
    raise SystemExit("end_offsets: unknown shape %s" % name)


def load(name):
    if name == "bunny":
        files = vlib.list_pngs(os.environ.get("LSMORPH_BUNNY", vlib.BUNNY_DIR))
        if not files:
            return None
        return np.array([vlib.read_mask(f) for f in files])
    return solid(name)


def run_offset(lsm, truth, k, m, method, extra, work):
    empty = np.zeros(truth[0].shape, bool)
    stack = [empty] * m + list(truth)
    while (len(stack) - 1) % k or stack[-1].any():
        stack.append(empty)
    tdir, kdir, odir = (os.path.join(work, d) for d in ("truth", "kept", "out"))
    for d in (tdir, kdir, odir):
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
    for i, sl in enumerate(stack):
        vlib.write_mask(os.path.join(tdir, "%04d.png" % (i + 1)), sl)
        if i % k == 0:
            vlib.write_mask(os.path.join(kdir, "%04d.png" % (i + 1)), sl)
    subprocess.run([lsm, "reconstruct", kdir, "-o", odir, "--spacing", str(k), "--method", method,
                    "-q", "--no-preview"] + extra, check=True)
    out = subprocess.run([lsm, "score", tdir, odir, "--stride", str(k)], check=True,
                         capture_output=True, text=True).stdout
    j = json.loads(out)
    return [j["dice_volume"], j["dice"], j["hd95"], j["hd95_pooled"]]


def main():
    args = sys.argv[1:]
    extra = []
    if "--" in args:
        extra = args[args.index("--") + 1:]
        args = args[:args.index("--")]
    build = "build"
    opts = {"--strides": "8,16", "--shapes": "bunny,ball,ellipsoid,tilted,cylinder,cone",
            "--methods": "ls,blend"}
    i = 0
    while i < len(args):
        if args[i] in opts and i + 1 < len(args):
            opts[args[i]] = args[i + 1]
            i += 2
        else:
            build = args[i]
            i += 1
    lsm = os.path.join(vlib.ROOT, build, "lsmorph") if not os.path.isabs(build) else \
        os.path.join(build, "lsmorph")
    if not os.access(lsm, os.X_OK):
        raise SystemExit("end_offsets: %s is missing (run make)" % lsm)
    print("| shape | kept | method | pooled Dice | mean Dice | mean HD95 (px) | pooled HD95 (px) |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="lsm-ends.") as work:
        for shape in opts["--shapes"].split(","):
            truth = load(shape)
            if truth is None:
                print("| %s | - | - | (missing) | | | |" % shape)
                continue
            for k in (int(v) for v in opts["--strides"].split(",")):
                for method in opts["--methods"].split(","):
                    rows = [run_offset(lsm, truth, k, m, method, extra, work) for m in range(k)]
                    a = np.nanmean(np.array(rows, float), axis=0)
                    print("| %s | every %d | %s | %.4f | %.3f | %.2f | %.2f |" % (
                        shape, k, method, a[0], a[1], a[2], a[3]), flush=True)


if __name__ == "__main__":
    main()
