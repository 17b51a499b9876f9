#!/usr/bin/env python3
"""Trains kozu's learned denoiser (src/render/learned_denoiser.h) on the pairs tools/denoiser/make_data.py renders,
with Debian's python3-torch, and writes its weights as a .kzw file (the format learned_denoiser.h reads; the
repository's data/denoiser/unet-v1.kzw is this script's output, compiled into kozu).

The network is a small U-Net on colour, albedo and normal (9 channels in, 3 out), the layout of Intel Open Image
Denoise's (Áfra 2019) at a fraction of its width: widths --widths c0,c1,c2,c3 on the way down (3 x 3 convolutions,
ReLU, 2 x 2 max-pooling) and d2,d1,d0 on the way up (nearest upsampling, concatenation with the skip). The colour
enters as log1p(s c) with the exposure s = 0.18 / exp(mean log(luminance + 1e-4)) of the whole image, clamped to
[1e-4, 1e4], the same transform as the C++ code; the loss is L1 on that transform (robust to the references'
own noise) plus L1 on its horizontal and vertical differences (edges and texture, as OIDN's gradient loss).

  python3 tools/denoiser/train.py DATA_DIR -o data/denoiser/unet-v1.kzw [--minutes 34] [--seed 1]

With --steps the run is deterministic for a seed, data and thread count (torch's CPU kernels); with --minutes (the
default) the step count, and so the weights, depend on the machine's speed. The last tenth of the examples (by
name) is held out for the validation loss printed every 200 steps.
"""
import argparse
import glob
import math
import os
import struct
import time

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F


def exposure(colour):
    """The C++ code's exposure scale of an (H, W, 3) linear image (learned_denoiser.cpp)."""
    lum = 0.2126 * colour[..., 0] + 0.7152 * colour[..., 1] + 0.0722 * colour[..., 2]
    s = 0.18 / math.exp(float(np.mean(np.log(np.maximum(lum, 0.0) + 1e-4))))
    return min(max(s, 1e-4), 1e4)


class UNet(nn.Module):
    def __init__(self, c, d):
        super().__init__()
        c0, c1, c2, c3 = c
        d2, d1, d0 = d
        conv = lambda i, o: nn.Conv2d(i, o, 3, padding=1)
        self.layers = nn.ModuleList([conv(9, c0), conv(c0, c0), conv(c0, c1), conv(c1, c2), conv(c2, c3),
                                     conv(c3 + c2, d2), conv(d2 + c1, d1), conv(d1 + c0, d0), conv(d0, 3)])

    def forward(self, x):
        L = self.layers
        x = F.relu(L[0](x))
        s0 = F.relu(L[1](x))
        s1 = F.relu(L[2](F.max_pool2d(s0, 2)))
        s2 = F.relu(L[3](F.max_pool2d(s1, 2)))
        x = F.relu(L[4](F.max_pool2d(s2, 2)))
        up = lambda t: F.interpolate(t, scale_factor=2, mode="nearest")
        x = F.relu(L[5](torch.cat([up(x), s2], 1)))
        x = F.relu(L[6](torch.cat([up(x), s1], 1)))
        x = F.relu(L[7](torch.cat([up(x), s0], 1)))
        return L[8](x)


def load(files):
    data = []
    for f in files:
        z = np.load(f)
        noisy, ref = z["noisy"], z["ref"]
        if not (np.isfinite(noisy).all() and np.isfinite(ref).all()):
            continue
        # Per spp level: the transformed input (9, H, W) and target (3, H, W), at the noisy image's exposure.
        levels = []
        for k in range(noisy.shape[0]):
            # As the C++ code: negative radiance ("direct": "ltc" films are signed) as 0, non-finite albedo as 0.
            c = np.maximum(noisy[k], 0.0)
            albedo = np.clip(np.nan_to_num(z["albedo"][k].astype(np.float32), nan=0, posinf=0, neginf=0), 0, 1)
            s = exposure(c)
            x = np.concatenate([np.log1p(s * c), albedo, z["normal"][k].astype(np.float32)],
                               axis=-1).transpose(2, 0, 1)
            y = np.log1p(s * np.maximum(ref, 0.0)).transpose(2, 0, 1)
            levels.append((np.ascontiguousarray(x), np.ascontiguousarray(y)))
        data.append((levels, z["spp"].tolist()))
    return data


