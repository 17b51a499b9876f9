# kozu's chi-square goodness-of-fit harness for direction samplers, in Python (numpy only).
#
# The twin of tests/support/chi2.{h,cpp}: draw many directions from a sampler, bin them on the sphere in
# (cos theta, phi), and compare the counts with the density the sampler claims, integrated numerically over
# each bin. The statistical model is Mitsuba 3's harness (Jakob et al.), written here from its description:
# Pearson's statistic, cells expecting fewer than 5 samples pooled, the p-value of the chi-square
# distribution, and a Sidak correction for a family of tests. The layout and the pooling follow the C++
# harness exactly, so that a model tested from Python and from C++ is judged by the same rules:
#   - res bins uniform in cos(theta) over [cos_theta_min, cos_theta_max] by 2 * res bins uniform in phi over
#     [0, 2 pi): every cell has the same solid angle; the rest of the sphere, when the range is narrowed, is
#     one more "outside" cell;
#   - samples the sampler rejects (weight 0) are lost energy, not a wrong density: they land in no bin, and
#     (check_lost_mass) they form one more cell expecting N * (1 - integral of the pdf);
#   - cells are pooled in order of increasing expected count until the pool expects min_expected or more.
#
# Only numpy is needed (no scipy): the p-value comes from our own regularized incomplete gamma function.
"""Chi-square tests of direction samplers against the densities they claim (kozu's harness)."""

import math

import numpy as np

__all__ = [
    "ChiSquareTest",
    "chi2_sf",
    "gamma_q",
    "integrate_pdf_over_sphere",
    "pearson_statistic",
    "sidak_threshold",
    "spherical_direction",
]

_EPSILON = np.finfo(float).eps
_TINY = 1e-300
_MAX_ITERATIONS = 1_000_000


# ---- the p-value --------------------------------------------------------------------------------------

def _gamma_p_series(a, x):
    """Regularized lower incomplete gamma P(a, x) by its power series.

    P(a, x) = e^-x x^a / Gamma(a) * sum_n x^n / (a (a+1) ... (a+n)); the terms shrink fast once n > x,
    so it is the method of choice for x < a + 1 (Numerical Recipes, 3rd ed., section 6.2).
    """
    term = 1.0 / a
    total = term
    ap = a
    for _ in range(_MAX_ITERATIONS):
        ap += 1.0
        term *= x / ap
        total += term
        if abs(term) < abs(total) * _EPSILON:
            return total * math.exp(-x + a * math.log(x) - math.lgamma(a))
    raise ArithmeticError(f"gamma series did not converge for a = {a}, x = {x}")


def _gamma_q_continued_fraction(a, x):
    """Regularized upper incomplete gamma Q(a, x) by its continued fraction (modified Lentz method).

    The Legendre continued fraction converges fast for x >= a + 1, exactly where the series is slow;
    evaluating Q directly there also keeps the tiny p-values of a failing test accurate, which 1 - P
    would round to 0 (Numerical Recipes, 3rd ed., section 6.2).
    """
    b = x + 1.0 - a
    c = 1.0 / _TINY
    d = 1.0 / b
    h = d
    for i in range(1, _MAX_ITERATIONS):
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        if abs(d) < _TINY:
            d = _TINY
        c = b + an / c
        if abs(c) < _TINY:
            c = _TINY
        d = 1.0 / d
        delta = d * c
        h *= delta
        if abs(delta - 1.0) <= _EPSILON:
            return math.exp(-x + a * math.log(x) - math.lgamma(a)) * h
    raise ArithmeticError(f"gamma continued fraction did not converge for a = {a}, x = {x}")


def gamma_q(a, x):
    """Regularized upper incomplete gamma Q(a, x) = Gamma(a, x) / Gamma(a), for a > 0.

    The series below a + 1 and the continued fraction above, each where it converges quickly.
    """
    if not a > 0.0:
        raise ValueError(f"gamma_q needs a > 0, got {a}")
    if math.isnan(x):
        return math.nan
    if x <= 0.0:
        return 1.0
    if math.isinf(x):
        return 0.0
    if x < a + 1.0:
        return 1.0 - _gamma_p_series(a, x)
    return _gamma_q_continued_fraction(a, x)


