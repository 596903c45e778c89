#!/usr/bin/env python3
"""Fill a label drawn on some slices of a NIfTI or NRRD volume, and write it back in its grid.

  sparse_labels.py LABELS.nii[.gz] OUT.nii[.gz] [--label L|all] [--axis A] [--slices LIST]
                   [--lsmorph PATH] [--keep DIR] [-- LSMORPH_OPTIONS...]
  sparse_labels.py LABELS.nrrd|LABELS.seg.nrrd OUT.nrrd|OUT.seg.nrrd [same options]

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
     `lsmorph reconstruct --pixel-size SX,SY --dz SZ --values mask`, so every output slice lies
     on a slice of the volume and the drawn slices come back exactly;
  4. writes OUT as a uint8 volume with the input's header and affine (or NRRD geometry): L (1 with no --label)
     where the filled structure is, 0 elsewhere, for the slices from the first to the last
     picked one (slices outside that range are 0).

With --label all (a multi-label atlas: several structures drawn on the same slices) every
distinct non-zero value of the volume is a label (each must be an integer 1 .. 255, the
uint8 output's range), and
  1. the drawn slices are those of --slices, else every slice where any label is present
     plus one typical step beyond each end, empty, as above; a label absent from a drawn
     slice is known to be absent there;
  2. each label in turn is filled by lsmorph, as above but with `--values sdf` (float32
     signed distance in mm, negative inside), on the drawn slices from the one before its
     first drawn slice to the one after its last (when there are such); without --slices
     that slice is at most one typical step away (a slice there holds no label: it is taken
     as drawn empty, as beyond the ends above), so that a label whose neighbours along the
     axis are far away still ends within one step.  A label on one drawn slice only, with
     no such slice on one side, is copied as drawn, with a warning;
  3. each voxel gets the label whose signed distance is the most negative there, when it is
     below 0 (a voxel outside a label's slice range counts as +inf for that label), else 0.
     The labels' regions on a drawn slice are disjoint and the signed distances exact there,
     so the drawn slices come back exactly.  Memory: the volume's labels, one float32
     volume (the running minimum), the uint8 output and one label's result at a time.
  With no options after "--" lsmorph runs with -q; one progress line per label on stderr.

NRRD (3D Slicer's labelmap .nrrd and segmentation .seg.nrrd, chosen by the file name): a
3D volume of integers or floats, raw or gzip encoded, in one file (no detached .nhdr header, no
byte or line skip); the voxel spacing of an axis is the length of its space direction (else its
'spacings' entry, else 1).  OUT is written with the input's header lines and key/value pairs in
order (space, space directions, space origin, Slicer's SegmentN_* keys, so a .seg.nrrd loads as
the same segments), with type uint8, encoding gzip and endian little.  A 4D .seg.nrrd (segments
overlapping, in layers) is refused: export a labelmap or make the segments non-overlapping.
OUT must have the input's format (NRRD to NIfTI or back is refused: their geometry conventions
differ, LPS and RAS).

The in-plane voxel spacing need not be square (lsmorph takes the pixel's width and height:
slices across the first axis of a 2.5 x 0.8 x 0.8 mm CT are 0.8 x 0.8 mm, across the second
2.5 x 0.8 mm).  Options after "--" go to lsmorph (for example `-- --method pls --threads 4`).
Needs numpy, and nibabel for NIfTI (Debian: python3-numpy, python3-nibabel).  Exit status 0, 1 on an
error ("sparse_labels.py: error: ..."), 2 on a usage error.
"""
import argparse
import gzip
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

# ---- NRRD (3D Slicer's .nrrd / .seg.nrrd): a small reader and writer ------------------------------
NRRD_TYPES = {}
for _dtype, _names in (("i1", "signed char, int8, int8_t"),
                       ("u1", "uchar, unsigned char, uint8, uint8_t"),
                       ("i2", "short, short int, signed short, signed short int, int16, int16_t"),
                       ("u2", "ushort, unsigned short, unsigned short int, uint16, uint16_t"),
                       ("i4", "int, signed int, int32, int32_t"),
                       ("u4", "uint, unsigned int, uint32, uint32_t"),
                       ("i8", "longlong, long long, long long int, signed long long, "
                              "signed long long int, int64, int64_t"),
                       ("u8", "ulonglong, unsigned long long, unsigned long long int, uint64, uint64_t"),
                       ("f4", "float"), ("f8", "double")):
    for _name in _names.split(", "):
        NRRD_TYPES[_name] = _dtype


def is_nrrd(path):
    return path.lower().endswith((".nrrd", ".nhdr"))


