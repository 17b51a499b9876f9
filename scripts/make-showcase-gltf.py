#!/usr/bin/env python3
"""Writes scenes/showcase.glb: a textured glTF 2.0 scene for `kozu render scenes/showcase.glb`.

Python 3's standard library only (PNG textures are written by hand with zlib), and fully reproducible: the same
bytes on every run. The scene: a checker ground plane (KHR_texture_transform repeats it), a brick sphere with a
normal map, a brushed gold sphere whose roughness comes from a metallic-roughness texture, a wooden cube, a glass
sphere (KHR_materials_transmission, KHR_materials_ior), a perspective camera and a sun (KHR_lights_punctual).

    scripts/make-showcase-gltf.py [-o scenes/showcase.glb]
"""
import argparse
import json
import math
import struct
import zlib

N = 256  # texture size


def png(width, height, channels, pixel):
    """An 8-bit PNG (colour type 2 or 6) of pixel(x, y) -> tuple of floats in [0, 1], row 0 at the top."""
    rows = bytearray()
    for y in range(height):
        rows.append(0)  # filter: none
        for x in range(width):
            for c in pixel(x, y)[:channels]:
                rows.append(max(0, min(255, int(round(c * 255)))))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6 if channels == 4 else 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(bytes(rows), 9)) + chunk(b"IEND", b"")


def hash01(i, j):
    """A deterministic value in [0, 1) per integer lattice point."""
    h = (i * 374761393 + j * 668265263) & 0xFFFFFFFF
    h = ((h ^ (h >> 13)) * 1274126177) & 0xFFFFFFFF
    return (h ^ (h >> 16)) / 2.0**32


def value_noise(x, y):
    i, j = math.floor(x), math.floor(y)
    fx, fy = x - i, y - j
    sx, sy = fx * fx * (3 - 2 * fx), fy * fy * (3 - 2 * fy)
    a, b = hash01(i, j), hash01(i + 1, j)
    c, d = hash01(i, j + 1), hash01(i + 1, j + 1)
    return (a + (b - a) * sx) * (1 - sy) + (c + (d - c) * sx) * sy


# --- textures (u right, v down the image, as glTF) ------------------------------------------------------------

