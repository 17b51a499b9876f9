#!/usr/bin/env python3
"""Equal-time efficiency of render variants, measured in pairs on a shared, noisy machine.

Each variant is a KOZU:DIRECT pair (a build and its "direct" mode, e.g. build/kozu:ltc) or just DIRECT (the default
build). For each seed 1..N every variant renders the scene back to back (the order alternating between seeds), so the
machine's load, which drifts more slowly than one render, weighs on all of them alike. Printed per variant:
  time      the median over seeds of its render_seconds (--stats) divided by the first variant's for the same seed
            ([the middle half of those ratios])
  variance  the mean over seed pairs (1, 2), (3, 4), ... of half the mean squared difference of the pair's EXRs
            (all pixels, RGB), relative to the first variant's
  eff       the first variant's variance x time over this one's (above 1: better at equal time)
Medians of alternating runs of whole renders (bench/ab_render.sh, bench/ltc_equal_time.sh) spread 10-30 % here;
the paired ratios' middle half spans about ±5 % (docs/lights.md).

  python3 bench/paired_efficiency.py scenes/microfacet.json --variants sample ltc --spp 16 --seeds 8 \\
      --res 320x180
  python3 bench/paired_efficiency.py SCENE --variants /tmp/base/kozu:ltc build/kozu:ltc build/kozu:sample
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenes", nargs="+")
    p.add_argument("--variants", nargs="+", default=["sample", "ltc"], help="KOZU:DIRECT or DIRECT; the first is the base")
    p.add_argument("--spp", type=int, default=32)
    p.add_argument("--seeds", type=int, default=8, help="an even number of seeds, 1..N")
    p.add_argument("--res", default=None, help="WIDTHxHEIGHT (default: the scene's)")
    p.add_argument("--kozu", default=os.path.join(ROOT, "build", "kozu"))
    a = p.parse_args()
    if a.seeds < 2 or a.seeds % 2:
        p.error("--seeds must be an even number >= 2")
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(a.kozu)), "python"))
    import kozu  # noqa: E402  (the build's Python module: EXR reading)
    import numpy as np  # noqa: E402

    variants = [(v.rsplit(":", 1) if ":" in v else (a.kozu, v)) for v in a.variants]
    extra = ["--resolution", a.res] if a.res else []
    with tempfile.TemporaryDirectory() as tmp:
        for scene in a.scenes:
            times = [[] for _ in variants]
            variances = [[] for _ in variants]
            pending = [None for _ in variants]
            for i in range(a.seeds):
                order = range(len(variants)) if i % 2 == 0 else reversed(range(len(variants)))
                for k in order:
                    binary, direct = variants[k]
                    exr, stats = os.path.join(tmp, f"{k}.exr"), os.path.join(tmp, f"{k}.json")
                    subprocess.run([binary, "render", scene, "--direct", direct, "--spp", str(a.spp), "--seed",
                                    str(i + 1), "-q", *extra, "--stats", stats, "-o", exr], check=True)
                    with open(stats) as f:
                        times[k].append(json.load(f)["render_seconds"])
                    image = np.asarray(kozu.read_image(exr), dtype=np.float64)[..., :3]
                    if pending[k] is None:
                        pending[k] = image
                    else:
                        variances[k].append(float(np.mean((image - pending[k]) ** 2)) / 2.0)
                        pending[k] = None
            base_var = statistics.fmean(variances[0])
            print(f"{os.path.basename(scene)}: {a.spp} spp, {a.seeds} seeds{', ' + a.res if a.res else ''}")
            for k, (binary, direct) in enumerate(variants):
                ratios = sorted(t / t0 for t, t0 in zip(times[k], times[0]))
                q = len(ratios) // 4
                time = statistics.median(ratios)
                var = statistics.fmean(variances[k]) / base_var
                print(f"  {binary}:{direct}: seconds {statistics.median(times[k]):.3f}, time {time:.3f} "
                      f"[{ratios[q]:.3f}, {ratios[-1 - q]:.3f}], variance {var:.3f} "
                      f"({statistics.fmean(variances[k]):.4e}), eff {1.0 / (var * time):.3f}", flush=True)


if __name__ == "__main__":
    main()
