// Image-level white furnace of the rough conductors: scenes/furnace_{compensated,none}.json, a row of
// F = 1 spheres with roughness 0, 0.2, ..., 1 in a uniform environment of radiance 1 (the images in
// docs/images/furnace_*.png). With `compensated` every sphere renders 1; with `none` the rough ones
// are darker by the single-scattering loss, which the albedo table predicts.
//
// Each sphere is measured on a 5 x 5 block of pixels around its centre (the sphere is ~10 px in radius). Tolerance: 5
// standard errors of the block mean plus the 1 % the issue allows for the compensation (table and interpolation error).
#include "support/render_test.h"

#include "core/file_io.h"
#include "materials/microfacet_albedo.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace kozu::test {
namespace {

constexpr int kWidth = 240, kHeight = 40;
constexpr float kRoughness[6] = {0.0f, 0.2f, 0.4f, 0.6f, 0.8f, 1.0f};

struct SphereMean {
  double mean = 0, standard_error = 0;
  std::vector<float> mu;  // cos θ between the view ray and the normal at each block pixel (approximate)
};

// Renders the scene file at kWidth x kHeight and measures a 5 x 5 block at each sphere's centre.
// `multiscatter` (optional) replaces the mode of every rough sphere.
std::vector<SphereMean> render_row(const std::string& file, int spp, const std::string& multiscatter = "") {
  nlohmann::json j = nlohmann::json::parse(read_input_file(source_dir() / "scenes" / file));
  if (!multiscatter.empty())
    for (auto& [name, m] : j["materials"].items())
      if (m.contains("multiscatter")) m["multiscatter"] = multiscatter;
  j["camera"]["resolution"] = {kWidth, kHeight};
  const TestRender r = render_json(j.dump(), spp, 0, 7);
  // Sphere i's centre is at x = (i - 2.5) * 1.25 in the focal plane 9.5 away; fov 12° vertical.
  const double half_height = 9.5 * std::tan(6.0 * 3.14159265358979 / 180.0);
  const double half_width = half_height * kWidth / kHeight;
  std::vector<SphereMean> out;
  for (int i = 0; i < 6; ++i) {
    const int cx = static_cast<int>(kWidth * 0.5 + (i - 2.5) * 1.25 / half_width * kWidth * 0.5);
    const int cy = kHeight / 2;
    double sum = 0, var = 0;
    int n = 0;
    for (int y = cy - 2; y <= cy + 2; ++y) {
      for (int x = cx - 2; x <= cx + 2; ++x) {
        sum += r.film.mean(x, y).g;
        var += r.film.variance_of_mean(x, y).g;
        ++n;
      }
    }
    // The block pixel at offset d from the centre sees the sphere at sin θ ≈ d / R, R the radius in pixels.
    const double dist = std::hypot(9.5, (i - 2.5) * 1.25);
    const double radius_px = 0.5 / dist * (kHeight * 0.5) / std::tan(6.0 * 3.14159265358979 / 180.0);
    std::vector<float> mu;
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx)
        mu.push_back(static_cast<float>(std::sqrt(std::max(0.0, 1.0 - (dx * dx + dy * dy) / (radius_px * radius_px)))));
    out.push_back({sum / n, std::sqrt(var) / n, mu});
  }
  return out;
}

TEST(FurnaceScene, CompensatedConductorsRenderOne) {
  const std::vector<SphereMean> m = render_row("furnace_compensated.json", 256);
  for (int i = 0; i < 6; ++i) {
    fmt::print("compensated roughness {:.1f}: {:.4f} +- {:.4f}\n", kRoughness[i], m[i].mean, m[i].standard_error);
    EXPECT_NEAR(m[i].mean, 1.0, 0.01 + 5.0 * m[i].standard_error) << "roughness " << kRoughness[i];
  }
}

// The Heitz et al. 2016 random walk conserves energy exactly (every walk exits with weight 1).
TEST(FurnaceScene, StochasticConductorsRenderOne) {
  const std::vector<SphereMean> m = render_row("furnace_compensated.json", 128, "stochastic");
  for (int i = 0; i < 6; ++i) {
    fmt::print("stochastic roughness {:.1f}: {:.4f} +- {:.4f}\n", kRoughness[i], m[i].mean, m[i].standard_error);
    EXPECT_NEAR(m[i].mean, 1.0, 0.01 + 5.0 * m[i].standard_error) << "roughness " << kRoughness[i];
  }
}

TEST(FurnaceScene, UncompensatedConductorsLoseTheTableEnergy) {
  const std::vector<SphereMean> m = render_row("furnace_none.json", 256);
  for (int i = 0; i < 6; ++i) {
    const float alpha = kRoughness[i] * kRoughness[i];
    // The table's E averaged over the block's view angles (cos θ from 1 down to ~0.7 at its corners).
    double expected = 0;
    for (const float mu : m[i].mu) expected += i == 0 ? 1.0 : albedo::conductor_E(MicrofacetType::GGX, mu, alpha);
    expected /= static_cast<double>(m[i].mu.size());
    fmt::print("none roughness {:.1f}: {:.4f} +- {:.4f} (table E {:.4f})\n", kRoughness[i], m[i].mean,
               m[i].standard_error, expected);
    EXPECT_NEAR(m[i].mean, expected, 0.01 + 5.0 * m[i].standard_error) << "roughness " << kRoughness[i];
  }
  // "Visibly darker": the roughest sphere keeps under a third of the light at normal incidence (1 − ln 2).
  EXPECT_LT(m[5].mean, 0.35);
}

}  // namespace
}  // namespace kozu::test
