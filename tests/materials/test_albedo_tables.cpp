// The checked-in albedo tables (src/materials/microfacet_albedo_data.inc) against an independent integration:
// each spot entry is recomputed as the integral of the single-scattering BSDF's own eval (RoughConductorBsdf with
// F = 1, RoughDielectricBsdf without compensation) over the directions wi, by a deterministic tensor-product
// Gauss–Legendre rule in double precision. The tables come from another estimator (visible-normal samples weighted
// by G2 / G1, microfacet_albedo.cpp), so the two agree only if the tables and the BSDFs they compensate describe
// the same model. The command that writes the tables is run on a tiny grid.
#include "support/render_test.h"

#include "core/file_io.h"
#include "materials/conductor.h"
#include "materials/dielectric.h"
#include "materials/microfacet_albedo.h"
#include "core/gauss_legendre.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <regex>
#include <vector>

namespace kozu::test {
namespace {

constexpr int kGrid = 128;  // the grid the checked-in file was generated with (its header says so)
constexpr double kPiD = 3.14159265358979323846;

// Tolerance, entry by entry: |table − integral| must stay below
//   kStatedAccuracy                 docs/materials.md ("Tables"): the 128 × 128 entries are within 5·10⁻⁴ of a
//                                   2048 × 2048 grid; the claim under test,
// + kPrinted                        the file prints 6 significant digits of values below 1: half a unit of the
//                                   6th digit is at most 5·10⁻⁷,
// + 32 · 2⁻²⁴ · |integral|          eval is float: a few dozen roundings of 2⁻²⁴ relative per evaluation,
// + |Q_fine − Q_coarse|             the quadrature's own error, estimated by two rules of different order and
//                                   panel size (and required to be small, so it cannot hide a mismatch).
constexpr double kStatedAccuracy = 5e-4;
constexpr double kPrinted = 5e-7;
constexpr double kFloatEval = 32.0 * 0x1p-24;
constexpr double kMaxQuadratureError = 5e-5;  // a tenth of the stated accuracy

float node_alpha(int j) {
  const float r = j / float(albedo::kRoughNodes - 1);
  return r * r;
}
float node_mu(int i) { return i / float(albedo::kMuNodes - 1); }

// The view direction of table column i: μ = 0 is a limit, which the tables take at μ = 10⁻⁴ (microfacet_albedo.cpp).
Vec3 view_direction(int i) {
  const float mu = std::max(node_mu(i), 1e-4f);
  return Vec3(std::sqrt(1.0f - mu * mu), 0.0f, mu);
}

// Panel edges on [a, b]: the points `kinks`, and around each of `peaks` edges at distances δ, 4δ, 16δ, ... on both
// sides, then split so that no panel is wider than max_width. A lobe of any width above δ at a peak is resolved
// by the panels of its own scale, and a kink of the integrand at a kink point falls on a panel edge.
std::vector<double> graded_edges(double a, double b, const std::vector<double>& peaks, const std::vector<double>& kinks,
                                 double delta, double max_width) {
  std::vector<double> coarse{a, b};
  for (const double p : peaks) {
    if (p < a || p > b) continue;
    coarse.push_back(p);
    for (double d = delta; d < b - a; d *= 4) {
      if (p - d > a) coarse.push_back(p - d);
      if (p + d < b) coarse.push_back(p + d);
    }
  }
  for (const double k : kinks)
    if (k > a && k < b) coarse.push_back(k);
  std::sort(coarse.begin(), coarse.end());
  coarse.erase(std::unique(coarse.begin(), coarse.end()), coarse.end());
  std::vector<double> edges{coarse[0]};
  for (size_t k = 1; k < coarse.size(); ++k) {
    const int parts = static_cast<int>(std::ceil((coarse[k] - coarse[k - 1]) / max_width));
    for (int p = 1; p <= parts; ++p) edges.push_back(coarse[k - 1] + (coarse[k] - coarse[k - 1]) * p / parts);
  }
  return edges;
}

struct Rule {
  int order;
  double max_width;  // of a panel in θi and in φi
};
constexpr Rule kCoarse{8, kPiD / 16}, kFine{12, kPiD / 32};
constexpr double kDelta = 1e-5;  // radians: below the narrowest lobe tested (a refraction at η ≈ 1.04, α ≈ 0.026)

// ∫ eval(wo, wi) dωi over wi with θi in [theta_a, theta_b], in spherical coordinates (θi, φi): the horizon is a
// panel edge. wo lies in the xz-plane and the distribution is isotropic, so the integrand is even in φi: twice
// the integral over [0, π]. The lobes peak at azimuth π (the mirror and the refracted direction); `theta_peaks`
// are the θi where they peak or where the integrand jumps. `cones`: values c of wo·wi where the integrand has a
// kink (the Fresnel term's total internal reflection, the edge of the refracted lobe); each cone meets a circle
// θi = const at an azimuth that becomes a panel edge of that circle, and the θi where it touches such a circle
// are peaks of the θi rule (the integral over φi is not smooth there).
double integrate_eval(const Bsdf& bsdf, const Vec3& wo, double theta_a, double theta_b, std::vector<double> theta_peaks,
                      const std::vector<double>& cones, TransportMode mode, const Rule& rule) {
  const GaussLegendre gl(rule.order);
  const double mu_o = wo.z, sin_o = std::sqrt(std::max(0.0, 1 - mu_o * mu_o)), theta_o = std::acos(mu_o);
  for (const double c : cones)
    for (const double theta : {theta_o - std::acos(c), theta_o + std::acos(c)})
      theta_peaks.push_back(std::acos(std::cos(theta)));  // folded into [0, π]
  const std::vector<double> theta_edges = graded_edges(theta_a, theta_b, theta_peaks, {}, kDelta, rule.max_width);
  double sum = 0;
  for (size_t a = 1; a < theta_edges.size(); ++a) {
    const double t_c = 0.5 * (theta_edges[a] + theta_edges[a - 1]), t_h = 0.5 * (theta_edges[a] - theta_edges[a - 1]);
    for (int p = 0; p < rule.order; ++p) {
      const double theta = t_c + t_h * gl.x[p], mu = std::cos(theta), sin_t = std::sin(theta);
      // wo·wi = sin θo sin θi cos φi + μo μi.
      std::vector<double> kinks;
      for (const double c : cones) {
        const double cos_phi = (c - mu_o * mu) / (sin_o * sin_t);
        if (std::abs(cos_phi) < 1) kinks.push_back(std::acos(cos_phi));
      }
      const std::vector<double> phi_edges = graded_edges(0.0, kPiD, {kPiD}, kinks, kDelta, rule.max_width);
      double row = 0;
      for (size_t b = 1; b < phi_edges.size(); ++b) {
        const double phi_c = 0.5 * (phi_edges[b] + phi_edges[b - 1]), phi_h = 0.5 * (phi_edges[b] - phi_edges[b - 1]);
        for (int q = 0; q < rule.order; ++q) {
          const double phi = phi_c + phi_h * gl.x[q];
          const Vec3 wi(static_cast<float>(sin_t * std::cos(phi)), static_cast<float>(sin_t * std::sin(phi)),
                        static_cast<float>(mu));
          row += phi_h * gl.w[q] * bsdf.eval(wo, wi, mode).r;
        }
      }
      sum += t_h * gl.w[p] * sin_t * row;
    }
  }
  return 2 * sum;
}

// The integral by the fine rule and its error estimate (the difference from the coarse rule).
struct Quadrature {
  double value, error;
};
template <class F>
Quadrature by_two_rules(const F& integral) {
  const double fine = integral(kFine), coarse = integral(kCoarse);
  return {fine, std::abs(fine - coarse)};
}

double tolerance(const Quadrature& q) { return kStatedAccuracy + kPrinted + kFloatEval * std::abs(q.value) + q.error; }

TEST(AlbedoTables, HeaderNamesTheGrid) {
  const std::string inc = read_input_file(source_dir() / "src/materials/microfacet_albedo_data.inc");
  EXPECT_NE(inc.find(fmt::format("{} x {} visible normals per entry", kGrid, kGrid)), std::string::npos);
}

// E(μ, α) with F = 1: ∫ over the upper hemisphere of the rough conductor's eval. Columns from μ = 0 (taken at
// 10⁻⁴) to 1, rows from α ≈ 0.009 to 1.
TEST(AlbedoTables, ConductorEntriesMatchQuadratureOfEval) {
  const ConductorFresnel perfect;  // F = 1
  ASSERT_TRUE(perfect.perfect);
  double worst = 0;
  for (const MicrofacetType type : {MicrofacetType::GGX, MicrofacetType::Beckmann}) {
    for (const int j : {3, 8, 17, 31}) {
      for (const int i : {0, 1, 5, 16, 31}) {
        const MicrofacetDistribution d(type, node_alpha(j), node_alpha(j));
        const RoughConductorBsdf bsdf(d, &perfect, nullptr);
        const Vec3 wo = view_direction(i);
        const Quadrature q = by_two_rules([&](const Rule& r) {
          return integrate_eval(bsdf, wo, 0.0, kPiD / 2, {std::acos(double(wo.z))}, {}, TransportMode::Radiance, r);
        });
        const std::string where =
            fmt::format("{} j {} (alpha {}) i {} (mu {})", type == MicrofacetType::GGX ? "ggx" : "beckmann", j,
                        node_alpha(j), i, wo.z);
        ASSERT_LT(q.error, kMaxQuadratureError) << where;
        const double table = albedo::conductor_E(type, node_mu(i), node_alpha(j));
        EXPECT_NEAR(table, q.value, tolerance(q)) << where;
        worst = std::max(worst, std::abs(table - q.value));
      }
    }
  }
  RecordProperty("worst_deviation", fmt::format("{:.3g}", worst));
}

// E_R(μ, α, η): the rough dielectric's eval over the upper hemisphere; E(μ, α, η): plus the lower hemisphere,
// as energy (TransportMode::Importance leaves out the 1/η² of radiance, as the tables do).
TEST(AlbedoTables, DielectricEntriesMatchQuadratureOfEval) {
  double worst = 0;
  for (const MicrofacetType type : {MicrofacetType::GGX, MicrofacetType::Beckmann}) {
    for (const int k : {2, 13, 16, 30}) {
      const float eta = albedo::eta_node(k);
      for (const int j : {5, 20}) {
        for (const int i : {1, 16, 31}) {
          const MicrofacetDistribution d(type, node_alpha(j), node_alpha(j));
          const RoughDielectricBsdf bsdf(d, eta, nullptr);
          const Vec3 wo = view_direction(i);
          // Peaks of the refracted lobe in θi: the smooth interface's refracted direction (or the horizon under
          // total internal reflection), and a jump: the refraction's half vector wo + η wi lies on the horizon at
          // μi = −μo / η, and no microfacet has such a normal (D = 0 below the horizon, but GGX's D tends to α²/π
          // above it).
          const double sin_t = std::sqrt(1.0 - double(wo.z) * wo.z) / eta;
          const std::vector<double> trans_peaks{std::acos(sin_t < 1 ? -std::sqrt(1 - sin_t * sin_t) : 0.0),
                                                std::acos(std::max(-1.0, -wo.z / double(eta)))};
          // Kinks: for η < 1, total internal reflection begins at microfacets with wo·h = cos θc, sin θc = η,
          // which are the reflections with wo·wi = cos 2θc and the refractions with wo·wi = −η (tangent to
          // the microfacet, where 1 − F grows like a square root); for η > 1 the refracted lobe ends at
          // microfacets seen edge-on, wo·wi = −1/η.
          const std::vector<double> refl_cones =
              eta < 1 ? std::vector<double>{1 - 2 * double(eta) * eta} : std::vector<double>{};
          const std::vector<double> trans_cones{eta < 1 ? -double(eta) : -1 / double(eta)};
          const Quadrature refl = by_two_rules([&](const Rule& r) {
            return integrate_eval(bsdf, wo, 0.0, kPiD / 2, {std::acos(double(wo.z))}, refl_cones,
                                  TransportMode::Importance, r);
          });
          const Quadrature trans = by_two_rules([&](const Rule& r) {
            return integrate_eval(bsdf, wo, kPiD / 2, kPiD, trans_peaks, trans_cones, TransportMode::Importance, r);
          });
          const Quadrature total{refl.value + trans.value, refl.error + trans.error};
          const std::string where =
              fmt::format("{} k {} (eta {}) j {} (alpha {}) i {} (mu {})",
                          type == MicrofacetType::GGX ? "ggx" : "beckmann", k, eta, j, node_alpha(j), i, wo.z);
          ASSERT_LT(total.error, kMaxQuadratureError) << where << ": reflection " << refl.value << " ± " << refl.error
                                                      << ", transmission " << trans.value << " ± " << trans.error;
          const double table_r = albedo::dielectric_ER(type, node_mu(i), node_alpha(j), eta);
          const double table_e = albedo::dielectric_E(type, node_mu(i), node_alpha(j), eta);
          EXPECT_NEAR(table_r, refl.value, tolerance(refl)) << where;
          EXPECT_NEAR(table_e, total.value, tolerance(total)) << where;
          worst = std::max({worst, std::abs(table_r - refl.value), std::abs(table_e - total.value)});
        }
      }
    }
  }
  RecordProperty("worst_deviation", fmt::format("{:.3g}", worst));
}

TEST(AlbedoTables, PrecomputeCommandWritesTheTables) {
  TempDir dir;
  const auto out_file = dir.path() / "t.inc";
  std::string out;
  ASSERT_EQ(run_command(fmt::format("'{}' precompute microfacet-albedo --grid 4 -o '{}'", kozu_binary().string(),
                                    out_file.string()),
                        &out),
            0)
      << out;
  const std::string inc = read_input_file(out_file);
  // Three arrays with 2 x 32 x 32, 2 x 32 x 32 x 32 and 2 x 32 x 32 x 32 numbers.
  const std::regex number(R"([-+]?[0-9]*\.?[0-9]+(e[-+]?[0-9]+)?,)");
  size_t counts[3] = {0, 0, 0};
  const char* names[3] = {"kConductorE", "kDielectricE", "kDielectricER"};
  for (int t = 0; t < 3; ++t) {
    const size_t a = inc.find(names[t]);
    ASSERT_NE(a, std::string::npos) << names[t];
    const size_t b = inc.find("};", a);
    const std::string body = inc.substr(inc.find('{', a), b - inc.find('{', a));
    counts[t] = static_cast<size_t>(
        std::distance(std::sregex_iterator(body.begin(), body.end(), number), std::sregex_iterator()));
  }
  EXPECT_EQ(counts[0], 2u * 32 * 32);
  EXPECT_EQ(counts[1], 2u * 32 * 32 * 32);
  EXPECT_EQ(counts[2], 2u * 32 * 32 * 32);
  // Bad output folder: exit 1, one message naming the file, no partial file.
  EXPECT_EQ(run_command(fmt::format("'{}' precompute microfacet-albedo --grid 4 -o '{}/no/such/dir/t.inc'",
                                    kozu_binary().string(), dir.path().string()),
                        &out),
            1);
  EXPECT_NE(out.find("no/such/dir/t.inc"), std::string::npos) << out;
}

}  // namespace
}  // namespace kozu::test
