#!/usr/bin/env python3
"""Plots and summarises the tables of `kozu sss-reference --table --json FILE [--rmax-scan ...]`.

Writes into --out (default docs/images):
  sss_fit_searchlight.png, sss_fit_diffuse.png, sss_fit_dmfp.png  (like Figs 7, 9 and 10 of Christensen & Burley
      2015): the optimal s per albedo over the table's range (filled) and over the --scan-rmax range of the scan
      (open), the memo's formula as a curve; for the dmfp also eq. (5) carried into units of l_d by eq. (7),
      l_d(A) * s5(A). Below: the mean relative error per albedo, both s, and the Monte Carlo noise floor.
  sss_dmfp_check.png: the dmfp the memo's own curves imply, s8(A) / s5(A), over l_d(A) from eq. (7) and from two
      other diffusion coefficients.
  sss_rmax_scan.png: the six mean errors against the outer radius of the fit (the rmax_scan of every table given),
      with the memo's figures and a band of +-1 point.
and prints the figures docs/subsurface.md quotes (means over all albedos, over A <= 0.94, the share of A >= 0.95).

    python3 tools/plot_sss_table.py docs/data/sss_table.json docs/data/sss_table_1.6M.json [--out docs/images]

The first table drives the per-parameterization plots; every table adds a line to the scan plot. Needs matplotlib
(Debian: apt-get install python3-matplotlib, then run it with /usr/bin/python3). A docs tool, not part of the build.
"""
import argparse
import json
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

NAMES = ("searchlight", "diffuse", "dmfp")
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


def label_of(table):
    s = table["settings"]
    p = s["photons"]
    return f"{p / 1e6:g} M photons" if p >= 1e6 else f"{p / 1e3:g} k photons"


def pick_scan(table, r_max):
    scans = table.get("rmax_scan", [])
    if not scans or r_max is None:
        return None
    return min(scans, key=lambda sc: abs(math.log(sc["r_max"] / r_max)))


def plot_fits(name, table, scan, out_dir):
    column = table[name]
    settings = table["settings"]
    rows = [{k: num(v) for k, v in r.items()} for r in column["per_albedo"]]
    A = [r["A"] for r in rows]
    label, formula = FORMULAS[name]
    fine = [i / 1000 for i in range(1, 1000)]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6.4, 7.0), sharex=True, gridspec_kw={"height_ratios": [3, 2]})
    top.plot(A, [r["s_opt"] for r in rows], "o", ms=3.5, color="tab:blue",
             label=f"optimal s, r ∈ [{settings['r_min']:g}, {settings['r_max']:g}]")
    if scan is not None:
        top.plot(A, [num(x) for x in scan[name]["s_opt"]], "o", ms=3.5, mfc="none", color="tab:green",
                 label=f"optimal s, r ∈ [{settings['r_min']:g}, {scan['r_max']:.3g}]")
    top.plot(fine, [formula(a) for a in fine], "-", color="tab:red", label=label)
    if name == "dmfp":
        s5 = FORMULAS["searchlight"][1]
        top.plot(A, [r["dmfp"] * s5(r["A"]) for r in rows], "--", color="tab:gray",
                 label="eq. (5) in units of ℓd: (ℓd/ℓ)·s₅(A), ℓd by eq. (7)")
        top.set_yscale("log")
    top.set_ylabel("scale s")
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
    bottom.set_ylim(0, 60 if name == "dmfp" else None)
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


