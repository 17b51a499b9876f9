// Normal and gloss mip filtering of the standard material and of textured roughness
// (materials/normal_gloss_filtering.h; D. Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course
// Advances in Real-Time Rendering in Games, §2, Algorithm 3): a plain standard roughness, a roughness image read
// through a channel (glTF's metallicRoughness "g"), a conductor's gloss image, a roughness image of another size, and a
// glTF asset.
//
// The far floor of test_normal_gloss_filtering_stat (a mirror-like floor of random facets, RMS slope 0.24, tiled
// 4000 times, out to the horizon, reflecting a large emitting sphere). Reference: "filter": "closest" on the normal
// map and the roughness (level 0, where filtering changes nothing), 1024 spp; filtered (the default) and unfiltered
// (normal_gloss_filtering false) at 16 spp. Checked: the filtered RMS error of the far floor's 8 x 8 blocks is at most
// a third of the unfiltered one (the bound of test_normal_gloss_filtering_stat; measured ratios in docs/wwii.md), and
// with "closest" lookups the key changes no bit.
#include "support/far_floor.h"
#include "support/render_test.h"
#include "support/sanitizer.h"

#include "io/gltf_test_files.h"
#include "io/image_io.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

namespace kozu::test {
namespace {

constexpr int kWidth = 128, kHeight = 32, kMapSize = 128;

// material: the floor's JSON without its closing brace; map_keys go into the normal map and the roughness image.
std::string floor_scene(const std::string& material) {
  return fmt::format(R"({{"camera": {{"position": [0, 0, 1], "look_at": [0, 100, 1], "up": [0, 0, 1], "fov": 20,
                                       "resolution": [{}, {}]}},
    "render": {{"max_depth": 2}},
    "materials": {{"floor": {}}},
    "shapes": [{{"type": "quad", "material": "floor",
                 "vertices": [[-2000, -2000, 0], [2000, -2000, 0], [2000, 2000, 0], [-2000, 2000, 0]]}},
               {{"type": "sphere", "center": [0, 1000, 101], "radius": 100, "emission": 4}}],
    "lights": [{{"type": "environment", "radiance": 0.05}}]}})",
                     kWidth, kHeight, material);
}

std::filesystem::path write_facet_map(const std::filesystem::path& file) {
  std::mt19937 rng(29);
  std::normal_distribution<float> slope(0.0f, 0.24f / std::sqrt(2.0f));
  std::vector<float> texels(size_t(kMapSize) * kMapSize * 3);
  for (size_t i = 0; i < texels.size(); i += 3) {
    const float sx = slope(rng), sy = slope(rng);
    const float inv = 1.0f / std::sqrt(sx * sx + sy * sy + 1.0f);
    texels[i] = 0.5f * (1.0f - sx * inv);
    texels[i + 1] = 0.5f * (1.0f - sy * inv);
    texels[i + 2] = 0.5f * (1.0f + inv);
  }
  return write_test_exr(file, kMapSize, kMapSize,
                        [&](int x, int y, int c) { return texels[(size_t(y) * kMapSize + x) * 3 + c]; });
}

// A size x size image whose channel `channel` holds the value v0 or v1 in a checkerboard of 8-texel squares and the
// other channels noise (so that a wrong channel shows).
std::filesystem::path write_checker(const std::filesystem::path& file, int size, int channel, float v0, float v1) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> noise(0.0f, 1.0f);
  std::vector<float> texels(size_t(size) * size * 3);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x)
      for (int c = 0; c < 3; ++c)
        texels[(size_t(y) * size + x) * 3 + c] = c == channel ? (((x / 8 + y / 8) % 2) ? v1 : v0) : noise(rng);
  return write_test_exr(file, size, size, [&](int x, int y, int c) { return texels[(size_t(y) * size + x) * 3 + c]; });
}

struct Errors {
  double filtered, unfiltered, mean;
};

