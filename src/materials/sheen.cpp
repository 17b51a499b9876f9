#include "materials/sheen.h"

#include "core/gauss_legendre.h"
#include "core/math.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace kozu::sheen {

namespace {

constexpr int kNodes = 32;

float clamp_roughness(float r) { return std::clamp(r, kMinRoughness, 1.0f); }

struct Table {
  std::array<float, kNodes * kNodes> e{};  // [roughness node][μ node]
  Table() {
    for (int j = 0; j < kNodes; ++j) {
      const float r = kMinRoughness + (1.0f - kMinRoughness) * sqr(j / float(kNodes - 1));
      for (int i = 0; i < kNodes; ++i)
        e[j * kNodes + i] = static_cast<float>(integrate_albedo(sqr(i / float(kNodes - 1)), r, 48));
    }
  }
};

const Table& table() {
  static const Table t;  // thread-safe initialization; ~50 ms, once per process that uses sheen
  return t;
}

// The projected area of the microsurface seen from μ, σ(μ) = ∫ max(0, ω·m) D(m) dm, which gives the exact Smith
// Λ(μ) = σ(μ) / μ − 1 (Heitz 2014, "Understanding the Masking-Shadowing Function", eqs. (17), (72)). The azimuthal
// integral is closed: ∫ max(0, A cos φ + B) dφ over [0, 2π) is 2πB for B ≥ A, 0 for B ≤ −A, otherwise
// 2 (B φ0 + A sin φ0) with φ0 = acos(−B / A); θm is integrated by 256-point Gauss–Legendre.
double projected_area(double mu, double r) {
  static const auto rule = [] {
    std::pair<std::vector<double>, std::vector<double>> xw;
    gauss_legendre_unit(256, &xw.first, &xw.second);
    return xw;
  }();
  const double k = 1.0 / (r * r * r * r);  // 1/α, α = r²
  const double s_mu = std::sqrt(std::max(0.0, 1.0 - mu * mu));
  double sum = 0;
  for (size_t i = 0; i < rule.first.size(); ++i) {
    const double theta = 0.5 * M_PI * rule.first[i], st = std::sin(theta), ct = std::cos(theta);
    const double A = st * s_mu, B = ct * mu;
    double ring;
    if (B >= A)
      ring = 2 * M_PI * B;
    else if (B <= -A)
      ring = 0;
    else {
      const double phi0 = std::acos(-B / A);
      ring = 2 * (B * phi0 + A * std::sin(phi0));
    }
    const double D = (2 + k) * std::pow(st, k) / (2 * M_PI);  // Estevez & Kulla eq. (2)
    sum += rule.second[i] * 0.5 * M_PI * ring * D * st;       // dm = sin θ dθ dφ
  }
  return sum;
}

constexpr int kMuNodes = 64;

// σ(μ) on kMuNodes μ nodes × kNodes roughness nodes, bilinear.
struct ProjectedAreaTable {
  std::array<float, kMuNodes * kNodes> s{};
  ProjectedAreaTable() {
    for (int j = 0; j < kNodes; ++j) {
      const double r = kMinRoughness + (1.0 - kMinRoughness) * j / (kNodes - 1);
      for (int i = 0; i < kMuNodes; ++i)
        s[j * kMuNodes + i] = static_cast<float>(projected_area(i / double(kMuNodes - 1), r));
    }
  }
};

float lambda(float mu, float r) {
  static const ProjectedAreaTable t;
  const float y = (r - kMinRoughness) / (1.0f - kMinRoughness) * (kNodes - 1);
  const float x = std::clamp(mu, 0.0f, 1.0f) * (kMuNodes - 1);
  const int i = std::min(static_cast<int>(x), kMuNodes - 2), j = std::min(static_cast<int>(y), kNodes - 2);
  const float tx = x - i, ty = y - j;
  const auto at = [&](int jj, int ii) { return t.s[jj * kMuNodes + ii]; };
  const float a = at(j, i) + tx * (at(j, i + 1) - at(j, i));
  const float b = at(j + 1, i) + tx * (at(j + 1, i + 1) - at(j + 1, i));
  return std::max(0.0f, (a + ty * (b - a)) / std::max(mu, 1e-6f) - 1.0f);
}

}  // namespace

float eval(const Vec3& wo, const Vec3& wi, float roughness) {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
  const float r = clamp_roughness(roughness);
  const float alpha = sqr(r);
  const Vec3 h = glm::normalize(wo + wi);
  const float sin2 = std::max(0.0f, 1.0f - h.z * h.z);
  const float inv_alpha = 1.0f / alpha;
  const float D = (2.0f + inv_alpha) * std::pow(sin2, 0.5f * inv_alpha) * (0.5f * kInvPi);  // Estevez & Kulla (2)
  const float G2 = 1.0f / (1.0f + lambda(wo.z, r) + lambda(wi.z, r));
  return D * G2 / (4.0f * wo.z);
}

double integrate_albedo(float mu, float roughness, int n) {
  mu = std::clamp(mu, 1e-4f, 1.0f);
  const Vec3 wo(std::sqrt(1.0f - mu * mu), 0.0f, mu);
  std::vector<double> x, w;
  gauss_legendre_unit(n, &x, &w);
  const int n_phi = 2 * n;
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    const double ct = x[i], st = std::sqrt(std::max(0.0, 1 - ct * ct));
    double ring = 0;
    for (int k = 0; k < n_phi; ++k) {  // periodic trapezoid rule: spectrally accurate in φ
      const double phi = 2 * M_PI * (k + 0.5) / n_phi;
      const Vec3 wi(float(st * std::cos(phi)), float(st * std::sin(phi)), float(ct));
      ring += eval(wo, wi, roughness);
    }
    sum += w[i] * ring * (2 * M_PI / n_phi);  // dω = d(cos θ) dφ
  }
  return sum;
}

float albedo(float mu, float roughness) {
  const Table& t = table();
  // Nodes at r = r_min + (1 − r_min)(j/31)²: E changes fastest at small r.
  const float y = std::sqrt((clamp_roughness(roughness) - kMinRoughness) / (1.0f - kMinRoughness)) * (kNodes - 1);
  const float x = std::sqrt(std::clamp(mu, 0.0f, 1.0f)) * (kNodes - 1);  // nodes at μ = (i/31)²: E bends near 0
  const int i = std::min(static_cast<int>(x), kNodes - 2), j = std::min(static_cast<int>(y), kNodes - 2);
  const float tx = x - i, ty = y - j;
  const auto at = [&](int jj, int ii) { return t.e[jj * kNodes + ii]; };
  const float a = at(j, i) + tx * (at(j, i + 1) - at(j, i));
  const float b = at(j + 1, i) + tx * (at(j + 1, i + 1) - at(j + 1, i));
  return a + ty * (b - a);
}

}  // namespace kozu::sheen
