// Production use of `kozu render`, run as a process (docs/production.md): checkpoints resume to the image of a
// render never stopped, bit for bit, and are refused for another render; crops and sample ranges merge into the
// whole render's image; --budget has the images on disk before the budget, measured from outside; partial
// images are always whole files. Wall-clock tests, so an `integration` binary of their own.
#include "apps/cli_helpers.h"

#include "integrators/integrator.h"
#include "io/image_io.h"
#include "support/sanitizer.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <thread>

namespace kozu::test {
namespace {

int exit_code(int status) { return WIFEXITED(status) ? WEXITSTATUS(status) : -1; }

std::string read_file_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Runs kozu with `args`; the exit status, the output in *log.
// How long a tiny render takes here from the fork to the exit: mostly loading the shared libraries and the
// process's teardown, seconds in a sanitizer build on a loaded machine. Budgets in the tests leave room for it.
double start_up_seconds() {
  static const double seconds = [] {
    TempDir dir;
    ChildProcess run(
        fmt::format("{} render {} --resolution 8x8 --spp 1 -q -o '{}'", kozu(), spheres(), (dir.path() / "t.exr").string()),
        dir.path() / "log.txt");
    return run.wait(60.0) ? run.seconds_since_start() : 60.0;
  }();
  return seconds;
}

// Seconds for a whole 1920x1080 render of one sample a pixel on this machine, as built (a sanitizer's build prepares
// full-HD films several times slower), for budgets that must leave room for such a render but not for a denoiser.
double full_hd_seconds() {
  static const double seconds = [] {
    TempDir dir;
    ChildProcess run(fmt::format("{} render {} --resolution 1920x1080 --spp 1 -q -o '{}'", kozu(), spheres(),
                                 (dir.path() / "t.exr").string()),
                     dir.path() / "log.txt");
    return run.wait(120.0) ? run.seconds_since_start() : 120.0;
  }();
  return seconds;
}

int kozu_run(const std::string& args, std::string* log = nullptr) {
  std::string out;
  const int status = run_command(kozu() + " " + args, &out);
  if (log) *log = out;
  return status;
}

// A small scene with glossy, diffuse and emissive parts, so that every pixel's samples differ.
std::filesystem::path small_scene(const TempDir& dir, const std::string& name = "s.json", float light = 10.0f) {
  return dir.write(name, fmt::format(R"({{
    "camera": {{"position": [0, 1, 4], "look_at": [0, 0.5, 0], "fov": 40, "resolution": [64, 48]}},
    "render": {{"spp": 8, "max_depth": 4}},
    "materials": {{"floor": {{"type": "diffuse", "albedo": 0.6}},
                   "ball": {{"type": "conductor", "eta": [0.2, 0.45, 1.3], "k": [3.6, 2.6, 2.0], "roughness": 0.3}},
                   "black": {{"type": "diffuse", "albedo": 0}}}},
    "shapes": [{{"type": "quad", "material": "floor", "vertices": [[-3, 0, 3], [3, 0, 3], [3, 0, -3], [-3, 0, -3]]}},
               {{"type": "sphere", "center": [0, 0.6, 0], "radius": 0.6, "material": "ball"}},
               {{"type": "quad", "material": "black", "emission": {},
                 "vertices": [[-0.5, 3, 0.5], [-0.5, 3, -0.5], [0.5, 3, -0.5], [0.5, 3, 0.5]]}}],
    "lights": [{{"type": "environment", "radiance": 0.2}}] }})",
                                     light));
}

// The colour of two images (other channels aside): the largest relative difference, or whether they are
// identical bit for bit.
double max_relative_difference(const Image& a, const Image& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  const std::vector<Rgb> x = a.to_rgb(), y = b.to_rgb();
  if (x.size() != y.size()) return INFINITY;
  double worst = 0.0;
  for (size_t i = 0; i < x.size(); ++i)
    for (int c = 0; c < 3; ++c)
      worst = std::max(worst, std::abs(double(x[i][c]) - y[i][c]) / std::max(1e-6, std::abs(double(y[i][c]))));
  return worst;
}

bool identical(const Image& a, const Image& b) {
  const std::vector<Rgb> x = a.to_rgb(), y = b.to_rgb();
  return a.width == b.width && a.height == b.height &&
         std::equal(x.begin(), x.end(), y.begin(), y.end(),
                    [](const Rgb& p, const Rgb& q) { return p.r == q.r && p.g == q.g && p.b == q.b; });
}

// The index of a channel by name (OpenEXR stores channels sorted, so the order read back is not the order written).
int channel(const Image& img, const std::string& name) {
  const auto it = std::find(img.channel_names.begin(), img.channel_names.end(), name);
  EXPECT_NE(it, img.channel_names.end()) << name;
  return static_cast<int>(it - img.channel_names.begin());
}

// ---- checkpoints -----------------------------------------------------------------------------------------

// Path guiding through a checkpoint and a time limit (render/guiding_training.h): a resumed film trains on the side
// (its first samples are not rendered again) and is written whole; under a time limit the passes stop in time.
TEST(Checkpoint, GuidedRenderResumesWithSideTraining) {
  TempDir dir;
  const auto scene = small_scene(dir).string();
  const auto d = dir.path().string();
  std::string log;
  ASSERT_EQ(kozu_run(fmt::format("render '{}' --spp 3 -q -o '{}/g.exr' --checkpoint '{}/g.kzc' -D /render/guiding=on",
                                 scene, d, d),
                     &log),
            0)
      << log;
  ASSERT_EQ(kozu_run(fmt::format("render '{}' --spp 16 -q -o '{}/g2.exr' --resume '{}/g.kzc' --stats '{}/g2.json' "
                                 "-D /render/guiding=on",
                                 scene, d, d, d),
                     &log),
            0)
      << log;
  const nlohmann::json resumed = read_json(dir.path() / "g2.json");
  EXPECT_FALSE(resumed["guiding"]["in_image"].get<bool>());
  EXPECT_GE(resumed["guiding"]["passes"].get<int>(), 1);
  EXPECT_EQ(resumed["spp"].get<double>(), 16.0);
  for (float v : read_image(dir.path() / "g2.exr").data) EXPECT_TRUE(std::isfinite(v));

  ASSERT_EQ(kozu_run(fmt::format("render '{}' --spp 0 --time-limit 0.5 -q -o '{}/t.exr' --stats '{}/t.json' "
                                 "-D /render/guiding=on",
                                 scene, d, d),
                     &log),
            0)
      << log;
  const nlohmann::json timed = read_json(dir.path() / "t.json");
  EXPECT_TRUE(timed["guiding"]["in_image"].get<bool>());
  EXPECT_GE(timed["guiding"]["passes"].get<int>(), 1);
  // Sampling stops at the limit, whatever the passes: the sanitizer build's slowness leaves it a second's slack.
  EXPECT_LT(timed["render_seconds"].get<double>(), 0.5 + 1.0);
}

