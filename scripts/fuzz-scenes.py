#!/usr/bin/env python3
"""Structured fuzzing of whole renders: the shipped scenes, mutated as JSON, each rendered small.

libFuzzer's fuzz_scene (tests/fuzz/) mutates bytes and only loads; almost none of its inputs reach the renderer.
This script keeps the JSON valid and changes what a user could: a number made 0, negated, scaled, or pushed to
10^±30 or to the integer limits; a value replaced by one of another type; a key or an array element
removed; an array element repeated; a flag flipped. Three changes to a number in four stay plausible (an integer
stays one; a real is scaled by up to 3 or by 10^±3, made 0 or negative), so that many cases pass the loader's
checks and reach the renderer. Each case renders at 24 x 16, 2 spp, and counts as a finding when kozu

  - is killed by a signal, aborts (a sanitizer build: AddressSanitizer, UBSan) or exits other than 0 or 1,
  - runs past --timeout seconds,
  - prints a sanitizer report or "terminate called",
  - exits 1 without naming the scene file (docs/limits.md: one clear message naming the file and the JSON path),
  - exits 0 with NaN, Inf or negative pixels in its EXR (`oiiotool --stats`); negative ones are allowed only where
    the EXR says kozu:negative_pixels "keep" (render.negative_pixels: "direct": "ltc"'s control variate gives signed,
    unbiased estimates, so that a pixel of a 2-spp render may rightly be below 0 unless clamped: docs/lights.md).

A mutated scene is written into a temporary folder beside links to its source folder's files (and its parent's,
one level up), so its relative paths still resolve. Findings are copied to --keep with kozu's stderr. Deterministic for a given --seed.

  python3 scripts/fuzz-scenes.py --kozu build/kozu --cases 200 --seed 7
  python3 scripts/fuzz-scenes.py --kozu build-asan/kozu --cases 30      # as scripts/test.sh runs it
"""
import argparse
import copy
import glob
import json
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Scenes whose loading alone takes tens of seconds (voxelizing the bush) or that are animations.
SKIP = ("bush_", "camp_animation")
OTHER_TYPES = [0, -1, 1, 0.5, 1e30, -1e30, 1e-30, 4294967297, -2147483649, "x", "", [], {}, None, True,
               [0, 0, 0], [1e30, 0, -1e30], [0], [[0, 0, 0]]]


def parent(o, path):
    for k in path[:-1]:
        o = o[k]
    return o


def pick(scene, rng):
    """A (path, value) by a random walk down from the root, stopping at each level with probability 1/4: every key
    of an object is as likely as its siblings however large it is (a mesh's thousands of indices would otherwise
    take nearly every mutation, and the loader refuses nearly every change to an index)."""
    path, v = (), scene
    while isinstance(v, (dict, list)) and v:
        key = rng.choice(list(v.keys()) if isinstance(v, dict) else range(len(v)))
        path, v = path + (key,), v[key]
        if rng.random() < 0.25:
            break
    return path, v


