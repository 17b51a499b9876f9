// The SGGX microflake module (media/sggx.h), for random S built from random rotations and projected areas:
// surface-like (two small σ: a disk-shaped ellipsoid), fiber-like (one small σ: a cylinder) and general.
//   - σ(ω) against ∫⟨ω, ωm⟩ D(ωm) dωm (eq. 4 vs eq. 11), VNDF normalisation (eq. 22), ∫ f_p = 1 (eq. 7) for
//     the specular phase, reciprocity (eq. 8);
//   - chi-square (Šidák-corrected family) of sample_visible, of the specular phase's sampling and of the
//     diffuse phase's sampling against the exact eq. 25;
//   - the stochastic diffuse evaluation (eq. 26) against a high-order quadrature of eq. 25, its normalisation
//     and reciprocity (statistical, 5 standard errors), and the MIS proxy's normalisation and positivity;
//   - estimation (eq. 17–18) round trips, compact storage (eq. 19–20) error bounds, lerp / MIP averages SPD;
//   - the float kernels at the limits (SggxThin rows: a surface and a fiber at roughness 1e-3, S's float rounding
//     taken into the reference), and the diffuse MIS proxy's per-wo cache against its definition.
//
// Quadrature. D is very peaked for thin distributions, so every integral over micronormals is taken in the
// ellipsoid's parameter space: with A = S^{1/2}, ωm = (Au)/|Au| maps the unit sphere onto itself with Jacobian
// dωm/du = |A| / |Au|³, so ∫ g(ωm) dωm = ∫ g(ωm(u)) |A|/|Au|³ du, with a smooth integrand in u if D is right.
// The clamp ⟨ω, ωm⟩ > 0 is u·(Aω) > 0: a hemisphere in u, whose pole we put on the quadrature's pole. A
// second clamp (eq. 25) is a second great circle, handled by integrating each ring only over its arc. (A is
// computed in double from the rotation and σ's; any A is a valid change of variables, so the float rounding of
// S does not enter the reference.) The identity D dωm = |Au| du / π (eq. 12 from the ellipsoid's surface)
// gives eq. 25 directly in u, without the code's D: f_diff(ωi → ωo) = ∫⟨Aωo, u⟩⁺⟨Aωi, u⟩⁺/|Au| du / (π² σ(ωi)).
#include "media/sggx.h"

#include "core/frame.h"
#include "core/warp.h"
#include "support/chi2.h"
#include "support/sanitizer.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <functional>
#include <map>
#include <numbers>
#include <string>
#include <vector>

namespace kozu::test {
namespace {

constexpr double kPiD = std::numbers::pi;
using Mat3d = glm::dmat3;

Vec3d to_d(const Vec3& v) { return Vec3d(v.x, v.y, v.z); }
Vec3 to_f(const Vec3d& v) { return Vec3(static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)); }

// ---------------------------------------------------------------------------------------------------------
// Random S

enum class Shape { Surface, Fiber, General };
const char* shape_name(Shape s) { return s == Shape::Surface ? "surface" : s == Shape::Fiber ? "fiber" : "general"; }

struct SggxCase {
  Shape shape;
  int index;
  bool thin = false;            // roughness sggx::kMinRoughness: the flat-surface and thin-fiber limits
  Mat3d Q;                      // rotation: columns are the eigenvectors
  std::array<double, 3> sigma;  // projected areas along them
  Sggx S;                       // the float coefficients the code sees
  Mat3d A;                      // S^{1/2} (double), for the change of variables
  std::array<Vec3, 2> w;        // incident directions: random, and near the smallest-σ axis
  std::string name() const { return fmt::format("{}{}{}", thin ? "thin_" : "", shape_name(shape), index); }
};

void PrintTo(const SggxCase& c, std::ostream* os) { *os << c.name(); }

// Two uniform numbers, the second drawn first: the order GCC gives Vec2(rng.next_float(), rng.next_float()), in
// which these cases were chosen. Written out, because a call's arguments are evaluated in an order the compiler
// picks (clang goes left to right), and the sanitizer build is clang's.
Vec2 next_vec2(Pcg32& rng) {
  const float y = rng.next_float();
  return Vec2(rng.next_float(), y);
}

Mat3d random_rotation(Pcg32& rng) {
  // Shoemake's uniform quaternion.
  const double u1 = rng.next_double(), u2 = 2.0 * kPiD * rng.next_double(), u3 = 2.0 * kPiD * rng.next_double();
  const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
  const double x = a * std::sin(u2), y = a * std::cos(u2), z = b * std::sin(u3), w = b * std::cos(u3);
  return Mat3d(1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y),  // column 0
               2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x),  // column 1
               2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y));
}

Sggx to_sggx(const Mat3d& m) {
  return {static_cast<float>(m[0][0]), static_cast<float>(m[1][1]), static_cast<float>(m[2][2]),
          static_cast<float>(m[1][0]), static_cast<float>(m[2][0]), static_cast<float>(m[2][1])};
}

// S^{1/2} of the float S itself, from its eigen-decomposition in double.
Mat3d sqrt_of(const Sggx& S) {
  const sggx::SymmetricEigen e = sggx::eigen(S);
  Mat3d a(0.0);
  for (size_t k = 0; k < 3; ++k) a += std::sqrt(e.values[k]) * glm::outerProduct(e.vectors[k], e.vectors[k]);
  return a;
}

SggxCase make_case(Shape shape, int index, bool thin = false) {
  Pcg32 rng(0x5a6a7800u + 16u * static_cast<uint64_t>(shape) + static_cast<uint64_t>(index) + (thin ? 64u : 0u), 7);
  SggxCase c{shape, index, thin, random_rotation(rng), {}, {}, {}, {}};
  const auto in = [&](double lo, double hi) { return lo + (hi - lo) * rng.next_double(); };
  if (shape == Shape::Surface) c.sigma = {in(0.05, 0.3), in(0.05, 0.3), 1.0};
  if (shape == Shape::Fiber) c.sigma = {1.0, in(0.7, 1.0), in(0.05, 0.3)};
  if (shape == Shape::General) c.sigma = {in(0.3, 1.0), in(0.3, 1.0), in(0.3, 1.0)};
  Mat3d s2(0.0), s1(0.0);
  for (int k = 0; k < 3; ++k) {
    s2[k][k] = c.sigma[static_cast<size_t>(k)] * c.sigma[static_cast<size_t>(k)];
    s1[k][k] = c.sigma[static_cast<size_t>(k)];
  }
  if (thin) {
    const double r = sggx::kMinRoughness;
    c.sigma = shape == Shape::Surface ? std::array<double, 3>{r, r, 1.0} : std::array<double, 3>{1.0, 1.0, r};
    for (int k = 0; k < 3; ++k) {
      s2[k][k] = c.sigma[static_cast<size_t>(k)] * c.sigma[static_cast<size_t>(k)];
      s1[k][k] = c.sigma[static_cast<size_t>(k)];
    }
  }
  c.S = to_sggx(c.Q * s2 * glm::transpose(c.Q));
  // At roughness 1e-3 the float rounding of S moves its small eigenvalue (1e-6) by several percent, so the
  // change of variables is built from the float S itself; elsewhere from the exact rotation and σ's.
  c.A = thin ? sqrt_of(c.S) : c.Q * s1 * glm::transpose(c.Q);
  const Vec3 random_dir = warp::square_to_uniform_sphere(next_vec2(rng));
  const size_t k_min = c.sigma[2] < c.sigma[0] ? 2 : 0;
  c.w[0] = random_dir;
  c.w[1] = glm::normalize(to_f(c.Q[static_cast<int>(k_min)]) + 0.25f * random_dir);
  return c;
}

