// Height from normals (Chan 2018 §4.2, Algorithm 5) and material surface occlusion (§4.3–4.5, eqs. 43–56)
// against closed forms.
#include "textures/height_from_normals.h"
#include "textures/surface_occlusion.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace kozu {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A periodic height field: a sum of sinusoids with integer periods over an n x n tile (heights in texel widths),
// with its exact gradient.
struct Wave {
  double amplitude;
  int kx, ky;
  double phase;
};
const std::vector<Wave> kWaves = {
    {6.0, 1, 0, 0.3}, {4.0, 0, 2, 1.1}, {2.0, 3, 2, 2.0}, {1.0, 5, -7, 0.7}, {0.5, 11, 13, 4.0}};

double wave_height(double x, double y, int n) {
  double h = 0;
  for (const Wave& w : kWaves) h += w.amplitude * std::sin(2 * kPi * (w.kx * x + w.ky * y) / n + w.phase);
  return h;
}

// The normal map of the waves, exact normals at texel centres, encoded as the renderer reads them (OpenGL).
std::vector<float> wave_normal_map(int n, double scale) {
  std::vector<float> rgb(size_t(n) * n * 3);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      double gx = 0, gy = 0;  // dh/dx, dh/dy (rows down)
      for (const Wave& w : kWaves) {
        const double c = scale * w.amplitude * std::cos(2 * kPi * (w.kx * x + w.ky * y) / n + w.phase) * 2 * kPi / n;
        gx += c * w.kx;
        gy += c * w.ky;
      }
      const double inv = 1 / std::sqrt(gx * gx + gy * gy + 1);
      float* c = &rgb[(size_t(y) * n + x) * 3];
      c[0] = float(0.5 * (-gx * inv + 1));
      c[1] = float(0.5 * (gy * inv + 1));  // +v is up the image
      c[2] = float(0.5 * (inv + 1));
    }
  return rgb;
}

double rms_error_of_height(const HeightField& hf, int n, double scale) {
  double mean = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) mean += scale * wave_height(x, y, n);
  mean /= double(n) * n;
  double err = 0, ref = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const double truth = scale * wave_height(x, y, n) - mean;
      const double d = hf.h[size_t(y) * n + x] - truth;
      err += d * d;
      ref += truth * truth;
    }
  return std::sqrt(err / ref);
}

TEST(HeightFromNormals, RecoversPeriodicHeightField) {
  // Slopes up to about 0.9 (scale 1) and 0.3 (scale 0.3): 3 % RMS is the bound. The trapezoid rule's own
  // error on the finest wave (period 256 / 17 texels) is (π k / n)² / 3 = 1.4 % of its amplitude 0.5, under 1e-3
  // of the RMS height (5.35), so the bound tests the solver's convergence, not the discretisation.
  const int n = 256;
  for (double scale : {1.0, 0.3}) {
    const std::vector<float> map = wave_normal_map(n, scale);
    const SlopeField g = normal_slopes(map.data(), n, n, 3);
    const HeightField hf = height_from_slopes(g);
    const double err = rms_error_of_height(hf, n, scale);
    std::printf("height from normals, %d x %d, slope scale %.1f: RMS error %.5f of the RMS height, residual %.2e\n", n,
                n, scale, err, slope_residual(g, hf));
    EXPECT_LT(err, 0.03) << "scale " << scale;
    EXPECT_LT(slope_residual(g, hf), 0.01) << "a possible map leaves no residual, scale " << scale;
    double mean = 0;
    for (float v : hf.h) mean += v;
    EXPECT_NEAR(mean / hf.h.size(), 0.0, 1e-6);
  }
}

TEST(HeightFromNormals, PaperSinglePassAlsoConvergesOnSmallMaps) {
  // Algorithm 5 as published (no correction cycles), on a non-power-of-two tile (odd sizes down the chain).
  const int n = 96;
  const std::vector<float> map = wave_normal_map(n, 0.5);
  const SlopeField g = normal_slopes(map.data(), n, n, 3);
  HeightFromNormalsOptions o;
  o.vcycles = 0;
  o.sweeps_per_level = 400;
  EXPECT_LT(rms_error_of_height(height_from_slopes(g, o), n, 0.5), 0.03);
}

