"""The narrow band against the full grid on the validation stacks (issue 56): every stack
reconstructed from every k-th slice with `--band on` and `--band off`, default options
otherwise, both scored against the held-out slices with `lsmorph score`; the voxels of
volume.nrrd that change sides, how far from the full grid's surface (|phi| there) and from the
nearest kept slice.

    /usr/bin/python3 validation/band.py [BUILD_DIR] [--sets bunny,organs,padded,motion,test]
        [-- EXTRA LSMORPH OPTIONS]

Sets: the bunny (examples/data/bunny, every 4th, 8th, 16th), organs.py's 16 organ stand-ins
(every 4th, 8th, 16th), padded.py's analytic shapes (every 8th, 16th), motion.py's 15 moving
stacks (every 4th, 8th) and split.py's frozen test split (16 stacks, every 4th, 8th).  Prints a
Markdown row per set and stride (means over its stacks) and the largest differences; about ten
minutes on 2 cores.  Needs python3-scipy (organs.py).
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

import end_offsets as eo
import motion
import organs
import padded
import split


def volume(out):
    data = open(os.path.join(out, "volume.nrrd"), "rb").read()
    head, _, body = data.partition(b"\n\n")
    fields = dict(line.split(":", 1) for line in head.decode().splitlines()[1:] if ":" in line)
    sizes = [int(v) for v in fields["sizes"].split()]
    return np.frombuffer(body, dtype="<f4").reshape(sizes[::-1])


def compare(lsm, stack, k, extra, work):
    """Scores with the band on and off and the voxels that change sides."""
    tdir, kdir = eo.write_truth_and_kept(stack, k, work)
    got = {}
    for band in ("off", "on"):
        out = os.path.join(work, band)
        shutil.rmtree(out, ignore_errors=True)
        subprocess.run([lsm, "reconstruct", kdir, "-o", out, "--spacing", str(k), "-q",
                        "--no-preview", "--band", band] + extra, check=True)
        score = json.loads(subprocess.run([lsm, "score", tdir, out, "--stride", str(k)],
                                          check=True, capture_output=True, text=True).stdout)
        totals = json.load(open(os.path.join(out, "run.json")))["totals"]
        got[band] = (score, volume(out), totals)
    a, b = got["off"][1], got["on"][1]
    flip = (a < 0) != (b < 0)
    z = np.nonzero(flip)[0]
    from_kept = np.minimum(z % k, k - z % k) if z.size else np.zeros(0)
    return {"dice": (got["off"][0]["dice_volume"], got["on"][0]["dice_volume"]),
            "hd95": (got["off"][0]["hd95_pooled"], got["on"][0]["hd95_pooled"]),
            "flips": int(flip.sum()), "inside": int((a < 0).sum()),
            "phi": float(np.abs(a[flip]).max()) if flip.any() else 0.0,
            "from_kept": int(from_kept.min()) if z.size else -1,
            "updates": (got["off"][2]["cell_updates"], got["on"][2]["cell_updates"])}


def sets(names):
    if "bunny" in names:
        truth = eo.load("bunny")
        if truth is not None:
            yield "bunny", [4, 8, 16], [("bunny", truth)]
    if "organs" in names:
        yield "organs", [4, 8, 16], [(n, padded.cut(v)) for n, v in organs.organs()]
    if "padded" in names:
        shapes = "ball,ellipsoid,tilted,cylinder,cone,smallball,torus,taper,fork,blob,lens,disc"
        yield "padded", [8, 16], [(s, padded.cut(eo.load(s))) for s in shapes.split(",")]
    if "motion" in names:
        yield "motion", [4, 8], [(n, motion.stack(n)) for n in motion.SHAPES]
    if "test" in names:
        yield "test split", [4, 8], [(n, v) for n, _, v in split.test_stacks()]


def main():
    lsm, opts, extra = eo.parse_args(sys.argv[1:], {"--sets": "bunny,organs,padded,motion,test"},
                                     "band")
    print("| set | kept | stacks | Dice full grid | Dice band | largest Dice change | HD95 full grid "
          "(px) | HD95 band (px) | largest HD95 change (px) | voxels changing sides | largest |phi| "
          "there (px) | nearest kept slice to them | cell updates, full / band |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="lsm-band.") as work:
        for name, strides, stacks in sets(opts["--sets"].split(",")):
            for k in strides:
                rows = [compare(lsm, stack, k, extra, work) for _, stack in stacks
                        if len(stack) > k]
                d = np.array([r["dice"] for r in rows], float)
                h = np.array([r["hd95"] for r in rows], float)
                flips = sum(r["flips"] for r in rows)
                inside = sum(r["inside"] for r in rows)
                updates = np.array([r["updates"] for r in rows], float).sum(axis=0)
                near = [r["from_kept"] for r in rows if r["flips"]]
                print("| %s | every %d | %d | %.5f | %.5f | %.5f | %.3f | %.3f | %.3f | %d of %d | "
                      "%.3f | %s | %.1fx |" % (name, k, len(rows), d[:, 0].mean(), d[:, 1].mean(),
                                               np.abs(d[:, 1] - d[:, 0]).max(), np.nanmean(h[:, 0]),
                                               np.nanmean(h[:, 1]),
                                               np.nanmax(np.abs(h[:, 1] - h[:, 0])), flips, inside,
                                               max(r["phi"] for r in rows),
                                               "%d slices" % min(near) if near else "-",
                                               updates[0] / updates[1]), flush=True)


if __name__ == "__main__":
    main()