std::vector<SggxCase> all_cases() {
  std::vector<SggxCase> v;
  for (Shape s : {Shape::Surface, Shape::Fiber, Shape::General})
    for (int i = 0; i < 3; ++i) v.push_back(make_case(s, i));
  return v;
}

struct DirCase {
  SggxCase c;
  int which;  // index into c.w
  Vec3 w() const { return c.w[static_cast<size_t>(which)]; }
  std::string name() const { return fmt::format("{}_w{}", c.name(), which); }
};
void PrintTo(const DirCase& c, std::ostream* os) { *os << c.name(); }

std::vector<DirCase> dir_cases() {
  std::vector<DirCase> v;
  for (const SggxCase& c : all_cases())
    for (int k = 0; k < 2; ++k) v.push_back({c, k});
  return v;
}
// The limits: a surface and a fiber at sggx::kMinRoughness, each seen from a random direction and from near
// its thin axis.
std::vector<DirCase> thin_dir_cases() {
  std::vector<DirCase> v;
  for (Shape s : {Shape::Surface, Shape::Fiber})
    for (int k = 0; k < 2; ++k) v.push_back({make_case(s, 0, true), k});
  return v;
}
std::vector<DirCase> general_dir_cases() {
  std::vector<DirCase> v;
  for (const DirCase& d : dir_cases())
    if (d.c.shape == Shape::General) v.push_back(d);
  return v;
}

// Chi-square family: VNDF and specular in u-space (all rows), diffuse (all rows), VNDF and specular directly
// on the sphere (general rows).
const int kChi2Tests =
    static_cast<int>(3 * (dir_cases().size() + thin_dir_cases().size()) + 2 * general_dir_cases().size());

// ---------------------------------------------------------------------------------------------------------
// Quadrature on the u-sphere

struct Rule01 {
  std::vector<double> x, w;
};
const Rule01& rule01(int n) {
  static std::map<int, Rule01> cache;
  auto it = cache.find(n);
  if (it != cache.end()) return it->second;
  const GaussRule g = gauss_legendre(n);
  Rule01 r;
  for (size_t i = 0; i < g.x.size(); ++i) {
    r.x.push_back(0.5 * (1.0 + g.x[i]));
    r.w.push_back(0.5 * g.w[i]);
  }
  return cache.emplace(n, r).first->second;
}

// ∫ g(u) du over {u·a > 0} (and u·b > 0 when b is given), n Gauss–Legendre points per panel, `panels` panels
// in each of z and φ. g may vanish linearly on u·b = 0 (the rings are cut there exactly; the square-root
// behaviour of the arc length where the cut circle touches a ring, z = z*, is removed by z = z*(1 − t²)).
template <typename G>
double integrate_hemisphere(const Vec3d& a_in, const Vec3d* b_in, const G& g, int n = 24, int panels = 2) {
  const Vec3d a = glm::normalize(a_in);
  Vec3d e1, e2;
  orthonormal_basis(a, e1, e2);
  const Rule01& r = rule01(n);
  const auto gl = [&](double lo, double hi, const auto& f) {
    double sum = 0;
    const double h = (hi - lo) / panels;
    for (int p = 0; p < panels; ++p)
      for (size_t i = 0; i < r.x.size(); ++i) sum += r.w[i] * f(lo + (p + r.x[i]) * h);
    return sum * h;
  };
  const auto ring = [&](double z, double phi_lo, double phi_hi) {
    const double st = std::sqrt(std::max(0.0, 1.0 - z * z));
    return gl(phi_lo, phi_hi, [&](double phi) { return g(st * std::cos(phi) * e1 + st * std::sin(phi) * e2 + z * a); });
  };
  if (!b_in) return gl(0.0, 1.0, [&](double z) { return ring(z, 0.0, 2.0 * kPiD); });
  const Vec3d b = glm::normalize(*b_in);
  const double bx = glm::dot(b, e1), by = glm::dot(b, e2), bz = glm::dot(b, a);
  const double R = std::hypot(bx, by);
  if (R < 1e-12) return bz > 0.0 ? gl(0.0, 1.0, [&](double z) { return ring(z, 0.0, 2.0 * kPiD); }) : 0.0;
  const double phi0 = std::atan2(by, bx), z_star = std::min(R, 1.0);
  // z in (0, z*): the arc cos(φ − φ0) > κ(z) = −z bz / (R sqrt(1 − z²)), with z = z*(1 − t²).
  double total = gl(0.0, 1.0, [&](double t) {
    const double z = z_star * (1.0 - t * t);
    const double kappa = std::clamp(-z * bz / (R * std::sqrt(std::max(1e-300, 1.0 - z * z))), -1.0, 1.0);
    const double half = std::acos(kappa);
    return ring(z, phi0 - half, phi0 + half) * 2.0 * z_star * t;
  });
  // z in (z*, 1): the whole ring when bz > 0, nothing otherwise.
  if (bz > 0.0 && z_star < 1.0) total += gl(z_star, 1.0, [&](double z) { return ring(z, 0.0, 2.0 * kPiD); });
  return total;
}

// ωm(u) and the Jacobian dωm/du = |A| / |Au|³.
struct UMap {
  Mat3d A, A_inv;
  double det;
  explicit UMap(const Mat3d& a) : A(a), A_inv(glm::inverse(a)), det(std::abs(glm::determinant(a))) {}
  Vec3d wm(const Vec3d& u) const { return glm::normalize(A * u); }
  double jacobian(const Vec3d& u) const { return det / std::pow(glm::length(A * u), 3); }
  Vec3d u_of(const Vec3d& wm) const { return glm::normalize(A_inv * wm); }
};

// Eq. 25 without the code: (1/(π² σ(ωi))) ∫ ⟨Aωo, u⟩⁺ ⟨Aωi, u⟩⁺ / |Au| du, σ(ωi) = |Aωi|.
double diffuse_reference(const Mat3d& A, const Vec3& wi_f, const Vec3& wo_f, int n = 24, int panels = 8) {
  const Vec3d awi = A * to_d(wi_f), awo = A * to_d(wo_f);
  const double integral = integrate_hemisphere(
      awi, &awo,
      [&](const Vec3d& u) { return std::max(0.0, glm::dot(awo, u)) * std::max(0.0, glm::dot(awi, u)) / glm::length(A * u); },
      n, panels);
  return integral / (kPiD * kPiD * glm::length(awi));
}

// The rule for eq. 25 inside the diffuse chi-square's pdf (called ~13k times per test).
constexpr int kChi2RuleN = 16, kChi2RulePanels = 4;

// A frame for chi2_test, whose bins are about +z: local <-> world.
struct PoleFrame {
  Vec3d e1, e2, e3;
  explicit PoleFrame(const Vec3d& pole) : e3(glm::normalize(pole)) { orthonormal_basis(e3, e1, e2); }
  Vec3 local(const Vec3d& w) const { return to_f(Vec3d(glm::dot(w, e1), glm::dot(w, e2), glm::dot(w, e3))); }
  Vec3d world(const Vec3& l) const { return double(l.x) * e1 + double(l.y) * e2 + double(l.z) * e3; }
};

// ---------------------------------------------------------------------------------------------------------
// Linear algebra, constructors

