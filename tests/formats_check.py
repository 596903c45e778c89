"""Helpers of tests/test_formats.sh: synthetic input and checks of every output
format with real readers (VTK's Python module, OpenImageIO's oiiotool/iinfo).
Run with Debian's /usr/bin/python3 (python3-vtk9, python3-numpy, python3-nibabel).

  formats_check.py ball DIR SIZE COUNT STRIDE R CX CY CZ
      writes the slices k = 0, STRIDE, 2 STRIDE, ... < COUNT of a ball (radius R
      pixels, centre CX CY CZ in pixels / slice numbers) of SIZE x SIZE pixels
      as 8-bit PNGs DIR/slice_NNN.png (a tiny zlib PNG writer)
  formats_check.py outline SRC DST
      writes each ball slice of SRC as its 1-px outline in DST (--input outline)
  formats_check.py check OUT --spacing SX SY SZ --values sdf|mask
                   [--mesh] [--caps] [--ball R CX CY CZ] [--pixel P]
      checks OUT (written with --format nrrd,mha,vtk,nii,exr,raw and, with --mesh
      or --ball, --mesh); SZ "auto": the mean step of heights.txt; --caps: the
      object is cut by the first and last slices, so the mesh has flat caps
      half a slice step beyond them.  Prints "ok - ..." or "FAIL - ..." per
      check.
"""
import json
import math
import os
import struct
import subprocess
import sys
import zlib

RESULTS = {"ok": 0, "fail": 0}


def report(good, what):
    RESULTS["ok" if good else "fail"] += 1
    print(("ok - " if good else "FAIL - ") + what, flush=True)
    return good


# ---- input -------------------------------------------------------------------------------

def write_png(path, rows, w, h):
    raw = b"".join(b"\x00" + r for r in rows)

    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def make_ball(args):
    out, size, count, stride = args[0], int(args[1]), int(args[2]), int(args[3])
    r, cx, cy, cz = (float(a) for a in args[4:8])
    os.makedirs(out, exist_ok=True)
    for k in range(0, count, stride):
        rows = []
        for j in range(size):
            row = bytearray(size)
            for i in range(size):
                if (i - cx) ** 2 + (j - cy) ** 2 + (k - cz) ** 2 <= r * r:
                    row[i] = 255
            rows.append(bytes(row))
        write_png(os.path.join(out, "slice_%03d.png" % k), rows, size, size)
    return 0


# ---- readers -------------------------------------------------------------------------------

def vtk_modules():
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    # Debian's VTK routes vtkNrrdReader through a parallel reader that wants a
    # global controller; a dummy one (kept referenced) makes it serial.
    controller = vtk.vtkDummyController()
    vtk.vtkMultiProcessController.SetGlobalController(controller)
    return vtk, vtk_to_numpy, controller


def read_image(vtk, reader, path):
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def close(a, b, tol=1e-9):
    return all(abs(x - y) <= tol * max(1.0, abs(x), abs(y)) for x, y in zip(a, b))


def check_nifti(out, name, vtk, vtk_to_numpy, raw, dims, spacing, z0, mask):
    """volume.nii or volume.nii.gz (name) through two independent readers: VTK's
    vtkNIFTIImageReader and nibabel (which inflate .gz themselves, VTK through zlib, nibabel
    through Python's gzip).  Both must give volume.raw's samples; nibabel's affine must be
    diag(-sx, -sy, sz) with offset (0, 0, z0) (RAS, so that ITK's LPS gets the identity, as
    for volume.nrrd)."""
    import numpy as np
    path = os.path.join(out, name)
    r = vtk.vtkNIFTIImageReader()
    r.SetFileName(path)
    r.Update()
    im = r.GetOutput()
    scal = im.GetPointData().GetScalars() if im and im.GetPointData() else None
    if report(scal is not None and im.GetDimensions() == dims,
              "VTK reads %s: dimensions %s (want %s)" % (name, im.GetDimensions() if im else None, dims)):
        a = vtk_to_numpy(scal)
        report(close(im.GetSpacing(), spacing, 1e-6), "%s spacing %s == %s (VTK)" % (name, im.GetSpacing(), spacing))
        report(a.dtype == (np.uint8 if mask else np.float32) and np.array_equal(a, raw),
               "%s has the same values as volume.raw (VTK, %s)" % (name, a.dtype))
        q = r.GetQFormMatrix()
        qm = [[q.GetElement(i, j) for j in range(4)] for i in range(3)] if q else None
        want = [[-1, 0, 0, 0], [0, -1, 0, 0], [0, 0, 1, z0]]
        report(qm is not None and all(close(qm[i], want[i], 1e-6) for i in range(3)),
               "%s qform (VTK) %s == %s" % (name, qm, want))
    import nibabel
    img = nibabel.load(path)
    data = np.asarray(img.dataobj)
    report(data.shape == dims and data.dtype == (np.uint8 if mask else np.float32),
           "nibabel reads %s: shape %s, %s" % (name, data.shape, data.dtype))
    report(data.shape == dims and np.array_equal(data.ravel(order="F"), raw),
           "%s has the same values as volume.raw (nibabel)" % name)
    sx, sy, sz = spacing
    want = np.array([[-sx, 0, 0, 0], [0, -sy, 0, 0], [0, 0, sz, z0], [0, 0, 0, 1]])
    for form, (aff, code) in (("sform", img.header.get_sform(coded=True)),
                              ("qform", img.header.get_qform(coded=True))):
        report(aff is not None and int(code) == 1 and np.allclose(aff, want, rtol=1e-6, atol=1e-6 * abs(z0)),
               "%s %s (nibabel, code %s) == diag(-sx, -sy, sz) + (0, 0, z0)" % (name, form, code))


