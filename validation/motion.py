"""The motion set: structures that move, turn or branch between the kept slices.

Every slice interpolator fails the same way on these: a section that moves by
more than its own width between two kept slices is interpolated to nothing, or
shrinks away and grows again beside.  Each stack is 97 slices of 128 x 128, the
structure present in every slice (no ends), so the held-out scores measure only
how the gaps follow the motion:

  tilted-tube    a disc (radius 6) whose centre moves 1.1 px per slice in x and
                 0.5 in y: 9.7 px per gap kept every 8th, against its 12 px width
  curved-tube    a disc (radius 6) along a helix-like curve, up to 2.3 px per slice
  turning        a thin ellipse (18 x 4.5 px) turning 4 degrees per slice while
                 it drifts 0.4 px per slice: its tips sweep 10 px per slice kept every 8th
  bifurcation    a tube (radius 7) that splits at slice 40 into two (radius 5)
                 whose centres diverge at 1.3 px per slice each
  wall           a straight wall 3 px thick, 88 px long, moving 0.9 px per slice
                 across itself: more than its thickness per gap kept every 4th
  arc-wall       a curved wall (a third of a ring, 3.5 px thick) moving 0.8 px per
                 slice along x and 0.5 along y
  drifting-pair  two discs (radii 8 and 5) 30 px apart that drift together by
                 0.9 px per slice
  tube-beside-body  a tube (radius 5) moving 1 px per slice past a still body
                 (radius 22): the slice's centroid barely moves
  growing-tube   a tube moving 1.2 px per slice whose radius grows from 3.5 to 9.3
  fast-turning   a thin ellipse (20 x 5 px) turning 6 degrees per slice about a
                 point 14 px away: 48 degrees per gap kept every 8th
  hinge          a wall 4 px thick and 80 px long swinging 1.2 degrees per slice
                 about a hinge on a still disc: its free end moves 1.7 px per slice
  thin-tube      a tube of radius 2.5 moving 1.35 px per slice: more than its width
                 per gap kept every 4th
  crossing-tubes two tubes (radius 4) moving 1 px per slice in opposite directions,
                 crossing mid-stack
  fast-split     a tube (radius 6) splitting at slice 30 into two (radius 4) whose
                 centres move apart at 3.6 px per slice
  wall-beside-wall  a wall 3 px thick moving 0.8 px per slice toward a still one

These fifteen are the development half of the motion set (issue 53's field was
tuned on them).  The test half, frozen 2026-12-02 before any run looked at it,
is eight fresh draws of the hard kinds with sizes and speeds from seeds 8000
onward (test_shapes(); validation/split.py declares both halves):

  t-tilted-tube    a disc (radius 3-6) drifting 0.8-1.3 px per slice in x and
                   up to 0.6 in y
  t-curved-tube    a disc (radius 4-6) on a Lissajous curve, up to 2.5 px per slice
  t-turning        a thin ellipse (half axes 14-20 x 3.5-5) turning 3-5 degrees
                   per slice while it drifts
  t-fast-turning   a thin ellipse (16-22 x 4-5.5) turning 5-7 degrees per slice
                   about a point 8-16 px away
  t-hinge          a wall (3-5 px thick, 60-72 long) swinging 0.9-1.3 degrees per
                   slice about a hinge on a still disc
  t-bifurcation    a tube (radius 5-7) drifting 0.3-0.6 px per slice, splitting at
                   slice 40-55 into two whose centres diverge at 0.8-1.1 px per
                   slice each
  t-fast-split     the same splitting at slice 68-74 into two (radius 3.5-5) moving
                   apart at 3-4 px per slice
  t-wall           a wall 2.5-3.5 px thick moving 0.7-1.0 px per slice across itself

Every k-th slice is kept (k = 4 and 8 by default), the gaps are reconstructed
with `lsmorph reconstruct --spacing k` and the held-out slices are scored with
`lsmorph score`, as in padded.py.  Deterministic; no download; seconds.

    /usr/bin/python3 validation/motion.py [BUILD_DIR] [--strides 4,8]
        [--split dev|test|all] [--shapes tilted-tube,...] [--methods ls,blend,pchip-drop]
        [-- EXTRA LSMORPH OPTIONS]

--split picks a half (default dev, the fifteen above); --shapes names stacks
of either half.

Prints a Markdown row per shape, stride and method (pooled Dice, pooled HD95,
mean per-slice Dice, mean HD95, slices empty on one side), then the means.
"""
import sys

import numpy as np

import end_offsets as eo
import padded

SIZE, DEPTH = 128, 97
SHAPES = ["tilted-tube", "curved-tube", "turning", "bifurcation", "wall", "arc-wall",
          "drifting-pair", "tube-beside-body", "growing-tube", "fast-turning", "hinge", "thin-tube",
          "crossing-tubes", "fast-split", "wall-beside-wall"]


