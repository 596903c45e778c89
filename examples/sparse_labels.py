#!/usr/bin/env python3
"""An example of lsmorph's Python API: fill a NIfTI label map drawn on every few slices.

    PYTHONPATH=build/python python3 examples/sparse_labels.py DRAWN.nii.gz FILLED.nii.gz \\
        [--labels 2,5] [--axis 0|1|2] [--slices 4,8,12] [--method ls|pls|blend]

The same as `lsmorph fill DRAWN.nii.gz -o FILLED.nii.gz`, written with nibabel and NumPy
around `lsmorph.fill`: the labels are read as an array, filled in memory (every label at
once, or those of --labels), and saved with the input's affine and header.  From a
notebook it is the two lines in the middle of main().  `make` puts the package in
build/python; `make install` installs it for the system's Python 3.
"""
import argparse
import sys

import nibabel as nib
import numpy as np

import lsmorph


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("drawn")
    p.add_argument("filled")
    p.add_argument("--labels", help="the labels to fill, comma separated (default: all)")
    p.add_argument("--axis", type=int, choices=(0, 1, 2), help="the slice axis (default: "
                   "the axis of the largest voxel spacing)")
    p.add_argument("--slices", help="the drawn slices, comma separated (default: those "
                   "holding a label, and one typical step beyond each end)")
    p.add_argument("--method", default="ls", choices=("ls", "pls", "blend"))
    a = p.parse_args()

    img = nib.load(a.drawn)
    labels = np.asarray(img.dataobj)           # as stored: integers, no scaling
    if labels.ndim == 4 and labels.shape[3] == 1:
        labels = labels[..., 0]
    spacing = [float(z) for z in img.header.get_zooms()[:3]]
    try:
        filled = lsmorph.fill(labels, spacing=spacing, axis=a.axis, method=a.method,
                              slices=None if a.slices is None else [int(s) for s in a.slices.split(",")],
                              fill_labels=None if a.labels is None else [int(v) for v in a.labels.split(",")])
    except (lsmorph.Error, TypeError, ValueError) as e:
        sys.exit("sparse_labels.py: error: %s: %s" % (a.drawn, e))
    nib.save(img.__class__(filled, img.affine, img.header), a.filled)
    print("sparse_labels.py: %d voxels labelled in %s" % ((filled != 0).sum(), a.filled))


if __name__ == "__main__":
    main()