TEST(Sggx, EigenRepeatedAndRandom) {
  // Reconstruction V Λ Vᵀ, orthonormality and the eigenvalues themselves, for triple, double and distinct
  // eigenvalues. Double-precision Jacobi: 1e-12 is ~1e4 ulps.
  std::vector<std::pair<Mat3d, std::array<double, 3>>> inputs;
  inputs.push_back({Mat3d(1.0), {1, 1, 1}});
  Pcg32 rng(11);
  for (int i = 0; i < 200; ++i) {
    const Mat3d q = random_rotation(rng);
    std::array<double, 3> l = {rng.next_double() + 0.01, rng.next_double() + 0.01, rng.next_double() + 0.01};
    if (i % 3 == 0) l[1] = l[0];
    if (i % 7 == 0) l[2] = l[1] = l[0];
    Mat3d d(0.0);
    for (int k = 0; k < 3; ++k) d[k][k] = l[static_cast<size_t>(k)];
    std::sort(l.begin(), l.end(), std::greater<>());
    inputs.push_back({q * d * glm::transpose(q), l});
  }
  for (const auto& [m, l] : inputs) {
    std::array<std::array<double, 3>, 3> a{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) a[static_cast<size_t>(i)][static_cast<size_t>(j)] = m[j][i];
    const sggx::SymmetricEigen e = sggx::eigen(a);
    for (size_t k = 0; k < 3; ++k) {
      EXPECT_NEAR(e.values[k], l[k], 1e-12);
      EXPECT_NEAR(glm::length(e.vectors[k]), 1.0, 1e-12);
      for (size_t j = 0; j < k; ++j) EXPECT_NEAR(glm::dot(e.vectors[k], e.vectors[j]), 0.0, 1e-12);
    }
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        double r = 0;
        for (size_t k = 0; k < 3; ++k) r += e.values[k] * e.vectors[k][i] * e.vectors[k][j];
        EXPECT_NEAR(r, m[j][i], 1e-12);
      }
  }
}

TEST(Sggx, ConstructorsMatchBasisForm) {
  // eq. 14 and 16 against eq. 9 with an explicit basis, and the projected areas they promise.
  Pcg32 rng(12);
  for (int i = 0; i < 100; ++i) {
    const Mat3d q = random_rotation(rng);
    const Vec3 w1 = to_f(q[0]), w2 = to_f(q[1]), w3 = to_f(q[2]);
    const float s = 0.02f + rng.next_float();
    const Sggx a = sggx::surface(w3, s), b = sggx::from_basis(w1, w2, w3, s, s, 1.0f);
    const Sggx c = sggx::fiber(w3, s), d = sggx::from_basis(w1, w2, w3, 1.0f, 1.0f, s);
    for (const auto& [x, y] : {std::pair{a, b}, std::pair{c, d}}) {
      EXPECT_NEAR(x.xx, y.xx, 1e-6f);
      EXPECT_NEAR(x.yy, y.yy, 1e-6f);
      EXPECT_NEAR(x.zz, y.zz, 1e-6f);
      EXPECT_NEAR(x.xy, y.xy, 1e-6f);
      EXPECT_NEAR(x.xz, y.xz, 1e-6f);
      EXPECT_NEAR(x.yz, y.yz, 1e-6f);
    }
    EXPECT_NEAR(sggx::projected_area(a, w3), 1.0f, 1e-6f);
    EXPECT_NEAR(sggx::projected_area(a, w1), s, 1e-6f);
    EXPECT_NEAR(sggx::projected_area(c, w3), s, 1e-6f);
    EXPECT_NEAR(sggx::projected_area(c, w2), 1.0f, 1e-6f);
    EXPECT_NEAR(sggx::max_projected_area(a), std::max(1.0f, s), 1e-6f);
  }
  // The sphere: S = I, D = 1/π everywhere, σ = 1.
  EXPECT_NEAR(sggx::D(Sggx{}, glm::normalize(Vec3(1, 2, 3))), kInvPi, 1e-7f);
}

TEST(Sggx, PrincipalAxisIsTheFibersTangentOrTheFlakesNormal) {
  // The denoiser's feature in SGGX media: the tangent of a fiber, the normal of a surface (either sign of the
  // input gives the same axis, its largest component positive), nothing for a sphere or a near-sphere.
  Pcg32 rng(13);
  for (int i = 0; i < 200; ++i) {
    const Vec3 axis = to_f(random_rotation(rng)[2]);
    const float s = 0.02f + 0.8f * rng.next_float();
    for (const Sggx& S : {sggx::fiber(axis, s), sggx::fiber(-axis, s), sggx::surface(axis, s), sggx::surface(-axis, s)}) {
      const Vec3 a = sggx::principal_axis(S);
      EXPECT_NEAR(std::abs(glm::dot(a, axis)), 1.0f, 1e-5f) << "sigma " << s;
      int largest = 0;
      for (int k = 1; k < 3; ++k)
        if (std::abs(a[k]) > std::abs(a[largest])) largest = k;
      EXPECT_GT(a[largest], 0.0f);
    }
  }
  EXPECT_EQ(sggx::principal_axis(Sggx{}), Vec3(0.0f));
  EXPECT_EQ(sggx::principal_axis(sggx::fiber(glm::normalize(Vec3(1, 2, 3)), 0.99999f)), Vec3(0.0f));
  // Through the phase functions, which the path's first medium vertex asks.
  const Vec3 t = glm::normalize(Vec3(0.3f, -0.2f, 0.9f));
  EXPECT_NEAR(glm::dot(SggxSpecularPhase(sggx::fiber(t, 0.2f)).feature_axis(), t), 1.0f, 1e-5f);
  EXPECT_NEAR(glm::dot(SggxDiffusePhase(sggx::surface(-t, 0.2f)).feature_axis(), t), 1.0f, 1e-5f);
}

class SggxMatrix : public testing::TestWithParam<SggxCase> {};
INSTANTIATE_TEST_SUITE_P(Sggx, SggxMatrix, testing::ValuesIn(all_cases()),
                         [](const testing::TestParamInfo<SggxCase>& row) { return row.param.name(); });

TEST_P(SggxMatrix, ProjectedAreaIsIntegralOfD) {
  // σ(ω) = sqrt(ωᵀSω) (eq. 11) against ∫⟨ω, ωm⟩ D(ωm) dωm (eq. 4) with the code's D, for 20 directions.
  // The quadrature is converged to < 1e-10 (ReferenceQuadratureConverges); the code returns floats
  // computed in double (≤ 1 ulp each) and D is evaluated at float ωm (≤ 1e-7 relative each, averaging out), so
  // 2e-6 relative is ~30 ulps of margin and still fails a D off by a part in 10⁵.
  const SggxCase& c = GetParam();
  const UMap map(c.A);
  Pcg32 rng(13);
  double worst = 0;
  for (int i = 0; i < 20; ++i) {
    const Vec3 w = warp::square_to_uniform_sphere(next_vec2(rng));
    const double integral = integrate_hemisphere(c.A * to_d(w), nullptr, [&](const Vec3d& u) {
      const Vec3d wm = map.wm(u);
      return glm::dot(to_d(w), wm) * sggx::D(c.S, to_f(wm)) * map.jacobian(u);
    });
    const double sigma = sggx::projected_area(c.S, w);
    EXPECT_NEAR(sigma, integral, 2e-6 * integral) << "w = " << w.x << ", " << w.y << ", " << w.z;
    worst = std::max(worst, std::abs(sigma - integral) / integral);
    // D is symmetric (a microflake distribution).
    EXPECT_EQ(sggx::D(c.S, w), sggx::D(c.S, -w));
  }
  RecordProperty("worst_relative_error", fmt::format("{:.3e}", worst));
  std::printf("[ sigma ] %s worst relative error %.3e\n", c.name().c_str(), worst);
}

