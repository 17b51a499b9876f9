// What `kozu render` puts in its EXRs besides the colour, run as a process: OpenEXR's standard camera matrices
// (worldToCamera, worldToNDC) checked against where the renderer draws a marker, the kozu:* attributes, and the
// coverage of --alpha (through sample ranges, kozu merge, checkpoints and crops).
#include "support/render_test.h"

#include "io/image_io.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>

namespace kozu::test {
namespace {

std::string kozu() { return fmt::format("'{}'", kozu_binary().string()); }

std::filesystem::path write_scene(const TempDir& dir, const std::string& name, const std::string& text) {
  const auto p = dir.path() / name;
  std::ofstream(p) << text;
  return p;
}

std::optional<std::array<float, 16>> matrix(const Image& img, const std::string& name) {
  for (const auto& [n, m] : img.matrices)
    if (n == name) return m;
  return std::nullopt;
}

// p M for the row vector (p, 1), divided by w: OpenEXR's (Imath's) convention.
Vec3 transform_point(const std::array<float, 16>& m, const Vec3& p) {
  double out[4];
  for (int c = 0; c < 4; ++c) out[c] = double(p.x) * m[c] + double(p.y) * m[4 + c] + double(p.z) * m[8 + c] + m[12 + c];
  return Vec3(out[0] / out[3], out[1] / out[3], out[2] / out[3]);
}

// The brightness-weighted centroid of an image, in pixel coordinates (pixel centres at + 0.5).
Vec2 centroid(const Image& img) {
  double sx = 0, sy = 0, sw = 0;
  const std::vector<Rgb> rgb = img.to_rgb();
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const Rgb c = rgb[static_cast<size_t>(y) * img.width + x];
      const double w = c.r + c.g + c.b;
      sx += w * (x + 0.5);
      sy += w * (y + 0.5);
      sw += w;
    }
  EXPECT_GT(sw, 0.0);
  return Vec2(static_cast<float>(sx / sw), static_cast<float>(sy / sw));
}

// A small emitting sphere at `marker` on black, seen by `camera` (a JSON object's body) at 128 x 96.
std::string marker_scene(const std::string& camera, const Vec3& marker) {
  return fmt::format(R"({{
    "camera": {{{}, "resolution": [128, 96]}},
    "render": {{"spp": 64, "max_depth": 1}},
    "materials": {{"black": {{"type": "diffuse", "albedo": 0}}}},
    "shapes": [{{"type": "sphere", "center": [{}, {}, {}], "radius": 0.04, "material": "black", "emission": 1}}] }})",
                     camera, marker.x, marker.y, marker.z);
}

struct Projected {
  Image image;
  Vec2 drawn;  // where the marker is in the image (centroid)
};
Projected render_marker(const TempDir& dir, const std::string& name, const std::string& camera, const Vec3& marker) {
  const auto scene = write_scene(dir, name + ".json", marker_scene(camera, marker));
  const auto exr = dir.path() / (name + ".exr");
  std::string out;
  EXPECT_EQ(
      run_command(fmt::format("{} render '{}' -o '{}' --threads 2 --seed 5 -q", kozu(), scene.string(), exr.string()),
                  &out),
      0)
      << out;
  Projected p{read_image_all(exr), {}};
  p.drawn = centroid(p.image);
  return p;
}

TEST(ExrMetadata, WorldToNdcProjectsWhereThePerspectiveCameraDraws) {
  TempDir dir;
  const Vec3 position(1, 2, 5), look_at(0.2f, 0.3f, 0), marker(0.9f, 0.8f, 0.3f);
  const Projected p =
      render_marker(dir, "persp", fmt::format(R"("position": [1, 2, 5], "look_at": [0.2, 0.3, 0], "fov": 40)"), marker);
  const auto ndc = matrix(p.image, "worldToNDC"), cam = matrix(p.image, "worldToCamera");
  ASSERT_TRUE(ndc && cam);
  // The look-at point is the image centre; the camera sits at the origin of camera space, looking down +z.
  const Vec3 centre = transform_point(*ndc, look_at);
  EXPECT_NEAR(centre.x, 0.5f, 1e-5f);
  EXPECT_NEAR(centre.y, 0.5f, 1e-5f);
  const Vec3 origin = transform_point(*cam, position), ahead = transform_point(*cam, look_at);
  EXPECT_NEAR(glm::length(origin), 0.0f, 1e-5f);
  EXPECT_NEAR(ahead.x, 0.0f, 1e-5f);
  EXPECT_NEAR(ahead.y, 0.0f, 1e-5f);
  EXPECT_NEAR(ahead.z, glm::length(look_at - position), 1e-5f);
  // +x right and +y up in camera space: the marker is up and to the right of the centre in the image.
  const Vec3 m = transform_point(*cam, marker);
  EXPECT_GT(m.x, 0.0f);
  EXPECT_GT(m.y, 0.0f);
  // The marker's projection lands where the renderer drew it (a 1.4-pixel disc: its centroid to a quarter pixel).
  const Vec3 q = transform_point(*ndc, marker);
  EXPECT_NEAR(q.x * 128.0f, p.drawn.x, 0.25f) << "drawn at " << p.drawn.x << ", " << p.drawn.y;
  EXPECT_NEAR(q.y * 96.0f, p.drawn.y, 0.25f) << "drawn at " << p.drawn.x << ", " << p.drawn.y;
  EXPECT_GT(std::abs(q.x - 0.5f) * 128.0f, 8.0f);  // far enough from the centre for a flip to show
  EXPECT_GT(std::abs(q.y - 0.5f) * 96.0f, 8.0f);
}

