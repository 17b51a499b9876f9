# Self-tests of tests/python/chi2.py, kozu's Python chi-square harness: it must pass exact samplers, fail
# wrong densities (a wrong shape, a wrong normalisation, mass where nothing is sampled), reject invalid
# output, and compute p-values that agree with closed forms, published tables and Monte Carlo.
# Run: /usr/bin/python3 -m unittest discover -s tests/python -p 'test_chi2_harness.py'
# Needs numpy only; every random draw has a fixed seed, so each run gives the same verdicts.
"""Unit tests of the chi-square harness (tests/python/chi2.py) and its p-value function."""

import math
import os
import sys
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from chi2 import (  # noqa: E402  (the harness lives beside this file)
    ChiSquareTest,
    chi2_sf,
    gamma_q,
    integrate_pdf_over_sphere,
    pearson_statistic,
    sidak_threshold,
    spherical_direction,
)


# ---- reference samplers and densities, in numpy --------------------------------------------------------

def cosine_hemisphere_sample(u):
    """Malley's method: a uniform point of the unit disk lifted to the hemisphere; pdf cos(theta) / pi."""
    r2 = u[:, 0]
    phi = 2.0 * math.pi * u[:, 1]
    w = spherical_direction(np.sqrt(np.maximum(0.0, 1.0 - r2)), phi)
    return w, np.ones(len(u))


def cosine_hemisphere_pdf(w):
    return np.maximum(w[:, 2], 0.0) / math.pi


def uniform_hemisphere_pdf(w):
    return np.where(w[:, 2] > 0.0, 1.0 / (2.0 * math.pi), 0.0)


def cosine_power_pdf(w, n=1.2):
    """The normalised cos^n lobe, (n + 1) / (2 pi) cos^n: a plausible but wrong pdf for a cosine sampler."""
    return (n + 1.0) / (2.0 * math.pi) * np.maximum(w[:, 2], 0.0) ** n


def hg_pdf(w, g):
    """Henyey-Greenstein about +z: (1 - g^2) / (4 pi (1 + g^2 - 2 g cos)^(3/2)), mean cosine g."""
    denom = 1.0 + g * g - 2.0 * g * w[:, 2]
    return (1.0 - g * g) / (4.0 * math.pi * denom * np.sqrt(denom))


