#!/usr/bin/env python3
"""The rational fits of D. Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in
Real-Time Rendering in Games, §3 and §2.4, redone with `kozu fit-rational` and compared with the paper's printed
coefficients on the same tables (docs/wwii.md, "Rational fitting (§3)").

Tables (written into OUT_DIR, default out/wwii-fits):
  gloss_length.csv  x = gloss g = i/255, value = the macrosurface shortened-normal length of GGX, eq. (26), with
                    alpha from eq. (2) and a from eq. (27) (a series near a = 0, where eq. (26) cancels)
  detail_gloss.csv  x, y = two glosses i/31, j/31 (the paper's 32 x 32 LUT), value = the gloss whose length is the
                    product of theirs (eq. 34), 0 where that product is below the length at gloss 0 (as eq. 37 clamps)
Fits: eq. (40) (degrees 3/2), eq. (42) (3/2 with f(0) = 0.66667 and f(1) = 0.999958, eq. 41), eqs. (35)-(37)
(symmetric degrees 2/2, fitted and measured as clamp(P/Q, 0, 1)), each by least squares (the paper's FindFit) and
minimax (--minimax).

Usage: python3 scripts/wwii-rational-fits.py [KOZU] [OUT_DIR]
"""
import json
import math
import os
import subprocess
import sys

KOZU = sys.argv[1] if len(sys.argv) > 1 else "build/kozu"
OUT = sys.argv[2] if len(sys.argv) > 2 else "out/wwii-fits"


def gloss_to_length(g):
    alpha2 = 2.0 / (1.0 + 2.0 ** (18.0 * g))  # Chan 2018 eq. (2), squared
    a = math.sqrt(max(1.0 - alpha2, 0.0))  # eq. (27)
    if a < 0.2:  # eq. (26) as the series 2 sum_k a^(2k-2) / ((2k-1)(2k+1)): the closed form cancels near a = 0
        return sum(2.0 * a ** (2 * k - 2) / ((2 * k - 1) * (2 * k + 1)) for k in range(1, 30))
    return (a - (1.0 - a * a) * math.atanh(a)) / a ** 3  # eq. (26)


def length_to_gloss(length):
    if length <= gloss_to_length(0.0):
        return 0.0
    lo, hi = 0.0, 1.0
    if length >= gloss_to_length(1.0):
        return 1.0
    for _ in range(200):  # bisection: the length rises with gloss
        mid = 0.5 * (lo + hi)
        if gloss_to_length(mid) < length:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def poly1(c, x):
    return sum(ci * x ** i for i, ci in enumerate(c))


def sym2(c, a, b):  # eqs. (35)-(36): 1, a + b, a^2 + b^2, ab
    return c[0] + c[1] * (a + b) + c[2] * (a * a + b * b) + c[3] * a * b


def errors(values):
    e = [abs(v) for v in values]
    return max(e), sum(e) / len(e), math.sqrt(sum(x * x for x in e) / len(e))


def fit(csv, args, name):
    out = os.path.join(OUT, name)
    cmd = [KOZU, "fit-rational", csv] + args + ["--json", out]
    subprocess.run(cmd, check=True)
    with open(out) as f:
        return json.load(f), " ".join(["kozu", "fit-rational", os.path.basename(csv)] + args + ["--json", name])


def main():
    os.makedirs(OUT, exist_ok=True)
    gl = [(i / 255.0, gloss_to_length(i / 255.0)) for i in range(256)]
    gl_csv = os.path.join(OUT, "gloss_length.csv")
    with open(gl_csv, "w") as f:
        f.write("x,value\n" + "".join("%.17g,%.17g\n" % r for r in gl))
    dg = [(i / 31.0, j / 31.0, length_to_gloss(gloss_to_length(i / 31.0) * gloss_to_length(j / 31.0)))
          for i in range(32) for j in range(32)]
    dg_csv = os.path.join(OUT, "detail_gloss.csv")
    with open(dg_csv, "w") as f:
        f.write("x,y,value\n" + "".join("%.17g,%.17g,%.17g\n" % r for r in dg))

    rows = []
    clamp = lambda t: min(max(t, 0.0), 1.0)
    cases = [
        ("eq. (40), 3/2, unconstrained", gl_csv, ["--num", "3", "--den", "2"], "eq40",
         ([0.66693, 0.0609009, 7.32398, 0.600464], [1.0, -1.13467, 8.78264])),
        ("eq. (42), 3/2, f(0) = 0.66667, f(1) = 0.999958", gl_csv,
         ["--num", "3", "--den", "2", "--constraint", "0=0.66667", "--constraint", "1=0.999958"], "eq42",
         ([0.6667, 0.0942205, 7.41935, 0.56711], [1.0, -1.0881, 8.83582])),
        ("eq. (37), symmetric 2/2, clamp(P/Q, 0, 1)", dg_csv,
         ["--num", "2", "--den", "2", "--2d-symmetric", "--clamp", "0,1"], "eq37",
         ([-0.535580, 1.002204, -0.223910, 13.323150], [1.0, 8.259559, 9.896132, -22.015902])),
    ]
    for name, csv, args, stem, paper in cases:
        if csv == gl_csv:
            table = [(x, 0.0, v) for x, v in gl]
            f = lambda c, x, y: poly1(c[0], x) / poly1(c[1], x)
        else:
            table = dg
            f = lambda c, x, y: clamp(sym2(c[0], x, y) / sym2(c[1], x, y))
        line = [name, errors([f(paper, x, y) - v for x, y, v in table])]
        for extra, suffix in (([], ""), (["--minimax"], "-minimax")):
            j, cmd = fit(csv, args + extra, stem + suffix + ".json")
            line.append(errors([f((j["numerator"], j["denominator"]), x, y) - v for x, y, v in table]))
            line.append((cmd, j))
        rows.append(line)

    print("Errors over the table (max, mean, RMS of |fit - value|):\n")
    print("| fit | paper's coefficients | kozu fit-rational (least squares) | kozu fit-rational --minimax |")
    print("|---|---|---|---|")
    for name, paper, ls, _, mm, _ in rows:
        print("| %s | %s |" % (name, " | ".join("%.3g, %.3g, %.3g" % e for e in (paper, ls, mm))))
    print()
    for name, _, _, (cmd, j), _, (cmd2, j2) in rows:
        for c, jj in ((cmd, j), (cmd2, j2)):
            print("`%s`:\n  numerator %s; denominator %s" % (
                c, ", ".join("%.6g" % x for x in jj["numerator"]), ", ".join("%.6g" % x for x in jj["denominator"])))


if __name__ == "__main__":
    main()