TEST(ExrMetadata, WorldToNdcProjectsWhereTheOrthographicCameraDraws) {
  TempDir dir;
  const Vec3 marker(-0.7f, 0.5f, 0.4f);
  const Projected p = render_marker(
      dir, "ortho", R"("type": "orthographic", "position": [0.5, 1, 6], "look_at": [0, 0, 0], "scale": 3)", marker);
  const auto ndc = matrix(p.image, "worldToNDC");
  ASSERT_TRUE(ndc);
  EXPECT_NEAR(transform_point(*ndc, Vec3(0)).x, 0.5f, 1e-5f);
  EXPECT_NEAR(transform_point(*ndc, Vec3(0)).y, 0.5f, 1e-5f);
  const Vec3 q = transform_point(*ndc, marker);
  EXPECT_NEAR(q.x * 128.0f, p.drawn.x, 0.25f) << "drawn at " << p.drawn.x << ", " << p.drawn.y;
  EXPECT_NEAR(q.y * 96.0f, p.drawn.y, 0.25f) << "drawn at " << p.drawn.x << ", " << p.drawn.y;
  EXPECT_GT(std::abs(q.x - 0.5f) * 128.0f, 10.0f);
  EXPECT_GT(std::abs(q.y - 0.5f) * 96.0f, 10.0f);
}

TEST(ExrMetadata, PanoramaHasWorldToCameraOnly) {
  TempDir dir;
  const auto scene =
      write_scene(dir, "pano.json",
                  marker_scene(R"("type": "panorama", "position": [0, 0, 0], "look_at": [0, 0, -1])", Vec3(0, 0, -2)));
  const auto exr = dir.path() / "pano.exr";
  std::string out;
  ASSERT_EQ(run_command(fmt::format("{} render '{}' -o '{}' --spp 1 -q", kozu(), scene.string(), exr.string()), &out),
            0)
      << out;
  const Image img = read_image_all(exr);
  const auto cam = matrix(img, "worldToCamera");
  ASSERT_TRUE(cam);
  EXPECT_FALSE(matrix(img, "worldToNDC"));
  const Vec3 ahead = transform_point(*cam, Vec3(0, 0, -2));
  EXPECT_NEAR(ahead.z, 2.0f, 1e-6f);
  EXPECT_NEAR(ahead.x, 0.0f, 1e-6f);
}