def checker(x, y):
    on = ((x * 8 // N) + (y * 8 // N)) % 2
    return (0.75, 0.74, 0.7) if on else (0.18, 0.2, 0.24)


def brick_height(x, y):
    """1 on a brick, 0 in the mortar: 4 rows of 2 bricks (staggered) per tile, with bevelled edges."""
    rows, cols, mortar = 8, 4, 0.06
    v = y / N * rows
    row = int(v)
    u = x / N * cols + (0.5 if row % 2 else 0.0)
    du, dv = u - math.floor(u), v - row
    edge = min(du, 1 - du, (dv) * cols / rows * 2, (1 - dv) * cols / rows * 2)
    return max(0.0, min(1.0, (edge - mortar * 0.5) / mortar))


def brick_color(x, y):
    h = brick_height(x, y)
    row = int(y / N * 8)
    col = int(x / N * 4 + (0.5 if row % 2 else 0.0))
    tint = 0.8 + 0.4 * hash01(row, col) + 0.1 * value_noise(x / 6.0, y / 6.0)
    brick = (0.55 * tint, 0.2 * tint, 0.12 * tint)
    mortar = (0.6, 0.58, 0.55)
    return tuple(m + (b - m) * h for b, m in zip(brick, mortar))


def brick_normal(x, y):
    """Tangent-space normal from the brick height (x right, y up in the image; glTF's convention)."""
    k = 1.5
    dhdx = (brick_height((x + 1) % N, y) - brick_height((x - 1) % N, y)) * 0.5
    dhdy_up = (brick_height(x, (y - 1) % N) - brick_height(x, (y + 1) % N)) * 0.5
    n = (-k * dhdx, -k * dhdy_up, 1.0)
    length = math.sqrt(sum(c * c for c in n))
    return tuple(0.5 * c / length + 0.5 for c in n)


def wood(x, y):
    u, v = x / N, y / N
    r = math.sqrt((u - 0.1) ** 2 * 4 + (v * 0.15) ** 2) * 7 + 0.8 * value_noise(u * 5, v * 12)
    ring = 0.5 + 0.5 * math.sin(r * 2 * math.pi)
    grain = 0.9 + 0.1 * value_noise(u * 80, v * 4)
    return (grain * (0.45 + 0.2 * ring), grain * (0.27 + 0.12 * ring), grain * (0.12 + 0.06 * ring))


def gold_metal_rough(x, y):
    """G = roughness (brushed bands), B = metallic (1)."""
    band = value_noise(x / 3.0, y / 40.0)
    rough = 0.12 + 0.3 * band * (1 if (y * 6 // N) % 2 else 0.4)
    return (1.0, rough, 1.0)


# --- geometry ------------------------------------------------------------------------------------------------

def sphere(radius, slices=64, stacks=32):
    pos, nrm, tan, uv, idx = [], [], [], [], []
    for i in range(stacks + 1):
        theta = math.pi * i / stacks
        for j in range(slices + 1):
            phi = 2 * math.pi * j / slices
            n = (math.sin(theta) * math.sin(phi), math.cos(theta), math.sin(theta) * math.cos(phi))
            pos += [radius * c for c in n]
            nrm += n
            tan += [math.cos(phi), 0.0, -math.sin(phi), 1.0]  # dP/du; cross(n, t) points up the image
            uv += [j / slices, i / stacks]
    for i in range(stacks):
        for j in range(slices):
            a, b = i * (slices + 1) + j, (i + 1) * (slices + 1) + j
            idx += [a, b, a + 1, a + 1, b, b + 1]
    return pos, nrm, tan, uv, idx


def cube(half):
    pos, nrm, tan, uv, idx = [], [], [], [], []
    for n, t in [((1, 0, 0), (0, 0, -1)), ((-1, 0, 0), (0, 0, 1)), ((0, 1, 0), (1, 0, 0)),
                 ((0, -1, 0), (1, 0, 0)), ((0, 0, 1), (1, 0, 0)), ((0, 0, -1), (-1, 0, 0))]:
        b = (n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0])  # image up
        base = len(pos) // 3
        for s, r in [(0, 0), (1, 0), (1, 1), (0, 1)]:
            pos += [half * (n[k] + (2 * s - 1) * t[k] + (2 * r - 1) * b[k]) for k in range(3)]
            nrm += n
            tan += list(t) + [1.0]
            uv += [s, 1 - r]
        idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return pos, nrm, tan, uv, idx


def plane(half):
    pos = [-half, 0, half, half, 0, half, half, 0, -half, -half, 0, -half]
    return pos, [0, 1, 0] * 4, [1, 0, 0, 1] * 4, [0, 1, 1, 1, 1, 0, 0, 0], [0, 1, 2, 0, 2, 3]


def look_at_matrix(eye, target, up=(0, 1, 0)):
    """Column-major matrix of a node at eye whose −Z looks at target (glTF cameras and lights)."""
    f = [t - e for t, e in zip(target, eye)]
    fl = math.sqrt(sum(c * c for c in f))
    f = [c / fl for c in f]
    r = [f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]]
    rl = math.sqrt(sum(c * c for c in r))
    r = [c / rl for c in r]
    u = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]]
    return r + [0] + u + [0] + [-c for c in f] + [0] + list(eye) + [1]