def check(args):
    import numpy as np
    out = args[0]
    opts = {}
    k = 1
    while k < len(args):
        name = args[k]
        n = {"--spacing": 3, "--values": 1, "--ball": 4, "--pixel": 1, "--mesh": 0, "--caps": 0}[name]
        opts[name] = args[k + 1:k + 1 + n]
        k += 1 + n
    values = opts["--values"][0]
    mask = values == "mask"
    vtk, vtk_to_numpy, controller = vtk_modules()

    heights = [float(line) for line in open(os.path.join(out, "heights.txt")) if line.strip()]
    nz = len(heights)
    # "auto" z spacing: the mean step of heights.txt (per-iteration mode)
    spacing = [float(v) if v != "auto" else (heights[-1] - heights[0]) / max(1, nz - 1)
               for v in opts["--spacing"]]
    meta = json.load(open(os.path.join(out, "volume.json")))
    nx, ny = meta["sizes"][0], meta["sizes"][1]
    report(meta["sizes"][2] == nz, "volume.json sizes %s match heights.txt (%d slices)" % (meta["sizes"], nz))
    report(close(meta["spacing"], spacing), "volume.json spacing %s == %s" % (meta["spacing"], spacing))
    report(close(meta["origin"], [0.0, 0.0, heights[0]]), "volume.json origin %s" % meta["origin"])
    want_dtype = "uint8" if mask else "float32"
    report(meta["dtype"] == want_dtype and meta["endianness"] == "little",
           "volume.json dtype %s, endianness %s" % (meta["dtype"], meta["endianness"]))
    raw = np.fromfile(os.path.join(out, "volume.raw"), dtype="u1" if mask else "<f4")
    report(raw.size == nx * ny * nz, "volume.raw holds %d samples (want %d)" % (raw.size, nx * ny * nz))

    images = {}
    arrays = {}
    readers = {"nrrd": vtk.vtkNrrdReader(), "mha": vtk.vtkMetaImageReader(), "vtk": vtk.vtkStructuredPointsReader()}
    for fmt, reader in readers.items():
        path = os.path.join(out, "volume." + fmt)
        im = read_image(vtk, reader, path)
        dims = im.GetDimensions() if im else None
        scal = im.GetPointData().GetScalars() if im and im.GetPointData() else None
        if not report(scal is not None and dims == (nx, ny, nz),
                      "VTK reads volume.%s: dimensions %s (want %s)" % (fmt, dims, (nx, ny, nz))):
            continue
        images[fmt] = im
        a = vtk_to_numpy(scal)
        arrays[fmt] = a
        report(close(im.GetSpacing(), spacing, 1e-6),
               "volume.%s spacing %s == %s" % (fmt, im.GetSpacing(), spacing))
        report(close(im.GetOrigin(), (0.0, 0.0, heights[0]), 1e-6),
               "volume.%s origin %s" % (fmt, im.GetOrigin()))
        report(a.dtype == (np.uint8 if mask else np.float32), "volume.%s type %s" % (fmt, a.dtype))
        report(a.shape == raw.shape and np.array_equal(a, raw),
               "volume.%s has the same values as volume.raw" % fmt)
    vol = raw.reshape(nz, ny, nx)
    for name in ("volume.nii", "volume.nii.gz"):
        if report(os.path.exists(os.path.join(out, name)), "%s written" % name):
            check_nifti(out, name, vtk, vtk_to_numpy, raw, (nx, ny, nz), spacing, heights[0], mask)
    if mask:
        report(set(np.unique(vol).tolist()) <= {0, 255}, "mask values are 0 and 255")

    # ---- EXR: every slice, through OpenImageIO ----
    exr_dir = os.path.join(out, "exr")
    files = sorted(f for f in os.listdir(exr_dir) if f.endswith(".exr"))
    report(files == ["%05d.exr" % (k + 1) for k in range(nz)], "exr/ holds %d files 00001.exr ... (want %d)" % (len(files), nz))
    dump = subprocess.run(["oiiotool", "--dumpdata"] + [os.path.join(exr_dir, f) for f in files],
                          capture_output=True, text=True)
    if report(dump.returncode == 0, "oiiotool --dumpdata reads every EXR slice"):
        slices = []
        cur = None
        for line in dump.stdout.splitlines():
            if not line.startswith(" "):
                cur = []
                slices.append(cur)
            elif "Pixel (" in line and cur is not None:
                cur.append(float(line.split(":")[1]))
        good = len(slices) == nz and all(len(s) == nx * ny for s in slices)
        worst = float("inf")
        if good:
            exr = np.array(slices, dtype=np.float64).reshape(nz, ny, nx)
            if mask:
                want = (vol == 255).astype(np.float64)
                worst = float(np.abs(exr - want).max())
                good = worst == 0.0
            else:
                v = vol.astype(np.float64)
                # --dumpdata prints 9 decimals: allow that rounding
                worst = float((np.abs(exr - v) / np.maximum(1.0, np.abs(v))).max())
                good = worst <= 2e-7 + 1e-9
        report(good, "EXR slices hold the volume's values (%d slices, largest difference %.3g)" % (len(slices), worst))
    stats = subprocess.run(["oiiotool", "--stats", os.path.join(exr_dir, files[nz // 2])],
                           capture_output=True, text=True).stdout
    vals = {}
    for line in stats.splitlines():
        line = line.strip()
        for key in ("Min", "Max"):
            if line.startswith("Stats %s:" % key):
                vals[key] = float(line.split()[2])
    mid = vol[nz // 2].astype(np.float64)
    if mask:
        mid = (mid == 255).astype(np.float64)
    report(len(vals) == 2 and abs(vals["Min"] - mid.min()) <= 1e-5 * max(1, abs(mid.min()))
           and abs(vals["Max"] - mid.max()) <= 1e-5 * max(1, abs(mid.max())),
           "oiiotool --stats of slice %d: min/max %s match the volume (%g, %g)" % (nz // 2 + 1, vals, mid.min(), mid.max()))
    info = subprocess.run(["iinfo", "-v", os.path.join(exr_dir, files[-1])], capture_output=True, text=True).stdout
    attrs = {}
    for line in info.splitlines():
        if ":" in line:
            key, _, val = line.strip().partition(":")
            attrs[key.strip()] = val.strip()
    ptype = "half" if mask else "float"
    report(("1 channel, %s openexr" % ptype) in info and attrs.get("channel list") == "Y",
           "last EXR slice: one %s channel Y" % ptype)
    try:
        ps = [float(x) for x in attrs.get("pixelSize", "").split(",")]
        sh = float(attrs.get("sliceHeight", "nan"))
    except ValueError:
        ps, sh = [], float("nan")
    report(close(ps, spacing[:2], 1e-12) and abs(sh - heights[-1]) <= 1e-9 * max(1, abs(sh)),
           "last EXR slice attributes pixelSize %s, sliceHeight %s (want %s, %s)" % (ps, sh, spacing[:2], heights[-1]))

    # ---- pictures ----
    for name in ("preview.png", "preview3d.png"):
        path = os.path.join(out, name)
        if not report(os.path.isfile(path), "%s exists" % name):
            continue
        r = vtk.vtkPNGReader()
        im = read_image(vtk, r, path)
        a = vtk_to_numpy(im.GetPointData().GetScalars()) if im.GetPointData().GetScalars() else None
        ok = a is not None and a.ndim == 2 and a.shape[1] == 3 and im.GetDimensions()[0] >= 64
        if ok and name == "preview3d.png":
            # the object must show: a good share of pixels are not background grey
            coloured = np.abs(a[:, 0].astype(int) - a[:, 2].astype(int)) > 12
            ok = 0.05 < coloured.mean() < 0.9
        report(ok, "%s is an RGB picture with content" % name)
    run = json.load(open(os.path.join(out, "run.json")))
    files_listed = run.get("output", {}).get("files", [])
    report(all(f in files_listed for f in ("volume.nrrd", "volume.mha", "volume.vtk", "volume.nii",
                                             "volume.nii.gz", "volume.raw",
                                             "volume.json", "exr/", "preview.png", "preview3d.png")),
           "run.json output files %s" % files_listed)

    if "--mesh" not in opts and "--ball" not in opts:
        return
    ply = vtk.vtkPLYReader()
    ply.SetFileName(os.path.join(out, "surface.ply"))
    ply.Update()
    mesh = ply.GetOutput()
    nv, nf = mesh.GetNumberOfPoints(), mesh.GetNumberOfCells()
    if not report(nv > 0 and nf > 0, "VTK reads surface.ply: %d vertices, %d triangles" % (nv, nf)):
        return
    edges = vtk.vtkFeatureEdges()
    edges.SetInputData(mesh)
    edges.BoundaryEdgesOn()
    edges.NonManifoldEdgesOn()
    edges.FeatureEdgesOff()
    edges.ManifoldEdgesOff()
    edges.Update()
    n_bad = edges.GetOutput().GetNumberOfCells()
    report(n_bad == 0, "surface.ply has no open or non-manifold edges (found %d)" % n_bad)
    mp2 = vtk.vtkMassProperties()
    mp2.SetInputData(mesh)
    mp2.Update()
    mesh_volume = mp2.GetVolume()
    pts = vtk_to_numpy(mesh.GetPoints().GetData()).astype(np.float64)
    tri = vtk_to_numpy(mesh.GetPolys().GetConnectivityArray()).reshape(-1, 3)
    p0, p1, p2 = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    signed = float(np.einsum("ij,ij->i", p0, np.cross(p1, p2)).sum() / 6.0)
    report(mesh_volume > 0 and abs(signed - mesh_volume) <= 1e-3 * mesh_volume,
           "triangles wound outward: signed volume %.1f == %.1f" % (signed, mesh_volume))
    # no triangle of zero area, no two vertices on one point: merged by position
    # (VTK's clean filter, ParaView's Clean) the mesh is still manifold
    area = 0.5 * np.linalg.norm(np.cross(p1 - p0, p2 - p0), axis=1)
    report(int((area <= 0).sum()) == 0, "no triangle of zero area (found %d)" % int((area <= 0).sum()))
    shared = len(pts) - len(np.unique(pts, axis=0))
    report(shared == 0, "no two vertices at one position (found %d)" % shared)
    clean = vtk.vtkCleanPolyData()
    clean.SetInputData(mesh)
    clean.SetTolerance(0.0)
    clean.Update()
    edges.SetInputData(clean.GetOutput())
    edges.Update()
    n_bad = edges.GetOutput().GetNumberOfCells()
    report(n_bad == 0, "merged by position, surface.ply has no open or non-manifold edges (found %d)" % n_bad)
    # inside the volume's voxels: x, y within half a pixel of the samples, z within
    # half a slice step beyond the first and last slices (a cut object's caps)
    sx, sy = spacing[0], spacing[1]
    z_lo = heights[0] - 0.5 * (heights[1] - heights[0]) if nz > 1 else heights[0] - 0.5 * spacing[2]
    z_hi = heights[-1] + 0.5 * (heights[-1] - heights[-2]) if nz > 1 else heights[-1] + 0.5 * spacing[2]
    lo = np.array([-0.5 * sx, -0.5 * sy, z_lo]) - 1e-4 * np.array([sx, sy, sx])
    hi = np.array([(nx - 0.5) * sx, (ny - 0.5) * sy, z_hi]) + 1e-4 * np.array([sx, sy, sx])
    outside = int(((pts < lo) | (pts > hi)).any(axis=1).sum())
    report(outside == 0, "mesh vertices inside the voxels' box %s .. %s (%d outside)" % (lo, hi, outside))
    if "--caps" in opts:  # the object is cut by the first and last slices: flat caps there
        zmin, zmax = pts[:, 2].min(), pts[:, 2].max()
        flat_lo = np.abs(pts[:, 2] - z_lo) <= 1e-4 * sx
        flat_hi = np.abs(pts[:, 2] - z_hi) <= 1e-4 * sx
        report(abs(zmin - z_lo) <= 1e-4 * sx and abs(zmax - z_hi) <= 1e-4 * sx and flat_lo.sum() > 8
               and flat_hi.sum() > 8,
               "caps half a slice step beyond the first and last slices: z %.4f .. %.4f, want %.4f .. %.4f "
               "(%d and %d vertices on them)" % (zmin, zmax, z_lo, z_hi, flat_lo.sum(), flat_hi.sum()))
        # vertex normals on the caps point out of the box: those on the lower cap down,
        # the upper cap's up (they were the gradient across the mirrored pad, some inward)
        normals = mesh.GetPointData().GetNormals()
        if normals is not None:
            nz_ = vtk_to_numpy(normals).astype(np.float64)[:, 2]
            wrong = int((nz_[flat_lo] > -0.99).sum() + (nz_[flat_hi] < 0.99).sum())
            report(wrong == 0, "cap vertices have normals (0, 0, -1) below and (0, 0, 1) above "
                   "(%d do not)" % wrong)
    if "--ball" not in opts:
        return
    # ---- the ball: isosurface volume against the ball's and the mesh's ----
    r, cx, cy, cz = (float(v) for v in opts["--ball"])
    pixel = float(opts.get("--pixel", ["1"])[0])
    true_volume = 4.0 / 3.0 * math.pi * (r * pixel) ** 3
    fe = vtk.vtkFlyingEdges3D()
    fe.SetInputData(images["nrrd"])
    fe.SetValue(0, 0.0)
    fe.Update()
    mp = vtk.vtkMassProperties()
    mp.SetInputData(fe.GetOutput())
    mp.Update()
    iso_volume = mp.GetVolume()
    err = (iso_volume - true_volume) / true_volume
    report(abs(err) <= 0.04, "flying edges at 0 encloses %.1f, ball %.1f: error %+.2f %% (limit 4 %%)"
           % (iso_volume, true_volume, 100 * err))
    diff = (mesh_volume - iso_volume) / iso_volume
    report(abs(diff) <= 0.01, "mesh volume %.1f vs isosurface %.1f: %+.3f %% (limit 1 %%)"
           % (mesh_volume, iso_volume, 100 * diff))
    chi = nv - nf * 3 // 2 + nf
    report(chi == 2, "ball mesh is one sphere: Euler characteristic %d (want 2)" % chi)
    centre = np.array([cx, cy, cz]) * pixel  # slice k is at height k * pixel
    normals = mesh.GetPointData().GetNormals()
    if report(normals is not None, "surface.ply has vertex normals"):
        nrm = vtk_to_numpy(normals).astype(np.float64)
        out_dot = np.einsum("ij,ij->i", nrm, pts - centre)
        unit = np.abs(np.linalg.norm(nrm, axis=1) - 1.0).max()
        report(unit < 1e-4 and (out_dot > 0).mean() > 0.999,
               "vertex normals are unit and point away from the centre (%.4f %% do)" % (100 * (out_dot > 0).mean()))
    radius = np.linalg.norm(pts - centre, axis=1) / pixel
    report(abs(np.median(radius) - r) <= 1.5, "mesh vertices lie near radius %.1f px (median %.2f)" % (r, np.median(radius)))
    del controller


def outline(args):
    """outline SRC DST: each mask of SRC (as make_ball writes them: 8-bit gray,
    filter 0) as its inner boundary, 1 px thick and 8-connected, in DST."""
    import numpy as np
    src, dst = args
    os.makedirs(dst, exist_ok=True)
    for name in sorted(os.listdir(src)):
        if not name.endswith(".png"):
            continue
        data = open(os.path.join(src, name), "rb").read()
        pos, idat, w, h = 8, b"", 0, 0
        while pos < len(data):
            n, kind = struct.unpack(">I4s", data[pos:pos + 8])
            body = data[pos + 8:pos + 8 + n]
            if kind == b"IHDR":
                w, h = struct.unpack(">II", body[:8])
            elif kind == b"IDAT":
                idat += body
            pos += 12 + n
        raw = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(h, w + 1)
        m = raw[:, 1:] > 127
        pad = np.pad(m, 1)
        interior = pad[1:-1, 1:-1] & pad[:-2, 1:-1] & pad[2:, 1:-1] & pad[1:-1, :-2] & pad[1:-1, 2:]
        edge = m & ~interior
        write_png(os.path.join(dst, name), [bytes(255 if v else 0 for v in row) for row in edge], w, h)
    return 0


def main(argv):
    if len(argv) >= 2 and argv[1] == "ball":
        return make_ball(argv[2:])
    if len(argv) >= 2 and argv[1] == "outline":
        return outline(argv[2:])
    if len(argv) >= 2 and argv[1] == "check":
        try:
            check(argv[2:])
        except Exception as e:  # a reader missing or a file unreadable: one failure
            report(False, "check raised %s: %s" % (type(e).__name__, e))
        print("checks: %d passed, %d failed" % (RESULTS["ok"], RESULTS["fail"]))
        return 1 if RESULTS["fail"] else 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