// Every kozu:* attribute is in the EXR with the render's values, and kozu merge keeps the camera matrices.
TEST(ExrMetadata, KozuAttributesAndMergedMatrices) {
  TempDir dir;
  const auto scene = write_scene(
      dir, "s.json", marker_scene(R"("position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 35)", Vec3(0.3f, 0, 0)));
  const auto a = dir.path() / "a.exr", b = dir.path() / "b.exr", m = dir.path() / "m.exr";
  std::string out;
  for (const auto& [file, range] : {std::pair{a, "0:3"}, std::pair{b, "3:5"}})
    ASSERT_EQ(run_command(fmt::format("{} render '{}' -o '{}' --sample-range {} --seed 77 --resolution 16x12 -q",
                                      kozu(), scene.string(), file.string(), range),
                          &out),
              0)
        << out;
  const Image part = read_image_all(a);
  std::map<std::string, std::string> attrs(part.attributes.begin(), part.attributes.end());
  std::string version;
  ASSERT_EQ(run_command(kozu() + " --version", &version), 0);
  EXPECT_NE(version.find(attrs["kozu:version"]), std::string::npos) << version << " vs " << attrs["kozu:version"];
  EXPECT_FALSE(attrs["kozu:version"].empty());
  EXPECT_EQ(attrs["kozu:seed"], "77");
  EXPECT_EQ(attrs["kozu:sample_begin"], "0");
  EXPECT_EQ(attrs["kozu:spp_min"], "3");
  EXPECT_EQ(attrs["kozu:spp_max"], "3");
  EXPECT_EQ(std::stod(attrs["kozu:spp_mean"]), 3.0);
  EXPECT_EQ(attrs["kozu:scene_hash"].size(), 16u);
  EXPECT_GE(std::stod(attrs["kozu:render_seconds"]), 0.0);
  EXPECT_NE(attrs["kozu:render_seconds"].find('.'), std::string::npos);
  EXPECT_EQ(attrs["kozu:partial"], "0");
  EXPECT_EQ(attrs["kozu:negative_pixels"], "clamp");  // the scene's; the part itself keeps them signed
  EXPECT_EQ(attrs.size(), 10u);                       // the ten above, nothing else
  ASSERT_EQ(run_command(fmt::format("{} merge '{}' '{}' -o '{}'", kozu(), a.string(), b.string(), m.string()), &out), 0)
      << out;
  const Image merged = read_image_all(m);
  ASSERT_TRUE(matrix(merged, "worldToNDC") && matrix(part, "worldToNDC"));
  EXPECT_EQ(*matrix(merged, "worldToNDC"), *matrix(part, "worldToNDC"));
  EXPECT_EQ(*matrix(merged, "worldToCamera"), *matrix(part, "worldToCamera"));
  std::map<std::string, std::string> mattrs(merged.attributes.begin(), merged.attributes.end());
  EXPECT_EQ(mattrs["kozu:spp_min"], "5");
  EXPECT_EQ(mattrs["kozu:merged_parts"], "2");
  EXPECT_EQ(mattrs["kozu:negative_pixels"], "clamp");
}

// A unit sphere seen from 4 units (angular radius asin(1/4)) against a uniform sky, 32 x 24, fov 35.
constexpr const char* kSphere = R"({
  "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 35, "resolution": [32, 24]},
  "render": {"spp": 64},
  "materials": {"m": {"type": "diffuse", "albedo": 0.5}},
  "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}],
  "lights": [{"type": "environment", "radiance": 1}] })";

// The named channel of an image read with read_image_all.
std::vector<float> channel_values(const Image& img, const std::string& name) {
  const auto it = std::find(img.channel_names.begin(), img.channel_names.end(), name);
  EXPECT_NE(it, img.channel_names.end()) << name;
  if (it == img.channel_names.end()) return {};
  const size_t c = static_cast<size_t>(it - img.channel_names.begin());
  std::vector<float> out(static_cast<size_t>(img.width) * img.height);
  for (size_t i = 0; i < out.size(); ++i) out[i] = img.data[i * img.channels + c];
  return out;
}

int render(const std::string& args, std::string* out) { return run_command(kozu() + " render -q " + args, out); }

TEST(Alpha, CoverageOfASphereAgainstTheSky) {
  TempDir dir;
  const auto scene = write_scene(dir, "s.json", kSphere);
  const auto exr = dir.path() / "a.exr";
  std::string out;
  ASSERT_EQ(render(fmt::format("'{}' -o '{}' --alpha --seed 3", scene.string(), exr.string()), &out), 0) << out;
  const Image img = read_image_all(exr);
  ASSERT_EQ(img.channel_names[3], "A");  // R, G, B, A: OpenEXR's order
  const std::vector<float> a = channel_values(img, "A");
  const auto at = [&](int x, int y) { return a[static_cast<size_t>(y) * 32 + x]; };
  EXPECT_EQ(at(16, 12), 1.0f);
  EXPECT_EQ(at(15, 11), 1.0f);
  for (const auto& [x, y] : {std::pair{0, 0}, {31, 0}, {0, 23}, {31, 23}}) EXPECT_EQ(at(x, y), 0.0f) << x << "," << y;
  int fractional = 0;
  double area = 0.0;
  for (const float v : a) {
    ASSERT_GE(v, 0.0f);
    ASSERT_LE(v, 1.0f);
    fractional += v > 0.0f && v < 1.0f;
    area += v;
  }
  // The silhouette: a ring of partly covered pixels 2 pi r = 62 long (r = 9.8 pixels), as wide as the pixel
  // filter's support (3 pixels) plus at most a pixel.
  EXPECT_GE(fractional, 62);
  EXPECT_LE(fractional, 4 * 62);
  // The covered area is the sphere's disc in the image: radius tan(asin(1/4)) / tan(17.5 deg) x 12 pixels (the
  // pixel filter spreads the edge but keeps the area); binomial noise over the edge pixels is about 0.5 pixel.
  const double r = std::tan(std::asin(0.25)) / std::tan(17.5 * kPi / 180.0) * 12.0;
  EXPECT_NEAR(area, kPi * r * r, 2.0) << "r = " << r;
  // The colour does not depend on --alpha.
  const auto plain = dir.path() / "plain.exr";
  ASSERT_EQ(render(fmt::format("'{}' -o '{}' --seed 3", scene.string(), plain.string()), &out), 0) << out;
  EXPECT_EQ(channel_values(read_image_all(plain), "R"), channel_values(img, "R"));
}

