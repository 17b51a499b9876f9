#!/usr/bin/env python3
"""Complex refractive indices (n, k) of metals at the kozu RGB wavelengths.

Reproduces the table in src/materials/metal_data.h.

kozu evaluates the exact conductor Fresnel equations per RGB channel with the
complex IOR eta + i k sampled at 650 nm (R), 550 nm (G) and 450 nm (B).

Data: the refractiveindex.info database (https://github.com/polyanskiy/
refractiveindex.info-database, public domain / CC0 1.0).  The rows below were
copied verbatim (wavelength in micrometres, then n, then k) from the YAML files
named with each dataset, at the commit given.  Only a contiguous excerpt of each
table covering 0.44-0.66 um is kept: it contains every row that brackets
0.450, 0.550 and 0.650 um.

Method: n and k are interpolated independently and linearly in wavelength
between the two tabulated rows that bracket the target wavelength (this is also
what refractiveindex.info does for tabulated data).  Results are rounded to
4 decimal places.

Sanity check: normal-incidence reflectance of the bare metal in air / vacuum,
    R = ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2).

Run:  python3 tools/metal_ior.py
      python3 tools/metal_ior.py --check src/materials/metal_data.h
        (also verifies that every generated C++ row appears verbatim in the
         header, and that the header has no other table rows; exit status 1
         on mismatch)
"""

from __future__ import annotations

import sys

REPO = "polyanskiy/refractiveindex.info-database"

# Target wavelengths (um), in kozu channel order R, G, B.
WAVELENGTHS = (0.650, 0.550, 0.450)
CHANNELS = ("R 650", "G 550", "B 450")
DECIMALS = 4

# --------------------------------------------------------------------------
# Datasets (citation as given in each file's REFERENCES block).
# --------------------------------------------------------------------------
JC1972 = ("P. B. Johnson and R. W. Christy, \"Optical constants of the noble "
          "metals\", Phys. Rev. B 6, 4370-4379 (1972), doi:10.1103/PhysRevB.6.4370")
JC1974 = ("P. B. Johnson and R. W. Christy, \"Optical constants of transition "
          "metals: Ti, V, Cr, Mn, Fe, Co, Ni, and Pd\", Phys. Rev. B 9, "
          "5056-5070 (1974), doi:10.1103/PhysRevB.9.5056")
RAKIC1995 = ("A. D. Rakic, \"Algorithm for the determination of intrinsic optical "
             "constants of metal films: application to aluminum\", Appl. Opt. 34, "
             "4755-4767 (1995), doi:10.1364/AO.34.004755")
RAKIC1998 = ("A. D. Rakic, A. B. Djurisic, J. M. Elazar and M. L. Majewski, "
             "\"Optical properties of metallic films for vertical-cavity "
             "optoelectronic devices\", Appl. Opt. 37, 5271-5283 (1998), "
             "doi:10.1364/AO.37.005271 (Brendel-Bormann model fit to experimental "
             "data from several sources, tabulated by refractiveindex.info)")
WEAVER1975 = ("J. H. Weaver, C. G. Olson and D. W. Lynch, \"Optical properties of "
              "crystalline tungsten\", Phys. Rev. B 12, 1293-1297 (1975), "
              "doi:10.1103/PhysRevB.12.1293 (data points extracted from a figure "
              "by refractiveindex.info)")
MATHEWSON1971 = ("A. G. Mathewson and H. P. Myers, \"Absolute values of the optical "
                 "constants of some pure metals\", Phys. Scr. 4, 291-292 (1971), "
                 "doi:10.1088/0031-8949/4/6/009 (298 K)")

# Cross-check-only datasets (not emitted to C++).
MCPEAK2015 = ("K. M. McPeak et al., \"Plasmonic films can easily be better: Rules "
              "and recipes\", ACS Photonics 2, 326-333 (2015), doi:10.1021/ph5004237")
TSELIN2024 = ("A. Tselin et al., \"Exploring the dielectric function of platinum\", "
              "Phys. Rev. B 110, 195130 (2024), doi:10.1103/PhysRevB.110.195130 "
              "(80 nm EB-PVD film, spectroscopic ellipsometry)")
WERNER2009 = ("W. S. M. Werner, K. Glantschnig and C. Ambrosch-Draxl, \"Optical "
              "constants and inelastic electron-scattering data for 17 elemental "
              "metals\", J. Phys. Chem. Ref. Data 38, 1013-1092 (2009), "
              "doi:10.1063/1.3243762 (experimental, from REELS spectra)")
