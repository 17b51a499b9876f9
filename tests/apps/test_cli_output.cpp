// What `kozu render` puts in its EXRs besides the colour, run as a process: OpenEXR's standard camera matrices
// (worldToCamera, worldToNDC) checked against where the renderer draws a marker, and the kozu:* attributes.
#include "support/render_test.h"

#include "io/image_io.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
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
  EXPECT_EQ(attrs.size(), 9u);  // the nine above, nothing else
  ASSERT_EQ(run_command(fmt::format("{} merge '{}' '{}' -o '{}'", kozu(), a.string(), b.string(), m.string()), &out), 0)
      << out;
  const Image merged = read_image_all(m);
  ASSERT_TRUE(matrix(merged, "worldToNDC") && matrix(part, "worldToNDC"));
  EXPECT_EQ(*matrix(merged, "worldToNDC"), *matrix(part, "worldToNDC"));
  EXPECT_EQ(*matrix(merged, "worldToCamera"), *matrix(part, "worldToCamera"));
  std::map<std::string, std::string> mattrs(merged.attributes.begin(), merged.attributes.end());
  EXPECT_EQ(mattrs["kozu:spp_min"], "5");
  EXPECT_EQ(mattrs["kozu:merged_parts"], "2");
}

}  // namespace
}  // namespace kozu::test
