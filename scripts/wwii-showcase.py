#!/usr/bin/env python3
"""The README's Call of Duty: WWII showcase (docs/wwii.md): a wet cobblestone street, normal-mapped, running from the
camera's feet to the horizon under a low sun, rendered with and without normal/gloss mip filtering and surface
occlusion, and put side by side.

  python3 scripts/wwii-showcase.py KOZU OUT_DIR [--spp N] [--width W] [--map-size N] [--variants LIST]

Writes OUT_DIR/cobble_normal.pfm (the procedural normal map: jittered Voronoi stones with rounded tops and mortar
joints, OpenGL convention), OUT_DIR/<variant>.json and .png for each variant, and OUT_DIR/wwii-showcase.png (the
panels side by side, by oiiotool). Variants: plain (filtering off, occlusion off), filtered, occluded (filtering and
surface occlusion on), reference (level-0 lookups, "filter": "closest", at 16x the samples: the supersampled truth).
"""
import argparse
import json
import math
import os
import random
import struct
import subprocess
import sys


def cobble_heights(n, cells, seed=4):
    """Height field (texel widths) of cells x cells jittered Voronoi stones tiling an n x n texture periodically."""
    rnd = random.Random(seed)
    pts = [[(i + 0.15 + 0.7 * rnd.random(), j + 0.15 + 0.7 * rnd.random()) for i in range(cells)] for j in range(cells)]
    tilt = [[(rnd.uniform(-0.05, 0.05), rnd.uniform(-0.05, 0.05), rnd.uniform(0.8, 1.2)) for i in range(cells)]
            for j in range(cells)]
    cell = n / cells
    dome = 0.16 * cell  # a stone's crown above its joint, in texels
    h = [0.0] * (n * n)
    for y in range(n):
        for x in range(n):
            px, py = (x + 0.5) / cell, (y + 0.5) / cell
            cx, cy = int(px), int(py)
            best = [(1e9, 0, 0, 0.0, 0.0), (1e9, 0, 0, 0.0, 0.0)]
            for dj in (-1, 0, 1):
                for di in (-1, 0, 1):
                    i, j = cx + di, cy + dj
                    fx, fy = pts[j % cells][i % cells]
                    fx += i - i % cells
                    fy += j - j % cells
                    d = (px - fx) ** 2 + (py - fy) ** 2
                    if d < best[0][0]:
                        best = [(d, i % cells, j % cells, fx, fy), best[0]]
                    elif d < best[1][0]:
                        best[1] = (d, i % cells, j % cells, fx, fy)
            # Distance to the bisector of the two nearest stones: how far inside its stone the texel is.
            (d1, i1, j1, x1, y1), (_, _, _, x2, y2) = best
            ex, ey = x2 - x1, y2 - y1
            el = math.hypot(ex, ey)
            edge = ((px - (x1 + x2) / 2) * -ex + (py - (y1 + y2) / 2) * -ey) / el  # > 0 inside stone 1
            t = min(max(edge / 0.45, 0.0), 1.0)
            profile = math.sqrt(t * (2 - t))  # rounded shoulder, flat-ish top
            a, b, s = tilt[j1][i1]
            h[y * n + x] = dome * (s * profile + a * (px - x1) * 4 + b * (py - y1) * 4) * (1 if edge > 0.02 else 0.0)
    return h


def write_normal_pfm(path, n, h, slope_scale=1.0):
    rows = []
    for y in range(n):
        row = []
        for x in range(n):
            # Central differences, wrapping; image y runs down, the map's +y (OpenGL) up the image.
            dx = (h[y * n + (x + 1) % n] - h[y * n + (x - 1) % n]) * 0.5 * slope_scale
            dy = (h[((y + 1) % n) * n + x] - h[((y - 1) % n) * n + x]) * 0.5 * slope_scale
            nx, ny, nz = -dx, dy, 1.0
            l = math.sqrt(nx * nx + ny * ny + nz * nz)
            row += [(nx / l + 1) / 2, (ny / l + 1) / 2, (nz / l + 1) / 2]
        rows.append(row)
    with open(path, "wb") as f:
        f.write(f"PF\n{n} {n}\n-1.0\n".encode())
        for y in reversed(range(n)):
            f.write(struct.pack(f"<{3 * n}f", *rows[y]))


