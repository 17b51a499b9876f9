"""Files the `interior` and `product` comparison scenes read (bench/cycles/surfaces.py), written once into the
comparison's folder by compare.py (or scenes.py's main) with numpy and kozu's Python module:

  interior.gltf (+ interior.bin, floor.png, plaster.png)  a textured room, 6 x 3 x 5 m, with a window in its
      +x wall (1.6 x 1.2 m) and a table, a cabinet and a low box inside; glTF's metallic-roughness materials
      (metallic 0, roughness 0.9), base-colour textures on the floor and the walls. The same file is imported by
      kozu (`gltf` shape) and by Blender's glTF importer.
  sky.exr    a lat-long sky for the interior: a blue gradient over a dark ground and a 4-degree sun, 40 degrees up,
      standing in front of the window.
  studio.exr a lat-long photo studio for the product shot: a dark grey room with two large softboxes and a warm
      floor bounce.
Deterministic: the same bytes on every run.
"""
import json
import math
import os
import struct

import numpy as np

SUN = dict(azimuth=0.0, elevation=40.0, size=4.0, radiance=1500.0)  # degrees; azimuth 0 looks along kozu's +x


def _latlong_dirs(w, h):
    """kozu's lat-long directions (y-up): u = 1/2 + atan2(x, -z) / 2 pi, v = acos(y) / pi, rows from the top."""
    u = (np.arange(w) + 0.5) / w
    v = (np.arange(h) + 0.5) / h
    phi = (u - 0.5) * 2 * np.pi
    theta = v * np.pi
    st = np.sin(theta)[:, None]
    x = st * np.sin(phi)[None, :]
    z = -st * np.cos(phi)[None, :]
    y = np.cos(theta)[:, None] * np.ones_like(phi)[None, :]
    return x, y, z


def sky(w=512, h=256):
    x, y, z = _latlong_dirs(w, h)
    img = np.zeros((h, w, 3))
    up = np.clip(y, 0, 1)[..., None]
    img[:] = np.where(y[..., None] > 0, np.array([0.9, 1.0, 1.1]) * (1 - up) + np.array([0.25, 0.45, 1.0]) * up,
                      np.array([0.12, 0.11, 0.1]))
    el, az = math.radians(SUN["elevation"]), math.radians(SUN["azimuth"])
    sun = np.array([math.cos(el) * math.cos(az), math.sin(el), math.cos(el) * math.sin(az)])
    cosang = x * sun[0] + y * sun[1] + z * sun[2]
    img[cosang > math.cos(math.radians(SUN["size"] / 2))] = SUN["radiance"] * np.array([1.0, 0.92, 0.8])
    return img.astype(np.float32)


def studio(w=512, h=256):
    x, y, z = _latlong_dirs(w, h)
    img = np.full((h, w, 3), 0.08)
    img[y < 0] = np.array([0.18, 0.14, 0.1])  # warm floor bounce
    # Two softboxes: a large one up and to the left of the camera (-x, +y), a strip at the right (+x).
    key = (x < -0.35) & (y > 0.35) & (np.abs(z) < 0.5)
    strip = (x > 0.8) & (np.abs(y - 0.2) < 0.25) & (np.abs(z) < 0.3)
    img[key] = 12.0
    img[strip] = 6.0
    return img.astype(np.float32)


