#!/usr/bin/env python3
"""Checks that a screenshot from the GLFW sample shows clouds: in the upper half of the image
(the sky), some pixels must be cloud-like (grey to white, unsaturated) and some clear blue sky.
Decodes 8-bit RGBA PNGs with filter 0 (what examples-c/png_write.h writes), stdlib only."""
import struct
import sys
import zlib


def read_png(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, w, h = 8, b"", 0, 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            w, h, depth, color = struct.unpack(">IIBB", body[:10])
            assert (depth, color) == (8, 6), "expected 8-bit RGBA"
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = 1 + 4 * w
    rows = []
    for y in range(h):
        assert raw[y * stride] == 0, "only filter 0 is supported"
        rows.append(raw[y * stride + 1:(y + 1) * stride])
    return w, h, rows


def main(path):
    w, h, rows = read_png(path)
    cloud = sky = total = 0
    for y in range(h // 2):
        row = rows[y]
        for x in range(w):
            r, g, b = row[4 * x], row[4 * x + 1], row[4 * x + 2]
            total += 1
            if max(r, g, b) - min(r, g, b) < 30 and 60 < max(r, g, b):
                cloud += 1
            elif b > r + 40 and b > 120:
                sky += 1
    cloud_frac, sky_frac = cloud / total, sky / total
    print(f"{path}: {w}x{h}, sky half: {cloud_frac:.1%} cloud-like, {sky_frac:.1%} blue sky")
    if cloud_frac < 0.10 or sky_frac < 0.02:
        sys.exit("the screenshot does not show clouds in a sky")


if __name__ == "__main__":
    main(sys.argv[1])