TEST_P(SggxMatrix, ReferenceQuadratureConverges) {
  // The cut-hemisphere rule against the closed form ∫(a·u)⁺(b·u)⁺ du = (2/3)((π − γ) cos γ + sin γ), γ = ∠(a, b)
  // (1e-10);
  // then eq. 25's reference: the default rule (24 points x 8 panels) moves by < 1e-10 relative when doubled, so
  // tolerances elsewhere are set by the code under test. The chi-square's cheaper rule is checked to 1e-4.
  const SggxCase& c = GetParam();
  Pcg32 rng(30 + static_cast<uint64_t>(c.index));
  for (int i = 0; i < 20; ++i) {
    const Vec3d a = glm::normalize(to_d(warp::square_to_uniform_sphere(next_vec2(rng))));
    const Vec3d b = glm::normalize(to_d(warp::square_to_uniform_sphere(next_vec2(rng))));
    // atan2, not acos: acos loses digits near γ = 0, π (clang's and GCC's random pairs differ, and one is there).
    const double gamma = std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
    const double exact = 2.0 / 3.0 * ((kPiD - gamma) * std::cos(gamma) + std::sin(gamma));
    const double q = integrate_hemisphere(a, &b, [&](const Vec3d& u) { return glm::dot(a, u) * std::max(0.0, glm::dot(b, u)); });
    EXPECT_NEAR(q, exact, 1e-10);
  }
  double worst_cheap = 0;
  for (int i = 0; i < 4; ++i) {
    const Vec3 wi = c.w[static_cast<size_t>(i % 2)];
    const Vec3 wo = warp::square_to_uniform_sphere(next_vec2(rng));
    const double a = diffuse_reference(c.A, wi, wo), b = diffuse_reference(c.A, wi, wo, 32, 16);
    EXPECT_NEAR(a, b, 1e-10 * b);
    worst_cheap = std::max(worst_cheap, std::abs(diffuse_reference(c.A, wi, wo, kChi2RuleN, kChi2RulePanels) - b) / b);
  }
  // The chi-square's expected counts (~1250 per cell) then err by < 0.1 sample, against a noise of ~35.
  EXPECT_LT(worst_cheap, 1e-4);
  std::printf("[ quadrature ] %s chi-square rule relative error %.2e\n", c.name().c_str(), worst_cheap);
}

// ---------------------------------------------------------------------------------------------------------
// VNDF, specular phase: normalisation, reciprocity, consistency

class SggxDirection : public testing::TestWithParam<DirCase> {};
INSTANTIATE_TEST_SUITE_P(Sggx, SggxDirection, testing::ValuesIn(dir_cases()),
                         [](const testing::TestParamInfo<DirCase>& row) { return row.param.name(); });
// The same normalisation, consistency, chi-square and reciprocity tests, unchanged, at roughness 1e-3.
INSTANTIATE_TEST_SUITE_P(SggxThin, SggxDirection, testing::ValuesIn(thin_dir_cases()),
                         [](const testing::TestParamInfo<DirCase>& row) { return row.param.name(); });

TEST_P(SggxDirection, VisibleNormalsAndSpecularPhaseNormalised) {
  // eq. 22: ∫ D_ωi = 1; eq. 7 for eq. 24, in u-space through ωo = reflect(ωi, ωm(u)), dωo = 4⟨ωi, ωm⟩ dωm.
  // VNDF: same precision argument as ProjectedAreaIsIntegralOfD, 2e-6. Specular: eval recomputes ωh from the
  // float ωo, and D's relative sensitivity to ωh is up to ~4/σ_min = 80 for the thinnest rows, so rounding ωo
  // (6e-8) moves single values by up to ~5e-6 (averaging down to the ~1e-6 measured): 5e-6. At roughness 1e-3
  // the same argument gives 4/σ_min · 6e-8 = 2.4e-4 per value (a float direction resolves a 1e-3-wide lobe
  // only so well), averaging down to the 1.0e-5 measured: 5e-5 for those rows. The VNDF's 2e-6 holds there.
  const DirCase& d = GetParam();
  const UMap map(d.c.A);
  const Vec3 wo = d.w();
  const SggxSpecularPhase phase(d.c.S);
  Pcg32 rng(1);
  const double vndf = integrate_hemisphere(d.c.A * to_d(wo), nullptr, [&](const Vec3d& u) {
    return sggx::D_visible(d.c.S, wo, to_f(map.wm(u))) * map.jacobian(u);
  });
  const double spec = integrate_hemisphere(d.c.A * to_d(wo), nullptr, [&](const Vec3d& u) {
    const Vec3d h = map.wm(u);
    const Vec3 wi = to_f(glm::normalize(2.0 * glm::dot(to_d(wo), h) * h - to_d(wo)));
    return phase.eval(wo, wi, rng) * 4.0 * glm::dot(to_d(wo), h) * map.jacobian(u);
  });
  EXPECT_NEAR(vndf, 1.0, 2e-6);
  EXPECT_NEAR(spec, 1.0, d.c.thin ? 5e-5 : 5e-6);
  std::printf("[ norm ] %s vndf-1 %.2e spec-1 %.2e\n", d.name().c_str(), vndf - 1.0, spec - 1.0);
}

TEST(Sggx, SpecularPhaseNormalisedOnSphereGrid) {
  // ∫ f_p dωo = 1 straight on the sphere (integrate_pdf_over_sphere, no change of variables) for the general
  // rows. The grid's pole is ωi: f_p's only irregular point, ωo = −ωi (where ωh turns around), is then the
  // grid's south pole, where f_p is smooth in (cos θ, φ). Converged: 96 and 192 cells agree to 1e-7 (checked
  // below), so 1e-6 is the float evaluation (1e-7 per value) with a margin.
  Pcg32 rng(1);
  for (const DirCase& d : general_dir_cases()) {
    const SggxSpecularPhase phase(d.c.S);
    const PoleFrame frame(to_d(d.w()));
    const auto f = [&](const Vec3& l) { return static_cast<double>(phase.eval(d.w(), to_f(frame.world(l)), rng)); };
    const double integral = integrate_pdf_over_sphere(f, 96);
    EXPECT_NEAR(integral, integrate_pdf_over_sphere(f, 192), 1e-7) << d.name();
    EXPECT_NEAR(integral, 1.0, 1e-6) << d.name();
    std::printf("[ norm-grid ] %s spec-1 %.2e\n", d.name().c_str(), integral - 1.0);
  }
}

