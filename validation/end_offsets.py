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
        [--shapes bunny,ball,ellipsoid,tilted,cylinder,cone]
        [--methods ls,blend,pchip-mirror,pchip-zero,pchip-drop]
        [-- EXTRA LSMORPH OPTIONS]

Shapes: the bunny (examples/data/bunny, when present) and analytic solids on
128 x 128 slices, 100 slices tall (also smallball, tube, fork, torus: small,
slanted and branching structures; taper, swim, vee: a narrowing slanted vessel,
a thin ellipse that moves and turns, two tubes moving apart; branch: a straight
tube with a side branch leaving it, whose centroid drifts though the trunk stays;
blob, lens, disc: a ball, a flat ellipsoid and a short cylinder 14 to 21 slices
tall, which at every 8th or 16th slice leave one kept slice through them).
Takes a few minutes.

Methods: lsmorph's (ls, blend, pls) and three references that are not lsmorph:
a monotone cubic (scipy's PchipInterpolator, Fritsch-Carlson slopes) through
the plain signed distances of the kept slices (zero level halfway between pixel
centres, negative inside), read at every slice, inside where it is < 0.  They
differ only in what an empty kept slice contributes:
  pchip-mirror  |phi| of the nearest non-empty kept slice (positive everywhere)
  pchip-zero    0 everywhere
  pchip-drop    nothing: the spline runs through the non-empty slices only
                and extrapolates beyond them (kept slices are copied as given;
                with one non-empty kept slice it is copied to every slice)
With no non-empty kept slice at all every reference is empty.
These need python3-scipy (`make validate` installs it).
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
    if name == "blob":  # a small ball, 21 slices tall
        return x ** 2 + y ** 2 + z ** 2 < 10 ** 2
    if name == "lens":  # a flat ellipsoid, 17 slices tall
        return (x / 30) ** 2 + (y / 20) ** 2 + (z / 8.6) ** 2 < 1
    if name == "disc":  # a short cylinder, 14 slices tall
        return (x ** 2 + y ** 2 < 20 ** 2) & (abs(z) < 7)
    if name == "taper":  # a slanted vessel narrowing from 8 to about 1 px radius
        return (x - 1.2 * z) ** 2 + y ** 2 < np.maximum(4.5 - z / 15, 0) ** 2
    if name == "swim":  # a thin ellipse moving 1.2 px and turning 0.05 rad per slice
        c, s = np.cos(0.05 * z), np.sin(0.05 * z)
        u, v = c * (x - 1.2 * z) + s * y, -s * (x - 1.2 * z) + c * y
        return (u / 12) ** 2 + (v / 4) ** 2 < 1
    if name == "vee":  # two thin tubes moving apart, 1 px per slice each (centroid fixed)
        return ((x - z - 10) ** 2 + y ** 2 < 5 ** 2) | ((x + z + 10) ** 2 + y ** 2 < 5 ** 2)
    if name == "branch":  # a straight 10 px tube with a 6 px side branch leaving it at 1 px per slice
        trunk = x ** 2 + y ** 2 < 10 ** 2
        side = ((x - 6 - np.maximum(z, 0)) ** 2 + y ** 2 < 6 ** 2) & (z > -10)
        return (trunk | side) & (abs(z) < 45)
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


def plain_sdf(mask):
    """Signed distance of a mask, zero level halfway between pixel centres."""
    from scipy.ndimage import distance_transform_edt as edt
    return np.where(mask, 0.5 - edt(mask), edt(~mask) - 0.5)


def pchip_reference(stack, k, empty_rule):
    """The plain monotone-cubic reference (see the module text) for every slice."""
    from scipy.interpolate import PchipInterpolator
    zs = list(range(0, len(stack), k))
    sdfs = [plain_sdf(stack[z]) if stack[z].any() else None for z in zs]
    full = [j for j, d in enumerate(sdfs) if d is not None]
    if len(full) < (2 if empty_rule == "drop" else 1):
        # no spline to draw (drop needs two non-empty slices): every slice is the
        # one non-empty kept slice, or empty
        result = np.zeros_like(stack, dtype=bool) if not full else \
            np.repeat(stack[zs[full[0]]][None], len(stack), axis=0)
        result[::k] = stack[::k]
        return result
    for j, d in enumerate(sdfs):
        if d is None:
            near = sdfs[min(full, key=lambda q: abs(q - j))]
            sdfs[j] = {"mirror": np.abs(near), "zero": np.zeros(near.shape),
                       "drop": None}[empty_rule]
    if empty_rule == "drop":
        zs, sdfs = [zs[j] for j in full], [sdfs[j] for j in full]
    spline = PchipInterpolator(np.array(zs, float), np.array(sdfs), axis=0, extrapolate=True)
    result = spline(np.arange(len(stack), dtype=float)) < 0
    result[::k] = stack[::k]
    return result


def write_truth_and_kept(stack, k, work):
    """Writes a truth stack into WORK/truth and its every k-th slice into WORK/kept (both emptied
    first), numbered from 0001: (truth folder, kept folder)."""
    tdir, kdir = os.path.join(work, "truth"), os.path.join(work, "kept")
    for d in (tdir, kdir):
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
    for i, sl in enumerate(stack):
        vlib.write_mask(os.path.join(tdir, "%04d.png" % (i + 1)), sl)
        if i % k == 0:
            vlib.write_mask(os.path.join(kdir, "%04d.png" % (i + 1)), sl)
    return tdir, kdir


def score_stack(lsm, stack, k, methods, extra, work, reference=pchip_reference):
    """`lsmorph score` of every method on a truth stack, every k-th slice kept:
    {method: score JSON}.  reference(stack, k, rule) gives the pchip-RULE rows."""
    tdir, kdir = write_truth_and_kept(stack, k, work)
    odir = os.path.join(work, "out")
    scores = {}
    for method in methods:
        shutil.rmtree(odir, ignore_errors=True)
        if method.startswith("pchip-"):
            os.makedirs(os.path.join(odir, "slices"))
            # up to the last kept slice, as lsmorph writes (score refuses more)
            last = (len(stack) - 1) // k * k
            for i, sl in enumerate(reference(stack, k, method[len("pchip-"):])[:last + 1]):
                vlib.write_mask(os.path.join(odir, "slices", "%05d.png" % (i + 1)), sl)
        else:
            subprocess.run([lsm, "reconstruct", kdir, "-o", odir, "--spacing", str(k),
                            "--method", method, "-q", "--no-preview"] + extra, check=True)
        out = subprocess.run([lsm, "score", tdir, odir, "--stride", str(k)], check=True,
                             capture_output=True, text=True).stdout
        scores[method] = json.loads(out)
    return scores


def offset_stack(truth, k, m):
    """The truth with m empty slices added below it and enough above it that
    the last of every k-th slice is empty."""
    empty = np.zeros(truth[0].shape, bool)
    stack = [empty] * m + list(truth)
    while (len(stack) - 1) % k or stack[-1].any():
        stack.append(empty)
    return np.array(stack)


def run_offset(lsm, truth, k, m, methods, extra, work):
    """Scores of every method with m empty slices added below the truth."""
    scores = score_stack(lsm, offset_stack(truth, k, m), k, methods, extra, work)
    return {m_: [j["dice_volume"], j["dice"], j["hd95"], j["hd95_pooled"], j["one_sided_empty"]]
            for m_, j in scores.items()}


def parse_args(args, opts, name):
    """[BUILD_DIR] [--OPTION VALUE ...] [-- EXTRA]: (lsmorph path, opts, extra)."""
    extra = []
    if "--" in args:
        extra = args[args.index("--") + 1:]
        args = args[:args.index("--")]
    build = "build"
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
        raise SystemExit("%s: %s is missing (run make)" % (name, lsm))
    return lsm, opts, extra


def main():
    lsm, opts, extra = parse_args(sys.argv[1:], {
        "--strides": "8,16", "--shapes": "bunny,ball,ellipsoid,tilted,cylinder,cone",
        "--methods": "ls,blend"}, "end_offsets")
    print("| shape | kept | method | pooled Dice | mean Dice | mean HD95 (px) | pooled HD95 (px) "
          "| one side empty |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="lsm-ends.") as work:
        for shape in opts["--shapes"].split(","):
            truth = load(shape)
            if truth is None:
                print("| %s | - | - | (missing) | | | |" % shape)
                continue
            for k in (int(v) for v in opts["--strides"].split(",")):
                methods = opts["--methods"].split(",")
                rows = [run_offset(lsm, truth, k, m, methods, extra, work) for m in range(k)]
                for method in methods:
                    a = np.nanmean(np.array([r[method] for r in rows], float), axis=0)
                    print("| %s | every %d | %s | %.4f | %.3f | %.2f | %.2f | %.1f |" % (
                        shape, k, method, a[0], a[1], a[2], a[3], a[4]), flush=True)


if __name__ == "__main__":
    main()