// floor(keys): the material's JSON for the given extra normal-map keys and extra material keys.
Errors far_floor_errors(const std::function<std::string(const std::string&, const std::string&)>& floor) {
  const TestRender ref = render_json(floor_scene(floor(R"(, "filter": "closest")", "")), kSanitized ? 128 : 1024, 0, 1);
  const TestRender filtered = render_json(floor_scene(floor("", "")), 16, 0, 2);
  const TestRender plain = render_json(floor_scene(floor("", R"(, "normal_gloss_filtering": false)")), 16, 0, 3);
  const std::vector<double> r = far_floor_blocks(ref.film), f = far_floor_blocks(filtered.film),
                            p = far_floor_blocks(plain.film);
  double mean = 0;
  for (double v : r) mean += v / static_cast<double>(r.size());
  const Errors e{rms_difference(f, r), rms_difference(p, r), mean};
  fmt::print("far floor: reference mean {:.4f}; RMS block error filtered {:.1f} %, unfiltered {:.1f} %\n", mean,
             100 * e.filtered / mean, 100 * e.unfiltered / mean);
  return e;
}

// Level-0 lookups everywhere: the key changes no bit.
void expect_closest_unchanged(const std::function<std::string(const std::string&, const std::string&)>& floor) {
  const TestRender on = render_json(floor_scene(floor(R"(, "filter": "closest")", "")), 2, 0, 5);
  const TestRender off =
      render_json(floor_scene(floor(R"(, "filter": "closest")", R"(, "normal_gloss_filtering": false)")), 2, 0, 5);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) ASSERT_EQ(on.film.mean(x, y).g, off.film.mean(x, y).g) << x << ", " << y;
}

// r = sqrt(α) of gloss 0.9 (Chan 2018 eq. 2): the far floor's own roughness.
const double kRoughness09 = std::sqrt(std::sqrt(2.0 / (1.0 + std::exp2(18.0 * 0.9))));

TEST(RoughnessFilteringScene, StandardWithAPlainRoughness) {
  TempDir dir;
  const std::string map = write_facet_map(dir.path() / "bumps.exr").string();
  const auto floor = [&](const std::string& map_keys, const std::string& keys) {
    return fmt::format(R"({{"type": "standard", "base_color": 1, "metallic": 1, "roughness": {},
                            "normal_map": {{"type": "image", "file": "{}", "uv_scale": [4000, 4000]{}}}{}}})",
                       kRoughness09, map, map_keys, keys);
  };
  const Errors e = far_floor_errors(floor);
  EXPECT_LE(e.filtered, e.unfiltered / 3.0);
  expect_closest_unchanged(floor);
}

TEST(RoughnessFilteringScene, StandardWithARoughnessImageChannel) {
  TempDir dir;
  const std::string map = write_facet_map(dir.path() / "bumps.exr").string();
  // Channel g (glTF's metallicRoughness roughness), the far floor's roughness and 1.5 times it, scaled by 0.5.
  const std::string rough =
      write_checker(dir.path() / "mr.exr", kMapSize, 1, 2 * kRoughness09, 3 * kRoughness09).string();
  const auto floor = [&](const std::string& map_keys, const std::string& keys) {
    return fmt::format(R"({{"type": "standard", "base_color": 1, "metallic": 1,
                            "roughness": {{"type": "image", "file": "{}", "channel": "g", "scale": 0.5,
                                           "uv_scale": [4000, 4000]{}}},
                            "normal_map": {{"type": "image", "file": "{}", "uv_scale": [4000, 4000]{}}}{}}})",
                       rough, map_keys, map, map_keys, keys);
  };
  const Errors e = far_floor_errors(floor);
  EXPECT_LE(e.filtered, e.unfiltered / 3.0);
  expect_closest_unchanged(floor);
}

