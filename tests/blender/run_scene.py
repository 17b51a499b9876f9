"""One Blender test scene, rendered three ways and compared (run by run_blender_test.py through ctest):
    blender -b --factory-startup --python-exit-code 1 --python tests/blender/run_scene.py -- SCENE OUT_DIR KOZU

1. the scene is built by script (scenes.py) and rendered by Cycles;
2. exported with bpy.ops.export_scene.kozu and rendered by the kozu command;
3. rendered by the add-on's render engine (bpy.ops.render.render with engine KOZU).
Block means of 2 and 3 are compared with Cycles' (mean, correlation, largest block error) and with each other; the
figures go to OUT_DIR/result.json. A failed check raises, which makes Blender exit with status 1.
"""
import json
import os
import shutil
import subprocess
import sys
import time

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "..", "blender"))
import scenes  # noqa: E402

BLOCK = 8  # pixels per block side


def render_to(path):
    scene = bpy.context.scene
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.filepath = path
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    return time.perf_counter() - start


def load(path, alpha=False):
    img = bpy.data.images.load(path, check_existing=False)
    w, h = img.size
    px = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    px = px.reshape(h, w, 4).astype(np.float64)
    return px if alpha else px[..., :3]


def block_means(img):
    h, w, _ = img.shape
    bh, bw = h // BLOCK, w // BLOCK
    return img[:bh * BLOCK, :bw * BLOCK].reshape(bh, BLOCK, bw, BLOCK, 3).mean(axis=(1, 3))


def compare(ref, test):
    """mean ratio - 1, correlation of block means, largest relative block error (over the blocks above a quarter of the mean: darker ones, lit by a
    few indirect paths, are noise at these sample counts, and the mean and correlation cover them)."""
    a, b = block_means(ref).ravel(), block_means(test).ravel()
    mean_err = b.mean() / a.mean() - 1.0
    corr = float(np.corrcoef(a, b)[0, 1])
    big = a > 0.25 * a.mean()
    block = float(np.max(np.abs(b[big] - a[big]) / a[big]))
    return {"mean": float(mean_err), "corr": corr, "block": block, "ref_mean": float(a.mean()),
            "test_mean": float(b.mean())}


def check_cancel(out, finished):
    """Esc during an engine render: the engine sends kozu SIGINT and shows what kozu wrote. The engine's Esc check
    is made to answer "Esc" two seconds into a render of a million samples per pixel."""
    import kozu_blender.engine as engine
    scene = bpy.context.scene
    samples = scene.cycles.samples
    scene.cycles.samples = 1000000
    start = time.perf_counter()
    real = engine.cancel_requested
    engine.cancel_requested = lambda _: time.perf_counter() - start > 2.0
    try:
        seconds = render_to(os.path.join(out, "cancelled.exr"))
    finally:
        engine.cancel_requested = real
        scene.cycles.samples = samples
    partial = load(os.path.join(out, "cancelled.exr"))
    r = compare(finished, partial)
    assert seconds < 60, f"the cancelled render took {seconds:.1f} s"
    assert abs(r["mean"]) < 0.02 and r["corr"] > 0.99, f"the cancelled render's image: {r}"
    return {"seconds": seconds, **r}


def check_animation(out):
    """An animation through the engine, frame by frame: a keyed cube moves, each frame is its own kozu render."""
    scene = bpy.context.scene
    cube = next(o for o in scene.objects if o.type == "MESH" and o.data.materials and
                o.data.materials[0].name == "red")
    scene.frame_start, scene.frame_end = 1, 2
    cube.location.x = 0.9
    cube.keyframe_insert("location", frame=1)
    cube.location.x = -0.1
    cube.keyframe_insert("location", frame=2)
    scene.render.filepath = os.path.join(out, "anim_")
    bpy.ops.render.render(animation=True)
    frames = [load(os.path.join(out, f"anim_{f:04d}.exr")) for f in (1, 2)]
    moved = float(np.abs(frames[0] - frames[1]).mean() / frames[0].mean())
    assert moved > 0.01, f"the two frames differ by {moved:.4f} of the mean: the cube did not move"
    return {"frames": 2, "relative_difference": moved}


def pass_of(exr, channels, out):
    """One render pass of a multilayer EXR as an (h, w, n) array, through oiiotool (Blender's loader reads one)."""
    names = [f"ViewLayer.{c}" for c in channels]
    names += [names[-1]] * (4 - len(names))
    subprocess.run(["oiiotool", exr, "--ch", ",".join(names), "--chnames", "R,G,B,A", "-o", out], check=True,
                   capture_output=True)
    img = bpy.data.images.load(out, check_existing=False)
    w, h = img.size
    px = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    return px.reshape(h, w, 4)[..., :len(channels)].astype(np.float64)


