// Tests for the procedural images (textures/procedural_image.h) and the procedural volumes a medium generates at
// load (media/procedural_volume.h, VoxelSource): what each image holds, determinism, the cache file written once,
// the scene keys rewritten and refused, and the built-in demo scene, which needs no file.
#include "textures/procedural_image.h"

#include "core/error.h"
#include "io/image_io.h"
#include "media/procedural_volume.h"
#include "media/sggx_medium.h"
#include "scene/scene_loader.h"
#include "support/render_test.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace kozu {
namespace {

namespace fs = std::filesystem;

Vec3 texel(const ProceduralImage& img, int x, int y) {
  const size_t o = 3 * (static_cast<size_t>(y) * img.width + x);
  return Vec3(img.rgb[o], img.rgb[o + 1], img.rgb[o + 2]);
}

TEST(ProceduralImage, EveryImageIsFiniteAndDeterministic) {
  for (const std::string& name : procedural_image_names()) {
    const ProceduralImage a = make_procedural_image(name, 64), b = make_procedural_image(name, 64);
    EXPECT_EQ(a.width, 64) << name;
    EXPECT_EQ(a.height, name == "dusk_sky" ? 32 : 64) << name;
    ASSERT_EQ(a.rgb.size(), 3u * a.width * a.height) << name;
    EXPECT_EQ(a.rgb, b.rgb) << name;
    for (float v : a.rgb) {
      ASSERT_TRUE(std::isfinite(v)) << name;
      ASSERT_GE(v, 0.0f) << name;
    }
  }
}

TEST(ProceduralImage, CobblestoneNormalsAreUnitAndFaceOutOnAverage) {
  const ProceduralImage img = make_procedural_image("cobblestone_normal", 128);
  Vec3 mean(0.0f);
  int tilted = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const Vec3 n = 2.0f * texel(img, x, y) - 1.0f;
      ASSERT_NEAR(glm::length(n), 1.0f, 1e-4f);
      ASSERT_GT(n.z, 0.0f);
      mean += n;
      tilted += n.z < 0.99f;
    }
  mean /= static_cast<float>(img.width * img.height);
  // A periodic height field has slopes that average to zero: the mean normal points straight out.
  EXPECT_NEAR(mean.x, 0.0f, 0.02f);
  EXPECT_NEAR(mean.y, 0.0f, 0.02f);
  // And the stones' shoulders tilt a good share of the texels (the map is not flat).
  EXPECT_GT(tilted, img.width * img.height / 5);
}

TEST(ProceduralImage, StainedGlassIsARoundWindowInBlackStone) {
  const int n = 256;
  const ProceduralImage img = make_procedural_image("stained_glass", n);
  // Corners (outside the rim): black. The centre: amber glass, red above blue.
  for (const auto& [x, y] : {std::pair{0, 0}, {n - 1, 0}, {0, n - 1}, {n - 1, n - 1}})
    EXPECT_EQ(texel(img, x, y), Vec3(0.0f));
  const Vec3 centre = texel(img, n / 2, n / 2);
  EXPECT_GT(centre.r, centre.b * 4.0f);
  EXPECT_GT(centre.g, centre.b * 2.0f);
  // Every value is a transmittance in [0, 1], and colour dominates: mean saturation well above grey.
  float max_value = 0.0f;
  for (float v : img.rgb) max_value = std::max(max_value, v);
  EXPECT_LE(max_value, 1.0f);
  EXPECT_GT(max_value, 0.5f);
}

TEST(ProceduralImage, DuskSkyGlowsTowardsTheSunAndIsDarkBelow) {
  const ProceduralImage img = make_procedural_image("dusk_sky", 256);
  const auto lum = [](const Vec3& c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; };
  // u = 0.5 looks down -z, where the sun is, 3 degrees up; u = 0 looks down +z.
  const int w = img.width, h = img.height;
  const int sun_row = static_cast<int>((90.0f - 3.0f) / 180.0f * static_cast<float>(h));
  EXPECT_GT(lum(texel(img, w / 2, sun_row)), 3.0f * lum(texel(img, 0, sun_row)));
  EXPECT_LT(lum(texel(img, 0, h - 1)), 0.1f);                       // the ground
  EXPECT_GT(lum(texel(img, 0, h / 2 - 2)), lum(texel(img, 0, 0)));  // a warm horizon over a blue zenith
}