TEST(Sggx, SpecularPhaseReciprocal) {
  // eq. 8: σ(ωi) f(ωi, ωo) = σ(ωo) f(ωo, ωi). Both sides share D(ωh) exactly (float addition commutes); what
  // remains is ~3 roundings of the products: 1e-6 relative.
  Pcg32 rng(14);
  double worst = 0;
  std::vector<SggxCase> cases = all_cases();
  for (Shape shape : {Shape::Surface, Shape::Fiber}) cases.push_back(make_case(shape, 0, true));  // roughness 1e-3
  for (const SggxCase& c : cases) {
    const SggxSpecularPhase phase(c.S);
    for (int i = 0; i < 2000; ++i) {
      const Vec3 a = warp::square_to_uniform_sphere(next_vec2(rng));
      const Vec3 b = warp::square_to_uniform_sphere(next_vec2(rng));
      const double l = sggx::projected_area(c.S, a) * double(phase.eval(a, b, rng));
      const double r = sggx::projected_area(c.S, b) * double(phase.eval(b, a, rng));
      EXPECT_NEAR(l, r, 1e-6 * std::max(l, r)) << c.name();
      if (l > 0) worst = std::max(worst, std::abs(l - r) / std::max(l, r));
    }
  }
  std::printf("[ reciprocity ] specular worst relative %.3e\n", worst);
}

TEST(Sggx, DiffuseProxyPdfMatchesItsDefinitionAcrossCalls) {
  // The MIS proxy is (15/16) (1/8π) Σ_j ⟨wi, m_j⟩⁺ + (1/16)/4π over the rule's visible normals m_j (header); the
  // phase computes it from per-wo cached lengths. Against the definition with sggx::VisibleNormals::normal, for
  // wo changing between calls (the cache must follow it) and repeating (the cache is reused): 1e-5 relative
  // (float rounding of two ways to form the same cosines, ~10 ulps).
  const double r1 = std::sqrt(0.5 - 0.5 / std::sqrt(3.0)), r2 = std::sqrt(0.5 + 0.5 / std::sqrt(3.0));
  Pcg32 rng(31);
  std::vector<SggxCase> cases = all_cases();
  for (Shape shape : {Shape::Surface, Shape::Fiber}) cases.push_back(make_case(shape, 0, true));
  for (const SggxCase& c : cases) {
    const SggxDiffusePhase phase(c.S);
    Vec3 wo = warp::square_to_uniform_sphere(next_vec2(rng));
    for (int i = 0; i < 400; ++i) {
      if (i % 4 == 0) wo = warp::square_to_uniform_sphere(next_vec2(rng));
      const Vec3 wi = warp::square_to_uniform_sphere(next_vec2(rng));
      const sggx::VisibleNormals map(c.S, wo);
      double sum = 0;
      for (int j = 0; j < 8; ++j) {
        const double r = j < 4 ? r1 : r2, phi = 2.0 * kPiD * (j % 4 + (j < 4 ? 0.0 : 0.5)) / 4.0;
        sum += std::max(0.0, double(glm::dot(wi, map.normal(float(r * std::cos(phi)), float(r * std::sin(phi))))));
      }
      const double expected = (15.0 / 16.0) * sum / (8.0 * kPiD) + (1.0 / 16.0) / (4.0 * kPiD);
      ASSERT_NEAR(phase.pdf(wo, wi), expected, 1e-5 * expected) << c.name() << " call " << i;
    }
  }
}

TEST_P(SggxDirection, SampleMatchesEvalAndPdf) {
  // sample()'s wi is unit, its pdf is pdf(wo, wi) bit for bit and equals eval; weight 1 (exact sampling).
  const DirCase& d = GetParam();
  const SggxSpecularPhase spec(d.c.S);
  const SggxDiffusePhase diff(d.c.S);
  Pcg32 rng(15), rng2(16);
  for (int i = 0; i < 1000; ++i) {
    const Vec2 u = next_vec2(rng);
    const PhaseSample s = spec.sample(d.w(), u, rng2);
    EXPECT_NEAR(glm::length(s.wi), 1.0f, 1e-5f);
    EXPECT_EQ(s.weight(), 1.0f);
    EXPECT_EQ(s.pdf, spec.pdf(d.w(), s.wi));
    EXPECT_EQ(s.pdf, spec.eval(d.w(), s.wi, rng2));
    const PhaseSample t = diff.sample(d.w(), u, rng2);
    EXPECT_NEAR(glm::length(t.wi), 1.0f, 1e-5f);
    EXPECT_EQ(t.weight(), 1.0f);
    EXPECT_EQ(t.pdf, diff.pdf(d.w(), t.wi));
    EXPECT_TRUE(t.valid());
    const Vec3 wm = sggx::sample_visible(d.c.S, d.w(), u);
    EXPECT_GE(glm::dot(wm, d.w()), 0.0f);
  }
}

// ---------------------------------------------------------------------------------------------------------
// Chi-square

Chi2Options chi2_options(uint64_t seed) {
  Chi2Options o;
  o.test_count = kChi2Tests;
  o.seed = seed;
  return o;
}

void report(const std::string& what, const DirCase& d, const Chi2Result& r) {
  std::printf("[ chi2 ] %-10s %-12s p = %.4f  %s\n", what.c_str(), d.name().c_str(), r.p_value,
              r.passed ? "" : r.message.c_str());
}

TEST_P(SggxDirection, Chi2VisibleNormalsInParameterSpace) {
  // Samples ωm mapped to u = A⁻¹ωm/|A⁻¹ωm| (a fixed bijection), binned about the pole Aωi, against the pdf
  // D_ωi(ωm(u)) |A|/|Au|³ (eq. 21 by the code's D_visible).
  const DirCase& d = GetParam();
  const UMap map(d.c.A);
  const PoleFrame frame(d.c.A * to_d(d.w()));
  const Chi2Result r = chi2_test(
      [&](const Vec2& u) -> std::optional<Vec3> {
        return frame.local(map.u_of(to_d(sggx::sample_visible(d.c.S, d.w(), u))));
      },
      [&](const Vec3& l) {
        const Vec3d u = frame.world(l);
        return double(sggx::D_visible(d.c.S, d.w(), to_f(map.wm(u)))) * map.jacobian(u);
      },
      chi2_options(100 + static_cast<uint64_t>(d.which)));
  report("vndf-u", d, r);
  EXPECT_TRUE(r.passed) << r.message;
}

TEST_P(SggxDirection, Chi2SpecularPhaseInParameterSpace) {
  // Samples ωo mapped to the half vector, then to u; pdf f_p(ωi, ωo(u)) · 4⟨ωi, ωh⟩ · |A|/|Au|³ (eq. 24 by eval).
  const DirCase& d = GetParam();
  const UMap map(d.c.A);
  const PoleFrame frame(d.c.A * to_d(d.w()));
  const SggxSpecularPhase phase(d.c.S);
  Pcg32 rng(17);
  const Vec3d wo = to_d(d.w());
  const Chi2Result r = chi2_test(
      [&](const Vec2& u) -> std::optional<Vec3> {
        const PhaseSample s = phase.sample(d.w(), u, rng);
        // Near forward scattering (⟨ωi, ωm⟩ → 0) ωi + ωo cancels and the recovered ωh can land a rounding error
        // past the equator of its hemisphere; fold it back (the density there tends to 0 anyway).
        Vec3 l = frame.local(map.u_of(glm::normalize(wo + to_d(s.wi))));
        l.z = std::abs(l.z);
        return l;
      },
      [&](const Vec3& l) {
        const Vec3d u = frame.world(l);
        const Vec3d h = map.wm(u);
        const double cos_h = glm::dot(wo, h);
        if (cos_h <= 0.0) return 0.0;
        const Vec3 wi = to_f(glm::normalize(2.0 * cos_h * h - wo));
        return double(phase.eval(d.w(), wi, rng)) * 4.0 * cos_h * map.jacobian(u);
      },
      chi2_options(200 + static_cast<uint64_t>(d.which)));
  report("spec-u", d, r);
  EXPECT_TRUE(r.passed) << r.message;
}

