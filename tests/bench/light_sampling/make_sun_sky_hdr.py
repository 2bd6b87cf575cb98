#!/usr/bin/env python3
# Usage: make_sun_sky_hdr.py OUT.hdr [WIDTH HEIGHT]
# An equirect Radiance HDR (the mapping of kernels/shared/light.h, row 0 = up):
# a blue sky brighter towards the horizon, a circumsolar glow, a sun disc of
# 1.5 degrees and radiance 2000 at 37 degrees elevation, and a dim brown
# ground. Pure Python (no numpy), deterministic.
import math
import sys

out = sys.argv[1]
W = int(sys.argv[2]) if len(sys.argv) > 2 else 512
H = int(sys.argv[3]) if len(sys.argv) > 3 else 256
sun = (0.5, 0.6, 0.3)
norm = math.sqrt(sum(v * v for v in sun))
sun = tuple(v / norm for v in sun)


def rgbe(col):
    m = max(col)
    if m <= 1e-32:
        return bytes([0, 0, 0, 0])
    mant, ex = math.frexp(m)
    scale = mant * 256.0 / m
    return bytes([min(255, int(c * scale)) for c in col] + [ex + 128])


pixels = bytearray()
for j in range(H):
    theta = (j + 0.5) / H * math.pi
    for i in range(W):
        phi = (i + 0.5) / W * 2 * math.pi - math.pi
        d = (math.sin(theta) * math.sin(phi), math.cos(theta), -math.sin(theta) * math.cos(phi))
        ang = math.acos(max(-1.0, min(1.0, sum(a * b for a, b in zip(d, sun)))))
        if d[1] > 0:
            k = 0.4 + 0.6 * (1 - d[1])
            glow = 3 * math.exp(-ang / 0.15)
            col = [0.3 * k + glow, 0.5 * k + 0.9 * glow, 1.0 * k + 0.7 * glow]
        else:
            col = [0.25, 0.2, 0.15]
        if ang < math.radians(1.5):
            col = [2000, 1900, 1700]
        pixels += rgbe(col)
with open(out, "wb") as f:
    f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (H, W))
    f.write(pixels)
