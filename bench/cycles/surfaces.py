"""The surface scenes of kozu's comparison with Cycles (issue: surfaces against Cycles), each built twice from one
description: as a kozu scene (JSON) and, inside Blender, with bpy for Cycles.

Everything is geometry, so the two renderers see the same emitters: lights are emissive meshes in Blender (an
Emission shader of strength L is radiance L in Cycles 3.4, as an emissive kozu shape's "emission"), one-sided ones
through a Backfacing mix; kozu's spheres are analytic, Blender's smooth UV spheres of 128 x 64 segments (emissive
ones 32 x 16: their area 0.8 % below the sphere's, 0.05 % for 128 x 64). Materials: diffuse; Glossy BSDF
(GGX, white: F = 1) = kozu's conductor without eta and without compensation; Glass BSDF (GGX) = kozu's dielectric.
Roughness r is the same number in both (alpha = r^2).

  cornell   the Cornell box: white, red and green diffuse walls, two boxes, a ceiling light
  spheres   a mirror-like, a rough glossy and a rough glass sphere on a diffuse floor under a quad light and a dim sky
  emitters  300 small emissive triangles of three brightnesses and 60 small emissive spheres among diffuse boxes
  interior  a textured glTF room (bench/cycles/assets.py) lit through its window by an HDR sky with a sun
  product   a glossy, a glass and a diffuse object on a floor under an HDR photo studio

The glTF room is read by kozu's `gltf` shape and by Blender's glTF importer, so its materials are each renderer's
glTF material: kozu's `standard` (Lambert base, energy-compensated coat) and Cycles 3.4's Principled BSDF (Disney
diffuse, single-scattering GGX); their means differ by that. HDR skies are placed by kozu's `rotate` r and by a
Mapping node turning Blender's lookup by -90 - r degrees about z (docs/blender.md, the environment's turn).
"""
import math
import os
import random

SURFACE_SCENES = {
    "cornell": "the Cornell box: diffuse walls, two boxes, a 0.5 x 0.5 ceiling light of radiance 15",
    "spheres": "glossy (r 0.15 and 0.45) and rough glass (r 0.2, IOR 1.5) spheres on a floor, a quad light, a dim sky",
    "emitters": "300 small emissive triangles (radiance 2, 8, 30) and 60 emissive spheres among diffuse boxes",
    "interior": "a textured glTF room, 6 x 3 x 5 m, lit through a 1.6 x 1.2 m window by an HDR sky with a 4-degree sun",
    "product": "glossy (r 0.2), glass (r 0.05) and diffuse objects on a floor under an HDR studio of two softboxes",
}

WHITE, RED, GREEN = [0.73, 0.73, 0.73], [0.63, 0.065, 0.05], [0.14, 0.45, 0.091]
DIM_SKY = [0.05, 0.06, 0.08]