// Sample ranges merged, a resumed checkpoint and a crop give the alpha of one whole render bit for bit.
TEST(Alpha, SurvivesMergeResumeAndCropExactly) {
  TempDir dir;
  const auto scene = write_scene(dir, "s.json", kSphere);
  const std::string s = scene.string();
  const auto p = [&](const char* name) { return (dir.path() / name).string(); };
  std::string out;
  ASSERT_EQ(render(fmt::format("'{}' -o '{}' --alpha --seed 9 --spp 37", s, p("whole.exr")), &out), 0) << out;
  ASSERT_EQ(render(fmt::format("'{}' -o '{}' --alpha --seed 9 --sample-range 0:13", s, p("a.exr")), &out), 0) << out;
  ASSERT_EQ(render(fmt::format("'{}' -o '{}' --alpha --seed 9 --sample-range 13:37", s, p("b.exr")), &out), 0) << out;
  ASSERT_EQ(run_command(fmt::format("{} merge '{}' '{}' -o '{}'", kozu(), p("a.exr"), p("b.exr"), p("m.exr")), &out), 0)
      << out;
  ASSERT_EQ(
      render(fmt::format("'{}' -o '{}' --alpha --seed 9 --spp 5 --checkpoint '{}'", s, p("early.exr"), p("c.kzc")),
             &out),
      0)
      << out;
  ASSERT_EQ(render(fmt::format("'{}' -o '{}' --alpha --seed 9 --spp 37 --resume '{}'", s, p("resumed.exr"), p("c.kzc")),
                   &out),
            0)
      << out;
  ASSERT_EQ(render(fmt::format("'{}' -o '{}' --alpha --seed 9 --spp 37 --crop 8,4,24,20", s, p("crop.exr")), &out), 0)
      << out;
  const std::vector<float> whole = channel_values(read_image_all(p("whole.exr")), "A");
  const std::vector<float> part = channel_values(read_image_all(p("a.exr")), "A");
  ASSERT_EQ(whole.size(), 32u * 24u);
  // The parts differ from the whole (13 samples are not 37), the merge does not.
  EXPECT_NE(part, whole);
  EXPECT_EQ(channel_values(read_image_all(p("m.exr")), "A"), whole);
  EXPECT_EQ(channel_values(read_image_all(p("resumed.exr")), "A"), whole);
  const Image crop = read_image_all(p("crop.exr"));
  const std::vector<float> c = channel_values(crop, "A");
  ASSERT_EQ(crop.width, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)
      EXPECT_EQ(c[static_cast<size_t>(y) * 16 + x], whole[static_cast<size_t>(y + 4) * 32 + x + 8]) << x << "," << y;
  // A checkpoint of a render without --alpha does not resume one with it.
  ASSERT_EQ(render(fmt::format("'{}' -o '{}' --seed 9 --spp 5 --checkpoint '{}'", s, p("x.exr"), p("d.kzc")), &out), 0)
      << out;
  EXPECT_EQ(render(fmt::format("'{}' -o '{}' --alpha --seed 9 --spp 8 --resume '{}'", s, p("y.exr"), p("d.kzc")), &out),
            1)
      << out;
  EXPECT_NE(out.find("--alpha"), std::string::npos) << out;
}

TEST(Alpha, RefusedForEightBitOutputs) {
  TempDir dir;
  const auto scene = write_scene(dir, "s.json", kSphere);
  for (const char* ext : {"png", "jpg", "hdr"}) {
    std::string out;
    const auto file = dir.path() / fmt::format("a.{}", ext);
    EXPECT_NE(render(fmt::format("'{}' -o '{}' --alpha", scene.string(), file.string()), &out), 0);
    EXPECT_NE(
        out.find(fmt::format("error: kozu render: --alpha: {}: alpha goes into .exr outputs only", file.string())),
        std::string::npos)
        << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
    EXPECT_FALSE(std::filesystem::exists(file));
  }
}

}  // namespace
}  // namespace kozu::test
