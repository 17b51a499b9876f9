# Statistical and consistency tests of kozu's models through the Python module (docs/python.md): BSDFs,
# phase functions and media, sampled and evaluated from numpy as a researcher would, and judged by the
# chi-square harness of tests/python/chi2.py (the twin of tests/support/chi2.h).
#   - chi-square: Bsdf.sample / Phase.sample draw the density that .pdf claims (lost samples = lost mass);
#   - consistency: sample's weight and pdf equal eval / pdf and pdf at the sampled direction;
#   - white furnace: a rough conductor (F = 1) and a rough dielectric with energy compensation reflect
#     (and transmit) all the light, within the 1 % that docs/materials.md states, plus 4 standard errors;
#   - reciprocity of eval; Medium.transmittance = exp(-sigma_t t) for a homogeneous medium.
# Run (after a build with -DKOZU_PYTHON=ON):
#   PYTHONPATH=build/python /usr/bin/python3 -m unittest discover -s tests/python -p 'test_models.py'
# Every random draw has a fixed seed; each test takes well under 2 s.
"""Tests of kozu.Bsdf, kozu.Phase and kozu.Medium against the harness and closed forms."""

import math
import os
import sys
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from chi2 import ChiSquareTest, integrate_pdf_over_sphere, spherical_direction  # noqa: E402

try:
    import kozu  # noqa: E402
except ImportError as error:  # a missing module is a failure, not a skip: CI must not pass without it
    raise ImportError(f"{error}: build with -DKOZU_PYTHON=ON and set PYTHONPATH=build/python") from error


# ---- the family of chi-square tests --------------------------------------------------------------------

# Each row: a material, the incident polar angles (degrees from +z; above 90 wo is below the surface), and the
# midpoints per bin and dimension that integrate its pdf (16: the lobes of alpha = 0.09 are ~2.5 cells wide at
# 45 degrees and thin across the plane of incidence at grazing angles, where 8 would leave ~1e-4 of the mass in
# the quadrature error, as much as the lost-mass cell can tell apart at 1M samples).
MATERIAL_ROWS = [
    ("diffuse", {"type": "diffuse", "albedo": 0.8}, (30.0, 75.0, 150.0), 8),
    ("rough gold", {"type": "conductor", "roughness": 0.3, "metal": "Au"}, (0.0, 45.0, 80.0), 16),
    ("rough glass", {"type": "dielectric", "ior": 1.5, "roughness": 0.3}, (0.0, 60.0, 150.0), 16),
    ("standard", {"type": "standard"}, (0.0, 45.0, 80.0), 16),
    ("standard metallic", {"type": "standard", "base_color": [0.9, 0.6, 0.3], "metallic": 0.5, "roughness": 0.4},
     (20.0, 70.0), 16),
]
PHASE_ROWS = [
    ("hg 0.7", {"type": "hg", "g": 0.7}),
    ("sggx specular surface", {"type": "sggx", "density": 1.0, "phase": "specular",
                               "distribution": {"kind": "surface", "normal": [0.0, 0.0, 1.0], "roughness": 0.5}}),
    ("sggx specular fiber", {"type": "sggx", "density": 1.0, "phase": "specular",
                             "distribution": {"kind": "fiber", "tangent": [1.0, 0.0, 0.0], "roughness": 0.5}}),
]
PHASE_WO = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
# Sidak over the whole family, so that one false failure in 100 runs of the file, not of each test.
CHI2_TESTS = sum(len(angles) for _, _, angles, _ in MATERIAL_ROWS) + len(PHASE_ROWS)

RES = 40  # 40 x 80 cells, the C++ harness's default
PHI_DEG = 30.0  # wo's azimuth: off the x axis, as the C++ tests


def direction_from_angles(theta_deg, phi_deg=PHI_DEG):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def float32_uniforms(u):
    """u as float32 in [0, 1): rounding to float32 can give 1.0, which the samplers' [0, 1) excludes."""
    u32 = np.asarray(u, dtype=np.float32)
    return np.minimum(u32, np.nextafter(np.float32(1.0), np.float32(0.0)))


