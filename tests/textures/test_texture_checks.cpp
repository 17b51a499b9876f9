// The checks a texture gets whatever its form: pre-tiled files scanned for NaN and negative values like converted
// ones, tiles too large for the cache re-tiled, tiny negative values (filtering noise) clamped with a warning and
// others refused, the conversion's memory estimated before reading, and files that exist but cannot be read.
#include "core/error.h"
#include "core/file_io.h"
#include "io/image_io.h"
#include "support/render_test.h"
#include "textures/image_texture.h"
#include "textures/texture_cache.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/texture.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>

namespace kozu::test {
namespace {

// A tiled, mip-mapped texture (as `maketx` or `oiiotool -otex` writes it) of f(x, y, c), with the given tile size.
std::filesystem::path write_pretiled(const std::filesystem::path& file, int size, int tile,
                                     const std::function<float(int, int, int)>& f) {
  OIIO::ImageBuf buf(OIIO::ImageSpec(size, size, 3, OIIO::TypeDesc::FLOAT));
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const float v[3] = {f(x, y, 0), f(x, y, 1), f(x, y, 2)};
      buf.setpixel(x, y, 0, v);
    }
  OIIO::ImageSpec config;
  config.format = OIIO::TypeDesc::FLOAT;  // half would turn NaN into -65504 in a TIFF
  config.tile_width = config.tile_height = tile;
  config.attribute("maketx:filtername", "box");
  EXPECT_TRUE(OIIO::ImageBufAlgo::make_texture(OIIO::ImageBufAlgo::MakeTxTexture, buf, file.string(), config))
      << OIIO::geterror();
  return file;
}

std::string prepare_error(TextureCache& cache, const std::filesystem::path& file, TextureUse use) {
  try {
    cache.prepare(file, ColorSpace::Auto, use);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

float noise(int x, int y, int c) { return 0.25f + 0.5f * float((x * 7 + y * 13 + c * 5) % 17) / 17.0f; }

// A tiled EXR with 4096 x 4096 tiles under a 16 MiB cache: OpenImageIO aborted (check_max_mem assertion). Such a
// file is converted into 64 x 64 tiles, and looks up the same values.
TEST(TextureChecks, TilesLargerThanAFractionOfTheCacheAreRetiled) {
  TempDir dir;
  const auto big = write_pretiled(dir.path() / "big_tiles.exr", 64, 4096, noise);
  ASSERT_EQ(probe_image(big).tile_width, 4096);
  TextureCacheOptions o;
  o.memory_mb = 16;
  o.convert_dir = dir.path() / "tx";
  TextureCache cache(o);
  const auto prepared = cache.prepare(big, ColorSpace::Auto, TextureUse::Color);
  EXPECT_NE(prepared, big);
  EXPECT_EQ(probe_image(prepared).tile_width, 64);
  ImageTexture::Options closest;
  closest.filter = ImageTexture::Filter::Closest;
  const ImageTexture t(cache, prepared, closest);
  TextureQuery q;
  q.uv = Vec2((5 + 0.5f) / 64, 1.0f - (9 + 0.5f) / 64);  // texel (5, 9)
  EXPECT_NEAR(t.eval(q).g, noise(5, 9, 1), 1e-3f);
  // Small tiles are read as they are.
  const auto small = write_pretiled(dir.path() / "small_tiles.exr", 64, 32, noise);
  EXPECT_EQ(cache.prepare(small, ColorSpace::Auto, TextureUse::Color), small);
  EXPECT_EQ(max_tile_bytes(16), uint64_t{1} << 20);
}

// NaN texels in a pre-tiled texture were read as they are (1,136 NaN samples, exit 0): they are refused with their
// count, as in an image that is converted.
TEST(TextureChecks, PreTiledNanTexelsAreRefused) {
  TempDir dir;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const auto tx = write_pretiled(dir.path() / "nan.tx", 64, 32, [&](int x, int y, int c) {
    return (x == 40 && y == 3 && c == 1) || (x == 2 && y == 50) ? nan : 0.5f;
  });
  TextureCacheOptions o;
  o.convert_dir = dir.path() / "tx";
  TextureCache cache(o);
  const std::string e = prepare_error(cache, tx, TextureUse::Data);
  EXPECT_NE(e.find(tx.string()), std::string::npos) << e;
  EXPECT_NE(e.find("NaN or infinite values"), std::string::npos) << e;
  // 4 values at level 0; the box filter carries them into every coarser level (1 + 3 values per level below).
  EXPECT_NE(e.find("(the first at pixel (40, 3) channel 1 of resolution level 0)"), std::string::npos) << e;
  const ImageScan scan = scan_image_values(tx);
  EXPECT_GE(scan.nonfinite, 4u);
  EXPECT_EQ(scan.values, 64u * 64u * 3u - 4u);
  // An infinite texel too.
  const auto inf = write_pretiled(dir.path() / "inf.exr", 64, 32, [](int x, int, int) {
    return x == 63 ? std::numeric_limits<float>::infinity() : 1.0f;
  });
  EXPECT_NE(prepare_error(cache, inf, TextureUse::Color).find("NaN or infinite"), std::string::npos);
  // A clean file is scanned once: the marker lets a later cache skip the scan.
  const auto clean = write_pretiled(dir.path() / "clean.tx", 64, 32, noise);
  EXPECT_EQ(cache.prepare(clean, ColorSpace::Auto, TextureUse::Color), clean);
  int markers = 0;
  for (const auto& f : std::filesystem::directory_iterator(o.convert_dir))
    markers += f.path().extension() == ".checked";
  EXPECT_EQ(markers, 1);
}

// Tiny negative values (as in the HDRIs shipped with Blender: -3e-6 to -4e-5) are clamped to 0 with one warning
// naming their count; a meaningfully negative value is refused; data textures may be negative.
TEST(TextureChecks, TinyNegativeColoursAreClampedOthersRefused) {
  TempDir dir;
  TextureCacheOptions o;
  o.convert_dir = dir.path() / "tx";
  TextureCache cache(o);
  const auto tiny = write_test_exr(dir.path() / "tiny.exr", 32, 32,
                                   [](int x, int y, int c) { return (x + y) % 5 == 0 && c == 2 ? -4e-5f : 0.5f; });
  std::string warning;
  const auto prepared = cache.prepare(tiny, ColorSpace::Auto, TextureUse::Color, &warning);
  EXPECT_EQ(warning, tiny.string() + ": 205 tiny negative values (filtering noise) clamped to 0");
  EXPECT_EQ(scan_image_values(prepared).negative, 0u);
  // A later cache reuses the conversion and warns again.
  TextureCache again(o);
  warning.clear();
  EXPECT_EQ(again.prepare(tiny, ColorSpace::Auto, TextureUse::Color, &warning), prepared);
  EXPECT_NE(warning.find("205 tiny negative values"), std::string::npos);
  // Pre-tiled: converted, so that the copy holds the clamped values.
  const auto tiny_tx =
      write_pretiled(dir.path() / "tiny.tx", 64, 32, [](int x, int, int) { return x == 7 ? -3e-6f : 0.5f; });
  warning.clear();
  EXPECT_NE(cache.prepare(tiny_tx, ColorSpace::Auto, TextureUse::Color, &warning), tiny_tx);
  EXPECT_NE(warning.find("tiny negative values"), std::string::npos) << warning;
  // Meaningfully negative: refused, converted or pre-tiled.
  const auto bad = write_test_exr(dir.path() / "bad.exr", 32, 32,
                                  [](int x, int y, int) { return x == 3 && y == 4 ? -0.25f : 0.5f; });
  const std::string e = prepare_error(cache, bad, TextureUse::Color);
  EXPECT_NE(e.find("a colour must be >= 0, and pixel (3, 4) channel 0 is -0.25"), std::string::npos) << e;
  const auto bad_tx =
      write_pretiled(dir.path() / "bad.tx", 64, 32, [](int x, int y, int) { return x == 3 && y == 4 ? -0.25f : 0.5f; });
  EXPECT_NE(prepare_error(cache, bad_tx, TextureUse::Color).find("pixel (3, 4) channel 0 is -0.25"), std::string::npos);
  // Data (a float normal or displacement map) keeps its signs.
  EXPECT_EQ(cache.prepare(bad_tx, ColorSpace::Auto, TextureUse::Data), bad_tx);
}

// The rule of io/image_io.h's NegativeValues: negative values are noise when together they carry at most 1e-4 of the
// positive energy and each is within 1e-3 of the largest value. Blender 3.4's night.exr, for one, has 829 negative
// values down to -0.0033 (2.5 % of its mean of 0.13) beside a largest value of 7168: noise, clamped.
TEST(TextureChecks, NegativeValuesAreNoiseByEnergyAndPeak) {
  // A dark sky with a bright sun and ringing around it, like night.exr.
  Image img;
  img.width = 256;
  img.height = 128;
  img.channels = 4;
  img.data.assign(size_t(256 * 128 * 4), 0.1f);
  for (int c = 0; c < 3; ++c) img.data[size_t(4 * (60 * 256 + 100) + c)] = 7168.0f;
  for (int k = 1; k <= 8; ++k) img.data[size_t(4 * (60 * 256 + 100 + k) + 2)] = -0.0033f;
  img.data[3] = -7.0f;  // alpha is not checked
  Image sky = img;
  EXPECT_EQ(clamp_small_negatives(sky, "sky.exr", 3, "radiance"), 8u);
  EXPECT_EQ(sky.data[size_t(4 * (60 * 256 + 101) + 2)], 0.0f);
  EXPECT_EQ(sky.data[3], -7.0f);
  // Without the sun, -0.0033 is 3 % of the largest value: not ringing, refused.
  Image dark = img;
  for (int c = 0; c < 3; ++c) dark.data[size_t(4 * (60 * 256 + 100) + c)] = 0.1f;
  EXPECT_THROW(clamp_small_negatives(dark, "sky.exr", 3, "radiance"), InputError);
  // A signed image (a normal map in a colour slot): half its energy negative, refused though each value is small
  // next to the largest.
  Image signed_map = img;
  for (size_t i = 0; i < signed_map.data.size(); i += 8) signed_map.data[i] = -0.1f;
  try {
    clamp_small_negatives(signed_map, "n.exr", 3, "a colour");
    ADD_FAILURE() << "a signed image was clamped";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("of its energy"), std::string::npos) << e.what();
  }
  NegativeValues n;
  EXPECT_TRUE(n.noise());
  n = {1, 1e-4, 1.0, -1e-3, 1.0};
  EXPECT_TRUE(n.noise());
  n.negative_sum = 1.01e-4;
  EXPECT_FALSE(n.noise());
  n.negative_sum = 1e-4;
  n.most_negative = -1.01e-3;
  EXPECT_FALSE(n.noise());
}

// `kozu maketx` of an 8192^2 image peaked at 1.28 GB: the conversion's memory is estimated from the header and
// refused, before a pixel is read, when it is more than is left.
TEST(TextureChecks, ConversionMemoryIsCheckedBeforeReading) {
  TempDir dir;
  // 4096^2 RGBA float: 256 MiB of floats, a few kB of file (constant, compressed).
  const std::filesystem::path file = dir.path() / "large.exr";
  {
    OIIO::ImageSpec spec(4096, 4096, 4, OIIO::TypeDesc::HALF);
    spec.attribute("compression", "zip");
    auto out = OIIO::ImageOutput::create(file.string());
    ASSERT_TRUE(out && out->open(file.string(), spec));
    std::vector<float> row(4096 * 4, 0.5f);
    for (int y = 0; y < 4096; ++y) ASSERT_TRUE(out->write_scanline(y, 0, OIIO::TypeDesc::FLOAT, row.data()));
    out->close();
  }
  EXPECT_GT(make_tiled_texture_bytes(4096, 4096, 4), uint64_t{512} << 20);
  setenv("KOZU_MEMORY_LIMIT", "300M", 1);
  std::string e;
  try {
    make_tiled_texture(file, dir.path() / "large.tx", ColorSpace::Linear, TextureUse::Color);
  } catch (const InputError& err) {
    e = err.what();
  }
  unsetenv("KOZU_MEMORY_LIMIT");
  EXPECT_NE(e.find("converting this 4096 x 4096 image into a texture needs about"), std::string::npos) << e;
  EXPECT_NE(e.find("KOZU_MEMORY_LIMIT"), std::string::npos) << e;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "large.tx"));
}