TEST(HeightFromNormals, ImpossibleMapLeavesItsCurl) {
  // g = (sin(2π y / n), 0) has no divergence: no height field has any part of it, h = 0, residual 1. Half of it
  // added to a true gradient leaves a residual between.
  const int n = 64;
  SlopeField curl;
  curl.width = curl.height = n;
  curl.gx.resize(size_t(n) * n);
  curl.gy.assign(size_t(n) * n, 0.0f);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) curl.gx[size_t(y) * n + x] = float(0.3 * std::sin(2 * kPi * y / n));
  const HeightField flat = height_from_slopes(curl);
  EXPECT_NEAR(slope_residual(curl, flat), 1.0, 1e-3);
  for (float v : flat.h) EXPECT_NEAR(v, 0.0f, 1e-4f);

  const std::vector<float> map = wave_normal_map(n, 0.2);
  SlopeField mixed = normal_slopes(map.data(), n, n, 3);
  for (size_t i = 0; i < mixed.gx.size(); ++i) mixed.gx[i] += curl.gx[i];
  // The curl part's edge differences have zero discrete divergence, so they are orthogonal to every discrete
  // gradient: the residual is their share of all the edge differences (trapezoid slopes, as slope_residual takes).
  double all2 = 0, curl2 = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const size_t i = size_t(y) * n + x, right = size_t(y) * n + (x + 1) % n, down = size_t((y + 1) % n) * n + x;
      const double ex = 0.5 * (double(mixed.gx[i]) + mixed.gx[right]),
                   ey = 0.5 * (double(mixed.gy[i]) + mixed.gy[down]);
      all2 += ex * ex + ey * ey;
      curl2 += double(curl.gx[i]) * curl.gx[i];
    }
  const double residual = slope_residual(mixed, height_from_slopes(mixed));
  std::printf("curl residual of the mixed map: %.4f (its curl share %.4f)\n", residual, std::sqrt(curl2 / all2));
  EXPECT_NEAR(residual, std::sqrt(curl2 / all2), 0.01);
  EXPECT_GT(residual, 0.1);
}

HeightField spherical_dent(int n, double rim_radius, double depth) {
  // A spherical cap of rim radius a and depth d pressed into a flat plane, centred on texel (n/2, n/2).
  const double rho = (rim_radius * rim_radius + depth * depth) / (2 * depth);
  HeightField hf;
  hf.width = hf.height = n;
  hf.h.assign(size_t(n) * n, 0.0f);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const double r2 = double(x - n / 2) * (x - n / 2) + double(y - n / 2) * (y - n / 2);
      if (r2 < rim_radius * rim_radius) hf.h[size_t(y) * n + x] = float((rho - depth) - std::sqrt(rho * rho - r2));
    }
  return hf;
}

TEST(SurfaceOcclusion, SphericalPitCentreMatchesClosedForm) {
  // From the bottom of a spherical cap (rim radius a, depth d) the wall's elevation rises to the rim's,
  // atan(d / a), in every direction: the visible set is the cone of half angle π/2 - atan(d / a) about the
  // normal, whose cosine-weighted visibility (eq. 43) is sin² of that angle, a² / (a² + d²) (eq. 54). The march
  // reads heights at whole steps: along the axes it lands on the rim exactly; in other directions the last sample
  // inside the rim may be up to one step short of it, where the wall's slope s = a / sqrt(ρ² - a²) lowers the
  // horizon's tangent by up to s / a. Shallow caps (a 24, d 8: s 0.75; a 40, d 10: s 0.53) bound one direction's
  // error by 2 sin e cos e · Δe <= 0.6 · 0.031 = 0.019: tolerance 0.02. The hemisphere (a = d) is vertical at the
  // rim: one step short costs up to 8° of horizon, 0.14 of visibility in one direction; of the 16 directions 4 land
  // on texel centres and the others fall short by different fractions of a step, so we allow a third of that, 0.05.
  struct Case {
    double a, d, tolerance;
  };
  for (const Case& c : {Case{24, 8, 0.02}, Case{24, 24, 0.05}, Case{40, 10, 0.02}}) {
    const int n = 128;
    const HeightField hf = spherical_dent(n, c.a, c.d);
    OcclusionOptions o;
    o.radius = float(c.a + 8);
    const std::vector<float> v = visibility(hf, o);
    const double expected = c.a * c.a / (c.a * c.a + c.d * c.d);
    std::printf("spherical pit a %.0f d %.0f: centre visibility %.4f, closed form %.4f\n", c.a, c.d,
                v[size_t(n / 2) * n + n / 2], expected);
    EXPECT_NEAR(v[size_t(n / 2) * n + n / 2], expected, c.tolerance) << "a " << c.a << " d " << c.d;
    // Far outside the pit, on the flat plane, nothing is above the horizon.
    EXPECT_FLOAT_EQ(v[0], 1.0f);
  }
}

