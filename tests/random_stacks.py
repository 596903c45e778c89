"""Random stacks through lsmorph (tests/test_random_stacks.sh): robustness on input no
hand-written test foresaw.

  random_stacks.py LSMORPH TMPDIR CASES SEED MAX_SIZE

Each case draws 2 to 9 slices of 1 to MAX_SIZE - 1 pixels a side, each slice one of: empty,
full, one pixel, one row, a checkerboard, salt noise, a disc (possibly cut by the border),
an annulus with an island, thresholded smooth noise; uneven integer heights (steps 1 to 19);
and random options (method, scheme, integrator, alignment, profile, ends, reinitialisation,
outline input, threads, mesh).  Checks, one line each ("ok - " / "FAIL - "):
  - lsmorph exits 0, or 1 / 2 with a one-line "lsmorph: error: " message;
  - nothing on stderr from a sanitizer (build-san: make test SANITIZE=1);
  - volume.raw is finite, its size the one volume.json states;
  - every input slice comes back exactly (phi <= 0 is the mask) at its height (masks).
Needs only numpy (Debian python3-numpy); PNGs are written with zlib.
"""
import json
import os
import shutil
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from formats_check import write_png  # noqa: E402  (the tiny 8-bit gray PNG writer)

FAILED = [0]


def report(good, what):
    if not good:
        FAILED[0] += 1
    print(("ok - " if good else "FAIL - ") + what, flush=True)


def smooth_noise(rng, w, h):
    """Uniform noise low-pass filtered by a Gaussian of 0.5 to 4 px (periodic, by FFT)."""
    sigma = rng.uniform(0.5, 4.0)
    ky = np.fft.fftfreq(h)[:, None]
    kx = np.fft.fftfreq(w)[None, :]
    gain = np.exp(-2.0 * (np.pi * sigma) ** 2 * (kx * kx + ky * ky))
    return np.real(np.fft.ifft2(np.fft.fft2(rng.random((h, w))) * gain))


def shape(rng, w, h):
    kind = int(rng.integers(0, 9))
    y, x = np.mgrid[0:h, 0:w]
    m = np.zeros((h, w), bool)
    if kind == 1:
        m[:] = True
    elif kind == 2:
        m[rng.integers(0, h), rng.integers(0, w)] = True
    elif kind == 3:
        m[rng.integers(0, h), :] = True
    elif kind == 4:
        m = ((x // int(rng.integers(1, 4)) + y // int(rng.integers(1, 4))) % 2) == 0
    elif kind == 5:
        m = rng.random((h, w)) < rng.random()
    elif kind == 6:
        cx, cy = rng.uniform(-5, w + 5), rng.uniform(-5, h + 5)
        r = rng.uniform(0.3, max(w, h))
        m = (x - cx) ** 2 + (y - cy) ** 2 < r * r
    elif kind == 7:
        r = np.hypot(x - w / 2 - rng.normal(), y - h / 2 - rng.normal())
        big = rng.uniform(0.5, min(w, h) / 2 + 1)
        m = ((r < big) & (r > big * rng.uniform(0.2, 0.8))) | (r < big * rng.uniform(0.0, 0.2))
    elif kind == 8:
        n = smooth_noise(rng, w, h)
        m = n > np.quantile(n, rng.uniform(0.3, 0.95))
    return m


def options(rng):
    opts = []
    pick = lambda p, name, values: opts.extend([name, str(rng.choice(values))]) if rng.random() < p else None
    pick(0.3, "--method", ["pls", "blend"])
    pick(0.3, "--scheme", ["roe-fix", "weno5"])
    pick(0.3, "--time", ["rk2", "rk3"])
    pick(0.3, "--align", ["hull", "none"])
    pick(0.3, "--interp", ["linear"])
    pick(0.3, "--ends", ["tip", "halfway"])
    pick(0.2, "--reinit-every", ["3"])
    pick(0.1, "--input", ["outline"])
    pick(0.3, "--threads", ["1", "2"])
    if rng.random() < 0.2:
        opts.append("--mesh")
    return opts


def run_case(lsm, tmp, seed, max_size):
    rng = np.random.default_rng(seed)
    w, h = int(rng.integers(1, max_size)), int(rng.integers(1, max_size))
    count = int(rng.integers(2, 10))
    src = os.path.join(tmp, "in%d" % seed)
    os.makedirs(src)
    masks = [shape(rng, w, h) for _ in range(count)]
    for k, m in enumerate(masks):
        write_png(os.path.join(src, "%02d.png" % k), [bytes(r) for r in (m * 255).astype(np.uint8)], w, h)
    heights = np.cumsum(rng.integers(1, 20, count))
    heights -= heights[0]
    with open(os.path.join(src, "heights.txt"), "w") as f:
        f.write("\n".join(str(int(v)) for v in heights) + "\n")
    opts = options(rng)
    out = os.path.join(tmp, "out%d" % seed)
    cmd = [lsm, "reconstruct", src, "-o", out, "--heights", os.path.join(src, "heights.txt"), "-q",
           "--format", "raw", "--no-preview", "--no-slices"] + opts
    what = "case %d (%dx%d, %d slices%s)" % (seed, w, h, count, (", " + " ".join(opts)) if opts else "")
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    except subprocess.TimeoutExpired:
        report(False, what + ": no result in 600 s")
        return
    err = p.stderr
    sanitizer = "runtime error" in err or "Sanitizer" in err
    report(not sanitizer, what + ": no sanitizer report" + (": " + err[-600:] if sanitizer else ""))
    if p.returncode != 0:
        clean = p.returncode in (1, 2) and err.startswith("lsmorph: error: ") and err.count("\n") == 1
        report(clean, what + ": exit %d with one error line (%s)" % (p.returncode, err.strip()[:300]))
        return
    report(True, what + ": exit 0")
    meta = json.load(open(os.path.join(out, "volume.json")))
    nx, ny, nz = meta["sizes"]
    phi = np.fromfile(os.path.join(out, "volume.raw"), "<f4")
    report(phi.size == nx * ny * nz and np.isfinite(phi).all(),
           what + ": volume.raw finite, %d samples (volume.json: %d)" % (phi.size, nx * ny * nz))
    if phi.size != nx * ny * nz or "outline" in opts:
        return
    phi = phi.reshape(nz, ny, nx)
    out_heights = [float(v) for v in open(os.path.join(out, "heights.txt"))]
    wrong = []
    for k, m in enumerate(masks):
        at = [j for j, z in enumerate(out_heights) if z == float(heights[k])]
        if not at or not np.array_equal(phi[at[0]] <= 0, m):
            wrong.append(k)
    report(not wrong, what + ": input slices back exactly" + (" (not %s)" % wrong if wrong else ""))
    shutil.rmtree(out)


def main():
    lsm, tmp, cases, seed, max_size = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
    for k in range(cases):
        run_case(lsm, tmp, seed + k, max_size)
    return 1 if FAILED[0] else 0


if __name__ == "__main__":
    sys.exit(main())
