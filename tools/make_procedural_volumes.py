#!/usr/bin/env python3
"""Writes two procedural volumes as .kvox (voxel_grid.h's format) into scenes/volumes/:
  smoke.kvox  64³ density: a rising plume of fBm value noise, fading with height (a `grid` medium)
  yarn.kvox   64³ density + SGGX S: a ball of yarn, strands wound on great circles of a sphere shell, with
              fiber-like flakes along each strand's tangent (eqs. 15–16 of seed 000) — a `sggx` medium
Deterministic (fixed seeds). Pure Python: about a minute.

Usage: python3 tools/make_procedural_volumes.py   (from the repository root)
"""
import math
import pathlib
import random
import struct

root = pathlib.Path(__file__).resolve().parent.parent
out = root / "scenes" / "volumes"
out.mkdir(parents=True, exist_ok=True)


def write_kvox(path, n, lo, hi, voxels, channels):
    with open(path, "wb") as f:
        f.write(b"KOZUVOX1")
        f.write(struct.pack("<4I", n[0], n[1], n[2], channels))
        f.write(struct.pack("<6f", *lo, *hi))
        for v in voxels:
            f.write(struct.pack(f"<{channels}f", *v))
    print("wrote", path)


def value_noise(seed):
    rng = random.Random(seed)
    table = [rng.random() for _ in range(4096)]

    def h(i, j, k):
        return table[(i * 73856093 ^ j * 19349663 ^ k * 83492791) & 4095]

    def smooth(t):
        return t * t * (3 - 2 * t)

    def noise(x, y, z):
        i, j, k = math.floor(x), math.floor(y), math.floor(z)
        fx, fy, fz = smooth(x - i), smooth(y - j), smooth(z - k)
        acc = 0.0
        for dk in (0, 1):
            for dj in (0, 1):
                for di in (0, 1):
                    w = (fx if di else 1 - fx) * (fy if dj else 1 - fy) * (fz if dk else 1 - fz)
                    acc += w * h(i + di, j + dj, k + dk)
        return acc
    return noise


def smoke(n=64):
    noise = value_noise(3)
    voxels = []
    for k in range(n):
        for j in range(n):
            for i in range(n):
                x, y, z = (i + 0.5) / n * 2 - 1, (j + 0.5) / n, (k + 0.5) / n * 2 - 1
                # a plume widening with height, swirled by a height-dependent offset
                cx = 0.15 * math.sin(5 * y)
                cz = 0.15 * math.cos(4 * y)
                r = math.hypot(x - cx, z - cz) / (0.2 + 0.5 * y)
                f = sum(noise(4 * x * 2 ** o, 4 * y * 2 ** o - 3 * y, 4 * z * 2 ** o) / 2 ** o for o in range(4)) / 1.875
                d = max(0.0, 1 - r) * max(0.0, f - 0.35) * 2.5 * (1 - y) ** 0.5
                voxels.append((d,))
    write_kvox(out / "smoke.kvox", (n, n, n), (-1, 0, -1), (1, 2, 1), voxels, 1)


def yarn(n=64):
    rng = random.Random(5)
    # strands: great circles of radius 0.8 with random axes, thickness 0.045
    axes = []
    for _ in range(90):
        a = [rng.gauss(0, 1) for _ in range(3)]
        l = math.sqrt(sum(x * x for x in a))
        axes.append([x / l for x in a])
    radius, thick, sigma = 0.8, 0.05, 0.25
    voxels = []
    for k in range(n):
        for j in range(n):
            for i in range(n):
                p = [(i + 0.5) / n * 2 - 1, (j + 0.5) / n * 2 - 1, (k + 0.5) / n * 2 - 1]
                rp = math.sqrt(sum(x * x for x in p))
                best, tangent = 1e9, None
                if abs(rp - radius) < 2 * thick:
                    for a in axes:
                        # distance to the great circle of axis a on the sphere of the yarn's radius
                        along = sum(p[c] * a[c] for c in range(3))
                        q = [p[c] - along * a[c] for c in range(3)]
                        ql = math.sqrt(sum(x * x for x in q))
                        if ql < 1e-6:
                            continue
                        d = math.hypot(ql - radius, along)
                        if d < best:
                            best = d
                            t = [a[1] * q[2] - a[2] * q[1], a[2] * q[0] - a[0] * q[2], a[0] * q[1] - a[1] * q[0]]
                            tl = math.sqrt(sum(x * x for x in t))
                            tangent = [x / tl for x in t]
                if tangent is not None and best < thick:
                    dens = 40.0 * (1 - (best / thick) ** 2)
                    tx, ty, tz = tangent
                    s2 = sigma * sigma
                    # eq. 16: S = ω1ω1ᵀ + ω2ω2ᵀ + σ² ω3ω3ᵀ = I − (1 − σ²) t tᵀ
                    S = (1 - (1 - s2) * tx * tx, 1 - (1 - s2) * ty * ty, 1 - (1 - s2) * tz * tz,
                         -(1 - s2) * tx * ty, -(1 - s2) * tx * tz, -(1 - s2) * ty * tz)
                    voxels.append((dens,) + S)
                else:
                    voxels.append((0.0, 1, 1, 1, 0, 0, 0))
    write_kvox(out / "yarn.kvox", (n, n, n), (-1, -1, -1), (1, 1, 1), voxels, 7)


smoke()
yarn()