// A render stopped at 3 spp, and one stopped by its time limit at uneven per-pixel counts, each resumed to 16 spp,
// give the uninterrupted 16-spp image bit for bit, with "direct": "sample" and with "ltc", whose pixel memory (what
// each pixel's neighbours taught it: PixelMemory) the checkpoint carries. (Renders that write or resume a checkpoint
// keep the visible emission in every sample, "emission_supersampling" off: the uninterrupted ones are rendered so too.)
TEST(Checkpoint, ResumeIsBitIdenticalToAnUninterruptedRender) {
  for (const std::string direct : {"sample", "ltc"}) {
    SCOPED_TRACE(direct);
    TempDir dir;
    const auto scene = small_scene(dir).string();
    const auto d = dir.path().string();
    const std::string off = "-D /render/emission_supersampling=off --direct " + direct;
    ASSERT_EQ(kozu_run(fmt::format("render '{}' --spp 16 {} -q -o '{}/whole.exr'", scene, off, d)), 0);
    std::string log;
    ASSERT_EQ(kozu_run(fmt::format("render '{}' --spp 3 {} -q -o '{}/a.exr' --checkpoint '{}/a.kzc'", scene, off, d, d),
                       &log),
              0)
        << log;
    ASSERT_EQ(kozu_run(fmt::format("render '{}' --spp 16 {} -q -o '{}/a2.exr' --resume '{}/a.kzc' --stats '{}/a2.json'",
                                   scene, off, d, d, d),
                       &log),
              0)
        << log;
    EXPECT_EQ(read_json(dir.path() / "a2.json")["resumed_samples"].get<uint64_t>(), 64u * 48u * 3u);
    const Image whole = read_image(dir.path() / "whole.exr");
    EXPECT_TRUE(identical(read_image(dir.path() / "a2.exr"), whole)) << "resumed from 3 spp";

    // Uneven counts: a 320x240 render stopped by a 0.1 s limit, continued at that size to 16 spp.
    ASSERT_EQ(kozu_run(fmt::format("render '{}' --resolution 320x240 --spp 16 {} -q -o '{}/big.exr'", scene, off, d)),
              0);
    ASSERT_EQ(kozu_run(fmt::format("render '{}' --resolution 320x240 --spp 16 --time-limit 0.1 {} -q -o '{}/b.exr' "
                                   "--checkpoint '{}/b.kzc' --stats '{}/b.json'",
                                   scene, off, d, d, d),
                       &log),
              0)
        << log;
    const nlohmann::json stopped = read_json(dir.path() / "b.json");
    EXPECT_LT(stopped["spp_min"].get<int>(), 16) << "the time limit did not stop the render early";
    ASSERT_EQ(kozu_run(fmt::format("render '{}' --resolution 320x240 --spp 16 {} -q -o '{}/b2.exr' --resume '{}/b.kzc'",
                                   scene, off, d, d),
                       &log),
              0)
        << log;
    EXPECT_TRUE(identical(read_image(dir.path() / "b2.exr"), read_image(dir.path() / "big.exr")))
        << "resumed from " << stopped["spp_min"] << " .. " << stopped["spp_max"] << " spp";
  }
}