def write_sky_pfm(path, w=512, h=256):
    """A late-afternoon sky, lat-long as kozu maps it (+y up, the image centre towards -z): warm at the horizon,
    blue above, a glow about the sun's direction (+z, 3 degrees up), dark ground below the horizon."""
    sun = (-0.02, 0.04, 1.0)
    sl = math.sqrt(sum(c * c for c in sun))
    sun = tuple(c / sl for c in sun)
    rows = []
    for j in range(h):
        theta = (j + 0.5) / h * math.pi
        row = []
        for i in range(w):
            phi = ((i + 0.5) / w - 0.5) * 2 * math.pi
            d = (math.sin(theta) * math.sin(phi), math.cos(theta), -math.sin(theta) * math.cos(phi))
            y = d[1]
            if y < 0:
                c = (0.05, 0.045, 0.04)
            else:
                t = 1 - (1 - y) ** 3
                c = tuple(a * (1 - t) + b * t for a, b in zip((1.1, 0.62, 0.36), (0.22, 0.36, 0.66)))
                cosg = max(0.0, sum(a * b for a, b in zip(d, sun)))
                glow = 2.5 * cosg ** 64 + 0.6 * cosg ** 8
                c = tuple(a + glow * b for a, b in zip(c, (1.0, 0.7, 0.45)))
            row += c
        rows.append(row)
    with open(path, "wb") as f:
        f.write(f"PF\n{w} {h}\n-1.0\n".encode())
        for j in reversed(range(h)):
            f.write(struct.pack(f"<{3 * w}f", *rows[j]))


def scene(normal_map, sky, width, height, variant):
    nm = {"type": "image", "file": normal_map, "uv_scale": [60, 120]}
    stone = {"type": "plastic", "albedo": [0.16, 0.14, 0.12], "gloss": 0.82, "ior": 1.33, "normal_map": nm}
    if variant == "plain":
        stone["normal_gloss_filtering"] = False
    elif variant == "reference":
        nm["filter"] = "closest"
    elif variant == "occluded":
        stone["surface_occlusion"] = True
    return {
        "comment": f"wwii showcase, variant {variant} (scripts/wwii-showcase.py)",
        "camera": {"position": [-1.5, 1.4, 0], "look_at": [-0.6, 1.3, 20], "up": [0, 1, 0], "fov": 40,
                   "resolution": [width, height]},
        "render": {"max_depth": 6},
        "materials": {"stone": stone,
                      "plaster": {"type": "diffuse", "albedo": [0.62, 0.52, 0.42]}},
        # A 60 m x 120 m paved street and square (one tile a metre) from the camera's feet to the horizon.
        "shapes": [{"type": "quad", "material": "stone",
                    "vertices": [[-30, 0, -2], [30, 0, -2], [30, 0, 118], [-30, 0, 118]]},
                   # House fronts along both sides of the street.
                   {"type": "quad", "material": "plaster",
                    "vertices": [[-7, 0, -2], [-7, 0, 45], [-7, 7, 45], [-7, 7, -2]]},
                   {"type": "quad", "material": "plaster",
                    "vertices": [[7, 0, 45], [7, 0, -2], [7, 9, -2], [7, 9, 45]]},
                   # A low sun ahead, a little above the horizon, and a warm sky.
                   {"type": "sphere", "center": [-20, 40, 1000], "radius": 12, "emission": [40, 34, 26]}],
        "lights": [{"type": "environment", "file": sky, "scale": 1.25}],
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("kozu")
    ap.add_argument("out")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--reference-factor", type=int, default=16)
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--map-size", type=int, default=512)
    ap.add_argument("--variants", default="plain,filtered,occluded,reference")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    normal = os.path.join(args.out, "cobble_normal.pfm")
    if not os.path.exists(normal):
        write_normal_pfm(normal, args.map_size, cobble_heights(args.map_size, 8))
    sky = os.path.join(args.out, "sky.pfm")
    if not os.path.exists(sky):
        write_sky_pfm(sky)
    width, height = args.width, args.width * 9 // 16
    pngs = []
    for v in args.variants.split(","):
        path = os.path.join(args.out, v + ".json")
        with open(path, "w") as f:
            json.dump(scene(os.path.abspath(normal), os.path.abspath(sky), width, height, v), f, indent=1)
        spp = args.spp * (args.reference_factor if v == "reference" else 1)
        png = os.path.join(args.out, v + ".png")
        print(f"{v}: {spp} spp", flush=True)
        exr = os.path.join(args.out, v + ".exr")
        subprocess.run([args.kozu, "render", path, "--spp", str(spp), "-o", png, "-o", exr], check=True)
        pngs.append(png)
        # Linear means of a far band (just below the horizon) and a near band (the bottom of the frame).
        for band, (y0, y1) in (("far", (0.505, 0.555)), ("near", (0.78, 0.98))):
            box = f"{width * 3 // 5}x{int((y1 - y0) * height)}+{width // 5}+{int(y0 * height)}"
            out = subprocess.run(["oiiotool", exr, "--cut", box, "--printstats"], capture_output=True, text=True).stdout
            avg = [line for line in out.splitlines() if "Stats Avg" in line]
            print(f"  {band} band {box}: {avg[0].split(':', 1)[1].strip() if avg else '?'}", flush=True)
    subprocess.run(["oiiotool"] + pngs + ["--mosaic", f"{len(pngs)}x1", "-o",
                                           os.path.join(args.out, "wwii-showcase.png")], check=True)


if __name__ == "__main__":
    sys.exit(main())
