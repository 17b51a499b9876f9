// `kozu texture height` and `kozu texture occlusion` as a user runs them: outputs, conventions (row 0 = the image's
// top, OpenGL normals, heights in texel widths), the mesh, and one-line errors.
#include "apps/cli_helpers.h"
#include "io/image_io.h"
#include "io/mesh_io.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace kozu::test {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kSize = 64;

// A height with whole periods over the tile, varying along both axes differently, so that a flipped or transposed
// reading would not match.
double height(int x, int y) {
  return 3.0 * std::sin(2 * kPi * x / kSize + 0.4) + 2.0 * std::cos(2 * kPi * 2 * y / kSize + 0.1);
}

void write_float_image(const std::filesystem::path& file, int channels, const std::vector<float>& v) {
  auto out = OIIO::ImageOutput::create(file.string());
  ASSERT_TRUE(out);
  OIIO::ImageSpec spec(kSize, kSize, channels, OIIO::TypeDesc::FLOAT);
  ASSERT_TRUE(out->open(file.string(), spec));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, v.data()));
  out->close();
}

// The map's exact normals, OpenGL convention (+y, green, up the image: rows run down).
std::filesystem::path write_normal_map(const std::filesystem::path& file) {
  std::vector<float> rgb(size_t(kSize) * kSize * 3);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const double gx = 3.0 * 2 * kPi / kSize * std::cos(2 * kPi * x / kSize + 0.4);
      const double gy = -2.0 * 2 * kPi * 2 / kSize * std::sin(2 * kPi * 2 * y / kSize + 0.1);
      const double inv = 1 / std::sqrt(gx * gx + gy * gy + 1);
      float* c = &rgb[(size_t(y) * kSize + x) * 3];
      c[0] = float(0.5 * (-gx * inv + 1));
      c[1] = float(0.5 * (gy * inv + 1));
      c[2] = float(0.5 * (inv + 1));
    }
  write_float_image(file, 3, rgb);
  return file;
}

std::string attribute(const Image& img, const std::string& name) {
  for (const auto& [key, value] : img.attributes)
    if (key == name) return value;
  return "";
}

TEST(CliSurfaceOcclusion, HeightRecoversTheMapAndWritesTheMesh) {
  TempDir dir;
  const auto normal = write_normal_map(dir.path() / "n.exr");
  const auto h = dir.path() / "h.exr", mesh = dir.path() / "h.ply";
  std::string out;
  ASSERT_EQ(run_command(fmt::format("{} texture height '{}' -o '{}' --mesh '{}' --height-scale 2", kozu(),
                                    normal.string(), h.string(), mesh.string()),
                        &out),
            0)
      << out;
  EXPECT_NE(out.find("curl residual"), std::string::npos) << out;
  const Image img = read_image_all(h);
  ASSERT_EQ(img.channels, 1);
  ASSERT_EQ(img.width, kSize);
  double mean = 0;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) mean += height(x, y);
  mean /= kSize * kSize;
  double err = 0, ref = 0;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const double truth = height(x, y) - mean;
      err += std::pow(img.data[size_t(y) * kSize + x] - truth, 2);
      ref += truth * truth;
    }
  EXPECT_LT(std::sqrt(err / ref), 0.03);
  EXPECT_LT(std::stod(attribute(img, "kozu:curl_residual")), 0.01);

  const MeshData m = read_ply(mesh);
  ASSERT_EQ(m.positions.size(), size_t(kSize) * kSize);
  EXPECT_EQ(m.indices.size(), size_t(kSize - 1) * (kSize - 1) * 6);
  ASSERT_EQ(m.uvs.size(), m.positions.size());
  // Vertex (x, y) sits at (x + 0.5, H - y - 0.5, 2 h) with v = 0 at the image's bottom.
  const size_t i = size_t(5) * kSize + 9;
  EXPECT_FLOAT_EQ(m.positions[i].x, 9.5f);
  EXPECT_FLOAT_EQ(m.positions[i].y, kSize - 5.5f);
  EXPECT_NEAR(m.positions[i].z, 2 * img.data[i], 1e-5);
  EXPECT_FLOAT_EQ(m.uvs[i].x, 9.5f / kSize);
  EXPECT_FLOAT_EQ(m.uvs[i].y, 1 - 5.5f / kSize);
  // Faces point up (+z) on average: counter-clockwise seen from above.
  const Vec3 a = m.positions[m.indices[0]], b = m.positions[m.indices[1]], c = m.positions[m.indices[2]];
  EXPECT_GT(glm::cross(b - a, c - a).z, 0.0f);
}

