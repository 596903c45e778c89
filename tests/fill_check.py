"""Volumes and checks for tests/test_fill.sh (lsmorph fill), read with real readers:
nibabel for NIfTI, VTK's vtkNrrdReader and a plain header parser for NRRD.

    fill_check.py make DIR                  writes the test volumes into DIR
    fill_check.py verify DIR IN OUT         OUT against IN and the truth
    fill_check.py same DIR A B ...          the same voxels
    fill_check.py labels DIR DRAWN SOME ALL L1,L2   SOME filled only the labels L

Each check prints "ok - ..." or "FAIL - ...".
"""
import gzip
import os
import re
import sys

import nibabel as nib
import numpy as np

SPACING = (0.9, 0.8, 2.0)
SHAPE = (60, 50, 41)
STEP = 4


def report(good, what):
    print(("ok - " if good else "FAIL - ") + what)


def affine():
    """An oblique RAS affine: 20 degrees about z, then the spacing."""
    t = np.radians(20.0)
    rot = np.array([[np.cos(t), -np.sin(t), 0, 0], [np.sin(t), np.cos(t), 0, 0], [0, 0, 1, 0],
                    [0, 0, 0, 1.0]])
    a = rot @ np.diag(list(SPACING) + [1.0])
    a[:3, 3] = (10.0, -20.0, 30.0)
    return a


def truth():
    """Two touching halves of an ellipsoid (1, 2), a ball nested in 1 (4), an oblique
    tube (3) and a disc two millimetres thick (5), on physical coordinates."""
    g = np.mgrid[0:SHAPE[0], 0:SHAPE[1], 0:SHAPE[2]].astype(float)
    x, y, z = (g[a] * SPACING[a] for a in range(3))
    lab = np.zeros(SHAPE, np.int16)
    ell = ((x - 29) / 15) ** 2 + ((y - 20) / 12) ** 2 + ((z - 40) / 28) ** 2 < 1
    lab[ell & (x < 29)] = 1
    lab[ell & (x >= 29)] = 2
    lab[(x - 22) ** 2 + (y - 20) ** 2 + (z - 40) ** 2 < 25] = 4
    p0, p1 = np.array([20.0, 33.0, 7.0]), np.array([45.0, 36.0, 73.0])
    d = (p1 - p0) / np.linalg.norm(p1 - p0)
    v = np.stack([x - p0[0], y - p0[1], z - p0[2]])
    along = np.tensordot(d, v, 1)
    off = v - d[:, None, None, None] * along
    tube = (np.sum(off ** 2, 0) < 3.0 ** 2) & (along >= 0) & (along <= np.linalg.norm(p1 - p0))
    lab[tube & (lab == 0)] = 3
    lab[((x - 47) ** 2 + (y - 30) ** 2 < 16) & (np.abs(z - 40) < 1)] = 5
    return lab


def drawn_of(lab, axis, step, first):
    out = np.zeros_like(lab)
    sl = [slice(None)] * 3
    for k in range(first, lab.shape[axis], step):
        sl[axis] = k
        out[tuple(sl)] = lab[tuple(sl)]
    return out


def lps(aff):
    return np.diag([-1.0, -1.0, 1.0, 1.0]) @ aff


def vec(v):
    return "(" + ",".join(repr(float(x)) for x in v) + ")"


def write_nrrd(path, lab, aff, encoding="raw", endian="little", extra=(), detached=False):
    m = lps(aff)
    kind = {np.dtype("int16"): "short", np.dtype("uint8"): "uchar"}[lab.dtype]
    head = ["NRRD0004", "# drawn by the test", "type: " + kind, "dimension: 3",
            "space: left-posterior-superior", "sizes: %d %d %d" % lab.shape,
            "space directions: " + " ".join(vec(m[:3, a]) for a in range(3)),
            "kinds: domain domain domain", "endian: " + endian, "encoding: " + encoding,
            "space origin: " + vec(m[:3, 3])] + list(extra)
    data = lab.astype(lab.dtype.newbyteorder("<" if endian == "little" else ">")).tobytes(order="F")
    if encoding == "gzip":
        data = gzip.compress(data)
    if detached:
        name = os.path.basename(path)[:-5] + ".raw" + (".gz" if encoding == "gzip" else "")
        open(os.path.join(os.path.dirname(path), name), "wb").write(data)
        head.append("data file: " + name)
        data = b""
    open(path, "wb").write(("\n".join(head) + "\n\n").encode() + data)


