"""A small scene built in Blender and rendered by kozu through the add-on's render engine (the README's picture):
    blender -b --factory-startup --python blender/examples/showcase.py -- OUT.png [WIDTH] [SAMPLES] [--compare]
KOZU (environment) or PATH gives the kozu binary. With --compare, Cycles renders it too: OUT is then the two stacked
(Cycles above, kozu below; with OpenImageIO's oiiotool), OUT.cycles.png and OUT.kozu.png each alone.
What it shows: a subdivided Suzanne in Principled subsurface, a rough gold sphere, a glass sphere, a clear-coated
torus, 400 geometry-nodes instances, an image-textured floor, an area light in watts, an HDR sky turned by a Mapping
node, depth of field, and Filmic (kozu's closest tone map, AgX).
"""
import math
import os
import sys
import tempfile

import bpy
import numpy as np
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
cycles = "--compare" in argv
argv = [a for a in argv if a != "--compare"]
out = os.path.abspath(argv[0] if argv else "showcase.png")
width = int(argv[1]) if len(argv) > 1 else 960
samples = int(argv[2]) if len(argv) > 2 else 256
textures = tempfile.mkdtemp(prefix="kozu_showcase_")

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.resolution_x, scene.render.resolution_y = width, width * 9 // 16
scene.cycles.samples = samples
scene.cycles.max_bounces = 8
for k in ("diffuse_bounces", "glossy_bounces", "transmission_bounces", "volume_bounces"):
    setattr(scene.cycles, k, 8)
scene.cycles.use_denoising = False
scene.view_settings.view_transform = "Filmic"


def save_image(name, pixels, is_float=False, colorspace="sRGB"):
    h, w = pixels.shape[:2]
    img = bpy.data.images.new(name, w, h, alpha=True, float_buffer=is_float)
    img.pixels.foreach_set(pixels.astype(np.float32).ravel())
    img.filepath_raw = os.path.join(textures, name + (".exr" if is_float else ".png"))
    img.file_format = "OPEN_EXR" if is_float else "PNG"
    img.save()
    bpy.data.images.remove(img)
    loaded = bpy.data.images.load(os.path.join(textures, name + (".exr" if is_float else ".png")))
    loaded.colorspace_settings.name = colorspace
    return loaded


def principled(name, **inputs):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    for k, v in inputs.items():
        mat.node_tree.nodes["Principled BSDF"].inputs[k].default_value = v
    return mat


def place(op, mat, smooth=True, **kw):
    op(**kw)
    obj = bpy.context.object
    obj.data.materials.append(mat)
    if smooth:
        bpy.ops.object.shade_smooth()
    return obj


# The sky: a warm horizon under a blue zenith, a bright patch for a sun-like highlight.
h, w = 128, 256
v = (np.arange(h) + 0.5) / h  # 0 at the bottom row (nadir), 1 at the top (zenith)
elev = (v - 0.5) * math.pi
sky = np.zeros((h, w, 4))
horizon, zenith, ground = np.array([1.0, 0.78, 0.55]), np.array([0.25, 0.45, 0.9]), np.array([0.15, 0.13, 0.12])
t = np.clip(np.sin(np.maximum(elev, 0)), 0, 1)[:, None, None] ** 0.6
sky[..., :3] = np.where(elev[:, None, None] > 0, horizon * (1 - t) + zenith * t, ground)
u = (np.arange(w) + 0.5) / w
patch = np.exp(-(((u[None, :] - 0.3) / 0.03) ** 2 + ((v[:, None] - 0.62) / 0.05) ** 2))
sky[..., :3] += 40.0 * patch[..., None] * np.array([1.0, 0.9, 0.75])
sky[..., 3] = 1
world = bpy.data.worlds.new("sky")
world.use_nodes = True
nt = world.node_tree
env = nt.nodes.new("ShaderNodeTexEnvironment")
env.image = save_image("sky", sky, is_float=True, colorspace="Linear")
mapping = nt.nodes.new("ShaderNodeMapping")
mapping.inputs["Rotation"].default_value = (0, 0, math.radians(-35))
coord = nt.nodes.new("ShaderNodeTexCoord")
nt.links.new(coord.outputs["Generated"], mapping.inputs["Vector"])
nt.links.new(mapping.outputs["Vector"], env.inputs["Vector"])
nt.links.new(env.outputs["Color"], nt.nodes["Background"].inputs["Color"])
nt.nodes["Background"].inputs["Strength"].default_value = 0.8
scene.world = world