// A file that exists but cannot be read was reported as "image file not found": its reason is given. As root
// (where permissions do not stop a read) the check runs in a child that drops to user nobody.
TEST(TextureChecks, UnreadableFilesSayWhy) {
  TempDir dir;
  const std::filesystem::path locked = dir.path() / "locked";
  std::filesystem::create_directories(locked);
  const auto image = write_test_exr(locked / "a.exr", 4, 4, [](int, int, int) { return 0.5f; });
  const auto plain = dir.path() / "b.exr";
  std::filesystem::copy_file(image, plain);
  ::chmod(dir.path().c_str(), 0755);
  ::chmod(locked.c_str(), 0700);  // no search permission for others: stat fails with EACCES
  ::chmod(plain.c_str(), 0600);   // no read permission for others
  const auto errors = [&]() {
    std::string a, b, c;
    try {
      read_image(image);
    } catch (const InputError& e) {
      a = e.what();
    }
    try {
      read_image(plain);
    } catch (const InputError& e) {
      b = e.what();
    }
    try {
      read_input_file(plain);
    } catch (const InputError& e) {
      c = e.what();
    }
    return a.find("cannot be read: Permission denied") != std::string::npos &&
           b.find("cannot be read: Permission denied") != std::string::npos &&
           c.find("cannot be read: Permission denied") != std::string::npos;
  };
  if (::geteuid() != 0) {
    EXPECT_TRUE(errors());
    return;
  }
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    if (::setgid(65534) != 0 || ::setuid(65534) != 0) ::_exit(2);
    ::_exit(errors() ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: a message lacks \"cannot be read: Permission denied\"; 2: setuid failed";
}

}  // namespace
}  // namespace kozu::test
