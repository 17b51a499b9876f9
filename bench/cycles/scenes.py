"""The scenes of kozu's comparison with Cycles (bench/cycles/compare.py), each built twice: as a kozu scene (JSON) and,
inside Blender, with bpy for Cycles. Same geometry, materials, lights and units in both.

kozu is y-up, Blender z-up: a kozu point (x, y, z) is Blender's (x, -z, y) (a rotation of +90 degrees about x).
Units measured against Cycles 3.4 (this file's scenes agree with kozu to the noise, compare.py prints the means):
  - an area light of radiance L and area A is Blender's "watts" P = 4 A L (Cycles 3.4's area lights emit P / (4 A));
  - a point or spot light of intensity I (W/sr) is P = 4 pi I; Cycles 3.4's spot lights also fall off as cos(theta)
    about their axis inside the cone, which kozu's spot takes from an IES profile of cos(theta) (spot_cosine.ies,
    written beside the scene);
  - Volume Scatter's colour multiplies its density and Volume Absorption absorbs density (1 - colour): scattering
    colour white and absorption colour black make the densities sigma_s and sigma_a themselves;
  - a uniform environment of radiance L is the world's background colour L at strength 1.
The area lights stay out of frame: Cycles hides them from the camera, kozu shows its emitting quads.
"""
import math
import os

from surfaces import SURFACE_SCENES, box_mesh
import surfaces

CAMERA = dict(position=[0, 1.0, 4.5], look_at=[0, 0.8, 0], fov=40)
CUBE_LO, CUBE_HI = (-0.6, 0.01, -0.6), (0.6, 1.21, 0.6)
SMOKE_LO, SMOKE_HI = (-1.0, 0.0, -1.0), (1.0, 2.0, 1.0)  # `kozu procedural smoke`'s box

# name: (what it shows, its medium, its lights)
SCENES = {
    "box": ("homogeneous grey medium (sigma_t 2, albedo 0.9) in a cube under a quad light, on a diffuse floor",
            dict(kind="homogeneous", sigma_t=[2, 2, 2], albedo=[0.9, 0.9, 0.9]), ["quad"]),
    "chromatic": ("the cube with sigma_t (0.5, 2, 4) and albedo (0.95, 0.9, 0.8), Henyey-Greenstein g 0.3",
                  dict(kind="homogeneous", sigma_t=[0.5, 2, 4], albedo=[0.95, 0.9, 0.8], g=0.3), ["quad"]),
    "spot": ("the grey cube lit by a small spot light from the side",
             dict(kind="homogeneous", sigma_t=[2, 2, 2], albedo=[0.9, 0.9, 0.9]), ["spot"]),
    "environment": ("the grey cube under a uniform sky (no other light)",
                    dict(kind="homogeneous", sigma_t=[2, 2, 2], albedo=[0.9, 0.9, 0.9]), ["sky"]),
    "vdb": ("`kozu procedural smoke -o smoke.vdb` (64^3) at density 20, albedo 0.9, under the quad and a dim sky",
            dict(kind="vdb", density=20.0, albedo=[0.9, 0.9, 0.9]), ["quad_high", "dim_sky"]),
}

# Every scene compare.py knows: the volumes above, then the surfaces (surfaces.py).
ALL = {**{k: v[0] for k, v in SCENES.items()}, **SURFACE_SCENES}

QUAD_L, QUAD_Y = 10.0, 3.2
SPOT = dict(position=[-2.2, 1.6, 1.2], look_at=[0, 0.6, 0], intensity=8.0, cone=25.0, blend=0.15)
SKY, DIM_SKY = [0.8, 0.9, 1.0], [0.05, 0.06, 0.08]


def _spot_falloff_deg():
    """kozu's falloff angle for Cycles' spot blend: Cycles smooths over cos in [cos c, cos c + (1 - cos c) blend]."""
    c = math.cos(math.radians(SPOT["cone"]))
    return math.degrees(math.acos(c + (1 - c) * SPOT["blend"]))


def write_cosine_profile(path):
    """An IES LM-63 profile of intensity cos(theta) about the nadir (kozu's spot axis), every degree to 90."""
    angles = range(91)
    with open(path, "w") as f:
        f.write("IESNA:LM-63-2002\n[TEST] bench/cycles: Cycles 3.4's spot falloff cos(theta)\nTILT=NONE\n")
        f.write(f"1 -1 1 {len(angles)} 1 1 2 0 0 0\n1 1 0\n")
        f.write(" ".join(str(a) for a in angles) + "\n0\n")
        f.write(" ".join(f"{math.cos(math.radians(a)):.6f}" for a in angles) + "\n")