def chi2_angle(material, nominal):
    """The dielectric's incident angle, nudged (by < 3 degrees) to put its pdf's jump on a cos(theta) edge.

    The transmission pdf jumps where the facet that would refract wo into wi turns vertical, on the cone
    |cos theta_i| = |cos theta_o| / eta (eta seen from wo). Midpoint quadrature resolves a jump only on a cell
    edge, and the edges lie at multiples of 2 / RES in cos(theta): as the C++ tests do (test_rough_materials).
    """
    if material.get("type") != "dielectric" or nominal == 0.0:
        return nominal
    inside = nominal > 90.0
    ior = material.get("ior", 1.5)
    eta = 1.0 / ior if inside else ior
    cone = abs(math.cos(math.radians(nominal))) / eta
    if cone >= 1.0:
        return nominal
    step = 2.0 / RES
    theta = math.degrees(math.acos(max(step, round(cone / step) * step) * eta))
    return 180.0 - theta if inside else theta


def bin_swap(theta_deg):
    """True at normal incidence, where the bins see directions with y and z swapped.

    The harness's pole is +z: a lobe about the normal would fill a fraction of the first cos(theta) row. The
    swap (a reflection: solid angle is kept) moves the normal to the equator, where cells are nearly square,
    and the horizon, where pdfs jump, onto the meridians phi = 0 and pi, which are cell edges.
    """
    return abs(math.cos(math.radians(theta_deg))) > 0.9999


def swap_yz(w):
    return w[:, [0, 2, 1]] if w.ndim == 2 else w[[0, 2, 1]]


def bsdf_chi2(bsdf, wo, swap, ires, seed):
    """A ChiSquareTest of bsdf.sample against bsdf.pdf at wo; samples with pdf 0 are lost mass."""
    wo32 = wo.astype(np.float32)

    def sample(u):
        u = float32_uniforms(u)
        wi, _, pdf = bsdf.sample(wo32, u[:, 0], u[:, 1:3])
        wi = np.asarray(wi, dtype=np.float64)
        return (swap_yz(wi) if swap else wi), np.asarray(pdf, dtype=np.float64)

    def pdf(w):
        w = swap_yz(w) if swap else w
        return np.asarray(bsdf.pdf(wo32, w.astype(np.float32)), dtype=np.float64)

    return ChiSquareTest(sample, pdf, sample_dim=3, res=RES, ires=ires, seed=seed, test_count=CHI2_TESTS)


def directional_albedo(bsdf, wo, mode, n, seed):
    """Integral of eval over wi at wo, by the BSDF's own sampling: (mean (3,), standard error (3,))."""
    u = float32_uniforms(np.random.default_rng(seed).random((n, 3)))
    _, weight, pdf = bsdf.sample(wo.astype(np.float32), u[:, 0], u[:, 1:3], mode=mode)
    weight = np.where((np.asarray(pdf) > 0.0)[:, None], np.asarray(weight, dtype=np.float64), 0.0)
    return weight.mean(axis=0), weight.std(axis=0, ddof=1) / math.sqrt(n)


def hg(cos_wo_wi, g):
    """Henyey-Greenstein in kozu's convention (phase.h, hg_phase.h): cos = wo . wi, forward is wi = -wo."""
    denom = 1.0 + g * g + 2.0 * g * cos_wo_wi
    return (1.0 - g * g) / (4.0 * math.pi * denom * np.sqrt(denom))


# ---- BSDFs ---------------------------------------------------------------------------------------------

class BsdfChi2Test(unittest.TestCase):
    """Bsdf.sample draws the density Bsdf.pdf claims, samples lost below the horizon included."""

    def check_row(self, index):
        name, material, angles, ires = MATERIAL_ROWS[index]
        bsdf = kozu.Bsdf(material)
        for nominal in angles:
            theta = chi2_angle(material, nominal)
            with self.subTest(material=name, theta=theta):
                test = bsdf_chi2(bsdf, direction_from_angles(theta), bin_swap(theta), ires,
                                 seed=1000 * index + int(theta))
                self.assertTrue(test.run(), f"{name} at theta {theta:.2f}: {test.message}")

    def test_diffuse(self):
        self.check_row(0)

    def test_rough_conductor(self):
        self.check_row(1)

    def test_rough_dielectric(self):
        self.check_row(2)

    def test_standard(self):
        self.check_row(3)

    def test_standard_metallic(self):
        self.check_row(4)