GOLOVASHKIN1968 = ("A. I. Golovashkin and G. P. Motulevich, \"Optical properties of "
                   "lead in the visible and infrared spectral ranges\", Sov. Phys. "
                   "JETP 26, 881-887 (1968) (293 K)")

# --------------------------------------------------------------------------
# Metals emitted to the C++ table.
# (name, symbol, short source label, citation, file path, commit, rows)
# --------------------------------------------------------------------------
METALS = [
    ("gold", "Au", "Johnson & Christy 1972", JC1972,
     "database/data-nk/main/Au/Johnson.yml",
     "5f69b9115a04d5ae68b4dfc945ec92ed38a157fd", """
        0.4305 1.45 1.948
        0.4509 1.38 1.914
        0.4714 1.31 1.849
        0.4959 1.04 1.833
        0.5209 0.62 2.081
        0.5486 0.43 2.455
        0.5821 0.29 2.863
        0.6168 0.21 3.272
        0.6595 0.14 3.697
    """),
    ("silver", "Ag", "Johnson & Christy 1972", JC1972,
     "database/data-nk/main/Ag/Johnson.yml",
     "96dcbbe845b94a9135564ea923f1390150e6eca0", """
        0.4305 0.04 2.462
        0.4509 0.04 2.657
        0.4714 0.05 2.869
        0.4959 0.05 3.093
        0.5209 0.05 3.324
        0.5486 0.06 3.586
        0.5821 0.05 3.858
        0.6168 0.06 4.152
        0.6595 0.05 4.483
    """),
    ("copper", "Cu", "Johnson & Christy 1972", JC1972,
     "database/data-nk/main/Cu/Johnson.yml",
     "5f69b9115a04d5ae68b4dfc945ec92ed38a157fd", """
        0.4305 1.25 2.305
        0.4509 1.24 2.397
        0.4714 1.25 2.483
        0.4959 1.22 2.564
        0.5209 1.18 2.608
        0.5486 1.02 2.577
        0.5821 0.70 2.704
        0.6168 0.30 3.205
        0.6595 0.22 3.747
    """),
    ("aluminium", "Al", "Rakic 1995", RAKIC1995,
     "database/data-nk/main/Al/Rakic.yml",
     "96dcbbe845b94a9135564ea923f1390150e6eca0", """
        4.4280E-01 6.0790E-01 5.3676E+00
        4.7687E-01 7.2780E-01 5.7781E+00
        5.1660E-01 8.7340E-01 6.2418E+00
        5.6357E-01 1.0728E+00 6.7839E+00
        6.1993E-01 1.3660E+00 7.4052E+00
        6.5225E-01 1.5724E+00 7.7354E+00
    """),
    ("chromium", "Cr", "Johnson & Christy 1974", JC1974,
     "database/data-nk/main/Cr/Johnson.yml",
     "96dcbbe845b94a9135564ea923f1390150e6eca0", """
        0.431 2.19 3.04
        0.451 2.33 3.14
        0.471 2.51 3.24
        0.496 2.75 3.30
        0.521 2.94 3.33
        0.549 3.18 3.33
        0.582 3.22 3.30
        0.617 3.17 3.30
        0.659 3.09 3.34
    """),
    ("titanium", "Ti", "Johnson & Christy 1974", JC1974,
     "database/data-nk/main/Ti/Johnson.yml",
     "96dcbbe845b94a9135564ea923f1390150e6eca0", """
        0.431 2.21 3.01
        0.451 2.27 3.04
        0.471 2.32 3.10
        0.496 2.36 3.19
        0.521 2.44 3.30
        0.549 2.54 3.43
        0.582 2.60 3.58
        0.617 2.67 3.72
        0.659 2.76 3.84
    """),
    ("iron", "Fe", "Johnson & Christy 1974", JC1974,
     "database/data-nk/main/Fe/Johnson.yml",
     "5f69b9115a04d5ae68b4dfc945ec92ed38a157fd", """
        0.431 2.48 2.71
        0.451 2.59 2.77
        0.471 2.67 2.82
        0.496 2.74 2.88
        0.521 2.86 2.91
        0.549 2.95 2.93
        0.582 2.94 2.99
        0.617 2.88 3.05
        0.659 2.92 3.10
    """),
    ("nickel", "Ni", "Johnson & Christy 1974", JC1974,
     "database/data-nk/main/Ni/Johnson.yml",
     "5f69b9115a04d5ae68b4dfc945ec92ed38a157fd", """
        0.431 1.71 2.82
        0.451 1.73 2.95
        0.471 1.78 3.09
        0.496 1.82 3.25
        0.521 1.85 3.42
        0.549 1.92 3.61
        0.582 1.96 3.80
        0.617 1.99 4.02
        0.659 1.99 4.26
    """),
    ("platinum", "Pt", "Rakic et al. 1998 (BB model)", RAKIC1998,
     "database/data-nk/main/Pt/Rakic-BB.yml",
     "5f69b9115a04d5ae68b4dfc945ec92ed38a157fd", """
        4.3852e-01 1.8193e+00 3.0702e+00
        4.4722e-01 1.8390e+00 3.1204e+00
        4.5610e-01 1.8591e+00 3.1717e+00
        4.6515e-01 1.8796e+00 3.2240e+00
        4.7439e-01 1.9006e+00 3.2774e+00
        4.8381e-01 1.9222e+00 3.3320e+00
        4.9341e-01 1.9445e+00 3.3878e+00
        5.0321e-01 1.9676e+00 3.4447e+00
        5.1320e-01 1.9916e+00 3.5027e+00
        5.2339e-01 2.0166e+00 3.5618e+00
        5.3378e-01 2.0427e+00 3.6219e+00
        5.4437e-01 2.0699e+00 3.6830e+00
        5.5518e-01 2.0984e+00 3.7451e+00
        5.6620e-01 2.1281e+00 3.8079e+00
        5.7744e-01 2.1592e+00 3.8715e+00
        5.8891e-01 2.1917e+00 3.9358e+00
        6.0060e-01 2.2255e+00 4.0007e+00
        6.1252e-01 2.2607e+00 4.0661e+00
        6.2468e-01 2.2974e+00 4.1318e+00
        6.3709e-01 2.3354e+00 4.1979e+00
        6.4973e-01 2.3748e+00 4.2641e+00
        6.6263e-01 2.4155e+00 4.3305e+00
    """),
    ("tungsten", "W", "Weaver, Olson & Lynch 1975", WEAVER1975,
     "database/data-nk/main/W/Weaver.yml",
     "5f69b9115a04d5ae68b4dfc945ec92ed38a157fd", """
        4.426E-01 3.317E+00 2.489E+00
        4.487E-01 3.314E+00 2.511E+00
        4.650E-01 3.325E+00 2.574E+00
        4.694E-01 3.332E+00 2.591E+00
        4.921E-01 3.380E+00 2.664E+00
        4.937E-01 3.384E+00 2.668E+00
        5.111E-01 3.433E+00 2.700E+00
        5.298E-01 3.490E+00 2.716E+00
        5.327E-01 3.497E+00 2.719E+00
        5.489E-01 3.522E+00 2.739E+00
        5.705E-01 3.524E+00 2.787E+00
        5.739E-01 3.526E+00 2.794E+00
        5.997E-01 3.557E+00 2.860E+00
        6.024E-01 3.562E+00 2.866E+00
        6.260E-01 3.607E+00 2.906E+00
        6.268E-01 3.609E+00 2.907E+00
        6.460E-01 3.657E+00 2.925E+00
        6.524E-01 3.680E+00 2.937E+00
    """),
    ("lead", "Pb", "Mathewson & Myers 1971", MATHEWSON1971,
     "database/data-nk/main/Pb/Mathewson-298K.yml",
     "1e60d8e3d32f8bc202f1eb6bbcc53e1f841575f8", """
        0.44280 2.03525 4.17639
        0.45085 2.11192 4.19049
        0.45920 2.18315 4.19120
        0.46786 2.25385 4.19283
        0.47686 2.30983 4.19944
        0.48621 2.36141 4.19241
        0.49594 2.40388 4.18074
        0.50606 2.44112 4.17841
        0.51660 2.47301 4.18518
        0.52759 2.49592 4.18684
        0.53906 2.51876 4.18857
        0.55104 2.54683 4.18167
        0.56356 2.56955 4.18361
        0.57667 2.58356 4.18028
        0.59040 2.59756 4.17700
        0.60480 2.60618 4.18237
        0.61992 2.60294 4.16837
        0.63582 2.59430 4.16298
        0.65255 2.57157 4.16088
    """),
]

