// Linearly transformed cosines (lights/ltc.h): eq. (1) integrates to 1 for random M (eq. 2); sampling against its
// own pdf (chi-square); the polygon integral of eqs. (3) and (11), with clipping, against a direct quadrature of
// D over the planar polygon for random polygons and matrices, horizon-crossing ones included.
#include "core/ltc.h"
#include "lights/ltc_polygon_sampler.h"

#include "core/frame.h"
#include "core/gauss_legendre.h"
#include "core/rng.h"
#include "support/chi2.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace kozu::test {
namespace {

// A random well-conditioned matrix: 1.5 I plus entries in [-1, 1], |det| >= 0.3.
Mat3 random_matrix(Pcg32& rng) {
  for (;;) {
    Mat3 m(1.5f);
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) m[c][r] += 2.0f * rng.next_float() - 1.0f;
    if (std::abs(glm::determinant(m)) >= 0.3f) return m;
  }
}

TEST(Ltc, NormalizedForRandomMatrices) {
  Pcg32 rng(7);
  for (int i = 0; i < 8; ++i) {
    const Ltc ltc(random_matrix(rng));
    // D's horizon (M⁻¹ω)_z = 0 is a great circle across the cells: a kink the 8x8-point cells resolve to O(h²).
    const double norm = integrate_pdf_over_sphere([&](const Vec3& w) { return double(ltc.eval(w)); }, 128);
    EXPECT_NEAR(norm, 1.0, 2e-4) << "matrix " << i;
  }
}

TEST(Ltc, SamplingMatchesEval) {
  Pcg32 rng(11);
  const int kTests = 6;
  for (int i = 0; i < kTests; ++i) {
    const Ltc ltc = i == 0 ? Ltc() : Ltc(random_matrix(rng));
    Chi2Options o;
    o.seed = 100 + static_cast<uint64_t>(i);
    o.test_count = kTests;
    o.check_lost_mass = false;  // D's horizon crosses the cells: the quadrature resolves it to ~1e-4 only
    const Chi2Result r = chi2_test([&](const Vec2& u) -> std::optional<Vec3> { return ltc.sample(u); },
                                   [&](const Vec3& w) { return double(ltc.pdf(w)); }, o);
    EXPECT_TRUE(r.passed) << "matrix " << i << ": " << r.message;
  }
}

// The part of a planar polygon where D is non-zero, (M⁻¹x)_z >= 0: a half-space through the origin, so the part
// is planar and convex again. Clipping here, in world space and double, keeps D's kink out of the quadrature's
// panels (a sliver above the horizon otherwise needs ~512 panels for 1e-4) and is independent of ltc.cpp's
// clipping in the cosine's space.
std::vector<Vec3d> clip_to_support(const Ltc& ltc, const std::vector<Vec3>& poly) {
  const glm::dmat3 m_inv(ltc.m_inv());
  std::vector<Vec3d> out;
  for (size_t i = 0; i < poly.size(); ++i) {
    const Vec3d a(poly[i]), b(poly[(i + 1) % poly.size()]);
    const double ha = (m_inv * a).z, hb = (m_inv * b).z;
    if (ha >= 0.0) out.push_back(a);
    if ((ha < 0.0) != (hb < 0.0)) out.push_back(a + (b - a) * (ha / (ha - hb)));
  }
  return out;
}