def chi2_sf(x, dof):
    """P(X >= x) for X chi-square distributed with dof degrees of freedom: the test's p-value.

    The chi-square distribution with k degrees of freedom is Gamma(k/2, scale 2), so its survival
    function is Q(k/2, x/2).
    """
    if dof < 1:
        raise ValueError(f"chi2_sf needs dof >= 1, got {dof}")
    if math.isnan(x):
        return math.nan
    return min(max(gamma_q(0.5 * dof, 0.5 * x), 0.0), 1.0)


def sidak_threshold(significance, test_count):
    """The per-test level that keeps a family of test_count independent tests at significance.

    Sidak: 1 - (1 - alpha)^(1/m), computed with log1p/expm1 so that small levels keep their digits.
    """
    return -math.expm1(math.log1p(-significance) / max(int(test_count), 1))


# ---- the statistic ------------------------------------------------------------------------------------

def pearson_statistic(observed, expected, min_expected=5.0):
    """Pearson's statistic after pooling small cells: (statistic, number of cells tested, pooled mask).

    Cells in order of increasing expected count are pooled until the pool expects min_expected or more, so
    that the chi-square approximation holds for every cell tested (as the C++ harness and Mitsuba's do). The
    pooled cells are a prefix of that order: those expecting too few, plus the first one that brings a
    nonempty pool up to the mark. The pool counts as one cell when it expects anything; the test then has
    (cells tested - 1) degrees of freedom.
    """
    observed = np.asarray(observed, dtype=np.float64).reshape(-1)
    expected = np.asarray(expected, dtype=np.float64).reshape(-1)
    order = np.argsort(expected, kind="stable")
    e_sorted = expected[order]
    before = np.cumsum(e_sorted) - e_sorted
    pooled_sorted = (e_sorted < min_expected) | ((before > 0.0) & (before < min_expected))
    pooled = np.zeros(expected.shape, dtype=bool)
    pooled[order] = pooled_sorted
    tested = ~pooled
    statistic = float(np.sum((observed[tested] - expected[tested]) ** 2 / expected[tested]))
    cells = int(tested.sum())
    pooled_expected = float(expected[pooled].sum())
    if pooled_expected > 0.0:
        statistic += (float(observed[pooled].sum()) - pooled_expected) ** 2 / pooled_expected
        cells += 1
    return statistic, cells, pooled


# ---- the sphere ----------------------------------------------------------------------------------------

def spherical_direction(cos_theta, phi):
    """Unit vectors (..., 3) at the given cos(theta) and phi about +z (broadcast)."""
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    phi = np.asarray(phi, dtype=np.float64)
    sin_theta = np.sqrt(np.maximum(0.0, 1.0 - cos_theta * cos_theta))
    return np.stack(np.broadcast_arrays(sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta),
                    axis=-1)


def _evaluate_pdf(pdf, directions):
    """pdf at directions (M, 3) as float64 (M,), or a message naming the first invalid value.

    A negative or non-finite density is a bug in the pdf, not noise: the test fails on it outright.
    """
    values = np.asarray(pdf(directions), dtype=np.float64).reshape(-1)
    if values.shape[0] != directions.shape[0]:
        return None, f"pdf returned {values.shape[0]} values for {directions.shape[0]} directions"
    bad = ~(np.isfinite(values) & (values >= 0.0))
    if bad.any():
        i = int(np.argmax(bad))
        w = directions[i]
        return None, f"pdf returned {values[i]} at ({w[0]:.9g}, {w[1]:.9g}, {w[2]:.9g})"
    return values, None


def _integrate_band(pdf, z0, z1, nz, nphi, ires):
    """Integrals of pdf over the nz x nphi cells of the band cos(theta) in [z0, z1] (row-major in z).

    In (z, phi) coordinates the solid angle is dz dphi, so each cell is a rectangle; it is integrated by the
    midpoint rule on ires x ires points. The rule is exact for densities linear in z and phi (a cosine
    lobe) and second-order otherwise; a discontinuity is resolved only to O(1/ires) unless it lies on a cell
    edge. Returns (cells (nz, nphi), error message or None).
    """
    dz = (z1 - z0) / nz
    dphi = 2.0 * math.pi / nphi
    offsets = (np.arange(ires) + 0.5) / ires
    z = z0 + (np.arange(nz)[:, None] + offsets[None, :]).reshape(-1) * dz
    phi = (np.arange(nphi)[:, None] + offsets[None, :]).reshape(-1) * dphi
    directions = spherical_direction(z[:, None], phi[None, :]).reshape(-1, 3)
    values, error = _evaluate_pdf(pdf, directions)
    if error:
        return None, error
    cells = values.reshape(nz, ires, nphi, ires).sum(axis=(1, 3)) * (dz * dphi / (ires * ires))
    return cells, None


