// Ray cones (geometry/ray_cone.h): the spread after a mirror or a refraction on a sphere against the two edge rays
// of the cone traced exactly, the mesh curvature from vertex normals, and the widening after a rough bounce
// against the width of kozu's GGX lobe, measured by sampling it.
#include "geometry/ray_cone.h"
#include "geometry/shape.h"
#include "materials/conductor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace kozu::test {
namespace {

struct D2 {
  double x, z;
};
D2 operator+(D2 a, D2 b) { return {a.x + b.x, a.z + b.z}; }
D2 operator-(D2 a, D2 b) { return {a.x - b.x, a.z - b.z}; }
D2 operator*(double s, D2 a) { return {s * a.x, s * a.z}; }
double dot(D2 a, D2 b) { return a.x * b.x + a.z * b.z; }

// The two edge rays of a cone of width w and full spread gamma whose axis runs along dir_z (±1, along z) and crosses
// z = r at x = 0; each is traced to the circle of radius r about the origin (from outside: the nearer root; from
// inside: the farther), reflected or refracted there exactly (relative IOR eta), and the signed full angle between
// the leaving rays returned (> 0: they diverge).
double traced_spread(double r, double w, double gamma, double dir_z, bool reflect, double eta) {
  double leaving[2];
  for (int side = 0; side < 2; ++side) {
    const double s = side == 0 ? 1.0 : -1.0;
    const D2 d{s * std::sin(gamma / 2), dir_z * std::cos(gamma / 2)};
    const D2 o = D2{s * w / 2, r} - 3.0 * r * d;  // back along the ray, far enough to start outside or inside
    const double b = dot(o, d), c = dot(o, o) - r * r, disc = std::sqrt(b * b - c);
    const double t = dir_z < 0 ? -b - disc : -b + disc;
    const D2 p = o + t * d;
    D2 n = (1.0 / r) * p;
    if (dot(n, d) > 0) n = -1.0 * n;  // against the ray
    D2 out;
    if (reflect) {
      out = d - 2.0 * dot(d, n) * n;
    } else {
      const double cos_i = -dot(d, n), sin2_t = (1 - cos_i * cos_i) / (eta * eta);
      out = (1 / eta) * d + (cos_i / eta - std::sqrt(1 - sin2_t)) * n;
    }
    // The angle away from the axis, outward positive; the axis leaves along +z after a reflection at normal
    // incidence, along dir_z after a refraction.
    const double axis_z = reflect ? -dir_z : dir_z;
    leaving[side] = s * std::atan2(out.x, axis_z * out.z);
  }
  return leaving[0] + leaving[1];
}

TEST(RayCone, MirrorSpreadMatchesTracedEdgeRays) {
  const double r = 2.0;
  for (double gamma : {0.0, 0.004, -0.003})
    for (double w : {1e-3, 4e-3})
      for (double dir_z : {-1.0, 1.0}) {  // from outside (convex, kappa = 1/r) and inside (concave)
        const float kappa = static_cast<float>(dir_z < 0 ? 1 / r : -1 / r);
        const RayCone cone = RayCone{0.0f, static_cast<float>(gamma)}.reflected(static_cast<float>(w), kappa);
        const double expected = traced_spread(r, w, gamma, dir_z, true, 1.0);
        EXPECT_NEAR(cone.spread, expected, 1e-3 * std::abs(expected) + 1e-7)
            << "gamma " << gamma << " w " << w << " dir_z " << dir_z;
      }
}

TEST(RayCone, RefractionSpreadMatchesTracedEdgeRays) {
  const double r = 2.0;
  for (double gamma : {0.0, 0.004, -0.003})
    for (double w : {1e-3, 4e-3})
      for (double dir_z : {-1.0, 1.0}) {  // into glass from outside; out of glass from inside
        const double eta = dir_z < 0 ? 1.5 : 1 / 1.5;
        const float kappa = static_cast<float>(dir_z < 0 ? 1 / r : -1 / r);
        const RayCone cone =
            RayCone{0.0f, static_cast<float>(gamma)}.refracted(static_cast<float>(w), kappa, static_cast<float>(eta));
        const double expected = traced_spread(r, w, gamma, dir_z, false, eta);
        EXPECT_NEAR(cone.spread, expected, 1e-3 * std::abs(expected) + 1e-7)
            << "gamma " << gamma << " w " << w << " dir_z " << dir_z;
      }
}

TEST(RayCone, WidthGrowsLinearlyThroughAFocus) {
  const RayCone c{0.02f, -0.01f};
  EXPECT_FLOAT_EQ(c.width_at(0.0f), 0.02f);
  EXPECT_FLOAT_EQ(c.width_at(1.0f), 0.01f);
  EXPECT_FLOAT_EQ(c.width_at(2.0f), 0.0f);
  EXPECT_FLOAT_EQ(c.width_at(3.0f), 0.01f);
}

// An octahedron on a sphere of radius 2 with the sphere's normals: every edge gives 1/r exactly. Wound the other
// way its front side looks inwards, where the surface is concave.
TEST(RayCone, LeavesAWidthRangeWhereTheWidthCrossesItsEnds) {
  // |0.2 + 0.8 t| reaches 1 at t = 1; |1.5 − 1.5 t| falls below 1 at t = 1/3, passes the focus at t = 1 and
  // reaches 1 again at t = 5/3; a cone of constant width never leaves.
  EXPECT_FLOAT_EQ((RayCone{0.2f, 0.8f}.leaves(0.0f, 0.0f, 1.0f)), 1.0f);
  const RayCone converging{1.5f, -1.5f};
  EXPECT_FLOAT_EQ(converging.leaves(0.0f, 1.0f, kInfinity), 1.0f / 3.0f);
  EXPECT_FLOAT_EQ(converging.leaves(0.5f, 0.0f, 1.0f), 5.0f / 3.0f);  // the focus (width 0) stays in [0, 1)
  EXPECT_FLOAT_EQ(converging.leaves(0.5f, 0.25f, 1.0f), 5.0f / 6.0f);
  EXPECT_EQ((RayCone{0.5f, 0.0f}.leaves(0.0f, 0.0f, 1.0f)), kInfinity);
  // Only crossings after t0 count.
  EXPECT_EQ((RayCone{0.2f, 0.8f}.leaves(2.0f, 1.0f, kInfinity)), kInfinity);
}

TEST(RayCone, MeshCurvatureFromVertexNormals) {
  const std::vector<Vec3> p = {{2, 0, 0}, {-2, 0, 0}, {0, 2, 0}, {0, -2, 0}, {0, 0, 2}, {0, 0, -2}};
  std::vector<uint32_t> outward;
  for (uint32_t x : {0u, 1u})
    for (uint32_t y : {2u, 3u})
      for (uint32_t z : {4u, 5u}) {
        const bool flip = (x == 1) ^ (y == 3) ^ (z == 5);  // keep counter-clockwise seen from outside
        outward.insert(outward.end(), {x, flip ? z : y, flip ? y : z});
      }
  std::vector<uint32_t> inward = outward;
  for (size_t i = 0; i < inward.size(); i += 3) std::swap(inward[i + 1], inward[i + 2]);
  std::vector<Vec3> n;
  for (const Vec3& v : p) n.push_back(v / 2.0f);
  for (bool out : {true, false}) {
    const TriangleMesh mesh(p, out ? outward : inward, n);
    const TriangleMesh flat(p, out ? outward : inward);
    for (uint32_t prim = 0; prim < 8; ++prim) {
      SurfaceInteraction si;
      si.prim = prim;
      const Vec3 a = mesh.triangle_vertex(prim, 0), b = mesh.triangle_vertex(prim, 1),
                 c = mesh.triangle_vertex(prim, 2);
      si.ng = glm::normalize(glm::cross(b - a, c - a));
      ASSERT_EQ(glm::dot(si.ng, a + b + c) > 0.0f, out) << "winding of face " << prim;
      EXPECT_NEAR(mesh.curvature(si), out ? 0.5f : -0.5f, 1e-6f) << "face " << prim;
      EXPECT_EQ(flat.curvature(si), 0.0f);
    }
  }
}

// A rough bounce widens the cone by the solid angle 1/p a sampled direction stands for. For a GGX lobe at normal
// incidence the cone from the peak density p = 1/(4 pi alpha^2) has half-angle acos(1 - 2 alpha^2) ~ 2 alpha,
// and half of the lobe's reflected directions lie within 2 atan(alpha) of the mirror direction: the two agree to
// O(alpha^2). Measured here on kozu's sampled lobe (the median angle of 10^5 samples).
TEST(RayCone, RoughBounceWidensByTheLobesWidth) {
  const ConductorFresnel fresnel;  // F = 1
  const Vec3 wo(0, 0, 1);
  for (float alpha : {0.02f, 0.05f, 0.1f}) {
    const RoughConductorBsdf bsdf(MicrofacetDistribution(MicrofacetType::GGX, alpha, alpha), &fresnel, nullptr);
    std::vector<float> angles;
    const int n = 100000;
    for (int i = 0; i < n; ++i) {
      // A stratified grid: the median of 10^5 strata is exact to far below the tolerance.
      const Vec2 u((static_cast<float>(i % 400) + 0.5f) / 400.0f, (static_cast<float>(i / 400) + 0.5f) / 250.0f);
      const BsdfSample s = bsdf.sample(wo, 0.5f, u, TransportMode::Radiance);
      if (s.valid()) angles.push_back(std::acos(std::clamp(s.wi.z, -1.0f, 1.0f)));
    }
    ASSERT_GT(angles.size(), size_t(n * 0.99));
    std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
    const float median = angles[angles.size() / 2];
    const float half_cone = RayCone{}.scattered(0.0f, bsdf.pdf(wo, wo)).spread / 2.0f;
    std::printf("alpha %.2f: lobe median angle %.5f, cone half-angle %.5f\n", alpha, median, half_cone);
    EXPECT_NEAR(half_cone, median, 0.01f * median) << "alpha " << alpha;
    // N paths per pixel: each stands for 1/N of the solid angle.
    const float half_cone_16 = RayCone{}.scattered(0.0f, bsdf.pdf(wo, wo), 16.0f).spread / 2.0f;
    EXPECT_NEAR(half_cone_16, median / 4.0f, 0.01f * median) << "alpha " << alpha;
  }
}

TEST(RayCone, LobeSpreadIsTheConeOfTheSampleSolidAngle) {
  // The full angle γ whose cone holds the solid angle 1/p: 2π (1 − cos(γ/2)) = 1/p, in double by std::acos, against
  // the polynomial the renderer uses, from hemisphere-wide lobes to a near-mirror's (densities 0.01 to 10^9).
  double worst = 0, worst_density = 0;
  for (double log_p = -2.0; log_p <= 9.0; log_p += 1.0 / 64.0) {
    const double p = std::pow(10.0, log_p);
    const double one_minus_c = 1.0 / (2.0 * kPi * p);
    const double exact = one_minus_c >= 1.0 ? kPi : 2.0 * std::acos(1.0 - one_minus_c);
    const double err = std::abs(RayCone::lobe_spread(static_cast<float>(p)) - exact) / exact;
    if (err > worst) worst = err, worst_density = p;
  }
  std::printf("lobe_spread: largest relative error %.3g, at density %.3g\n", worst, worst_density);
  // A&S 4.4.45's relative error tends to 4.8e-5 as c → 1 (its coefficients sum to 1.4141461, not √2).
  EXPECT_LT(worst, 1e-4) << "relative, at density " << worst_density;
  EXPECT_EQ(RayCone::lobe_spread(0.0f), kPi);
  EXPECT_EQ(RayCone::lobe_spread(std::nanf("")), kPi);
}

}  // namespace
}  // namespace kozu::test