// ∫_P g dω by Gauss–Legendre on the planar polygon clipped to D's support (a fan of triangles, each mapped from
// the unit square by Duffy's map, 32 x 32 panels of 6 x 6 points): dω = |n · x̂| / |x|² dA. Independent of
// eqs. (3) and (11). g defaults to D.
template <class G>
double quadrature_over_polygon(const Ltc& ltc, const std::vector<Vec3>& polygon, const G& g) {
  const std::vector<Vec3d> poly = clip_to_support(ltc, polygon);
  const GaussLegendre gl(6);
  const int panels = 32;
  double sum = 0.0;
  for (size_t k = 1; k + 1 < poly.size(); ++k) {
    const Vec3d a = poly[0], e1 = poly[k] - a, e2 = poly[k + 1] - a;
    const Vec3d cr = glm::cross(e1, e2);
    const double area2 = glm::length(cr);
    if (area2 == 0.0) continue;
    const Vec3d n = cr / area2;
    for (int pu = 0; pu < panels; ++pu)
      for (int pv = 0; pv < panels; ++pv)
        for (size_t i = 0; i < gl.x.size(); ++i)
          for (size_t j = 0; j < gl.x.size(); ++j) {
            const double u = (pu + 0.5 * (gl.x[i] + 1.0)) / panels, v = (pv + 0.5 * (gl.x[j] + 1.0)) / panels;
            const double w = gl.w[i] * gl.w[j] * 0.25 / (panels * panels);
            const Vec3d x = a + u * e1 + v * (1.0 - u) * e2;  // Duffy: Jacobian (1 - u) |e1 × e2|
            const double r2 = glm::dot(x, x);
            const Vec3d d = x / std::sqrt(r2);
            sum += w * (1.0 - u) * area2 * double(g(Vec3(d))) * std::abs(glm::dot(n, d)) / r2;
          }
  }
  return sum;
}
double quadrature_over_polygon(const Ltc& ltc, const std::vector<Vec3>& polygon) {
  return quadrature_over_polygon(ltc, polygon, [&](const Vec3& w) { return ltc.eval(w); });
}

// Three uniform numbers in a fixed order (a constructor's arguments are evaluated in an order the compiler
// chooses: GCC and clang differ, and so would the test's polygons).
Vec3 next_vec3(Pcg32& rng) {
  const float x = rng.next_float();
  const float y = rng.next_float();
  return Vec3(x, y, rng.next_float());
}

// A convex polygon of n corners on an ellipse about centre c in a random plane.
std::vector<Vec3> random_polygon(Pcg32& rng, int n, const Vec3& c) {
  const Frame f(glm::normalize(next_vec3(rng) - Vec3(0.5f)));
  const float ra = 0.3f + 0.7f * rng.next_float();
  const float rb = 0.3f + 0.7f * rng.next_float();
  std::vector<Vec3> p;
  const float phase = kTwoPi * rng.next_float();
  for (int i = 0; i < n; ++i) {
    const float phi = phase + kTwoPi * (static_cast<float>(i) + 0.3f * rng.next_float()) / static_cast<float>(n);
    p.push_back(c + ra * std::cos(phi) * f.s + rb * std::sin(phi) * f.t);
  }
  return p;
}

TEST(Ltc, PolygonIntegralMatchesQuadrature) {
  Pcg32 rng(23);
  int clipped = 0;
  double worst = 0.0;
  for (int i = 0; i < 80; ++i) {
    const Ltc ltc = i % 5 == 0 ? Ltc() : Ltc(random_matrix(rng));
    const int n = 3 + i % 6;
    // Centres from high above to below the horizon of D: some polygons cross it, some lie wholly behind.
    const Vec3 c = Vec3(3.0f, 3.0f, -2.0f) * next_vec3(rng) + Vec3(-1.5f, -1.5f, 1.0f);
    if (glm::length(c) < 1.2f) continue;  // keep the shading point off the polygon
    const std::vector<Vec3> poly = random_polygon(rng, n, c);
    bool crosses = false;
    for (const Vec3& v : poly) crosses |= (ltc.m_inv() * v).z < 0.0f;
    clipped += crosses;
    const double exact = quadrature_over_polygon(ltc, poly);
    const double closed = ltc.integrate_polygon(poly);
    const double err = std::abs(closed - exact) / std::max(exact, 1e-3);
    worst = std::max(worst, err);
    EXPECT_LT(err, 1e-4) << fmt::format("polygon {} ({} corners{}): closed form {:.7f}, quadrature {:.7f}", i, n,
                                        crosses ? ", clipped" : "", closed, exact);
  }
  std::printf("worst relative error %.2e; %d polygons crossed D's horizon\n", worst, clipped);
  EXPECT_GE(clipped, 15);
}

// Why the edge terms are in double: eq. (11) as written (acos of the dot product), in float, against the closed
// form in double, for a square of side s facing the shading point 10 units away. Its integral is close to
// s² / (100 π) (small solid angle s²/100 at the pole of D_o = 1/π).
float eq11_in_float(const std::vector<Vec3>& p) {
  float sum = 0.0f;
  for (size_t i = 0; i < p.size(); ++i) {
    const Vec3 a = glm::normalize(p[i]), b = glm::normalize(p[(i + 1) % p.size()]);
    const Vec3 x = glm::cross(a, b);
    sum += std::acos(std::clamp(glm::dot(a, b), -1.0f, 1.0f)) * x.z / glm::length(x);
  }
  return std::abs(sum) / kTwoPi;
}