def _texture(kind, n=256):
    yy, xx = (np.mgrid[0:n, 0:n] + 0.5) / n
    rng = np.random.default_rng(3)
    if kind == "floor":  # planks: stripes of varying warm tone, dark seams
        plank = np.floor(yy * 8)
        tone = 0.35 + 0.15 * rng.random(8)[plank.astype(int)]
        grain = 0.03 * np.sin(2 * np.pi * (xx * 40 + 3 * yy))
        base = (tone + grain)[..., None] * np.array([1.0, 0.72, 0.45])
        base[(yy * 8) % 1 < 0.03] *= 0.35
        return np.clip(base, 0, 1)
    noise = rng.random((n // 8, n // 8)).repeat(8, 0).repeat(8, 1)  # plaster: pale, blotchy
    return np.clip((0.72 + 0.06 * noise)[..., None] * np.array([1.0, 0.97, 0.92]), 0, 1)


def _box(lo, hi, inward=False):
    """Positions, normals, uvs (per face, scaled by size in metres) and indices of a box."""
    pos, nrm, uv, idx = [], [], [], []
    for axis in range(3):
        for side in (0, 1):
            n = [0.0, 0.0, 0.0]
            n[axis] = (1.0 if side else -1.0) * (-1.0 if inward else 1.0)
            a, b = (axis + 1) % 3, (axis + 2) % 3
            c = (lo, hi)[side][axis]
            corners = []
            for ua, ub in ((0, 0), (1, 0), (1, 1), (0, 1)):
                p = [0.0, 0.0, 0.0]
                p[axis], p[a], p[b] = c, (lo, hi)[ua][a], (lo, hi)[ub][b]
                corners.append((p, [p[a], p[b]]))
            base = len(pos)
            for p, t in corners:
                pos.append(p)
                nrm.append(n)
                uv.append(t)
            e1 = [corners[1][0][k] - corners[0][0][k] for k in range(3)]
            e2 = [corners[2][0][k] - corners[0][0][k] for k in range(3)]
            cr = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
            if sum(cr[k] * n[k] for k in range(3)) > 0:
                idx += [base, base + 1, base + 2, base, base + 2, base + 3]
            else:
                idx += [base, base + 2, base + 1, base, base + 3, base + 2]
    return pos, nrm, uv, idx


def _quad_x(x, y0, y1, z0, z1, normal_sign):
    """A quad in the plane x, facing normal_sign along x; uvs in metres."""
    pos = [[x, y0, z0], [x, y0, z1], [x, y1, z1], [x, y1, z0]]
    nrm = [[normal_sign, 0.0, 0.0]] * 4
    uv = [[z0, y0], [z1, y0], [z1, y1], [z0, y1]]
    # (0, 0, z1 - z0) x (0, y1 - y0, z1 - z0) points along -x: flip for a face towards +x.
    idx = [0, 2, 1, 0, 3, 2] if normal_sign > 0 else [0, 1, 2, 0, 2, 3]
    return pos, nrm, uv, idx


def interior(folder):
    """Writes interior.gltf, interior.bin, floor.png and plaster.png into folder."""
    import kozu
    for name in ("floor", "plaster"):
        # kozu's clamp tone map writes the texture's sRGB encoding of these linear values.
        kozu.write_image(os.path.join(folder, name + ".png"), _texture(name), tonemap="clamp")
    X, Y, Z = 3.0, 3.0, 2.5  # half-width, height, half-depth
    wx0, wx1, wy0, wy1 = -0.8, 0.8, 0.9, 2.1  # the window in the +x wall: z range and y range
    parts = {"floor": [], "plaster": [], "wood": [], "cloth": []}
    parts["floor"].append(_quad_y(0.0, -X, X, -Z, Z, +1))
    parts["plaster"] += [_quad_y(Y, -X, X, -Z, Z, -1), _quad_x(-X, 0, Y, -Z, Z, +1),
                         _quad_z(-Z, -X, X, 0, Y, +1), _quad_z(Z, -X, X, 0, Y, -1)]
    # The +x wall around the window (facing -x, into the room), and the reveal's four sides.
    for y0, y1, z0, z1 in ((0, wy0, -Z, Z), (wy1, Y, -Z, Z), (wy0, wy1, -Z, wx0), (wy0, wy1, wx1, Z)):
        parts["plaster"].append(_quad_x(X, y0, y1, z0, z1, -1))
    parts["wood"] += [_box([0.2, 0.72, -0.9], [1.6, 0.78, 0.1])] + [
        _box([x, 0.0, z], [x + 0.06, 0.72, z + 0.06]) for x in (0.25, 1.49) for z in (-0.85, -0.01)]
    parts["wood"].append(_box([-2.9, 0.0, -2.4], [-2.2, 1.8, -0.8]))  # cabinet
    parts["cloth"].append(_box([-1.2, 0.0, 0.9], [0.4, 0.45, 1.9]))  # a low box, a bench
    colours = {"floor": None, "plaster": None, "wood": [0.45, 0.28, 0.15], "cloth": [0.2, 0.3, 0.55]}

    blob, views, accessors, meshes, nodes = bytearray(), [], [], [], []

    def add_view(data, target):
        while len(blob) % 4:
            blob.append(0)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data), "target": target})
        blob.extend(data)
        return len(views) - 1

    def add_accessor(values, kind):
        flat = [c for v in values for c in (v if isinstance(v, list) else [v])]
        if kind == "SCALAR":
            view = add_view(struct.pack(f"<{len(flat)}I", *flat), 34963)
            accessors.append({"bufferView": view, "componentType": 5125, "count": len(flat), "type": "SCALAR"})
        else:
            view = add_view(struct.pack(f"<{len(flat)}f", *flat), 34962)
            acc = {"bufferView": view, "componentType": 5126, "count": len(values), "type": kind}
            if kind == "VEC3":
                acc["min"] = [min(v[k] for v in values) for k in range(3)]
                acc["max"] = [max(v[k] for v in values) for k in range(3)]
            accessors.append(acc)
        return len(accessors) - 1

    materials, textures, images = [], [], []
    for i, (name, pieces) in enumerate(parts.items()):
        pos, nrm, uv, idx = [], [], [], []
        for p, n, t, ix in pieces:
            base = len(pos)
            pos += p
            nrm += n
            uv += [[c / 2.0 for c in tt] for tt in t]  # a texture repeat per 2 m
            idx += [base + k for k in ix]
        mat = {"name": name, "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.9}}
        if colours[name] is None:
            images.append({"uri": name + ".png"})
            textures.append({"source": len(images) - 1})
            mat["pbrMetallicRoughness"]["baseColorTexture"] = {"index": len(textures) - 1}
        else:
            mat["pbrMetallicRoughness"]["baseColorFactor"] = colours[name] + [1.0]
        materials.append(mat)
        meshes.append({"name": name, "primitives": [{
            "attributes": {"POSITION": add_accessor(pos, "VEC3"), "NORMAL": add_accessor(nrm, "VEC3"),
                           "TEXCOORD_0": add_accessor(uv, "VEC2")},
            "indices": add_accessor(idx, "SCALAR"), "material": i}]})
        nodes.append({"name": name, "mesh": i})
    with open(os.path.join(folder, "interior.bin"), "wb") as f:
        f.write(bytes(blob))
    gltf = {"asset": {"version": "2.0", "generator": "kozu bench/cycles/assets.py"},
            "scene": 0, "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes, "meshes": meshes,
            "materials": materials, "textures": textures, "images": images, "accessors": accessors,
            "bufferViews": views, "buffers": [{"uri": "interior.bin", "byteLength": len(blob)}]}
    with open(os.path.join(folder, "interior.gltf"), "w") as f:
        json.dump(gltf, f, indent=1)


def _quad_y(y, x0, x1, z0, z1, normal_sign):
    pos = [[x0, y, z0], [x1, y, z0], [x1, y, z1], [x0, y, z1]]
    nrm = [[0.0, normal_sign, 0.0]] * 4
    uv = [[x0, z0], [x1, z0], [x1, z1], [x0, z1]]
    # (x1 - x0, 0, 0) x (x1 - x0, 0, z1 - z0) points along -y: flip for an upward face.
    idx = [0, 2, 1, 0, 3, 2] if normal_sign > 0 else [0, 1, 2, 0, 2, 3]
    return pos, nrm, uv, idx


def _quad_z(z, x0, x1, y0, y1, normal_sign):
    pos = [[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]]
    nrm = [[0.0, 0.0, normal_sign]] * 4
    uv = [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
    idx = [0, 1, 2, 0, 2, 3] if normal_sign > 0 else [0, 2, 1, 0, 3, 2]
    return pos, nrm, uv, idx


def write(folder):
    """Every asset, into folder (created)."""
    import kozu
    os.makedirs(folder, exist_ok=True)
    interior(folder)
    kozu.write_image(os.path.join(folder, "sky.exr"), sky())
    kozu.write_image(os.path.join(folder, "studio.exr"), studio())