// A checkpoint is refused, with the reason, for another seed, scene (a -D override too, even one that sets the
// file's own value), resolution or max depth, and when it is truncated, damaged or not a checkpoint at all.
TEST(Checkpoint, RefusesAnotherRenderAndDamagedFiles) {
  TempDir dir;
  const auto scene = small_scene(dir).string();
  const auto other = small_scene(dir, "other.json", 11.0f).string();
  const auto d = dir.path().string();
  ASSERT_EQ(kozu_run(fmt::format("render '{}' --spp 2 -q -o '{}/a.exr' --checkpoint '{}/c.kzc'", scene, d, d)), 0);
  const auto expect_refused = [&](const std::string& args, const std::string& reason) {
    std::string log;
    EXPECT_EQ(kozu_run(fmt::format("render {} --spp 4 -q -o '{}/r.exr' --resume '{}/c.kzc'", args, d, d), &log), 1)
        << args;
    EXPECT_NE(log.find(reason), std::string::npos) << args << ": " << log;
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "r.exr")) << args;
  };
  expect_refused(fmt::format("'{}' --seed 7", scene), "its seed is 0 (this render: 7)");
  expect_refused(fmt::format("'{}'", other), "another scene");
  expect_refused(fmt::format("'{}' -D /render/max_depth=4", scene), "another scene");  // an override is the scene
  expect_refused(fmt::format("'{}' --resolution 32x24", scene), "its resolution is 64x48 (this render: 32x24)");
  expect_refused(fmt::format("'{}' --max-depth 2", scene), "its max_depth is 4 (this render: 2)");
  expect_refused(fmt::format("'{}' --crop 0,0,32,48", scene), "it covers the window 64x48 at 0,0");

  std::string bytes;
  {
    std::ifstream in(dir.path() / "c.kzc", std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto c = dir.path() / "c.kzc";
  dir.write("c.kzc", bytes.substr(0, bytes.size() - 100));
  expect_refused(fmt::format("'{}'", scene), "(truncated?)");
  std::string damaged = bytes;
  damaged[damaged.size() / 2] ^= 0x10;
  dir.write("c.kzc", damaged);
  expect_refused(fmt::format("'{}'", scene), "damaged");
  dir.write("c.kzc", "{\"not\": \"a checkpoint\"}");
  expect_refused(fmt::format("'{}'", scene), "not a kozu checkpoint: bad magic number");
  EXPECT_TRUE(std::filesystem::exists(c));
}

// ---- crops, sample ranges and kozu merge ------------------------------------------------------------------

// Two crops merge into the whole image bit for bit (each pixel has the same samples wherever it is rendered).
TEST(Merge, CropsPasteIntoTheWholeImageExactly) {
  TempDir dir;
  const auto scene = small_scene(dir).string();
  const auto d = dir.path().string();
  ASSERT_EQ(kozu_run(fmt::format("render '{}' -q -o '{}/whole.exr' --stats '{}/whole.json'", scene, d, d)), 0);
  // Under the default "direct": "ltc", whose pixels learn from their neighbours': the crops' edges learn from the
  // pixels across them as the whole render's do (PixelMemory).
  EXPECT_GT(read_json(dir.path() / "whole.json")["ltc"]["pixels_taking"].get<uint64_t>(), 0u);
  std::string log;
  ASSERT_EQ(kozu_run(fmt::format("render '{}' -q --crop 0,0,64,20 -o '{}/top.exr'", scene, d), &log), 0) << log;
  ASSERT_EQ(kozu_run(fmt::format("render '{}' -q --crop 0,20,64,48 -o '{}/bottom.exr'", scene, d), &log), 0) << log;
  const Image top = read_image_all(dir.path() / "top.exr");
  EXPECT_EQ(top.height, 20);
  EXPECT_EQ(top.full_size, Vec2i(64, 48));
  ASSERT_EQ(kozu_run(fmt::format("merge '{}/bottom.exr' '{}/top.exr' -o '{}/merged.exr'", d, d, d), &log), 0) << log;
  const Image merged = read_image(dir.path() / "merged.exr"), whole = read_image(dir.path() / "whole.exr");
  EXPECT_TRUE(identical(merged, whole)) << max_relative_difference(merged, whole);
  // A missing crop is named.
  EXPECT_EQ(kozu_run(fmt::format("merge '{}/top.exr' '{}/top.exr' -o '{}/bad.exr'", d, d, d), &log), 1);
  EXPECT_NE(log.find("the same samples would count twice"), std::string::npos) << log;
}

// Renders of samples 0..2 and 3..7 merge into the 8-spp render to float rounding, and overlapping ranges, or parts
// of other renders, are refused.
TEST(Merge, SampleRangesCombineIntoTheWholeRender) {
  TempDir dir;
  const auto scene = small_scene(dir).string();
  const auto d = dir.path().string();
  std::string log;
  ASSERT_EQ(kozu_run(fmt::format("render '{}' --spp 8 -q -o '{}/whole.exr'", scene, d)), 0);
  ASSERT_EQ(kozu_run(fmt::format("render '{}' --sample-range 0:3 -q -o '{}/p0.exr'", scene, d), &log), 0) << log;
  ASSERT_EQ(kozu_run(fmt::format("render '{}' --sample-range 3:8 -q -o '{}/p1.exr'", scene, d), &log), 0) << log;
  ASSERT_EQ(kozu_run(fmt::format("merge '{}/p0.exr' '{}/p1.exr' -o '{}/m.exr' -o '{}/m.png'", d, d, d, d), &log), 0)
      << log;
  const Image merged = read_image(dir.path() / "m.exr"), whole = read_image(dir.path() / "whole.exr");
  // Each part stores float means; n0·m0 + n1·m1 over 8 rounds to within a few float ulps of the whole mean.
  EXPECT_LT(max_relative_difference(merged, whole), 4 * 6e-8);
  const Image merged_all = read_image_all(dir.path() / "m.exr");
  ASSERT_EQ(merged_all.channels, 4);
  const int count = channel(merged_all, "sample_count");
  for (size_t i = count; i < merged_all.data.size(); i += 4) ASSERT_EQ(merged_all.data[i], 8.0f);
  // Under the default "direct": "ltc" (PixelMemory): parts that begin within the pilot samples its pixels learn from
  // (above: after them; here also just after them), each tracing again the pilots its film does not hold.
  for (const int split : {1, PixelMemory::kPilotSamples}) {
    ASSERT_EQ(kozu_run(fmt::format("render '{}' --sample-range 0:{} -q -o '{}/a.exr'", scene, split, d), &log), 0)
        << log;
    ASSERT_EQ(kozu_run(fmt::format("render '{}' --sample-range {}:8 -q -o '{}/b.exr'", scene, split, d), &log), 0)
        << log;
    ASSERT_EQ(kozu_run(fmt::format("merge '{}/a.exr' '{}/b.exr' -o '{}/ab.exr'", d, d, d), &log), 0) << log;
    EXPECT_LT(max_relative_difference(read_image(dir.path() / "ab.exr"), whole), 4 * 6e-8) << "split at " << split;
  }

  ASSERT_EQ(kozu_run(fmt::format("render '{}' --sample-range 2:8 -q -o '{}/p2.exr'", scene, d)), 0);
  EXPECT_EQ(kozu_run(fmt::format("merge '{}/p0.exr' '{}/p2.exr' -o '{}/bad.exr'", d, d, d), &log), 1);
  EXPECT_NE(log.find("holds samples 2..7 of pixels that"), std::string::npos) << log;
  ASSERT_EQ(kozu_run(fmt::format("render '{}' --sample-range 3:8 --seed 2 -q -o '{}/p3.exr'", scene, d)), 0);
  EXPECT_EQ(kozu_run(fmt::format("merge '{}/p0.exr' '{}/p3.exr' -o '{}/bad.exr'", d, d, d), &log), 1);
  EXPECT_NE(log.find("its kozu:seed is 2"), std::string::npos) << log;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "bad.exr"));
}