def plot_dmfp_check(table, out_dir):
    """s8/s5 over l_d(A) for three diffusion coefficients (sigma_t = 1, alpha of the searchlight run)."""
    rows = table["dmfp"]["per_albedo"]
    s5, s8 = FORMULAS["searchlight"][1], FORMULAS["dmfp"][1]
    variants = [
        ("D = (σt + σa)/(3σt²), eq. (7) (kozu)", lambda sa: (1 + sa) / 3, "tab:blue"),
        ("D = 1/(3σt)", lambda sa: 1 / 3, "tab:orange"),
        ("D = 1/(3(σt + σa))", lambda sa: 1 / (3 * (1 + sa)), "tab:purple"),
    ]
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    A = [r["A"] for r in rows]
    for label, D, color in variants:
        ratio = []
        for r in rows:
            sa = 1 - r["alpha"]
            ld = 1 / math.sqrt(sa / D(sa))
            ratio.append(s8(r["A"]) / s5(r["A"]) / ld)
        ax.plot(A, ratio, "-", color=color, label=label)
    ax.axhspan(0.9, 1.1, color="gray", alpha=0.15, label="±10 % (how closely eqs. 5, 6 follow the optimal s)")
    ax.axhline(1.0, color="gray", lw=0.8)
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.6)
    ax.set_xlabel("surface albedo A (searchlight α from the H-function)")
    ax.set_ylabel("(s₈(A) / s₅(A)) / (ℓd/ℓ)")
    ax.set_title("The dmfp implied by the memo's curves, eq. (8) over eq. (5), against ℓd", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    path = os.path.join(out_dir, "sss_dmfp_check.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(path)


def plot_scan(tables, out_dir):
    fig, axes = plt.subplots(1, 3, figsize=(12, 4.0), sharey=True)
    colors = ["tab:blue", "tab:green", "tab:purple", "tab:brown"]
    for ax, name in zip(axes, NAMES):
        paper = tables[0][name]["paper"]
        for value, style, color, what in ((paper["optimal_s_error"], "-", "tab:red", "optimal s"),
                                          (paper["formula_error"], "--", "tab:orange", "formula")):
            ax.axhspan(100 * value - 1, 100 * value + 1, color=color, alpha=0.10)
            ax.axhline(100 * value, color=color, ls=style, lw=1.2, label=f"paper, {what} (±1 point)")
        for table, color in zip(tables, colors):
            points = [(sc["r_max"], sc[name]) for sc in table.get("rmax_scan", [])]
            points.append((table["settings"]["r_max"], table[name]))
            points.sort(key=lambda p: p[0])
            r = [p[0] for p in points]
            ax.plot(r, [100 * p[1]["optimal_s_error"] for p in points], "o-", ms=3, color=color,
                    label=f"{label_of(table)}: optimal s")
            ax.plot(r, [100 * p[1]["formula_error"] for p in points], "s--", ms=3, mfc="none", color=color,
                    label=f"{label_of(table)}: formula")
        ax.set_xscale("log")
        ax.set_xlabel(f"outer radius of the fit (units of {'ℓd' if name == 'dmfp' else 'ℓ'})")
        ax.set_title(f"{name}: paper {100 * paper['optimal_s_error']:.1f} % (optimal s) / "
                     f"{100 * paper['formula_error']:.1f} % (formula)", fontsize=9)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("mean relative error over A = 0.01 … 0.99 (%)")
    axes[2].legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    path = os.path.join(out_dir, "sss_rmax_scan.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(path)


def means(rows, key, keep):
    vals = [r[key] for r in rows if keep(r["A"]) and r[key] is not None]
    return sum(vals) / len(vals) if vals else float("nan")


def summary(table, path):
    print(f"\n{path}: {table['settings']['photons']} photons, {table['settings']['seconds']:.0f} s")
    print(f"{'r_max':>7s} {'':3s}" + "".join(f"{n:>32s}" for n in NAMES))
    entries = [(sc["r_max"], sc, True) for sc in table.get("rmax_scan", [])]
    entries.append((table["settings"]["r_max"], table, False))
    for r_max, entry, is_scan in sorted(entries, key=lambda e: e[0]):
        cells = []
        for name in NAMES:
            if is_scan:
                rows = [{"A": a, "error_opt": eo, "error_formula": ef}
                        for a, eo, ef in zip(table["settings"]["albedos"], entry[name]["error_opt"],
                                             entry[name]["error_formula"])]
            else:
                rows = entry[name]["per_albedo"]
            n = len([r for r in rows if r["error_opt"] is not None])
            top = [r for r in rows if r["A"] >= 0.945 and r["error_opt"] is not None]
            share_o = sum(r["error_opt"] for r in top) / n
            share_f = sum(r["error_formula"] for r in top) / n
            cells.append(f"{100 * entry[name]['optimal_s_error']:4.1f}/{100 * entry[name]['formula_error']:4.1f}"
                         f" [≤.94 {100 * means(rows, 'error_opt', lambda a: a < 0.945):3.1f}/"
                         f"{100 * means(rows, 'error_formula', lambda a: a < 0.945):3.1f};"
                         f" ≥.95 +{100 * share_o:3.1f}/+{100 * share_f:3.1f}]")
        print(f"{r_max:7.3f} {'' if is_scan else '(*)':3s}" + "".join(f"{c:>32s}" for c in cells))
    print("  cells: mean optimal/formula error (%) over all albedos [means over A ≤ 0.94; points added by A ≥ 0.95];"
          " (*) the table's own range")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tables", nargs="+", help="JSON from kozu sss-reference --table --json")
    parser.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "docs", "images"))
    parser.add_argument("--scan-rmax", type=float, default=2.37,
                        help="the scan range whose optimal s the fit plots add (nearest r_max of the first table)")
    args = parser.parse_args()
    tables = []
    for path in args.tables:
        with open(path) as f:
            tables.append(json.load(f))
    os.makedirs(args.out, exist_ok=True)
    scan = pick_scan(tables[0], args.scan_rmax)
    for name in NAMES:
        plot_fits(name, tables[0], scan, args.out)
    plot_dmfp_check(tables[0], args.out)
    plot_scan(tables, args.out)
    for table, path in zip(tables, args.tables):
        summary(table, path)


if __name__ == "__main__":
    main()
