#!/usr/bin/env python3
"""kozu against Cycles, scene for scene (bench/cycles/scenes.py): both render at equal resolution, samples, bounces,
pixel filter (box) and threads, twice with two seeds; printed per renderer: the time to the image, the per-pixel
variance ((a - b)^2 / 2 over the two seeds, averaged over pixels and channels), the peak memory, and
efficiency = (variance x time) of Cycles over kozu's (above 1: kozu reaches equal noise sooner). The image means
must agree: their difference is printed beside the figures.

    python3 bench/cycles/compare.py [--res 512] [--spp 64] [--threads 2] [scene ...]

Times: kozu's load + render seconds from `kozu render --stats` (process start-up excluded), Cycles' is the
bpy.ops.render.render call (scene sync, BVH, volume load and render; Blender's own start-up excluded). Peak memory
is each process's maximum resident set (Blender's includes Blender itself). Needs Debian's `blender` (a benchmark
tool, never a build or test dependency), numpy, and kozu built with the Python module (build/python).
"""
import argparse
import json
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import scenes  # noqa: E402


def run(cmd, log):
    """Runs cmd; returns (stdout, peak resident set in MiB). Exits with its output when it fails."""
    with open(log, "w") as f:
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        out = p.stdout.read()
        _, status, usage = os.wait4(p.pid, 0)
        f.write(out)
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({p.returncode}):\n{out[-3000:]}")
    return out, usage.ru_maxrss / 1024.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="*", default=list(scenes.ALL), help=f"of {', '.join(scenes.ALL)}")
    ap.add_argument("--res", type=int, default=512)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--depth", type=int, default=64, help="kozu max_depth and Cycles' max bounces (all kinds)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seeds", type=int, nargs=2, default=[1, 2])
    ap.add_argument("--kozu", default=os.path.join(HERE, "..", "..", "build", "kozu"))
    ap.add_argument("--blender", default="blender")
    ap.add_argument("--set", action="append", default=[], metavar="PATH=VALUE",
                    help="a kozu scene override (kozu render -D), e.g. /render/volume_sampling=distance")
    ap.add_argument("--out", default="/tmp/kozu-cycles", help="folder for scenes, images and logs")
    ap.add_argument("--portals", choices=["both", "none", "kozu", "cycles"], default="both",
                    help="which renderer gets the scenes' light portals (the interior's window)")
    a = ap.parse_args()
    os.environ["KOZU_BENCH_PORTALS"] = a.portals  # read by surfaces.py, here and in Blender
    kozu_bin = os.path.abspath(a.kozu)
    # kozu's Python module reads the EXRs: beside the binary, else this tree's build.
    sys.path[:0] = [os.path.join(os.path.dirname(kozu_bin), "python"), os.path.join(HERE, "..", "..", "build", "python")]
    import kozu  # noqa: E402  (build/python, beside the binary)
    import numpy as np  # noqa: E402
    os.makedirs(a.out, exist_ok=True)
    unknown = [s for s in a.scenes if s not in scenes.ALL]
    if unknown:
        sys.exit(f"unknown scene(s) {', '.join(unknown)}; known: {', '.join(scenes.ALL)}")
    vdb, profile = os.path.join(a.out, "smoke.vdb"), os.path.join(a.out, "spot_cosine.ies")
    scenes.write_cosine_profile(profile)
    if "vdb" in a.scenes and not os.path.exists(vdb):
        run([kozu_bin, "procedural", "smoke", "-o", vdb], os.path.join(a.out, "procedural.log"))
    if {"interior", "product"} & set(a.scenes):
        import assets  # noqa: E402  (the glTF room and the HDR skies, with kozu's module)
        assets.write(a.out)

    print(f"{a.res}x{a.res}, {a.spp} spp, {a.depth} bounces, {a.threads} threads, box filter, seeds {a.seeds}")
    print("| scene | kozu s | Cycles s | kozu variance | Cycles variance | kozu MiB | Cycles MiB | means | efficiency |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for name in a.scenes:
        rows = {}
        for renderer in ("kozu", "cycles"):
            images, seconds, peak = [], [], 0.0
            for seed in a.seeds:
                exr = os.path.join(a.out, f"{name}-{renderer}-{seed}.exr")
                log = os.path.join(a.out, f"{name}-{renderer}-{seed}.log")
                if renderer == "kozu":
                    scene_file = os.path.join(a.out, f"{name}.json")
                    with open(scene_file, "w") as f:
                        json.dump(scenes.kozu_scene(name, a.res, a.spp, seed, a.depth, vdb, profile), f, indent=1)
                    stats = os.path.join(a.out, f"{name}-kozu-{seed}.stats.json")
                    cmd = [kozu_bin, "render", scene_file, "-q", "-o", exr, "--threads", str(a.threads),
                           "--stats", stats]
                    for s in a.set:
                        cmd += ["-D", s]
                    _, mib = run(cmd, log)
                    with open(stats) as f:
                        st = json.load(f)
                    guiding = st.get("guiding", {})
                    # Path guiding's training passes on the side ("guiding": "on" resuming) are part of the time to the
                    # image; passes in the image are in render_seconds already.
                    side = 0.0 if guiding.get("in_image", True) else guiding.get("seconds", 0.0)
                    seconds.append(st["load_seconds"] + st["render_seconds"] + side)
                else:
                    out, mib = run([a.blender, "-b", "--factory-startup", "--python",
                                    os.path.join(HERE, "blender_render.py"), "--", name, str(a.res), str(a.spp),
                                    str(seed), str(a.depth), str(a.threads), exr, vdb], log)
                    m = re.search(r"CYCLES_RENDER_SECONDS ([\d.]+)", out)
                    if not m:
                        sys.exit(f"no render time in {log}")
                    seconds.append(float(m.group(1)))
                peak = max(peak, mib)
                images.append(kozu.read_image(exr)[..., :3].astype(np.float64))
            x, y = images
            rows[renderer] = dict(mean=(x.mean() + y.mean()) / 2, var=float(np.mean((x - y) ** 2) / 2),
                                  secs=float(np.median(seconds)), mib=peak)
        k, c = rows["kozu"], rows["cycles"]
        eff = (c["var"] * c["secs"]) / (k["var"] * k["secs"]) if k["var"] > 0 else float("inf")
        print(f"| {name} | {k['secs']:.2f} | {c['secs']:.2f} | {k['var']:.3g} | {c['var']:.3g} | {k['mib']:.0f} | "
              f"{c['mib']:.0f} | {100 * (k['mean'] / c['mean'] - 1):+.2f} % | **{eff:.2f}** |", flush=True)


if __name__ == "__main__":
    main()