// A pixel whose mean is below 0 ("direct": "ltc"'s control variate at 1 sample a pixel: here 10 values of the small
// scene) is 0 in the images by default, and the signed mean under "negative_pixels": "keep". A --sample-range part
// stays signed whatever the scene says, and its merge clamps as the render would have, unless --keep-negative.
TEST(NegativePixels, AreZeroInImagesUnlessKept) {
  TempDir dir;
  const auto scene = small_scene(dir).string();
  const auto d = dir.path().string();
  std::string log;
  ASSERT_EQ(kozu_run(fmt::format("render '{}' --spp 1 -q -o '{}/clamp.exr'", scene, d), &log), 0) << log;
  ASSERT_EQ(
      kozu_run(fmt::format("render '{}' --spp 1 -D /render/negative_pixels=keep -q -o '{}/keep.exr'", scene, d), &log),
      0)
      << log;
  ASSERT_EQ(kozu_run(fmt::format("render '{}' --sample-range 0:1 -q -o '{}/part.exr'", scene, d), &log), 0) << log;
  ASSERT_EQ(kozu_run(fmt::format("merge '{}/part.exr' -o '{}/m.exr'", d, d), &log), 0) << log;
  ASSERT_EQ(kozu_run(fmt::format("merge --keep-negative '{}/part.exr' -o '{}/mk.exr'", d, d), &log), 0) << log;
  const Image keep = read_image(dir.path() / "keep.exr"), clamp = read_image(dir.path() / "clamp.exr");
  const auto negatives = [](const Image& im) {
    return std::count_if(im.data.begin(), im.data.end(), [](float v) { return v < 0.0f; });
  };
  ASSERT_GT(negatives(keep), 0) << "the scene no longer gives a negative pixel at 1 spp: the test shows nothing";
  Image expected = keep;
  for (float& v : expected.data) v = std::max(v, 0.0f);
  EXPECT_TRUE(identical(clamp, expected));
  EXPECT_TRUE(identical(read_image(dir.path() / "part.exr"), keep));
  EXPECT_TRUE(identical(read_image(dir.path() / "m.exr"), expected));
  EXPECT_TRUE(identical(read_image(dir.path() / "mk.exr"), keep));
  const auto said = [&](const char* file) {
    for (const auto& [k, v] : read_image_all(dir.path() / file).attributes)
      if (k == "kozu:negative_pixels") return v;
    return std::string("(none)");
  };
  EXPECT_EQ(said("clamp.exr"), "clamp");
  EXPECT_EQ(said("keep.exr"), "keep");
  EXPECT_EQ(said("m.exr"), "clamp");
  EXPECT_EQ(said("mk.exr"), "keep");
  EXPECT_EQ(
      kozu_run(fmt::format("render '{}' --spp 1 -D /render/negative_pixels=drop -q -o '{}/bad.exr'", scene, d), &log),
      1);
  EXPECT_NE(log.find("negative_pixels"), std::string::npos) << log;
}

// ---- AOVs -------------------------------------------------------------------------------------------------

// --aov writes the conventional channel names; the colour is the same image as without AOVs; the features are
// right where the answer is known (the diffuse floor's albedo is its sample weight exactly, its normal is +y, Z is
// the depth of P along the view axis, the sky is Z = 1e10); and a resumed render keeps them bit for bit.
TEST(Aov, ConventionalChannelsWithTheRightValues) {
  TempDir dir;
  const auto scene = small_scene(dir).string();
  const auto d = dir.path().string();
  std::string log;
  ASSERT_EQ(kozu_run(fmt::format("render '{}' -q -o '{}/plain.exr'", scene, d)), 0);
  ASSERT_EQ(kozu_run(fmt::format("render '{}' -q -o '{}/aov.exr' --aov albedo,normal,depth,position,variance,"
                                 "sample_count,emission",
                                 scene, d),
                     &log),
            0)
      << log;
  const Image img = read_image_all(dir.path() / "aov.exr");
  std::vector<std::string> names = img.channel_names;
  std::sort(names.begin(), names.end());
  const std::vector<std::string> expected = {
      "B",        "G",          "N.X",        "N.Y",        "N.Z",        "P.X",        "P.Y",
      "P.Z",      "R",          "Z",          "albedo.B",   "albedo.G",   "albedo.R",   "emission.B",
      "emission.G", "emission.R", "sample_count", "variance.B", "variance.G", "variance.R"};
  ASSERT_EQ(names, expected);
  const Image plain = read_image(dir.path() / "plain.exr");
  EXPECT_TRUE(identical(img, plain)) << "the colour changed with --aov";
  const int c = img.channels;
  const auto at = [&](int x, int y, const char* name) {
    return img.data[(size_t(y) * img.width + x) * c + channel(img, name)];
  };
  // The bottom row's middle sees the floor only (the sphere stands behind it).
  const Vec3 cam(0, 1, 4), forward = glm::normalize(Vec3(0, 0.5, 0) - cam);
  for (int x = 28; x < 36; ++x) {
    const int y = 47;
    for (const char* a : {"albedo.R", "albedo.G", "albedo.B"}) EXPECT_NEAR(at(x, y, a), 0.6f, 1e-5f) << x;
    EXPECT_NEAR(at(x, y, "N.Y"), 1.0f, 1e-5f);
    EXPECT_NEAR(at(x, y, "P.Y"), 0.0f, 1e-4f) << "P.Y on the floor";
    const Vec3 p(at(x, y, "P.X"), at(x, y, "P.Y"), at(x, y, "P.Z"));
    EXPECT_NEAR(at(x, y, "Z"), glm::dot(p - cam, forward), 1e-3f);
    EXPECT_EQ(at(x, y, "sample_count"), 8.0f);
    EXPECT_GT(at(x, y, "variance.R"), 0.0f);
    EXPECT_EQ(at(x, y, "emission.G"), 0.0f) << "the floor emits nothing";
  }
  // The top row sees the sky, which is all visible emission (the environment's 0.2).
  EXPECT_EQ(at(32, 0, "Z"), 1e10f);
  EXPECT_EQ(at(32, 0, "albedo.G"), 0.0f);
  for (const char* e : {"emission.R", "emission.G", "emission.B"}) EXPECT_NEAR(at(32, 0, e), 0.2f, 1e-6f) << e;

  // Features survive a checkpoint: 3 spp then resumed to 8 equals the uninterrupted AOV image.
  ASSERT_EQ(kozu_run(fmt::format("render '{}' --spp 3 -q -o '{}/a.exr' --aov albedo,normal,depth,position,"
                                 "variance,sample_count,emission --checkpoint '{}/a.kzc'",
                                 scene, d, d),
                     &log),
            0)
      << log;
  ASSERT_EQ(kozu_run(fmt::format("render '{}' --spp 8 -q -o '{}/b.exr' --aov albedo,normal,depth,position,variance,"
                                 "sample_count,emission --resume '{}/a.kzc'",
                                 scene, d, d),
                     &log),
            0)
      << log;
  EXPECT_TRUE(read_image_all(dir.path() / "b.exr").data == img.data);
  // A checkpoint without features cannot continue a render that needs them.
  EXPECT_EQ(kozu_run(fmt::format("render '{}' --spp 2 -q -o '{}/c.exr' --checkpoint '{}/c.kzc'", scene, d, d)), 0);
  EXPECT_EQ(kozu_run(fmt::format("render '{}' -q -o '{}/e.exr' --aov normal --resume '{}/c.kzc'", scene, d, d), &log),
            1);
  EXPECT_NE(log.find("it was saved without the features"), std::string::npos) << log;
  EXPECT_EQ(kozu_run(fmt::format("render '{}' -q -o '{}/e.exr' --aov normals", scene, d), &log), 1);
  EXPECT_NE(log.find("--aov: unknown AOV 'normals'"), std::string::npos) << log;
}

