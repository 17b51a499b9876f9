// The checked-in albedo tables (src/materials/microfacet_albedo_data.inc) are what
// `kozu precompute microfacet-albedo` writes: spot entries recomputed here with the generator's own
// integration (128 x 128 jittered grid, seeded from the entry) must match to the file's 6 significant
// digits, so the file is reproducible and not hand-edited. The command itself is run on a tiny grid.
#include "support/render_test.h"

#include "core/file_io.h"
#include "materials/microfacet_albedo.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <regex>

namespace kozu::test {
namespace {

constexpr int kGrid = 128;  // the grid the checked-in file was generated with (its header says so)

float node_alpha(int j) {
  const float r = j / float(albedo::kRoughNodes - 1);
  return r * r;
}
float node_mu(int i) { return i / float(albedo::kMuNodes - 1); }

TEST(AlbedoTables, HeaderNamesTheGrid) {
  const std::string inc = read_input_file(source_dir() / "src/materials/microfacet_albedo_data.inc");
  EXPECT_NE(inc.find(fmt::format("{} x {} visible normals per entry", kGrid, kGrid)), std::string::npos);
}

TEST(AlbedoTables, ConductorEntriesRegenerate) {
  for (const MicrofacetType type : {MicrofacetType::GGX, MicrofacetType::Beckmann}) {
    for (const int j : {3, 17, 31}) {
      for (const int i : {0, 9, 31}) {
        const MicrofacetDistribution d(type, node_alpha(j), node_alpha(j));
        const double fresh = albedo::integrate_conductor(d, node_mu(i), kGrid);
        const float table = albedo::conductor_E(type, node_mu(i), node_alpha(j));
        EXPECT_NEAR(table, fresh, 1e-5 * fresh) << "j " << j << " i " << i;
      }
    }
  }
}

TEST(AlbedoTables, DielectricEntriesRegenerate) {
  for (const MicrofacetType type : {MicrofacetType::GGX, MicrofacetType::Beckmann}) {
    for (const int k : {2, 13, 16, 30}) {
      const float eta = albedo::eta_node(k);
      for (const int j : {5, 20}) {
        for (const int i : {1, 16, 31}) {
          const MicrofacetDistribution d(type, node_alpha(j), node_alpha(j));
          double refl, total;
          albedo::integrate_dielectric(d, node_mu(i), eta, kGrid, &refl, &total);
          EXPECT_NEAR(albedo::dielectric_E(type, node_mu(i), node_alpha(j), eta), total, 1e-5 * total)
              << "k " << k << " j " << j << " i " << i;
          EXPECT_NEAR(albedo::dielectric_ER(type, node_mu(i), node_alpha(j), eta), refl, 1e-5 * refl + 1e-7)
              << "k " << k << " j " << j << " i " << i;
        }
      }
    }
  }
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