def mutate(scene, rng):
    path, v = pick(scene, rng)
    if not path:
        return
    where, key = parent(scene, path), path[-1]
    r = rng.random()
    if isinstance(v, bool):
        where[key] = not v
    elif isinstance(v, int):
        # Integers stay integers (a count, an index, a size) in three cases of four.
        where[key] = rng.choice([0, 1, -v, 2 * v, v // 2, v + 1, v - 1] if r < 0.75 else
                                [2**31, -(2**31), 2**63 - 1, v * 10**9, 0.5])
    elif isinstance(v, float):
        # Values the loader's range checks may well accept, so that most such cases reach the renderer.
        where[key] = (rng.choice([0.0, -v, v * rng.uniform(0.0, 3.0), v * 1e-3, v * 1e3, 1e-6, v + 1.0]) if r < 0.75
                      else rng.choice([v * 1e10, v * 1e-10, 1e30, -1e30, 1e-38]))
    elif r < 0.4:
        del where[key]
    elif r < 0.7 and isinstance(v, list) and v:
        v.append(copy.deepcopy(rng.choice(v)))
    else:
        where[key] = copy.deepcopy(rng.choice(OTHER_TYPES))


def pixels_problem(exr):
    """None when every pixel of exr is finite and non-negative (or finite, where it says its negative pixels were
    kept), else what is wrong."""
    out = subprocess.run(["oiiotool", "-v", "--stats", exr], capture_output=True, text=True).stdout
    signed = re.search(r'kozu:negative_pixels: "keep"', out) is not None
    counts = {}
    for name in ("NanCount", "InfCount", "Min"):
        m = re.search(rf"Stats {name}: ([^\n]*)", out)
        if not m:
            return f"oiiotool printed no {name}"
        counts[name] = [float(x) for x in m.group(1).split() if re.match(r"^-?[0-9.e+-]+$", x)]
    if any(counts["NanCount"]) or any(counts["InfCount"]):
        return f"NaN {counts['NanCount']}, Inf {counts['InfCount']}"
    if not signed and min(counts["Min"]) < 0.0:
        return f"negative pixels (min {counts['Min']})"
    return None


def run_case(kozu, src, scene, timeout):
    """(finding or None, stderr, exit status) for one mutated scene."""
    with tempfile.TemporaryDirectory(prefix="kozu-fuzz-scenes-") as tmp:
        # The source folder's files, and its parent's beside it (a cookbook scene reads ../textures).
        folder = os.path.dirname(src)
        up = os.path.dirname(folder)
        here = os.path.join(tmp, os.path.basename(folder))
        os.mkdir(here)
        for name in os.listdir(up):
            if name != os.path.basename(folder):
                os.symlink(os.path.join(up, name), os.path.join(tmp, name))
        for name in os.listdir(folder):
            os.symlink(os.path.join(folder, name), os.path.join(here, name))
        case = os.path.join(here, "fuzz_case.json")
        with open(case, "w") as f:
            json.dump(scene, f)
        exr, stats = os.path.join(tmp, "out.exr"), os.path.join(tmp, "stats.json")
        try:
            p = subprocess.run([kozu, "render", case, "--resolution", "24x16", "--spp", "2", "--threads", "2", "-q",
                                "-o", exr, "--stats", stats], capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return f"still running after {timeout} s", "", None
        err = p.stderr
        if p.returncode not in (0, 1):
            return f"exit status {p.returncode}", err, p.returncode
        for mark in ("Sanitizer", "runtime error:", "terminate called"):
            if mark in err:
                return f"printed '{mark}'", err, p.returncode
        if p.returncode == 1 and "fuzz_case.json" not in err:
            return "exit 1 without naming the scene file", err, p.returncode
        if p.returncode == 0:
            problem = pixels_problem(exr)
            if problem:
                return problem, err, p.returncode
        return None, err, p.returncode


def main():
    a = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    a.add_argument("--kozu", default=os.path.join(ROOT, "build", "kozu"))
    a.add_argument("--cases", type=int, default=40)
    a.add_argument("--seed", type=int, default=1)
    a.add_argument("--timeout", type=float, default=120.0, help="seconds a case may take")
    a.add_argument("--keep", default=os.path.join(tempfile.gettempdir(), "kozu-fuzz-scenes"),
                   help="folder for the findings")
    args = a.parse_args()
    scenes = sorted(p for p in glob.glob(os.path.join(ROOT, "scenes", "*.json")) +
                    glob.glob(os.path.join(ROOT, "scenes", "cookbook", "*.json"))
                    if not any(s in os.path.basename(p) for s in SKIP))
    if not scenes:
        sys.exit("fuzz-scenes: no scenes under scenes/")
    rng = random.Random(args.seed)
    findings, rendered = 0, 0
    for i in range(args.cases):
        src = rng.choice(scenes)
        with open(src) as f:
            scene = json.load(f)
        for _ in range(rng.randint(1, 2)):
            mutate(scene, rng)
        finding, err, status = run_case(args.kozu, src, scene, args.timeout)
        rendered += status == 0
        if finding:
            findings += 1
            os.makedirs(args.keep, exist_ok=True)
            base = os.path.join(args.keep, f"seed{args.seed}_case{i}")
            with open(base + ".json", "w") as f:
                json.dump(scene, f, indent=1)
            with open(base + ".stderr", "w") as f:
                f.write(err)
            print(f"fuzz-scenes: case {i} (from {os.path.relpath(src, ROOT)}): {finding}; kept as {base}.json\n"
                  f"{err[-800:]}", flush=True)
    print(f"fuzz-scenes: {args.cases} cases from {len(scenes)} scenes (seed {args.seed}): {rendered} rendered, "
          f"{args.cases - rendered} refused or failed, {findings} findings")
    sys.exit(1 if findings else 0)


if __name__ == "__main__":
    main()
