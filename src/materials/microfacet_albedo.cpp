#include "materials/microfacet_albedo.h"

#include "core/rng.h"
#include "materials/fresnel.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cstring>
#include <vector>

namespace kozu {

namespace albedo {

// The checked-in tables (microfacet_albedo_data.cpp).
extern const float kConductorE[2][kRoughNodes][kMuNodes];
extern const float kDielectricE[2][kEtaNodes][kRoughNodes][kMuNodes];
extern const float kDielectricER[2][kEtaNodes][kRoughNodes][kMuNodes];

namespace {

float mu_node(int i) { return i / float(kMuNodes - 1); }
float alpha_node(int j) {
  const float r = j / float(kRoughNodes - 1);
  return r * r;
}

// Point (a, b) of an n x n jittered grid: one uniform point per cell. Jittering converts the O(1/n) error
// the midpoint rule makes at the integrands' discontinuities (the horizon, total internal reflection)
// into noise of order n^-1.5; the generator is seeded from the entry, so the tables still regenerate
// bit for bit.
Vec2 jittered(int a, int b, int n, Pcg32& rng) {
  const float x = rng.next_float(), y = rng.next_float();
  return Vec2(std::min((a + x) / n, 0x1.fffffep-1f), std::min((b + y) / n, 0x1.fffffep-1f));
}

uint64_t entry_seed(const MicrofacetDistribution& d, float mu, float eta) {
  uint64_t h = 0x9e3779b97f4a7c15ull;
  for (const float v : {d.alpha_x(), d.alpha_y(), mu, eta, d.type() == MicrofacetType::GGX ? 0.0f : 1.0f}) {
    uint32_t bits;
    std::memcpy(&bits, &v, 4);
    h = mix64(h ^ bits);
  }
  return h;
}

// μ = 0 is a limit: integrate just above it.
Vec3 view_direction(float mu) {
  mu = std::max(mu, 1e-4f);
  return Vec3(safe_sqrt(1.0f - mu * mu), 0.0f, mu);
}

struct Coord {
  int i;
  float t;
};
Coord coord(float x, int nodes) {
  x = std::clamp(x, 0.0f, float(nodes - 1));
  const int i = std::min(static_cast<int>(x), nodes - 2);
  return {i, x - i};
}

float lerp2(const float (&table)[kRoughNodes][kMuNodes], float mu, float alpha) {
  const Coord m = coord(mu * (kMuNodes - 1), kMuNodes);
  const Coord r = coord(std::sqrt(std::max(alpha, 0.0f)) * (kRoughNodes - 1), kRoughNodes);
  auto row = [&](int j) { return table[j][m.i] + m.t * (table[j][m.i + 1] - table[j][m.i]); };
  return row(r.i) + r.t * (row(r.i + 1) - row(r.i));
}

float lerp3(const float (&table)[kEtaNodes][kRoughNodes][kMuNodes], float mu, float alpha, float eta) {
  const float x = (std::log(eta) / std::log(kEtaMax) + 1.0f) * 0.5f * (kEtaNodes - 1);
  const Coord e = coord(x, kEtaNodes);
  const float a = lerp2(table[e.i], mu, alpha), b = lerp2(table[e.i + 1], mu, alpha);
  return a + e.t * (b - a);
}

int dist_index(MicrofacetType t) { return t == MicrofacetType::GGX ? 0 : 1; }

}  // namespace

float eta_node(int k) { return std::exp(std::log(kEtaMax) * (2.0f * k / float(kEtaNodes - 1) - 1.0f)); }

double integrate_conductor(const MicrofacetDistribution& d, float mu, int n) {
  const Vec3 wo = view_direction(mu);
  const double lambda_o = d.lambda(wo);
  Pcg32 rng(entry_seed(d, mu, 1.0f));
  double sum = 0;
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      const Vec3 m = d.sample_visible(wo, jittered(a, b, n, rng));
      const Vec3 wi = reflect(wo, m);
      if (wi.z <= 0.0f) continue;
      // f cos θi / D_wo(m) (dωm/dωi) = G2 / G1(wo) for F = 1.
      sum += (1.0 + lambda_o) / (1.0 + lambda_o + d.lambda(wi));
    }
  }
  return sum / (double(n) * n);
}

void integrate_dielectric(const MicrofacetDistribution& d, float mu, float eta, int n, double* reflect_out,
                          double* total_out) {
  const Vec3 wo = view_direction(mu);
  const double lambda_o = d.lambda(wo);
  Pcg32 rng(entry_seed(d, mu, eta));
  double r_sum = 0, t_sum = 0;
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      const Vec3 m = d.sample_visible(wo, jittered(a, b, n, rng));
      const float cos_om = glm::dot(wo, m);
      if (cos_om <= 0.0f) continue;
      const float F = fresnel_dielectric(cos_om, eta);
      // Both lobes for every normal: the estimator weight of each is its Fresnel share times G2 / G1(wo).
      const Vec3 wr = reflect(wo, m);
      if (wr.z > 0.0f) r_sum += F * (1.0 + lambda_o) / (1.0 + lambda_o + d.lambda(wr));
      Vec3 wt;
      if (F < 1.0f && refract(wo, m, eta, &wt) && wt.z < 0.0f)
        t_sum += (1.0f - F) * (1.0 + lambda_o) / (1.0 + lambda_o + d.lambda(wt));
    }
  }
  const double norm = 1.0 / (double(n) * n);
  *reflect_out = r_sum * norm;
  *total_out = (r_sum + t_sum) * norm;
}

