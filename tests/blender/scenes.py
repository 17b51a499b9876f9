"""Test scenes for the Blender add-on, built by script inside Blender (run_scene.py renders each with Cycles and with
kozu through the exporter and through the render engine, and compares them).

Every scene is small (96 x 72 by default) and lit so that block means are well above the noise at 64 samples.
SCENES maps a name to (builder, what it checks, tolerances); the tolerances are the models' stated differences
(docs/blender.md), not the noise.
"""
import math
import os

import bpy
import numpy as np


def reset(width=96, height=72, samples=64, bounces=8):
    """An empty scene rendered by Cycles on the CPU, without the biasing defaults (glossy filter, clamping)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    cy = scene.cycles
    cy.device = "CPU"
    cy.samples = samples
    cy.use_denoising = False
    cy.use_adaptive_sampling = False
    cy.max_bounces = bounces
    for k in ("diffuse_bounces", "glossy_bounces", "transmission_bounces", "volume_bounces"):
        setattr(cy, k, bounces)
    cy.transparent_max_bounces = bounces
    cy.sample_clamp_direct = 0.0
    cy.sample_clamp_indirect = 0.0
    cy.blur_glossy = 0.0
    cy.seed = 1
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    scene.world = world
    scene.view_settings.view_transform = "Standard"
    return scene


def camera(location, target, lens=35.0, sensor_fit="AUTO"):
    cam = bpy.data.cameras.new("camera")
    cam.lens = lens
    cam.sensor_fit = sensor_fit
    obj = bpy.data.objects.new("camera", cam)
    bpy.context.scene.collection.objects.link(obj)
    obj.location = location
    from mathutils import Vector
    obj.rotation_euler = (Vector(target) - Vector(location)).to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.camera = obj
    return obj


def principled(name, **inputs):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    for key, value in inputs.items():
        bsdf.inputs[key].default_value = value
    return mat


def diffuse(name, colour):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.remove(nt.nodes["Principled BSDF"])
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (*colour, 1)
    nt.links.new(d.outputs[0], nt.nodes["Material Output"].inputs["Surface"])
    return mat


def add(obj_op, material=None, **kw):
    obj_op(**kw)
    obj = bpy.context.object
    if material is not None:
        obj.data.materials.append(material)
    return obj


def room(floor=(0.8, 0.8, 0.8), wall=(0.8, 0.8, 0.8)):
    """A floor and a back wall (Lambert)."""
    add(bpy.ops.mesh.primitive_plane_add, diffuse("floor", floor), size=8, location=(0, 0, 0))
    add(bpy.ops.mesh.primitive_plane_add, diffuse("wall", wall), size=8, location=(0, 3, 4),
        rotation=(math.pi / 2, 0, 0))


def light(kind, location, target=(0, 0, 0), energy=100.0, colour=(1, 1, 1), **props):
    data = bpy.data.lights.new(kind.lower(), kind)
    data.energy = energy
    data.color = colour
    for k, v in props.items():
        setattr(data, k, v)
    obj = bpy.data.objects.new(kind.lower(), data)
    bpy.context.scene.collection.objects.link(obj)
    obj.location = location
    from mathutils import Vector
    if Vector(target) != Vector(location):
        obj.rotation_euler = (Vector(target) - Vector(location)).to_track_quat("-Z", "Y").to_euler()
    return obj


def image(name, width, height, pixels, folder, float_=False, colorspace="sRGB"):
    """An image written to disk (PNG or EXR) and loaded as Blender loads a user's file."""
    img = bpy.data.images.new(name, width, height, alpha=True, float_buffer=float_)
    img.pixels.foreach_set(np.asarray(pixels, dtype=np.float32).ravel())
    ext, fmt = (".exr", "OPEN_EXR") if float_ else (".png", "PNG")
    path = os.path.join(folder, name + ext)
    img.filepath_raw = path
    img.file_format = fmt
    img.save()
    bpy.data.images.remove(img)
    out = bpy.data.images.load(path)
    out.colorspace_settings.name = colorspace
    return out


