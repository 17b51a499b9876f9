#!/usr/bin/env python3
"""Training data for kozu's learned denoiser (src/render/learned_denoiser.h, tools/denoiser/train.py): pairs that
kozu renders itself, noisy inputs at 1-64 spp against a high-spp reference of the same view.

Each example is a 128 x 128 view of either a random procedural scene (random room, spheres and meshes, random
materials of every kind kozu has: Lambert and CoD multiple-scattering diffuse, plastic, rough conductors, rough and
smooth glass, subsurface; checker and procedural textures, normal maps; area, polygon, spot, sun and sky lights,
sometimes haze) or a random zoomed view of one of the repository's scenes that the denoiser table does NOT hold out
(bench/denoise_table.py holds out the interior, the Cornell box, the demo, the product shot and the fabric). It is
saved as EXAMPLE.npz with
  noisy    (S, H, W, 3) float32  the colour minus the visible emission (what the denoisers filter) at each of SPP
  albedo   (S, H, W, 3) float16  the render's own albedo AOV at that spp (noisy like the colour, as at run time)
  normal   (S, H, W, 3) float16  its normal AOV
  ref      (H, W, 3)    float32  the reference (REF spp, another seed) minus its visible emission
  spp      (S,)         int32

  PYTHONPATH=build/python python3 tools/denoiser/make_data.py OUT_DIR [--count 150] [--ref-spp 512] [--seed 1]

(512-spp references: 150 examples take an hour on 2 cores; their residual noise is left to the L1 loss, which
is robust to it. More references, or more samples in them, are the first thing to try with more cores.)

Deterministic for a seed (scene choice and kozu's own seeds); examples already in OUT_DIR are kept, so an
interrupted run continues where it stopped.
"""
import argparse
import copy
import json
import os
import random
import sys
import time

import numpy as np

import kozu

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
SPP = [1, 2, 4, 8, 16, 32, 64]
SIZE = 128
# Repository scenes that bench/denoise_table.py does not hold out (camera views of them are randomized).
REPO_SCENES = ["spheres", "subsurface", "stained_glass", "ltc_glossy", "smoke", "yarn", "microfacet",
               "cookbook/volume", "bush_mesh"]


def rgb(r, lo=0.05, hi=0.9):
    return [round(r.uniform(lo, hi), 3) for _ in range(3)]


def random_texture(r):
    kind = r.random()
    if kind < 0.35:
        return {"type": "checker", "scale": [r.choice([2, 4, 8, 16, 32])] * 2, "a": rgb(r, 0.3, 0.9),
                "b": rgb(r, 0.02, 0.4)}
    if kind < 0.7:
        s = r.choice([2, 4, 8, 16])
        return {"type": "image", "procedural": "cobblestone_albedo", "resolution": 256, "uv_scale": [s, s],
                "scale": [round(r.uniform(1.5, 3.8), 2) for _ in range(3)]}
    return {"type": "image", "procedural": "stained_glass", "resolution": 256,
            "scale": round(r.uniform(0.5, 1.0), 2)}


def random_material(r, textured_ok=True):
    kind = r.random()
    albedo = random_texture(r) if textured_ok and r.random() < 0.3 else rgb(r)
    if kind < 0.25:
        m = {"type": "diffuse", "albedo": albedo}
        if r.random() < 0.4:
            m.update({"model": "cod-multiscatter", "gloss": round(r.uniform(0.1, 0.9), 2)})
    elif kind < 0.45:
        m = {"type": "plastic", "albedo": albedo, "roughness": round(r.uniform(0.02, 0.6), 3)}
    elif kind < 0.65:
        m = {"type": "conductor", "metal": r.choice(["Au", "Cu", "Ag", "Al"]),
             "roughness": round(r.choice([0.0, r.uniform(0.05, 0.6)]), 3)}
        if m["roughness"] > 0.1 and r.random() < 0.5:
            m["multiscatter"] = "compensated"
    elif kind < 0.8:
        m = {"type": "dielectric", "ior": round(r.uniform(1.3, 1.7), 2),
             "roughness": round(r.choice([0.0, r.uniform(0.05, 0.4)]), 3)}
    elif kind < 0.9:
        m = {"type": "subsurface", "albedo": rgb(r, 0.3, 0.9),
             "mfp": [round(r.uniform(0.01, 0.2), 3) for _ in range(3)], "ior": 1.4,
             "roughness": round(r.uniform(0.2, 0.5), 2)}
    else:
        m = {"type": "diffuse", "albedo": albedo}
    if m["type"] in ("diffuse", "plastic") and r.random() < 0.25:
        s = r.choice([2, 4, 8, 16])
        m["normal_map"] = {"type": "image", "procedural": "cobblestone_normal", "resolution": 256,
                           "uv_scale": [s, s]}
    return m