def make(d):
    lab, aff = truth(), affine()
    nib.save(nib.Nifti1Image(lab, aff), os.path.join(d, "truth.nii.gz"))
    moved = aff.copy()
    moved[:3, 3] += (0.0, 0.0, 3.0)  # the same voxels 3 mm higher: another grid
    nib.save(nib.Nifti1Image(lab, moved), os.path.join(d, "truth-moved.nii.gz"))
    drawn = drawn_of(lab, 2, STEP, 0)
    nib.save(nib.Nifti1Image(drawn, aff), os.path.join(d, "drawn.nii.gz"))
    nib.save(nib.Nifti2Image(drawn.astype(np.uint8), aff), os.path.join(d, "drawn2.nii"))
    write_nrrd(os.path.join(d, "drawn.nrrd"), drawn, aff, extra=["MyKey:=my value"])
    values = [int(v) for v in np.unique(lab) if v]
    seg = ["Segmentation_MasterRepresentation:=Binary labelmap"]
    for n, v in enumerate(values):
        seg += ["Segment%d_ID:=Segment_%d" % (n, v), "Segment%d_Name:=structure %d" % (n, v),
                "Segment%d_Color:=0.%d 0.5 0.25" % (n, v), "Segment%d_LabelValue:=%d" % (n, v),
                "Segment%d_Layer:=0" % n, "Segment%d_Extent:=0 0 0 0 0 0" % n]
    write_nrrd(os.path.join(d, "drawn.seg.nrrd"), drawn, aff, "gzip", "big", seg)
    write_nrrd(os.path.join(d, "drawn.nhdr"), drawn, aff, "gzip", detached=True)
    # across i: the same volume turned, every 3rd slice
    turned = np.ascontiguousarray(lab.transpose(2, 1, 0))
    aff_i = aff[:, [2, 1, 0, 3]]
    nib.save(nib.Nifti1Image(turned, aff_i), os.path.join(d, "truth-i.nii.gz"))
    nib.save(nib.Nifti1Image(drawn_of(turned, 0, 3, 1), aff_i), os.path.join(d, "drawn-i.nii.gz"))
    # refusals
    half = drawn.astype(np.float32)
    half[30, 20, 8] = 2.5
    nib.save(nib.Nifti1Image(half, aff), os.path.join(d, "half.nii"))
    # NaN and Inf, which nifticlib turns into 0 as it loads (big endian: swapped back first)
    nan = drawn.astype(">f4")
    nan[30, 20, 8] = np.nan
    nib.save(nib.Nifti1Image(nan, aff, dtype=np.dtype(">f4")), os.path.join(d, "nan.nii"))
    inf = drawn.astype(np.float64)
    inf[31, 21, 12] = -np.inf
    nib.save(nib.Nifti2Image(inf, aff, dtype=np.float64), os.path.join(d, "inf.nii.gz"))
    # vox_offset 0 (nifticlib alone reads the samples from byte 348, inside the header) and NaN
    for name, offset in (("offset0.nii", 0.0), ("offnan.nii", np.nan)):
        nib.save(nib.Nifti1Image(drawn, aff), os.path.join(d, name))
        with open(os.path.join(d, name), "r+b") as f:
            f.seek(108)
            f.write(np.float32(offset).tobytes())
    # pixdim[3] NaN in a qform-only header (nifticlib alone takes it as 1)
    nib.save(nib.Nifti1Image(drawn, aff), os.path.join(d, "pixnan.nii"))
    with open(os.path.join(d, "pixnan.nii"), "r+b") as f:
        f.seek(88)
        f.write(np.float32(np.nan).tobytes())
        f.seek(252)
        f.write(np.array([1, 0], "<i2").tobytes())
    parallel = aff.copy()
    parallel[:3, 1] = aff[:3, 0]  # the j axis along the i axis: a singular grid
    write_nrrd(os.path.join(d, "parallel.nrrd"), drawn, parallel)
    big = drawn.astype(np.float64)
    big[30, 20, 8] = 1e16  # a whole number, past what a double holds exactly
    nib.save(nib.Nifti1Image(big, aff, dtype=np.float64), os.path.join(d, "big.nii"))
    far = np.diag([1e29, 1.0, 2.0, 1.0])  # 1e29 per voxel: the volume spans more than 1e30
    nib.save(nib.Nifti1Image(drawn, far), os.path.join(d, "far.nii"))
    one = np.zeros_like(lab)
    one[:, :, 20] = lab[:, :, 20]
    nib.save(nib.Nifti1Image(one, aff), os.path.join(d, "one.nii.gz"))
    layers = np.stack([drawn, drawn]).astype(np.uint8)
    head = ["NRRD0004", "type: uchar", "dimension: 4", "sizes: 2 %d %d %d" % lab.shape,
            "kinds: list domain domain domain", "encoding: raw"]
    open(os.path.join(d, "layers.seg.nrrd"), "wb").write(("\n".join(head) + "\n\n").encode()
                                                         + layers.tobytes(order="F"))


