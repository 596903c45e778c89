"""The two end rules side by side: an object ending next to an empty slice
against the same object ending beside something that goes on.

lsmorph ends a part of the object in two ways (solver/README.md §8):
  - alone: the whole section meets an empty slice, and the end rule of
    solver/recon/lsm_ends.c runs (the trend of the slices before, area caps, a
    section whole at mid-gap closing in a tip at the empty slice);
  - beside: the slice on the other side still holds something else, far away,
    and the part has no counterpart there; the halfway rule for components
    (lsm_cap_unmatched in solver/recon/lsm_unmatched.c) closes it by mid-gap, a paraboloid
    cap, inside the ordinary morph and cubic.
This script puts each analytic solid of end_offsets.py on a wider canvas,
once alone and once with a bar in every slice, 90 px to its right (farther
than any solid's depth, so the solid counts as unmatched), moves the ends
through every offset inside a gap as end_offsets.py does, and scores the
held-out slices of the solid's part of the canvas only.

    /usr/bin/python3 validation/interior_ends.py [BUILD_DIR] [--strides 8,16]
        [--shapes ball,ellipsoid,cylinder,cone,smallball,torus] [-- EXTRA OPTIONS]

Prints, per shape and stride, averaged over the offsets: pooled Dice, pooled
HD95 (px; a held-out slice empty on one side only counts the image size for
each boundary pixel), mean per-slice Dice, mean HD95 (slices non-empty on both
sides), and the count of slices empty on one side.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

import end_offsets as eo
import vlib

BAR_GAP = 90  # columns between the solid's canvas and the bar
BAR_WIDTH = 20


def reconstruct(lsm, stack, k, width, extra, work, tag):
    """Runs lsmorph on every k-th slice of stack; returns a folder whose
    slices/ hold the result cut to the first `width` columns."""
    kept, out, cut = (os.path.join(work, d + tag) for d in ("kept-", "out-", "cut-"))
    for d in (kept, out, cut):
        shutil.rmtree(d, ignore_errors=True)
    os.makedirs(kept)
    os.makedirs(os.path.join(cut, "slices"))
    for i in range(0, len(stack), k):
        vlib.write_mask(os.path.join(kept, "%04d.png" % (i + 1)), stack[i])
    subprocess.run([lsm, "reconstruct", kept, "-o", out, "--spacing", str(k), "-q",
                    "--no-preview"] + extra, check=True)
    for i, f in enumerate(vlib.list_pngs(os.path.join(out, "slices"))):
        vlib.write_mask(os.path.join(cut, "slices", "%05d.png" % (i + 1)),
                        vlib.read_mask(f)[:, :width])
    return cut


def score(lsm, truth_dir, out_dir, k):
    out = subprocess.run([lsm, "score", truth_dir, out_dir, "--stride", str(k)], check=True,
                         capture_output=True, text=True).stdout
    j = json.loads(out)
    return [j["dice_volume"], j["hd95_pooled"], j["dice"], j["hd95"], j["one_sided_empty"]]


def main():
    lsm, opts, extra = eo.parse_args(sys.argv[1:], {
        "--strides": "8,16", "--shapes": "ball,ellipsoid,cylinder,cone,smallball,torus"},
        "interior_ends")
    print("| shape | kept | ends | pooled Dice | pooled HD95 (px) | mean Dice | mean HD95 (px) "
          "| one side empty |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="lsm-interior.") as work:
        for shape in opts["--shapes"].split(","):
            solid = eo.solid(shape)
            nz, ny, width = solid.shape
            margin = np.zeros((nz, ny, BAR_GAP + BAR_WIDTH + 10), bool)
            alone = np.concatenate([solid, margin], axis=2)
            bar = np.zeros_like(alone[0])
            bar[ny // 2 - 10:ny // 2 + 10, width + BAR_GAP:width + BAR_GAP + BAR_WIDTH] = True
            for k in (int(v) for v in opts["--strides"].split(",")):
                rows = {"alone": [], "beside": []}
                for m in range(k):
                    stack = [np.zeros_like(bar)] * m + list(alone)
                    while (len(stack) - 1) % k or stack[-1].any():
                        stack.append(np.zeros_like(bar))
                    stack = np.array(stack)
                    truth = os.path.join(work, "truth")
                    shutil.rmtree(truth, ignore_errors=True)
                    os.makedirs(truth)
                    for i, sl in enumerate(stack):
                        vlib.write_mask(os.path.join(truth, "%04d.png" % (i + 1)), sl[:, :width])
                    for ends, s in (("alone", stack), ("beside", stack | bar[None])):
                        out = reconstruct(lsm, s, k, width, extra, work, ends)
                        rows[ends].append(score(lsm, truth, out, k))
                for ends, r in rows.items():
                    a = np.nanmean(np.array(r, float), axis=0)
                    print("| %s | every %d | %s | %.4f | %.2f | %.3f | %.2f | %.1f |"
                          % ((shape, k, ends) + tuple(a)), flush=True)


if __name__ == "__main__":
    main()