TEST(SurfaceOcclusion, FlatAndTiltedPlanesAreUnoccluded) {
  HeightField flat;
  flat.width = 32;
  flat.height = 16;
  flat.h.assign(32 * 16, 0.0f);
  for (float v : visibility(flat)) EXPECT_FLOAT_EQ(v, 1.0f);
  // A plane tilted along x wraps with a seam, so test the analytic slice integral directly: for any tilt γ and
  // horizons at the normal's hemisphere, the slice's share times its projected length averages to 1.
  for (double tilt : {0.0, 0.3, 1.0}) {
    double sum = 0;
    const int d = 64;
    for (int k = 0; k < d; ++k) {
      const double phi = kPi * k / d;
      const double nx = std::sin(tilt), nz = std::cos(tilt);
      const double nd = nx * std::cos(phi);
      sum += slice_visibility(std::atan2(nd, nz), std::sqrt(nd * nd + nz * nz), -kPi, kPi);
    }
    EXPECT_NEAR(sum / d, 1.0, 1e-12) << "tilt " << tilt;
  }
}

TEST(SurfaceOcclusion, SinusoidVisibilityIsBoundedAndSymmetric) {
  // Ridges along y: every texel and its mirror image across a crest see the same; troughs see less than crests.
  const int n = 64;
  HeightField hf;
  hf.width = hf.height = n;
  hf.h.resize(size_t(n) * n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) hf.h[size_t(y) * n + x] = float(4 * std::cos(2 * kPi * x / 16));
  const std::vector<float> v = visibility(hf);
  for (float a : v) {
    EXPECT_GE(a, 0.0f);
    EXPECT_LE(a, 1.0f);
  }
  EXPECT_NEAR(v[3], v[13], 1e-5);  // mirror about the crest x = 0 (period 16)
  EXPECT_LT(v[8], v[0]);           // trough below crest
  EXPECT_NEAR(v[0], 1.0, 1e-6);    // a crest sees its whole hemisphere
}

// Eq. (43) by brute force: the cosine-weighted hemisphere about the texel's normal (the same central-difference
// normal visibility() uses) on a fine grid of directions, each a ray marched through the bilinear height field in
// quarter-texel steps until it leaves the radius or rises above the map's highest point.
double reference_visibility(const HeightField& hf, int x, int y, double radius) {
  auto at = [&](double px, double py) {
    const int x0 = int(std::floor(px)), y0 = int(std::floor(py));
    const double tx = px - x0, ty = py - y0;
    auto h = [&](int i, int j) {
      return double(hf.h[size_t(((j % hf.height) + hf.height) % hf.height) * hf.width +
                         size_t(((i % hf.width) + hf.width) % hf.width)]);
    };
    return (1 - ty) * ((1 - tx) * h(x0, y0) + tx * h(x0 + 1, y0)) +
           ty * ((1 - tx) * h(x0, y0 + 1) + tx * h(x0 + 1, y0 + 1));
  };
  double top = -1e30;
  for (float v : hf.h) top = std::max(top, double(v));
  const double z0 = at(x, y);
  const double gx = 0.5 * (at(x + 1, y) - at(x - 1, y)), gy = 0.5 * (at(x, y + 1) - at(x, y - 1));
  const double inv = 1 / std::sqrt(gx * gx + gy * gy + 1);
  const double n[3] = {-gx * inv, -gy * inv, inv};
  // A frame about n.
  double t[3] = {n[2], 0, -n[0]};
  const double tl = std::sqrt(t[0] * t[0] + t[2] * t[2]);
  for (double& c : t) c /= tl;
  const double b[3] = {n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0]};
  const int np = 256, nr = 96;
  int visible = 0;
  for (int i = 0; i < nr; ++i)
    for (int j = 0; j < np; ++j) {
      // Cosine-weighted: the unit disk's equal-area cells lifted to the hemisphere (Nusselt), each of weight 1 / N.
      const double r = std::sqrt((i + 0.5) / nr), phi = 2 * kPi * (j + 0.5) / np;
      const double lx = r * std::cos(phi), ly = r * std::sin(phi), lz = std::sqrt(std::max(0.0, 1 - r * r));
      const double d[3] = {lx * t[0] + ly * b[0] + lz * n[0], lx * t[1] + ly * b[1] + lz * n[1],
                           lx * t[2] + ly * b[2] + lz * n[2]};
      const double horizontal = std::sqrt(d[0] * d[0] + d[1] * d[1]);
      bool hit = false;
      for (double s = 0.25; !hit; s += 0.25 / std::max(horizontal, 0.25)) {
        const double px = x + s * d[0], py = y + s * d[1], pz = z0 + s * d[2];
        if (s * horizontal > radius || pz > top) break;
        hit = at(px, py) > pz;
      }
      visible += hit ? 0 : 1;
    }
  return double(visible) / (np * nr);
}