def nrrd_header(path):
    raw = open(path, "rb").read()
    end = raw.find(b"\n\n")  # a detached header has no blank line
    end = len(raw.rstrip(b"\n")) if end < 0 else end
    lines = raw[:end].decode("latin-1").split("\n")
    fields = dict(l.split(": ", 1) for l in lines[1:] if ": " in l and ":=" not in l and l[0] != "#")
    return lines, fields, raw[end + 2:]


def nrrd_geometry(fields):
    dirs = re.findall(r"\(([^)]*)\)", fields["space directions"])
    m = np.eye(4)
    for a in range(3):
        m[:3, a] = [float(v) for v in dirs[a].split(",")]
    m[:3, 3] = [float(v) for v in re.findall(r"\(([^)]*)\)", fields["space origin"])[0].split(",")]
    return m  # LPS


def read(path):
    """(voxels [i, j, k], LPS affine, lsmorph's fill note, header lines or None)."""
    if path.endswith((".nii", ".nii.gz")):
        img = nib.load(path)
        note = None
        for e in img.header.extensions:
            text = e.get_content().decode("latin-1").rstrip("\0")
            if text.startswith("lsmorph_fill: "):
                note = text[len("lsmorph_fill: "):]
        return np.asarray(img.dataobj), lps(img.affine), note, None
    lines, fields, data = nrrd_header(path)
    types = {"short": "i2", "uchar": "u1", "unsigned char": "u1", "uint8": "u1", "int16": "i2"}
    dtype = np.dtype(types[fields["type"]]).newbyteorder("<" if fields.get("endian", "little") == "little" else ">")
    if "data file" in fields:
        data = open(os.path.join(os.path.dirname(path), fields["data file"].lstrip("./")), "rb").read()
    if fields["encoding"] == "gzip":
        data = gzip.decompress(data)
    sizes = [int(v) for v in fields["sizes"].split()]
    vox = np.frombuffer(data, dtype, int(np.prod(sizes))).reshape(sizes[::-1]).T
    kv = dict(l.split(":=", 1) for l in lines if ":=" in l)
    return vox, nrrd_geometry(fields), kv.get("lsmorph_fill"), lines


CONTROLLER = None


def vtk_read(path):
    """vtkNrrdReader's voxels, spacing and origin (it needs an MPI controller in Debian's VTK)."""
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    global CONTROLLER  # held: the reader finds no controller once it is collected
    CONTROLLER = vtk.vtkDummyController()
    vtk.vtkMultiProcessController.SetGlobalController(CONTROLLER)
    r = vtk.vtkNrrdReader()
    r.SetFileName(path)
    r.Update()
    img = r.GetOutput()
    dims = img.GetDimensions()
    vox = vtk_to_numpy(img.GetPointData().GetScalars()).reshape(dims[::-1]).T
    return vox, np.array(img.GetSpacing()), np.array(img.GetOrigin())


