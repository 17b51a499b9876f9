#!/usr/bin/env python3
"""Light selection at equal settings: the light hierarchy ("light_selection": "tree", lights/light_tree.h) against
selection by power ("power"), on scenes of many lights. Each scene renders twice per mode (seeds 1 and 2); printed
per mode: the render time (`--stats`), the variance (the per-pixel (a - b)^2 / 2 of the two seeds, averaged over
channels and over the pixels that see no emitter directly: a small bright emitter's edge in a pixel is noise no
light selection touches, and it would hide the rest; the mask is a 16-spp render of emission alone), the image
mean, and efficiency = (variance x time) of "power" over the tree's.

Scenes (written to --out):
  corridor   a 40-unit corridor lit by 100 small ceiling quads of four brightnesses (1, 3, 10, 30), diffuse walls
  mixed      the corridor's floor under a dim uniform sky, 24 quads, 6 spheres and 6 point lights, a glossy sphere

  python3 bench/light_selection.py                 # both scenes, 320x180, 64 spp
  python3 bench/light_selection.py corridor --spp 16 --kozu build/kozu
"""
import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def corridor(res, spp):
    shapes = [
        {"type": "quad", "material": "wall", "vertices": [[-2, 0, 0], [2, 0, 0], [2, 0, 40], [-2, 0, 40]]},
        {"type": "quad", "material": "wall", "vertices": [[-2, 3, 0], [-2, 3, 40], [2, 3, 40], [2, 3, 0]]},
        {"type": "quad", "material": "wall", "vertices": [[-2, 0, 0], [-2, 0, 40], [-2, 3, 40], [-2, 3, 0]]},
        {"type": "quad", "material": "wall", "vertices": [[2, 0, 0], [2, 3, 0], [2, 3, 40], [2, 0, 40]]},
        {"type": "quad", "material": "wall", "vertices": [[-2, 0, 40], [2, 0, 40], [2, 3, 40], [-2, 3, 40]]},
    ]
    levels = [1, 3, 10, 30]
    for i in range(100):
        x = -1.5 + 3.0 * ((i * 37) % 10) / 9.0
        z = 0.5 + 39.0 * i / 99.0
        s = 0.1
        shapes.append({"type": "quad", "emission": levels[(i * 7) % 4],
                       "vertices": [[x - s, 2.99, z - s], [x + s, 2.99, z - s], [x + s, 2.99, z + s], [x - s, 2.99, z + s]]})
    return {
        "camera": {"position": [0, 1.5, 0.5], "look_at": [0.3, 1.2, 10], "fov": 60, "resolution": list(res)},
        "render": {"spp": spp, "max_depth": 8, "filter": "box"},
        "materials": {"wall": {"type": "diffuse", "albedo": 0.6}},
        "shapes": shapes,
    }


def mixed(res, spp):
    shapes = [{"type": "quad", "material": "floor", "vertices": [[-10, 0, -10], [-10, 0, 10], [10, 0, 10], [10, 0, -10]]},
              {"type": "sphere", "material": "gloss", "center": [0, 1, 0], "radius": 1}]
    lights = [{"type": "environment", "radiance": [0.02, 0.03, 0.05]}]
    for i in range(24):
        x, z = -6 + 12 * ((i * 5) % 24) / 23.0, -6 + 12 * ((i * 11) % 24) / 23.0
        y = 0.5 + 2.5 * (i % 4) / 3.0
        shapes.append({"type": "quad", "emission": [2, 5, 20][i % 3],
                       "vertices": [[x, y, z], [x + 0.3, y, z], [x + 0.3, y, z + 0.3], [x, y, z + 0.3]]})
    for i in range(6):
        shapes.append({"type": "sphere", "emission": 10, "center": [-5 + 2 * i, 0.3, 4], "radius": 0.1})
        lights.append({"type": "point", "position": [-5 + 2 * i, 2.0, -4], "intensity": 1 + i})
    return {
        "camera": {"position": [0, 4, -11], "look_at": [0, 0.5, 0], "fov": 45, "resolution": list(res)},
        "render": {"spp": spp, "max_depth": 8, "filter": "box"},
        "materials": {"floor": {"type": "diffuse", "albedo": 0.5},
                      "gloss": {"type": "conductor", "roughness": 0.2}},
        "shapes": shapes,
        "lights": lights,
    }


SCENES = {"corridor": corridor, "mixed": mixed}


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenes", nargs="*", default=list(SCENES), help="of " + ", ".join(SCENES))
    p.add_argument("--res", default="320x180")
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--kozu", default=os.path.join(ROOT, "build", "kozu"))
    p.add_argument("--out", default="/tmp/kozu-light-selection")
    a = p.parse_args()
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(a.kozu)), "python"))
    import kozu  # noqa: E402  (the build's Python module: EXR reading)
    import numpy as np  # noqa: E402

    os.makedirs(a.out, exist_ok=True)
    res = tuple(int(v) for v in a.res.split("x"))
    print(f"{a.res}, {a.spp} spp, {a.threads} threads, box filter, seeds 1 and 2")
    print("| scene | mode | seconds | variance | mean | efficiency |  (variance over the pixels that see no emitter)")
    print("| --- | --- | ---: | ---: | ---: | ---: |")
    for name in a.scenes:
        scene_file = os.path.join(a.out, f"{name}.json")
        with open(scene_file, "w") as f:
            json.dump(SCENES[name](res, a.spp), f)
        mask_exr = os.path.join(a.out, f"{name}-emitters.exr")
        subprocess.run([a.kozu, "render", scene_file, "-q", "-o", mask_exr, "--threads", str(a.threads), "--spp", "16",
                        "-D", "/render/max_depth=0"], check=True)
        lit = np.asarray(kozu.read_image(mask_exr))[..., :3].max(axis=2) <= 0.0  # pixels that see no emitter
        figures = {}
        for mode in ("power", "tree"):
            images, seconds = [], []
            for seed in (1, 2):
                exr = os.path.join(a.out, f"{name}-{mode}-{seed}.exr")
                stats = os.path.join(a.out, f"{name}-{mode}-{seed}.json")
                subprocess.run([a.kozu, "render", scene_file, "-q", "-o", exr, "--threads", str(a.threads),
                                "--stats", stats, "-D", f"/render/seed={seed}", "-D", f"/render/light_selection={mode}"],
                               check=True)
                with open(stats) as f:
                    seconds.append(json.load(f)["render_seconds"])
                images.append(np.asarray(kozu.read_image(exr))[..., :3].astype(np.float64))
            variance = float(((images[0] - images[1]) ** 2 / 2)[lit].mean())
            figures[mode] = (sum(seconds) / 2, variance, float(images[0].mean()))
        base = figures["power"][0] * figures["power"][1]
        for mode, (t, v, m) in figures.items():
            print(f"| {name} | {mode} | {t:.2f} | {v:.3e} | {m:.4f} | {base / (t * v):.2f} |")


if __name__ == "__main__":
    main()
