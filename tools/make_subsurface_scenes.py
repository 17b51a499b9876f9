#!/usr/bin/env python3
"""Writes the subsurface showcase: scenes/subsurface.json (marble, skin, jade and wax through the
Christensen-Burley BSSRDF), scenes/subsurface_lambert.json (the same objects, Lambertian with the same
albedos) and the procedural meshes they use in scenes/meshes/ (binary PLY with normals).

Usage: python3 tools/make_subsurface_scenes.py   (from the repository root)
"""
import json
import math
import pathlib
import struct

root = pathlib.Path(__file__).resolve().parent.parent


def write_ply(path, verts, normals, tris):
    head = ("ply\nformat binary_little_endian 1.0\ncomment kozu tools/make_subsurface_scenes.py\n"
            f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n"
            "property float nx\nproperty float ny\nproperty float nz\n"
            f"element face {len(tris)}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as f:
        f.write(head.encode())
        for v, n in zip(verts, normals):
            f.write(struct.pack("<6f", *v, *n))
        for t in tris:
            f.write(struct.pack("<B3i", 3, *t))


def grid_mesh(nu, nv, point, wrap_u=True, wrap_v=False):
    """A (u, v) grid of point(u, v) -> (position, normal); u wraps around, v runs pole to pole."""
    verts, normals, tris = [], [], []
    cols = nu if wrap_u else nu + 1
    rows = nv if wrap_v else nv + 1
    for j in range(rows):
        for i in range(cols):
            p, n = point(i / nu, j / nv)
            verts.append(p)
            normals.append(n)
    for j in range(nv):
        for i in range(nu):
            a = j * cols + i
            b = j * cols + (i + 1) % cols if wrap_u else a + 1
            c = ((j + 1) % rows) * cols + (i + 1) % cols if wrap_u else ((j + 1) % rows) * cols + i + 1
            d = ((j + 1) % rows) * cols + i
            for t in ((a, b, c), (a, c, d)):
                pa, pb, pc = (verts[k] for k in t)
                e1 = [pb[k] - pa[k] for k in range(3)]
                e2 = [pc[k] - pa[k] for k in range(3)]
                cr = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
                if sum(x * x for x in cr) > 1e-16:
                    tris.append(t)
    # Outward-facing (counter-clockwise seen from outside): a closed mesh then has a positive volume.
    volume = sum(
        verts[a][0] * (verts[b][1] * verts[c][2] - verts[b][2] * verts[c][1])
        - verts[a][1] * (verts[b][0] * verts[c][2] - verts[b][2] * verts[c][0])
        + verts[a][2] * (verts[b][0] * verts[c][1] - verts[b][1] * verts[c][0]) for a, b, c in tris)
    if volume < 0:
        tris = [(a, c, b) for a, b, c in tris]
    return verts, normals, tris


def normalize(v):
    l = math.sqrt(sum(x * x for x in v))
    return [x / l for x in v]


def torus(R, r):
    def point(u, v):
        a, b = 2 * math.pi * u, 2 * math.pi * v
        n = [math.cos(a) * math.cos(b), math.sin(a) * math.cos(b), math.sin(b)]
        p = [(R + r * math.cos(b)) * math.cos(a), (R + r * math.cos(b)) * math.sin(a), r * math.sin(b)]
        return p, n
    return grid_mesh(128, 48, point, wrap_u=True, wrap_v=True)


def ellipsoid(a, b, c):
    """Outward-facing ellipsoid; v = 0 at the top pole (+y)."""
    def point(u, v):
        phi, th = -2 * math.pi * u, math.pi * v
        s = [math.sin(th) * math.cos(phi), math.cos(th), math.sin(th) * math.sin(phi)]
        p = [a * s[0], b * s[1], c * s[2]]
        n = normalize([s[0] / a, s[1] / b, s[2] / c])
        return p, n
    return grid_mesh(96, 64, point)


def candle(radius, height, cap):
    """A cylinder with a flat bottom and a rounded top (a squashed half-sphere of height `cap`)."""
    def point(u, v):
        phi = -2 * math.pi * u
        c, s = math.cos(phi), math.sin(phi)
        if v < 0.05:  # bottom disk, from the centre out
            t = v / 0.05
            return [radius * t * c, 0.0, radius * t * s], [0.0, -1.0, 0.0]
        if v < 0.6:  # side wall
            t = (v - 0.05) / 0.55
            return [radius * c, (height - cap) * t, radius * s], [c, 0.0, s]
        t = (v - 0.6) / 0.4  # rounded top, to the pole
        th = 0.5 * math.pi * t
        p = [radius * math.cos(th) * c, height - cap + cap * math.sin(th), radius * math.cos(th) * s]
        n = normalize([math.cos(th) * c / radius, math.sin(th) / cap, math.cos(th) * s / radius])
        return p, n
    verts, normals, tris = grid_mesh(96, 80, point)
    # The grid's first row is the bottom centre and the last the top pole; both collapse to points.
    return verts, normals, tris


MATERIALS = {
    # surface albedo A and mean free paths in scene units (the objects are about 1 unit across)
    "marble": {"albedo": [0.87, 0.85, 0.82], "mfp": [0.06, 0.05, 0.045], "roughness": 0.25},
    "skin": {"albedo": [0.85, 0.58, 0.45], "dmfp": [0.30, 0.11, 0.06], "roughness": 0.35},
    "jade": {"albedo": [0.40, 0.80, 0.52], "mfp": [0.12, 0.30, 0.16], "ior": 1.62},
    "wax": {"albedo": [0.92, 0.74, 0.42], "mfp": [0.25, 0.16, 0.09], "roughness": 0.3,
            "parameterization": "diffuse"},
}


def scene(subsurface):
    materials = {
        "floor": {"type": "diffuse", "albedo": [0.30, 0.29, 0.28]},
        "wall": {"type": "diffuse", "albedo": [0.10, 0.11, 0.13]},
        "black": {"type": "diffuse", "albedo": 0.0},
    }
    for name, m in MATERIALS.items():
        materials[name] = dict({"type": "subsurface"}, **m) if subsurface else {"type": "diffuse", "albedo": m["albedo"]}
    shapes = [
        {"type": "quad", "material": "floor", "vertices": [[-8, 0, 6], [8, 0, 6], [8, 0, -3], [-8, 0, -3]]},
        {"type": "quad", "material": "wall", "vertices": [[-8, 0, -3], [8, 0, -3], [8, 6, -3], [-8, 6, -3]]},
        {"type": "sphere", "center": [-2.35, 0.62, 0.0], "radius": 0.62, "material": "marble"},
        {"type": "mesh", "file": "meshes/leaf.ply", "material": "skin",
         "transform": {"rotate": [0, 1, 0, 25], "translate": [-0.8, 0.72, 0.1]}},
        {"type": "mesh", "file": "meshes/torus.ply", "material": "jade",
         "transform": {"rotate": [0, 1, 0, -20], "translate": [0.75, 0.62, 0.0]}},
        {"type": "mesh", "file": "meshes/candle.ply", "material": "wax", "transform": {"translate": [2.3, 0.0, 0.0]}},
        # key light: small, above front left
        {"type": "quad", "material": "black", "emission": [60, 57, 52],
         "vertices": [[-3.4, 4.2, 1.8], [-2.6, 4.2, 1.8], [-2.6, 4.2, 2.6], [-3.4, 4.2, 2.6]]},
        # back light: small, low behind the objects, facing the camera
        {"type": "quad", "material": "black", "emission": [80, 55, 35],
         "vertices": [[-1.05, 0.45, -0.8], [-0.55, 0.45, -0.8], [-0.55, 0.95, -0.8], [-1.05, 0.95, -0.8]]},
    ]
    kind = "Christensen-Burley subsurface" if subsurface else "Lambertian (same albedos)"
    return {
        "comment": f"kozu subsurface showcase, {kind}: marble sphere, skin leaf, jade torus, wax candle; a small key "
                   "light above left and a small warm light behind. Generated by tools/make_subsurface_scenes.py.",
        "camera": {"type": "perspective", "position": [0.0, 1.7, 6.6], "look_at": [0.0, 0.55, 0.0], "fov": 30,
                   "resolution": [1280, 720]},
        "render": {"spp": 256, "max_depth": 16, "seed": 0},
        "materials": materials,
        "shapes": shapes,
        "lights": [{"type": "environment", "radiance": [0.03, 0.035, 0.045]}],
    }


write_ply(root / "scenes/meshes/torus.ply", *torus(0.44, 0.17))
write_ply(root / "scenes/meshes/leaf.ply", *ellipsoid(0.42, 0.66, 0.07))
write_ply(root / "scenes/meshes/candle.ply", *candle(0.34, 1.25, 0.18))
for sss, file in ((True, "subsurface.json"), (False, "subsurface_lambert.json")):
    (root / "scenes" / file).write_text(json.dumps(scene(sss), indent=1) + "\n")
    print("wrote", root / "scenes" / file)