class Nrrd(object):
    """A NRRD file's header: magic, lines (("field", name, value), ("kv", key, value) or
    ("comment", text, None), in order), fields (lowercase name -> value) and spacings."""


def read_nrrd(path):
    """(header, labels indexed [i, j, k], the first axis the fastest in the file)."""
    if path.lower().endswith(".nhdr"):
        fail("%s: a detached NRRD header (.nhdr) is not supported; save the volume as a single "
             ".nrrd or .seg.nrrd file" % path)
    try:
        f = open(path, "rb")
    except OSError as e:
        fail("%s: cannot read: %s" % (path, e.strerror))
    with f:
        magic = f.readline().decode("latin-1").rstrip("\r\n")
        if not (magic.startswith("NRRD000") and magic[7:].isdigit()):
            fail("%s: cannot read: not a NRRD file (no NRRD000N magic line)" % path)
        hdr = Nrrd()
        hdr.magic, hdr.lines, hdr.fields = magic, [], {}
        while True:
            line = f.readline()
            if not line:
                fail("%s: the NRRD header has no blank line, so no data follows it (a detached "
                     "header?); save the volume as a single .nrrd or .seg.nrrd file" % path)
            line = line.decode("latin-1").rstrip("\r\n")
            if line == "":
                break
            if line.startswith("#"):
                hdr.lines.append(("comment", line, None))
                continue
            kv, fd = line.find(":="), line.find(": ")
            if kv > 0 and (fd < 0 or kv < fd):
                hdr.lines.append(("kv", line[:kv], line[kv + 2:]))
            elif fd > 0:
                name, value = line[:fd], line[fd + 2:].strip()
                hdr.lines.append(("field", name, value))
                hdr.fields[name.lower().replace(" ", "")] = value
            else:
                fail("%s: cannot read NRRD header line '%s'" % (path, line))
        fields = hdr.fields
        for name in ("datafile", "datafiles"):
            if name in fields:
                fail("%s: the data is in a separate file (data file: %s), not supported; save the "
                     "volume as a single .nrrd or .seg.nrrd file" % (path, fields[name]))
        for name in ("type", "dimension", "sizes", "encoding"):
            if name not in fields:
                fail("%s: the NRRD header has no '%s' field" % (path, name))
        try:
            dimension = int(fields["dimension"])
            sizes = [int(v) for v in fields["sizes"].split()]
        except ValueError:
            fail("%s: bad NRRD dimension or sizes: %s, %s" % (path, fields["dimension"], fields["sizes"]))
        if dimension == 4:
            fail("%s: a 4D NRRD (a .seg.nrrd whose segments overlap, stored as layers) is not "
                 "supported; in 3D Slicer export the segmentation as a labelmap volume, or make "
                 "the segments non-overlapping (one layer) and save again" % path)
        if dimension != 3 or len(sizes) != 3:
            fail("%s: a 3D volume is needed, this NRRD has dimension %s, sizes %s"
                 % (path, fields["dimension"], fields["sizes"]))
        kind = NRRD_TYPES.get(" ".join(fields["type"].split()).lower())
        if kind is None:
            fail("%s: NRRD type '%s' is not supported" % (path, fields["type"]))
        encoding = fields["encoding"].lower()
        if encoding not in ("raw", "gzip", "gz"):
            fail("%s: NRRD encoding '%s' is not supported (raw or gzip only); save the volume "
                 "compressed or uncompressed from 3D Slicer" % (path, fields["encoding"]))
        for name in ("byteskip", "lineskip"):
            if fields.get(name, "0").strip() != "0":
                fail("%s: NRRD %s skip %s is not supported (0 only)"
                     % (path, name[:-4], fields[name]))
        endian = fields.get("endian", "little").lower()
        if endian not in ("little", "big"):
            fail("%s: bad NRRD endian '%s'" % (path, fields["endian"]))
        dtype = np.dtype(("<" if endian == "little" else ">") + kind)
        if dtype.itemsize > 1 and "endian" not in fields:
            fail("%s: the NRRD header has no 'endian' field" % path)
        data = f.read()
    if encoding != "raw":
        try:
            data = gzip.decompress(data)
        except (OSError, EOFError, zlib.error) as e:
            fail("%s: cannot read: bad gzip data: %s" % (path, e))
    count = sizes[0] * sizes[1] * sizes[2]
    if len(data) < count * dtype.itemsize:
        fail("%s: cannot read: %d bytes of data, %d expected" % (path, len(data), count * dtype.itemsize))
    labels = np.frombuffer(data, dtype, count).reshape(sizes[::-1]).transpose(2, 1, 0)
    hdr.spacings = nrrd_spacings(path, fields)
    return hdr, labels