TEST(ProceduralImage, RefusesUnknownNamesAndSizes) {
  EXPECT_THROW(make_procedural_image("marble", 64), std::invalid_argument);
  EXPECT_THROW(make_procedural_image("stained_glass", kProceduralImageMinResolution - 1), std::invalid_argument);
  EXPECT_THROW(make_procedural_image("stained_glass", kProceduralImageMaxResolution + 1), std::invalid_argument);
}

TEST(ProceduralImage, FileIsWrittenOnceAndReadBack) {
  test::TempDir dir;
  const fs::path f = procedural_image_file("stained_glass", 32, dir.path());
  EXPECT_EQ(f.parent_path(), dir.path() / "procedural");
  const Image img = read_image(f);
  ASSERT_EQ(img.width, 32);
  ASSERT_EQ(img.height, 32);
  const ProceduralImage expected = make_procedural_image("stained_glass", 32);
  for (size_t i = 0; i < expected.rgb.size(); ++i)
    ASSERT_NEAR(img.data[i / 3 * img.channels + i % 3], expected.rgb[i], 1e-6f);
  // A second call finds the file: not rewritten.
  const auto written = fs::last_write_time(f);
  fs::last_write_time(f, written - std::chrono::hours(1));
  EXPECT_EQ(procedural_image_file("stained_glass", 32, dir.path()), f);
  EXPECT_EQ(fs::last_write_time(f), written - std::chrono::hours(1));
}

TEST(ProceduralImage, SceneKeysBecomeFiles) {
  test::TempDir dir;
  Json root = Json::parse(R"({"materials": {"m": {"type": "diffuse",
      "albedo": {"type": "image", "procedural": "cobblestone_albedo", "resolution": 32, "uv_scale": [4, 4]}}},
      "lights": [{"type": "environment", "procedural": "dusk_sky", "resolution": 32}]})");
  expand_procedural_images(root, "s.json", dir.path());
  const Json& albedo = root["materials"]["m"]["albedo"];
  EXPECT_FALSE(albedo.contains("procedural"));
  EXPECT_FALSE(albedo.contains("resolution"));
  EXPECT_EQ(albedo["uv_scale"], Json::parse("[4, 4]"));
  EXPECT_TRUE(fs::is_regular_file(albedo["file"].get<std::string>()));
  EXPECT_TRUE(fs::path(albedo["file"].get<std::string>()).is_absolute());
  EXPECT_TRUE(fs::is_regular_file(root["lights"][0]["file"].get<std::string>()));
}

TEST(ProceduralImage, SceneKeyErrorsNameTheirPath) {
  test::TempDir dir;
  const auto error = [&](const std::string& text) {
    Json root = Json::parse(text);
    try {
      expand_procedural_images(root, "s.json", dir.path());
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error(R"({"a": {"type": "image", "procedural": "marble"}})")
                .find("s.json: /a/procedural: unknown procedural "
                      "image \"marble\""),
            std::string::npos);
  EXPECT_NE(error(R"({"a": [{"type": "image", "procedural": "dusk_sky", "file": "x.exr"}]})").find("/a/0/procedural"),
            std::string::npos);
  EXPECT_NE(error(R"({"a": {"type": "image", "procedural": 3}})").find("expected the name"), std::string::npos);
  EXPECT_NE(error(R"({"a": {"type": "image", "procedural": "dusk_sky", "resolution": 1e9}})").find("/a/resolution"),
            std::string::npos);
  EXPECT_NE(error(R"({"a": {"type": "image", "procedural": "dusk_sky", "resolution": 100000}})").find("outside"),
            std::string::npos);
  // Another type's "procedural" key is left to that type's parser.
  EXPECT_EQ(error(R"({"a": {"type": "sggx", "procedural": "fabric"}})"), "no error");
}

std::string load_error(const std::string& json) {
  try {
    load_scene_text(json, "v.json", ".");
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

std::string volume_scene(const std::string& medium) {
  return R"({"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "resolution": [8, 8]}, "media": {"m": )" + medium +
         R"(}, "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "m"}],
             "lights": [{"type": "environment", "radiance": 1}]})";
}