TEST_P(SggxDirection, Chi2DiffusePhase) {
  // Samples ωo of the diffuse phase straight on the sphere (pole ωi) against the exact eq. 25 by the reference
  // quadrature (kChi2RuleN x kChi2RulePanels: < 1e-4 relative, see ReferenceQuadratureConverges). The
  // lost-mass cell is off: the sampler never rejects, and 4x4 points per cell integrate eq. 25's near-kinks
  // (thin surfaces) to ~1e-4 only.
  const DirCase& d = GetParam();
  // Half of this suite's time (35 s of 64 in Release, four times that under AddressSanitizer, where CI has 30
  // minutes for everything): the sanitizer build runs one row per shape (the same code, every branch), the Release
  // build every row.
  if (kSanitized && (d.which != 0 || d.c.name().back() != '0')) GTEST_SKIP() << "one row per shape under sanitizers";
  const SggxDiffusePhase phase(d.c.S);
  const PoleFrame frame(to_d(d.w()));
  Pcg32 rng(18);
  Chi2Options o = chi2_options(300 + static_cast<uint64_t>(d.which));
  o.theta_bins = 20;
  o.phi_bins = 40;
  o.integration_points = 4;
  o.check_lost_mass = false;
  const Chi2Result r = chi2_test(
      [&](const Vec2& u) -> std::optional<Vec3> { return frame.local(to_d(phase.sample(d.w(), u, rng).wi)); },
      [&](const Vec3& l) { return diffuse_reference(d.c.A, d.w(), to_f(frame.world(l)), kChi2RuleN, kChi2RulePanels); }, o);
  report("diffuse", d, r);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3);
}

class SggxGeneralDirection : public testing::TestWithParam<DirCase> {};
INSTANTIATE_TEST_SUITE_P(Sggx, SggxGeneralDirection, testing::ValuesIn(general_dir_cases()),
                         [](const testing::TestParamInfo<DirCase>& row) { return row.param.name(); });

TEST_P(SggxGeneralDirection, Chi2OnTheSphere) {
  // The same two samplers binned directly in ωm and ωo (no change of variables), for the general rows whose
  // densities a 40 x 80 grid resolves. VNDF binned about ωi (its clamp is then a cell edge), the phase about
  // the mirror direction of the mean visible normal.
  const DirCase& d = GetParam();
  const Vec3 wi = d.w();
  {
    const PoleFrame frame(to_d(wi));
    const Chi2Result r = chi2_test(
        [&](const Vec2& u) -> std::optional<Vec3> { return frame.local(to_d(sggx::sample_visible(d.c.S, wi, u))); },
        [&](const Vec3& l) { return double(sggx::D_visible(d.c.S, wi, to_f(frame.world(l)))); },
        chi2_options(400 + static_cast<uint64_t>(d.which)));
    report("vndf-w", d, r);
    EXPECT_TRUE(r.passed) << r.message;
  }
  {
    const SggxSpecularPhase phase(d.c.S);
    Pcg32 rng(19);
    const PoleFrame frame(to_d(wi));
    Chi2Options o = chi2_options(500 + static_cast<uint64_t>(d.which));
    const Chi2Result r = chi2_test(
        [&](const Vec2& u) -> std::optional<Vec3> { return frame.local(to_d(phase.sample(wi, u, rng).wi)); },
        [&](const Vec3& l) { return double(phase.eval(wi, to_f(frame.world(l)), rng)); }, o);
    report("spec-w", d, r);
    EXPECT_TRUE(r.passed) << r.message;
  }
}

// ---------------------------------------------------------------------------------------------------------
// Diffuse phase: stochastic evaluation, normalisation, reciprocity, MIS proxy

struct MeanSe {
  double mean, se;
};
MeanSe mean_of(int n, const std::function<double()>& f) {
  double s = 0, s2 = 0;
  for (int i = 0; i < n; ++i) {
    const double x = f();
    s += x;
    s2 += x * x;
  }
  const double m = s / n;
  return {m, std::sqrt(std::max(0.0, s2 / n - m * m) / n)};
}

TEST_P(SggxDirection, DiffuseStochasticEvalIsUnbiased) {
  // Mean of 200k single-normal estimates (eq. 26, N = 1) and of 50k N = 4 estimates against the quadrature of
  // eq. 25, at five ωo (random, the visible-normal mode direction, its mirror, and two grazing ones): within 5
  // standard errors (1 false failure in ~2e6 per comparison).
  const DirCase& d = GetParam();
  const Vec3 wi = d.w();
  Pcg32 dir_rng(20);
  const Vec3 mode = glm::normalize(Vec3(to_f(d.c.A * d.c.A * to_d(wi))));
  std::vector<Vec3> outs = {warp::square_to_uniform_sphere(Vec2(dir_rng.next_float(), dir_rng.next_float())), mode,
                            glm::normalize(reflect(wi, mode)), glm::normalize(glm::cross(wi, mode) + 0.1f * wi),
                            -wi};
  const SggxDiffusePhase one(d.c.S), four(d.c.S, 4);
  Pcg32 rng(21 + static_cast<uint64_t>(d.which));
  for (const Vec3& wo : outs) {
    const double ref = diffuse_reference(d.c.A, wi, wo);
    const MeanSe m1 = mean_of(200000, [&] { return double(one.eval(wi, wo, rng)); });
    const MeanSe m4 = mean_of(50000, [&] { return double(four.eval(wi, wo, rng)); });
    EXPECT_LE(std::abs(m1.mean - ref), 5.0 * m1.se + 1e-7 * ref) << d.name() << " ref " << ref;
    EXPECT_LE(std::abs(m4.mean - ref), 5.0 * m4.se + 1e-7 * ref) << d.name() << " ref " << ref;
    std::printf("[ diffuse-mean ] %s ref %.6f  N=1 %.6f (%.1f se)  N=4 %.6f (%.1f se)\n", d.name().c_str(), ref,
                m1.mean, m1.se > 0 ? (m1.mean - ref) / m1.se : 0.0, m4.mean, m4.se > 0 ? (m4.mean - ref) / m4.se : 0.0);
  }
}