# The floor: 8-bit sRGB tiles with a non-colour roughness map (the grout is rough).
n = 256
yy, xx = np.mgrid[0:n, 0:n]
grout = ((xx % 64) < 3) | ((yy % 64) < 3)
tile = ((xx // 64 + yy // 64) % 2).astype(float)
floor_rgb = np.zeros((n, n, 4))
floor_rgb[..., :3] = np.where(grout[..., None], [0.12, 0.11, 0.1],
                              np.where(tile[..., None] > 0, [0.55, 0.5, 0.45], [0.32, 0.3, 0.28]))
floor_rgb[..., 3] = 1
floor_rough = np.zeros((n, n, 4))
floor_rough[..., :3] = np.where(grout, 0.9, 0.25)[..., None]
floor_rough[..., 3] = 1
floor = principled("tiles")
fnt = floor.node_tree
for img, socket in ((save_image("tiles", floor_rgb), "Base Color"),
                    (save_image("tiles_rough", floor_rough, colorspace="Non-Color"), "Roughness")):
    tex = fnt.nodes.new("ShaderNodeTexImage")
    tex.image = img
    m = fnt.nodes.new("ShaderNodeMapping")
    m.inputs["Scale"].default_value = (4, 4, 1)
    c = fnt.nodes.new("ShaderNodeTexCoord")
    fnt.links.new(c.outputs["UV"], m.inputs["Vector"])
    fnt.links.new(m.outputs["Vector"], tex.inputs["Vector"])
    fnt.links.new(tex.outputs["Color"], fnt.nodes["Principled BSDF"].inputs[socket])
place(bpy.ops.mesh.primitive_plane_add, floor, smooth=False, size=12)

# The heroes.
monkey = place(bpy.ops.mesh.primitive_monkey_add,
               principled("wax", **{"Base Color": (0.9, 0.75, 0.6, 1), "Subsurface": 1.0,
                                    "Subsurface Color": (0.95, 0.55, 0.35, 1),
                                    "Subsurface Radius": (0.03, 0.012, 0.006), "Roughness": 0.35}),
               size=1.1, location=(0, 0.3, 0.75), rotation=(math.radians(-10), 0, math.radians(20)))
monkey.modifiers.new("subsurf", "SUBSURF").render_levels = 2
place(bpy.ops.mesh.primitive_uv_sphere_add,
      principled("gold", **{"Base Color": (1.0, 0.77, 0.34, 1), "Metallic": 1.0, "Roughness": 0.22}),
      radius=0.45, location=(-1.35, -0.2, 0.45), segments=64, ring_count=32)
place(bpy.ops.mesh.primitive_uv_sphere_add,
      principled("glass", **{"Transmission": 1.0, "Roughness": 0.02, "IOR": 1.5, "Base Color": (1, 1, 1, 1)}),
      radius=0.4, location=(1.25, -0.5, 0.4), segments=64, ring_count=32)
place(bpy.ops.mesh.primitive_torus_add,
      principled("paint", **{"Base Color": (0.6, 0.04, 0.03, 1), "Roughness": 0.5, "Clearcoat": 1.0,
                             "Clearcoat Roughness": 0.03}),
      major_radius=0.42, minor_radius=0.14, location=(1.6, 1.0, 0.14))

# 400 small chrome balls in a ring, as geometry-nodes instances.
bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3, radius=1.0, location=(0, 0, -5))
ball = bpy.context.object
ball.data.materials.append(principled("chrome", **{"Base Color": (0.9, 0.9, 0.92, 1), "Metallic": 1.0,
                                                   "Roughness": 0.1}))
bpy.ops.object.shade_smooth()
ball.hide_render = True
bpy.ops.mesh.primitive_circle_add(vertices=400, radius=2.6, location=(0, 0.6, 0.06))
ring = bpy.context.object
tree = bpy.data.node_groups.new("ring", "GeometryNodeTree")
if hasattr(tree, "interface"):  # Blender 4.x
    tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
else:
    tree.inputs.new("NodeSocketGeometry", "Geometry")
    tree.outputs.new("NodeSocketGeometry", "Geometry")
gin, gout = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
inst, info = tree.nodes.new("GeometryNodeInstanceOnPoints"), tree.nodes.new("GeometryNodeObjectInfo")
info.inputs["Object"].default_value = ball
inst.inputs["Scale"].default_value = (0.06, 0.06, 0.06)
tree.links.new(gin.outputs[0], inst.inputs["Points"])
tree.links.new(info.outputs["Geometry"], inst.inputs["Instance"])
tree.links.new(inst.outputs["Instances"], gout.inputs[0])
ring.modifiers.new("ring", "NODES").node_group = tree

# A warm key light in watts, out of frame above the camera's left.
key = bpy.data.lights.new("key", "AREA")
key.shape, key.size, key.size_y, key.energy, key.color = "RECTANGLE", 2.0, 1.0, 600.0, (1.0, 0.92, 0.82)
key_obj = bpy.data.objects.new("key", key)
scene.collection.objects.link(key_obj)
key_obj.location = (-2.5, -2.5, 3.5)
key_obj.rotation_euler = (Vector((0, 0.3, 0.5)) - key_obj.location).to_track_quat("-Z", "Y").to_euler()

cam = bpy.data.cameras.new("camera")
cam.lens = 42
cam.dof.use_dof = True
cam.dof.aperture_fstop = 2.8
cam_obj = bpy.data.objects.new("camera", cam)
scene.collection.objects.link(cam_obj)
cam_obj.location = (0.4, -5.2, 1.7)
target = Vector((0.05, 0.2, 0.6))
cam_obj.rotation_euler = (target - cam_obj.location).to_track_quat("-Z", "Y").to_euler()
cam.dof.focus_distance = (target - cam_obj.location).length
scene.camera = cam_obj

import addon_utils  # noqa: E402
addon_utils.enable("kozu_blender", default_set=True)
scene.render.image_settings.file_format = "PNG"
stem = os.path.splitext(out)[0]
if cycles:
    scene.render.engine = "CYCLES"
    scene.render.filepath = stem + ".cycles.png"
    bpy.ops.render.render(write_still=True)
scene.render.engine = "KOZU"
scene.render.filepath = stem + ".kozu.png" if cycles else out
bpy.ops.render.render(write_still=True)
if cycles:
    import subprocess  # noqa: E402
    subprocess.run(["oiiotool", stem + ".cycles.png", "--ch", "R,G,B", stem + ".kozu.png", "--ch", "R,G,B",
                    "--mosaic", "1x2", "-o", out], check=True)
