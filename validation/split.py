"""The frozen split of the validation stacks: a development half and a test half.

Rules are tuned only on the development half.  The test half is kept for
measuring them (study 6's ablation table, validation/measurements/ablation.md)
and is never looked at while a rule or a constant is chosen: a rule that needs
a new test set to show its worth gets one drawn fresh, not this one re-cut.

Development (every stack a rule has ever been tuned on; the figures in
validation/measurements/rules.md were measured on these):
  - the bunny (examples/data/bunny), studies 3-5;
  - validation/organs.py's 16 organ stand-ins (seeds 100 onward);
  - the analytic shapes of validation/end_offsets.py, padded.py,
    interior_gaps.py and interior_ends.py (ball, ellipsoid, tilted, cylinder,
    cone, smallball, tube, fork, torus, taper, swim, vee, branch, blob, lens,
    disc);
  - validation/motion.py's 15 moving, turning and branching stacks;
  - the downloaded sets (atlas.py, meshes.py, ct.py).

Test (frozen 2026-12-02; no rule was tuned on any of these):
  fresh draws from the same generators with seeds no tuning run ever used, so
  they are the same kinds of shapes as the development half but not the same
  shapes:
  - organ-t0 .. organ-t6: organs.py's organ stand-ins from seeds 5000 onward
    (every third a pair, as in organs.py);
  - solid-t0 .. solid-t3: an ellipsoid tilted out of the slice plane, a
    cylinder with flat ends, a cone, a torus lying across the slices, each
    with sizes, tilts and positions drawn from seed 6000 + i;
  - motion-t0 .. motion-t4: a thin tube drifting obliquely, a thin ellipse
    turning as it travels, a tube that bifurcates with its branches diverging,
    two tubes moving apart, a thin wall moving across itself, with sizes and
    speeds drawn from seed 7000 + i: the kinds of issue 53, each moving by
    about its own width or more per gap at every 8th slice kept (no ends: the
    structure is in every slice).
  Each stack with ends gets a seeded number of empty slices below (1 to 16)
  and above (so that the last slice is empty and the stack height is 1 + a
  multiple of 8), so its ends fall at assorted offsets inside a gap, and with
  every 4th slice kept some ends have more empty kept slices beyond them
  (--ends auto then ends them at mid-gap) and some do not (the tip).

The motion set (validation/motion.py, issue 53) has a split of its own, frozen
2026-12-02 before any run looked at its test half: development = its fifteen
named stacks (the correspondence field's constants were chosen on them);
test = eight fresh draws of the hard kinds (a tilted and a curved tube, a
section turning as it travels and one turning fast about a point off it, a
hinged wall, a bifurcation and a fast split with diverging branches, a thin
wall moving more than its thickness per gap) with sizes and speeds from seeds
8000 onward (motion.py --split test; MOTION_TEST below).

Why fresh draws rather than half of the old sets: every old stack has been
used to choose some rule (the organ stand-ins the tip exponents and the floor,
the analytic shapes the ends, the bunny almost everything), so no half of them
is a set "no rule was tuned on".  The generators are what the development
work was tuned to represent; new seeds test whether the rules carry over.

    /usr/bin/python3 validation/split.py   lists the test stacks and their sizes
"""
import numpy as np

import organs

SIZE = 128
STACK_MULTIPLE = 8  # every stack with ends is 1 + a multiple of this tall

TEST_ORGANS = 7
TEST_SOLIDS = ["ellipsoid", "cylinder", "cone", "torus"]
TEST_MOTIONS = ["tube", "turning", "bifurcation", "apart", "wall"]

MOTION_TEST = ["t-tilted-tube", "t-curved-tube", "t-turning", "t-fast-turning", "t-hinge",
               "t-bifurcation", "t-fast-split", "t-wall"]  # motion.py's TEST_SHAPES

DEVELOPMENT = ["bunny", "organs.py organ0-organ15", "end_offsets.py / padded.py shapes",
               "motion.py", "atlas.py", "meshes.py", "ct.py"]


def _solid(kind, rng):
    """One analytic solid (boolean volume, z first) with drawn parameters."""
    depth = 100
    z, y, x = np.mgrid[0:depth, 0:SIZE, 0:SIZE].astype(float)
    z -= depth / 2 + rng.uniform(-3, 3)
    y -= SIZE / 2 + rng.uniform(-8, 8)
    x -= SIZE / 2 + rng.uniform(-8, 8)
    if kind == "ellipsoid":
        t = rng.uniform(0.2, 0.8)
        xr, zr = np.cos(t) * x + np.sin(t) * z, -np.sin(t) * x + np.cos(t) * z
        a, b, c = rng.uniform(30, 48), rng.uniform(15, 30), rng.uniform(18, 34)
        return (xr / a) ** 2 + (y / b) ** 2 + (zr / c) ** 2 < 1
    if kind == "cylinder":
        r, h = rng.uniform(15, 35), rng.uniform(15, 38)
        return (x ** 2 + y ** 2 < r * r) & (np.abs(z) < h)
    if kind == "cone":
        r, h = rng.uniform(22, 40), rng.uniform(25, 42)
        return (np.sqrt(x ** 2 + y ** 2) < r * (h - z) / (2 * h)) & (np.abs(z) < h)
    if kind == "torus":
        big, small, t = rng.uniform(22, 34), rng.uniform(6, 12), rng.uniform(0, np.pi)
        u = np.cos(t) * x + np.sin(t) * y
        v = -np.sin(t) * x + np.cos(t) * y
        return (np.sqrt(u ** 2 + z ** 2) - big) ** 2 + v ** 2 < small ** 2
    raise ValueError(kind)