def disc(x, y, cx, cy, r):
    return (x - cx) ** 2 + (y - cy) ** 2 < r * r


def section(name, z, x, y):
    """The boolean section of shape `name` at slice z on the pixel grid (x, y)."""
    if name == "tilted-tube":
        return disc(x, y, 11 + 1.1 * z, 40 + 0.5 * z, 6)
    if name == "curved-tube":
        a = z / (DEPTH - 1) * 1.6 * np.pi
        return disc(x, y, 64 + 44 * np.sin(a), 64 + 34 * np.cos(1.3 * a), 6)
    if name == "turning":
        t = np.radians(4.0 * z)
        cx, cy = 44 + 0.4 * z, 64
        u = (x - cx) * np.cos(t) + (y - cy) * np.sin(t)
        v = -(x - cx) * np.sin(t) + (y - cy) * np.cos(t)
        return (u / 18) ** 2 + (v / 4.5) ** 2 < 1
    if name == "bifurcation":
        if z < 40:
            return disc(x, y, 64, 64 + 0.2 * z, 7)
        d = 1.3 * (z - 40)
        return disc(x, y, 64 - 3 - d, 72, 5) | disc(x, y, 64 + 3 + d, 72, 5)
    if name == "wall":
        x0 = 20 + 0.9 * z
        return (np.abs(x - x0) < 1.5) & (np.abs(y - 64) < 44)
    if name == "arc-wall":
        cx, cy = 40 + 0.8 * z, 40 + 0.5 * z
        r = np.hypot(x - cx, y - cy)
        ang = np.degrees(np.arctan2(y - cy, x - cx)) % 360
        return (np.abs(r - 30) < 1.75) & (ang > 20) & (ang < 140)
    if name == "drifting-pair":
        return disc(x, y, 20 + 0.9 * z, 50, 8) | disc(x, y, 20 + 0.9 * z, 80, 5)
    if name == "tube-beside-body":
        return disc(x, y, 34, 64, 22) | disc(x, y, 70 + 0.5 * z, 20 + 0.9 * z, 5)
    if name == "growing-tube":
        return disc(x, y, 16 + 1.0 * z, 30 + 0.7 * z, 3.5 + 0.06 * z)
    if name == "fast-turning":
        t = np.radians(6.0 * z)
        cx, cy = 64 + 14 * np.cos(t), 64 + 14 * np.sin(t)
        u = (x - cx) * np.cos(t) + (y - cy) * np.sin(t)
        v = -(x - cx) * np.sin(t) + (y - cy) * np.cos(t)
        return (u / 20) ** 2 + (v / 5) ** 2 < 1
    if name == "hinge":
        t = np.radians(20 + 1.2 * z)
        hx, hy = 24, 104
        u = (x - hx) * np.cos(t) - (y - hy) * np.sin(t)
        v = (x - hx) * np.sin(t) + (y - hy) * np.cos(t)
        door = (u > 0) & (u < 80) & (np.abs(v) < 2)
        return door | disc(x, y, hx, hy, 9)
    if name == "thin-tube":
        return disc(x, y, 14 + 1.0 * z, 20 + 0.9 * z, 2.5)
    if name == "crossing-tubes":
        return disc(x, y, 16 + 1.0 * z, 56, 4) | disc(x, y, 112 - 1.0 * z, 72, 4)
    if name == "fast-split":
        if z < 30:
            return disc(x, y, 64, 64, 6)
        d = 1.8 * (z - 30)
        return disc(x, y, 64 - 2 - d, 64 - 0.5 * d, 4) | disc(x, y, 64 + 2 + d, 64 - 0.5 * d, 4)
    if name == "wall-beside-wall":
        still = (np.abs(x - 100) < 1.5) & (np.abs(y - 64) < 40)
        moving = (np.abs(x - 10 - 0.8 * z) < 1.5) & (np.abs(y - 64) < 40)
        return still | moving
    raise ValueError(name)


TEST_KINDS = ["tilted-tube", "curved-tube", "turning", "fast-turning", "hinge", "bifurcation",
              "fast-split", "wall"]
TEST_SHAPES = ["t-" + k for k in TEST_KINDS]


def ellipse(x, y, cx, cy, t, a, b):
    u = (x - cx) * np.cos(t) + (y - cy) * np.sin(t)
    v = -(x - cx) * np.sin(t) + (y - cy) * np.cos(t)
    return (u / a) ** 2 + (v / b) ** 2 < 1