TEST(ProceduralVolumeMedium, GeneratedAtLoadLikeTheFile) {
  const auto scene = load_scene_text(
      volume_scene(R"({"type": "sggx", "procedural": "fabric", "resolution": 32, "storage": "float"})"), "v.json", ".");
  ASSERT_EQ(scene->media.size(), 1u);
  const auto* m = dynamic_cast<const SggxVoxelMedium*>(scene->media[0].get());
  ASSERT_NE(m, nullptr);
  const VoxelGrid& g = m->levels().front();
  EXPECT_EQ(g.resolution(), Vec3i(32, 8, 32));
  const VoxelGrid expected = make_woven_fabric(32);
  for (int k = 0; k < 32; k += 3)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 32; i += 3) ASSERT_EQ(g.voxel_density(i, j, k), expected.voxel_density(i, j, k));
  // The yarn's settings reach the generator.
  const auto yarn = load_scene_text(
      volume_scene(
          R"({"type": "sggx", "procedural": "yarn", "resolution": 24, "strands": 40, "strand_width": 0.2, "twists": 3, "storage": "float"})"),
      "v.json", ".");
  YarnSettings y;
  y.strands = 40;
  y.strand_radius = 0.1f;
  y.twists_per_unit = 3.0f;
  const VoxelGrid expected_yarn = make_yarn_ball(24, y), default_yarn = make_yarn_ball(24);
  const VoxelGrid& gy = dynamic_cast<const SggxVoxelMedium&>(*yarn->media[0]).levels().front();
  int differ_from_default = 0;
  for (int k = 0; k < 24; ++k)
    for (int j = 0; j < 24; ++j)
      for (int i = 0; i < 24; ++i) {
        ASSERT_EQ(gy.voxel_density(i, j, k), expected_yarn.voxel_density(i, j, k));
        differ_from_default += gy.voxel_density(i, j, k) != default_yarn.voxel_density(i, j, k);
      }
  EXPECT_GT(differ_from_default, 0);
  // A grid medium takes the smoke.
  EXPECT_EQ(load_error(volume_scene(R"({"type": "grid", "procedural": "smoke", "resolution": 16})")), "no error");
}

TEST(ProceduralVolumeMedium, ErrorsNameTheKey) {
  EXPECT_NE(load_error(volume_scene(R"({"type": "sggx", "procedural": "smoke", "resolution": 16})"))
                .find("/media/m/procedural: the grid has no SGGX channels"),
            std::string::npos);
  EXPECT_NE(load_error(volume_scene(R"({"type": "sggx", "procedural": "fabric", "file": "a.kvox"})"))
                .find("/media/m/procedural: give either"),
            std::string::npos);
  EXPECT_NE(load_error(volume_scene(R"({"type": "grid", "procedural": "cloud"})")).find("/media/m/procedural"),
            std::string::npos);
  EXPECT_NE(load_error(volume_scene(R"({"type": "grid", "procedural": "smoke", "resolution": 4})"))
                .find("/media/m/resolution"),
            std::string::npos);
  EXPECT_NE(load_error(volume_scene(R"({"type": "grid"})")).find("/media/m"), std::string::npos);
  // The yarn's settings out of range, and the yarn's keys on the fabric, which has no strands.
  const std::pair<const char*, const char*> yarn_cases[] = {
      {R"("yarn", "strands": 15)", "/media/m/strands: 15: expected a multiple of 10"},
      {R"("yarn", "strand_width": 1)", "/media/m/strand_width"},
      {R"("yarn", "twists": -1)", "/media/m/twists"},
      {R"("fabric", "strands": 40)", "/media/m/strands"}};
  for (const auto& [keys, message] : yarn_cases) {
    const std::string e =
        load_error(volume_scene(fmt::format(R"({{"type": "sggx", "resolution": 16, "procedural": {}}})", keys)));
    EXPECT_NE(e.find(message), std::string::npos) << keys << ": " << e;
  }
}

TEST(ProceduralVolumeMedium, RefusedBeforeAllocatingWhatDoesNotFit) {
  setenv("KOZU_MEMORY_LIMIT", "256M", 1);
  const std::string e = load_error(volume_scene(R"({"type": "sggx", "procedural": "yarn", "resolution": 1024})"));
  unsetenv("KOZU_MEMORY_LIMIT");
  EXPECT_NE(e.find("/media/m/procedural: procedural yarn at resolution 1024: a 1024 x 1024 x 1024 grid needs about"),
            std::string::npos)
      << e;
}

}  // namespace
}  // namespace kozu