class BsdfConsistencyTest(unittest.TestCase):
    """sample's weight is eval / pdf and its pdf is pdf(), at the direction it sampled (bsdf.h)."""

    N = 20_000

    def check(self, material, theta, mode, seed):
        bsdf = kozu.Bsdf(material)
        wo = direction_from_angles(theta).astype(np.float32)
        u = float32_uniforms(np.random.default_rng(seed).random((self.N, 3)))
        wi, weight, pdf = bsdf.sample(wo, u[:, 0], u[:, 1:3], mode=mode)
        wi, weight, pdf = np.asarray(wi), np.asarray(weight, dtype=np.float64), np.asarray(pdf, dtype=np.float64)
        self.assertEqual(wi.shape, (self.N, 3))
        self.assertEqual(weight.shape, (self.N, 3))
        self.assertEqual(pdf.shape, (self.N,))
        valid = pdf > 0.0
        self.assertGreater(valid.mean(), 0.5, "most samples must succeed")
        # Directions at grazing angles or with tiny densities carry float32 cancellation (a half vector of two
        # nearly opposite directions): they are left out, the bulk is checked to 1e-3 (float32 ~ 1e-7; the
        # models' own round-off ~ 1e-5). A formula bug moves whole lobes, far beyond it.
        wi_valid = wi[valid]
        eval_at = np.asarray(bsdf.eval(wo, wi_valid, mode=mode), dtype=np.float64)
        pdf_at = np.asarray(bsdf.pdf(wo, wi_valid), dtype=np.float64)
        robust = (np.abs(wi_valid[:, 2]) > 1e-2) & (pdf[valid] > 1e-3)
        self.assertGreater(robust.mean(), 0.9)
        np.testing.assert_allclose(pdf_at[robust], pdf[valid][robust], rtol=1e-3,
                                   err_msg=f"{material} theta {theta}: sample's pdf != pdf()")
        np.testing.assert_allclose(weight[valid][robust], eval_at[robust] / pdf_at[robust, None], rtol=1e-3,
                                   atol=1e-6, err_msg=f"{material} theta {theta}: weight != eval / pdf")
        # A failed sample carries no weight (the path ends there).
        self.assertTrue(np.all(weight[~valid] == 0.0))

    def test_weight_is_eval_over_pdf(self):
        for i, (_, material, angles, _) in enumerate(MATERIAL_ROWS):
            for theta in angles:
                with self.subTest(material=material, theta=theta):
                    self.check(material, theta, "radiance", seed=17 + i)

    def test_importance_mode_of_the_dielectric(self):
        # Importance transport omits transmission's 1/eta^2 (bsdf.h): its weights must still be eval / pdf.
        for theta in (30.0, 150.0):
            with self.subTest(theta=theta):
                self.check({"type": "dielectric", "ior": 1.5, "roughness": 0.3}, theta, "importance", seed=5)

    def test_pdf_integrates_to_the_kept_fraction(self):
        # The integral of pdf over the sphere is 1 minus the probability that sample() fails (C++:
        # PdfIntegratesToOneMinusLostMass). Tolerance: 1e-3 for the quadrature plus 4 binomial standard
        # deviations of the kept fraction measured from 2^18 draws.
        n = 1 << 18
        material = {"type": "conductor", "roughness": 0.3, "metal": "Au"}
        bsdf = kozu.Bsdf(material)
        for theta in (45.0, 80.0):
            wo = direction_from_angles(theta).astype(np.float32)
            u = float32_uniforms(np.random.default_rng(int(theta)).random((n, 3)))
            kept = float((np.asarray(bsdf.sample(wo, u[:, 0], u[:, 1:3])[2]) > 0.0).mean())
            integral = integrate_pdf_over_sphere(
                lambda w: np.asarray(bsdf.pdf(wo, w.astype(np.float32)), dtype=np.float64), res=80, ires=16)
            with self.subTest(theta=theta):
                self.assertAlmostEqual(integral, kept, delta=1e-3 + 4.0 * math.sqrt(kept * (1.0 - kept) / n))