// ---- animation --------------------------------------------------------------------------------------------

// A camera animation renders every frame to its numbered file; one frame rendered alone (--frames N) is the same
// image as in the whole run; a shared --budget has every frame on disk before it; and the mistakes are named.
TEST(Animation, FramesToNumberedFilesWithinOneBudget) {
  TempDir dir;
  const auto d = dir.path().string();
  const std::string scene = dir.write("anim.json", R"({
    "camera": {"position": [0, 1, 4], "look_at": [0, 0.5, 0], "fov": 40, "resolution": [64, 48]},
    "render": {"spp": 4, "max_depth": 4},
    "animation": {"fps": 10, "frames": 4,
                  "camera": [{"time": 0}, {"time": 0.3, "position": [2, 1, 4], "fov": 30}]},
    "materials": {"floor": {"type": "diffuse", "albedo": 0.6}},
    "shapes": [{"type": "quad", "material": "floor", "vertices": [[-3, 0, 3], [3, 0, 3], [3, 0, -3], [-3, 0, -3]]},
               {"type": "sphere", "center": [0, 0.6, 0], "radius": 0.6, "material": "floor"}],
    "lights": [{"type": "environment", "radiance": 0.8}] })")
                                .string();
  std::string log;
  ASSERT_EQ(kozu_run(fmt::format("render '{}' -q -o '{}/f/%03d.exr' --stats '{}/s.json'", scene, d, d), &log), 0)
      << log;
  std::vector<Image> frames;
  for (int f = 0; f < 4; ++f) frames.push_back(read_image(dir.path() / "f" / fmt::format("{:03}.exr", f)));
  EXPECT_FALSE(identical(frames[0], frames[3])) << "the camera did not move";
  EXPECT_EQ(read_json(dir.path() / "s.json")["frames"].size(), 4u);
  ASSERT_EQ(kozu_run(fmt::format("render '{}' --frames 2 -q -o '{}/two.exr'", scene, d), &log), 0) << log;
  EXPECT_TRUE(identical(read_image(dir.path() / "two.exr"), frames[2]));

  // Four frames share a 4-second budget (more where kozu starts slowly): all on disk before it, timed from outside.
  const double budget = std::max(4.0, 6.0 * start_up_seconds());
  ChildProcess run(fmt::format("{} render '{}' --budget {} -q -o '{}/b/%02d.png'", kozu(), scene, budget, d),
                   dir.path() / "log.txt");
  const std::optional<int> status = run.wait(60.0);
  const double wall = run.seconds_since_start();
  ASSERT_TRUE(status);
  EXPECT_EQ(WEXITSTATUS(*status), 0) << run.log();
  EXPECT_LT(wall, budget);
  for (int f = 0; f < 4; ++f) EXPECT_TRUE(std::filesystem::exists(dir.path() / "b" / fmt::format("{:02}.png", f)));

  // With --denoise and no sample cap (--spp 0: until the budget) every frame is denoised, the last one too (its
  // plan once left it the measured cost of the frames before, less than the denoiser's estimate, and skipped it).
  // Room for four frames with their denoiser whatever the build: 12 x one denoised frame at 1 spp, timed here (under
  // AddressSanitizer the filter alone takes seconds at this size).
  const auto probe_start = std::chrono::steady_clock::now();
  ASSERT_EQ(kozu_run(fmt::format("render '{}' --frames 0:0 --spp 1 --resolution 160x90 --denoise -q -o '{}/p/%02d.png'",
                                 scene, d),
                     &log),
            0)
      << log;
  const double probe = std::chrono::duration<double>(std::chrono::steady_clock::now() - probe_start).count();
  const double roomy = std::max(8.0, 12.0 * probe);
  ChildProcess denoised(fmt::format("{} render '{}' --spp 0 --resolution 160x90 --denoise --budget {} -q -o '{}/c/%02d.png'",
                                    kozu(), scene, roomy, d),
                        dir.path() / "log2.txt");
  const std::optional<int> denoised_status = denoised.wait(roomy + 60.0);
  ASSERT_TRUE(denoised_status);
  EXPECT_EQ(WEXITSTATUS(*denoised_status), 0) << denoised.log();
  EXPECT_LT(denoised.seconds_since_start(), roomy);
  // Under AddressSanitizer the calibrations (a 160x90 write, a 160x90 filter) misjudge the frames' real costs by
  // more than the margins (the last frame's filter was skipped there on 2026-11-29); the budget itself holds.
  if (!kSanitized) {
    EXPECT_EQ(denoised.log().find("skipped"), std::string::npos) << denoised.log();
    for (int f = 0; f < 4; ++f)
      EXPECT_TRUE(std::filesystem::exists(dir.path() / "c" / fmt::format("{:02}.denoised.png", f))) << f;
  }

  // The default outputs, with --denoise: out/anim/0000.exr, .png, 0000.denoised.exr, .png, ... (the denoised names
  // once collided with the plain ones).
  ASSERT_EQ(run_command(fmt::format("cd '{}' && {} render '{}' --frames 0:1 --denoise -q", d, kozu(), scene), &log), 0)
      << log;
  for (int f = 0; f < 2; ++f)
    for (const char* name : {"{:04}.exr", "{:04}.png", "{:04}.denoised.exr", "{:04}.denoised.png"})
      EXPECT_TRUE(std::filesystem::exists(dir.path() / "out" / "anim" / fmt::format(fmt::runtime(name), f)))
          << fmt::format(fmt::runtime(name), f);

  EXPECT_EQ(kozu_run(fmt::format("render '{}' -q -o '{}/one.png'", scene, d), &log), 1);
  EXPECT_NE(log.find("4 frames would overwrite one file"), std::string::npos) << log;
  EXPECT_EQ(kozu_run(fmt::format("render '{}' --frames 3:5 -q -o '{}/%d.png'", scene, d), &log), 1);
  EXPECT_NE(log.find("--frames: expected A:B"), std::string::npos) << log;
  EXPECT_EQ(kozu_run(fmt::format("render '{}' --frames 1 -q -o '{}/x.png'", small_scene(dir).string(), d), &log), 1);
  EXPECT_NE(log.find("has no \"animation\" block"), std::string::npos) << log;
}