TEST_P(SggxDirection, DiffuseNormalisedAndReciprocal) {
  // eq. 7: ∫ E[eval] dωo = 4π E_uniform[eval] = 1 (1.6M uniform ωo, one estimate each: se ≈ 1e-3), and the proxy pdf
  // (deterministic: integrate_pdf_over_sphere, converged to 1e-6 at 64) integrates to 1 and stays ≥ its
  // uniform floor. eq. 8 in expectation: σ(ωi) E[eval(ωi, ωo)] = σ(ωo) E[eval(ωo, ωi)], and exactly on the
  // reference quadrature. Statistical checks at 5 standard errors.
  const DirCase& d = GetParam();
  const Vec3 wi = d.w();
  const SggxDiffusePhase phase(d.c.S);
  Pcg32 rng(22 + static_cast<uint64_t>(d.which));
  const MeanSe integral = mean_of(1600000, [&] {
    const Vec3 wo = warp::square_to_uniform_sphere(next_vec2(rng));
    return 4.0 * kPiD * phase.eval(wi, wo, rng);
  });
  EXPECT_LE(std::abs(integral.mean - 1.0), 5.0 * integral.se) << integral.mean << " ± " << integral.se;
  double proxy_min = 1e30;
  const double proxy = integrate_pdf_over_sphere(
      [&](const Vec3& wo) {
        const double p = phase.pdf(wi, wo);
        proxy_min = std::min(proxy_min, p);
        return p;
      },
      64);
  EXPECT_NEAR(proxy, 1.0, 1e-5);
  EXPECT_GE(proxy_min, (1.0 / 16.0) / (4.0 * kPiD) * (1.0 - 1e-6));
  const Vec3 wo = warp::square_to_uniform_sphere(next_vec2(rng));
  const MeanSe ab = mean_of(200000, [&] { return double(phase.eval(wi, wo, rng)); });
  const MeanSe ba = mean_of(200000, [&] { return double(phase.eval(wo, wi, rng)); });
  const double sa = sggx::projected_area(d.c.S, wi), sb = sggx::projected_area(d.c.S, wo);
  EXPECT_LE(std::abs(sa * ab.mean - sb * ba.mean), 5.0 * std::hypot(sa * ab.se, sb * ba.se));
  const double qa = glm::length(d.c.A * to_d(wi)) * diffuse_reference(d.c.A, wi, wo);
  const double qb = glm::length(d.c.A * to_d(wo)) * diffuse_reference(d.c.A, wo, wi);
  // The reference's own reciprocity: its quadrature is converged to 1e-10, or to ~1e-8 at roughness 1e-3
  // (1/|Au| varies 1000-fold there; 1.0e-8 measured): 1e-7, far below the statistical tests' resolution.
  EXPECT_NEAR(qa, qb, (d.c.thin ? 1e-7 : 1e-10) * qa);
  std::printf("[ diffuse-norm ] %s ∫f-1 %+.2e (se %.1e)  proxy-1 %+.2e  recip %+.2e (se %.1e)\n", d.name().c_str(),
              integral.mean - 1.0, integral.se, proxy - 1.0, sa * ab.mean - sb * ba.mean,
              std::hypot(sa * ab.se, sb * ba.se));
}

// ---------------------------------------------------------------------------------------------------------
// Estimation

double relative_frobenius(const Sggx& a, const Sggx& b) {
  const auto sq = [](const Sggx& s) {
    return double(s.xx) * s.xx + double(s.yy) * s.yy + double(s.zz) * s.zz +
           2.0 * (double(s.xy) * s.xy + double(s.xz) * s.xz + double(s.yz) * s.yz);
  };
  return std::sqrt(sq(a + b * -1.0f)) / std::sqrt(sq(b));
}

TEST_P(SggxMatrix, EstimateRecoversSggx) {
  // S → D → estimate → S (eq. 17–18 on an SGGX input are exact). resolution 256 resolves σ ≥ 0.05 peaks; the
  // result moves by < 1e-6 relative from 256 to 384, so the 2e-6 tolerance is the float storage of S (1e-7) plus
  // that quadrature error, and fails e.g. the covariance's eigenvectors used with Σ's eigenvalues.
  const SggxCase& c = GetParam();
  const Sggx est = sggx::estimate([&](const Vec3& w) { return double(sggx::D(c.S, w)); }, 256);
  const double err = relative_frobenius(est, c.S);
  EXPECT_LT(err, 2e-6);
  // Scaled input (D is unnormalised): S scales by the square.
  const Sggx est3 = sggx::estimate([&](const Vec3& w) { return 3.0 * sggx::D(c.S, w); }, 256);
  EXPECT_LT(relative_frobenius(est3, c.S * 9.0f), 2e-6);
  std::printf("[ estimate ] %s relative Frobenius error %.3e\n", c.name().c_str(), err);
}

TEST(Sggx, EstimateKeepsProjectedAreasOfNonSggxInput) {
  // A non-SGGX input, the angular Gaussian fiber distribution D ∝ exp(−(ωm·t)²/(2γ²)) (Jakob et al. 2010):
  // the estimate's largest-variance axes are ⟂ t, its smallest-σ eigenvector is t, and σ_est(ω_k) equals the
  // input's projected area ∫⟨ω_k, ωm⟩ D dωm along its eigenvectors (§4.3), by an independent quadrature
  // (integrate_pdf_over_sphere at 128: < 1e-7 on this smooth integrand).
  const Vec3 t = glm::normalize(Vec3(0.3f, -0.5f, 0.8f));
  const double gamma = 0.3;
  const auto d_in = [&](const Vec3& w) { return std::exp(-sqr(double(glm::dot(w, t))) / (2 * gamma * gamma)); };
  const Sggx est = sggx::estimate(d_in, 128);
  const sggx::SymmetricEigen e = sggx::eigen(est);
  EXPECT_NEAR(std::abs(glm::dot(e.vectors[2], to_d(t))), 1.0, 1e-6);
  for (size_t k = 0; k < 3; ++k) {
    const Vec3 w = to_f(e.vectors[k]);
    const double area = integrate_pdf_over_sphere(
        [&](const Vec3& m) { return std::max(0.0, double(glm::dot(w, m))) * d_in(m); }, 128);
    EXPECT_NEAR(sggx::projected_area(est, w), area, 1e-5 * area) << k;
  }
}

TEST(Sggx, EstimateFromNormalsAxisAlignedIsExact) {
  // Surface elements with normals ±e_k of an axis-aligned frame (a signed permutation of x, y, z: exact in
  // float) and total weights W_k: Σ = Σ_k W_k e_k e_kᵀ / W has eigenvectors e_k, σ(e_k) = W_k / W, so
  // S = Σ (W_k / W)² e_k e_kᵀ exactly (float rounding of the result: 1e-6). (A rotated frame is not exact in
  // float: the rounding of the normals enters σ_k at first order through |ω_k · n|.)
  Pcg32 rng(23);
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int trial = 0; trial < 48; ++trial) {
    Mat3d q(0.0);
    for (int k = 0; k < 3; ++k) q[k][perms[trial % 6][k]] = (trial >> (3 + k)) & 1 ? -1.0 : 1.0;
    std::vector<WeightedNormal> normals;
    std::array<double, 3> wk{};
    for (int k = 0; k < 3; ++k)
      for (int copy = 0; copy < 3; ++copy) {
        const float w = 0.1f + rng.next_float();
        normals.push_back({(copy % 2 ? -1.0f : 1.0f) * to_f(q[k]), w});
        wk[static_cast<size_t>(k)] += w;
      }
    const double total = wk[0] + wk[1] + wk[2];
    const Sggx expect = sggx::from_basis(to_f(q[0]), to_f(q[1]), to_f(q[2]), float(wk[0] / total),
                                         float(wk[1] / total), float(wk[2] / total));
    const Sggx est = sggx::estimate_from_normals(normals);
    EXPECT_LT(relative_frobenius(est, expect), 1e-6) << trial;
  }
}