def hg_sample(u, g):
    """Inverts the Henyey-Greenstein cdf in cos(theta) (pbrt-v3 section 15.2.3); exact."""
    s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u[:, 0])
    cos_t = np.clip((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0)
    return spherical_direction(cos_t, 2.0 * math.pi * u[:, 1]), np.ones(len(u))


def even_dof_sf(x, dof):
    """The chi-square survival function for even dof in closed form: a Poisson sum.

    P(X >= x) = e^(-x/2) sum_{j < dof/2} (x/2)^j / j!  (Abramowitz & Stegun, section 26.4, the relation
    between the chi-square and Poisson distributions). Summed in log space to stay finite for large x.
    """
    half = 0.5 * x
    return sum(math.exp(-half + j * math.log(half) - math.lgamma(j + 1.0)) for j in range(dof // 2))


class PValueTest(unittest.TestCase):
    """chi2_sf (our regularized upper incomplete gamma) against closed forms, tables and Monte Carlo."""

    def test_one_dof_is_a_complementary_error_function(self):
        # With 1 degree of freedom X = Z^2, so P(X >= x) = P(|Z| >= sqrt x) = erfc(sqrt(x / 2)).
        for x in (1e-6, 0.01, 0.5, 1.0, 2.0, 3.841458820694124, 10.0, 30.0, 100.0):
            with self.subTest(x=x):
                self.assertAlmostEqual(chi2_sf(x, 1) / math.erfc(math.sqrt(0.5 * x)), 1.0, delta=1e-10)

    def test_the_95_percent_point_of_one_dof(self):
        # 3.841459 = 1.959964^2, the two-sided 5 % point of the normal distribution.
        self.assertAlmostEqual(chi2_sf(3.841458820694124, 1), 0.05, delta=1e-12)

    def test_even_dof_match_the_poisson_sum(self):
        # Covers both branches: x < a + 1 (series) and x >= a + 1 (continued fraction), a = dof / 2.
        for dof in (2, 4, 10, 80, 200, 1600):
            for x in (0.1, 0.5 * dof, dof - 2.0, dof + 2.5, 1.5 * dof, 3.0 * dof + 40.0):
                if x <= 0.0:
                    continue
                with self.subTest(dof=dof, x=x):
                    exact = even_dof_sf(x, dof)
                    self.assertLess(abs(chi2_sf(x, dof) - exact), 1e-12 + 1e-9 * exact)

    def test_x_100_with_80_dof(self):
        # e^-50 sum_{j<40} 50^j / j! = 0.064570 (the Poisson sum, 5 digits), between the tables' 10 % point
        # (96.578) and 5 % point (101.879) for 80 dof, as it must be.
        self.assertAlmostEqual(chi2_sf(100.0, 80), even_dof_sf(100.0, 80), delta=1e-13)
        self.assertAlmostEqual(chi2_sf(100.0, 80), 0.064570, delta=5e-7)
        self.assertTrue(chi2_sf(101.879, 80) < chi2_sf(100.0, 80) < chi2_sf(96.578, 80))

    def test_published_critical_values(self):
        # Upper-tail critical values, 3 decimals, from the NIST/SEMATECH e-Handbook of Statistical Methods,
        # section 1.3.6.7.4 "Critical Values of the Chi-Square Distribution". The tolerance is what rounding
        # the critical value to 0.0005 moves the tail probability by (density there x 0.0005), doubled.
        table = [  # (dof, upper-tail probability, critical value)
            (1, 0.05, 3.841), (1, 0.01, 6.635), (5, 0.05, 11.070), (10, 0.05, 18.307), (10, 0.01, 23.209),
            (20, 0.10, 28.412), (30, 0.05, 43.773), (80, 0.10, 96.578), (80, 0.05, 101.879),
            (80, 0.01, 112.329), (100, 0.05, 124.342), (100, 0.01, 135.807),
        ]
        for dof, alpha, critical in table:
            with self.subTest(dof=dof, alpha=alpha):
                h = 1e-3
                density = (chi2_sf(critical - h, dof) - chi2_sf(critical + h, dof)) / (2.0 * h)
                self.assertAlmostEqual(chi2_sf(critical, dof), alpha, delta=2.0 * 0.0005 * density + 1e-9)

    def test_odd_dof_against_a_monte_carlo_of_squared_normals(self):
        # Chi-square variates built from their definition (sums of squared standard normals), independent of
        # any gamma-function code; the fraction at or beyond x is binomial, so it must lie within 4.5 standard
        # errors of chi2_sf (a false failure once in ~150,000 runs; the seed is fixed anyway).
        rng = np.random.default_rng(20261128)
        n = 200_000
        for dof in (1, 3, 7):
            variates = (rng.standard_normal((n, dof)) ** 2).sum(axis=1)
            for x in (0.3 * dof, float(dof), 2.0 * dof + 3.0):
                with self.subTest(dof=dof, x=x):
                    p = chi2_sf(x, dof)
                    fraction = float(np.mean(variates >= x))
                    self.assertLess(abs(fraction - p), 4.5 * math.sqrt(p * (1.0 - p) / n))

    def test_large_dof_against_numpy_chi_square_variates(self):
        # numpy's own chi-square generator (a gamma sampler) at the dof of a typical 40 x 80 test.
        rng = np.random.default_rng(7)
        n = 200_000
        for dof in (51, 1599):
            variates = rng.chisquare(dof, n)
            for z in (-2.0, 0.0, 1.0, 2.5):
                x = dof + z * math.sqrt(2.0 * dof)
                with self.subTest(dof=dof, x=x):
                    p = chi2_sf(x, dof)
                    fraction = float(np.mean(variates >= x))
                    self.assertLess(abs(fraction - p), 4.5 * math.sqrt(p * (1.0 - p) / n))

    def test_branches_join_continuously(self):
        # The series and the continued fraction meet at x = a + 1: both sides must agree there.
        for a in (0.5, 3.0, 40.0, 799.5):
            below, above = gamma_q(a, a + 1.0 - 1e-9), gamma_q(a, a + 1.0)
            with self.subTest(a=a):
                self.assertAlmostEqual(below, above, delta=1e-9)

    def test_limits_and_tiny_tails(self):
        self.assertEqual(chi2_sf(0.0, 5), 1.0)
        self.assertEqual(chi2_sf(math.inf, 5), 0.0)
        self.assertTrue(math.isnan(chi2_sf(math.nan, 5)))
        # A hopeless fit must give a p-value that is tiny but not rounded to a wrong nonzero value.
        self.assertLess(chi2_sf(5000.0, 1599), 1e-200)
        self.assertAlmostEqual(math.log(chi2_sf(400.0, 2)), -200.0, delta=1e-9)
        with self.assertRaises(ValueError):
            chi2_sf(1.0, 0)

    def test_sidak_threshold(self):
        self.assertAlmostEqual(sidak_threshold(0.01, 1), 0.01, delta=1e-15)
        # 1 - 0.99^(1/10) = 0.0010045...: ten tests together keep a 1 % family-wise rate.
        self.assertAlmostEqual(sidak_threshold(0.01, 10), 1.0 - 0.99 ** 0.1, delta=1e-15)
        self.assertAlmostEqual(1.0 - (1.0 - sidak_threshold(0.05, 37)) ** 37, 0.05, delta=1e-14)


class PoolingTest(unittest.TestCase):
    """pearson_statistic's pooling, on counts worked out by hand with the C++ harness's rule."""

    def test_small_cells_pool_into_one(self):
        # Expected 1, 2, 3 (< 5) pool into one cell expecting 6 (observed 6): contributes 0; then
        # (12 - 10)^2 / 10 + (18 - 20)^2 / 20 = 0.4 + 0.2.
        statistic, cells, pooled = pearson_statistic([0, 3, 3, 12, 18], [1, 2, 3, 10, 20])
        self.assertAlmostEqual(statistic, 0.6, delta=1e-12)
        self.assertEqual(cells, 3)
        self.assertEqual(pooled.tolist(), [True, True, True, False, False])

    def test_a_pool_short_of_the_mark_takes_the_next_cell(self):
        # The cell expecting 4 alone is too small, so the next (6) joins it although 6 >= 5: pool 10,
        # observed 7: (7 - 10)^2 / 10 = 0.9; then (33 - 30)^2 / 30 = 0.3.
        statistic, cells, pooled = pearson_statistic([2, 5, 33], [4, 6, 30])
        self.assertAlmostEqual(statistic, 1.2, delta=1e-12)
        self.assertEqual(cells, 2)
        self.assertEqual(pooled.tolist(), [True, True, False])

    def test_cells_expecting_nothing_add_no_cell(self):
        statistic, cells, _ = pearson_statistic([0, 0, 12, 8], [0, 0, 10, 10])
        self.assertAlmostEqual(statistic, 0.8, delta=1e-12)
        self.assertEqual(cells, 2)


class HarnessTest(unittest.TestCase):
    """The harness on numpy samplers whose true densities are known."""

    def test_cosine_sampler_with_its_pdf_passes(self):
        test = ChiSquareTest(cosine_hemisphere_sample, cosine_hemisphere_pdf, seed=1)
        self.assertTrue(test.run(), test.message)
        self.assertAlmostEqual(test.pdf_integral, 1.0, delta=1e-9)  # the midpoint rule is exact for cos
        self.assertEqual(test.lost_samples, 0)
        self.assertEqual(test.observed.shape, (40, 80))  # 2:1 in phi / theta, the C++ harness's layout
        self.assertEqual(test.observed.sum(), 1_000_000)

    def test_henyey_greenstein_on_the_whole_sphere_passes(self):
        for g in (-0.5, 0.7):
            with self.subTest(g=g):
                test = ChiSquareTest(lambda u: hg_sample(u, g), lambda w: hg_pdf(w, g), seed=3, ires=16)
                self.assertTrue(test.run(), test.message)

    def test_uniform_hemisphere_pdf_fails(self):
        test = ChiSquareTest(cosine_hemisphere_sample, uniform_hemisphere_pdf, seed=1)
        self.assertFalse(test.run())
        self.assertLess(test.p_value, 1e-100)
        self.assertIn("worst cells", test.message)

    def test_cosine_power_1_2_pdf_fails(self):
        # Normalised and on the same support: only the shape is wrong, by a power of cos^0.2.
        test = ChiSquareTest(cosine_hemisphere_sample, cosine_power_pdf, seed=1)
        self.assertFalse(test.run())
        self.assertLess(test.p_value, 1e-10)

    def test_misnormalised_pdf_fails_through_the_lost_mass_cell(self):
        # 2 % too little density: the cells alone can hardly see it, the lost-mass cell expects 20,000 rejected
        # samples and sees none.
        test = ChiSquareTest(cosine_hemisphere_sample, lambda w: 0.98 * cosine_hemisphere_pdf(w), seed=1)
        self.assertFalse(test.run())
        self.assertAlmostEqual(test.pdf_integral, 0.98, delta=1e-9)
        self.assertIn("integrates to 0.980000", test.message)
        self.assertIn("rejected samples", test.message)

    def test_rejected_samples_are_lost_energy(self):
        # A sampler that fails (weight 0) for u1 >= 0.75, i.e. never returns phi in [270, 360) degrees (a cell
        # edge): with a pdf that is 0 there it is exact, whatever the direction it returned when failing.
        def sample(u):
            w, weight = cosine_hemisphere_sample(u)
            fails = u[:, 1] >= 0.75
            w[fails] = np.nan  # a failed sample's direction is never read
            return w, np.where(fails, 0.0, weight)

        def pdf(w):
            phi = np.mod(np.arctan2(w[:, 1], w[:, 0]), 2.0 * math.pi)
            return np.where(phi < 1.5 * math.pi, cosine_hemisphere_pdf(w), 0.0)

        test = ChiSquareTest(sample, pdf, seed=5)
        self.assertTrue(test.run(), test.message)
        self.assertAlmostEqual(test.lost_samples / 1e6, 0.25, delta=0.005)
        self.assertAlmostEqual(test.pdf_integral, 0.75, delta=1e-9)
        # Claiming density where the sampler never lands is a wrong pdf.
        claims_all = ChiSquareTest(sample, cosine_hemisphere_pdf, seed=5)
        self.assertFalse(claims_all.run())

    def test_samples_where_the_pdf_is_zero_fail(self):
        def sample(u):  # the cosine lobe mirrored below the horizon
            w, weight = cosine_hemisphere_sample(u)
            w[:, 2] = -w[:, 2]
            return w, weight

        test = ChiSquareTest(sample, cosine_hemisphere_pdf, seed=1)
        self.assertFalse(test.run())
        self.assertIn("region with pdf 0", test.message)

    def test_invalid_output_fails_outright(self):
        def long_directions(u):
            w, weight = cosine_hemisphere_sample(u)
            return 1.01 * w, weight

        test = ChiSquareTest(long_directions, cosine_hemisphere_pdf, sample_count=1000)
        self.assertFalse(test.run())
        self.assertIn("not unit length", test.message)

        test = ChiSquareTest(cosine_hemisphere_sample, lambda w: np.full(len(w), np.nan), sample_count=1000)
        self.assertFalse(test.run())
        self.assertIn("pdf returned nan", test.message)

        def negative_weight(u):
            w, weight = cosine_hemisphere_sample(u)
            return w, -weight

        test = ChiSquareTest(negative_weight, cosine_hemisphere_pdf, sample_count=1000)
        self.assertFalse(test.run())
        self.assertIn("invalid weight", test.message)

    def test_too_few_samples_have_no_power(self):
        test = ChiSquareTest(cosine_hemisphere_sample, cosine_hemisphere_pdf, sample_count=4)
        self.assertFalse(test.run())
        self.assertIn("no power", test.message)

    def test_narrow_band_with_outside_cell(self):
        # Uniform sphere binned over cos(theta) in [0.5, 1] only: the rest (75 %) is one cell.
        def uniform_sphere(u):
            return spherical_direction(1.0 - 2.0 * u[:, 0], 2.0 * math.pi * u[:, 1]), np.ones(len(u))

        uniform = lambda w: np.full(len(w), 1.0 / (4.0 * math.pi))  # noqa: E731
        test = ChiSquareTest(uniform_sphere, uniform, seed=2, cos_theta_min=0.5, sample_count=200_000)
        self.assertTrue(test.run(), test.message)
        self.assertAlmostEqual(test.outside_samples / 200_000, 0.75, delta=0.005)
        # The same band with a pdf that moves 1 % of the mass from the band to the rest: only the outside cell
        # and the band's cells together can see it.
        shifted = lambda w: np.where(w[:, 2] >= 0.5, 0.96, 1.0 + 0.04 / 3.0) / (4.0 * math.pi)  # noqa: E731
        test = ChiSquareTest(uniform_sphere, shifted, seed=2, cos_theta_min=0.5, sample_count=200_000)
        self.assertFalse(test.run())

    def test_statistic_follows_chi_square_under_the_null(self):
        # Under a true pdf the statistic is chi-square with dof degrees of freedom: its mean over 30 seeds
        # must be dof within 4 standard errors (sd of one statistic: sqrt(2 dof)). This fails if the pooling
        # or the degrees of freedom are wrong, which a single pass could not reveal.
        excess = []
        for seed in range(30):
            test = ChiSquareTest(cosine_hemisphere_sample, cosine_hemisphere_pdf, res=10, sample_count=40_000,
                                 seed=100 + seed)
            test.run()
            excess.append((test.statistic - test.dof) / math.sqrt(2.0 * test.dof))
        self.assertLess(abs(np.mean(excess)), 4.0 / math.sqrt(len(excess)), excess)

    def test_sample_dim_and_test_count_are_honoured(self):
        seen = {}

        def sample(u):
            seen["shape"] = u.shape
            return cosine_hemisphere_sample(u[:, 1:])

        test = ChiSquareTest(sample, cosine_hemisphere_pdf, sample_dim=3, sample_count=10_000, test_count=10)
        self.assertTrue(test.run(), test.message)
        self.assertEqual(seen["shape"], (10_000, 3))
        self.assertAlmostEqual(test.threshold, sidak_threshold(0.01, 10), delta=1e-15)

    def test_same_seed_same_verdict(self):
        a = ChiSquareTest(cosine_hemisphere_sample, cosine_hemisphere_pdf, sample_count=50_000, seed=9)
        b = ChiSquareTest(cosine_hemisphere_sample, cosine_hemisphere_pdf, sample_count=50_000, seed=9)
        a.run()
        b.run()
        self.assertEqual(a.statistic, b.statistic)


class IntegralTest(unittest.TestCase):
    """integrate_pdf_over_sphere, the helper behind the pdf-normalisation checks."""

    def test_known_integrals(self):
        self.assertAlmostEqual(integrate_pdf_over_sphere(cosine_hemisphere_pdf), 1.0, delta=1e-12)
        self.assertAlmostEqual(integrate_pdf_over_sphere(uniform_hemisphere_pdf), 1.0, delta=1e-12)
        self.assertAlmostEqual(integrate_pdf_over_sphere(lambda w: 2.0 * cosine_power_pdf(w, 3.0)), 2.0, delta=1e-4)
        self.assertAlmostEqual(integrate_pdf_over_sphere(lambda w: hg_pdf(w, 0.7), ires=16), 1.0, delta=1e-4)
        self.assertTrue(math.isnan(integrate_pdf_over_sphere(lambda w: -np.ones(len(w)))))


if __name__ == "__main__":
    unittest.main()