TEST(Ltc, SmallDistantPolygonsNeedDouble) {
  const Ltc ltc;
  for (float side : {1.0f, 0.1f, 0.01f, 0.001f}) {
    const float h = side / 2;
    const std::vector<Vec3> sq = {{-h, -h, 10}, {h, -h, 10}, {h, h, 10}, {-h, h, 10}};
    const double approx = double(side) * side / (100.0 * kPi);  // exact to O(side² / 100)
    const double closed = ltc.integrate_polygon(sq);
    const double naive = eq11_in_float(sq);
    std::printf("square of side %g at distance 10: closed form rel. error %.1e, float acos form %.1e\n", side,
                std::abs(closed / approx - 1.0), std::abs(naive / approx - 1.0));
    EXPECT_NEAR(closed / approx, 1.0, 1e-5 + 2.0 * double(side) * side / 100.0) << "side " << side;
  }
}

TEST(Ltc, PolygonWindingAndDegenerateCases) {
  const Ltc ltc;
  std::vector<Vec3> quad = {{-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}};
  const float ccw = ltc.integrate_polygon(quad);
  std::reverse(quad.begin(), quad.end());
  EXPECT_FLOAT_EQ(ltc.integrate_polygon(quad), ccw);
  // Lambert's form factor of a square [-1, 1]² at height 1 seen from below its centre: 4 (1/(2π)) 2 atan(1/√2)/√2.
  EXPECT_NEAR(ccw, 4.0 / (2.0 * kPi) * (1.0 / std::sqrt(2.0)) * std::atan(1.0 / std::sqrt(2.0)) * 2.0, 1e-6);
  // Wholly behind the horizon; a corner at the shading point; a sliver.
  EXPECT_EQ(ltc.integrate_polygon(std::vector<Vec3>{{0, 0, -1}, {1, 0, -1}, {0, 1, -1}}), 0.0f);
  EXPECT_EQ(ltc.integrate_polygon(std::vector<Vec3>{{0, 0, 0}, {1, 0, 1}, {0, 1, 1}}), 0.0f);
  const float sliver = ltc.integrate_polygon(std::vector<Vec3>{{0, 0, 1}, {1e-4f, 0, 1}, {0, 1e-4f, 1}});
  EXPECT_NEAR(sliver, 0.5e-8 / kPi, 1e-3 * 0.5e-8 / kPi);  // area / π at the pole
}

// The fan triangulation of a convex polygon, as PolygonLight keeps it.
std::vector<std::array<Vec3, 3>> fan(const std::vector<Vec3>& poly) {
  std::vector<std::array<Vec3, 3>> t;
  for (size_t k = 1; k + 1 < poly.size(); ++k) t.push_back({poly[0], poly[k], poly[k + 1]});
  return t;
}

// The polygon-restricted sampler's density is a density on P: its integral over P (by the quadrature above,
// independent of the sampler's own solid angles) is 1, for polygons of 3–8 corners, some across D's horizon.
TEST(LtcPolygonSampler, DensityIntegratesToOneOverThePolygon) {
  Pcg32 rng(31);
  int tested = 0, clipped = 0;
  double worst = 0.0;
  for (int i = 0; i < 120; ++i) {
    const Ltc ltc = i % 5 == 0 ? Ltc() : Ltc(random_matrix(rng));
    const int n = 3 + i % 6;
    const Vec3 c = Vec3(3.0f, 3.0f, -2.0f) * next_vec3(rng) + Vec3(-1.5f, -1.5f, 1.0f);
    if (glm::length(c) < 1.2f) continue;
    const std::vector<Vec3> poly = random_polygon(rng, n, c);
    const LtcPolygonSampler sampler(ltc, fan(poly));
    if (!sampler.valid()) continue;  // wholly behind D's horizon
    bool crosses = false;
    for (const Vec3& v : poly) crosses |= (ltc.m_inv() * v).z < 0.0f;
    clipped += crosses;
    ++tested;
    const double integral = quadrature_over_polygon(ltc, poly, [&](const Vec3& w) { return sampler.pdf(w); });
    worst = std::max(worst, std::abs(integral - 1.0));
    EXPECT_NEAR(integral, 1.0, 1e-4) << fmt::format("polygon {} ({} corners{}), solid angle {:.4f}", i, n,
                                                    crosses ? ", clipped" : "", sampler.solid_angle());
  }
  std::printf("%d polygons (%d clipped): worst |integral - 1| %.2e\n", tested, clipped, worst);
  EXPECT_GE(tested, 30);
  EXPECT_GE(clipped, 10);
}