TEST(RoughnessFilteringScene, ConductorWithAGlossImage) {
  TempDir dir;
  const std::string map = write_facet_map(dir.path() / "bumps.exr").string();
  const std::string gloss = write_checker(dir.path() / "gloss.exr", kMapSize, 0, 0.9f, 0.85f).string();
  const auto floor = [&](const std::string& map_keys, const std::string& keys) {
    return fmt::format(R"({{"type": "conductor",
                            "gloss": {{"type": "image", "file": "{}", "uv_scale": [4000, 4000]{}}},
                            "normal_map": {{"type": "image", "file": "{}", "uv_scale": [4000, 4000]{}}}{}}})",
                       gloss, map_keys, map, map_keys, keys);
  };
  const Errors e = far_floor_errors(floor);
  EXPECT_LE(e.filtered, e.unfiltered / 3.0);
}

// The files a load builds, in a conversion folder of the test's own.
std::vector<std::string> built_files(const std::filesystem::path& tx) {
  std::vector<std::string> names;
  for (const auto& f : std::filesystem::directory_iterator(tx)) {
    const std::string n = f.path().filename().string();
    for (const char* suffix : {".normal.exr", ".gloss.exr", ".roughness.exr", ".source-gloss.exr"})
      if (n.size() > std::string_view(suffix).size() && n.ends_with(suffix)) names.push_back(suffix);
  }
  std::sort(names.begin(), names.end());
  return names;
}

// A roughness image of another size than the normal map is resampled to the map's texels (bilinear, wrapping).
TEST(RoughnessFilteringScene, ARoughnessImageOfAnotherSizeIsResampled) {
  TempDir dir;
  const std::string map = write_facet_map(dir.path() / "bumps.exr").string();
  const std::string rough = write_checker(dir.path() / "r.exr", 48, 0, 0.2f, 0.4f).string();
  SceneLoadOptions options;
  options.textures.convert_dir = dir.path() / "tx";
  const auto scene =
      load_scene_text(floor_scene(fmt::format(R"({{"type": "standard", "roughness": {{"type": "image", "file": "{}"}},
                                   "normal_map": {{"type": "image", "file": "{}"}}}})",
                                              rough, map)),
                      "scene.json", dir.path(), options);
  EXPECT_EQ(built_files(dir.path() / "tx"),
            (std::vector<std::string>{".gloss.exr", ".normal.exr", ".roughness.exr", ".source-gloss.exr"}));
  const Image source = read_image([&] {
    for (const auto& f : std::filesystem::directory_iterator(dir.path() / "tx"))
      if (f.path().filename().string().ends_with(".source-gloss.exr")) return f.path();
    return std::filesystem::path();
  }());
  EXPECT_EQ(source.width, kMapSize);
  EXPECT_EQ(source.height, kMapSize);
  // Inside a square of 0.2 (well inside, away from the bilinear blend), the gloss of α = 0.04.
  const double g = std::log2(2.0 / (0.04 * 0.04) - 1.0) / 18.0;
  EXPECT_NEAR(source.data[(5 * size_t(kMapSize) + 5) * size_t(source.channels)], g, 1e-4);
}

// A standard material with a detail normal map: both maps' chains, and the roughness a wwii_gloss_combine of the
// two gloss chains (output roughness) rather than a roughness chain.
TEST(RoughnessFilteringScene, StandardWithADetailMap) {
  TempDir dir;
  const std::string map = write_facet_map(dir.path() / "bumps.exr").string();
  SceneLoadOptions options;
  options.textures.convert_dir = dir.path() / "tx";
  const auto scene =
      load_scene_text(floor_scene(fmt::format(
                          R"({{"type": "standard", "roughness": 0.3, "normal_map": {{"type": "image", "file": "{}"}},
                                   "detail_normal_map": {{"type": "image", "file": "{}", "uv_scale": [5, 5]}}}})",
                          map, map)),
                      "scene.json", dir.path(), options);
  // Two normal and gloss chains (the base's, and the detail's from gloss 1), no roughness chain.
  EXPECT_EQ(built_files(dir.path() / "tx"),
            (std::vector<std::string>{".gloss.exr", ".gloss.exr", ".normal.exr", ".normal.exr"}));
}

