"""Writes small test PNGs of every kind lsmorph must read or refuse, with only
the standard library (zlib, struct).  Used by tests/test_errors.sh and to make
the fuzz seed corpus.

Usage: make_png.py KIND OUT.png [SIZE [RADIUS]]
       make_png.py - < LIST      (one "KIND OUT.png [SIZE [RADIUS]]" per line: many files
                                  for one Python start-up)

Good images (a bright disc of RADIUS pixels, default SIZE/4, centred on a
SIZE x SIZE dark background, default SIZE 32; SIZE may also be WxH):
  gray8 gray16 gray1 graya8 rgb8 rgb16 rgba8 rgba16 palette palette_trns
  interlaced (8-bit gray, Adam7)  empty (8-bit gray, all dark)
  label01 (8-bit gray, the disc stored as label value 1 on 0)
  label01_speck (label01 with its top-left pixel at 255)
  labels (8-bit gray, a label map: the disc's left part label 1, its right third 200)
  text_chunks (8-bit gray with tEXt, zTXt and iTXt chunks before IDAT)
Bad ones:
  bad_crc (IHDR CRC wrong)  bad_idat_crc  bad_zlib (IDAT is not zlib data)
  truncated (cut in the middle of IDAT)  no_iend  text (not a PNG)  zero (0 bytes)
  huge (a valid signature and IHDR of 200000 x 200000 pixels, then nothing)
  huge_idat (the same header with a short IDAT and IEND)
  text_liar (IHDR, then a tEXt chunk that claims 2^31 - 1 bytes and ends the file)

From Python (sys.path holding tests/): write_drawn(PATH, ROWS) writes an 8-bit gray
mask drawn as text rows, "#" inside (255) and anything else outside (0).
"""
import struct
import sys
import zlib

SIG = b"\x89PNG\r\n\x1a\n"


def chunk(kind, data, crc=None):
    if crc is None:
        crc = zlib.crc32(kind + data) & 0xFFFFFFFF
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", crc)


def ihdr(w, h, depth, color, interlace=0):
    return chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, color, 0, 0, interlace))


def write_drawn(path, rows):
    """An 8-bit gray mask drawn as text rows: "#" inside (255), anything else 0."""
    raw = b"".join(b"\x00" + bytes(255 if c == "#" else 0 for c in r) for r in rows)
    with open(path, "wb") as f:
        f.write(SIG + ihdr(len(rows[0]), len(rows), 8, 0) + chunk(b"IDAT", zlib.compress(raw, 9)) +
                chunk(b"IEND", b""))


def disc(w, h, radius):
    cx, cy = (w - 1) / 2.0, (h - 1) / 2.0
    return [[(x - cx) ** 2 + (y - cy) ** 2 <= radius * radius for x in range(w)]
            for y in range(h)]


def pack_bits(values, depth):
    """Packs sub-byte samples (depth 1, 2, 4) MSB first."""
    out, acc, n = bytearray(), 0, 0
    for v in values:
        acc = (acc << depth) | v
        n += depth
        if n == 8:
            out.append(acc)
            acc, n = 0, 0
    if n:
        out.append(acc << (8 - n))
    return bytes(out)


def row_bytes(kind, row):
    """Raw samples of one row for each kind; inside is bright / opaque."""
    out = bytearray()
    if kind == "gray1":
        return pack_bits([1 if v else 0 for v in row], 1)
    if kind == "palette2":  # 2-bit indices: 3 (white, with alpha) inside, 1 (dark gray) outside
        return pack_bits([3 if v else 1 for v in row], 2)
    for v in row:
        if kind in ("gray8", "interlaced", "empty"):
            out += bytes([200 if v and kind != "empty" else 10])
        elif kind == "label01":
            out += bytes([1 if v else 0])
        elif kind == "gray16":
            out += struct.pack(">H", 60000 if v else 1000)
        elif kind == "graya8":
            out += bytes([255, 255]) if v else bytes([255, 0])  # outside: transparent white
        elif kind == "rgb8":
            out += bytes([250, 240, 230]) if v else bytes([20, 0, 40])
        elif kind == "rgb16":
            out += struct.pack(">HHH", 65000, 64000, 63000) if v else struct.pack(">HHH", 0, 300, 0)
        elif kind == "rgba8":
            out += bytes([255, 255, 255, 255]) if v else bytes([255, 255, 255, 0])
        elif kind == "rgba16":
            out += struct.pack(">HHHH", 65535, 65535, 65535, 65535) if v else struct.pack(">HHHH", 65535, 65535, 65535, 0)
        elif kind in ("palette", "palette_trns", "palette_short"):
            out += bytes([1 if v else 0])
        else:
            raise SystemExit("unknown kind " + kind)
    return bytes(out)