class BsdfFurnaceTest(unittest.TestCase):
    """Directional albedos where they are known in closed form."""

    N = 1 << 18

    def test_compensated_rough_conductor_reflects_everything(self):
        # No metal, eta or k: F = 1, the white-furnace conductor. Kulla-Conty compensation restores what single
        # scattering loses, to the 1 % that docs/materials.md states; without it, alpha = 1 loses > 5 %.
        for roughness in (0.3, 0.7, 1.0):
            bsdf = kozu.Bsdf({"type": "conductor", "roughness": roughness, "multiscatter": "compensated"})
            single = kozu.Bsdf({"type": "conductor", "roughness": roughness})
            for theta in (0.0, 45.0, 80.0):
                wo = direction_from_angles(theta)
                mean, se = directional_albedo(bsdf, wo, "radiance", self.N, seed=int(100 * roughness + theta))
                with self.subTest(roughness=roughness, theta=theta):
                    self.assertLess(se.max(), 2e-3, "too few samples for a 1 % test")
                    for c in range(3):
                        self.assertAlmostEqual(mean[c], 1.0, delta=0.01 + 4.0 * se[c])
                    if roughness == 1.0:
                        lost, lost_se = directional_albedo(single, wo, "radiance", self.N, seed=7)
                        self.assertLess(lost[1] + 4.0 * lost_se[1], 0.95)

    def test_compensated_rough_dielectric_conserves_energy(self):
        # In importance mode (no 1/eta^2) reflection plus transmission is an energy balance: 1, from outside
        # and from inside (C++: RoughMaterial.WhiteFurnace).
        bsdf = kozu.Bsdf({"type": "dielectric", "ior": 1.5, "roughness": 0.5, "multiscatter": "compensated"})
        for theta in (30.0, 75.0, 150.0):
            mean, se = directional_albedo(bsdf, direction_from_angles(theta), "importance", self.N, seed=int(theta))
            with self.subTest(theta=theta):
                self.assertLess(se.max(), 2e-3)
                self.assertAlmostEqual(mean[1], 1.0, delta=0.01 + 4.0 * se[1])

    def test_diffuse_weight_is_its_albedo(self):
        # Cosine sampling of albedo / pi: every sample's weight is the albedo, exactly (up to float32).
        bsdf = kozu.Bsdf({"type": "diffuse", "albedo": [0.8, 0.5, 0.2]})
        u = float32_uniforms(np.random.default_rng(3).random((10_000, 3)))
        _, weight, pdf = bsdf.sample(direction_from_angles(40.0), u[:, 0], u[:, 1:3])
        valid = np.asarray(pdf) > 0.0
        self.assertGreater(valid.mean(), 0.999)
        np.testing.assert_allclose(np.asarray(weight)[valid], np.broadcast_to([0.8, 0.5, 0.2], (valid.sum(), 3)),
                                   rtol=1e-5)