def nrrd_spacings(path, fields):
    """Each axis's voxel spacing: the length of its space direction, else its 'spacings'
    entry, else 1."""
    if "spacedirections" in fields:
        import re
        parts = re.findall(r"\(([^)]*)\)|(none)", fields["spacedirections"])
        if len(parts) != 3 or any(not vector for vector, _ in parts):
            fail("%s: NRRD space directions '%s': three vectors expected"
                 % (path, fields["spacedirections"]))
        try:
            return [float(np.linalg.norm([float(v) for v in vector.split(",")])) for vector, _ in parts]
        except ValueError:
            fail("%s: bad NRRD space directions '%s'" % (path, fields["spacedirections"]))
    if "spacings" in fields:
        try:
            values = [float(v) for v in fields["spacings"].split()]
        except ValueError:
            fail("%s: bad NRRD spacings '%s'" % (path, fields["spacings"]))
        if len(values) == 3:
            return [v if np.isfinite(v) and v > 0 else 1.0 for v in values]
    return [1.0, 1.0, 1.0]


def write_nrrd(hdr, data, path):
    """uint8 labels [i, j, k] as a gzip NRRD with the input's header lines and key/value pairs
    in order (its geometry too); type, encoding and endian changed, no data file or skips."""
    out = [hdr.magic if hdr.magic >= "NRRD0004" else "NRRD0004"]
    # 3D Slicer's SegmentN_Extent (i0 i1 j0 j1 k0 k1) bounds segment N, whose voxels hold
    # SegmentN_LabelValue: the filled segment may reach farther, so it is recomputed
    values = dict((name[:-len("_LabelValue")], value) for what, name, value in hdr.lines
                  if what == "kv" and name.endswith("_LabelValue"))
    for what, name, value in hdr.lines:
        if what == "kv" and name.endswith("_Extent") and name[:-len("_Extent")] in values:
            try:
                where = np.nonzero(np.asarray(data) == int(values[name[:-len("_Extent")]]))
            except ValueError:
                where = None
            if where is not None:
                value = " ".join("%d %d" % (w.min(), w.max()) if w.size else "0 -1" for w in where)
                out.append("%s:=%s" % (name, value))
                continue
        low = name.lower().replace(" ", "") if what == "field" else None
        if what == "comment":
            out.append(name)
        elif what == "kv":
            out.append("%s:=%s" % (name, value))
        elif low in ("datafile", "datafiles", "byteskip", "lineskip"):
            continue
        elif low == "type":
            out.append("%s: uint8" % name)
        elif low == "encoding":
            out.append("%s: gzip" % name)
            if "endian" not in hdr.fields:
                out.append("endian: little")
        elif low == "endian":
            out.append("%s: little" % name)
        else:
            out.append("%s: %s" % (name, value))
    with open(path, "wb") as f:
        f.write(("\n".join(out) + "\n\n").encode("latin-1"))
        f.write(gzip.compress(np.asarray(data, np.uint8).tobytes(order="F"), 6))


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


def drawn_slices(present, what="the label is"):
    """The slices where the label is, and one typical step beyond each end, empty."""
    drawn = [k for k, p in enumerate(present) if p]
    if len(drawn) < 2:
        fail("%s on %d slice%s: at least two are needed"
             % (what, len(drawn), "" if len(drawn) == 1 else "s"))
    step = int(np.median(np.diff(drawn)))
    picked = list(drawn)
    if drawn[0] - step >= 0:
        picked.insert(0, drawn[0] - step)
    if drawn[-1] + step < len(present):
        picked.append(drawn[-1] + step)
    return picked


def save(nibabel, image, data, path):
    """A uint8 volume with the input's header and affine."""
    header = image.header.copy()
    header.set_data_dtype(np.uint8)
    header["scl_slope"], header["scl_inter"] = 1, 0
    nibabel.save(type(image)(data, image.affine, header), path)


def label_arg(text):
    """--label: a label number, or 'all'."""
    if text == "all":
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError("'%s' is not a label number or 'all'" % text)


def atlas_labels(labels, name):
    """The distinct non-zero values of the volume, each an integer 1 .. 255, as ints."""
    values = np.unique(labels[labels != 0])
    if values.size == 0:
        fail("%s: no label (every voxel is 0)" % name)
    whole = np.isfinite(values) & (values == np.round(values)) if values.dtype.kind == "f" \
        else np.ones(values.shape, bool)
    bad = values[~whole | (values < 1) | (values > 255)]
    if bad.size:
        fail("%s: --label all needs labels that are integers 1 .. 255 (the uint8 output), this "
             "volume has %s" % (name, ", ".join("%g" % v for v in bad[:5].tolist())
                                + (" and %d more" % (bad.size - 5) if bad.size > 5 else "")))
    return [int(v) for v in values.tolist()]