class Glb:
    def __init__(self):
        self.bin = bytearray()
        self.doc = {"asset": {"version": "2.0", "generator": "kozu scripts/make-showcase-gltf.py"},
                    "buffers": [], "bufferViews": [], "accessors": [], "meshes": [], "nodes": [],
                    "images": [], "textures": [], "materials": [], "samplers": [{"wrapS": 10497, "wrapT": 10497}]}

    def view(self, data):
        while len(self.bin) % 4:
            self.bin.append(0)
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)})
        self.bin += data
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, values, kind, comps):
        fmt = "<%d%s" % (len(values), "f" if kind == 5126 else "I")
        acc = {"bufferView": self.view(struct.pack(fmt, *values)), "componentType": kind,
               "count": len(values) // comps, "type": {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}[comps]}
        if comps == 3 and kind == 5126:
            acc["min"] = [min(values[k::3]) for k in range(3)]
            acc["max"] = [max(values[k::3]) for k in range(3)]
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def texture(self, data):
        self.doc["images"].append({"bufferView": self.view(data), "mimeType": "image/png"})
        self.doc["textures"].append({"source": len(self.doc["images"]) - 1, "sampler": 0})
        return len(self.doc["textures"]) - 1

    def mesh(self, geometry, material, translation):
        pos, nrm, tan, uv, idx = geometry
        prim = {"attributes": {"POSITION": self.accessor(pos, 5126, 3), "NORMAL": self.accessor(nrm, 5126, 3),
                               "TANGENT": self.accessor(tan, 5126, 4), "TEXCOORD_0": self.accessor(uv, 5126, 2)},
                "indices": self.accessor(idx, 5125, 1), "material": material}
        self.doc["meshes"].append({"primitives": [prim]})
        self.doc["nodes"].append({"mesh": len(self.doc["meshes"]) - 1, "translation": translation})

    def write(self, path):
        self.doc["buffers"] = [{"byteLength": len(self.bin)}]
        js = json.dumps(self.doc, separators=(",", ":"), sort_keys=True).encode()
        js += b" " * (-len(js) % 4)
        bn = bytes(self.bin) + b"\0" * (-len(self.bin) % 4)
        with open(path, "wb") as f:
            f.write(struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(js) + 8 + len(bn)))
            f.write(struct.pack("<I4s", len(js), b"JSON") + js)
            f.write(struct.pack("<I4s", len(bn), b"BIN\0") + bn)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default="scenes/showcase.glb")
    args = ap.parse_args()

    g = Glb()
    t_checker = g.texture(png(N, N, 3, checker))
    t_brick = g.texture(png(N, N, 3, brick_color))
    t_brick_n = g.texture(png(N, N, 3, brick_normal))
    t_wood = g.texture(png(N, N, 3, wood))
    t_gold_mr = g.texture(png(N, N, 3, gold_metal_rough))
    g.doc["materials"] = [
        {"name": "ground", "pbrMetallicRoughness": {
            "baseColorTexture": {"index": t_checker, "extensions": {"KHR_texture_transform": {"scale": [6, 6]}}},
            "metallicFactor": 0.0, "roughnessFactor": 0.6}},
        {"name": "brick", "pbrMetallicRoughness": {"baseColorTexture": {"index": t_brick},
                                                   "metallicFactor": 0.0, "roughnessFactor": 0.8},
         "normalTexture": {"index": t_brick_n, "scale": 1.0}},
        {"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.78, 0.34, 1.0],
                                                  "metallicRoughnessTexture": {"index": t_gold_mr},
                                                  "metallicFactor": 1.0, "roughnessFactor": 1.0}},
        {"name": "wood", "pbrMetallicRoughness": {"baseColorTexture": {"index": t_wood},
                                                  "metallicFactor": 0.0, "roughnessFactor": 0.45},
         "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1.0, "clearcoatRoughnessFactor": 0.05}}},
        {"name": "glass", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0.0,
                                                   "roughnessFactor": 0.0},
         "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                        "KHR_materials_ior": {"ior": 1.5}}},
    ]
    g.mesh(plane(6.0), 0, [0, 0, 0])
    g.mesh(sphere(0.6), 1, [-1.5, 0.6, 0.2])
    g.mesh(sphere(0.6), 2, [0.0, 0.6, -0.4])
    g.mesh(cube(0.45), 3, [1.5, 0.45, 0.1])
    g.mesh(sphere(0.35), 4, [0.7, 0.35, 1.1])
    g.doc["cameras"] = [{"type": "perspective",
                         "perspective": {"yfov": 0.55, "aspectRatio": 16 / 9, "znear": 0.05}}]
    g.doc["nodes"].append({"name": "camera", "camera": 0, "matrix": look_at_matrix((0.8, 2.0, 5.2), (0.0, 0.45, 0.0))})
    # The sun: 683 × 3 lux is 3 W/m² in kozu's photometric conversion (683 lm/W).
    g.doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"type": "directional", "name": "sun", "color": [1.0, 0.95, 0.88], "intensity": 683 * 3.0}]}}
    g.doc["nodes"].append({"name": "sun", "extensions": {"KHR_lights_punctual": {"light": 0}},
                           "matrix": look_at_matrix((3, 6, 4), (0, 0, 0))})
    g.doc["scenes"] = [{"nodes": list(range(len(g.doc["nodes"])))}]
    g.doc["scene"] = 0
    g.doc["extensionsUsed"] = ["KHR_texture_transform", "KHR_materials_clearcoat", "KHR_materials_transmission",
                               "KHR_materials_ior", "KHR_lights_punctual"]
    g.write(args.output)
    print("wrote", args.output)


if __name__ == "__main__":
    main()