// Chi-square of the sampled directions against the density, over the points of a parallelogram p0 + a e1 + b e2
// ((a, b) in [0, 1]², so no cell straddles the light's edge), with the density per unit (a, b):
// p(ω) |cos θ_l| |e1 × e2| / r². Some parallelograms cross D's horizon (the density drops to 0 along a line).
TEST(LtcPolygonSampler, SamplesMatchTheDensity) {
  Pcg32 rng(37);
  const int kTests = 8;
  int clipped = 0;
  for (int i = 0; i < kTests; ++i) {
    const Ltc ltc = i == 0 ? Ltc() : Ltc(random_matrix(rng));
    Vec3 p0, e1, e2;
    std::vector<Vec3> quad;
    for (;;) {  // a parallelogram D sees, off the shading point
      const Vec3 c = Vec3(2.0f, 2.0f, -1.0f) * next_vec3(rng) + Vec3(-1.0f, -1.0f, 0.8f);
      if (glm::length(c) < 1.0f) continue;
      const Frame f(glm::normalize(next_vec3(rng) - Vec3(0.5f)));
      e1 = (0.4f + 0.8f * rng.next_float()) * f.s;
      e2 = (0.4f + 0.8f * rng.next_float()) * glm::normalize(f.t + (rng.next_float() - 0.5f) * f.s);
      p0 = c - 0.5f * (e1 + e2);
      quad = {p0, p0 + e1, p0 + e1 + e2, p0 + e2};
      if (LtcPolygonSampler(ltc, fan(quad)).solid_angle() > 0.05) break;
    }
    bool crosses = false;
    for (const Vec3& v : quad) crosses |= (ltc.m_inv() * v).z < 0.0f;
    clipped += crosses;
    const LtcPolygonSampler sampler(ltc, fan(quad));
    const Vec3d n = glm::cross(Vec3d(e1), Vec3d(e2));
    const double area = glm::length(n);
    // (a, b) where the ray along w meets the parallelogram's plane.
    const auto coordinates = [&](const Vec3& w) {
      const double t = glm::dot(n, Vec3d(p0)) / glm::dot(n, Vec3d(w));
      const Vec3d d = t * Vec3d(w) - Vec3d(p0);
      return Vec2(static_cast<float>(glm::dot(glm::cross(d, Vec3d(e2)), n) / (area * area)),
                  static_cast<float>(glm::dot(glm::cross(Vec3d(e1), d), n) / (area * area)));
    };
    int off = 0;
    Chi2Options o;
    o.seed = 300 + static_cast<uint64_t>(i);
    o.test_count = kTests;
    o.integration_points = 16;
    o.check_lost_mass = false;  // the horizon's line crosses cells of the clipped ones
    const Chi2Result r = chi2_test_2d(
        [&](const Vec2& u) -> std::optional<Vec2> {
          const Vec2 ab = coordinates(sampler.sample(u));
          off += !(ab.x > -1e-4f && ab.x < 1.0001f && ab.y > -1e-4f && ab.y < 1.0001f);
          return glm::clamp(ab, Vec2(0.0f), Vec2(kOneMinusEpsilon));
        },
        [&](const Vec2& ab) -> double {
          const Vec3d x = Vec3d(p0) + double(ab.x) * Vec3d(e1) + double(ab.y) * Vec3d(e2);
          const double r2 = glm::dot(x, x);
          const Vec3 w(x / std::sqrt(r2));
          return double(sampler.pdf(w)) * std::abs(glm::dot(n, Vec3d(w))) / r2;
        },
        Chi2Grid2D{}, o);
    EXPECT_TRUE(r.passed) << "parallelogram " << i << (crosses ? " (clipped)" : "") << ": " << r.message;
    EXPECT_NEAR(r.pdf_integral, 1.0, 2e-3) << "parallelogram " << i;
    EXPECT_EQ(off, 0) << "parallelogram " << i << ": samples off the light";
  }
  EXPECT_GE(clipped, 2);
}

}  // namespace
}  // namespace kozu::test
