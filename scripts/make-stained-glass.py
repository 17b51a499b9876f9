#!/usr/bin/env python3
"""Writes the stained-glass window texture of scenes/stained_glass.json (a textured polygon light, docs/lights.md).

    python3 scripts/make-stained-glass.py /tmp/glass.ppm && oiiotool /tmp/glass.ppm -o scenes/textures/stained_glass.png

A pointed-arch window of Voronoi panes in five glass colours, joined by dark lead lines, with a rose ring near the
top; everything outside the arch is black (it emits nothing). Deterministic: the same bytes every run.
"""
import math
import sys

W, H = 160, 320
PALETTE = [  # sRGB-encoded glass colours
    (30, 70, 200), (190, 25, 40), (235, 170, 40), (30, 150, 80), (120, 50, 170), (60, 140, 220), (220, 120, 30),
]
LEAD = (8, 8, 10)


def lcg(state):
    state = (state * 6364136223846793005 + 1442695040888963407) % (1 << 64)
    return state, (state >> 33) / float(1 << 31)


def main(path):
    state = 12345
    seeds = []
    for _ in range(46):
        state, x = lcg(state)
        state, y = lcg(state)
        state, c = lcg(state)
        seeds.append((x * W, y * H, PALETTE[int(c * len(PALETTE)) % len(PALETTE)]))
    cx, ring_y, ring_r = W / 2.0, H * 0.27, W * 0.3
    rows = []
    for j in range(H):
        row = bytearray()
        for i in range(W):
            x, y = i + 0.5, j + 0.5
            # The pointed arch: two circles of radius W through the opposite jambs, above y = W * 0.85.
            inside = 6 <= x <= W - 6 and y <= H - 6
            if inside and y < W * 0.87:
                dy = W * 0.87 - y
                inside = math.hypot(x - 6, dy) <= W - 12 and math.hypot(W - 6 - x, dy) <= W - 12
            if not inside:
                row += bytes((0, 0, 0))
                continue
            # The rose ring: lead circles, with its own panes between them.
            rd = math.hypot(x - cx, y - ring_y)
            if abs(rd - ring_r) < 1.6 or abs(rd - ring_r * 0.45) < 1.4:
                row += bytes(LEAD)
                continue
            if rd < ring_r:
                sector = int((math.atan2(y - ring_y, x - cx) + math.pi) / (2 * math.pi) * 12) % 12
                if rd > ring_r * 0.45 and abs(((math.atan2(y - ring_y, x - cx) + math.pi) / (2 * math.pi) * 12) % 1.0 - 0.5) > 0.45:
                    row += bytes(LEAD)
                    continue
                colour = PALETTE[(sector * 3 + (rd < ring_r * 0.45)) % len(PALETTE)]
                row += bytes(colour)
                continue
            d = sorted((math.hypot(x - sx, y - sy), c) for sx, sy, c in seeds)
            if d[1][0] - d[0][0] < 1.8:
                row += bytes(LEAD)
            else:
                # A little streaking inside each pane, as in blown glass.
                shade = 0.85 + 0.15 * math.sin(0.11 * x + 0.07 * y + d[0][0] * 0.2)
                row += bytes(min(255, int(v * shade)) for v in d[0][1])
        rows.append(bytes(row))
    with open(path, "wb") as f:
        f.write(b"P6\n%d %d\n255\n" % (W, H))
        for r in rows:
            f.write(r)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "stained_glass.ppm")
