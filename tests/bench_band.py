"""make bench, the narrow band (issue 56): the same default runs with the band and with the full
grid (--band off), on stand-ins for CT organ stacks, interleaved, best of 3 on 2 threads.

    /usr/bin/python3 tests/bench_band.py LSMORPH CACHE_DIR [--base OLD_LSMORPH] [--mci MCI_DIR]

Stand-ins (made once into CACHE_DIR, a few minutes; validation/organs.py, python3-scipy):
  organs   the 16 organ stand-ins of validation/organs.py (128 x 128, 40 to 65 slices, cut to
           the organ and one empty slice either side), every 4th slice kept;
  512^2    two CT liver-sized ones: organ0 and organ5 scaled 4x in-plane and 2x along z
           (about 220 x 190 px, 88 and 100 slices) in a 512 x 512 field of view, every 4th.
Every run is `lsmorph reconstruct KEPT -o OUT --heights-from-names --threads 2` with the
default outputs (volume, slice PNGs, previews): end to end.  Per set: wall and CPU seconds
(best of 3, runs interleaved), the cell updates and band share from run.json (deterministic),
and the band's cells per second of solver time.  --base: the same with an older build (the
build before the band).  --mci: ITK's MorphologicalContourInterpolator (validation/mci.mjs
installed in MCI_DIR with its npm package) on the same kept slices as a label volume, once.
"""
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "validation"))

KEEP = 4


def make_stacks(cache):
    """Writes CACHE/<set>/<name>/kept (every KEEP-th slice, numbered as in the stack) once."""
    import organs
    import padded
    import vlib
    from scipy import ndimage

    done = os.path.join(cache, "done")
    if os.path.exists(done):
        return
    shutil.rmtree(cache, ignore_errors=True)

    def write(group, name, stack):
        d = os.path.join(cache, group, name, "kept")
        os.makedirs(d)
        for i in range(0, len(stack), KEEP):
            vlib.write_mask(os.path.join(d, "%04d.png" % (i + 1)), stack[i])

    volumes = {}
    for name, volume in organs.organs():
        volumes[name] = volume
        write("organs", name, padded.cut(volume))
    for source in ("organ0", "organ5"):
        v = volumes[source]
        z, y, x = (np.nonzero(v.any(axis=axes))[0] for axes in ((1, 2), (0, 2), (0, 1)))
        v = v[z[0]:z[-1] + 1, y[0]:y[-1] + 1, x[0]:x[-1] + 1].astype(np.float32)
        big = ndimage.zoom(v, (2, 4, 4), order=1) > 0.5
        field = np.zeros((big.shape[0], 512, 512), bool)
        oy, ox = (512 - big.shape[1]) // 2, (512 - big.shape[2]) // 2 - 60
        field[:, oy:oy + big.shape[1], ox:ox + big.shape[2]] = big
        write("512", source + "-512", padded.cut(field))
    open(done, "w").close()


