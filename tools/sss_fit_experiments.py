#!/usr/bin/env python3
"""Experiments on the assumptions behind Christensen & Burley's fit-error table (Pixar Technical Memo
#15-04, 2015, § 3–5).

`kozu sss-reference --table` fixes one set-up: log-spaced bins over r in [0.01, 10] (units of the mfp l, or of the
dmfp l_d = 1/sigma_tr with eq. 7's D), exact annulus averages, the mean relative error, bins whose Monte Carlo
relative standard error is at most 5 %. The memo states only the criterion sum_i |R(r_i) - R_MC(r_i)| / R_MC(r_i).
This tool re-bins fine Monte Carlo profiles from `kozu sss-reference` and refits s under other assumptions, to see
which of them moves the six figures (docs/subsurface.md, "Why the dmfp figures differ").

    python3 tools/sss_fit_experiments.py generate /tmp/sss_fine --photons 400000       # 198 kozu runs, ~4 min
    python3 tools/sss_fit_experiments.py analyse /tmp/sss_fine                         # every experiment
    python3 tools/sss_fit_experiments.py analyse /tmp/sss_fine --only dmfp_unit_l --verbose
    python3 tools/sss_fit_experiments.py ranges /tmp/sss_fine                          # dmfp at A >= 0.95

`generate` runs `kozu sss-reference --surface-albedo A --illumination I` for A = 0.01 ... 0.99 and both
illuminations with 2700 log bins over [1e-4, 1e5] l (300 per decade), one JSON per run. `analyse` merges those fine
bins into each experiment's bins (edges snap to the nearest fine edge, under 0.4 % off), rebuilds sum w and sum w^2
from R and its standard error, selects bins, fits s per albedo (log scan then golden section, as
src/tools/profile_fit.cpp) and prints the mean errors of the optimal s and of eqs. 5, 6, 8 over the albedos.
It reimplements the C++ fit in plain Python (no numpy) so that every variant is one dictionary; the "baseline"
experiment reproduces `kozu sss-reference --table` to within the re-binning and the different seeds.
"""
import argparse
import json
import math
import os
import subprocess
import sys

FINE_MIN, FINE_MAX, FINE_BINS = 1e-4, 1e5, 2700
PAPER = {"searchlight": (4.9, 5.5), "diffuse": (2.6, 3.9), "dmfp": (6.4, 7.7)}

# name: (what it tests, settings). Keys: spacing log|lin, rmin, rmax, nbins (per parameterization with a suffix
# _searchlight/_diffuse/_dmfp), max_rel_se, eval annulus|mid|geo (exact annulus average, or R at the bin's middle or
# geometric-mean radius), crit rel|rel2|log, A_norm mc|target, dmfp_D grosjean|textbook|contini, dmfp_illum
# searchlight|diffuse, dmfp_unit_l (the dmfp fit over the searchlight's radii in l), amax.
EXPERIMENTS = {
    "baseline": ("kozu's rule: log bins [0.01, 10], 16/decade, rel. s.e. <= 5 %", {}),
    "dmfp_D_textbook": ("dmfp with D = 1/(3 sigma_t) instead of eq. 7", {"dmfp_D": "textbook"}),
    "dmfp_D_contini": ("dmfp with D = 1/(3 (sigma_t + sigma_a))", {"dmfp_D": "contini"}),
    "dmfp_illum_diffuse": ("dmfp profile from the diffuse-transmission runs", {"dmfp_illum": "diffuse"}),
    "dmfp_unit_l": ("dmfp fitted over the searchlight's radii (fixed in l)", {"dmfp_unit_l": True}),
    "eval_mid": ("model at the bin's middle radius, not the annulus average", {"eval": "mid"}),
    "eval_geo": ("model at the bin's geometric-mean radius", {"eval": "geo"}),
    "crit_rms": ("root-mean-square relative error", {"crit": "rel2"}),
    "crit_log": ("mean |log(R / R_MC)|", {"crit": "log"}),
    "A_target": ("model normalised to the target A, not the simulated A", {"A_norm": "target"}),
    "se_2pc": ("bins with rel. s.e. <= 2 %", {"max_rel_se": 0.02}),
    "se_10pc": ("bins with rel. s.e. <= 10 %", {"max_rel_se": 0.10}),
    "lin_0_5_dr0.1": ("linear bins of 0.1 over [0, 5]", {"spacing": "lin", "rmin": 0.0, "rmax": 5.0, "nbins": 50}),
    "lin_0_2_dr0.05": ("linear bins of 0.05 over [0, 2]", {"spacing": "lin", "rmin": 0.0, "rmax": 2.0, "nbins": 40}),
    "lin_0_1_dr0.01": ("linear bins of 0.01 over [0, 1]", {"spacing": "lin", "rmin": 0.0, "rmax": 1.0, "nbins": 100}),
    "log_0.01_1": ("log bins [0.01, 1]", {"rmax": 1.0, "nbins": 32}),
    "log_0.01_3.16": ("log bins [0.01, 3.16]", {"rmax": 10 ** 0.5, "nbins": 40}),
    "log_0.001_10": ("log bins [0.001, 10]", {"rmin": 0.001, "nbins": 64}),
    "log_0.1_10": ("log bins [0.1, 10]", {"rmin": 0.1, "nbins": 32}),
    "log_0.001_1": ("log bins [0.001, 1]", {"rmin": 0.001, "rmax": 1.0, "nbins": 48}),
    "dmfp_unit_l_2.37": ("dmfp over the searchlight's radii, log [0.01, 2.37] l",
                         {"dmfp_unit_l": True, "rmax": 2.3714, "nbins": 38}),
    "baseline_A<=0.94": ("baseline, mean over A <= 0.94 only", {"amax": 0.945}),
}


