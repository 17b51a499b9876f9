#!/usr/bin/env python3
"""Synthetic inputs with known answers for `kozu texture height` and `kozu texture occlusion` (docs/wwii.md,
"Surface occlusion (§4)"): written as PFM (float) images, row 0 = the image's top as kozu reads them.

  waves_normal.pfm  the normal map (OpenGL convention, colour = (n + 1) / 2) of a periodic height field, a sum of
                    sinusoids with whole periods over the tile, exact normals at texel centres
  waves_height.pfm  that height field, in texel widths, mean zero (the reference for the recovered height)
  curl_normal.pfm   the same normals plus a divergence-free slope field (an "impossible" map)
  pit_height.pfm    a spherical cap dent (rim radius A, depth D texels) in a flat plane, centred on texel (N/2, N/2)

usage: python3 scripts/wwii-occlusion-inputs.py OUT_DIR [--size N] [--pit-radius A] [--pit-depth D]
"""
import argparse
import math
import os
import struct

WAVES = [(6.0, 1, 0, 0.3), (4.0, 0, 2, 1.1), (2.0, 3, 2, 2.0), (1.0, 5, -7, 0.7), (0.5, 11, 13, 4.0)]


def write_pfm(path, width, height, channels, rows):
    """rows[y] holds width * channels floats, y = 0 the image's top (PFM stores the bottom row first)."""
    with open(path, "wb") as f:
        f.write(b"PF\n" if channels == 3 else b"Pf\n")
        f.write(f"{width} {height}\n-1.0\n".encode())
        for y in reversed(range(height)):
            f.write(struct.pack(f"<{width * channels}f", *rows[y]))


def waves(n, x, y):
    h = gx = gy = 0.0
    for a, kx, ky, phase in WAVES:
        arg = 2 * math.pi * (kx * x + ky * y) / n + phase
        h += a * math.sin(arg)
        c = a * math.cos(arg) * 2 * math.pi / n
        gx += c * kx
        gy += c * ky
    return h, gx, gy  # height, dh/dx (right), dh/dy (down the image)


def encode(gx, gy):
    inv = 1 / math.sqrt(gx * gx + gy * gy + 1)
    return [0.5 * (-gx * inv + 1), 0.5 * (gy * inv + 1), 0.5 * (inv + 1)]  # +v (green) is up the image


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--pit-radius", type=float, default=48)
    p.add_argument("--pit-depth", type=float, default=16)
    a = p.parse_args()
    n = a.size
    os.makedirs(a.out, exist_ok=True)
    heights, normals, curl = [], [], []
    total = 0.0
    for y in range(n):
        hrow, nrow, crow = [], [], []
        for x in range(n):
            h, gx, gy = waves(n, x, y)
            hrow.append(h)
            total += h
            nrow += encode(gx, gy)
            crow += encode(gx + 0.3 * math.sin(2 * math.pi * 3 * y / n), gy)  # the added part has no divergence
        heights.append(hrow)
        normals.append(nrow)
        curl.append(crow)
    mean = total / (n * n)
    write_pfm(os.path.join(a.out, "waves_height.pfm"), n, n, 1, [[h - mean for h in r] for r in heights])
    write_pfm(os.path.join(a.out, "waves_normal.pfm"), n, n, 3, normals)
    write_pfm(os.path.join(a.out, "curl_normal.pfm"), n, n, 3, curl)
    r, d = a.pit_radius, a.pit_depth
    rho = (r * r + d * d) / (2 * d)
    pit = []
    for y in range(n):
        row = []
        for x in range(n):
            r2 = (x - n // 2) ** 2 + (y - n // 2) ** 2
            row.append((rho - d) - math.sqrt(rho * rho - r2) if r2 < r * r else 0.0)
        pit.append(row)
    write_pfm(os.path.join(a.out, "pit_height.pfm"), n, n, 1, pit)
    print(f"{a.out}: waves (RMS height {math.sqrt(sum(h * h for r_ in heights for h in r_) / n / n - mean * mean):.4f}),"
          f" pit: centre visibility a^2/(a^2+d^2) = {r * r / (r * r + d * d):.6f}")


if __name__ == "__main__":
    main()