def batch(data, rng, n, size):
    xs, ys = [], []
    for _ in range(n):
        levels, _ = data[rng.integers(len(data))]
        x, y = levels[rng.integers(len(levels))]
        h, w = x.shape[1:]
        i, j = rng.integers(h - size + 1), rng.integers(w - size + 1)
        x, y = x[:, i:i + size, j:j + size], y[:, i:i + size, j:j + size]
        if rng.random() < 0.5:
            x, y = x[:, :, ::-1], y[:, :, ::-1]
        if rng.random() < 0.5:
            x, y = x[:, ::-1, :], y[:, ::-1, :]
        xs.append(np.ascontiguousarray(x))
        ys.append(np.ascontiguousarray(y))
    return torch.from_numpy(np.stack(xs)), torch.from_numpy(np.stack(ys))


def loss_fn(p, y):
    dx = lambda t: t[..., :, 1:] - t[..., :, :-1]
    dy = lambda t: t[..., 1:, :] - t[..., :-1, :]
    return F.l1_loss(p, y) + 0.5 * (F.l1_loss(dx(p), dx(y)) + F.l1_loss(dy(p), dy(y)))


def write_kzw(model, path):
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(b"KZUNET01")
        f.write(struct.pack("<I", len(model.layers)))
        for conv in model.layers:
            w = conv.weight.detach().cpu().numpy().astype("<f4")
            b = conv.bias.detach().cpu().numpy().astype("<f4")
            f.write(struct.pack("<III", w.shape[0], w.shape[1], w.shape[2]))
            f.write(w.tobytes(order="C"))
            f.write(b.tobytes())
        f.write(b"END!")
    os.replace(tmp, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("data")
    ap.add_argument("-o", "--output", default="data/denoiser/unet-v1.kzw")
    ap.add_argument("--minutes", type=float, default=34.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--steps", type=int, default=0,
                    help="train exactly this many steps (the learning rate's decay over them) instead of --minutes: "
                         "the same data, seed and thread count then give the same weights")
    ap.add_argument("--widths", default="32,48,64,80,64,48,32")
    ap.add_argument("--batch", type=int, default=12)
    ap.add_argument("--patch", type=int, default=64)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    torch.manual_seed(args.seed)
    torch.set_num_threads(args.threads)
    rng = np.random.default_rng(args.seed)
    files = sorted(glob.glob(os.path.join(args.data, "*.npz")))
    if len(files) < 4:
        raise SystemExit(f"{args.data}: {len(files)} examples; make_data.py writes them")
    n_val = max(1, len(files) // 10)
    train, val = load(files[:-n_val]), load(files[-n_val:])
    print(f"{len(train)} training and {len(val)} validation examples", flush=True)
    w = [int(v) for v in args.widths.split(",")]
    model = UNet(w[:4], w[4:])
    opt = torch.optim.Adam(model.parameters(), lr=args.lr)
    vrng = np.random.default_rng(12345)
    vx, vy = batch(val, vrng, 48, args.patch)
    start, step, seconds = time.time(), 0, 60.0 * args.minutes
    while True:
        elapsed = time.time() - start
        done = step / args.steps if args.steps else elapsed / seconds
        if done >= 1.0:
            break
        # Cosine decay over the steps or the time budget.
        for g in opt.param_groups:
            g["lr"] = args.lr * 0.5 * (1 + math.cos(math.pi * done))
        x, y = batch(train, rng, args.batch, args.patch)
        loss = loss_fn(model(x), y)
        opt.zero_grad()
        loss.backward()
        opt.step()
        step += 1
        if step % 200 == 0:
            with torch.no_grad():
                v = loss_fn(model(vx), vy).item()
                base = loss_fn(vx[:, :3], vy).item()
            print(f"step {step} {elapsed:.0f} s  train {loss.item():.4f}  val {v:.4f} (input {base:.4f})",
                  flush=True)
            os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
            write_kzw(model, args.output)
    write_kzw(model, args.output)
    print(f"{step} steps; weights in {args.output}")


if __name__ == "__main__":
    main()