def formula(name, A):
    """Eqs. (5), (6), (8)."""
    if name == "searchlight":
        return 1.85 - A + 7 * abs(A - 0.8) ** 3
    if name == "diffuse":
        return 1.9 - A + 3.5 * (A - 0.8) ** 2
    return 3.5 + 100 * (A - 0.33) ** 4


def dmfp(alpha, D="grosjean"):
    """l_d / l for sigma_t = 1: sigma_tr = sqrt(sigma_a / D)."""
    sa = 1.0 - alpha
    if sa <= 0:
        return math.inf
    d = {"grosjean": (1 + sa) / 3, "textbook": 1 / 3, "contini": 1 / (3 * (1 + sa))}[D]  # eq. 7 is "grosjean"
    return 1 / math.sqrt(sa / d)


# ------------------------------------------------------------------------------------------------------------------
# generate


def generate(args):
    os.makedirs(args.out, exist_ok=True)
    for k in range(1, 100):
        A = k / 100
        for i, illum in enumerate(("searchlight", "diffuse")):
            path = os.path.join(args.out, f"{illum}_{A:.2f}.json")
            if os.path.exists(path):
                continue
            partial = path[:-5] + ".partial.json"  # kozu picks the format by the extension
            cmd = [args.kozu, "sss-reference", "--surface-albedo", f"{A:.2f}", "--illumination", illum,
                   "--photons", str(args.photons), "--seed", str(args.seed * 1000 + 2 * k + i),
                   "--rmin", str(FINE_MIN), "--rmax", str(FINE_MAX), "--bins", str(FINE_BINS), "-o", partial]
            subprocess.run(cmd, check=True, stderr=subprocess.DEVNULL)
            os.replace(partial, path)
        print(f"A = {A:.2f}", file=sys.stderr, flush=True)


# ------------------------------------------------------------------------------------------------------------------
# analyse


class Fine:
    """One run's fine histogram as cumulative sums of w and w^2 per photon, radii in units of l."""

    def __init__(self, path, A):
        with open(path) as f:
            j = json.load(f)
        n = j["photons"]
        self.n, self.A_target, self.A_mc, self.alpha = n, A, j["surface_albedo"], j["albedo"]
        below = j["below_r_min"] * n
        self.cw, self.cw2 = [below], [below]  # w <= 1, so sum w^2 <= sum w below r_min (1e-4 l: negligible)
        for b in j["profile"]:
            area = math.pi * (b["r_hi"] ** 2 - b["r_lo"] ** 2)
            w = b["R"] * n * area
            w2 = (b["R_se"] * area) ** 2 * n * (n - 1) + w * w / n
            self.cw.append(self.cw[-1] + w)
            self.cw2.append(self.cw2[-1] + w2)

    def index(self, r):
        t = math.log(r / FINE_MIN) / math.log(FINE_MAX / FINE_MIN) * FINE_BINS
        return max(0, min(FINE_BINS, int(round(t))))

    def edge(self, i):
        return FINE_MIN * (FINE_MAX / FINE_MIN) ** (i / FINE_BINS)

    def bins(self, edges, unit):
        """(r_lo, r_hi, R, R_se) for bins with the given edges in units of `unit` (an edge of 0 takes everything
        below)."""
        out = []
        for lo, hi in zip(edges, edges[1:]):
            ia = None if lo <= 0 else self.index(lo * unit)
            ib = self.index(hi * unit)
            w = self.cw[ib] - (0.0 if ia is None else self.cw[ia])
            w2 = self.cw2[ib] - (0.0 if ia is None else self.cw2[ia])
            r_lo = 0.0 if ia is None else self.edge(ia) / unit
            r_hi = self.edge(ib) / unit
            if r_hi <= r_lo:
                continue
            area = math.pi * (r_hi ** 2 - r_lo ** 2)
            R = w / (self.n * area)
            se = math.sqrt(max(w2 - w * w / self.n, 0.0) / (self.n * (self.n - 1))) / area
            out.append((r_lo, r_hi, R, se))
        return out


