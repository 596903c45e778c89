"""The label volume of tests/bench_fill.sh, and its scores.

    bench_fill.py DIR                     writes DIR/truth.nrrd (every slice), DIR/drawn.nrrd and
                                          DIR/drawn.raw (every 5th slice; raw uint8, i fastest)
    bench_fill.py DIR --score LSM RESULT  lsmorph score of RESULT (.nrrd, or .raw as drawn.raw)
                                          against the truth on the slices filled

512 x 512 x 200 voxels of 0.8 x 0.8 x 2.5 mm holding 6 organ-like structures of CT sizes: two
large lobed ones, a tube along the whole stack, two kidneys side by side, one drifting.
"""
import json
import subprocess
import sys

import numpy as np

SHAPE = (512, 512, 200)
SPACING = (0.8, 0.8, 2.5)
STEP = 5
# label, centre x, y, z (mm), radii x, y, z (mm), drift of the centre in x, y per mm of z
ORGANS = [(1, 150, 200, 250, 90, 70, 110, 0.10, 0.0),
          (2, 280, 190, 230, 45, 40, 70, 0.0, 0.05),
          (3, 230, 260, 250, 12, 12, 240, 0.02, 0.0),
          (4, 160, 300, 180, 28, 35, 55, 0.0, 0.0),
          (5, 300, 300, 185, 28, 35, 55, 0.0, 0.0),
          (6, 330, 230, 260, 40, 55, 60, -0.1, 0.0)]


def volume():
    lab = np.zeros(SHAPE, np.uint8)
    y, x = np.mgrid[0:SHAPE[1], 0:SHAPE[0]]
    px, py = x * SPACING[0], y * SPACING[1]
    for k in range(SHAPE[2]):
        z = k * SPACING[2]
        plane = lab[:, :, k]
        for (l, cx, cy, cz, rx, ry, rz, dx, dy) in ORGANS:
            t = (z - cz) / rz
            if abs(t) >= 1:
                continue
            s = np.sqrt(1 - t * t)
            inside = ((px - cx - dx * (z - cz)) / (rx * s)) ** 2 + ((py - cy - dy * (z - cz)) / (ry * s)) ** 2 < 1
            plane[inside.T & (plane == 0)] = l
    return lab


def write_nrrd(path, lab, raw_name=None):
    head = ["NRRD0004", "type: uchar", "dimension: 3", "space: left-posterior-superior",
            "sizes: %d %d %d" % lab.shape,
            "space directions: (%g,0,0) (0,%g,0) (0,0,%g)" % SPACING,
            "kinds: domain domain domain", "encoding: raw", "space origin: (0,0,0)"]
    if raw_name:
        head.append("data file: " + raw_name)
    data = b"" if raw_name else lab.tobytes(order="F")
    open(path, "wb").write(("\n".join(head) + ("\n" if raw_name else "\n\n")).encode() + data)


def drawn_slices(lab):
    held = [k for k in range(0, SHAPE[2], STEP) if lab[:, :, k].any()]
    out = ([held[0] - STEP] if held[0] >= STEP else []) + held
    return out + ([held[-1] + STEP] if held[-1] + STEP < SHAPE[2] else [])


def main():
    d = sys.argv[1]
    if len(sys.argv) > 2 and sys.argv[2] == "--score":
        lsm, result = sys.argv[3], sys.argv[4]
        if result.endswith(".raw"):
            write_nrrd(result + ".nhdr", np.zeros(SHAPE, np.uint8), result.rsplit("/", 1)[-1])
            result += ".nhdr"
        lab = np.fromfile(d + "/drawn.raw", np.uint8).reshape(SHAPE[::-1]).T
        r = subprocess.run([lsm, "score", d + "/truth.nrrd", result, "--axis", "k", "--slices",
                            ",".join(map(str, drawn_slices(lab)))], capture_output=True, text=True)
        if r.returncode:
            sys.exit("bench_fill: score failed: " + r.stderr)
        res = json.loads(r.stdout)
        print("  against the truth: mean Dice %.4f, mean HD95 %.2f mm, mean surface distance %.3f mm "
              "(%d labels, %d slices filled)" % (res["mean"]["dice"], res["mean"]["hd95"],
                                                 res["mean"]["mean_surface"], len(res["labels"]),
                                                 res["held_out"]))
        return
    lab = volume()
    write_nrrd(d + "/truth.nrrd", lab)
    drawn = np.zeros_like(lab)
    drawn[:, :, ::STEP] = lab[:, :, ::STEP]
    write_nrrd(d + "/drawn.nrrd", drawn)
    open(d + "/drawn.raw", "wb").write(drawn.tobytes(order="F"))


if __name__ == "__main__":
    main()