def read_volume(out, dtype):
    """lsmorph's volume.raw as (slice, row, column), with volume.json's sizes."""
    import json
    try:
        with open(os.path.join(out, "volume.json")) as f:
            meta = json.load(f)
        nx, ny, nz = meta["sizes"]
        if meta.get("dtype", np.dtype(dtype).name) != np.dtype(dtype).name:
            raise ValueError("%s samples, %s expected" % (meta["dtype"], np.dtype(dtype).name))
        return np.fromfile(os.path.join(out, "volume.raw"), dtype).reshape(nz, ny, nx)
    except (OSError, ValueError, KeyError) as e:
        fail("%s: cannot read lsmorph's volume.raw / volume.json (are --format or --values among "
             "the options after \"--\"?): %s" % (out, e))


def run_lsmorph(args, options, masks, run, sx, sy, sz, base, values, dtype, what=""):
    """Runs lsmorph on masks (slice k of the volume -> boolean array (i, j)) of the slices in
    run, with heights k * sz and pixels sx (along i) by sy (along j), in folder base; returns its volume as (slice, i, j), one slice per
    volume slice from run[0] to run[-1].  what names the label in messages ("" for one)."""
    src, out = os.path.join(base, "slices"), os.path.join(base, "out")
    shutil.rmtree(src, ignore_errors=True)  # no slices left from an earlier --keep run
    os.makedirs(src)
    for n, k in enumerate(run):
        # PNG rows run along the second in-plane axis, columns along the first
        write_png(os.path.join(src, "%05d.png" % n), masks(k).T)
    with open(os.path.join(base, "heights.txt"), "w") as f:
        f.write("".join("%.17g\n" % (k * sz) for k in run))
    cmd = [args.lsmorph, "reconstruct", src, "-o", out, "--heights", os.path.join(base, "heights.txt"),
           "--pixel-size", "%r,%r" % (sx, sy), "--dz", repr(sz), "--values", values, "--format", "raw",
           "--no-preview", "--no-slices"] + options
    done = subprocess.run(cmd)
    if done.returncode != 0:
        fail("lsmorph failed%s (exit %d): %s" % (what, done.returncode, " ".join(cmd)))
    volume = read_volume(out, dtype)
    if volume.shape[0] != run[-1] - run[0] + 1:
        fail("lsmorph wrote %d slices%s, expected %d (slices %d .. %d)"
             % (volume.shape[0], what, run[-1] - run[0] + 1, run[0], run[-1]))
    return volume.transpose(0, 2, 1)


