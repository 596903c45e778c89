"""The same first-order Godunov upwind update as kernels/lsm_cell.h, written
with NumPy whole-array operations: the baseline of `make bench`.
Usage: /usr/bin/python3 tests/bench_numpy.py N [float32|float64]
prints cells per second (default float32, the C path's precision): the best of
five timed blocks, as tests/bench_scheme.c times the C path."""
import sys
import time

import numpy as np

n = int(sys.argv[1]) if len(sys.argv) > 1 else 512
real = np.dtype(sys.argv[2] if len(sys.argv) > 2 else "float32").type
y, x = np.mgrid[0:n, 0:n].astype(real) - real(0.5 * n)
phi = (np.hypot(x, y) - real(0.3 * n)).astype(real)
target = (np.hypot(x - real(0.1 * n), real(1.5) * y) - real(0.25 * n)).astype(real)
dt = real(0.01)


def step(phi):
    p = np.pad(phi, 1, mode="edge")
    c = p[1:-1, 1:-1]
    dxm = c - p[1:-1, :-2]
    dxp = p[1:-1, 2:] - c
    dym = c - p[:-2, 1:-1]
    dyp = p[2:, 1:-1] - c
    F = c - target
    gpos = np.sqrt(np.maximum(np.maximum(dxm, 0) ** 2, np.minimum(dxp, 0) ** 2) +
                   np.maximum(np.maximum(dym, 0) ** 2, np.minimum(dyp, 0) ** 2))
    gneg = np.sqrt(np.maximum(np.minimum(dxm, 0) ** 2, np.maximum(dxp, 0) ** 2) +
                   np.maximum(np.minimum(dym, 0) ** 2, np.maximum(dyp, 0) ** 2))
    H = np.where(F > 0, F * gpos, F * gneg)
    return c - dt * H


step(phi)
reps = max(3, int(4e6 / (n * n)))
best = float("inf")
for _ in range(5):
    t0 = time.perf_counter()
    for _ in range(reps):
        out = step(phi)
    best = min(best, time.perf_counter() - t0)
print("%.4g" % (n * n * reps / best))
