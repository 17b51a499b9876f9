// `kozu texture filter-normals` as a user runs it: an 8-bit PNG normal map and a gloss map in, two tiled files with
// every mip level out (OpenEXR and .tx), flat maps keeping their gloss, and one-line errors that write nothing.
#include "apps/cli_helpers.h"
#include "io/image_io.h"
#include "textures/normal_gloss_files.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace kozu::test {
namespace {

void write_png(const std::filesystem::path& file, int w, int h, int channels, const std::vector<float>& v) {
  auto out = OIIO::ImageOutput::create(file.string());
  ASSERT_TRUE(out);
  OIIO::ImageSpec spec(w, h, channels, OIIO::TypeDesc::UINT8);
  ASSERT_TRUE(out->open(file.string(), spec));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, v.data()));
  out->close();
}

// 32 x 16 texels: a bump field tilted by up to 0.5 rad (so coarse levels lose gloss), encoded c = (n + 1) / 2.
std::filesystem::path write_bumps(const std::filesystem::path& file) {
  std::vector<float> rgb;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 32; ++x) {
      const double tx = 0.5 * std::sin(1.7 * x + 0.3 * y), ty = 0.5 * std::cos(2.3 * y + 0.9 * x);
      const double nx = std::sin(tx), ny = std::sin(ty), nz = std::sqrt(std::max(0.0, 1 - nx * nx - ny * ny));
      for (double n : {nx, ny, nz}) rgb.push_back(float(0.5 * (n + 1)));
    }
  write_png(file, 32, 16, 3, rgb);
  return file;
}

TEST(CliFilterNormals, WritesEveryLevel) {
  TempDir dir;
  const auto normal = write_bumps(dir.path() / "n.png");
  write_png(dir.path() / "g.png", 32, 16, 1, std::vector<float>(32 * 16, 0.8f));
  for (const std::string model : {"macro", "micro"}) {
    const auto on = dir.path() / ("on-" + model + ".exr"), og = dir.path() / ("og-" + model + ".tx");
    std::string out;
    ASSERT_EQ(
        run_command(fmt::format("{} texture filter-normals '{}' --gloss '{}' -o '{}' '{}' --model {}", kozu(),
                                normal.string(), (dir.path() / "g.png").string(), on.string(), og.string(), model),
                    &out),
        0)
        << out;
    EXPECT_NE(out.find("6 mip levels"), std::string::npos) << out;
    for (const auto& file : {on, og}) {
      const ImageInfo info = probe_image(file);
      EXPECT_TRUE(info.tiled);
      EXPECT_EQ(info.mip_levels, 6);  // 32 x 16, 16 x 8, 8 x 4, 4 x 2, 2 x 1, 1 x 1
    }
    // Level 0 is the map as authored (8-bit gloss 0.8 = 204/255); the coarsest has lost gloss to the bumps, and its
    // normal is a unit vector encoded c = (n + 1) / 2.
    EXPECT_NEAR(read_mip_level(og, 0).data[0], 204.0f / 255.0f, 1e-6);
    const Image g5 = read_mip_level(og, 5), n5 = read_mip_level(on, 5);
    EXPECT_LT(g5.data[0], 0.7f);
    EXPECT_GT(g5.data[0], 0.0f);
    double len2 = 0;
    for (int c = 0; c < 3; ++c) len2 += std::pow(2.0 * n5.data[size_t(c)] - 1.0, 2);
    EXPECT_NEAR(len2, 1.0, 1e-5);
  }
  // A flat map with one gloss value keeps it at every level.
  write_png(dir.path() / "flat.png", 8, 8, 3, [] {
    std::vector<float> v;
    for (int i = 0; i < 64; ++i) v.insert(v.end(), {0.5f, 0.5f, 1.0f});
    return v;
  }());
  std::string out;
  ASSERT_EQ(run_command(fmt::format("{} texture filter-normals '{}' --gloss-value 0.37 -o '{}' '{}'", kozu(),
                                    (dir.path() / "flat.png").string(), (dir.path() / "fn.exr").string(),
                                    (dir.path() / "fg.exr").string()),
                        &out),
            0)
      << out;
  for (int level = 0; level < 4; ++level) EXPECT_NEAR(read_mip_level(dir.path() / "fg.exr", level).data[0], 0.37, 1e-6);
}

TEST(CliFilterNormals, OneLineErrorsWriteNothing) {
  TempDir dir;
  const auto normal = write_bumps(dir.path() / "n.png");
  write_png(dir.path() / "small.png", 8, 8, 1, std::vector<float>(64, 0.5f));
  const std::string outputs =
      fmt::format("-o '{}' '{}'", (dir.path() / "a.exr").string(), (dir.path() / "b.exr").string());
  const struct {
    std::string args;
    int code;
    std::string message;
  } cases[] = {
      {"--model foo " + outputs, 1, "error: kozu texture filter-normals: --model: 'foo' is not one of macro, micro"},
      {"--gloss-value 1.5 " + outputs, 1,
       "error: kozu texture filter-normals: --gloss-value: expected a number in [0, 1]"},
      {fmt::format("--gloss '{}' {}", (dir.path() / "small.png").string(), outputs), 1,
       "small.png: the gloss map is 8 x 8, the normal map 32 x 16"},
      {fmt::format("-o '{}' '{}'", (dir.path() / "a.png").string(), (dir.path() / "b.exr").string()), 1,
       "the outputs are .exr, .tx or .tif files"},
      {fmt::format("-o '{}' '{}'", (dir.path() / "a.exr").string(), (dir.path() / "a.exr").string()), 1,
       "every output needs its own file"},
      {fmt::format("-o '{}'", (dir.path() / "a.exr").string()), 2, "--output"},
  };
  for (const auto& c : cases) {
    std::string out;
    EXPECT_EQ(run_command(fmt::format("{} texture filter-normals '{}' {}", kozu(), normal.string(), c.args), &out),
              c.code)
        << c.args << "\n"
        << out;
    EXPECT_NE(out.find(c.message), std::string::npos) << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "a.exr"));
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "b.exr"));
  }
  std::string out;
  EXPECT_EQ(run_command(fmt::format("{} texture filter-normals '{}' {}", kozu(), (dir.path() / "missing.png").string(),
                                    outputs),
                        &out),
            1);
  EXPECT_NE(out.find("missing.png: image file not found"), std::string::npos) << out;
}

}  // namespace
}  // namespace kozu::test