def fill_all(args, extra, labels, stack, sx, sy, sz, work):
    """--label all: (picked slices, uint8 stack (slice, i, j)), one lsmorph run per label."""
    values = atlas_labels(labels, args.labels)
    present = stack.reshape(stack.shape[0], -1).any(axis=1)
    picked = parse_slices(args.slices, len(present)) if args.slices \
        else drawn_slices(present, "the labels are")
    if len(picked) < 2:
        fail("--slices names %d slice: at least two are needed" % len(picked), 2)
    # found drawn slices: a label's range reaches at most one typical step beyond its ends,
    # as with one label (a slice there holds no label, so it is as empty as the union's ends)
    step = None if args.slices else int(np.median(np.diff([k for k, p in enumerate(present) if p])))
    # on_drawn[n]: the labels present on drawn slice picked[n]
    on_drawn = [set(np.unique(stack[k]).tolist()) - {0} for k in picked]
    best = np.zeros(stack.shape, np.float32)  # running minimum signed distance, 0 = none below 0
    result = np.zeros(stack.shape, np.uint8)
    copies = []
    for count, value in enumerate(values, 1):
        where = [n for n in range(len(picked)) if value in on_drawn[n]]
        if not where:
            print("sparse_labels.py: warning: label %d (%d of %d) is on none of the drawn slices; "
                  "left out" % (value, count, len(values)), file=sys.stderr)
            continue
        first, last = picked[where[0]], picked[where[-1]]
        before = picked[where[0] - 1] if where[0] > 0 else None
        after = picked[where[-1] + 1] if where[-1] + 1 < len(picked) else None
        if step is not None and first - step >= 0 and (before is None or first - step > before):
            before = first - step
        if step is not None and last + step < len(present) and (after is None or last + step < after):
            after = last + step
        if len(where) == 1 and (before is None or after is None):
            print("sparse_labels.py: warning: label %d (%d of %d) is on one drawn slice only, %d, with "
                  "no drawn slice %s it: copied as drawn, not filled"
                  % (value, count, len(values), first, "before" if before is None else "after"),
                  file=sys.stderr)
            copies.append((value, first))
            continue
        run = ([before] if before is not None else []) + picked[where[0]:where[-1] + 1] \
            + ([after] if after is not None else [])
        print("sparse_labels.py: label %d (%d of %d): slices %d .. %d"
              % (value, count, len(values), run[0], run[-1]), file=sys.stderr)
        sys.stderr.flush()
        base = os.path.join(work, "label-%03d" % value)
        sdf = run_lsmorph(args, extra or ["-q"], lambda k: stack[k] == value, run, sx, sy, sz, base,
                          "sdf", "<f4", " on label %d" % value)
        part = best[run[0]:run[-1] + 1]
        lower = sdf < part
        part[lower] = sdf[lower]
        result[run[0]:run[-1] + 1][lower] = value
        del sdf, lower
        if not args.keep:
            shutil.rmtree(base, ignore_errors=True)
    for value, k in copies:
        result[k][stack[k] == value] = value
    return values, picked, result


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
    ap.add_argument("--label", type=label_arg, default=None,
                    help="the label to fill (default: any non-zero), or 'all': each label in turn")
    ap.add_argument("--axis", type=int, choices=(0, 1, 2), default=None,
                    help="slice axis (default: the one with the largest voxel spacing)")
    ap.add_argument("--slices", default=None, help="the drawn slices, e.g. 10:60:5,63 (b included)")
    ap.add_argument("--lsmorph", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                      "..", "build", "lsmorph"))
    ap.add_argument("--keep", default=None, help="keep lsmorph's input and output in this folder")
    args = ap.parse_args(argv)

    value = args.label if args.label is not None else 1
    if value != "all" and not 0 < value < 256:
        fail("--label %d does not fit the uint8 output (1 .. 255)" % value, 2)
    if is_nrrd(args.labels) != is_nrrd(args.out) or args.out.lower().endswith(".nhdr"):
        # NRRD's geometry is usually in LPS, NIfTI's in RAS: no conversion here
        fail("write OUT with the input's format: %s" % (".nrrd / .seg.nrrd" if is_nrrd(args.labels)
                                                        else ".nii / .nii.gz"))
    if is_nrrd(args.labels):
        nrrd, labels = read_nrrd(args.labels)
        zooms = nrrd.spacings

        def save_volume(data):
            write_nrrd(nrrd, data, args.out)
    else:
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

        def save_volume(data):
            save(nibabel, image, data, args.out)
    axis = args.axis if args.axis is not None else max((zooms[a], a) for a in (0, 1, 2))[1]
    plane = [a for a in (0, 1, 2) if a != axis]
    sx, sy, sz = zooms[plane[0]], zooms[plane[1]], zooms[axis]
    if value == "all":
        work = args.keep or tempfile.mkdtemp(prefix="sparse-labels-")
        try:
            stack = np.moveaxis(labels, axis, 0)  # (slice, i, j): slice k is stack[k]
            values, picked, result = fill_all(args, extra, labels, stack, sx, sy, sz, work)
            save_volume(np.moveaxis(result, 0, axis))
        finally:
            if not args.keep:
                shutil.rmtree(work, ignore_errors=True)
        print("sparse_labels.py: %d label%s on %d drawn slices (%d .. %d along axis %d) filled into %s"
              % (len(values), "" if len(values) == 1 else "s", len(picked), picked[0], picked[-1],
                 axis, args.out))
        return
    inside = labels == args.label if args.label is not None else labels != 0
    stack = np.moveaxis(inside, axis, 0)  # (slice, i, j): slice k is stack[k]
    present = stack.reshape(stack.shape[0], -1).any(axis=1)
    picked = parse_slices(args.slices, len(present)) if args.slices else drawn_slices(present)
    if len(picked) < 2:
        fail("--slices names %d slice: at least two are needed" % len(picked), 2)

    work = args.keep or tempfile.mkdtemp(prefix="sparse-labels-")
    try:
        filled = run_lsmorph(args, extra, lambda k: stack[k], picked, sx, sy, sz, work, "mask", np.uint8)
        result = np.zeros(stack.shape, np.uint8)
        result[picked[0]:picked[-1] + 1] = np.where(filled == 255, value, 0)
        save_volume(np.moveaxis(result, 0, axis))
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    print("sparse_labels.py: %d drawn slices (%d .. %d along axis %d) filled into %s"
          % (len(picked), picked[0], picked[-1], axis, args.out))


if __name__ == "__main__":
    main()
