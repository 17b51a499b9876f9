// `kozu fit-ltc --brdf ggx|beckmann [--size 64] -o FILE.json`: fits the linearly transformed cosines of a BRDF on
// the seed's grid (src/tools/ltc_fit.h) and writes the table with each entry's fit error. Deterministic: the same
// command gives the same file (fixed stratified samples, a fixed order of fits per column).
// Exit codes: 0 success, 1 failure to write.
#include "apps/commands.h"
#include "core/arena.h"
#include "core/file_io.h"
#include "materials/conductor.h"
#include "tools/ltc_fit.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

namespace kozu::app {

Command add_fit_ltc_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "fit-ltc", "Fit linearly transformed cosines to a BRDF on a θ × √α grid (seed 003 §4) and write the table");
  auto brdf = std::make_shared<std::string>("ggx");
  auto size = std::make_shared<int>(64);
  auto threads = std::make_shared<int>(0);
  auto output = std::make_shared<std::string>();
  cmd->add_option("--brdf", *brdf, "The BRDF (single scattering, F = 1): ggx or beckmann")
      ->check(CLI::IsMember({"ggx", "beckmann"}))
      ->capture_default_str();
  cmd->add_option("--size", *size, "Entries per axis, in [2, 256]")
      ->transform(decimal_integer())
      ->check(CLI::Range(2, 256))
      ->capture_default_str();
  cmd->add_option("--threads", *threads, "Worker threads (0: all)")
      ->transform(decimal_integer())
      ->check(CLI::Range(0, 1024));
  cmd->add_option("-o,--output", *output, "Output table (.json)")->required();
  return [cmd, brdf, size, threads, output]() -> int {
    if (!cmd->parsed()) return 2;
    const MicrofacetType type = *brdf == "ggx" ? MicrofacetType::GGX : MicrofacetType::Beckmann;
    const ConductorFresnel fresnel;  // F = 1
    LtcFitOptions o;
    o.size = *size;
    o.threads = *threads;
    const auto start = std::chrono::steady_clock::now();
    const std::vector<LtcFitEntry> table = fit_ltc_table(
        [&](float alpha, Arena& arena) -> const Bsdf* {
          return arena.make<RoughConductorBsdf>(MicrofacetDistribution(type, alpha, alpha), &fresnel, nullptr);
        },
        o);
    nlohmann::json j;
    j["brdf"] = *brdf;
    j["size"] = *size;
    j["layout"] =
        "entry [i * size + j]: alpha = max((i / (size - 1))^2, 1e-3), theta_v = min(j / (size - 1) * pi/2, 1.57)";
    j["m_inv"] = "M^-1 / (M^-1)_22 as [m00, m02, m11, m20] (row, column); the other entries are 0 and (2, 2) is 1";
    std::vector<float> m_inv, norm, fresnel_norm, error;
    for (const LtcFitEntry& e : table) {
      const Mat3 inv = e.m_inv_normalized();  // glm: inv[column][row]
      m_inv.insert(m_inv.end(), {inv[0][0], inv[2][0], inv[1][1], inv[0][2]});
      norm.push_back(e.norm);
      fresnel_norm.push_back(e.fresnel_norm);
      error.push_back(e.error);
    }
    j["entries"] = {{"m_inv", m_inv}, {"norm", norm}, {"fresnel_norm", fresnel_norm}, {"l1_error", error}};
    std::vector<float> sorted = error;
    std::sort(sorted.begin(), sorted.end());
    const auto pct = [&](double q) { return sorted[static_cast<size_t>(q * double(sorted.size() - 1))]; };
    j["l1_error_summary"] = {{"median", pct(0.5)}, {"p90", pct(0.9)}, {"max", sorted.back()}};
    try {
      write_file_atomic(*output, j.dump(1) + "\n");
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: kozu fit-ltc: %s\n", e.what());
      return 1;
    }
    std::fprintf(stderr, "%s: %d x %d %s entries in %.1f s; L1 error median %.4f, 90th percentile %.4f, max %.4f\n",
                 output->c_str(), *size, *size, brdf->c_str(),
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), pct(0.5), pct(0.9),
                 sorted.back());
    return 0;
  };
}

}  // namespace kozu::app