def integrate_pdf_over_sphere(pdf, res=80, ires=8):
    """Integral of pdf (vectorised: (M, 3) -> (M,)) over the whole sphere.

    A normalised density integrates to 1; a sampler that loses mass (directions below the horizon, lobes
    it never returns) must have a pdf integrating to 1 minus the probability of losing it. The grid is
    res cells in cos(theta) by 2 res in phi, ires x ires midpoints each; NaN if the pdf is invalid somewhere.
    """
    cells, error = _integrate_band(pdf, -1.0, 1.0, res, 2 * res, ires)
    return math.nan if error else float(cells.sum())


# ---- the test ------------------------------------------------------------------------------------------

class ChiSquareTest:
    """Pearson's chi-square test of a direction sampler against the pdf it claims.

    sample(u): u is an (N, sample_dim) float64 array of uniforms in [0, 1); returns (wi (N, 3), weight (N,)
        or (N, k)). A sample whose weight is 0 in every component (the sampler failed, or its pdf is 0) is
        rejected: lost energy, counted apart from the bins.
    pdf(wi): wi (M, 3) float64 unit vectors; returns (M,) densities per unit solid angle.

    res: bins in cos(theta); phi gets 2 * res (cells of equal solid angle). ires: midpoints per bin and
    dimension for the expected counts. significance is for the whole family of test_count tests (Sidak).
    cos_theta_min/max narrow the binned band (the rest of the sphere becomes one cell). check_lost_mass
    adds the rejected samples as a cell expecting N (1 - integral of the pdf): it catches a pdf that is
    misnormalised by far less than the bins can, but needs the quadrature accurate to ~1e-5 relative to
    the lost fraction; switch it off for a pdf the quadrature cannot resolve.

    run() returns whether the test passed; afterwards p_value, statistic, dof, threshold, pdf_integral,
    lost_samples, message (why it failed: the pdf integral, the worst cells), and the histograms observed
    and expected ((res, 2 res) arrays, for plotting) are set.
    """

    def __init__(self, sample, pdf, sample_dim=2, res=40, ires=8, sample_count=1_000_000, seed=1,
                 significance=0.01, test_count=1, min_expected=5.0, cos_theta_min=-1.0, cos_theta_max=1.0,
                 check_lost_mass=True):
        self.sample = sample
        self.pdf = pdf
        self.sample_dim = int(sample_dim)
        self.res = int(res)
        self.ires = int(ires)
        self.sample_count = int(sample_count)
        self.seed = seed
        self.significance = float(significance)
        self.test_count = int(test_count)
        self.min_expected = float(min_expected)
        self.cos_theta_min = float(cos_theta_min)
        self.cos_theta_max = float(cos_theta_max)
        self.check_lost_mass = bool(check_lost_mass)
        self.threshold = sidak_threshold(self.significance, self.test_count) \
            if 0.0 < self.significance < 1.0 else math.nan
        self._reset()

    def _reset(self):
        self.passed = False
        self.p_value = math.nan
        self.statistic = math.nan
        self.dof = 0
        self.pdf_integral = math.nan
        self.lost_samples = 0
        self.outside_samples = 0
        self._has_outside = False
        self.observed = None
        self.expected = None
        self.message = ""

    def _fail(self, message):
        self.passed = False
        self.message = message
        return False

    def _check_options(self):
        """A message when the options make no test at all (they would otherwise pass vacuously)."""
        if (self.sample_count <= 0 or self.ires <= 0 or self.res <= 0 or self.sample_dim <= 0
                or self.min_expected <= 0 or not 0.0 < self.significance < 1.0 or self.test_count < 1):
            return (f"invalid options: sample_count = {self.sample_count}, res = {self.res}, ires = {self.ires}, "
                    f"sample_dim = {self.sample_dim}, min_expected = {self.min_expected}, significance = "
                    f"{self.significance}, test_count = {self.test_count}")
        if not -1.0 <= self.cos_theta_min < self.cos_theta_max <= 1.0:
            return f"invalid band: cos(theta) in [{self.cos_theta_min}, {self.cos_theta_max}]"
        return None

    def _draw(self):
        """Samples the sampler and bins what it returns: (observed (res, 2 res), outside, lost) or a message."""
        rng = np.random.default_rng(self.seed)
        u = rng.random((self.sample_count, self.sample_dim))
        result = self.sample(u)
        if not isinstance(result, tuple) or len(result) != 2:
            return None, "sample(u) must return (wi, weight)"
        wi = np.asarray(result[0], dtype=np.float64).reshape(-1, 3)
        weight = np.asarray(result[1], dtype=np.float64).reshape(self.sample_count, -1)
        if wi.shape[0] != self.sample_count:
            return None, f"sample(u) returned {wi.shape[0]} directions for {self.sample_count} draws"
        bad_weight = ~np.isfinite(weight).all(axis=1) | (weight < 0.0).any(axis=1)
        if bad_weight.any():
            i = int(np.argmax(bad_weight))
            return None, f"sample(u = {u[i].tolist()}) returned an invalid weight {weight[i].tolist()}"
        kept = (weight > 0.0).any(axis=1)
        lost = int(self.sample_count - kept.sum())
        wi = wi[kept]
        u_kept = u[kept]
        if not np.isfinite(wi).all():
            i = int(np.argmax(~np.isfinite(wi).all(axis=1)))
            return None, f"sample(u = {u_kept[i].tolist()}) returned a non-finite direction {wi[i].tolist()}"
        length = np.linalg.norm(wi, axis=1)
        off = np.abs(length - 1.0) > 1e-3
        if off.any():
            i = int(np.argmax(off))
            return None, (f"sample(u = {u_kept[i].tolist()}) returned a direction that is not unit length: "
                          f"{wi[i].tolist()}, |w| = {length[i]}")
        z0, z1 = self.cos_theta_min, self.cos_theta_max
        nz, nphi = self.res, 2 * self.res
        z = np.clip(wi[:, 2], -1.0, 1.0)
        inside = (z >= z0) & (z <= z1)
        outside = int((~inside).sum())
        z = z[inside]
        phi = np.arctan2(wi[inside, 1], wi[inside, 0])
        phi = np.where(phi < 0.0, phi + 2.0 * math.pi, phi)
        iz = np.minimum(((z - z0) / (z1 - z0) * nz).astype(np.int64), nz - 1)
        ip = np.minimum((phi / (2.0 * math.pi) * nphi).astype(np.int64), nphi - 1)
        observed = np.bincount(iz * nphi + ip, minlength=nz * nphi).astype(np.float64).reshape(nz, nphi)
        return (observed, outside, lost), None

    def _cell_label(self, i):
        """Names cell i (grid cells row-major, then outside, then lost) for the failure message."""
        nz, nphi = self.res, 2 * self.res
        z0, z1 = self.cos_theta_min, self.cos_theta_max
        if i >= nz * nphi:
            if self._has_outside and i == nz * nphi:
                return f"outside the binned range cos(theta) in [{z0}, {z1}]"
            return "the rejected samples (weight 0), expected to number N * (1 - pdf integral)"
        iz, ip = divmod(i, nphi)
        c0 = z0 + (z1 - z0) * iz / nz
        c1 = z0 + (z1 - z0) * (iz + 1) / nz
        deg = 180.0 / math.pi
        return (f"cos(theta) in [{c0:.4f}, {c1:.4f}] (theta {math.acos(c1) * deg:.2f}..{math.acos(c0) * deg:.2f} "
                f"deg), phi {360.0 * ip / nphi:.2f}..{360.0 * (ip + 1) / nphi:.2f} deg")

    def run(self):
        """Draws, bins, integrates and tests; True when p_value >= the Sidak-corrected threshold."""
        self._reset()
        error = self._check_options()
        if error:
            return self._fail(error)
        drawn, error = self._draw()
        if error:
            return self._fail(error)
        observed, outside_observed, lost_observed = drawn
        self.lost_samples = lost_observed
        self.outside_samples = outside_observed

        z0, z1 = self.cos_theta_min, self.cos_theta_max
        nz, nphi = self.res, 2 * self.res
        cells, error = _integrate_band(self.pdf, z0, z1, nz, nphi, self.ires)
        if error:
            return self._fail(error)
        outside_integral = 0.0
        for lo, hi in ((-1.0, z0), (z1, 1.0)):
            if hi > lo:
                band, error = _integrate_band(self.pdf, lo, hi, nz, nphi, self.ires)
                if error:
                    return self._fail(error)
                outside_integral += float(band.sum())
        self.pdf_integral = float(cells.sum()) + outside_integral
        n = float(self.sample_count)
        self.observed = observed
        self.expected = cells * n

        # The grid, then the rest of the sphere (if the grid does not cover it), then the rejected samples.
        self._has_outside = z0 > -1.0 or z1 < 1.0
        obs = [observed.reshape(-1)]
        exp = [self.expected.reshape(-1)]
        if self._has_outside:
            obs.append([outside_observed])
            exp.append([outside_integral * n])
        if self.check_lost_mass:
            obs.append([lost_observed])
            exp.append([n * max(0.0, 1.0 - self.pdf_integral)])
        context = (f"pdf integral = {self.pdf_integral:.6f}, {self.sample_count} samples ({lost_observed} "
                   f"rejected" + (f", {outside_observed} outside the binned range" if self._has_outside else "")
                   + ")")
        if self._pearson(np.concatenate(obs).astype(np.float64), np.concatenate(exp), context):
            return True
        # A misnormalised pdf is the commonest bug; say so plainly when the kept fraction disagrees with the
        # integral by more than 4 binomial standard deviations (plus 1e-3 for the quadrature).
        kept = 1.0 - lost_observed / n
        sd = math.sqrt(max(kept * (1.0 - kept), 1.0 / n) / n)
        if abs(self.pdf_integral - kept) > 4.0 * sd + 1e-3:
            self.message += (f"\n  the pdf integrates to {self.pdf_integral:.6f} but the sampler kept a fraction "
                             f"{kept:.6f} of its samples (they should agree)")
        return False

    def _pearson(self, observed, expected, context):
        """Pooling, statistic, p-value and the message, as the C++ harness's pearson()."""
        empty = (expected == 0.0) & (observed > 0.0)
        if empty.any():
            i = int(np.argmax(empty))
            return self._fail(f"{observed[i]:.0f} sample(s) in a region with pdf 0, {self._cell_label(i)}; "
                              f"{context}")

        statistic, cells, pooled = pearson_statistic(observed, expected, self.min_expected)
        pooled_observed = float(observed[pooled].sum())
        pooled_expected = float(expected[pooled].sum())
        self.statistic = statistic
        self.dof = cells - 1
        if self.dof < 1:
            return self._fail(f"only {cells} cell(s) after pooling: the test has no power (more samples or fewer "
                              f"bins needed); {context}")
        self.p_value = chi2_sf(statistic, self.dof)
        self.passed = self.p_value >= self.threshold
        pooled_count = int(pooled.sum())
        self.message = (f"chi2 = {statistic:.2f}, dof = {self.dof}, p = {self.p_value:.4g} (passes at >= "
                        f"{self.threshold:.3g}), {pooled_count} of {expected.size} cells pooled; {context}")
        if not self.passed:
            # The worst individual cells, pooled or not: a tiny cell with many samples is the usual culprit.
            candidates = np.flatnonzero(expected > 0.0)
            contribution = (observed[candidates] - expected[candidates]) ** 2 / expected[candidates]
            worst = candidates[np.argsort(-contribution, kind="stable")[:5]]
            self.message += "\n  worst cells, by (O-E)^2/E:"
            for i in worst:
                c = (observed[i] - expected[i]) ** 2 / expected[i]
                self.message += (f"\n    {self._cell_label(int(i))}: observed {observed[i]:.0f}, expected "
                                 f"{expected[i]:.2f}, (O-E)^2/E = {c:.2f}" + (" (pooled)" if pooled[i] else ""))
            if pooled_count:
                self.message += (f"\n    pool of {pooled_count} cells: observed {pooled_observed:.0f}, expected "
                                 f"{pooled_expected:.2f}")
        return self.passed

    def __repr__(self):
        state = "not run" if self.observed is None else ("passed" if self.passed else "failed")
        return f"<ChiSquareTest {state}: {self.message.splitlines()[0] if self.message else ''}>"