def kozu_scene(name, res, spp, seed, depth, vdb_path=None, spot_profile=None):
    if name in SURFACE_SCENES:
        return surfaces.kozu_scene(name, res, spp, seed, depth, os.path.dirname(vdb_path) if vdb_path else ".")
    _, medium, lights = SCENES[name]
    shapes, light_list = [{"type": "quad", "material": "floor",
                           "vertices": [[-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]]}], []
    if medium["kind"] == "homogeneous":
        m = {"type": "homogeneous", "density": medium["sigma_t"], "albedo": medium["albedo"]}
        if medium.get("g"):
            m["phase"] = {"type": "hg", "g": medium["g"]}
        pos, idx = box_mesh(CUBE_LO, CUBE_HI)
    else:
        m = {"type": "grid", "file": vdb_path, "density_scale": medium["density"], "albedo": medium["albedo"]}
        pos, idx = box_mesh([v - 0.01 for v in SMOKE_LO], [v + 0.01 for v in SMOKE_HI])
    shapes.append({"type": "mesh", "interior": "fog", "positions": pos, "indices": idx})
    for light in lights:
        if light.startswith("quad"):
            y = QUAD_Y + (1.5 if light == "quad_high" else 0.0)
            shapes.append({"type": "quad", "emission": QUAD_L,
                           "vertices": [[0.5, y, -0.5], [0.5, y, 0.5], [-0.5, y, 0.5], [-0.5, y, -0.5]]})
        elif light == "spot":
            light_list.append({"type": "spot", "position": SPOT["position"], "look_at": SPOT["look_at"],
                               "intensity": SPOT["intensity"], "cone_angle": SPOT["cone"],
                               "falloff_angle": _spot_falloff_deg(), "profile": spot_profile})
        else:
            light_list.append({"type": "environment", "radiance": SKY if light == "sky" else DIM_SKY})
    return {
        "comment": f"bench/cycles scene '{name}': {SCENES[name][0]}",
        "camera": {"type": "perspective", **CAMERA, "resolution": [res, res]},
        "render": {"spp": spp, "max_depth": depth, "seed": seed, "filter": "box"},
        "materials": {"floor": {"type": "diffuse", "albedo": 0.5}},
        "media": {"fog": m},
        "shapes": shapes,
        "lights": light_list,
    }


def blender_scene(name, res, spp, seed, depth, threads, vdb_path=None):
    """Builds the scene in the running Blender (bpy) for Cycles: CPU, no adaptive sampling, no denoising, no
    clamping, box filter, the Standard view transform."""
    import bpy
    from mathutils import Vector
    b = lambda p: Vector((p[0], -p[2], p[1]))
    _, medium, lights = SCENES.get(name, (None, None, []))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.samples = spp
    c.use_adaptive_sampling = False
    c.seed = seed
    c.max_bounces = c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = depth
    c.volume_bounces = c.transparent_max_bounces = depth
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = c.caustics_refractive = True
    c.pixel_filter_type = "BOX"
    c.use_denoising = False
    c.light_sampling_threshold = 0.0
    scene.render.threads_mode = "FIXED"
    scene.render.threads = threads
    scene.render.resolution_x = scene.render.resolution_y = res
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    sky = SKY if "sky" in lights else DIM_SKY if "dim_sky" in lights else [0, 0, 0]
    bg.inputs["Strength"].default_value = 1.0
    scene.world = world

    def material(name_, surface=None, volume=None):
        m = bpy.data.materials.new(name_)
        m.use_nodes = True
        nt = m.node_tree
        nt.nodes.clear()
        out = nt.nodes.new("ShaderNodeOutputMaterial")
        if surface:
            nt.links.new(surface(nt).outputs[0], out.inputs["Surface"])
        if volume:
            nt.links.new(volume(nt).outputs[0], out.inputs["Volume"])
        return m

    def diffuse(nt):
        d = nt.nodes.new("ShaderNodeBsdfDiffuse")
        d.inputs["Color"].default_value = (0.5, 0.5, 0.5, 1)
        return d

    if name in SURFACE_SCENES:
        camera, sky = surfaces.blender_build(name, b, lambda n, fn: material(n, surface=fn),
                                             os.path.dirname(vdb_path) if vdb_path else ".")
        if isinstance(sky, dict):
            # kozu's rotate r is Blender's lookup turned by -90 - r degrees about z (docs/blender.md).
            nt = world.node_tree
            env = nt.nodes.new("ShaderNodeTexEnvironment")
            env.image = bpy.data.images.load(sky["file"])
            env.image.colorspace_settings.name = "Linear"
            coord, turn = nt.nodes.new("ShaderNodeTexCoord"), nt.nodes.new("ShaderNodeMapping")
            turn.inputs["Rotation"].default_value = (0, 0, math.radians(-90.0 - sky["rotate"]))
            nt.links.new(coord.outputs["Generated"], turn.inputs["Vector"])
            nt.links.new(turn.outputs["Vector"], env.inputs["Vector"])
            nt.links.new(env.outputs["Color"], bg.inputs["Color"])
        else:
            bg.inputs["Color"].default_value = (*sky, 1)
        _camera(scene, b, camera)
        return
    bg.inputs["Color"].default_value = (*sky, 1)

    bpy.ops.mesh.primitive_plane_add(size=10)
    bpy.context.object.data.materials.append(material("floor", surface=diffuse))

    if medium["kind"] == "homogeneous":
        st, al = medium["sigma_t"], medium["albedo"]

        def fog(nt):
            dens = max(st)  # colours in [0, 1]: sigma_s = dens colour, sigma_a = dens (1 - colour)
            sc = nt.nodes.new("ShaderNodeVolumeScatter")
            sc.inputs["Color"].default_value = (*[s * a / dens for s, a in zip(st, al)], 1)
            sc.inputs["Density"].default_value = dens
            sc.inputs["Anisotropy"].default_value = medium.get("g", 0.0)
            ab = nt.nodes.new("ShaderNodeVolumeAbsorption")
            ab.inputs["Color"].default_value = (*[1 - s * (1 - a) / dens for s, a in zip(st, al)], 1)
            ab.inputs["Density"].default_value = dens
            add = nt.nodes.new("ShaderNodeAddShader")
            nt.links.new(sc.outputs[0], add.inputs[0])
            nt.links.new(ab.outputs[0], add.inputs[1])
            return add

        lo, hi = CUBE_LO, CUBE_HI
        bpy.ops.mesh.primitive_cube_add(size=1.0, location=b([(l + h) / 2 for l, h in zip(lo, hi)]))
        cube = bpy.context.object
        cube.scale = (hi[0] - lo[0], hi[2] - lo[2], hi[1] - lo[1])
        m = material("fog", volume=fog)
        m.cycles.homogeneous_volume = True
        cube.data.materials.append(m)
    else:
        bpy.ops.object.volume_import(filepath=vdb_path)
        vol = bpy.context.object
        vol.rotation_euler = (math.pi / 2, 0, 0)  # the file's y-up box into Blender's z-up

        def smoke(nt):
            pv = nt.nodes.new("ShaderNodeVolumePrincipled")
            pv.inputs["Color"].default_value = (*medium["albedo"], 1)  # sigma_s = density colour
            pv.inputs["Density"].default_value = medium["density"]
            pv.inputs["Absorption Color"].default_value = (0, 0, 0, 1)  # sigma_a = density (1 - colour)
            return pv

        vol.data.materials.append(material("smoke", volume=smoke))

    for light in lights:
        if light.startswith("quad"):
            y = QUAD_Y + (1.5 if light == "quad_high" else 0.0)
            data = bpy.data.lights.new("quad", "AREA")
            data.shape = "SQUARE"
            data.size = 1.0
            data.energy = 4.0 * 1.0 * QUAD_L
            obj = bpy.data.objects.new("quad", data)
            obj.location = b([0, y, 0])
            scene.collection.objects.link(obj)
        elif light == "spot":
            data = bpy.data.lights.new("spot", "SPOT")
            data.energy = 4 * math.pi * SPOT["intensity"]
            data.spot_size = math.radians(2 * SPOT["cone"])
            data.spot_blend = SPOT["blend"]
            data.shadow_soft_size = 0.0
            obj = bpy.data.objects.new("spot", data)
            obj.location = b(SPOT["position"])
            obj.rotation_euler = (b(SPOT["look_at"]) - b(SPOT["position"])).to_track_quat("-Z", "Y").to_euler()
            scene.collection.objects.link(obj)

    _camera(scene, b, CAMERA)