# --------------------------------------------------------------------------
# Alternative datasets, read only to cross-check the choices above (printed,
# never emitted to C++).  (label, citation, file path, commit, rows)
# --------------------------------------------------------------------------
CROSS_CHECKS = [
    ("Al  McPeak 2015", MCPEAK2015, "database/data-nk/main/Al/McPeak.yml",
     "96dcbbe845b94a9135564ea923f1390150e6eca0", """
        0.45 0.489220122 4.778319404
        0.55 0.789405353 5.851936501
        0.65 1.246364405 6.852329839
    """),
    ("Pt  Tselin 2024", TSELIN2024, "database/data-nk/main/Pt/Tselin.yml",
     "5f69b9115a04d5ae68b4dfc945ec92ed38a157fd", """
        0.448309 1.653 3.749
        0.449965 1.657 3.761
        0.451621 1.662 3.774
        0.549315 1.926 4.494
        0.550970 1.930 4.506
        0.648664 2.227 5.184
        0.650320 2.232 5.195
    """),
    ("Pt  Werner 2009 (REELS)", WERNER2009, "database/data-nk/main/Pt/Werner.yml",
     "96dcbbe845b94a9135564ea923f1390150e6eca0", """
        0.413281 0.8675 3.2129
        0.450852 0.6273 3.7605
        0.495937 0.5124 4.3965
        0.551041 0.4643 5.1210
        0.619921 0.4611 5.9757
        0.708481 0.5013 7.0273
    """),
    ("W   Rakic 1998 (BB)", RAKIC1998, "database/data-nk/main/W/Rakic-BB.yml",
     "96dcbbe845b94a9135564ea923f1390150e6eca0", """
        4.4722e-01 3.3086e+00 2.6004e+00
        4.5610e-01 3.3227e+00 2.6154e+00
        5.4437e-01 3.4949e+00 2.7528e+00
        5.5518e-01 3.5170e+00 2.7637e+00
        6.4973e-01 3.6517e+00 2.7955e+00
        6.6263e-01 3.6580e+00 2.7944e+00
    """),
    ("W   Werner 2009 (REELS)", WERNER2009, "database/data-nk/main/W/Werner.yml",
     "5f69b9115a04d5ae68b4dfc945ec92ed38a157fd", """
        0.413281 1.6556 5.1025
        0.450852 2.2457 5.1471
        0.495937 2.0777 4.7820
        0.551041 1.3296 5.2379
        0.619921 0.9330 6.3712
        0.708481 0.8969 7.8089
    """),
    ("Zn  Werner 2009 (REELS)", WERNER2009, "database/data-nk/main/Zn/Werner.yml",
     "5f69b9115a04d5ae68b4dfc945ec92ed38a157fd", """
        0.413281 0.6029 3.6376
        0.450852 0.6794 4.0209
        0.495937 0.7858 4.4636
        0.551041 0.9322 4.9850
        0.619921 1.1356 5.6116
        0.708481 1.4247 6.3811
    """),
    ("Pb  Golovashkin 1968 (293 K)", GOLOVASHKIN1968,
     "database/data-nk/main/Pb/Golovashkin-293K.yml",
     "1e60d8e3d32f8bc202f1eb6bbcc53e1f841575f8", """
        0.45 1.44 3.18
        0.46 1.54 3.20
        0.54 1.81 3.37
        0.55 1.83 3.40
        0.56 1.87 3.41
        0.64 1.94 3.49
        0.65 1.91 3.51
        0.66 1.89 3.51
    """),
]