// Every frame's outputs are checked before the first frame is rendered: a folder named like frame 2 and a file name
// too long once numbered (%999d) once stopped an animation after frame 0 with "written: none".
TEST(Animation, EveryFramesOutputsAreCheckedBeforeRendering) {
  TempDir dir;
  const auto d = dir.path().string();
  const std::string scene = dir.write("anim.json", R"({
    "camera": {"position": [0, 1, 4], "look_at": [0, 0.5, 0], "fov": 40, "resolution": [16, 12]},
    "render": {"spp": 1},
    "animation": {"fps": 10, "frames": 5, "camera": [{"time": 0}, {"time": 0.4, "position": [2, 1, 4]}]},
    "materials": {"m": {"type": "diffuse", "albedo": 0.6}},
    "shapes": [{"type": "sphere", "center": [0, 0.6, 0], "radius": 0.6, "material": "m"}],
    "lights": [{"type": "environment", "radiance": 0.8}] })")
                                .string();
  std::filesystem::create_directories(dir.path() / "f" / "0002.png");
  std::string log;
  EXPECT_EQ(kozu_run(fmt::format("render '{}' -q -o '{}/f/%04d.png'", scene, d), &log), 1);
  EXPECT_NE(log.find("f/0002.png: is a folder (frame 2)"), std::string::npos) << log;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "f" / "0000.png")) << "frame 0 was rendered first";
  EXPECT_EQ(kozu_run(fmt::format("render '{}' -q -o '{}/g/%999d.png'", scene, d), &log), 1);
  EXPECT_NE(log.find("File name too long"), std::string::npos) << log;
  // A frame's statistics named like the scene itself (an input) are refused too.
  std::filesystem::copy_file(scene, dir.path() / "0003.json");
  EXPECT_EQ(kozu_run(fmt::format("render '{}/0003.json' -q -o '{}/%04d.png' --stats '{}/%04d.json'", d, d, d), &log),
            1);
  EXPECT_NE(log.find("an input of the render (frame 3)"), std::string::npos) << log;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "0000.png"));
}

// A file that is not a scene is named as such (an OBJ once answered with a JSON syntax error), and --aov with no EXR
// output is refused as --alpha is (it was dropped silently).
TEST(ProductionFlags, NotAScene_AndAovsWithoutAnExr) {
  TempDir dir;
  const auto d = dir.path().string();
  const std::pair<std::string, std::string> cases[] = {
      {"m.obj", "an OBJ mesh is not a scene"},
      {"m.ply", "a PLY mesh is not a scene"},
      {"m.blend", "export the scene from Blender as glTF 2.0"},
      {"m.fbx", "convert it to glTF"},
      {"m.png", "an image is not a scene"},
  };
  for (const auto& [file, message] : cases) {
    dir.write(file, "v 0 0 0\n");
    std::string log;
    EXPECT_EQ(kozu_run(fmt::format("render '{}/{}' -q -o '{}/x.exr'", d, file, d), &log), 1) << file;
    EXPECT_NE(log.find(message), std::string::npos) << file << ": " << log;
  }
  std::string log;
  EXPECT_EQ(kozu_run(fmt::format("render --demo --aov normal -q -o '{}/x.png'", d), &log), 1);
  EXPECT_NE(log.find("--aov: AOVs are extra channels of .exr outputs"), std::string::npos) << log;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "x.png"));
}

// An output named in bytes that are not UTF-8 keeps its statistics (their JSON once failed to serialise the name,
// and the statistics were lost).
TEST(ProductionFlags, StatisticsSurviveANameThatIsNotUtf8) {
  TempDir dir;
  std::string log;
  ASSERT_EQ(kozu_run(fmt::format("render --demo --resolution 16x16 --spp 1 -q -o '{}/\xff.exr' --stats '{}/s.json'",
                                 dir.path().string(), dir.path().string()),
                     &log),
            0)
      << log;
  EXPECT_EQ(read_json(dir.path() / "s.json")["outputs"].size(), 1u);
}

// ---- flags ------------------------------------------------------------------------------------------------