HEADER = {  # kind: (bit depth, colour type)
    "gray8": (8, 0), "interlaced": (8, 0), "empty": (8, 0), "label01": (8, 0), "gray16": (16, 0),
    "labels": (8, 0), "label01_speck": (8, 0),
    "gray1": (1, 0),
    "graya8": (8, 4), "rgb8": (8, 2), "rgb16": (16, 2), "rgba8": (8, 6), "rgba16": (16, 6),
    "palette": (8, 3), "palette_trns": (8, 3), "palette2": (2, 3),
    "palette_short": (8, 3),  # broken: index 1 inside, but a palette of one entry
}


def adam7(rows, kind):
    """Filtered (filter 0) data of the seven Adam7 passes."""
    passes = [(0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4), (1, 0, 2, 2), (0, 1, 1, 2)]
    h, w = len(rows), len(rows[0])
    out = bytearray()
    for x0, y0, dx, dy in passes:
        if x0 >= w or y0 >= h:
            continue
        for y in range(y0, h, dy):
            out += b"\x00" + row_bytes(kind, [rows[y][x] for x in range(x0, w, dx)])
    return bytes(out)


def good(kind, size, radius):
    w, h = size
    rows = disc(w, h, radius)
    depth, color = HEADER[kind]
    if kind == "interlaced":
        raw = adam7(rows, kind)
    elif kind == "label01_speck":
        raw = b"".join(b"\x00" + bytes([255 if x == 0 and y == 0 else 1 if v else 0
                                         for x, v in enumerate(r)]) for y, r in enumerate(rows))
    elif kind == "labels":
        raw = b"".join(b"\x00" + bytes([(200 if x > w / 2 + radius / 3 else 1) if v else 0
                                         for x, v in enumerate(r)]) for r in rows)
    else:
        raw = b"".join(b"\x00" + row_bytes(kind, r) for r in rows)
    data = SIG + ihdr(w, h, depth, color, 1 if kind == "interlaced" else 0)
    if kind in ("palette", "palette_trns"):
        data += chunk(b"PLTE", bytes([0, 0, 0, 255, 255, 255]))
        if kind == "palette_trns":
            data += chunk(b"tRNS", bytes([0, 255]))
    elif kind == "palette2":  # 4 entries; the bright gray of entry 2 is never used
        data += chunk(b"PLTE", bytes([0, 0, 0, 60, 60, 60, 200, 200, 200, 255, 255, 255]))
        data += chunk(b"tRNS", bytes([255, 255, 0, 200]))
    elif kind == "palette_short":
        data += chunk(b"PLTE", bytes([0, 0, 0]))
    return data + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")


def main():
    if sys.argv[1:] == ["-"]:
        for line in sys.stdin:
            if line.split():
                make(*line.split())
    else:
        make(*sys.argv[1:])


def make(kind, out, arg="32", radius=None):
    size = tuple(int(v) for v in arg.split("x")) if "x" in arg else (int(arg), int(arg))
    radius = float(radius) if radius is not None else min(size) / 4.0
    if kind in HEADER:
        data = good(kind, size, radius)
    elif kind == "text_chunks":
        g = good("gray8", size, radius)
        data = (g[:33] + chunk(b"tEXt", b"Comment\x00drawn by hand") +
                chunk(b"zTXt", b"Software\x00\x00" + zlib.compress(b"a mask")) +
                chunk(b"iTXt", b"Title\x00\x00\x00en\x00\x00mask") + g[33:])
    elif kind == "text_liar":
        data = SIG + ihdr(size[0], size[1], 8, 0) + struct.pack(">I", 0x7FFFFFFF) + b"tEXt" + b"Comment\x00"
    elif kind == "bad_crc":
        data = SIG + chunk(b"IHDR", struct.pack(">IIBBBBB", size[0], size[1], 8, 0, 0, 0, 0), crc=0x12345678)
        data += good("gray8", size, radius)[33:]
    elif kind == "bad_idat_crc":
        g = good("gray8", size, radius)
        n = struct.unpack(">I", g[33:37])[0]
        end = 33 + 8 + n
        data = g[:end] + bytes([g[end] ^ 0xFF]) + g[end + 1:]
    elif kind == "bad_zlib":
        data = SIG + ihdr(size[0], size[1], 8, 0) + chunk(b"IDAT", b"this is not zlib data at all") + chunk(b"IEND", b"")
    elif kind == "truncated":
        g = good("gray8", size, radius)
        n = struct.unpack(">I", g[33:37])[0]
        data = g[:33 + 8 + n // 2]
    elif kind == "no_iend":
        g = good("gray8", size, radius)
        data = g[:-12]
    elif kind == "text":
        data = b"hello, I am not a PNG image\n"
    elif kind == "zero":
        data = b""
    elif kind == "huge":
        data = SIG + ihdr(200000, 200000, 8, 0)
    elif kind == "huge_idat":
        data = SIG + ihdr(200000, 200000, 8, 0) + chunk(b"IDAT", zlib.compress(b"\x00" * 100)) + chunk(b"IEND", b"")
    else:
        raise SystemExit("make_png.py: unknown kind " + kind)
    with open(out, "wb") as f:
        f.write(data)


if __name__ == "__main__":
    main()