std::string generate_tables(int n, const std::function<void(size_t, size_t)>& progress) {
  const MicrofacetType types[2] = {MicrofacetType::GGX, MicrofacetType::Beckmann};
  constexpr size_t kCond = 2 * kRoughNodes * kMuNodes;
  constexpr size_t kDiel = 2 * kEtaNodes * kRoughNodes * kMuNodes;
  std::vector<float> cond(kCond), diel(kDiel), diel_r(kDiel);
  std::atomic<size_t> done{0};
  const size_t total = kCond + kDiel;
  // Rows of μ per task: each task is a (distribution, η, α) row, so no two tasks share an output.
  tbb::parallel_for(size_t{0}, total / kMuNodes, [&](size_t row) {
    if (row < kCond / kMuNodes) {
      const int t = static_cast<int>(row / kRoughNodes), j = static_cast<int>(row % kRoughNodes);
      const MicrofacetDistribution d(types[t], alpha_node(j), alpha_node(j));
      for (int i = 0; i < kMuNodes; ++i)
        cond[row * kMuNodes + i] = j == 0 ? 1.0f : static_cast<float>(integrate_conductor(d, mu_node(i), n));
    } else {
      const size_t r = row - kCond / kMuNodes;
      const int t = static_cast<int>(r / (kEtaNodes * kRoughNodes));
      const int k = static_cast<int>(r / kRoughNodes % kEtaNodes), j = static_cast<int>(r % kRoughNodes);
      const MicrofacetDistribution d(types[t], alpha_node(j), alpha_node(j));
      for (int i = 0; i < kMuNodes; ++i) {
        double refl, tot;
        if (j == 0) {  // smooth interface: no energy is lost; the reflection is the Fresnel term
          refl = fresnel_dielectric(std::max(mu_node(i), 1e-4f), eta_node(k));
          tot = 1.0;
        } else {
          integrate_dielectric(d, mu_node(i), eta_node(k), n, &refl, &tot);
        }
        diel[r * kMuNodes + i] = static_cast<float>(tot);
        diel_r[r * kMuNodes + i] = static_cast<float>(refl);
      }
    }
    done += kMuNodes;
  });
  if (progress) progress(done.load(), total);

  std::string out;
  out += "// Generated by `kozu precompute microfacet-albedo` (src/apps/precompute_command.cpp); do not edit.\n";
  out += fmt::format("// Integration grid: {} x {} visible normals per entry. See src/materials/microfacet_albedo.h.\n",
                     n, n);
  auto emit = [&](const char* name, const char* dims, const std::vector<float>& v) {
    out += fmt::format("const float {}{} = {{\n", name, dims);
    for (size_t i = 0; i < v.size(); i += kMuNodes) {
      out += " ";
      for (int k = 0; k < kMuNodes; ++k) out += fmt::format(" {:.6g},", v[i + k]);
      out += "\n";
    }
    out += "};\n";
  };
  emit("kConductorE", "[2][kRoughNodes][kMuNodes]", cond);
  emit("kDielectricE", "[2][kEtaNodes][kRoughNodes][kMuNodes]", diel);
  emit("kDielectricER", "[2][kEtaNodes][kRoughNodes][kMuNodes]", diel_r);
  return out;
}

float conductor_E(MicrofacetType type, float mu, float alpha) {
  return lerp2(kConductorE[dist_index(type)], mu, alpha);
}
float dielectric_E(MicrofacetType type, float mu, float alpha, float eta) {
  return lerp3(kDielectricE[dist_index(type)], mu, alpha, eta);
}
float dielectric_ER(MicrofacetType type, float mu, float alpha, float eta) {
  return lerp3(kDielectricER[dist_index(type)], mu, alpha, eta);
}

}  // namespace albedo

void AlbedoCurve::finish() {
  // Exact 2 ∫ E(μ) μ dμ of the piecewise-linear curve: per segment h (E_a (2a + b) + E_b (a + 2b)) / 6.
  const float h = 1.0f / (albedo::kMuNodes - 1);
  double sum = 0;
  for (int i = 0; i + 1 < albedo::kMuNodes; ++i) {
    const double a = i * h, b = (i + 1) * h;
    sum += h * (e_[i] * (2 * a + b) + e_[i + 1] * (a + 2 * b)) / 6.0;
  }
  avg_ = static_cast<float>(2.0 * sum);
}

namespace {
constexpr int kLobeBins = 64;
}

CoupledLobe::CoupledLobe(const AlbedoCurve& e_in) : e_(e_in) {
  active_ = 1.0f - e_.average() > 1e-6f;
  if (!active_) return;
  std::array<float, kLobeBins> f{};
  for (int i = 0; i < kLobeBins; ++i) f[i] = std::max(1.0f - e_.eval(std::sqrt((i + 0.5f) / kLobeBins)), 1e-6f);
  s_dist_ = Distribution1D(f);
}

float CoupledLobe::shape(float mu_i) const {
  if (!active_) return 0.0f;
  return (1.0f - e_.eval(std::abs(mu_i))) / (kPi * (1.0f - e_.average()));
}

Vec3 CoupledLobe::sample(const Vec2& u, float* pdf) const {
  float ps;
  const float s = s_dist_.sample(u.x, &ps);
  const float mu = std::sqrt(s);
  const float sin_t = safe_sqrt(1.0f - s);
  const float phi = kTwoPi * u.y;
  *pdf = ps * mu * kInvPi;  // p(s) ds dφ/2π with ds = 2μ dμ
  return Vec3(sin_t * std::cos(phi), sin_t * std::sin(phi), mu);
}

float CoupledLobe::pdf(float mu_i) const {
  if (!active_) return 0.0f;
  mu_i = std::abs(mu_i);
  return s_dist_.pdf(mu_i * mu_i) * mu_i * kInvPi;
}

}  // namespace kozu