TEST(SurfaceOcclusion, HorizonsMatchBruteForceVisibility) {
  // Where each slice's visible set is one arc (a ridge field, a spherical dent off its centre), the horizon-based
  // estimate is eq. (43) itself: what is left is the slice quadrature (D directions) and where the march reads
  // heights; with quarter-texel steps in both and D = 64 the two agree to the reference grid's resolution
  // (96 x 256 directions: about 0.005 from the cells the horizon cuts).
  const int n = 64;
  HeightField ridges;
  ridges.width = ridges.height = n;
  ridges.h.resize(size_t(n) * n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) ridges.h[size_t(y) * n + x] = float(2 * std::cos(2 * kPi * x / 16));
  const HeightField dent = spherical_dent(n, 20, 10);
  OcclusionOptions o;
  o.radius = 24;
  o.directions = 64;
  o.step = 0.25f;
  // The defaults (whole-texel steps, D = 16) trade accuracy for speed: their difference is printed and bounded
  // by the step bound of SphericalPitCentreMatchesClosedForm (0.02 where walls are no steeper than 1).
  const OcclusionOptions defaults{1.0f, 24.0f, 16, 1.0f};
  double worst = 0, worst_default = 0;
  for (const HeightField* hf : std::vector<const HeightField*>{&ridges, &dent}) {
    const std::vector<float> v = visibility(*hf, o), vd = visibility(*hf, defaults);
    for (int x : {32, 36, 38, 40, 44, 48}) {
      const int y = hf == &ridges ? 5 : 35;
      const size_t i = size_t(y) * n + x;
      const double ref = reference_visibility(*hf, x, y, o.radius);
      worst = std::max(worst, std::abs(v[i] - ref));
      worst_default = std::max(worst_default, std::abs(vd[i] - ref));
      EXPECT_NEAR(v[i], ref, 0.005) << (hf == &ridges ? "ridges" : "dent") << " x " << x;
      EXPECT_NEAR(vd[i], ref, 0.02) << (hf == &ridges ? "ridges" : "dent") << " x " << x << " (defaults)";
    }
  }
  std::printf("horizon-based vs brute-force visibility: largest difference %.4f (D 64, step 1/4), %.4f (defaults)\n",
              worst, worst_default);
}

TEST(SurfaceOcclusion, InterreflectionAdjustment) {
  // Eq. (49) is the fixed point of "the occluded directions send back the point's own radiance": A' = A + (1 - A) ρ A'.
  for (double a : {0.0, 0.3, 0.8, 1.0})
    for (double rho : {0.0, 0.5, 0.9}) {
      const double ap = adjusted_visibility(a, rho);
      EXPECT_NEAR(ap, a + (1 - a) * rho * ap, 1e-12);
      EXPECT_GE(ap, a);
      EXPECT_LE(ap, 1.0);
    }
  EXPECT_DOUBLE_EQ(adjusted_visibility(0.4, 0.0), 0.4);  // black occluders change nothing
  EXPECT_DOUBLE_EQ(adjusted_visibility(0.4, 0.7, OcclusionAdjustment::Black), 0.4);
  EXPECT_DOUBLE_EQ(adjusted_visibility(0.4, 0.7, OcclusionAdjustment::WhiteOccluded), 0.4 * 0.6 + 0.4);
  EXPECT_DOUBLE_EQ(adjusted_visibility(0.4, 0.7, OcclusionAdjustment::SameAlbedo), 0.7 * 0.6 + 0.4);
  EXPECT_DOUBLE_EQ(adjusted_visibility(0.4, 0.7, OcclusionAdjustment::SameAlbedoOccluded), 0.7 * 0.4 * 0.6 + 0.4);
}

TEST(SurfaceOcclusion, EqualAreaCone) {
  // A cone of half angle θ about the normal has cosine-weighted visibility (1/π)∫ cos over it = sin²θ: integrate
  // it numerically and convert back (eqs. 50–56).
  for (double theta : {0.1, 0.5, 0.9, 1.3, kPi / 2}) {
    const int steps = 20000;
    double v = 0;
    for (int i = 0; i < steps; ++i) {
      const double t = (i + 0.5) * theta / steps;
      v += 2 * kPi * std::cos(t) * std::sin(t) * theta / steps;  // ∫ cos θ dω over the cone
    }
    v /= kPi;
    EXPECT_NEAR(v, std::sin(theta) * std::sin(theta), 1e-6);
    EXPECT_NEAR(cone_cos(v), std::cos(theta), 1e-4);
    EXPECT_NEAR(cone_visibility(cone_cos(v)), std::min(v, 1.0), 1e-12);
  }
  EXPECT_DOUBLE_EQ(cone_cos(1.0), 0.0);  // unoccluded: the whole hemisphere
  EXPECT_DOUBLE_EQ(cone_cos(0.0), 1.0);  // fully occluded: a cone of angle 0
  // The hemispherical pit's centre sees V = 1/2: the cone of 45°.
  EXPECT_NEAR(std::acos(cone_cos(0.5)), kPi / 4, 1e-12);
}

}  // namespace
}  // namespace kozu