def image_texture(mat, img, socket, output="Color", mapping=None):
    nt = mat.node_tree
    bsdf = nt.nodes["Principled BSDF"]
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = img
    nt.links.new(tex.outputs[output], bsdf.inputs[socket])
    if mapping is not None:
        coord = nt.nodes.new("ShaderNodeTexCoord")
        m = nt.nodes.new("ShaderNodeMapping")
        m.inputs["Scale"].default_value = mapping
        nt.links.new(coord.outputs["UV"], m.inputs["Vector"])
        nt.links.new(m.outputs["Vector"], tex.inputs["Vector"])
    return tex


# --- the scenes -------------------------------------------------------------------------------------------------

def _objects_under_light():
    add(bpy.ops.mesh.primitive_uv_sphere_add, diffuse("grey", (0.6, 0.6, 0.6)), radius=0.6, location=(-0.8, 0.5, 0.6),
        segments=48, ring_count=24)
    bpy.ops.object.shade_smooth()
    add(bpy.ops.mesh.primitive_cube_add, diffuse("red", (0.7, 0.15, 0.1)), size=0.9, location=(0.9, 0.8, 0.45))


def light_area(folder):
    reset()
    room()
    _objects_under_light()
    light("AREA", (0.5, -0.5, 3.0), energy=150.0, colour=(1.0, 0.9, 0.8), shape="RECTANGLE", size=1.0, size_y=0.5)
    camera((0, -6, 2.2), (0, 0.5, 0.8))


def light_disk(folder):
    reset()
    room()
    _objects_under_light()
    light("AREA", (-0.5, -1.0, 2.5), target=(0, 0.5, 0), energy=120.0, shape="DISK", size=0.8)
    camera((0, -6, 2.2), (0, 0.5, 0.8))


def light_point(folder):
    reset()
    room()
    _objects_under_light()
    light("POINT", (0.3, -1.0, 2.5), energy=200.0, colour=(0.9, 0.95, 1.0), shadow_soft_size=0.1)
    camera((0, -6, 2.2), (0, 0.5, 0.8))


def light_spot(folder):
    reset()
    room()
    _objects_under_light()
    light("SPOT", (-1.5, -2.0, 3.0), target=(0.0, 0.8, 0.3), energy=400.0, spot_size=math.radians(50),
          spot_blend=0.3, shadow_soft_size=0.0)
    camera((0, -6, 2.2), (0, 0.5, 0.8))


def light_sun(folder):
    reset()
    room()
    _objects_under_light()
    light("SUN", (0, 0, 5), target=(0.6, 0.9, 0), energy=3.0, angle=math.radians(3.0))
    camera((0, -6, 2.2), (0, 0.5, 0.8))


def world_colour(folder):
    reset()
    room(floor=(0.5, 0.5, 0.5))
    _objects_under_light()
    bpy.context.scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.4, 0.5, 0.7, 1)
    bpy.context.scene.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.5
    camera((0, -6, 2.2), (0, 0.5, 0.8))