def parse_note(note):
    fields = dict(part.split("=", 1) for part in note.split())
    return "ijk".index(fields["axis"]), [int(v) for v in fields["drawn"].split(",")]


def verify(d, src, out):
    a, ma, _, la = read(os.path.join(d, src))
    b, mb, note, lb = read(os.path.join(d, out))
    report(a.shape == b.shape, "%s: shape %s" % (out, b.shape))
    report(a.dtype.kind == b.dtype.kind and a.dtype.itemsize == b.dtype.itemsize,
           "%s: voxel type %s, as the input's %s" % (out, b.dtype, a.dtype))
    report(np.allclose(ma, mb, atol=1e-4), "%s: the input's affine (LPS)" % out)
    if note is None:
        report(False, "%s: lsmorph's note on the fill in the header" % out)
        return
    axis, drawn = parse_note(note)
    a, b = np.moveaxis(a, axis, 0), np.moveaxis(b, axis, 0)
    report(all((a[k] == b[k]).all() for k in drawn), "%s: %d drawn slices exact" % (out, len(drawn)))
    outside = [k for k in range(a.shape[0]) if k < drawn[0] or k > drawn[-1]]
    report(all((a[k] == b[k]).all() for k in outside), "%s: slices outside the drawn range kept" % out)
    report(set(np.unique(b)) <= set(np.unique(a)), "%s: only the input's labels" % out)
    held = [k for k in range(drawn[0], drawn[-1]) if k not in drawn]
    t = np.moveaxis(np.asarray(nib.load(os.path.join(d, "truth-i.nii.gz" if "-i" in src
                                                     else "truth.nii.gz")).dataobj), axis, 0)
    for v in (1, 2, 3, 4, 5):
        x, y = t[held] == v, b[held] == v
        dice = 2 * (x & y).sum() / max(1, x.sum() + y.sum())
        sections = sum((a[k] == v).any() for k in drawn)
        if sections >= 3:  # a sanity bound (the accuracy is measured in validation/labels.py)
            report(dice > 0.85, "%s: label %d (%d drawn sections), Dice %.3f on the %d slices filled"
                   % (out, v, sections, dice, len(held)))
        else:
            print("%s: label %d (%d drawn sections), Dice %.3f" % (out, v, sections, dice))
    if lb is not None and out.endswith(".nrrd") and src.endswith(".nrrd"):
        def meaning(lines):  # key/value pairs in order, comments, fields (numbers as numbers)
            kv = [l for l in lines if ":=" in l and "_Extent:=" not in l and not l.startswith("lsmorph")]
            comments = sorted(l for l in lines if l.startswith("#"))
            fields = {}
            for l in lines[1:]:
                if ": " in l and ":=" not in l and l[0] != "#":
                    name, value = l.split(": ", 1)
                    if name not in ("type", "encoding", "endian", "data file"):
                        fields[name] = [float(v) for v in re.findall(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?", value)] or value
            return kv, comments, fields
        report(meaning(la) == meaning(lb),
               "%s: the input's header fields, comments and key/value pairs (in order)" % out)
        for n, v in enumerate(int(x) for x in np.unique(a) if x):
            if "Segment%d_Extent:=0 0 0 0 0 0" % n in la:
                box = " ".join("%d %d" % (w.min(), w.max()) for w in np.nonzero(np.moveaxis(b, 0, axis) == v))
                report("Segment%d_Extent:=%s" % (n, box) in lb, "%s: segment %d's extent %s" % (out, n, box))
    if out.endswith((".nrrd", ".nhdr")):
        vv, sp, org = vtk_read(os.path.join(d, out))
        report((np.moveaxis(vv, 0, 0) == np.moveaxis(b, 0, axis)).all() if vv.shape == np.moveaxis(b, 0, axis).shape
               else False, "%s: vtkNrrdReader reads the same voxels" % out)
        report(np.allclose(sp, np.linalg.norm(ma[:3, :3], axis=0), atol=1e-4)
               and np.allclose(org, ma[:3, 3], atol=1e-4),
               "%s: vtkNrrdReader: spacing %s and origin %s, the input's" % (out, np.round(sp, 4).tolist(), np.round(org, 3).tolist()))


def surface(v, label):
    """The voxels of label with a 6-neighbour outside it, or on the volume's border."""
    m = v == label
    inner = m.copy()
    for a in range(3):
        for shift in (1, -1):
            inner &= np.roll(m, shift, a)
        sl = [slice(None)] * 3
        sl[a] = 0
        inner[tuple(sl)] = False
        sl[a] = -1
        inner[tuple(sl)] = False
    return m & ~inner


def score(d, truth, out, report_json):
    """lsmorph score's Dice and distances against numpy's: Dice pooled over the slices not
    drawn, the 3D distances between the labels' surfaces (brute force)."""
    import json
    t, _, _, _ = read(os.path.join(d, truth))
    b, _, note, _ = read(os.path.join(d, out))
    res = json.load(open(os.path.join(d, report_json)))
    axis, drawn = parse_note(note)
    held = [k for k in range(drawn[0] + 1, drawn[-1]) if k not in drawn]
    report(res["held_out"] == len(held) and res["axis"] == "ijk"[axis],
           "score: axis %s, %d slices scored" % (res["axis"], res["held_out"]))
    sel = [slice(None)] * 3
    sel[axis] = held
    for entry in res["labels"]:
        v = entry["label"]
        x, y = t[tuple(sel)] == v, b[tuple(sel)] == v
        dice = 2 * (x & y).sum() / max(1, x.sum() + y.sum())
        st, sr = surface(t, v), surface(b, v)
        pt, pr = np.argwhere(st) * SPACING, np.argwhere(sr) * SPACING
        on_t = np.isin(np.argwhere(st)[:, axis], held)
        on_r = np.isin(np.argwhere(sr)[:, axis], held)
        def nearest(p, q):
            return np.array([np.sqrt(((q - r) ** 2).sum(1)).min() for r in p]) if len(p) else np.zeros(0)
        dist = np.sort(np.concatenate([nearest(pt[on_t], pr), nearest(pr[on_r], pt)]))
        hd = dist[int(np.ceil(0.95 * len(dist))) - 1] if len(dist) else None
        good = abs(entry["dice"] - dice) < 1e-9 and (hd is None or
               (abs(entry["hd95"] - hd) < 1e-6 and abs(entry["mean_surface"] - dist.mean()) < 1e-6))
        report(good, "score: label %d: Dice %.4f (numpy %.4f), HD95 %s, mean %s mm (numpy %s, %s)"
               % (v, entry["dice"], dice, entry["hd95"], entry["mean_surface"], hd,
                  None if hd is None else dist.mean()))


def same(d, names):
    first = read(os.path.join(d, names[0]))[0]
    for n in names[1:]:
        v = read(os.path.join(d, n))[0]
        report(v.shape == first.shape and (v == first).all(), "%s holds the voxels of %s" % (n, names[0]))


def labels(d, drawn, some, every, chosen):
    chosen = [int(v) for v in chosen.split(",")]
    a, s, e = (read(os.path.join(d, n))[0] for n in (drawn, some, every))
    kept = ~np.isin(a, chosen) & (a != 0)
    report((s[kept] == a[kept]).all() and (s[~np.isin(s, chosen)] == a[~np.isin(s, chosen)]).all(),
           "%s: the labels not filled are the input's" % some)
    for v in chosen:
        report((s == v).sum() > (a == v).sum(), "%s: label %d filled (%d voxels, %d drawn)"
               % (some, v, (s == v).sum(), (a == v).sum()))


if __name__ == "__main__":
    cmd, args = sys.argv[1], sys.argv[2:]
    {"make": lambda: make(*args), "verify": lambda: verify(*args), "same": lambda: same(args[0], args[1:]),
     "labels": lambda: labels(*args), "score": lambda: score(*args)}[cmd]()
