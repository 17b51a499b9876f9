"""The exporter's mappings that the rendered comparisons (run_scene.py) do not show, checked on the JSON it writes:
    blender -b --factory-startup --python-exit-code 1 --python tests/blender/check_export.py -- OUT_DIR
Each check builds a small scene, exports it and asserts the keys kozu reads; a failure raises (exit status 1).
"""
import json
import math
import os
import shutil
import sys

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "..", "blender"))
import scenes  # noqa: E402

out = os.path.abspath(sys.argv[sys.argv.index("--") + 1])
if os.path.isdir(out):
    shutil.rmtree(out)
os.makedirs(out)
checked = []


def export(name):
    import addon_utils
    addon_utils.enable("kozu_blender", default_set=True)
    path = os.path.join(out, name + ".json")
    assert bpy.ops.export_scene.kozu(filepath=path) == {"FINISHED"}
    with open(path) as f:
        return json.load(f)


def base():
    scenes.reset()
    scenes.add(bpy.ops.mesh.primitive_plane_add, scenes.diffuse("floor", (0.5, 0.5, 0.5)), size=4)
    return scenes.camera((0, -5, 2), (0, 0, 0))


def check(name):
    def wrap(fn):
        fn()
        checked.append(name)
        return fn
    return wrap


@check("camera: panorama, focus object, time limit, adaptive sampling, colour management")
def _():
    cam = base()
    target = bpy.data.objects.new("focus", None)
    bpy.context.scene.collection.objects.link(target)
    target.location = (0, 0, 0)
    cam.data.dof.use_dof = True
    cam.data.dof.focus_object = target
    cam.data.dof.aperture_fstop = 2.0
    s = bpy.context.scene
    s.cycles.time_limit = 30.0
    s.cycles.use_adaptive_sampling = True
    s.cycles.adaptive_threshold = 0.02
    s.cycles.adaptive_min_samples = 16
    s.view_settings.view_transform = "Filmic"
    s.view_settings.exposure = 1.5
    s.render.film_transparent = True
    j = export("camera")
    c = j["camera"]
    assert c["type"] == "thinlens", c
    want = math.dist((0, -5, 2), (0, 0, 0))  # the target lies on the view axis
    assert abs(c["focus_distance"] - want) < 1e-4, (c["focus_distance"], want)
    assert abs(c["aperture_radius"] - 0.035 / 4) < 1e-9, c  # scenes.camera's 35 mm lens at f/2
    r = j["render"]
    assert r["time_limit"] == 30.0 and abs(r["noise_threshold"] - 0.02) < 1e-7 and r["min_spp"] == 16, r
    cmd = j["comment"]["render_with"]
    assert cmd[cmd.index("--tonemap") + 1] == "agx" and cmd[cmd.index("--exposure") + 1] == "1.5", cmd
    assert "--alpha" in cmd, cmd
    assert any("Filmic" in line for line in j["comment"]["not_mapped_exactly"]), j["comment"]
    cam.data.type = "PANO"
    if hasattr(cam.data, "panorama_type"):
        cam.data.panorama_type = "EQUIRECTANGULAR"
    else:
        cam.data.cycles.panorama_type = "EQUIRECTANGULAR"
    assert export("panorama")["camera"]["type"] == "panorama"


@check("shaders: Transparent, Mix of a BSDF and Emission, Glossy multiscatter and Beckmann, an unknown shader")
def _():
    base()
    transparent = scenes.node_material("hole", "ShaderNodeBsdfTransparent")
    scenes.add(bpy.ops.mesh.primitive_cube_add, transparent, size=0.5, location=(-1, 0, 0.3))
    mixed = scenes.node_material("glowing", "ShaderNodeBsdfDiffuse", Color=(0.2, 0.3, 0.4, 1))
    nt = mixed.node_tree
    e = nt.nodes.new("ShaderNodeEmission")
    e.inputs["Strength"].default_value = 2.0
    mix = nt.nodes.new("ShaderNodeMixShader")
    mix.inputs["Fac"].default_value = 0.25
    nt.links.new(nt.nodes["Diffuse BSDF"].outputs[0], mix.inputs[1])
    nt.links.new(e.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], nt.nodes["Material Output"].inputs["Surface"])
    scenes.add(bpy.ops.mesh.primitive_cube_add, mixed, size=0.5, location=(0, 0, 0.3))
    ms = scenes.node_material("ms", "ShaderNodeBsdfGlossy", Color=(1, 1, 1, 1), Roughness=0.5)
    ms.node_tree.nodes["Glossy BSDF"].distribution = "MULTI_GGX"
    beck = scenes.node_material("beck", "ShaderNodeBsdfGlossy", Color=(1, 1, 1, 1), Roughness=0.3)
    beck.node_tree.nodes["Glossy BSDF"].distribution = "BECKMANN"
    toon = scenes.node_material("toon", "ShaderNodeBsdfToon")
    for i, m in enumerate((ms, beck, toon)):
        scenes.add(bpy.ops.mesh.primitive_cube_add, m, size=0.3, location=(1 + 0.5 * i, 0, 0.3))
    j = export("shaders")
    mats = j["materials"]
    assert mats["hole"]["opacity"] == 0.0, mats["hole"]
    assert mats["glowing"]["type"] == "diffuse", mats["glowing"]
    glow = [s for s in j["shapes"] if s.get("material") == "glowing"][0]
    assert all(abs(c - 0.5) < 1e-6 for c in glow["emission"]), glow  # strength 2 at mix weight 0.25
    assert mats["ms"] == {"type": "conductor", "roughness": 0.5, "multiscatter": "compensated"}, mats["ms"]
    assert mats["beck"]["distribution"] == "beckmann", mats["beck"]
    assert mats["toon"]["type"] == "diffuse", mats["toon"]
    assert any("toon" in line and "no kozu model" in line for line in j["comment"]["not_mapped_exactly"])