def world_hdr(folder):
    """An equirectangular EXR with four coloured quarters, turned 40 degrees by a Mapping node; a mirror sphere and
    a white one show which way each quarter lies."""
    reset()
    w, h = 128, 64
    px = np.zeros((h, w, 4), dtype=np.float32)
    quarters = [(1.5, 0.2, 0.2), (0.2, 1.5, 0.2), (0.2, 0.2, 1.5), (1.2, 1.2, 0.2)]
    for i, c in enumerate(quarters):
        px[:, i * w // 4:(i + 1) * w // 4, :3] = c
    px[:h // 2, :, :3] *= 0.3  # the lower half (rows from the bottom) darker: up and down differ too
    px[..., 3] = 1.0
    img = image("sky", w, h, px, folder, float_=True, colorspace="Linear")
    nt = bpy.context.scene.world.node_tree
    env = nt.nodes.new("ShaderNodeTexEnvironment")
    env.image = img
    coord = nt.nodes.new("ShaderNodeTexCoord")
    m = nt.nodes.new("ShaderNodeMapping")
    m.inputs["Rotation"].default_value = (0, 0, math.radians(40))
    nt.links.new(coord.outputs["Generated"], m.inputs["Vector"])
    nt.links.new(m.outputs["Vector"], env.inputs["Vector"])
    nt.links.new(env.outputs["Color"], nt.nodes["Background"].inputs["Color"])
    add(bpy.ops.mesh.primitive_uv_sphere_add, principled("mirror", **{"Metallic": 1.0, "Roughness": 0.05,
                                                                   "Base Color": (0.9, 0.9, 0.9, 1)}),
        radius=0.7, location=(-0.8, 0, 0.7), segments=48, ring_count=24)
    bpy.ops.object.shade_smooth()
    add(bpy.ops.mesh.primitive_uv_sphere_add, diffuse("white", (0.8, 0.8, 0.8)), radius=0.7, location=(0.8, 0, 0.7),
        segments=48, ring_count=24)
    bpy.ops.object.shade_smooth()
    camera((0, -5, 1.0), (0, 0, 0.7), lens=40)


def principled_materials(folder):
    """Principled spheres: a textured dielectric (sRGB checker on base colour, non-colour roughness map), a rough
    metal, glass, a clearcoated plastic, under an area light and a grey world."""
    reset(width=128, height=72)
    room(floor=(0.6, 0.6, 0.6))
    n = 16
    checker = np.zeros((n, n, 4), dtype=np.float32)
    yy, xx = np.mgrid[0:n, 0:n]
    on = ((xx // 4 + yy // 4) % 2 == 0)
    checker[on] = (0.9, 0.5, 0.1, 1.0)
    checker[~on] = (0.1, 0.3, 0.8, 1.0)
    tex = principled("textured", **{"Roughness": 0.5})
    image_texture(tex, image("checker", n, n, checker, folder), "Base Color", mapping=(2.0, 2.0, 1.0))
    rough = np.zeros((n, n, 4), dtype=np.float32)
    rough[..., :3] = np.linspace(0.2, 0.9, n)[None, :, None]
    rough[..., 3] = 1
    image_texture(tex, image("rough", n, n, rough, folder, colorspace="Non-Color"), "Roughness")
    mats = [tex,
            principled("gold", **{"Base Color": (1.0, 0.76, 0.33, 1), "Metallic": 1.0, "Roughness": 0.3}),
            principled("glass", **{"Base Color": (1, 1, 1, 1), "Transmission": 1.0, "Roughness": 0.0, "IOR": 1.5}),
            principled("coated", **{"Base Color": (0.1, 0.4, 0.1, 1), "Roughness": 0.6, "Clearcoat": 1.0,
                                    "Clearcoat Roughness": 0.05})]
    for i, m in enumerate(mats):
        add(bpy.ops.mesh.primitive_uv_sphere_add, m, radius=0.5, location=(-1.8 + 1.2 * i, 0, 0.5), segments=48,
            ring_count=24)
        bpy.ops.object.shade_smooth()
    light("AREA", (0, -1.5, 3.5), target=(0, 0, 0), energy=300.0, shape="SQUARE", size=1.5)
    bpy.context.scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.3, 0.3, 0.3, 1)
    camera((0, -6, 2.0), (0, 0, 0.6), lens=45)


def parenting(folder):
    """A child cube under an empty that is rotated and scaled non-uniformly, itself rotated: the shape kozu draws
    must be the sheared box Blender draws."""
    reset()
    room()
    parent = bpy.data.objects.new("parent", None)
    bpy.context.scene.collection.objects.link(parent)
    parent.location = (0.2, 0.5, 0.8)
    parent.rotation_euler = (0, 0, math.radians(30))
    parent.scale = (1.8, 0.6, 1.0)
    child = add(bpy.ops.mesh.primitive_cube_add, diffuse("child", (0.2, 0.6, 0.8)), size=0.8, location=(0, 0, 0))
    child.parent = parent
    child.rotation_euler = (math.radians(20), math.radians(35), 0)
    light("AREA", (0, -2.0, 3.5), target=(0, 0.5, 0), energy=250.0, shape="SQUARE", size=1.5)
    bpy.context.scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.1, 0.1, 0.1, 1)
    camera((0, -6, 2.2), (0, 0.5, 0.8))


def instances(folder):
    """10,000 small cubes placed by geometry nodes (Instance on Points on a grid): they must reach kozu as 10,000
    instances of one object, not as copies."""
    reset()
    room(floor=(0.5, 0.5, 0.5))
    src = add(bpy.ops.mesh.primitive_cube_add, diffuse("cube", (0.8, 0.3, 0.2)), size=1.0, location=(0, 0, -10))
    src.hide_render = True
    holder = add(bpy.ops.mesh.primitive_plane_add, size=1.0, location=(0, 0.5, 0.02))
    mod = holder.modifiers.new("instances", "NODES")
    tree = bpy.data.node_groups.new("instances", "GeometryNodeTree")
    mod.node_group = tree
    tree.outputs.new("NodeSocketGeometry", "Geometry") if hasattr(tree, "outputs") else None
    out = tree.nodes.new("NodeGroupOutput")
    grid = tree.nodes.new("GeometryNodeMeshGrid")
    grid.inputs["Size X"].default_value = 4.0
    grid.inputs["Size Y"].default_value = 4.0
    grid.inputs["Vertices X"].default_value = 100
    grid.inputs["Vertices Y"].default_value = 100
    inst = tree.nodes.new("GeometryNodeInstanceOnPoints")
    info = tree.nodes.new("GeometryNodeObjectInfo")
    info.inputs["Object"].default_value = src
    inst.inputs["Scale"].default_value = (0.02, 0.02, 0.02)
    tree.links.new(grid.outputs["Mesh"], inst.inputs["Points"])
    tree.links.new(info.outputs["Geometry"], inst.inputs["Instance"])
    tree.links.new(inst.outputs["Instances"], out.inputs[0])
    light("AREA", (0, -1.0, 3.5), target=(0, 0.5, 0), energy=300.0, shape="SQUARE", size=1.5)
    camera((0, -5, 3.0), (0, 0.5, 0))


def subdivision(folder):
    """A cube under a Subdivision Surface modifier (viewport level 1, render level 3), shaded smooth: kozu must get
    the render level's smooth surface."""
    reset()
    room()
    cube = add(bpy.ops.mesh.primitive_cube_add, principled("clay", **{"Base Color": (0.7, 0.5, 0.4, 1),
                                                                     "Roughness": 0.35}), size=1.2,
               location=(0, 0.5, 0.8))
    mod = cube.modifiers.new("subsurf", "SUBSURF")
    mod.levels, mod.render_levels = 1, 3
    bpy.ops.object.shade_smooth()
    light("AREA", (1.5, -2.0, 3.0), target=(0, 0.5, 0.5), energy=300.0, shape="SQUARE", size=1.0)
    bpy.context.scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.1, 0.1, 0.1, 1)
    camera((0, -4.5, 1.8), (0, 0.5, 0.8))


def depth_of_field(folder):
    """Three spheres at 3, 6 and 9 m from an f/1.4 50 mm camera focused on the middle one."""
    reset()
    add(bpy.ops.mesh.primitive_plane_add, diffuse("floor", (0.5, 0.5, 0.5)), size=30, location=(0, 4, 0))
    for i, (x, y, c) in enumerate([(-1.0, -3.0, (0.9, 0.2, 0.1)), (0.0, 0.0, (0.1, 0.8, 0.2)),
                                   (1.2, 3.0, (0.2, 0.3, 0.9))]):
        add(bpy.ops.mesh.primitive_uv_sphere_add, diffuse(f"s{i}", c), radius=0.5, location=(x, y, 0.5), segments=48,
            ring_count=24)
        bpy.ops.object.shade_smooth()
    cam = camera((0, -6, 0.8), (0, 0, 0.5), lens=50)
    cam.data.dof.use_dof = True
    cam.data.dof.focus_distance = 6.0
    cam.data.dof.aperture_fstop = 1.4
    bpy.context.scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.8, 0.8, 0.8, 1)


