#!/usr/bin/env python3
"""Fill a label drawn on some slices of a NIfTI volume, and write it back in the volume's grid.

  sparse_labels.py LABELS.nii[.gz] OUT.nii[.gz] [--label L] [--axis A] [--slices LIST]
                   [--lsmorph PATH] [--keep DIR] [-- LSMORPH_OPTIONS...]

The usual case: a structure segmented on every few CT or MRI slices (ITK-SNAP, 3D Slicer),
saved as a label volume whose other slices are empty.  This script
  1. takes the slices of label L (default: any non-zero label) across axis A (default: the
     axis with the largest voxel spacing, the slice direction of a scan; 2 on ties);
  2. picks the drawn slices: with --slices (comma-separated slice numbers from 0, ranges
     a:b or a:b:step with b included; empty ones mark where the structure is known to be
     absent), else every slice where the label is present plus, beyond each end, the slice one typical step
     (the median step between drawn slices) further out, empty, when the volume has it:
     without it nothing would tell lsmorph where the structure ends;
  3. writes them as PNG masks with their heights in the volume's units (mm) and runs
     `lsmorph reconstruct --pixel-size SX --dz SZ --values mask`, so every output slice lies
     on a slice of the volume and the drawn slices come back exactly;
  4. writes OUT as a uint8 volume with the input's header and affine: L (1 with no --label)
     where the filled structure is, 0 elsewhere, for the slices from the first to the last
     picked one (slices outside that range are 0).

The in-plane voxel spacing must be square (lsmorph takes one pixel size); resample first
otherwise.  Options after "--" go to lsmorph (for example `-- --method pls --threads 4`).
Needs nibabel and numpy (Debian: python3-nibabel, python3-numpy).  Exit status 0, 1 on an
error ("sparse_labels.py: error: ..."), 2 on a usage error.
"""
import argparse
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib

import numpy as np


def fail(message, status=1):
    print("sparse_labels.py: error: %s" % message, file=sys.stderr)
    sys.exit(status)


def write_png(path, mask):
    """An 8-bit grayscale PNG of a boolean array (rows, columns): 255 inside."""
    h, w = mask.shape
    rows = (mask.astype(np.uint8) * 255)
    raw = b"".join(b"\x00" + rows[j].tobytes() for j in range(h))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def parse_slices(text, count):
    picked = set()
    for part in text.split(","):
        part = part.strip()
        try:
            if ":" in part:
                fields = [int(v) for v in part.split(":")]
                if len(fields) not in (2, 3) or (len(fields) == 3 and fields[2] <= 0):
                    raise ValueError
                picked.update(range(fields[0], fields[1] + 1, fields[2] if len(fields) == 3 else 1))
            else:
                picked.add(int(part))
        except ValueError:
            fail("--slices: '%s' is not a slice number or a range a:b[:step]" % part, 2)
    bad = [k for k in picked if not 0 <= k < count]
    if bad:
        fail("--slices: %d is outside 0 .. %d" % (bad[0], count - 1), 2)
    return sorted(picked)