def random_scene(r):
    """A random room (floor, sometimes walls), 2-8 objects, 1-3 lights, sometimes haze."""
    mats = {"floor": random_material(r), "wall": random_material(r), "soot": {"type": "diffuse", "albedo": 0.03}}
    shapes = [{"type": "quad", "material": "floor", "vertices": [[-6, 0, 6], [6, 0, 6], [6, 0, -6], [-6, 0, -6]]}]
    if r.random() < 0.6:
        shapes.append({"type": "quad", "material": "wall",
                       "vertices": [[-6, 0, -3], [6, 0, -3], [6, 5, -3], [-6, 5, -3]]})
    if r.random() < 0.4:
        side = r.choice([-1, 1]) * 3.5
        shapes.append({"type": "quad", "material": "wall",
                       "vertices": [[side, 0, 6], [side, 0, -3], [side, 5, -3], [side, 5, 6]]})
    for i in range(r.randint(2, 8)):
        name = f"m{i}"
        mats[name] = random_material(r)
        x, z = r.uniform(-2.2, 2.2), r.uniform(-2.0, 2.0)
        if r.random() < 0.7:
            rad = r.uniform(0.15, 0.8)
            shapes.append({"type": "sphere", "center": [round(x, 3), round(rad, 3), round(z, 3)],
                           "radius": round(rad, 3), "material": name})
        else:
            mesh = r.choice(["torus.ply", "candle.ply"])
            s = r.uniform(0.3, 1.0)
            shapes.append({"type": "mesh", "file": os.path.join(ROOT, "scenes", "meshes", mesh), "material": name,
                           "transform": {"scale": round(s, 3), "rotate": [0, 1, 0, round(r.uniform(0, 360), 1)],
                                         "translate": [round(x, 3), 0, round(z, 3)]}})
    lights = []
    env = r.random()
    if env < 0.4:
        lights.append({"type": "environment", "procedural": "dusk_sky", "resolution": 256,
                       "rotate": round(r.uniform(-180, 180), 1), "scale": round(r.uniform(0.3, 2.0), 2)})
    elif env < 0.8:
        lights.append({"type": "environment", "radiance": rgb(r, 0.01, 0.4)})
    for _ in range(r.randint(1, 3)):
        k = r.random()
        if k < 0.4:  # an area light, small and bright or large and soft
            w = r.uniform(0.2, 1.5)
            y, cx, cz = r.uniform(2.0, 4.5), r.uniform(-2, 2), r.uniform(-2, 2)
            emission = [round(v * (3.0 / w) ** 2, 3) for v in rgb(r, 0.5, 1.5)]
            tex = r.random() < 0.2
            shapes.append({"type": "quad", "material": "soot",
                           "emission": ({"type": "image", "procedural": "stained_glass", "resolution": 256,
                                         "scale": round(emission[0], 2)} if tex else emission),
                           "vertices": [[cx - w, y, cz + w], [cx - w, y, cz - w], [cx + w, y, cz - w],
                                        [cx + w, y, cz + w]]})
        elif k < 0.6:
            lights.append({"type": "spot", "position": [round(r.uniform(-4, 4), 2), round(r.uniform(2, 5), 2),
                                                         round(r.uniform(-1, 4), 2)],
                           "look_at": [round(r.uniform(-1, 1), 2), 0.3, round(r.uniform(-1, 1), 2)],
                           "intensity": [round(v * 40, 2) for v in rgb(r, 0.5, 1.5)],
                           "cone_angle": round(r.uniform(10, 40), 1), "falloff_angle": round(r.uniform(2, 10), 1)})
        elif k < 0.8:  # a small sun-like sphere far away
            d = np.array([r.uniform(-1, 1), r.uniform(0.2, 1), r.uniform(-1, 1)])
            d = 60 * d / np.linalg.norm(d)
            shapes.append({"type": "sphere", "center": [round(float(v), 2) for v in d], "radius": 2.0,
                           "material": "soot", "emission": [round(v * 300, 1) for v in rgb(r, 0.6, 1.2)]})
        else:
            lights.append({"type": "point", "position": [round(r.uniform(-3, 3), 2), round(r.uniform(1, 4), 2),
                                                          round(r.uniform(-1, 4), 2)],
                           "intensity": [round(v * 20, 2) for v in rgb(r, 0.5, 1.5)]})
    scene = {"camera": {"position": [round(r.uniform(-4, 4), 2), round(r.uniform(0.4, 3.5), 2),
                                     round(r.uniform(3.5, 7), 2)],
                        "look_at": [round(r.uniform(-1, 1), 2), round(r.uniform(0, 1), 2), round(r.uniform(-1, 1), 2)],
                        "fov": round(r.uniform(15, 50), 1), "resolution": [SIZE, SIZE]},
             "render": {"max_depth": r.choice([6, 8, 12])},
             "materials": mats, "shapes": shapes, "lights": lights}
    if r.random() < 0.15:
        scene["media"] = {"haze": {"type": "homogeneous", "density": round(r.uniform(0.01, 0.08), 3), "albedo": 0.9,
                                   "phase": {"type": "hg", "g": 0.5}}}
        scene["camera"]["medium"] = "haze"
    return scene, None