@check("visibility: disabled in renders (object and collection), hidden from the camera, viewport-hidden")
def _():
    base()
    a = scenes.add(bpy.ops.mesh.primitive_cube_add, scenes.diffuse("a", (1, 0, 0)), size=0.5, location=(-1, 0, 0.3))
    a.hide_render = True
    hidden = bpy.data.collections.new("hidden")
    bpy.context.scene.collection.children.link(hidden)
    b = scenes.add(bpy.ops.mesh.primitive_cube_add, scenes.diffuse("b", (0, 1, 0)), size=0.5, location=(0, 0, 0.3))
    for c in b.users_collection:
        c.objects.unlink(b)
    hidden.objects.link(b)
    hidden.hide_render = True
    c = scenes.add(bpy.ops.mesh.primitive_cube_add, scenes.diffuse("c", (0, 0, 1)), size=0.5, location=(1, 0, 0.3))
    c.visible_camera = False
    d = scenes.add(bpy.ops.mesh.primitive_cube_add, scenes.diffuse("d", (1, 1, 0)), size=0.5, location=(2, 0, 0.3))
    d.hide_set(True)  # hidden in the viewport only: a render has it
    j = export("visibility")
    mats = {s.get("material"): s for s in j["shapes"]}
    assert "a" not in mats and "b" not in mats, list(mats)
    assert mats["c"]["camera_visible"] is False, mats["c"]
    assert "d" in mats and d.hide_get(), "the viewport-hidden object is exported, and hidden again afterwards"


@check("lights: spot radius, area spread, square and ellipse shapes, a world without nodes")
def _():
    base()
    scenes.light("SPOT", (0, -1, 3), energy=100.0, shadow_soft_size=0.2)
    scenes.light("AREA", (1, -1, 3), energy=100.0, shape="SQUARE", size=0.5, spread=math.radians(90))
    scenes.light("AREA", (-1, -1, 3), energy=100.0, shape="ELLIPSE", size=1.0, size_y=0.5)
    bpy.context.scene.world.use_nodes = False
    bpy.context.scene.world.color = (0.1, 0.2, 0.3)
    j = export("lights")
    notes = "\n".join(j["comment"]["not_mapped_exactly"])
    assert "spot radius" in notes and "spread 90" in notes, notes
    emitters = [s for s in j["shapes"] if "emission" in s]
    square = [s for s in emitters if s["type"] == "quad"][0]
    ellipse = [s for s in emitters if s["type"] == "polygon"][0]
    assert abs(square["emission"][0] / (100.0 / (4 * 0.25)) - 1) < 1e-6, square  # P / (4 A)
    assert len(ellipse["vertices"]) == 64 and abs(ellipse["emission"][0] - 100.0 / (4 * 0.999 * math.pi / 8)) < 0.2
    env = [li for li in j["lights"] if li["type"] == "environment"][0]
    assert [round(c, 6) for c in env["radiance"]] == [0.1, 0.2, 0.3], env


@check("lights: a Cycles portal is the environment's portal, not an emitter; its front along the light's direction")
def _():
    base()
    scenes.light("AREA", (0, 0, 2), energy=100.0, shape="RECTANGLE", size=1.0, size_y=0.5, **{"cycles.is_portal": True})
    bpy.context.scene.world.use_nodes = False
    bpy.context.scene.world.color = (0.1, 0.2, 0.3)
    j = export("portal")
    assert not [s for s in j["shapes"] if "emission" in s], j["shapes"]
    env = [li for li in j["lights"] if li["type"] == "environment"][0]
    (portal,) = env["portals"]
    v = portal["vertices"]
    e1 = [v[1][k] - v[0][k] for k in range(3)]
    e2 = [v[2][k] - v[0][k] for k in range(3)]
    front = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
    # Blender's -z (the light's direction, down towards the target) is kozu's -y; the area 1 x 0.5 at height 2.
    assert front[1] < 0 and abs(front[0]) < 1e-6 and abs(front[2]) < 1e-6, v
    assert abs(-front[1] - 0.5) < 1e-5 and all(abs(p[1] - 2.0) < 1e-6 for p in v), v


@check("images: a packed image is written beside the scene; Closest interpolation")
def _():
    base()
    img = bpy.data.images.new("packed", 4, 4)
    img.pixels.foreach_set([0.5] * 64)
    img.pack()
    mat = scenes.principled("packed")
    tex = mat.node_tree.nodes.new("ShaderNodeTexImage")
    tex.image = img
    tex.interpolation = "Closest"
    mat.node_tree.links.new(tex.outputs["Color"], mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"])
    scenes.add(bpy.ops.mesh.primitive_cube_add, mat, size=0.5, location=(0, 0, 0.3))
    j = export("images")
    t = j["materials"]["packed"]["base_color"]
    assert t["filter"] == "closest" and os.path.isfile(os.path.join(out, t["file"])), t


print("KOZU_EXPORT_CHECKS " + json.dumps(checked))