// Errors while the chains are built name the key whose file failed.
TEST(RoughnessFilteringScene, BuildErrorsNameTheKey) {
  TempDir dir;
  const std::string map = write_facet_map(dir.path() / "bumps.exr").string();
  const std::string rough = write_checker(dir.path() / "r.exr", 16, 0, 0.2f, 0.4f).string();
  const std::string zero = write_test_exr(dir.path() / "zero.exr", 4, 4, [](int, int, int) { return 0.5f; }).string();
  const auto error_of = [&](const std::string& material) -> std::string {
    SceneLoadOptions options;
    options.textures.convert_dir = dir.path() / "tx";
    try {
      load_scene_text(floor_scene(material), "scene.json", dir.path(), options);
    } catch (const std::exception& e) {
      return e.what();
    }
    return "accepted";
  };
  const std::string channel = error_of(fmt::format(
      R"({{"type": "standard", "roughness": {{"type": "image", "file": "{}", "channel": "a"}},
           "normal_map": {{"type": "image", "file": "{}"}}}})",
      rough, map));
  EXPECT_NE(channel.find("/materials/floor/roughness"), std::string::npos) << channel;
  EXPECT_NE(channel.find("no channel a"), std::string::npos) << channel;
  const std::string detail = error_of(fmt::format(
      R"({{"type": "conductor", "roughness": 0.3, "normal_map": {{"type": "image", "file": "{}"}},
           "detail_normal_map": {{"type": "image", "file": "{}"}}}})",
      map, zero));
  EXPECT_NE(detail.find("/materials/floor/detail_normal_map"), std::string::npos) << detail;
  EXPECT_NE(detail.find("length 0"), std::string::npos) << detail;
}

std::string png_bytes(int w, int h, int channels, const std::function<unsigned char(int, int, int)>& f) {
  TempDir dir;
  const auto file = dir.path() / "t.png";
  auto out = OIIO::ImageOutput::create(file.string());
  const OIIO::ImageSpec spec(w, h, channels, OIIO::TypeDesc::UINT8);
  std::vector<unsigned char> px(size_t(w) * h * channels);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < channels; ++c) px[(size_t(y) * w + x) * channels + c] = f(x, y, c);
  EXPECT_TRUE(out->open(file.string(), spec));
  EXPECT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px.data()));
  out->close();
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A glTF asset (standard material) with a normalTexture and a metallicRoughnessTexture loads filtered: the normal,
// gloss and roughness chains are built.
TEST(RoughnessFilteringScene, GltfWithNormalAndMetallicRoughnessTexturesLoadsFiltered) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node({0, 0, 0, 1, 0, 0, 0, 1, 0}, 0);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> tilt(96, 160);
  const std::string normal = png_bytes(32, 32, 3, [&](int, int, int c) { return c == 2 ? 255 : tilt(rng); });
  const std::string mr = png_bytes(32, 32, 3, [](int x, int, int c) { return c == 1 ? (x % 2 ? 60 : 120) : 255; });
  b.doc["images"] = {{{"bufferView", b.bytes_view(normal)}, {"mimeType", "image/png"}},
                     {{"bufferView", b.bytes_view(mr)}, {"mimeType", "image/png"}}};
  b.doc["textures"] = {{{"source", 0}}, {{"source", 1}}};
  b.doc["materials"] = {
      {{"pbrMetallicRoughness", {{"metallicFactor", 1.0}, {"metallicRoughnessTexture", {{"index", 1}}}}},
       {"normalTexture", {{"index", 0}}}}};
  const auto gltf = dir.write("asset.gltf", b.gltf());
  SceneLoadOptions options;
  options.textures.convert_dir = dir.path() / "tx";
  const auto scene = load_scene_text(
      R"({"camera": {"position": [0.3, 0.3, 2], "look_at": [0.3, 0.3, 0], "resolution": [4, 4]},
          "shapes": [{"type": "gltf", "file": "asset.gltf"}]})",
      "scene.json", dir.path(), options);
  EXPECT_EQ(built_files(dir.path() / "tx"),
            (std::vector<std::string>{".gloss.exr", ".normal.exr", ".roughness.exr", ".source-gloss.exr"}));
  (void)gltf;
}

}  // namespace
}  // namespace kozu::test