def repo_view(r):
    """A random zoomed and re-aimed view of one of REPO_SCENES (a crop of it, roughly)."""
    name = r.choice(REPO_SCENES)
    path = os.path.join(ROOT, "scenes", name + ".json")
    with open(path) as f:
        d = json.load(f)
    cam = d["camera"]
    cam["resolution"] = [SIZE, SIZE]
    cam["fov"] = round(cam.get("fov", 40) * r.uniform(0.25, 0.8), 2)
    la = np.array(cam.get("look_at", [0, 0, 0]), float)
    cam["look_at"] = [round(float(v + r.uniform(-0.4, 0.4)), 3) for v in la]
    cam["position"] = [round(float(v + r.uniform(-0.3, 0.3)), 3) for v in cam["position"]]
    return d, os.path.dirname(path)


def render(scene, base, spp, seed):
    kw = {"base_dir": base} if base else {}
    out = kozu.render(copy.deepcopy(scene), spp=spp, seed=seed, resolution=(SIZE, SIZE),
                      aovs=["albedo", "normal", "emission"], **kw)
    colour = np.nan_to_num(out["rgb"] - out["emission"], nan=0.0, posinf=0.0, neginf=0.0)
    return np.maximum(colour, 0.0).astype(np.float32), out["albedo"], out["normal"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--count", type=int, default=150)
    ap.add_argument("--ref-spp", type=int, default=512)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--repo-share", type=float, default=0.35, help="share of views of repository scenes")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    start = time.time()
    for i in range(args.count):
        r = random.Random(args.seed * 100003 + i)
        scene, base = repo_view(r) if r.random() < args.repo_share else random_scene(r)
        path = os.path.join(args.out, f"{i:05d}.npz")
        if os.path.exists(path):
            continue
        try:
            ref, _, _ = render(scene, base, args.ref_spp, 1_000_000 + i)
            noisy, albedo, normal = [], [], []
            for k, spp in enumerate(SPP):
                c, a, n = render(scene, base, spp, 10 * i + k)
                noisy.append(c)
                albedo.append(a.astype(np.float16))
                normal.append(n.astype(np.float16))
        except Exception as e:  # a random scene kozu rejects is reported and skipped, not fatal
            print(f"{i:05d}: skipped: {e}", file=sys.stderr)
            continue
        tmp = path + ".tmp.npz"
        np.savez(tmp, noisy=np.stack(noisy), albedo=np.stack(albedo), normal=np.stack(normal), ref=ref,
                 spp=np.array(SPP, np.int32))
        os.replace(tmp, path)
        with open(os.path.join(args.out, f"{i:05d}.json"), "w") as f:
            json.dump({"scene": scene, "base_dir": base}, f)
        print(f"{i:05d} done ({time.time() - start:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