def parse_rows(text: str) -> list[tuple[float, float, float, str]]:
    rows = []
    for line in text.strip().splitlines():
        fields = line.split()
        if len(fields) != 3:
            raise ValueError(f"bad row: {line!r}")
        wl, n, k = (float(f) for f in fields)
        rows.append((wl, n, k, line.strip()))
    for a, b in zip(rows, rows[1:]):
        if not a[0] < b[0]:
            raise ValueError(f"wavelengths not increasing: {a[3]!r} then {b[3]!r}")
    return rows


def interpolate(rows, wl):
    """Linear interpolation of n and k at wl; returns (n, k, lower_row, upper_row)."""
    for lo, hi in zip(rows, rows[1:]):
        if lo[0] <= wl <= hi[0]:
            t = (wl - lo[0]) / (hi[0] - lo[0])
            n = lo[1] + t * (hi[1] - lo[1])
            k = lo[2] + t * (hi[2] - lo[2])
            return n, k, lo, hi
    raise ValueError(f"{wl} um is outside the tabulated excerpt "
                     f"[{rows[0][0]}, {rows[-1][0]}]")


def reflectance(n: float, k: float) -> float:
    return ((n - 1.0) ** 2 + k * k) / ((n + 1.0) ** 2 + k * k)


def rounded(x: float) -> float:
    return round(x, DECIMALS)


