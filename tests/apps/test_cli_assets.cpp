// Hostile and real-world image assets through the kozu command: textures with tiles larger than the cache, HDRIs
// with filtering noise below 0, `kozu merge` parts that lie about their windows or are named as the output, and
// `kozu maketx`'s flag values, outputs and write errors.
#include "apps/cli_helpers.h"
#include "core/tonemap.h"
#include "io/image_io.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <unistd.h>

#include <fstream>
#include <functional>
#include <iterator>

namespace kozu::test {
namespace {

std::string file_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

int count_lines(const std::string& text, const std::string& prefix) {
  int n = 0;
  for (size_t pos = 0; pos < text.size();) {
    const size_t eol = std::min(text.find('\n', pos), text.size());
    n += text.compare(pos, prefix.size(), prefix) == 0;
    pos = eol + 1;
  }
  return n;
}

std::string scene_with(const std::string& material, const std::string& light) {
  return fmt::format(R"({{
  "camera": {{"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 35, "resolution": [16, 12]}},
  "render": {{"spp": 2}},
  "materials": {{"m": {}}},
  "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}}],
  "lights": [{}] }})",
                     material, light);
}

// A 64 x 64 tiled mip-mapped EXR with 4096 x 4096 tiles (25 kB): under --texture-cache-mb 16, OpenImageIO's cache
// aborted (check_max_mem assertion, SIGABRT). It is re-tiled and renders.
TEST(CliAssets, TexturesWithTilesLargerThanTheCacheRender) {
  TempDir dir;
  OIIO::ImageBuf noise(OIIO::ImageSpec(64, 64, 3, OIIO::TypeDesc::FLOAT));
  OIIO::ImageBufAlgo::noise(noise, "uniform", 0.2f, 0.8f);
  OIIO::ImageSpec config;
  config.format = OIIO::TypeDesc::HALF;
  config.tile_width = config.tile_height = 4096;
  const auto tex = dir.path() / "big_tiles.exr";
  ASSERT_TRUE(OIIO::ImageBufAlgo::make_texture(OIIO::ImageBufAlgo::MakeTxTexture, noise, tex.string(), config));
  const auto scene =
      dir.write("s.json", scene_with(R"({"type": "diffuse", "albedo": {"type": "image", "file": "big_tiles.exr"}})",
                                     R"({"type": "environment", "radiance": 1})"));
  std::string out;
  EXPECT_EQ(run_command(fmt::format("{} render '{}' -o '{}' --texture-cache-mb 16 -q", kozu(), scene.string(),
                                    (dir.path() / "o.exr").string()),
                        &out),
            0)
      << out;
}

// Blender 3.4's HDRIs hold filtering noise below zero (down to -0.00385) and were refused: such values are clamped
// with one warning giving their count; a meaningfully negative one is still refused.
TEST(CliAssets, HdrisWithFilteringNoiseBelowZeroRender) {
  TempDir dir;
  write_test_exr(dir.path() / "sky.exr", 64, 32, [](int x, int y, int c) {
    return (x * 3 + y) % 7 == 0 && c == 1 ? -3.7e-5f : 0.2f + 0.01f * float(y);
  });
  write_test_exr(dir.path() / "bad.exr", 64, 32, [](int x, int y, int) { return x == 9 && y == 4 ? -0.5f : 1.0f; });
  const std::string diffuse = R"({"type": "diffuse", "albedo": 0.5})";
  const auto sky = dir.write("sky.json", scene_with(diffuse, R"({"type": "environment", "file": "sky.exr"})"));
  const auto bad = dir.write("bad.json", scene_with(diffuse, R"({"type": "environment", "file": "bad.exr"})"));
  std::string out;
  ASSERT_EQ(run_command(fmt::format("{} render '{}' -o '{}' -q", kozu(), sky.string(), (dir.path() / "o.exr").string()),
                        &out),
            0)
      << out;
  EXPECT_EQ(count_lines(out, "warning:"), 1) << out;
  EXPECT_NE(out.find("/lights/0/file: " + (dir.path() / "sky.exr").string() +
                     ": 293 tiny negative values (filtering noise) clamped to 0"),
            std::string::npos)
      << out;
  EXPECT_EQ(run_command(fmt::format("{} render '{}' -o '{}' -q", kozu(), bad.string(), (dir.path() / "o.exr").string()),
                        &out),
            1);
  EXPECT_NE(out.find("radiance must be >= 0, and pixel (9, 4) channel 0 is -0.5: its 3 negative values"),
            std::string::npos)
      << out;
}

// A kozu EXR part: 1 x 1 pixel at `origin` of a full x full image.
std::filesystem::path write_part(const std::filesystem::path& file, Vec2i origin, int full) {
  ImageExtras extras;
  extras.origin = origin;
  extras.full_size = Vec2i(full);
  extras.attributes = {{"kozu:version", "test"}, {"kozu:scene_hash", "0123456789abcdef"},
                       {"kozu:seed", "1"},       {"kozu:sample_begin", "0"},
                       {"kozu:spp_min", "4"},    {"kozu:spp_max", "4"},
                       {"kozu:spp_mean", "4"},   {"kozu:partial", "0"}};
  write_image(file, 1, 1, {0.5f, 0.5f, 0.5f}, ToneMap{}, extras);
  return file;
}

// Two 1 kB parts at opposite corners of a 16384^2 display window: merge allocated their bounding box (2.7 GB)
// before finding it uncovered. The parts' pixels are counted against the window first.
TEST(CliAssets, MergeChecksThePartsBeforeAllocating) {
  TempDir dir;
  const auto a = write_part(dir.path() / "a.exr", Vec2i(0), 16384);
  const auto b = write_part(dir.path() / "b.exr", Vec2i(16383), 16384);
  ASSERT_LT(std::filesystem::file_size(a), 2000u);
  std::string out;
  // GNU time, where installed, reports the peak memory.
  const std::string timer = std::filesystem::exists("/usr/bin/time") ? "/usr/bin/time -f 'peak %M kB' " : "";
  EXPECT_EQ(run_command(fmt::format("{}{} merge '{}' '{}' -o '{}'", timer, kozu(), a.string(), b.string(),
                                    (dir.path() / "m.exr").string()),
                        &out),
            1)
      << out;
  EXPECT_NE(out.find("the parts hold 2 pixels in all, fewer than the 268435456 of the merged window 16384x16384 at "
                     "0,0"),
            std::string::npos)
      << out;
  const size_t peak = out.find("peak ");
  if (peak != std::string::npos) {
    // Within 100 MB of what kozu takes to start at all (its libraries: 200 MB under AddressSanitizer once oneDNN was
    // linked), where the bounding box alone is 2.7 GB.
    std::string base;
    ASSERT_EQ(run_command(fmt::format("{}{} --version", timer, kozu()), &base), 0) << base;
    const size_t base_peak = base.find("peak ");
    ASSERT_NE(base_peak, std::string::npos) << base;
    EXPECT_LT(std::stol(out.substr(peak + 5)), std::stol(base.substr(base_peak + 5)) + 100000) << out << base;
  }
}

// `kozu merge a.exr b.exr -o a.exr` replaced a part: the parts are inputs, and every output is checked first.
TEST(CliAssets, MergeNeverOverwritesAPart) {
  TempDir dir;
  const auto a = write_part(dir.path() / "a.exr", Vec2i(0), 2);
  const auto b = write_part(dir.path() / "b.exr", Vec2i(1, 0), 2);
  const std::string before = file_bytes(a);
  std::string out;
  EXPECT_EQ(run_command(fmt::format("{} merge '{}' '{}' -o '{}'", kozu(), a.string(), b.string(), a.string()), &out),
            1);
  EXPECT_NE(out.find("would overwrite"), std::string::npos) << out;
  EXPECT_EQ(file_bytes(a), before);
  // An output that cannot be written is refused before the parts are read (here: they do not even exist).
  EXPECT_EQ(run_command(fmt::format("{} merge '{}' '{}' -o '{}'", kozu(), (dir.path() / "x.exr").string(), b.string(),
                                    "/proc/m.exr"),
                        &out),
            1);
  EXPECT_NE(out.find("-o /proc/m.exr: cannot be written"), std::string::npos) << out;
  EXPECT_EQ(temp_files(dir.path()), 0);
}

// maketx: a bad flag value is bad input (1; a usage error such as an unknown option stays 2); the output is
// checked before converting (never the input); a full disk gives one line, not libtiff's 82.
TEST(CliAssets, MaketxValuesOutputsAndWriteErrors) {
  TempDir dir;
  const auto src = write_test_exr(dir.path() / "in.exr", 256, 256,
                                  [](int x, int y, int c) { return float((x * 31 + y * 17 + c * 7) % 101) / 100.0f; });
  const std::string before = file_bytes(src);
  std::string out;
  EXPECT_EQ(run_command(fmt::format("{} maketx '{}' -o '{}' --colorspace bogus", kozu(), src.string(),
                                    (dir.path() / "o.tx").string()),
                        &out),
            1);
  EXPECT_EQ(out, "error: kozu maketx: --colorspace: 'bogus' is not one of auto, srgb, linear\n");
  EXPECT_EQ(
      run_command(fmt::format("{} maketx '{}' -o '{}' --bogus", kozu(), src.string(), (dir.path() / "o.tx").string()),
                  &out),
      2);
  const auto same = dir.path() / "in.tx";
  std::filesystem::copy_file(src, same);
  EXPECT_EQ(run_command(fmt::format("{} maketx '{}' -o '{}'", kozu(), src.string(), src.string()), &out), 1);
  EXPECT_EQ(file_bytes(src), before);
  EXPECT_EQ(temp_files(dir.path()), 0);

  // A 64 kB file system fills up during the write. Mounting needs root: skipped otherwise.
  const auto full = dir.path() / "full";
  std::filesystem::create_directories(full);
  if (::geteuid() != 0 || ::mount("tmpfs", full.c_str(), "tmpfs", 0, "size=64k") != 0)
    GTEST_SKIP() << "not root (or tmpfs cannot be mounted): the full-disk case is not run";
  const int rc =
      run_command(fmt::format("{} maketx '{}' -o '{}'", kozu(), src.string(), (full / "o.tx").string()), &out);
  const int files = int(std::distance(std::filesystem::directory_iterator(full), {}));
  ::umount(full.c_str());
  EXPECT_EQ(rc, 1);
  EXPECT_EQ(count_lines(out, ""), 1) << out;
  EXPECT_EQ(out.rfind("error: kozu maketx: ", 0), 0u) << out;
  EXPECT_NE(out.find("no space left on device"), std::string::npos) << out;
  EXPECT_EQ(files, 0) << "the temporary texture is removed";
}

}  // namespace
}  // namespace kozu::test
