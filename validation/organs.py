"""Random smooth solids as stand-ins for CT organ segmentations: white noise
low-pass filtered (Gaussian, about 9 px in-plane and 7 to 14 slices along z),
pulled toward the centre by a Gaussian envelope and thresholded at its top
5 %; the largest connected piece is kept (and the second largest too for
every third seed, a pair like the kidneys), holes filled.  Solids touching
the border of the 128 x 128 x 90 volume are skipped (their ends would be
cut flat by the volume, which the next seed does not do), so each is whole:
rounded, lobed, bent, 40 to 65 slices tall, 50 to 95 px across.  Like the
other protocols each is cut to its extent plus one empty slice at either end,
every k-th slice kept from the first (empty) one, and the held-out slices up
to the last kept one scored with `lsmorph score` against the plain monotone
cubics of padded.py.  Deterministic (seeded); no download.

    /usr/bin/python3 validation/organs.py [BUILD_DIR] [--strides 4,8,16]
        [--shapes organ0,organ1,...] [--methods ls,pchip-mirror,pchip-zero,pchip-R,pchip-c10]
        [--offsets first|all] [--margin M]
        [-- EXTRA LSMORPH OPTIONS]

Prints the same columns as padded.py; about three minutes on 2 cores.
"""
import sys

import numpy as np

import end_offsets as eo
import padded

COUNT = 16          # organs (shapes organ0 .. organ15)
SIZE, DEPTH = 128, 90


def solid(seed, pair):
    """One random organ as a boolean (DEPTH, SIZE, SIZE) volume, or None when
    it touches the border of the volume."""
    from scipy import ndimage
    rng = np.random.default_rng(seed)
    smooth = 9.0
    field = ndimage.gaussian_filter(rng.standard_normal((DEPTH, SIZE, SIZE)),
                                    (smooth * rng.uniform(0.8, 1.6), smooth, smooth))
    z, y, x = np.meshgrid(np.linspace(-1, 1, DEPTH), np.linspace(-1, 1, SIZE),
                          np.linspace(-1, 1, SIZE), indexing="ij")
    field = field / field.std() + 4.0 * np.exp(-3.0 * (x * x + y * y + z * z))
    inside = field > np.quantile(field, 0.95)
    label, count = ndimage.label(inside)
    sizes = ndimage.sum(inside, label, range(1, count + 1))
    order = np.argsort(sizes)[::-1] + 1
    keep = list(order[:2]) if pair and count > 1 else [order[0]]
    organ = ndimage.binary_fill_holes(np.isin(label, keep))
    border = (organ[0].any() or organ[-1].any() or organ[:, 0].any() or organ[:, -1].any()
              or organ[:, :, 0].any() or organ[:, :, -1].any())
    return None if border else organ


def organs():
    """(name, volume) of the COUNT organs, seeds tried in order from 100."""
    seed, found = 100, 0
    while found < COUNT:
        volume = solid(seed, pair=found % 3 == 2)
        seed += 1
        if volume is not None:
            yield "organ%d" % found, volume
            found += 1


def main():
    lsm, opts, extra = eo.parse_args(sys.argv[1:], dict(padded.OPTIONS, **{
        "--strides": "4,8,16", "--methods": "ls,pchip-mirror,pchip-zero,pchip-R,pchip-c10",
        "--shapes": ",".join("organ%d" % i for i in range(COUNT))}), "organs")
    wanted = opts["--shapes"].split(",")
    unknown = [s for s in wanted if s not in ["organ%d" % i for i in range(COUNT)]]
    if unknown:
        raise SystemExit("organs: unknown shape %s (organ0 .. organ%d)" % (unknown[0], COUNT - 1))

    def stacks():
        for name, volume in organs():
            if name in wanted:
                yield name, padded.cut(volume)

    padded.score_table(lsm, stacks(), opts, extra)


if __name__ == "__main__":
    main()