def evaluate(rows_text):
    rows = parse_rows(rows_text)
    out = []
    for wl in WAVELENGTHS:
        n, k, lo, hi = interpolate(rows, wl)
        out.append((rounded(n), rounded(k), lo, hi))
    return out


def source_string(label: str, path: str) -> str:
    """The `source` string of a C++ row: dataset plus the file it was read from."""
    short = path.removeprefix("database/data-nk/")
    return f"{label} [refractiveindex.info {short}]"


def fmt_f(x: float) -> str:
    return f"{x:.{DECIMALS}f}f"


def main(argv: list[str]) -> int:
    print(f"Source: {REPO}")
    print("Linear interpolation in wavelength; n, k rounded to "
          f"{DECIMALS} decimals; R = normal-incidence reflectance.\n")

    results = []
    for name, symbol, label, citation, path, commit, rows_text in METALS:
        vals = evaluate(rows_text)
        results.append((name, symbol, source_string(label, path), vals))
        print(f"{symbol:2s} {name} -- {label}")
        print(f"   {citation}")
        print(f"   {path} @ {commit}")
        for ch, wl, (n, k, lo, hi) in zip(CHANNELS, WAVELENGTHS, vals):
            # R is computed from the rounded values, i.e. exactly what kozu uses.
            print(f"   {ch}: n = {n:.4f}  k = {k:.4f}  R = {reflectance(n, k):.3f}"
                  f"   [{lo[3]}] .. [{hi[3]}]")
        print()

    print("Summary (channels R 650 / G 550 / B 450 nm)")
    print(f"{'metal':12s} {'n (R, G, B)':>26s} {'k (R, G, B)':>26s} {'R0 (R, G, B)':>20s}")
    for name, symbol, label, vals in results:
        ns = " ".join(f"{v[0]:8.4f}" for v in vals)
        ks = " ".join(f"{v[1]:8.4f}" for v in vals)
        rs = " ".join(f"{reflectance(v[0], v[1]):6.3f}" for v in vals)
        print(f"{symbol + ' ' + name:12s} {ns} {ks} {rs}")
    print()

    print("Cross-checks against alternative datasets (not used in the table)")
    for label, citation, path, commit, rows_text in CROSS_CHECKS:
        vals = evaluate(rows_text)
        ns = " ".join(f"{v[0]:7.4f}" for v in vals)
        ks = " ".join(f"{v[1]:7.4f}" for v in vals)
        rs = " ".join(f"{reflectance(v[0], v[1]):6.3f}" for v in vals)
        print(f"  {label:30s} n {ns} | k {ks} | R0 {rs}")
        print(f"  {'':30s} {path} @ {commit[:12]}")
    print()

    print("C++ rows for src/materials/metal_data.h (eta and k at 650/550/450 nm):")
    cpp_rows = []
    for name, symbol, label, vals in results:
        eta = ", ".join(fmt_f(v[0]) for v in vals)
        k = ", ".join(fmt_f(v[1]) for v in vals)
        cpp_rows.append(f'{{"{name}", "{symbol}", Rgb{{{eta}}}, Rgb{{{k}}}, "{label}"}},')
    for row in cpp_rows:
        print("    " + row)

    if len(argv) >= 2 and argv[0] == "--check":
        with open(argv[1], encoding="utf-8") as f:
            header_rows = [ln.strip() for ln in f if ln.strip().startswith('{"')]
        if header_rows != cpp_rows:
            print(f"\nCHECK FAILED: the kMetals rows in {argv[1]} differ from the above")
            for row in cpp_rows:
                if row not in header_rows:
                    print("  missing: " + row)
            for row in header_rows:
                if row not in cpp_rows:
                    print("  unexpected: " + row)
            return 1
        print(f"\nCHECK OK: {argv[1]} matches ({len(cpp_rows)} rows)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