def _motion(kind, rng):
    """One moving structure, 97 slices, present in every slice; at every 8th
    slice kept each moves by about its own width or more per gap."""
    depth = 97
    y, x = np.mgrid[0:SIZE, 0:SIZE].astype(float)
    out = []
    if kind == "tube":
        r, vx, vy = rng.uniform(3, 5), rng.uniform(0.8, 1.1), rng.uniform(-0.4, 0.4)
        for z in range(depth):
            out.append((x - 10 - vx * z) ** 2 + (y - 64 - vy * (z - 48)) ** 2 < r * r)
    elif kind == "turning":
        rate, drift = np.radians(rng.uniform(2.5, 5.5)), rng.uniform(0.2, 0.5)
        a, b = rng.uniform(15, 20), rng.uniform(3.5, 5.5)
        for z in range(depth):
            t = rate * z
            cx, cy = 44 + drift * z, 64
            u = (x - cx) * np.cos(t) + (y - cy) * np.sin(t)
            v = -(x - cx) * np.sin(t) + (y - cy) * np.cos(t)
            out.append((u / a) ** 2 + (v / b) ** 2 < 1)
    elif kind == "bifurcation":
        split, speed, r = int(rng.integers(45, 60)), rng.uniform(0.8, 1.1), rng.uniform(3.5, 5)
        for z in range(depth):
            if z < split:
                out.append((x - 64) ** 2 + (y - 64) ** 2 < (r + 2) ** 2)
            else:
                d = speed * (z - split)
                out.append(((x - 61 + d) ** 2 + (y - 66) ** 2 < r * r) |
                           ((x - 67 - d) ** 2 + (y - 66) ** 2 < r * r))
    elif kind == "apart":  # two tubes moving apart, the slice's centroid still
        r, speed, gap = rng.uniform(3, 4.5), rng.uniform(0.45, 0.55), rng.uniform(14, 20)
        for z in range(depth):
            d = gap / 2 + speed * z
            out.append(((x - 64 + d) ** 2 + (y - 64) ** 2 < r * r) |
                       ((x - 64 - d) ** 2 + (y - 64) ** 2 < r * r))
    elif kind == "wall":
        thick, speed, length = rng.uniform(2.5, 4.0), rng.uniform(0.6, 1.0), rng.uniform(35, 45)
        for z in range(depth):
            out.append((np.abs(x - 18 - speed * z) < thick / 2) & (np.abs(y - 64) < length))
    else:
        raise ValueError(kind)
    return np.array(out)


def _pad(volume, rng):
    """The object's extent plus 1-16 empty slices below and enough above that
    the last slice is empty and the height is 1 + a multiple of STACK_MULTIPLE."""
    nz = np.nonzero(volume.any(axis=(1, 2)))[0]
    body = volume[nz[0]:nz[-1] + 1]
    empty = np.zeros((1,) + volume.shape[1:], bool)
    below = int(rng.integers(1, 17))
    above = int(rng.integers(1, 17))
    n = below + len(body) + above
    above += (-(n - 1)) % STACK_MULTIPLE
    return np.concatenate([np.repeat(empty, below, 0), body, np.repeat(empty, above, 0)])


def test_stacks():
    """(name, kind, boolean volume z-first) of every test stack, in order."""
    seed, found = 5000, 0
    while found < TEST_ORGANS:
        volume = organs.solid(seed, pair=found % 3 == 2)
        seed += 1
        if volume is not None:
            yield "organ-t%d" % found, "organ", _pad(volume, np.random.default_rng(seed + 50000))
            found += 1
    for i, kind in enumerate(TEST_SOLIDS):
        rng = np.random.default_rng(6000 + i)
        yield "solid-t%d" % i, kind, _pad(_solid(kind, rng), rng)
    for i, kind in enumerate(TEST_MOTIONS):
        yield "motion-t%d" % i, kind, _motion(kind, np.random.default_rng(7000 + i))


def main():
    for name, kind, volume in test_stacks():
        nz = np.nonzero(volume.any(axis=(1, 2)))[0]
        print("%-10s %-12s %3d slices, object %d..%d, largest section %d px" % (
            name, kind, len(volume), nz[0] + 1, nz[-1] + 1, volume.sum(axis=(1, 2)).max()))


if __name__ == "__main__":
    main()