def drawn_slices(present):
    """The slices where the label is, and one typical step beyond each end, empty."""
    drawn = [k for k, p in enumerate(present) if p]
    if len(drawn) < 2:
        fail("the label is on %d slice%s: at least two are needed"
             % (len(drawn), "" if len(drawn) == 1 else "s"))
    step = int(np.median(np.diff(drawn)))
    picked = list(drawn)
    if drawn[0] - step >= 0:
        picked.insert(0, drawn[0] - step)
    if drawn[-1] + step < len(present):
        picked.append(drawn[-1] + step)
    return picked


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        extra = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("labels")
    ap.add_argument("out")
    ap.add_argument("--label", type=int, default=None, help="the label to fill (default: any non-zero)")
    ap.add_argument("--axis", type=int, choices=(0, 1, 2), default=None,
                    help="slice axis (default: the one with the largest voxel spacing)")
    ap.add_argument("--slices", default=None, help="the drawn slices, e.g. 10:60:5,63 (b included)")
    ap.add_argument("--lsmorph", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                      "..", "build", "lsmorph"))
    ap.add_argument("--keep", default=None, help="keep lsmorph's input and output in this folder")
    args = ap.parse_args(argv)

    value = args.label if args.label is not None else 1
    if not 0 < value < 256:
        fail("--label %d does not fit the uint8 output (1 .. 255)" % value, 2)
    try:
        import nibabel
    except ImportError:
        fail("needs nibabel (Debian: python3-nibabel)")
    try:
        image = nibabel.load(args.labels)
        labels = np.asanyarray(image.dataobj)
    except Exception as e:  # nibabel raises several kinds
        fail("%s: cannot read: %s" % (args.labels, e))
    if labels.ndim == 4 and labels.shape[3] == 1:
        labels = labels[..., 0]
    if labels.ndim != 3:
        fail("%s: a 3D volume is needed, this one has shape %s" % (args.labels, labels.shape))
    zooms = [float(v) for v in image.header.get_zooms()[:3]]
    axis = args.axis if args.axis is not None else max((zooms[a], a) for a in (0, 1, 2))[1]
    plane = [a for a in (0, 1, 2) if a != axis]
    sx, sy, sz = zooms[plane[0]], zooms[plane[1]], zooms[axis]
    if abs(sx - sy) > 1e-6 * max(sx, sy):
        fail("%s: in-plane spacing %g x %g is not square; resample the volume first"
             % (args.labels, sx, sy))
    inside = labels == args.label if args.label is not None else labels != 0
    stack = np.moveaxis(inside, axis, 0)  # (slice, i, j): slice k is stack[k]
    present = stack.reshape(stack.shape[0], -1).any(axis=1)
    picked = parse_slices(args.slices, len(present)) if args.slices else drawn_slices(present)
    if len(picked) < 2:
        fail("--slices names %d slice: at least two are needed" % len(picked), 2)

    work = args.keep or tempfile.mkdtemp(prefix="sparse-labels-")
    try:
        src = os.path.join(work, "slices")
        out = os.path.join(work, "out")
        os.makedirs(src, exist_ok=True)
        for n, k in enumerate(picked):
            # PNG rows run along the second in-plane axis, columns along the first
            write_png(os.path.join(src, "%05d.png" % n), stack[k].T)
        with open(os.path.join(work, "heights.txt"), "w") as f:
            f.write("".join("%.17g\n" % (k * sz) for k in picked))
        cmd = [args.lsmorph, "reconstruct", src, "-o", out, "--heights", os.path.join(work, "heights.txt"),
               "--pixel-size", repr(sx), "--dz", repr(sz), "--values", "mask", "--format", "raw",
               "--no-preview", "--no-slices"] + extra
        run = subprocess.run(cmd)
        if run.returncode != 0:
            fail("lsmorph failed (exit %d): %s" % (run.returncode, " ".join(cmd)))
        import json
        meta = json.load(open(os.path.join(out, "volume.json")))
        nx, ny, nz = meta["sizes"]
        filled = np.fromfile(os.path.join(out, "volume.raw"), np.uint8).reshape(nz, ny, nx)
        if nz != picked[-1] - picked[0] + 1:
            fail("lsmorph wrote %d slices, expected %d (slices %d .. %d)"
                 % (nz, picked[-1] - picked[0] + 1, picked[0], picked[-1]))
        result = np.zeros(stack.shape, np.uint8)
        result[picked[0]:picked[-1] + 1] = np.where(filled.transpose(0, 2, 1) == 255, value, 0)
        header = image.header.copy()
        header.set_data_dtype(np.uint8)
        header["scl_slope"], header["scl_inter"] = 1, 0
        nibabel.save(type(image)(np.moveaxis(result, 0, axis), image.affine, header), args.out)
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    print("sparse_labels.py: %d drawn slices (%d .. %d along axis %d) filled into %s"
          % (len(picked), picked[0], picked[-1], axis, args.out))


if __name__ == "__main__":
    main()