def test_section(kind, p, z, x, y):
    """The section at slice z of a test stack of `kind` with drawn parameters p."""
    if kind == "tilted-tube":
        return disc(x, y, 64 + p["vx"] * (z - 48), 64 + p["vy"] * (z - 48), p["r"])
    if kind == "curved-tube":
        a = z / (DEPTH - 1) * p["turns"] * np.pi
        return disc(x, y, 64 + p["ax"] * np.sin(a + p["phase"]),
                    64 + p["ay"] * np.cos(p["ratio"] * a), p["r"])
    if kind == "turning":
        return ellipse(x, y, 64 + p["drift"] * (z - 48), 64, np.radians(p["rate"] * z), p["a"], p["b"])
    if kind == "fast-turning":
        t = np.radians(p["rate"] * z)
        return ellipse(x, y, 64 + p["arm"] * np.cos(t), 64 + p["arm"] * np.sin(t), t, p["a"], p["b"])
    if kind == "hinge":
        t = np.radians(p["start"] + p["rate"] * z)
        hx, hy = 24, 104
        u = (x - hx) * np.cos(t) - (y - hy) * np.sin(t)
        v = (x - hx) * np.sin(t) + (y - hy) * np.cos(t)
        return ((u > 0) & (u < p["length"]) & (np.abs(v) < p["thick"] / 2)) | disc(x, y, hx, hy, 9)
    if kind in ("bifurcation", "fast-split"):  # a drifting trunk, then two diverging branches
        zs = min(z, p["split"])
        cx, cy = 64 - p["drift"] * (p["split"] - zs), 64 - 0.5 * p["drift"] * (p["split"] - zs)
        if z < p["split"]:
            return disc(x, y, cx, cy, p["r"])
        d = p["speed"] * (z - p["split"])
        return (disc(x, y, cx - 0.4 * p["r"] - 0.9 * d, cy + 0.4 * d, p["rb"])
                | disc(x, y, cx + 0.4 * p["r"] + 0.9 * d, cy + 0.4 * d, p["rb"]))
    if kind == "wall":
        return (np.abs(x - 20 - p["speed"] * z) < p["thick"] / 2) & (np.abs(y - 64) < 40)
    raise ValueError(kind)


def test_params(kind, rng):
    """The drawn sizes and speeds of a test stack (every structure stays in the image)."""
    u = rng.uniform
    if kind == "tilted-tube":
        return {"r": u(3, 6), "vx": u(0.8, 1.1), "vy": u(-0.6, 0.6)}
    if kind == "curved-tube":
        return {"r": u(4, 6), "turns": u(1.4, 1.8), "phase": u(0, np.pi), "ax": u(36, 46),
                "ay": u(28, 40), "ratio": u(1.1, 1.5)}
    if kind == "turning":
        return {"a": u(14, 20), "b": u(3.5, 5), "rate": u(3, 5), "drift": u(0.2, 0.4)}
    if kind == "fast-turning":
        return {"a": u(16, 22), "b": u(4, 5.5), "rate": u(5, 7), "arm": u(8, 16)}
    if kind == "hinge":
        return {"length": u(60, 72), "thick": u(3, 5), "rate": u(0.9, 1.3), "start": u(-10, 10)}
    if kind == "bifurcation":
        r = u(5, 7)
        return {"r": r, "rb": 0.75 * r, "speed": u(0.8, 1.1), "split": int(rng.integers(40, 56)),
                "drift": u(0.3, 0.6)}
    if kind == "fast-split":
        r = u(5, 6.5)
        return {"r": r, "rb": u(3.5, 5), "speed": u(1.5, 2.0), "split": int(rng.integers(68, 75)),
                "drift": u(0.3, 0.6)}
    if kind == "wall":
        return {"thick": u(2.5, 3.5), "speed": u(0.7, 0.95)}
    raise ValueError(kind)


def stack(name):
    y, x = np.mgrid[0:SIZE, 0:SIZE].astype(float)
    if name in TEST_SHAPES:
        kind = name[2:]
        p = test_params(kind, np.random.default_rng(8000 + TEST_KINDS.index(kind)))
        return np.array([test_section(kind, p, z, x, y) for z in range(DEPTH)])
    return np.array([section(name, z, x, y) for z in range(DEPTH)])


def main():
    lsm, opts, extra = eo.parse_args(sys.argv[1:], {
        "--strides": "4,8", "--methods": "ls,blend,pchip-drop", "--split": "dev",
        "--shapes": ""}, "motion")
    halves = {"dev": SHAPES, "test": TEST_SHAPES, "all": SHAPES + TEST_SHAPES}
    if opts["--split"] not in halves:
        raise SystemExit("motion: --split is dev, test or all")
    wanted = opts["--shapes"].split(",") if opts["--shapes"] else halves[opts["--split"]]
    unknown = [s for s in wanted if s not in SHAPES + TEST_SHAPES]
    if unknown:
        raise SystemExit("motion: unknown shape %s (%s)" % (unknown[0], ", ".join(SHAPES + TEST_SHAPES)))
    opts.setdefault("--offsets", "first")
    opts.setdefault("--margin", "0")
    padded.score_table(lsm, ((s, stack(s)) for s in wanted), opts, extra)


if __name__ == "__main__":
    main()