def check_passes(out):
    """The engine's Depth and Normal passes (kozu's AOVs) against Cycles' own: same axes, same depth."""
    scene = bpy.context.scene
    layer = bpy.context.view_layer
    layer.use_pass_z = layer.use_pass_normal = layer.use_pass_diffuse_color = True
    scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    files = {}
    for engine in ("CYCLES", "KOZU"):
        scene.render.engine = engine
        scene.render.filepath = os.path.join(out, f"passes_{engine.lower()}.exr")
        bpy.ops.render.render(write_still=True)
        files[engine] = scene.render.filepath
    got = {}
    for engine, exr in files.items():
        got[engine] = (pass_of(exr, ["Normal.X", "Normal.Y", "Normal.Z"], os.path.join(out, f"n_{engine}.exr")),
                       pass_of(exr, ["Depth.Z"], os.path.join(out, f"z_{engine}.exr"))[..., 0])
    (nc, zc), (nk, zk) = got["CYCLES"], got["KOZU"]
    hit = (zc < 1e5) & (zk > 0) & (zk < 1e5) & (np.linalg.norm(nc, axis=2) > 0.5)
    assert hit.mean() > 0.5, f"only {hit.mean():.2f} of the pixels hit geometry in both"
    normal_ok = float(np.mean(np.linalg.norm(nc - nk, axis=2)[hit] < 0.05))
    depth_err = float(np.median(np.abs(zk[hit] / zc[hit] - 1.0)))
    albedo = pass_of(files["KOZU"], ["DiffCol.R", "DiffCol.G", "DiffCol.B"], os.path.join(out, "a_KOZU.exr"))
    assert normal_ok > 0.9, f"normals agree on {100 * normal_ok:.1f} % of the pixels"
    assert depth_err < 0.01, f"median depth error {100 * depth_err:.2f} %"
    assert albedo.max() > 0.1, "the Diffuse Color pass is empty"
    return {"normal_agreement": normal_ok, "depth_median_error": depth_err}


def main():
    argv = sys.argv[sys.argv.index("--") + 1:]
    name, out, kozu = argv[0], os.path.abspath(argv[1]), os.path.abspath(argv[2])
    if os.path.isdir(out):
        shutil.rmtree(out)  # a clean folder: nothing of an earlier run is compared
    os.makedirs(out)
    os.environ["KOZU"] = kozu  # the engine finds kozu through it; the vdb scene makes its smoke with it
    build, what, tol = scenes.SCENES[name]
    build(out)
    result = {"scene": name, "checks": what, "tolerance": tol}

    result["cycles_seconds"] = render_to(os.path.join(out, "cycles.exr"))

    import addon_utils
    addon_utils.enable("kozu_blender", default_set=True)
    scene_file = os.path.join(out, "scene.json")
    res = bpy.ops.export_scene.kozu(filepath=scene_file)
    assert res == {"FINISHED"}, f"export returned {res}"
    exported = json.load(open(scene_file))
    result["not_mapped"] = exported["comment"]["not_mapped_exactly"]
    start = time.perf_counter()
    cmd = [kozu, "render", scene_file, "-q", "-o", os.path.join(out, "kozu.exr")]
    subprocess.run(cmd + exported["comment"]["render_with"][3:], check=True)
    result["kozu_seconds"] = time.perf_counter() - start

    bpy.context.scene.render.engine = "KOZU"
    result["engine_seconds"] = render_to(os.path.join(out, "engine.exr"))

    cycles, cli, eng = (load(os.path.join(out, f)) for f in ("cycles.exr", "kozu.exr", "engine.exr"))
    result["exporter_vs_cycles"] = compare(cycles, cli)
    result["engine_vs_cycles"] = compare(cycles, eng)
    result["engine_vs_exporter"] = compare(cli, eng)
    failures = []
    if name == "light_area":
        result["cancel"] = check_cancel(out, eng)
        result["animation"] = check_animation(out)
        result["passes"] = check_passes(out)
    if bpy.context.scene.render.film_transparent:
        # Coverage: Cycles' alpha against kozu's (--alpha, which the exporter asks for), the image mean and blocks.
        a_c, a_k = (load(os.path.join(out, f), alpha=True)[..., 3:].repeat(3, axis=2)
                    for f in ("cycles.exr", "engine.exr"))
        result["alpha"] = compare(a_c, a_k)
        if abs(result["alpha"]["mean"]) > 0.02 or result["alpha"]["corr"] < 0.99:
            failures.append(f"alpha (coverage) differs: {result['alpha']}")
    extra = getattr(scenes, "check_" + name, None)
    if extra is not None:
        try:
            result["extra"] = extra(exported, out)
        except AssertionError as e:
            failures.append(f"{name}: {e}")
    for key in ("exporter_vs_cycles", "engine_vs_cycles"):
        r = result[key]
        if abs(r["mean"]) > tol["mean"]:
            failures.append(f"{key}: image mean off by {100 * r['mean']:+.2f} % (tolerance {100 * tol['mean']:.0f} %)")
        if r["corr"] < tol["corr"]:
            failures.append(f"{key}: block correlation {r['corr']:.4f} < {tol['corr']}")
        if r["block"] > tol["block"]:
            failures.append(f"{key}: a block mean off by {100 * r['block']:.1f} % (tolerance {100 * tol['block']:.0f} %)")
    # The engine renders the same export with the same seed: the same image up to its flags' effects (none on RGB).
    if result["engine_vs_exporter"]["block"] > 1e-3:
        failures.append(f"engine and exporter routes differ: {result['engine_vs_exporter']}")
    result["failures"] = failures
    with open(os.path.join(out, "result.json"), "w") as f:
        json.dump(result, f, indent=1)
    print("KOZU_BLENDER_RESULT " + json.dumps(result))
    if failures:
        raise AssertionError("; ".join(failures))


main()
