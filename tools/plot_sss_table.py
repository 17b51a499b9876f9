#!/usr/bin/env python3
"""Plots the fitted scale s per surface albedo from `kozu sss-reference --table --json FILE`.

Writes docs/images/sss_fit_searchlight.png, sss_fit_diffuse.png and sss_fit_dmfp.png (like Figs 7, 9 and 10 of
Christensen & Burley 2015): the optimal s of each albedo as points with the paper's formula as a curve (top), and the
mean relative error of both per albedo with the Monte Carlo noise floor (bottom).

    python3 tools/plot_sss_table.py docs/data/sss_table.json [--out docs/images]

Needs matplotlib (Debian: apt-get install python3-matplotlib). A docs tool, not part of the build.
"""
import argparse
import json
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

FORMULAS = {
    "searchlight": ("eq. (5): s = 1.85 − A + 7|A − 0.8|³", lambda a: 1.85 - a + 7 * abs(a - 0.8) ** 3),
    "diffuse": ("eq. (6): s = 1.9 − A + 3.5(A − 0.8)²", lambda a: 1.9 - a + 3.5 * (a - 0.8) ** 2),
    "dmfp": ("eq. (8): s = 3.5 + 100(A − 0.33)⁴", lambda a: 3.5 + 100 * (a - 0.33) ** 4),
}
TITLES = {
    "searchlight": "Searchlight, radii in units of the mfp ℓ (paper Fig. 7)",
    "diffuse": "Diffuse transmission, radii in units of ℓ (paper Fig. 9)",
    "dmfp": "Searchlight, radii in units of the dmfp ℓd (paper Fig. 10)",
}


def num(x):
    """Rows with too few bins for a fit hold null (NaN in kozu): plot them as gaps."""
    return float("nan") if x is None else x


def plot(name, column, settings, out_dir):
    rows = [{k: num(v) for k, v in r.items()} for r in column["per_albedo"]]
    A = [r["A"] for r in rows]
    label, formula = FORMULAS[name]
    fine = [i / 1000 for i in range(1, 1000)]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6.4, 6.8), sharex=True, gridspec_kw={"height_ratios": [3, 2]})
    top.plot(A, [r["s_opt"] for r in rows], "o", ms=3.5, color="tab:blue", label="optimal s (Monte Carlo fit)")
    top.plot(fine, [formula(a) for a in fine], "-", color="tab:red", label=label)
    top.set_ylabel("scale s")
    if name == "dmfp":
        top.set_yscale("log")
    top.set_title(TITLES[name], fontsize=10)
    top.grid(alpha=0.3)
    top.legend(fontsize=8)
    bottom.plot(A, [100 * r["error_opt"] for r in rows], "o", ms=3, color="tab:blue",
                label=f"optimal s: mean {100 * column['optimal_s_error']:.1f} % "
                      f"(paper {100 * column['paper']['optimal_s_error']:.1f} %)")
    bottom.plot(A, [100 * r["error_formula"] for r in rows], "s", ms=3, mfc="none", color="tab:red",
                label=f"formula: mean {100 * column['formula_error']:.1f} % "
                      f"(paper {100 * column['paper']['formula_error']:.1f} %)")
    bottom.plot(A, [100 * r["noise_floor"] for r in rows], "-", lw=1, color="gray", label="Monte Carlo noise floor")
    bottom.set_xlabel("surface albedo A")
    bottom.set_ylabel("mean relative error (%)")
    bottom.set_xlim(0, 1)
    bottom.set_ylim(bottom=0)
    bottom.grid(alpha=0.3)
    bottom.legend(fontsize=8)
    fig.text(0.01, 0.005,
             f"{settings['bins']} log bins, r in [{settings['r_min']:g}, {settings['r_max']:g}], "
             f"{settings['photons']} photons per albedo, bins with rel. s.e. ≤ {settings['max_relative_se']:g}",
             fontsize=7, color="gray")
    fig.tight_layout(rect=(0, 0.02, 1, 1))
    path = os.path.join(out_dir, f"sss_fit_{name}.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("table", help="JSON from kozu sss-reference --table --json")
    parser.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "docs", "images"))
    args = parser.parse_args()
    with open(args.table) as f:
        table = json.load(f)
    os.makedirs(args.out, exist_ok=True)
    for name in ("searchlight", "diffuse", "dmfp"):
        plot(name, table[name], table["settings"], args.out)


if __name__ == "__main__":
    main()
