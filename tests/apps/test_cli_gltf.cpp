// `kozu render` on a glTF file, run as a process: the files the glTF reads (its .bin buffer, its images) are inputs
// of the render, which no output (-o, --stats) may overwrite; the file is refused before any rendering and left as
// it was.
#include "apps/cli_helpers.h"
#include "io/gltf_test_files.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

namespace kozu::test {
namespace {

std::string file_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(CliGltf, OutputsMayNotOverwriteTheModelsBuffersOrTextures) {
  TempDir dir;
  GltfBuilder b;
  b.triangle_node({-1, -1, 0, 1, -1, 0, 0, 1, 0}, 0);
  b.doc["images"] = {{{"uri", "tex.png"}}};
  b.doc["textures"] = {{{"source", 0}}};
  b.doc["materials"] = nlohmann::json::parse(R"([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}])");
  {
    auto out = OIIO::ImageOutput::create((dir.path() / "tex.png").string());
    const unsigned char px[4] = {200, 100, 50, 255};
    ASSERT_TRUE(out->open((dir.path() / "tex.png").string(), OIIO::ImageSpec(1, 1, 4, OIIO::TypeDesc::UINT8)));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px));
    out->close();
  }
  const std::string png = file_bytes(dir.path() / "tex.png");
  dir.write("m.bin", b.bin);
  const auto model = dir.write("m.gltf", b.gltf_external("m.bin"));
  const std::string base =
      fmt::format("cd '{}' && {} render m.gltf --spp 1 --resolution 8x8 --quiet ", dir.path().string(), kozu());
  std::string out;
  EXPECT_EQ(run_command(base + "-o tex.png", &out), 1) << out;
  EXPECT_NE(out.find("would overwrite"), std::string::npos) << out;
  EXPECT_NE(out.find("tex.png"), std::string::npos) << out;
  EXPECT_EQ(file_bytes(dir.path() / "tex.png"), png);
  EXPECT_EQ(run_command(base + "-o out.exr --stats m.bin", &out), 1) << out;
  EXPECT_NE(out.find("would overwrite"), std::string::npos) << out;
  EXPECT_NE(out.find("m.bin"), std::string::npos) << out;
  EXPECT_EQ(file_bytes(dir.path() / "m.bin"), b.bin);
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "out.exr"));
}

}  // namespace
}  // namespace kozu::test