class BsdfReciprocityTest(unittest.TestCase):
    """f(wo, wi) = f(wi, wo) for reciprocal models; eval carries |cos theta_i|, so it is divided out."""

    def check(self, material):
        bsdf = kozu.Bsdf(material)
        rng = np.random.default_rng(11)
        n = 4096
        # Pairs on one side of the surface (both models are two-sided reflectors), away from the horizon.
        a = spherical_direction(rng.uniform(0.05, 1.0, n), rng.uniform(0.0, 2.0 * math.pi, n))
        b = spherical_direction(rng.uniform(0.05, 1.0, n), rng.uniform(0.0, 2.0 * math.pi, n))
        a, b = a.astype(np.float32), b.astype(np.float32)
        f_ab = np.asarray(bsdf.eval(a, b), dtype=np.float64) / np.abs(b[:, 2:3].astype(np.float64))
        f_ba = np.asarray(bsdf.eval(b, a), dtype=np.float64) / np.abs(a[:, 2:3].astype(np.float64))
        self.assertTrue(np.all(f_ab > 0.0), f"{material}: eval must be positive above the surface")
        np.testing.assert_allclose(f_ab, f_ba, rtol=1e-4, atol=1e-7, err_msg=str(material))
        # Reflection carries no radiance scaling: the two transport modes agree.
        np.testing.assert_allclose(np.asarray(bsdf.eval(a, b, mode="importance")), np.asarray(bsdf.eval(a, b)),
                                   rtol=1e-6, err_msg=str(material))

    def test_diffuse(self):
        self.check({"type": "diffuse", "albedo": 0.8})

    def test_rough_conductor(self):
        self.check({"type": "conductor", "roughness": 0.3, "metal": "Au"})

    def test_compensated_rough_conductor(self):
        self.check({"type": "conductor", "roughness": 0.6, "metal": "Cu", "multiscatter": "compensated"})


class BsdfInterfaceTest(unittest.TestCase):
    """The parts of the interface the statistical tests rely on: flags, broadcasting, errors."""

    def test_flags(self):
        self.assertEqual(kozu.Bsdf({"type": "diffuse"}).flags, {"reflection", "diffuse"})
        self.assertEqual(kozu.Bsdf({"type": "conductor", "roughness": 0.3}).flags, {"reflection", "glossy"})
        self.assertEqual(kozu.Bsdf({"type": "conductor"}).flags, {"reflection", "specular"})
        self.assertEqual(kozu.Bsdf({"type": "dielectric", "roughness": 0.3}).flags,
                         {"reflection", "transmission", "glossy"})

    def test_single_wo_broadcasts_against_many_wi(self):
        bsdf = kozu.Bsdf({"type": "diffuse", "albedo": 0.8})
        wi = spherical_direction(np.linspace(0.1, 0.9, 5), np.zeros(5)).astype(np.float32)
        values = np.asarray(bsdf.eval(np.array([0.0, 0.0, 1.0]), wi))
        self.assertEqual(values.shape, (5, 3))
        self.assertEqual(values.dtype, np.float32)
        np.testing.assert_allclose(values[:, 0], 0.8 / math.pi * wi[:, 2], rtol=1e-6)
        np.testing.assert_allclose(np.asarray(bsdf.pdf([0.0, 0.0, 1.0], wi)), wi[:, 2] / math.pi, rtol=1e-6)

    def test_a_misspelt_key_is_a_scene_error(self):
        with self.assertRaises(kozu.SceneError) as caught:
            kozu.Bsdf({"type": "diffuse", "albdo": 0.8})
        self.assertIn("albdo", str(caught.exception))


# ---- phase functions and media -------------------------------------------------------------------------