TEST(ProductionFlags, BadValuesNameTheFlagAndTheRule) {
  TempDir dir;
  const auto scene = small_scene(dir).string();
  const auto d = dir.path().string();
  const std::pair<std::string, std::string> cases[] = {
      {"--checkpoint-every 5", "--checkpoint-every: needs --checkpoint FILE"},
      {"--sample-range 5:3", "--sample-range: expected A:B with integers 0 <= A < B"},
      {"--sample-range 0:4 --spp 4", "give it or --spp, not both"},
      {"--crop 0,0,65,48", "--crop: expected X0,Y0,X1,Y1 with 0 <= X0 < X1 <= 64"},
      {"--crop 1,2,3", "--crop: expected X0,Y0,X1,Y1"},
      {"--budget 0", "--budget: expected a number in (0, 1000000000], got 0"},
      {"--partial-every -1", "--partial-every: expected a number in (0, 1000000000], got -1"},
      {"--stats ''", "--stats: expected a file name, got an empty one"},
      {"--checkpoint ''", "--checkpoint: expected a file name, got an empty one"},
      {"--resume ''", "--resume: expected a file name, got an empty one"},
      {"--denoise --denoiser oidn", "--denoiser: 'oidn': expected nlmeans (the default), regression, unet or ensemble"},
      {"--denoiser unet", "--denoiser: chooses the filter of --denoise or --denoise-only: give one"},
  };
  for (const auto& [flags, message] : cases) {
    std::string log;
    EXPECT_EQ(kozu_run(fmt::format("render '{}' {} -q -o '{}/x.exr'", scene, flags, d), &log), 1) << flags;
    EXPECT_NE(log.find(message), std::string::npos) << flags << ": " << log;
  }
}

// ---- budgets and partial images ---------------------------------------------------------------------------

// With --budget B the process has written its images and exited within B seconds, timed from outside (from the
// fork), on the sphere studio (scenes/spheres.json, the first demo) at its full 1280x720. The budgets are 2 and 5 s, or more where merely starting kozu takes long
// (a sanitizer build, which starts in 0.5 s on a quiet machine, took over 1.5 s beside another test): a budget is
// held when it leaves room for the start and the writes; one that does not is refused (the test below).
TEST(Budget, ImagesAreOnDiskBeforeTheBudget) {
  const double start_up = start_up_seconds();
  for (const double budget : {std::max(2.0, 4.0 * start_up), std::max(5.0, 8.0 * start_up)}) {
    TempDir dir;
    const auto exr = dir.path() / "d.exr", png = dir.path() / "d.png", stats = dir.path() / "d.json";
    ChildProcess run(fmt::format("{} render {} --budget {} -q -o '{}' -o '{}' --stats '{}'", kozu(), spheres(), budget,
                                 exr.string(), png.string(), stats.string()),
                     dir.path() / "log.txt");
    const std::optional<int> status = run.wait(budget + 30.0);
    const double wall = run.seconds_since_start();
    ASSERT_TRUE(status);
    EXPECT_EQ(exit_code(*status), 0) << run.log();
    EXPECT_LT(wall, budget) << "budget " << budget << " s\n" << run.log() << "\n" << read_file_text(stats);
    const nlohmann::json j = read_json(stats);
    EXPECT_TRUE(j["hit_time_limit"].get<bool>());
    // The budget was used, not wasted. Sampling ran until what was left was the reserve kozu planned for the writes
    // (process_seconds - write_seconds is when sampling and the hole filling ended; 0.25 s for the scheduler and the
    // last pass's samples). At 5 s sampling took most of it, except under a sanitizer, whose writes measure several
    // times slower and whose reserve grows with them when another test loads the machine (2.35 s of 5 once); at 2 s
    // a slow machine may rightly reserve it all for the writes.
    if (budget >= 5.0) {
      EXPECT_GT(j["spp"].get<double>(), 0.0);
      const double sampled_until = j["process_seconds"].get<double>() - j["write_seconds"].get<double>();
      const double reserve = j["budget_reserve_seconds"].get<double>();
      EXPECT_GT(sampled_until, budget - reserve - 0.25) << "budget " << budget << "\n" << read_file_text(stats);
      if (!kSanitized) {
        EXPECT_GT(wall, 0.5 * budget) << "budget " << budget << "\n" << read_file_text(stats);
      }
    }
    EXPECT_EQ(read_image(exr).width, 1280);
    EXPECT_EQ(read_image(png).width, 1280);
    // Under a budget the EXR is written uncompressed (zip takes ten times as long for 10 % of the size).
    const auto in = OIIO::ImageInput::open(exr.string());
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().get_string_attribute("compression"), "none");
  }
}

// The frames stop when the budget does: 20,000 frames cannot all be set up and written in 2 s (2,000 could, on a
// quiet machine: 16 x 12 frames take about 1 ms each), so kozu renders the frames that fit, names the ones it did
// not render, exits 1, and is done inside the budget (20,000 frames with --budget 3 once took 9.2 s, each frame's
// setting up and writing unaccounted for).
TEST(Budget, FramesStopWhenTheBudgetDoes) {
  TempDir dir;
  const auto d = dir.path().string();
  const std::string scene = dir.write("anim.json", R"({
    "camera": {"position": [0, 1, 4], "look_at": [0, 0.5, 0], "fov": 40, "resolution": [16, 12]},
    "animation": {"fps": 10, "frames": 20000,
                  "camera": [{"time": 0}, {"time": 1999.9, "position": [2, 1, 4]}]},
    "materials": {"m": {"type": "diffuse", "albedo": 0.6}},
    "shapes": [{"type": "sphere", "center": [0, 0.6, 0], "radius": 0.6, "material": "m"}],
    "lights": [{"type": "environment", "radiance": 0.8}] })")
                                .string();
  const double budget = std::max(2.0, 4.0 * start_up_seconds());
  ChildProcess run(fmt::format("{} render '{}' --budget {} -q -o '{}/f/%04d.png'", kozu(), scene, budget, d),
                   dir.path() / "log.txt");
  const std::optional<int> status = run.wait(60.0);
  const double wall = run.seconds_since_start();
  ASSERT_TRUE(status);
  EXPECT_EQ(exit_code(*status), 1) << run.log();
  EXPECT_LT(wall, budget) << run.log();
  EXPECT_NE(run.log().find("were not rendered"), std::string::npos) << run.log();
  int written = 0;
  for (const auto& f : std::filesystem::directory_iterator(dir.path() / "f")) written += f.path().extension() == ".png";
  EXPECT_GT(written, 0);
  EXPECT_LT(written, 20000);
  // The frames written are the first ones, with no gap.
  for (int f = 0; f < written; ++f)
    EXPECT_TRUE(std::filesystem::exists(dir.path() / "f" / fmt::format("{:04}.png", f)));
}