TEST_P(SggxMatrix, EstimateFromSampledNormalsRecoversShape) {
  // Normals of the ellipsoid: u uniform on the sphere, n = Au/|Au| with surface weight |Au| (D dωm = |Au| du/π).
  // Then σ_est(ω) = Σ|ω·n| w / Σw → |Aω| / (2 E|Au|), i.e. S_est = S / (2 E|Au|)², E|Au| by quadrature. 400k
  // samples: σ_est's relative standard error ≈ 0.58/√N ≈ 1e-3, so σ²(ω) within 1% over 50 directions is > 4.5 se.
  const SggxCase& c = GetParam();
  Pcg32 rng(24);
  std::vector<WeightedNormal> normals(400000);
  for (WeightedNormal& wn : normals) {
    const Vec3d au = c.A * to_d(warp::square_to_uniform_sphere(next_vec2(rng)));
    wn = {to_f(glm::normalize(au)), static_cast<float>(glm::length(au))};
  }
  const double mean_au =
      integrate_pdf_over_sphere([&](const Vec3& u) { return glm::length(c.A * to_d(u)); }, 64) / (4.0 * kPiD);
  const Sggx est = sggx::estimate_from_normals(normals) * static_cast<float>(sqr(2.0 * mean_au));
  double worst = 0;
  for (int i = 0; i < 50; ++i) {
    const Vec3 w = warp::square_to_uniform_sphere(next_vec2(rng));
    const double a = sqr(double(sggx::projected_area(est, w))), b = sqr(double(sggx::projected_area(c.S, w)));
    EXPECT_NEAR(a, b, 1e-2 * b);
    worst = std::max(worst, std::abs(a - b) / b);
  }
  std::printf("[ from-normals ] %s worst relative σ² error %.3e\n", c.name().c_str(), worst);
}

// ---------------------------------------------------------------------------------------------------------
// Compact storage, interpolation

TEST_P(SggxMatrix, CompactRoundTripWithinQuantisation) {
  // Coefficients: |Δσ_a| ≤ scale/510, |Δr| ≤ 1/254 (plus float rounding 1e-6) when the guard does not act.
  // Projected areas: with v = σ∘ω (|v| ≤ scale) and R the correlation matrix, σ(ω) = |R^{1/2} v|, so
  //   |Δσ(ω)| ≤ |R'^{1/2}Δv| + |vᵀΔR v| / (σ' + σ) ≤ √3 scale/510 + (2/254) scale² / (σ' + σ)
  // (λ(R') ≤ 3, |ΔR|₂ ≤ 2/254 by Gershgorin). The decompressed S must be SPD.
  const SggxCase& c = GetParam();
  const float scale = std::sqrt(std::max({c.S.xx, c.S.yy, c.S.zz}));
  const SggxCompact k = sggx::compress(c.S, scale);
  const Sggx back = sggx::decompress(k, scale);
  EXPECT_TRUE(sggx::is_spd(back));
  const double sig[3] = {std::sqrt(double(c.S.xx)), std::sqrt(double(c.S.yy)), std::sqrt(double(c.S.zz))};
  const double sig_b[3] = {std::sqrt(double(back.xx)), std::sqrt(double(back.yy)), std::sqrt(double(back.zz))};
  for (int a = 0; a < 3; ++a) EXPECT_LE(std::abs(sig_b[a] - sig[a]), scale / 510.0 + 1e-6);
  const double r[3] = {c.S.xy / (sig[0] * sig[1]), c.S.xz / (sig[0] * sig[2]), c.S.yz / (sig[1] * sig[2])};
  const double rb[3] = {back.xy / (sig_b[0] * sig_b[1]), back.xz / (sig_b[0] * sig_b[2]), back.yz / (sig_b[1] * sig_b[2])};
  for (int a = 0; a < 3; ++a) EXPECT_LE(std::abs(rb[a] - r[a]), 1.0 / 254.0 + 1e-6) << a;
  Pcg32 rng(25);
  double worst = 0;
  for (int i = 0; i < 1000; ++i) {
    const Vec3 w = warp::square_to_uniform_sphere(next_vec2(rng));
    const double s0 = sggx::projected_area(c.S, w), s1 = sggx::projected_area(back, w);
    const double bound = std::sqrt(3.0) * scale / 510.0 + (2.0 / 254.0) * scale * scale / (s0 + s1) + 1e-6;
    EXPECT_LE(std::abs(s1 - s0), bound);
    worst = std::max(worst, std::abs(s1 - s0) / s0);
  }
  std::printf("[ compact ] %s worst relative σ(ω) error %.3e\n", c.name().c_str(), worst);
}

TEST(Sggx, CompactGuardKeepsThinDistributionsSpd) {
  // A σ = 0.01 surface / fiber at random orientations: 8-bit r's can leave the correlation matrix indefinite
  // (checked below that it happens for some of them), yet decompress must return an SPD S.
  Pcg32 rng(26);
  int indefinite = 0;
  for (int i = 0; i < 500; ++i) {
    const Mat3d q = random_rotation(rng);
    const Sggx s = i % 2 ? sggx::surface(to_f(q[2]), 0.01f) : sggx::fiber(to_f(q[2]), 0.01f);
    const SggxCompact k = sggx::compress(s);
    const double r0 = k.r[0] / 127.0, r1 = k.r[1] / 127.0, r2 = k.r[2] / 127.0;
    if (1.0 + 2.0 * r0 * r1 * r2 - r0 * r0 - r1 * r1 - r2 * r2 <= 0.0) ++indefinite;
    EXPECT_TRUE(sggx::is_spd(sggx::decompress(k))) << i;
  }
  EXPECT_GT(indefinite, 0);
  std::printf("[ compact-guard ] %d of 500 quantised correlation matrices were not positive definite\n", indefinite);
}

TEST(Sggx, InterpolationAndMipStaySpd) {
  // Convex combinations of SPD matrices are SPD, and σ²(ω) interpolates linearly (§4.4): lerp of random
  // pairs over all shapes, and a 3-level 2x2x2 box-filter MIP of an 8³ grid of random S. σ² linearity in float:
  // 1e-5 relative.
  const std::vector<SggxCase> cases = all_cases();
  Pcg32 rng(27);
  std::vector<Sggx> pool;
  for (int i = 0; i < 64; ++i) {
    const Mat3d q = random_rotation(rng);
    const float s = 0.01f + 0.5f * rng.next_float();
    pool.push_back(i % 3 == 0 ? sggx::surface(to_f(q[2]), s)
                              : i % 3 == 1 ? sggx::fiber(to_f(q[2]), s)
                                           : sggx::from_basis(to_f(q[0]), to_f(q[1]), to_f(q[2]), s, 1.0f, 0.5f));
  }
  for (const SggxCase& c : cases) pool.push_back(c.S);
  for (int i = 0; i < 2000; ++i) {
    const Sggx& a = pool[rng.next_u32() % pool.size()];
    const Sggx& b = pool[rng.next_u32() % pool.size()];
    const float t = rng.next_float();
    const Sggx m = sggx::lerp(a, b, t);
    ASSERT_TRUE(sggx::is_spd(m));
    const Vec3 w = warp::square_to_uniform_sphere(next_vec2(rng));
    const double expect = (1.0 - t) * sqr(double(sggx::projected_area(a, w))) + t * sqr(double(sggx::projected_area(b, w)));
    EXPECT_NEAR(sqr(double(sggx::projected_area(m, w))), expect, 1e-5 * expect);
  }
  std::vector<Sggx> level(512);
  for (Sggx& s : level) s = pool[rng.next_u32() % pool.size()];
  for (int n = 8; n > 1; n /= 2) {
    const int h = n / 2;
    std::vector<Sggx> next(static_cast<size_t>(h * h * h), Sggx{0, 0, 0, 0, 0, 0});
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          Sggx& dst = next[static_cast<size_t>((z / 2 * h + y / 2) * h + x / 2)];
          dst = dst + level[static_cast<size_t>((z * n + y) * n + x)] * 0.125f;
        }
    for (const Sggx& s : next) {
      ASSERT_TRUE(sggx::is_spd(s));
      EXPECT_GT(sggx::eigen(s).values[2], 0.0);
    }
    level = std::move(next);
  }
}

}  // namespace
}  // namespace kozu::test