def annulus_fraction(d, lo, hi):
    """cdf(hi) - cdf(lo) of eq. 11 without cancellation."""
    delta = hi - lo
    return (-0.25 * math.exp(-lo / d) * math.expm1(-delta / d)
            - 0.75 * math.exp(-lo / (3 * d)) * math.expm1(-delta / (3 * d)))


def profile(A, d, r):
    """Eq. 3 with l = 1."""
    return A * (math.exp(-r / d) + math.exp(-r / (3 * d))) / (8 * math.pi * d * r)


def error(bins, A, s, ev, crit):
    d = 1 / s
    total = 0.0
    for lo, hi, R, _ in bins:
        if ev == "annulus":
            model = A * annulus_fraction(d, lo, hi) / (math.pi * (hi * hi - lo * lo))
        elif ev == "mid":
            model = profile(A, d, 0.5 * (lo + hi))
        else:
            model = profile(A, d, math.sqrt(lo * hi) if lo > 0 else 0.5 * hi)
        if crit == "rel":
            total += abs(model - R) / R
        elif crit == "rel2":
            total += ((model - R) / R) ** 2
        else:
            total += abs(math.log(model / R)) if model > 0 else 50.0
    mean = total / len(bins)
    return math.sqrt(mean) if crit == "rel2" else mean


def fit(bins, A, ev, crit):
    lo, hi, n = 0.05, 400.0, 300
    q = (hi / lo) ** (1 / n)
    best = min(range(n + 1), key=lambda i: error(bins, A, lo * q ** i, ev, crit))
    a, b = lo * q ** max(best - 1, 0), lo * q ** min(best + 1, n)
    g = (math.sqrt(5) - 1) / 2
    x1, x2 = b - g * (b - a), a + g * (b - a)
    f1, f2 = error(bins, A, x1, ev, crit), error(bins, A, x2, ev, crit)
    while b - a > 1e-6 * b:
        if f1 < f2:
            b, x2, f2 = x2, x1, f1
            x1 = b - g * (b - a)
            f1 = error(bins, A, x1, ev, crit)
        else:
            a, x1, f1 = x1, x2, f2
            x2 = a + g * (b - a)
            f2 = error(bins, A, x2, ev, crit)
    s = 0.5 * (a + b)
    return s, error(bins, A, s, ev, crit)


def rms_log(rows):
    if not rows:
        return float("nan")
    return math.sqrt(sum(math.log(r["s_opt"] / r["s_formula"]) ** 2 for r in rows) / len(rows))


def run_experiment(runs, cfg):
    out = {}
    for name in ("searchlight", "diffuse", "dmfp"):
        illum = cfg.get("dmfp_illum", "searchlight") if name == "dmfp" else name
        get = lambda key, default: cfg.get(f"{key}_{name}", cfg.get(key, default))  # noqa: E731
        rows = []
        for (run_illum, A), run in sorted(runs.items()):
            if run_illum != illum or A > cfg.get("amax", 1.0):
                continue
            unit = dmfp(run.alpha, cfg.get("dmfp_D", "grosjean")) if name == "dmfp" else 1.0
            rmin, rmax, n = get("rmin", 0.01), get("rmax", 10.0), get("nbins", 48)
            if name == "dmfp" and cfg.get("dmfp_unit_l"):
                rmin, rmax = rmin / unit, rmax / unit
            if get("spacing", "log") == "log":
                edges = [rmin * (rmax / rmin) ** (i / n) for i in range(n + 1)]
            else:
                edges = [rmin + (rmax - rmin) * i / n for i in range(n + 1)]
            bins = [b for b in run.bins(edges, unit) if b[2] > 0 and b[3] <= get("max_rel_se", 0.05) * b[2]]
            if len(bins) < 5:
                continue
            A_norm = run.A_mc if cfg.get("A_norm", "mc") == "mc" else run.A_target
            s, e = fit(bins, A_norm, cfg.get("eval", "annulus"), cfg.get("crit", "rel"))
            s_f = formula(name, A)
            e_f = error(bins, A_norm, s_f, cfg.get("eval", "annulus"), cfg.get("crit", "rel"))
            rows.append({"A": A, "s_opt": s, "error_opt": e, "s_formula": s_f, "error_formula": e_f,
                         "bins": len(bins), "unit": unit})
        out[name] = {
            "optimal_s_error": sum(r["error_opt"] for r in rows) / len(rows),
            "formula_error": sum(r["error_formula"] for r in rows) / len(rows),
            # RMS of log(s_opt / formula): how far the optimal s lies from the memo's curve, below and above A = 0.93.
            "s_rms_log": [rms_log([r for r in rows if r["A"] < 0.925]), rms_log([r for r in rows if r["A"] > 0.925])],
            "rows": rows}
    return out