def volume(folder):
    """A cube of Principled Volume (density 1.5, colour 0.8, anisotropy 0.3) on a floor under an area light."""
    reset(bounces=16)
    room(floor=(0.6, 0.6, 0.6))
    mat = bpy.data.materials.new("fog")
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.remove(nt.nodes["Principled BSDF"])
    pv = nt.nodes.new("ShaderNodeVolumePrincipled")
    pv.inputs["Color"].default_value = (0.9, 0.8, 0.7, 1)
    pv.inputs["Density"].default_value = 1.5
    pv.inputs["Anisotropy"].default_value = 0.3
    nt.links.new(pv.outputs[0], nt.nodes["Material Output"].inputs["Volume"])
    mat.cycles.homogeneous_volume = True
    add(bpy.ops.mesh.primitive_cube_add, mat, size=1.2, location=(0, 0.5, 0.61))
    light("AREA", (0.5, -0.5, 3.0), target=(0, 0.5, 0), energy=300.0, shape="SQUARE", size=1.0)
    bpy.context.scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.05, 0.05, 0.05, 1)
    camera((0, -5, 1.8), (0, 0.5, 0.6))


# name: (builder, what it checks, tolerances: mean = |kozu / Cycles - 1| of the image mean, corr = the least
# correlation of block means, block = the largest relative error of a block mean, over blocks above 25 % of the mean)
SCENES = {
    "light_area": (light_area, "a rectangular area light of 150 W, coloured", dict(mean=0.03, corr=0.98, block=0.15)),
    "light_disk": (light_disk, "a disk area light (a 64-gon in kozu)", dict(mean=0.03, corr=0.98, block=0.15)),
    "light_point": (light_point, "a point light of radius 0.1 (an emitting sphere in kozu)",
                    dict(mean=0.03, corr=0.98, block=0.15)),
    "light_spot": (light_spot, "a spot of 50 degrees, blend 0.3", dict(mean=0.04, corr=0.98, block=0.2)),
    "light_sun": (light_sun, "a sun of 3 W/m^2 and 3 degrees", dict(mean=0.03, corr=0.98, block=0.15)),
    "world_colour": (world_colour, "a uniform world colour at strength 1.5", dict(mean=0.03, corr=0.98, block=0.15)),
    "world_hdr": (world_hdr, "an HDR environment turned 40 degrees by a Mapping node",
                  dict(mean=0.04, corr=0.97, block=0.25)),
    "principled": (principled_materials, "Principled: textures (sRGB, non-colour), metal, glass, clearcoat",
                   dict(mean=0.06, corr=0.95, block=0.35)),
    "parenting": (parenting, "parenting with rotation and non-uniform scale", dict(mean=0.03, corr=0.98, block=0.2)),
    "instances": (instances, "10,000 geometry-nodes instances", dict(mean=0.04, corr=0.97, block=0.25)),
    "subdivision": (subdivision, "a subdivided, smooth-shaded cube (render levels)",
                    dict(mean=0.05, corr=0.97, block=0.25)),
    "dof": (depth_of_field, "depth of field: f/1.4, 50 mm, focus at 6 m", dict(mean=0.03, corr=0.98, block=0.2)),
    "volume": (volume, "a Principled Volume cube", dict(mean=0.05, corr=0.97, block=0.25)),
}
