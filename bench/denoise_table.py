#!/usr/bin/env python3
"""The denoisers side by side (docs/production.md, "The denoiser"): for each held-out scene, a reference at REF spp
(another seed; kept in CACHE so that later runs reuse it), then one 16-spp render with --denoise --denoiser
regression (the feature regression), one with --denoiser unet (the learned U-Net), one with --denoiser ensemble
(the mean of NL-means and the regression) and one with --denoiser nlmeans (the default), the same samples (same
seed) for all. Prints a Markdown table of, per scene and image (raw 16 spp, NL-means, regression, U-Net, ensemble):

  relMSE   mean over pixels and channels of (x - ref)^2 / (ref^2 + 0.01), linear radiance (Rousselle et al. 2012)
  SSIM     structural similarity (Wang et al. 2004: 11 x 11 Gaussian window, sigma 1.5) of the display-referred
           luminance (ACES-free: linear clamped to [0, 1], sRGB-encoded), against the reference's
  detail   high-pass energy (the image minus its Gaussian blur of sigma 1 px, squared, summed) over the
           reference's: 1 keeps the reference's fine detail, below 1 erases it, above 1 adds noise
  blotch   low-frequency error: the error blurred by a Gaussian of sigma 4 px, its mean square over the reference's
           mean square, x 1000 (what reads as stains on flat walls)
  time     the filter's seconds (--stats denoise_seconds) and per pixel
  memory   the render's peak resident memory with the denoiser over the same render without it

  PYTHONPATH=build/python python3 bench/denoise_table.py [--kozu build/kozu] [--ref-spp 1024] [--cache DIR]
        [--denoisers regression,nlmeans,unet,ensemble] [SCENE:WxH ...]

Defaults: the five held-out scenes below. "demo" is the built-in scene (kozu render --demo).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

import kozu

HELD_OUT = [
    "scenes/cookbook/interior.json:480x270",  # an interior lit through a window
    "scenes/cornell.json:256x256",
    "demo:480x270",
    "scenes/cookbook/product.json:480x270",  # a textured product shot
    "scenes/fabric.json:320x240",  # an SGGX fabric close-up
]


def gaussian_blur(img, sigma):
    """Separable Gaussian blur (truncated at 3 sigma, edges clamped) of an (H, W) or (H, W, C) array."""
    r = max(1, int(3 * sigma + 0.5))
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k /= k.sum()
    out = img.astype(np.float64)
    for axis in (0, 1):
        pad = [(0, 0)] * out.ndim
        pad[axis] = (r, r)
        p = np.pad(out, pad, mode="edge")
        acc = np.zeros_like(out)
        n = out.shape[axis]
        for i, w in enumerate(k):
            sl = [slice(None)] * out.ndim
            sl[axis] = slice(i, i + n)
            acc += w * p[tuple(sl)]
        out = acc
    return out


def display_luma(rgb):
    c = np.clip(rgb[..., :3], 0.0, 1.0)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return s @ np.array([0.2126, 0.7152, 0.0722])


def ssim(a, b):
    c1, c2 = 0.01 ** 2, 0.03 ** 2
    mu_a, mu_b = gaussian_blur(a, 1.5), gaussian_blur(b, 1.5)
    va = gaussian_blur(a * a, 1.5) - mu_a ** 2
    vb = gaussian_blur(b * b, 1.5) - mu_b ** 2
    cov = gaussian_blur(a * b, 1.5) - mu_a * mu_b
    s = ((2 * mu_a * mu_b + c1) * (2 * cov + c2)) / ((mu_a ** 2 + mu_b ** 2 + c1) * (va + vb + c2))
    return float(s.mean())


def metrics(x, ref):
    x, ref = x[..., :3].astype(np.float64), ref[..., :3].astype(np.float64)
    rel = float(np.mean((x - ref) ** 2 / (ref ** 2 + 0.01)))
    lx, lr = display_luma(x), display_luma(ref)
    hp = lambda l: float(np.sum((l - gaussian_blur(l, 1.0)) ** 2))
    detail = hp(lx) / max(hp(lr), 1e-12)
    blotch = 1000 * float(np.mean(gaussian_blur(x - ref, 4.0) ** 2) / max(np.mean(ref ** 2), 1e-12))
    return rel, ssim(lx, lr), detail, blotch


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"failed ({r.returncode}): {' '.join(cmd)}\n{r.stderr}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--kozu", default="build/kozu")
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "kozu-denoise-refs"))
    ap.add_argument("--denoisers", default="regression,nlmeans,unet,ensemble",
                    help="comma-separated filters to run (default: all four)")
    ap.add_argument("scenes", nargs="*", default=HELD_OUT)
    args = ap.parse_args()
    os.makedirs(args.cache, exist_ok=True)
    work = tempfile.mkdtemp()
    print(f"| scene | image | relMSE | SSIM | detail | blotch | filter s (µs/px) | memory |")
    print(f"|---|---|---|---|---|---|---|---|")
    for item in args.scenes:
        scene, res = item.rsplit(":", 1)
        name = "demo" if scene == "demo" else os.path.splitext(os.path.basename(scene))[0]
        src = ["--demo"] if scene == "demo" else [scene]
        ref = os.path.join(args.cache, f"{name}-{res}-{args.ref_spp}.exr")
        if not os.path.exists(ref):
            run([args.kozu, "render", *src, "--resolution", res, "--spp", str(args.ref_spp), "--seed", "7", "-q",
                 "-o", ref])
        base = [args.kozu, "render", *src, "--resolution", res, "--spp", str(args.spp), "--seed", "1", "-q"]
        out = {}
        chosen = args.denoisers.split(",")
        for label, extra in [("plain", [])] + [(d, ["--denoise", "--denoiser", d]) for d in chosen]:
            exr = os.path.join(work, f"{name}.{label}.exr")
            stats = os.path.join(work, f"{name}.{label}.json")
            run(base + extra + ["-o", exr, "--stats", stats])
            with open(stats) as f:
                out[label] = json.load(f)
        r = kozu.read_image(ref)
        w, h = (int(v) for v in res.split("x"))
        px = w * h
        rows = [("raw 16 spp", os.path.join(work, f"{name}.plain.exr"), None),
                ("NL-means", os.path.join(work, f"{name}.nlmeans.denoised.exr"), "nlmeans"),
                ("regression", os.path.join(work, f"{name}.regression.denoised.exr"), "regression"),
                ("U-Net", os.path.join(work, f"{name}.unet.denoised.exr"), "unet"),
                ("ensemble", os.path.join(work, f"{name}.ensemble.denoised.exr"), "ensemble")]
        rows = [row for row in rows if row[2] is None or row[2] in chosen]
        for label, path, key in rows:
            rel, s, detail, blotch = metrics(kozu.read_image(path), r)
            t = mem = ""
            if key:
                sec = out[key]["denoise_seconds"]
                t = f"{sec:.3f} ({1e6 * sec / px:.2f})"
                mem = f"{out[key]['peak_memory_bytes'] / out['plain']['peak_memory_bytes']:.2f}x"
            print(f"| {name} {res} | {label} | {rel:.4f} | {s:.3f} | {detail:.2f} | {blotch:.3f} | {t} | {mem} |")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
