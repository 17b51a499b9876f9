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


def node_material(name, kind, output="Surface", **inputs):
    """A material whose `output` (Surface or Volume) is one node of type `kind` with the given input values."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    for n in [n for n in nt.nodes if n.bl_idname != "ShaderNodeOutputMaterial"]:
        nt.nodes.remove(n)
    node = nt.nodes.new(kind)
    for k, v in inputs.items():
        node.inputs[k].default_value = v
    nt.links.new(node.outputs[0], nt.nodes["Material Output"].inputs[output])
    return mat


def diffuse(name, colour):
    return node_material(name, "ShaderNodeBsdfDiffuse", Color=(*colour, 1))


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
        owner, _, attr = k.rpartition(".")  # "cycles.is_portal": an attribute of data.cycles
        setattr(getattr(data, owner) if owner else data, attr, v)
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
    """10,000 small cubes placed by geometry nodes (Instance on Points on a grid), and three empties instancing a
    collection: they must reach kozu as 10,003 instances of two objects, not as copies."""
    reset()
    room(floor=(0.5, 0.5, 0.5))
    src = add(bpy.ops.mesh.primitive_cube_add, diffuse("cube", (0.8, 0.3, 0.2)), size=1.0, location=(0, 0, -10))
    src.hide_render = True
    holder = add(bpy.ops.mesh.primitive_plane_add, size=1.0, location=(0, 0.5, 0.02))
    mod = holder.modifiers.new("instances", "NODES")
    tree = bpy.data.node_groups.new("instances", "GeometryNodeTree")
    mod.node_group = tree
    if hasattr(tree, "interface"):  # Blender 4.x
        tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    else:
        tree.outputs.new("NodeSocketGeometry", "Geometry")
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
    pillars = bpy.data.collections.new("pillars")  # not linked to the scene: seen only through its instances
    bpy.ops.mesh.primitive_cylinder_add(radius=0.12, depth=1.0, location=(0, 0, 0.5))
    pillar = bpy.context.object
    pillar.data.materials.append(diffuse("pillar", (0.3, 0.6, 0.3)))
    for c in pillar.users_collection:
        c.objects.unlink(pillar)
    pillars.objects.link(pillar)
    for i, x in enumerate((-1.5, 0.0, 1.5)):
        e = bpy.data.objects.new(f"pillar{i}", None)
        e.instance_type = "COLLECTION"
        e.instance_collection = pillars
        e.location = (x, 2.3, 0)
        e.scale = (1.0, 1.0, 1.0 + 0.4 * i)
        bpy.context.scene.collection.objects.link(e)
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
    mat = node_material("fog", "ShaderNodeVolumePrincipled", "Volume", Color=(0.9, 0.8, 0.7, 1), Density=1.5,
                        Anisotropy=0.3)
    mat.cycles.homogeneous_volume = True
    add(bpy.ops.mesh.primitive_cube_add, mat, size=1.2, location=(0, 0.5, 0.61))
    light("AREA", (0.5, -0.5, 3.0), target=(0, 0.5, 0), energy=300.0, shape="SQUARE", size=1.0)
    bpy.context.scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.05, 0.05, 0.05, 1)
    camera((0, -5, 1.8), (0, 0.5, 0.6))


def nodes(folder):
    """The shader nodes besides the Principled BSDF: Diffuse, a white Glossy (kozu's F = 1 conductor), a tinted
    Glossy, Glass, and an emitting mesh (Emission node, strength 4: its radiance)."""
    reset(width=128, height=72)
    room(floor=(0.6, 0.6, 0.6))

    mats = [node_material("diffuse", "ShaderNodeBsdfDiffuse", Color=(0.2, 0.5, 0.8, 1)),
            node_material("chrome", "ShaderNodeBsdfGlossy", Color=(1, 1, 1, 1), Roughness=0.25),
            node_material("copper", "ShaderNodeBsdfGlossy", Color=(0.95, 0.64, 0.54, 1), Roughness=0.4),
            node_material("glass", "ShaderNodeBsdfGlass", Color=(1, 1, 1, 1), Roughness=0.1, IOR=1.5)]
    for i, m in enumerate(mats):
        add(bpy.ops.mesh.primitive_uv_sphere_add, m, radius=0.5, location=(-1.8 + 1.2 * i, 0, 0.5), segments=48,
            ring_count=24)
        bpy.ops.object.shade_smooth()
    glow = node_material("glow", "ShaderNodeEmission", Color=(1.0, 0.6, 0.3, 1), Strength=4.0)
    add(bpy.ops.mesh.primitive_cube_add, glow, size=0.4, location=(0.0, 1.2, 0.2))
    light("AREA", (0, -1.5, 3.5), target=(0, 0, 0), energy=200.0, shape="SQUARE", size=1.5)
    bpy.context.scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.2, 0.2, 0.2, 1)
    camera((0, -6, 2.0), (0, 0, 0.6), lens=45)


def normal_map(folder):
    """A Diffuse BSDF plane with a tangent-space normal map of ridges (Normal Map node, strength 1) under a low
    light, and a Principled sphere with the same map: kozu must read the map with Blender's tangents and sign
    conventions (a sign error swaps the ridges' bright and dark sides). The light stands 60 degrees up: from lower
    lights Cycles darkens facets tilted towards the light by its bump-shadowing term (Chiang et al. 2019), which
    kozu does not have (docs/blender.md: 10 % on a plane tilted 30 degrees towards a light 35 degrees up)."""
    reset()
    # Two ridges over 32 texels: each texel spans several pixels, so kozu's texture filtering (EWA over the
    # pixel's footprint, which averages normals before shading) and Cycles' bilinear lookups read the same values.
    n = 32
    u = (np.arange(n) + 0.5) / n
    slope = 0.6 * np.cos(2 * np.pi * 2 * u)  # ridges along v: the normal tilts in u
    nx = -slope / np.sqrt(1 + slope ** 2)
    nz = 1 / np.sqrt(1 + slope ** 2)
    px = np.zeros((n, n, 4), dtype=np.float32)
    px[..., 0] = 0.5 + 0.5 * nx[None, :]
    px[..., 1] = 0.5
    px[..., 2] = 0.5 + 0.5 * nz[None, :]
    px[..., 3] = 1
    img = image("ridges", n, n, px, folder, colorspace="Non-Color")
    for name, op, kw in (("plane", bpy.ops.mesh.primitive_plane_add, dict(size=4, location=(0, 0.5, 0))),
                         ("ball", bpy.ops.mesh.primitive_uv_sphere_add,
                          dict(radius=0.6, location=(0.8, 0.3, 0.6), segments=48, ring_count=24))):
        mat = (principled(name, **{"Base Color": (0.7, 0.7, 0.7, 1), "Roughness": 0.4}) if name == "ball"
               else diffuse(name, (0.7, 0.7, 0.7)))
        nt = mat.node_tree
        tex = nt.nodes.new("ShaderNodeTexImage")
        tex.image = img
        nm = nt.nodes.new("ShaderNodeNormalMap")
        nt.links.new(tex.outputs["Color"], nm.inputs["Color"])
        bsdf = nt.nodes.get("Principled BSDF") or nt.nodes["Diffuse BSDF"]
        nt.links.new(nm.outputs["Normal"], bsdf.inputs["Normal"])
        obj = add(op, mat, **kw)
        if name == "ball":
            bpy.ops.object.shade_smooth()
    light("AREA", (-1.5, 0.5, 2.6), target=(0, 0.5, 0), energy=300.0, shape="SQUARE", size=1.0)
    bpy.context.scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.05, 0.05, 0.05, 1)
    camera((0, -2.5, 4.5), (0, 0.5, 0.2))


def subsurface(folder):
    """A Principled sphere with subsurface 1 (Cycles 3.4: random walk) beside a Lambert one: kozu renders it with
    the Christensen-Burley profile, a different model of the same mean free paths."""
    reset(bounces=16)
    room(floor=(0.5, 0.5, 0.5))
    mat = principled("wax", **{"Base Color": (0.8, 0.8, 0.8, 1), "Subsurface": 1.0,
                               "Subsurface Color": (0.9, 0.6, 0.4, 1), "Subsurface Radius": (0.1, 0.05, 0.025),
                               "Roughness": 0.4})
    add(bpy.ops.mesh.primitive_uv_sphere_add, mat, radius=0.6, location=(-0.5, 0.5, 0.6), segments=64,
        ring_count=32)
    bpy.ops.object.shade_smooth()
    add(bpy.ops.mesh.primitive_cube_add, diffuse("red", (0.7, 0.15, 0.1)), size=0.7, location=(0.9, 0.8, 0.35))
    light("AREA", (1.5, -1.0, 2.5), target=(-0.5, 0.5, 0.6), energy=150.0, shape="SQUARE", size=1.0)
    bpy.context.scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.1, 0.1, 0.1, 1)
    camera((0, -4.5, 1.5), (0, 0.5, 0.6))


def vdb(folder):
    """An OpenVDB smoke (kozu procedural smoke, 64^3) imported as a Blender volume object, rotated and scaled, with
    a Principled Volume (density 8, colour 0.9): kozu loads the same file as a grid medium."""
    reset(bounces=16)
    import subprocess
    path = os.path.join(folder, "smoke.vdb")
    subprocess.run([os.environ["KOZU"], "procedural", "smoke", "-o", path, "--resolution", "48"], check=True,
                   capture_output=True)
    add(bpy.ops.mesh.primitive_plane_add, diffuse("floor", (0.5, 0.5, 0.5)), size=8, location=(0, 0, -0.01))
    bpy.ops.object.volume_import(filepath=path)
    vol = bpy.context.object
    vol.rotation_euler = (math.pi / 2, 0, math.radians(25))  # the file's y-up box stands on Blender's floor
    vol.scale = (0.8, 0.8, 0.8)
    vol.data.materials.append(node_material("smoke", "ShaderNodeVolumePrincipled", "Volume",
                                            Color=(0.9, 0.9, 0.9, 1), Density=8.0))
    light("SUN", (0, 0, 5), target=(0.5, 0.8, 0), energy=4.0, angle=math.radians(2.0))
    bpy.context.scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.1, 0.12, 0.15, 1)
    camera((0, -4.5, 1.2), (0, 0, 0.8))


def camera_ortho(folder):
    """An orthographic camera fitted vertically, at 50 % resolution of a 192 x 144 setting."""
    reset(width=192, height=144)
    bpy.context.scene.render.resolution_percentage = 50
    room()
    _objects_under_light()
    light("AREA", (0.5, -0.5, 3.0), energy=150.0, shape="SQUARE", size=1.0)
    cam = camera((3, -6, 4), (0, 0.5, 0.6), sensor_fit="VERTICAL")
    cam.data.type = "ORTHO"
    cam.data.ortho_scale = 3.5


def cutout_sheen_bump(folder):
    """A leaf-shaped cut-out (an image's alpha on Principled Alpha) before the wall, a sheen sphere, a cube with a
    Bump node, roughness from a Separate RGB node's G, an ellipse area light, and Film > Transparent: the alpha
    channel (coverage) is compared too."""
    reset(width=128, height=72)
    bpy.context.scene.render.film_transparent = True
    add(bpy.ops.mesh.primitive_plane_add, diffuse("floor", (0.6, 0.6, 0.6)), size=6, location=(0, 0.5, 0))
    n = 64
    yy, xx = (np.mgrid[0:n, 0:n] + 0.5) / n
    leaf = np.zeros((n, n, 4), dtype=np.float32)
    leaf[..., :3] = (0.2, 0.6, 0.15)
    leaf[..., 3] = (((xx - 0.5) / 0.45) ** 2 + ((yy - 0.5) / 0.25) ** 2 < 1.0).astype(np.float32)
    cut = principled("leaf", **{"Roughness": 0.6})
    nt = cut.node_tree
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = image("leaf", n, n, leaf, folder)
    nt.links.new(tex.outputs["Color"], nt.nodes["Principled BSDF"].inputs["Base Color"])
    nt.links.new(tex.outputs["Alpha"], nt.nodes["Principled BSDF"].inputs["Alpha"])
    add(bpy.ops.mesh.primitive_plane_add, cut, size=1.4, location=(-1.3, 0.0, 0.9), rotation=(math.pi / 2, 0, 0))
    add(bpy.ops.mesh.primitive_uv_sphere_add,
        principled("velvet", **{"Base Color": (0.3, 0.05, 0.1, 1), "Roughness": 0.8, "Sheen": 1.0,
                                "Sheen Tint": 0.2}), radius=0.5, location=(0.1, 0.6, 0.5), segments=48, ring_count=24)
    bpy.ops.object.shade_smooth()
    bumps = np.zeros((n, n, 4), dtype=np.float32)
    bumps[..., :3] = (0.5 + 0.5 * np.sin(2 * np.pi * 4 * xx) * np.sin(2 * np.pi * 4 * yy))[..., None]
    bumps[..., 3] = 1
    mixed = np.zeros((n, n, 4), dtype=np.float32)
    mixed[..., 0] = 0.9  # R would make it rough
    mixed[..., 1] = np.where(xx < 0.5, 0.15, 0.6)  # G: the roughness the Separate RGB node reads
    mixed[..., 3] = 1
    mat = principled("bumpy", **{"Base Color": (0.7, 0.6, 0.4, 1), "Metallic": 1.0})
    # Multiscatter GGX: kozu's standard is energy-conserving, and Principled's default single-scattering GGX loses
    # up to a third of a rough metal's light here (docs/blender.md).
    mat.node_tree.nodes["Principled BSDF"].distribution = "MULTI_GGX"
    nt = mat.node_tree
    bump_tex = nt.nodes.new("ShaderNodeTexImage")
    bump_tex.image = image("bumps", n, n, bumps, folder, colorspace="Non-Color")
    bump = nt.nodes.new("ShaderNodeBump")
    bump.inputs["Distance"].default_value = 0.02
    nt.links.new(bump_tex.outputs["Color"], bump.inputs["Height"])
    nt.links.new(bump.outputs["Normal"], nt.nodes["Principled BSDF"].inputs["Normal"])
    rough_tex = nt.nodes.new("ShaderNodeTexImage")
    rough_tex.image = image("mixed", n, n, mixed, folder, colorspace="Non-Color")
    sep = nt.nodes.new("ShaderNodeSeparateRGB")
    nt.links.new(rough_tex.outputs["Color"], sep.inputs["Image"])
    nt.links.new(sep.outputs["G"], nt.nodes["Principled BSDF"].inputs["Roughness"])
    add(bpy.ops.mesh.primitive_cube_add, mat, size=0.8, location=(1.3, 0.4, 0.4), rotation=(0, 0, math.radians(30)))
    light("AREA", (0.5, -1.5, 3.0), target=(0, 0.5, 0), energy=250.0, shape="ELLIPSE", size=1.2, size_y=0.6)
    bpy.context.scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.2, 0.2, 0.25, 1)
    camera((0, -5, 2.0), (0, 0.5, 0.6), lens=40)


def volume_nodes(folder):
    """A chromatic medium made of Volume Scatter + Volume Absorption through an Add Shader, a tinted Glass BSDF
    (kozu's transmissive standard) and a Subsurface Scattering node."""
    reset(width=128, height=72, bounces=16)
    room(floor=(0.6, 0.6, 0.6))
    fog = node_material("fog", "ShaderNodeVolumeScatter", "Volume", Color=(0.9, 0.6, 0.3, 1), Density=2.0,
                        Anisotropy=-0.2)
    nt = fog.node_tree
    sc = nt.nodes["Volume Scatter"]
    ab = nt.nodes.new("ShaderNodeVolumeAbsorption")
    ab.inputs["Color"].default_value = (0.8, 0.9, 0.95, 1)
    ab.inputs["Density"].default_value = 1.0
    addn = nt.nodes.new("ShaderNodeAddShader")
    nt.links.new(sc.outputs[0], addn.inputs[0])
    nt.links.new(ab.outputs[0], addn.inputs[1])
    nt.links.new(addn.outputs[0], nt.nodes["Material Output"].inputs["Volume"])
    add(bpy.ops.mesh.primitive_cube_add, fog, size=0.9, location=(-1.1, 0.5, 0.46))

    glass = node_material("tinted", "ShaderNodeBsdfGlass", Color=(0.6, 0.9, 0.7, 1), Roughness=0.2)
    add(bpy.ops.mesh.primitive_uv_sphere_add, glass, radius=0.45, location=(0.1, 0.3, 0.45), segments=48,
        ring_count=24)
    bpy.ops.object.shade_smooth()

    skin = node_material("skin", "ShaderNodeSubsurfaceScattering", Color=(0.85, 0.55, 0.45, 1), Scale=0.1,
                         Radius=(1.0, 0.4, 0.2))
    add(bpy.ops.mesh.primitive_uv_sphere_add, skin, radius=0.45, location=(1.2, 0.6, 0.45), segments=48,
        ring_count=24)
    bpy.ops.object.shade_smooth()
    light("AREA", (0.5, -1.5, 3.0), target=(0, 0.5, 0), energy=300.0, shape="SQUARE", size=1.2)
    bpy.context.scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.1, 0.1, 0.1, 1)
    camera((0, -5, 1.8), (0, 0.5, 0.5), lens=40)


def check_instances(exported, out):
    shapes = exported["shapes"]
    placed = sum(1 for s in shapes if s["type"] == "instance")
    assert placed == 10003, f"{placed} instance shapes, expected 10,003"
    assert len(exported.get("objects", {})) == 2, f"objects: {list(exported.get('objects', {}))}"
    meshes = os.listdir(os.path.join(out, "scene_files", "meshes"))
    assert len(meshes) <= 4, f"{len(meshes)} mesh files: instances were copied"
    return {"instances": placed, "objects": len(exported["objects"]), "mesh_files": len(meshes)}


def _ply_faces(path):
    with open(path, "rb") as f:
        for line in f:
            if line.startswith(b"element face"):
                return int(line.split()[2])
    raise AssertionError(f"{path}: no faces")


def check_subdivision(exported, out):
    files = [s["file"] for s in exported["shapes"] if s["type"] == "mesh" and "clay" in s.get("material", "")]
    assert len(files) == 1, files
    faces = _ply_faces(os.path.join(out, files[0]))
    # Render level 3 of a cube: 6 x 4^3 quads, two triangles each (viewport level 1 would give 48).
    assert faces == 768, f"{faces} triangles, expected the render level's 768"
    return {"triangles": faces}


def check_camera_ortho(exported, out):
    cam = exported["camera"]
    assert cam["type"] == "orthographic" and cam["resolution"] == [96, 72], cam
    assert abs(cam["scale"] - 3.5) < 1e-9, cam  # fitted vertically: the scale is the height
    return {"scale": cam["scale"]}


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
    "instances": (instances, "10,000 geometry-nodes instances and 3 collection instances",
                  dict(mean=0.04, corr=0.97, block=0.25)),
    "subdivision": (subdivision, "a subdivided, smooth-shaded cube (render levels)",
                    dict(mean=0.05, corr=0.97, block=0.25)),
    "dof": (depth_of_field, "depth of field: f/1.4, 50 mm, focus at 6 m", dict(mean=0.03, corr=0.98, block=0.2)),
    "volume": (volume, "a Principled Volume cube", dict(mean=0.05, corr=0.97, block=0.25)),
    "nodes": (nodes, "Diffuse, Glossy (white, tinted), Glass and Emission nodes", dict(mean=0.05, corr=0.97, block=0.3)),
    "normal_map": (normal_map, "a tangent-space normal map (Normal Map node)", dict(mean=0.04, corr=0.97, block=0.25)),
    "subsurface": (subsurface, "Principled subsurface (random walk in Cycles, Christensen-Burley in kozu)",
                   dict(mean=0.08, corr=0.97, block=0.3)),
    "vdb": (vdb, "an OpenVDB volume object with a Principled Volume", dict(mean=0.05, corr=0.97, block=0.25)),
    "cutout_sheen_bump": (cutout_sheen_bump, "alpha cut-out, sheen, Bump node, Separate RGB, ellipse light, alpha",
                          dict(mean=0.05, corr=0.97, block=0.3)),
    "volume_nodes": (volume_nodes, "Volume Scatter + Absorption, tinted Glass BSDF, Subsurface Scattering node",
                     dict(mean=0.06, corr=0.97, block=0.3)),
    "camera_ortho": (camera_ortho, "an orthographic camera, vertical fit, 50 % resolution",
                     dict(mean=0.03, corr=0.98, block=0.2)),
}