def run(cmd):
    """(wall, CPU) seconds of one command."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if r.returncode != 0:
        sys.exit("bench_band: %s failed: %s" % (" ".join(cmd[:3]), r.stderr[-400:]))
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main():
    lsm, cache = sys.argv[1:3]
    opts = dict(zip(sys.argv[3::2], sys.argv[4::2]))
    make_stacks(cache)
    variants = [("band", lsm, []), ("full grid", lsm, ["--band", "off"])]
    if "--base" in opts:
        variants.append(("before the band", opts["--base"], []))
    # what is not the morph nor the previews: reading, signed distances, z-profile, the volume
    variants.append(("floor", lsm, ["--method", "blend", "--no-preview", "--no-slices"]))
    work = tempfile.mkdtemp(prefix="lsmorph-bench-band.")
    try:
        for group in ("organs", "512"):
            names = sorted(os.listdir(os.path.join(cache, group)))
            best = {v[0]: [float("inf"), float("inf")] for v in variants}
            totals = {}
            for _ in range(3):
                for label, exe, extra in variants:
                    wall = cpu = 0.0
                    updates = full = 0
                    seconds = 0.0
                    for name in names:
                        out = os.path.join(work, "out")
                        shutil.rmtree(out, ignore_errors=True)
                        w, c = run([exe, "reconstruct", os.path.join(cache, group, name, "kept"),
                                    "-o", out, "--heights-from-names", "-q", "--threads", "2"]
                                   + extra)
                        wall += w
                        cpu += c
                        t = json.load(open(os.path.join(out, "run.json")))["totals"]
                        updates += t["cell_updates"]
                        seconds += t["seconds"]
                        share = t.get("band_share")
                        full += int(round(t["cell_updates"] / share)) if share else t["cell_updates"]
                    best[label] = [min(best[label][0], wall), min(best[label][1], cpu)]
                    totals[label] = (updates, full, seconds)
            print("%s (%d stacks, every %dth slice, default outputs, 2 threads; best of 3):"
                  % ("organ stand-ins, 128^2" if group == "organs" else "CT liver-sized, 512^2",
                     len(names), KEEP))
            for label, _, _ in variants:
                if label == "floor":
                    continue
                updates, full, seconds = totals[label]
                print("  %-16s %7.2f s wall, %7.2f s CPU, %12d cell updates (band share %.3f), "
                      "%.3g cells/s of solver time" % (label, best[label][0], best[label][1],
                                                       updates, updates / full, updates / seconds))
            b, f = best["band"], best["full grid"]
            ub, uf = totals["band"][0], totals["full grid"][0]
            print("  band against the full grid: %.2fx wall, %.2fx CPU, %.1fx fewer cell updates "
                  "(target >= 5x): %s" % (f[0] / b[0], f[1] / b[1], uf / ub,
                                          "PASS" if uf / ub >= 5 else "FAIL"))
            if "before the band" in best:
                o = best["before the band"]
                print("  band against the build before it: %.2fx wall, %.2fx CPU (target >= 3x): %s"
                      % (o[0] / b[0], o[1] / b[1], "PASS" if o[0] / b[0] >= 3 else "FAIL"))
            fl = best["floor"]
            print("  floor (--method blend --no-preview --no-slices: no morph, no pictures): "
                  "%.2f s wall, %.2f s CPU" % (fl[0], fl[1]))
            if "before the band" in best:
                print("  3x the build before the band is %.2f s wall: %s the floor"
                      % (o[0] / 3, "below" if o[0] / 3 < fl[0] else "above"))
            if "--mci" in opts:
                mci = 0.0
                for name in names:
                    mci += run_mci(opts["--mci"], os.path.join(cache, group, name, "kept"), work)
                print("  ITK MorphologicalContourInterpolator (itk-wasm, node), the same slices: "
                      "%.2f s wall; band %.1fx faster (stretch target 20x)" % (mci, mci / b[0]))
    finally:
        shutil.rmtree(work, ignore_errors=True)


def run_mci(mci_dir, kept, work):
    """Wall seconds of MCI (node, reading and writing raw files) on the kept slices as a label
    volume: the slices between them empty, label 1 on the kept ones."""
    sys.path.insert(0, os.path.join(HERE, "..", "validation"))
    import vlib
    files = sorted(os.listdir(kept))
    numbers = [int(f.split(".")[0]) for f in files]
    first = vlib.read_mask(os.path.join(kept, files[0]))
    volume = np.zeros((numbers[-1] - numbers[0] + 1,) + first.shape, np.uint8)
    for n, f in zip(numbers, files):
        volume[n - numbers[0]] = vlib.read_mask(os.path.join(kept, f))
    raw, out = os.path.join(work, "in.raw"), os.path.join(work, "mci.raw")
    volume.tofile(raw)
    nz, ny, nx = volume.shape
    wall, _ = run(["node", os.path.join(mci_dir, "mci.mjs"), raw, out, str(nx), str(ny), str(nz),
                   "1", "1", "1", "2"])
    return wall


if __name__ == "__main__":
    main()