def box_mesh(lo, hi):
    """A closed box, outward-facing triangles."""
    p = [[(lo, hi)[x][0], (lo, hi)[y][1], (lo, hi)[z][2]] for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    idx = []
    for a, b, c, d in [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]:
        idx += [a, b, c, a, c, d]
    return p, idx


def _quad(a, b, c, d):
    """Corners in order; the front faces along (b - a) x (c - a)."""
    return [a, b, c, d], [0, 1, 2, 0, 2, 3]


def describe(name):
    """The scene as renderer-neutral parts: camera, and items (kind, data) — 'mesh' (positions, indices, material),
    'sphere' (centre, radius, material), where a material is ('diffuse', rgb), ('glossy', r), ('glass', r, ior) or
    ('emission', L, two_sided) — and the sky radiance."""
    items, sky = [], None
    if name == "cornell":
        camera = dict(position=[0, 1, 3.4], look_at=[0, 1, 0], fov=40)
        items += [("mesh", *_quad([-1, 0, -1], [-1, 0, 1], [1, 0, 1], [1, 0, -1]), ("diffuse", WHITE)),  # floor, up
                  ("mesh", *_quad([-1, 2, -1], [1, 2, -1], [1, 2, 1], [-1, 2, 1]), ("diffuse", WHITE)),  # ceiling
                  ("mesh", *_quad([-1, 0, -1], [1, 0, -1], [1, 2, -1], [-1, 2, -1]), ("diffuse", WHITE)),  # back
                  ("mesh", *_quad([-1, 0, -1], [-1, 2, -1], [-1, 2, 1], [-1, 0, 1]), ("diffuse", RED)),  # left
                  ("mesh", *_quad([1, 0, -1], [1, 0, 1], [1, 2, 1], [1, 2, -1]), ("diffuse", GREEN)),  # right
                  ("mesh", *box_mesh([-0.65, 0, -0.55], [-0.05, 1.2, 0.05]), ("diffuse", WHITE)),
                  ("mesh", *box_mesh([0.1, 0, -0.1], [0.7, 0.6, 0.5]), ("diffuse", WHITE)),
                  ("mesh", *_quad([0.25, 1.99, -0.25], [0.25, 1.99, 0.25], [-0.25, 1.99, 0.25], [-0.25, 1.99, -0.25]),
                   ("emission", 15.0, False))]
    elif name == "spheres":
        camera = dict(position=[0, 1.2, 4.5], look_at=[0, 0.6, 0], fov=40)
        sky = DIM_SKY
        items += [("mesh", *_quad([-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]), ("diffuse", [0.5, 0.5, 0.5])),
                  ("sphere", [-1.3, 0.6, 0], 0.6, ("glossy", 0.15)),
                  ("sphere", [0, 0.6, 0], 0.6, ("glass", 0.2, 1.5)),
                  ("sphere", [1.3, 0.6, 0], 0.6, ("glossy", 0.45)),
                  ("mesh", *_quad([0.5, 3.2, -0.5], [0.5, 3.2, 0.5], [-0.5, 3.2, 0.5], [-0.5, 3.2, -0.5]),
                   ("emission", 10.0, False))]
    elif name == "emitters":
        camera = dict(position=[0, 2.2, 5.5], look_at=[0, 0.5, 0], fov=45)
        rng = random.Random(7)
        items += [("mesh", *_quad([-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]), ("diffuse", [0.5, 0.5, 0.5]))]
        for i in range(6):
            x, z = -2.5 + i, rng.uniform(-1.5, 1.0)
            items.append(("mesh", *box_mesh([x - 0.25, 0, z - 0.25], [x + 0.25, rng.uniform(0.4, 1.4), z + 0.25]),
                          ("diffuse", [0.6, 0.6, 0.6])))
        for i in range(300):
            c = [rng.uniform(-3, 3), rng.uniform(0.2, 2.5), rng.uniform(-3, 1.5)]
            tri = [[c[k] + rng.uniform(-0.06, 0.06) for k in range(3)] for _ in range(3)]
            items.append(("mesh", tri, [0, 1, 2], ("emission", [2.0, 8.0, 30.0][i % 3], True)))
        for i in range(60):
            items.append(("sphere", [rng.uniform(-3, 3), rng.uniform(0.05, 2.0), rng.uniform(-3, 1.5)], 0.04,
                          ("emission", 5.0 + 15.0 * (i % 2), False)))
    elif name == "interior":
        camera = dict(position=[-2.6, 1.6, 2.0], look_at=[1.5, 0.8, -0.5], fov=60)
        items.append(("gltf", "interior.gltf"))
        # The window (bench/cycles/assets.py) as a portal for both renderers, corners in a quad light's order,
        # front into the room.
        sky = {"file": "sky.exr", "rotate": 0.0,
               "portals": [[[3.0, 0.9, -0.8], [3.0, 0.9, 0.8], [3.0, 2.1, 0.8], [3.0, 2.1, -0.8]]]}
    elif name == "product":
        camera = dict(position=[0, 0.8, 3.0], look_at=[0, 0.35, 0], fov=35)
        sky = {"file": "studio.exr", "rotate": 0.0}
        items += [("mesh", *_quad([-3, 0, -3], [-3, 0, 3], [3, 0, 3], [3, 0, -3]), ("diffuse", [0.4, 0.4, 0.4])),
                  ("sphere", [-0.55, 0.35, 0.0], 0.35, ("glossy", 0.2)),
                  ("sphere", [0.35, 0.3, 0.1], 0.3, ("glass", 0.05, 1.5)),
                  ("mesh", *box_mesh([0.55, 0.0, -0.6], [0.95, 0.5, -0.2]), ("diffuse", [0.7, 0.2, 0.15]))]
    else:
        raise KeyError(name)
    return camera, items, sky


def portals_for(renderer):
    """Whether renderer ("kozu" or "cycles") gets the scene's portals: compare.py --portals sets
    KOZU_BENCH_PORTALS to both (the default), none, kozu or cycles."""
    return os.environ.get("KOZU_BENCH_PORTALS", "both") in ("both", renderer)


def _kozu_material(mat, materials):
    kind = mat[0]
    key = f"m{len(materials)}"
    if kind == "diffuse":
        materials[key] = {"type": "diffuse", "albedo": mat[1]}
    elif kind == "glossy":
        materials[key] = {"type": "conductor", "roughness": mat[1]}
    elif kind == "glass":
        materials[key] = {"type": "dielectric", "roughness": mat[1], "ior": mat[2]}
    return key


def _blender_portals(b, portals):
    """Cycles' portals: rectangular area lights marked is_portal, emitting (their local -z) into the room."""
    import bpy
    from mathutils import Matrix, Vector
    for i, c in enumerate(portals):
        p = [Vector(b(v)) for v in c]
        e1, e3 = p[1] - p[0], p[3] - p[0]
        # b() is a rotation, so the front normal e1 x e3 maps to Blender's; local x = e3, y = e1 make z = -front.
        x, y = e3.normalized(), e1.normalized()
        z = x.cross(y)
        light = bpy.data.lights.new(f"portal{i}", "AREA")
        light.shape = "RECTANGLE"
        light.size, light.size_y = e3.length, e1.length
        light.cycles.is_portal = True
        obj = bpy.data.objects.new(f"portal{i}", light)
        obj.matrix_world = Matrix.Translation((p[0] + p[2]) / 2) @ Matrix((x, y, z)).transposed().to_4x4()
        bpy.context.scene.collection.objects.link(obj)


def kozu_scene(name, res, spp, seed, depth, assets="."):
    """assets: the folder of bench/cycles/assets.py's files (interior, product)."""
    camera, items, sky = describe(name)
    shapes, materials = [], {}
    for item in items:
        if item[0] == "gltf":
            shapes.append({"type": "gltf", "file": os.path.abspath(os.path.join(assets, item[1]))})
            continue
        if item[0] == "mesh":
            _, positions, indices, mat = item
            shape = {"type": "mesh", "positions": positions, "indices": indices}
        else:
            _, centre, radius, mat = item
            shape = {"type": "sphere", "center": centre, "radius": radius}
        if mat[0] == "emission":
            shape["emission"] = mat[1]
            if mat[2]:
                shape["two_sided"] = True
        else:
            shape["material"] = _kozu_material(mat, materials)
        shapes.append(shape)
    scene = {
        "comment": f"bench/cycles scene '{name}': {SURFACE_SCENES[name]}",
        "camera": {"type": "perspective", **camera, "resolution": [res, res]},
        "render": {"spp": spp, "max_depth": depth, "seed": seed, "filter": "box"},
        "materials": materials,
        "shapes": shapes,
    }
    if isinstance(sky, dict):
        scene["lights"] = [{"type": "environment", "file": os.path.abspath(os.path.join(assets, sky["file"])),
                            "rotate": sky["rotate"]}]
        if sky.get("portals") and portals_for("kozu"):
            scene["lights"][0]["portals"] = [{"vertices": p} for p in sky["portals"]]
    elif sky:
        scene["lights"] = [{"type": "environment", "radiance": sky}]
    return scene


def blender_build(name, b, material_of, assets="."):
    """Adds the scene's objects to the open Blender scene. b maps a kozu point to Blender's; material_of(name,
    surface_fn) makes a material from a node-building function. Returns (camera, sky): sky an RGB, or a dict
    {"file": absolute path, "rotate": kozu's degrees}."""
    import bpy

    camera, items, sky = describe(name)
    cache = {}

    def bl_material(mat):
        key = repr(mat)
        if key in cache:
            return cache[key]
        kind = mat[0]

        def surface(nt):
            if kind == "diffuse":
                n = nt.nodes.new("ShaderNodeBsdfDiffuse")
                n.inputs["Color"].default_value = (*mat[1], 1)
                return n
            if kind in ("glossy", "glass"):
                n = nt.nodes.new("ShaderNodeBsdfGlossy" if kind == "glossy" else "ShaderNodeBsdfGlass")
                n.distribution = "GGX"
                n.inputs["Color"].default_value = (1, 1, 1, 1)
                n.inputs["Roughness"].default_value = mat[1]
                if kind == "glass":
                    n.inputs["IOR"].default_value = mat[2]
                return n
            e = nt.nodes.new("ShaderNodeEmission")
            e.inputs["Color"].default_value = (1, 1, 1, 1)
            e.inputs["Strength"].default_value = mat[1]
            if mat[2]:
                return e
            # One-sided: black where the back faces the ray (kozu's emitters emit along their front only).
            black = nt.nodes.new("ShaderNodeEmission")
            black.inputs["Strength"].default_value = 0.0
            geo = nt.nodes.new("ShaderNodeNewGeometry")
            mix = nt.nodes.new("ShaderNodeMixShader")
            nt.links.new(geo.outputs["Backfacing"], mix.inputs["Fac"])
            nt.links.new(e.outputs[0], mix.inputs[1])
            nt.links.new(black.outputs[0], mix.inputs[2])
            return mix

        cache[key] = material_of(f"{kind}{len(cache)}", surface)
        return cache[key]

    # One Blender object per material: meshes of a material merged (300 emissive triangles stay one object).
    merged = {}
    for item in items:
        if item[0] == "gltf":
            # Debian 12's Blender 3.4 glTF importer still uses np.bool, which Debian's numpy 1.24 removed: the alias
            # is restored for it. The importer turns glTF's y-up into z-up as b() does.
            import numpy as np
            if not hasattr(np, "bool"):
                np.bool = bool
            bpy.ops.import_scene.gltf(filepath=os.path.join(assets, item[1]))
            continue
        if item[0] == "mesh":
            _, positions, indices, mat = item
            verts, faces = merged.setdefault(repr(mat), (mat, [], []))[1:]
            base = len(verts)
            verts += [tuple(b(p)) for p in positions]
            faces += [tuple(base + i for i in indices[k:k + 3]) for k in range(0, len(indices), 3)]
        else:
            _, centre, radius, mat = item
            emissive = mat[0] == "emission"
            bpy.ops.mesh.primitive_uv_sphere_add(segments=32 if emissive else 128, ring_count=16 if emissive else 64,
                                                 radius=radius, location=b(centre))
            obj = bpy.context.object
            bpy.ops.object.shade_smooth()
            obj.data.materials.append(bl_material(mat))
    for i, (mat, verts, faces) in enumerate(merged.values()):
        mesh = bpy.data.meshes.new(f"mesh{i}")
        mesh.from_pydata(verts, [], faces)
        mesh.update()
        obj = bpy.data.objects.new(f"mesh{i}", mesh)
        bpy.context.scene.collection.objects.link(obj)
        mesh.materials.append(bl_material(mat))
    if isinstance(sky, dict):
        if portals_for("cycles"):
            _blender_portals(b, sky.get("portals", []))
        return camera, {"file": os.path.abspath(os.path.join(assets, sky["file"])), "rotate": sky["rotate"]}
    return camera, sky or [0, 0, 0]