def _camera(scene, b, camera):
    """A perspective camera of vertical field of view camera["fov"] degrees (kozu's), as the scene's camera."""
    import bpy
    cam = bpy.data.cameras.new("camera")
    cam.sensor_fit = "VERTICAL"
    cam.angle = math.radians(camera["fov"])
    obj = bpy.data.objects.new("camera", cam)
    obj.location = b(camera["position"])
    obj.rotation_euler = (b(camera["look_at"]) - b(camera["position"])).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(obj)
    scene.camera = obj


if __name__ == "__main__":
    # kozu's side alone, for benchmarks that need no Blender (bench/bench_rays, bench/thread_scaling.sh):
    #   python3 bench/cycles/scenes.py OUT_DIR [RES] [SPP]   writes OUT_DIR/NAME.json for every scene; `vdb` needs
    #   OUT_DIR/smoke.vdb (`kozu procedural smoke -o OUT_DIR/smoke.vdb`); `interior` and `product` read the files
    #   bench/cycles/assets.py writes there, with kozu's Python module (build/python).
    import json
    import sys
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "build", "python"))
    import assets
    if len(sys.argv) < 2:
        sys.exit(f"usage: {sys.argv[0]} OUT_DIR [RES] [SPP]")
    out = sys.argv[1]
    res = int(sys.argv[2]) if len(sys.argv) > 2 else 512
    spp = int(sys.argv[3]) if len(sys.argv) > 3 else 64
    os.makedirs(out, exist_ok=True)
    profile = os.path.join(out, "spot_cosine.ies")
    write_cosine_profile(profile)
    assets.write(out)
    for scene_name in ALL:
        with open(os.path.join(out, scene_name + ".json"), "w") as f:
            json.dump(kozu_scene(scene_name, res, spp, 1, 64, os.path.join(out, "smoke.vdb"), profile), f, indent=1)
    print(f"{len(ALL)} scenes in {out}")