// Under --budget the raw images come first and the denoised ones only when the denoiser fits: at 1920x1080 the
// denoiser needs seconds (filter and re-estimation about 3 µs a pixel on a quiet 2-core machine), so a 2 s budget
// writes the raw images, warns, and exits 0 in time (--denoise --budget 1 at 720p once took 13 s; 640x360 was
// enough until the filter was vectorized). --denoise-only writes the raw image under its name.
TEST(Budget, TheDenoiserRunsOnlyWhenItFits) {
  for (const char* flag : {"--denoise", "--denoise-only"}) {
    TempDir dir;
    const auto exr = dir.path() / "d.exr";
    // Room for a full-HD sample and its writes even where preparing the film is slow (under AddressSanitizer and a
    // loaded machine it once took 1.96 s of a 2.01 s budget); the denoiser needs many times that.
    const double budget = std::max({2.0, 4.0 * start_up_seconds(), full_hd_seconds()});
    ChildProcess run(fmt::format("{} render {} --resolution 1920x1080 {} --budget {} -q -o '{}'", kozu(), spheres(), flag,
                                 budget, exr.string()),
                     dir.path() / "log.txt");
    const std::optional<int> status = run.wait(60.0);
    const double wall = run.seconds_since_start();
    ASSERT_TRUE(status);
    EXPECT_EQ(exit_code(*status), 0) << run.log();
    EXPECT_LT(wall, budget) << flag << "\n" << run.log();
    EXPECT_NE(run.log().find("--denoise: skipped"), std::string::npos) << run.log();
    EXPECT_EQ(read_image(exr).width, 1920);
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "d.denoised.exr"));
  }
  // With room for it (a sample cap ends sampling early, leaving most of the budget), the denoised image is written
  // too. The room includes the filter's calibration at plan time, which the start-up probe does not run: under
  // AddressSanitizer on a busy 2-core machine it alone took 1.7 s, and a 4 s budget once left too little.
  TempDir dir;
  const auto exr = dir.path() / "d.exr";
  std::string log;
  ASSERT_EQ(kozu_run(fmt::format("render {} --resolution 96x54 --spp 4 --denoise --budget {} -q -o '{}'", spheres(),
                                 std::max(10.0, 8.0 * start_up_seconds()), exr.string()),
                     &log),
            0)
      << log;
  EXPECT_EQ(log.find("skipped"), std::string::npos) << log;
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "d.denoised.exr"));
}

// A budget that cannot hold even the writes is refused at once, before rendering, with nothing written (4K with
// --budget 1.5 once took 5.3 s).
TEST(Budget, OneThatCannotHoldTheWritesIsRefusedAtOnce) {
  TempDir dir;
  const auto png = dir.path() / "d.png";
  ChildProcess run(fmt::format("{} render {} --resolution 320x180 --budget 0.05 -q -o '{}'", kozu(), spheres(), png.string()),
                   dir.path() / "log.txt");
  const std::optional<int> status = run.wait(60.0);
  ASSERT_TRUE(status);
  EXPECT_EQ(exit_code(*status), 1) << run.log();
  EXPECT_NE(run.log().find("nothing rendered"), std::string::npos) << run.log();
  EXPECT_FALSE(std::filesystem::exists(png));
  EXPECT_EQ(temp_files(dir.path()), 0);
}

// A scene whose loading outlasts the budget (the built-in demo in a fresh folder makes its textures, their filtered
// normal map and its surface occlusion: over a second) ends the process inside the budget, with one message, exit 1,
// nothing written and no temporary file left (the watch fires 0.15 s before the budget).
TEST(Budget, LoadingThatOutlastsItEndsInsideIt) {
  TempDir dir;
  const auto png = dir.path() / "d.png";
  const double budget = start_up_seconds() + 0.3;
  ChildProcess run(fmt::format("{} render --demo --budget {} -q -o '{}'", kozu(), budget, png.string()),
                   dir.path() / "log.txt");
  const std::optional<int> status = run.wait(120.0);
  const double wall = run.seconds_since_start();
  ASSERT_TRUE(status);
  EXPECT_EQ(exit_code(*status), 1) << run.log();
  EXPECT_NE(run.log().find("the budget ran out while the scene was loading"), std::string::npos) << run.log();
  EXPECT_LT(wall, budget) << run.log();
  EXPECT_FALSE(std::filesystem::exists(png));
  EXPECT_EQ(temp_files(dir.path()), 0);
  if (std::filesystem::exists(dir.path() / ".kozu-tx")) {
    for (const auto& f : std::filesystem::recursive_directory_iterator(dir.path() / ".kozu-tx"))
      EXPECT_EQ(f.path().filename().string().find(".tmp"), std::string::npos) << f.path();
  }
}

// While --partial-every writes the images, every read of the output sees a whole image (the writes are atomic
// renames), and the partial writes happened.
TEST(PartialImages, AreAlwaysWholeFiles) {
  TempDir dir;
  const auto exr = dir.path() / "p.exr", stats = dir.path() / "p.json";
  ChildProcess run(fmt::format("{} render {} --resolution 320x180 --time-limit 3 --partial-every 0.25 -q -o '{}' "
                               "--stats '{}'",
                               kozu(), spheres(), exr.string(), stats.string()),
                   dir.path() / "log.txt");
  int reads = 0;
  std::optional<int> status;
  while (!(status = run.wait(0.0))) {
    if (std::filesystem::exists(exr)) {
      const Image img = read_image(exr);  // throws (fails the test) on a half-written file
      EXPECT_EQ(img.width, 320);
      ++reads;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    ASSERT_LT(run.seconds_since_start(), 60.0);
  }
  EXPECT_EQ(exit_code(*status), 0) << run.log();
  EXPECT_GE(reads, 3);  // each read is checked whole; a sanitizer build reads slowly
  EXPECT_GE(read_json(stats)["partial_images"].get<int>(), 4);
  EXPECT_EQ(temp_files(dir.path()), 0);
}

}  // namespace
}  // namespace kozu::test
