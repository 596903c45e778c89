"""Rules switched off on the development sets: pooled held-out Dice per stack.

Study 6 (study6_ablation.py) measures each rule on the frozen test split; this script
measures variants of the default on the other stack sets, so that a rule the split does not
exercise can show (or fail to show) an effect before it is removed.  A variant is a
comma-free list of `--rules-off` names joined by '+', or "default":

    /usr/bin/python3 validation/dev_ablation.py [BUILD_DIR] SET VARIANT[,VARIANT...]
        [--strides 4,8]

SET is one of
  atlas       the brain-atlas structures of atlas.py, each cut along z, y and x (33 stacks);
  organs      the 16 organ stand-ins of organs.py;
  motion-dev  the motion set's development half (motion.py);
  test        the frozen test split of split.py (study 6's 16 stacks);
  lone        40 random ellipsoids (seed 5) of 1.5 to 9 slices' half-height on a 41-slice
              stack, most seen on a single kept slice: the lone sections no other set holds.
Every STRIDE-th slice is kept (from the first), the run is `lsmorph reconstruct` with default
options but `--threads 1 --no-preview`, and the score is Dice pooled over the held-out slices.
Prints one line per stack and stride, the means, and per variant the mean and the worst change
against the first variant.  The session 5 section of measurements/ablation.md was measured
with it.
"""
import os
import shutil
import sys
import tempfile

import numpy as np

import vlib


def lone_stacks():
    rng = np.random.default_rng(5)
    z, y, x = np.mgrid[0:41, 0:64, 0:64].astype(float)
    for i in range(40):
        a, b = rng.uniform(4, 14, 2)
        c = rng.uniform(1.5, 9)
        cz = rng.uniform(12, 28)
        cy, cx = rng.uniform(26, 38, 2)
        turn = rng.uniform(0, np.pi)
        u = (x - cx) * np.cos(turn) + (y - cy) * np.sin(turn)
        v = -(x - cx) * np.sin(turn) + (y - cy) * np.cos(turn)
        yield "ell%02d-c%.1f" % (i, c), (u / a) ** 2 + (v / b) ** 2 + ((z - cz) / c) ** 2 <= 1


def stacks(name):
    if name == "motion-dev":
        import motion
        for n in motion.SHAPES:
            yield n, motion.stack(n).astype(bool)
    elif name == "lone":
        yield from lone_stacks()
    elif name == "test":
        import split
        for n, _kind, volume in split.test_stacks():
            yield n, np.asarray(volume).astype(bool)
    elif name == "organs":
        import organs
        for n, volume in organs.organs():
            yield n, np.asarray(volume).astype(bool)
    elif name == "atlas":
        import atlas
        import meshes
        import padded
        image, names = atlas.load_atlas(meshes.cache_dir())
        for s in atlas.STRUCTURES:
            mask = atlas.structure(image, names, *atlas.STRUCTURES[s])
            for a in "zyx":
                yield "%s-%s" % (s, a), padded.cut(np.moveaxis(mask, "zyx".index(a), 0)).astype(bool)
    else:
        raise SystemExit("dev_ablation: unknown set %r" % name)


def pooled_dice(lsmorph, volume, stride, variant, work):
    kept = list(range(0, len(volume), stride))
    kd, od = os.path.join(work, "kept"), os.path.join(work, "out")
    shutil.rmtree(kd, ignore_errors=True)
    shutil.rmtree(od, ignore_errors=True)
    os.makedirs(kd)
    for i, z in enumerate(kept):
        vlib.write_mask(os.path.join(kd, "%04d.png" % (i + 1)), volume[z])
    heights = os.path.join(work, "heights.txt")
    with open(heights, "w") as f:
        f.write("\n".join(str(z) for z in kept) + "\n")
    cmd = [lsmorph, "reconstruct", kd, "-o", od, "--heights", heights, "--dz", "1", "-q",
           "--no-preview", "--threads", "1"]
    if variant != "default":
        cmd += ["--rules-off", variant.replace("+", ",")]
    vlib.run(cmd)
    out = [vlib.read_mask(f) > 0 for f in vlib.list_pngs(os.path.join(od, "slices"))]
    both = total = 0
    for z in range(kept[0], kept[-1] + 1):
        if z in kept:
            continue
        truth, got = volume[z], out[z - kept[0]]
        both += 2 * np.count_nonzero(truth & got)
        total += np.count_nonzero(truth) + np.count_nonzero(got)
    return both / total if total else 1.0


def main(argv):
    strides = [4, 8]
    if "--strides" in argv:
        k = argv.index("--strides")
        strides = [int(s) for s in argv[k + 1].split(",")]
        del argv[k:k + 2]
    build = argv.pop(0) if len(argv) == 3 else "build"
    if len(argv) != 2:
        raise SystemExit(__doc__)
    lsmorph = os.path.abspath(os.path.join(build, "lsmorph"))
    set_name, variants = argv[0], argv[1].split(",")
    scores = {}
    with tempfile.TemporaryDirectory() as work:
        for name, volume in stacks(set_name):
            for k in strides:
                if len(range(0, len(volume), k)) < 2:
                    continue
                row = [pooled_dice(lsmorph, volume, k, v, work) for v in variants]
                for v, d in zip(variants, row):
                    scores.setdefault((k, v), []).append(d)
                print("%-22s every %d  " % (name, k) +
                      "  ".join("%s %.4f" % (v, d) for v, d in zip(variants, row)), flush=True)
    for k in strides:
        base = np.array(scores[(k, variants[0])])
        for v in variants:
            change = np.array(scores[(k, v)]) - base
            print("every %d  %-40s mean %.4f  change %+.4f  worst %+.4f" % (
                k, v, np.mean(scores[(k, v)]), change.mean(), change.min()))


if __name__ == "__main__":
    main(sys.argv[1:])