class PhaseTest(unittest.TestCase):
    """Phase.sample draws Phase.pdf (world space, phase.h); HG matches its closed form."""

    def test_chi2(self):
        wo = PHASE_WO.astype(np.float32)
        for i, (name, desc) in enumerate(PHASE_ROWS):
            phase = kozu.Phase(desc)

            def sample(u, phase=phase):
                wi, _, pdf = phase.sample(wo, float32_uniforms(u))
                return np.asarray(wi, dtype=np.float64), np.asarray(pdf, dtype=np.float64)

            def pdf(w, phase=phase):
                return np.asarray(phase.pdf(wo, w.astype(np.float32)), dtype=np.float64)

            with self.subTest(phase=name):
                test = ChiSquareTest(sample, pdf, res=RES, ires=16, seed=500 + i, test_count=CHI2_TESTS)
                self.assertTrue(test.run(), f"{name}: {test.message}")
                self.assertAlmostEqual(test.pdf_integral, 1.0, delta=1e-3)  # f_p is normalised (eq. 7)

    def test_hg_closed_form_and_weight(self):
        g = 0.7
        phase = kozu.Phase({"type": "hg", "g": g})
        rng = np.random.default_rng(2)
        wi = spherical_direction(rng.uniform(-1.0, 1.0, 1000), rng.uniform(0.0, 2.0 * math.pi, 1000))
        wo = PHASE_WO
        expected = hg(wi @ wo, g)
        np.testing.assert_allclose(np.asarray(phase.pdf(wo, wi)), expected, rtol=1e-4)
        np.testing.assert_allclose(np.asarray(phase.eval(wo, wi)), expected, rtol=1e-4)
        # Exact sampling: weight 1, pdf = pdf(), and the mean cosine about the propagation direction -wo is g.
        # HG's second Legendre moment is g^2, so E[cos^2] = (1 + 2 g^2) / 3 and the variance of cos is
        # (1 - g^2) / 3: the mean of n samples lies within 4.5 standard errors of g.
        n = 100_000
        u = float32_uniforms(rng.random((n, 2)))
        wi_s, weight, pdf = phase.sample(wo, u)
        wi_s = np.asarray(wi_s, dtype=np.float64)
        np.testing.assert_allclose(np.asarray(weight), 1.0, rtol=1e-5)
        np.testing.assert_allclose(np.asarray(pdf), np.asarray(phase.pdf(wo, wi_s)), rtol=1e-4)
        mean_cos = float(np.mean(wi_s @ -wo))
        self.assertAlmostEqual(mean_cos, g, delta=4.5 * math.sqrt((1.0 - g * g) / 3.0 / n))


class MediumTest(unittest.TestCase):
    """A homogeneous medium: its coefficients, its phase function and its transmittance."""

    DESC = {"type": "homogeneous", "density": [0.5, 1.0, 2.0], "albedo": 0.8, "phase": {"type": "hg", "g": 0.5}}

    def test_properties(self):
        medium = kozu.Medium(self.DESC)
        sigma_t, sigma_s = medium.properties(np.zeros((4, 3)), np.tile([0.0, 0.0, 1.0], (4, 1)))
        np.testing.assert_allclose(np.asarray(sigma_t), np.tile([0.5, 1.0, 2.0], (4, 1)), rtol=1e-6)
        np.testing.assert_allclose(np.asarray(sigma_s), 0.8 * np.tile([0.5, 1.0, 2.0], (4, 1)), rtol=1e-6)

    def test_transmittance_is_beer_lambert(self):
        # Ratio tracking is unbiased (exact for a homogeneous medium if the module computes it in closed form):
        # the mean over n rays is exp(-sigma_t t) within float32 round-off plus 4.5 standard errors.
        medium = kozu.Medium(self.DESC)
        n = 20_000
        sigma_t = np.array([0.5, 1.0, 2.0])
        direction = np.array([0.6, 0.0, 0.8])
        for t in (0.0, 0.3, 1.0, 2.5):
            tr = np.asarray(medium.transmittance(np.zeros((n, 3)), np.tile(direction, (n, 1)), np.full(n, t),
                                                 seed=int(10 * t)), dtype=np.float64)
            self.assertEqual(tr.shape, (n, 3))
            mean, se = tr.mean(axis=0), tr.std(axis=0, ddof=1) / math.sqrt(n)
            expected = np.exp(-sigma_t * t)
            with self.subTest(t=t):
                self.assertTrue(np.all(np.abs(mean - expected) <= 1e-5 + 4.5 * se), f"{mean} vs {expected}")

    def test_phase_of_the_medium(self):
        phase = kozu.Medium(self.DESC).phase((0.0, 0.0, 0.0))
        wi = spherical_direction(np.linspace(-0.9, 0.9, 7), np.linspace(0.0, 6.0, 7))
        np.testing.assert_allclose(np.asarray(phase.pdf(PHASE_WO, wi)), hg(wi @ PHASE_WO, 0.5), rtol=1e-4)


if __name__ == "__main__":
    unittest.main()