def analyse(args):
    runs = {}
    for fname in sorted(os.listdir(args.data)):
        if fname.endswith(".json") and not fname.endswith(".partial.json"):
            illum, A = fname[:-5].split("_")
            runs[(illum, float(A))] = Fine(os.path.join(args.data, fname), float(A))
    names = args.only or list(EXPERIMENTS)
    print(f"{len(runs)} runs from {args.data}; mean relative error in %, optimal s / formula "
          f"(paper: searchlight 4.9/5.5, diffuse 2.6/3.9, dmfp 6.4/7.7);\n[a b]: RMS of log(s_opt / formula) over "
          f"A <= 0.92 and A >= 0.93")
    print(f"{'experiment':17s} {'searchlight':>22s} {'diffuse':>22s} {'dmfp':>22s}  what")
    results = {}
    for name in names:
        what, cfg = EXPERIMENTS[name]
        res = run_experiment(runs, cfg)
        results[name] = res
        cells = " ".join(f"{100 * res[k]['optimal_s_error']:5.1f}/{100 * res[k]['formula_error']:4.1f} "
                         f"[{res[k]['s_rms_log'][0]:4.2f} {res[k]['s_rms_log'][1]:4.2f}]"
                         for k in ("searchlight", "diffuse", "dmfp"))
        print(f"{name:17s} {cells}  {what}", flush=True)
        if args.verbose:
            for k in ("searchlight", "diffuse", "dmfp"):
                for r in res[k]["rows"]:
                    if round(100 * r["A"]) % 7 == 1 or r["A"] >= 0.95:
                        print(f"    {k:11s} A {r['A']:.2f}  s_opt {r['s_opt']:8.3f}  formula {r['s_formula']:7.3f}  "
                              f"error {100 * r['error_opt']:5.1f} / {100 * r['error_formula']:5.1f} %  "
                              f"{r['bins']} bins")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f)


def ranges(args):
    """The dmfp fit at high albedo over many log ranges [r_min, r_max] in units of l_d: optimal s, its error and the
    error of eq. 8's s."""
    print("dmfp, log bins (16 per decade, at least 8) over [r_min, r_max] l_d, rel. s.e. <= 5 %: "
          "s_opt  error(s_opt) %  error(eq. 8) %")
    for A in args.albedos:
        run = Fine(os.path.join(args.data, f"searchlight_{A:.2f}.json"), A)
        unit = dmfp(run.alpha)
        print(f"A = {A:.2f}: l_d = {unit:.1f} l, eq. 8 s = {formula('dmfp', A):.1f}")
        r_maxes = (0.1, 0.3, 1.0, 3.0, 10.0)
        print(f"{'r_min / r_max':>14s}" + "".join(f"{r:>21g}" for r in r_maxes))
        for r_min in (0.001, 0.01, 0.03, 0.1, 0.3):
            cells = []
            for r_max in r_maxes:
                n = max(8, round(16 * math.log10(r_max / r_min))) if r_max > 3 * r_min else 0
                edges = [r_min * (r_max / r_min) ** (i / n) for i in range(n + 1)] if n else []
                bins = [b for b in run.bins(edges, unit) if b[2] > 0 and b[3] <= 0.05 * b[2]] if n else []
                if len(bins) < 5:
                    cells.append(f"{'-':>21s}")
                    continue
                s, e = fit(bins, run.A_mc, "annulus", "rel")
                e8 = error(bins, run.A_mc, formula("dmfp", A), "annulus", "rel")
                cells.append(f"{s:7.1f} {100 * e:5.1f} {100 * e8:6.1f}")
            print(f"{r_min:>14g}" + "".join(cells))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    g = sub.add_parser("generate", help="run kozu sss-reference for every albedo and illumination")
    g.add_argument("out")
    g.add_argument("--photons", type=int, default=400000)
    g.add_argument("--seed", type=int, default=1)
    g.add_argument("--kozu", default=os.path.join(os.path.dirname(__file__), "..", "build", "kozu"))
    g.set_defaults(func=generate)
    a = sub.add_parser("analyse", help="refit under every experiment's assumptions")
    a.add_argument("data")
    a.add_argument("--only", nargs="*", choices=list(EXPERIMENTS))
    a.add_argument("--verbose", action="store_true")
    a.add_argument("--json", help="also write every experiment's per-albedo fits here")
    a.set_defaults(func=analyse)
    r = sub.add_parser("ranges", help="dmfp fits at high albedo over many radial ranges")
    r.add_argument("data")
    r.add_argument("--albedos", type=float, nargs="*", default=[0.95, 0.97, 0.99])
    r.set_defaults(func=ranges)
    args = parser.parse_args()
    args.func(args)


if __name__ == "__main__":
    main()
