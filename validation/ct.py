"""A real CT segmentation as test stacks: the lung nodule ("Mass") of the DICOM
Segmentation object shipped in the npm package ami.js (data/dicom/dcm.seg.andrei,
an LIDC-IDRI chest CT, 512 x 512 x 275 frames, 0.78 x 0.78 mm pixels, 1 mm
apart), sliced along each of the three axes and cut to the nodule plus one
empty slice at either end (18 axial, 28 and 26 slices the other ways, about
20 to 30 px across).  Slices are taken in voxel units, as the other protocols
do: along x and y each slice's pixels are 1 mm by 0.78 mm.  Every k-th slice
is kept from the first (empty) one and the held-out slices up to the last kept
one are scored with `lsmorph score`, against the plain monotone-cubic
references of padded.py.  The only CT segmentation among the protocols (the
organs of organs.py are random solids): a small rounded lesion, a tail on one
side.

    /usr/bin/python3 validation/ct.py [BUILD_DIR] [--strides 2,4,8]
        [--shapes nodule-z,nodule-y,nodule-x] [--methods ls,pchip-mirror,pchip-zero,pchip-R,pchip-c10]
        [--offsets first|all] [--margin M]
        [-- EXTRA LSMORPH OPTIONS]

Needs python3-pydicom (Debian) to read the DICOM file.  The package (ami.js
0.33.0, 10 MB) is fetched once with `npm pack` into $LSMORPH_MESH_CACHE
(default ~/.cache/lsmorph-meshes, shared with meshes.py); without network and
cache the script says so and stops.  Prints the same columns as padded.py;
a few seconds.
"""
import io
import sys
import tarfile

import numpy as np

import end_offsets as eo
import meshes
import padded

PACKAGE = ("ami.js", "0.33.0")
SEGMENTATION = "package/data/dicom/dcm.seg.andrei"


def load_nodule(cache):
    """The segmentation as a boolean (frames, rows, columns) volume, frames in
    increasing z."""
    try:
        import pydicom
    except ImportError:
        raise SystemExit("ct: needs python3-pydicom (apt-get install python3-pydicom)")
    path = meshes.fetch_or_exit("ct", *PACKAGE, cache)
    with tarfile.open(path) as tar:
        dataset = pydicom.dcmread(io.BytesIO(tar.extractfile(SEGMENTATION).read()))
    frames, rows, columns = int(dataset.NumberOfFrames), dataset.Rows, dataset.Columns
    if dataset.BitsAllocated != 1 or len(dataset.SegmentSequence) != 1:
        raise SystemExit("ct: expected one binary segment in %s" % SEGMENTATION)
    bits = np.unpackbits(np.frombuffer(dataset.PixelData, np.uint8), bitorder="little")
    volume = bits[:frames * rows * columns].reshape(frames, rows, columns).astype(bool)
    z = [float(f.PlanePositionSequence[0].ImagePositionPatient[2])
         for f in dataset.PerFrameFunctionalGroupsSequence]
    return volume[np.argsort(z)]


def crop(stack, margin=3):
    """The stack cut in-plane to its foreground's box plus `margin` pixels."""
    rows, columns = np.nonzero(stack.any(axis=0))
    return stack[:, max(rows.min() - margin, 0):rows.max() + margin + 1,
                 max(columns.min() - margin, 0):columns.max() + margin + 1]


def main():
    lsm, opts, extra = eo.parse_args(sys.argv[1:], dict(padded.OPTIONS, **{
        "--strides": "2,4,8", "--methods": "ls,pchip-mirror,pchip-zero,pchip-R,pchip-c10",
        "--shapes": "nodule-z,nodule-y,nodule-x"}), "ct")
    volume = load_nodule(meshes.cache_dir())

    def stacks():
        for shape in opts["--shapes"].split(","):
            axis = shape.rsplit("-", 1)[-1]
            if not shape.startswith("nodule-") or axis not in ("x", "y", "z"):
                raise SystemExit("ct: unknown shape %s (nodule-z, nodule-y or nodule-x)" % shape)
            yield shape, crop(padded.cut(np.moveaxis(volume, "zyx".index(axis), 0)))

    padded.score_table(lsm, stacks(), opts, extra)


if __name__ == "__main__":
    main()