TEST(CliSurfaceOcclusion, OcclusionAndConeFromHeightOrNormals) {
  TempDir dir;
  const auto normal = write_normal_map(dir.path() / "n.exr");
  std::vector<float> flat(size_t(kSize) * kSize, 0.0f);
  write_float_image(dir.path() / "flat.exr", 1, flat);
  std::string out;
  const auto ao = dir.path() / "ao.exr", cone = dir.path() / "cone.exr", raw = dir.path() / "raw.exr";
  ASSERT_EQ(run_command(fmt::format("{} texture occlusion '{}' -o '{}' --cone '{}' --radius 16 --height-scale 2",
                                    kozu(), normal.string(), ao.string(), cone.string()),
                        &out),
            0)
      << out;
  ASSERT_EQ(run_command(fmt::format("{} texture occlusion '{}' -o '{}' --adjust black --radius 16 --height-scale 2",
                                    kozu(), normal.string(), raw.string()),
                        &out),
            0)
      << out;
  const Image a = read_image_all(ao), c = read_image_all(cone), v = read_image_all(raw);
  ASSERT_EQ(a.channels, 1);
  double lowest = 1;
  for (size_t i = 0; i < v.data.size(); ++i) {
    // Eq. (49) with the default albedo 0.5, and eq. (56)'s cone of the unadjusted visibility.
    EXPECT_NEAR(a.data[i], v.data[i] / (0.5 + 0.5 * v.data[i]), 1e-6);
    EXPECT_NEAR(c.data[i], std::sqrt(1 - v.data[i]), 1e-6);
    lowest = std::min(lowest, double(v.data[i]));
  }
  EXPECT_LT(lowest, 0.99) << "the troughs are occluded";
  EXPECT_EQ(attribute(a, "kozu:adjust"), "interreflection");

  // A flat height map is unoccluded everywhere.
  ASSERT_EQ(run_command(fmt::format("{} texture occlusion '{}' -o '{}'", kozu(), (dir.path() / "flat.exr").string(),
                                    ao.string()),
                        &out),
            0)
      << out;
  for (float x : read_image(ao).data) EXPECT_FLOAT_EQ(x, 1.0f);
}

TEST(CliSurfaceOcclusion, BadInputIsOneLine) {
  TempDir dir;
  const auto normal = write_normal_map(dir.path() / "n.exr");
  const std::string n = normal.string(), o = (dir.path() / "o.exr").string();
  std::string out;
  EXPECT_EQ(run_command(fmt::format("{} texture occlusion '{}' -o '{}' --albedo 2", kozu(), n, o), &out), 1);
  EXPECT_EQ(out, "error: kozu texture occlusion: --albedo: expected a number in [0, 1], got 2\n");
  EXPECT_EQ(run_command(fmt::format("{} texture occlusion '{}' -o '{}' --adjust grey", kozu(), n, o), &out), 1);
  EXPECT_EQ(out,
            "error: kozu texture occlusion: --adjust: 'grey' is not one of black, white, albedo, albedo-occluded, "
            "interreflection\n");
  EXPECT_EQ(run_command(fmt::format("{} texture height '{}' -o '{}.png'", kozu(), n, o), &out), 1);
  EXPECT_EQ(out, fmt::format("error: kozu texture height: -o: {}.png: the output must be an .exr file\n", o));
  EXPECT_EQ(run_command(fmt::format("{} texture height '{}' -o '{}' --mesh '{}.obj'", kozu(), n, o, o), &out), 1);
  EXPECT_EQ(run_command(fmt::format("{} texture height '{}' -o '{}'", kozu(), n, n), &out), 1);
  EXPECT_EQ(out.find('\n'), out.size() - 1) << out;
  EXPECT_EQ(run_command(fmt::format("{} texture height '{}' -o '{}' --bogus", kozu(), n, o), &out), 2);
  std::vector<float> one(size_t(kSize) * kSize, 0.0f);
  write_float_image(dir.path() / "one.exr", 1, one);
  EXPECT_EQ(
      run_command(fmt::format("{} texture height '{}' -o '{}'", kozu(), (dir.path() / "one.exr").string(), o), &out),
      1);
  EXPECT_NE(out.find("a normal map needs three channels"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(o));
  EXPECT_EQ(temp_files(dir.path()), 0);
}

}  // namespace
}  // namespace kozu::test
