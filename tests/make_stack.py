"""Writes a synthetic stack of binary PNG slices (a slowly changing ellipse)
for benchmarks.  Usage: make_stack.py OUT_DIR COUNT SIZE"""
import math
import os
import struct
import sys
import zlib


def write_png(path, rows, w, h):
    raw = b"".join(b"\x00" + r for r in rows)
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


out, count, size = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
os.makedirs(out, exist_ok=True)
for k in range(count):
    a = size * (0.25 + 0.1 * math.sin(0.3 * k))
    b = size * (0.2 + 0.08 * math.cos(0.2 * k))
    cx = size / 2 + size * 0.05 * math.sin(0.1 * k)
    rows = []
    for y in range(size):
        dy = (y - size / 2) / b
        if abs(dy) >= 1:
            rows.append(bytes(size))
            continue
        half = a * math.sqrt(1 - dy * dy)
        x0, x1 = max(0, int(math.ceil(cx - half))), min(size, int(math.floor(cx + half)) + 1)
        rows.append(bytes(x0) + b"\xff" * max(0, x1 - x0) + bytes(size - max(x0, x1)))
    write_png(os.path.join(out, "%04d.png" % (k + 1)), rows, size, size)
