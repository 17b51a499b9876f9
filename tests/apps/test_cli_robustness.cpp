// `kozu render` against hostile input, run as a process: flags are validated by the rules of their scene keys,
// outputs are checked before any work, absurd sizes are refused before any allocation, and non-finite time limits
// are rejected. Each test is the regression case of a defect found by a round of hostile input. The deadline and
// stop-signal tests, which wait on the clock, are in test_cli_timing.cpp.
#include "apps/cli_helpers.h"

#include "core/memory.h"
#include "io/image_io.h"
#include "render/renderer.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

namespace kozu::test {
namespace {

// --time-limit nan rendered forever and 1e10 overflowed the deadline into an all-black image with exit 0.
TEST(CliDeadline, NonFiniteLimitsAreRejectedAndHugeOnesSaturate) {
  TempDir dir;
  const auto scene = dir.write("s.json", kFurnace);
  std::string out;
  for (const char* bad : {"nan", "inf", "-inf", "-1"}) {
    EXPECT_EQ(run_command(fmt::format("{} render '{}' --time-limit {} -o '{}'", kozu(), scene.string(), bad,
                                      (dir.path() / "x.exr").string()),
                          &out),
              1)
        << bad;
    EXPECT_NE(out.find("error: kozu render: --time-limit: expected"), std::string::npos) << out;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "x.exr"));
  const auto exr = dir.path() / "t.exr";
  ASSERT_EQ(run_command(fmt::format("{} render '{}' --time-limit 1e10 --spp 2 -o '{}'", kozu(), scene.string(),
                                    exr.string()),
                        &out),
            0)
      << out;
  for (float v : read_image(exr).data) EXPECT_NEAR(v, 1.0f, 1e-4f);  // the furnace sphere, not black
}

// ---- flags and scene keys share one rule -------------------------------------------------------------------

TEST(CliFlags, ValidatedByTheRulesOfTheirSceneKeys) {
  TempDir dir;
  const auto scene = dir.write("s.json", kFurnace);
  const auto x = dir.path() / "x.exr";
  struct Case {
    std::string flags, message;
  };
  const std::vector<Case> cases = {
      {"--seed -1", "error: kozu render: --seed: expected an integer in [0, 18446744073709551615], got -1\n"},
      {"--max-depth 100000", "error: kozu render: --max-depth: expected an integer in [0, 1024], got 100000\n"},
      {"--max-depth 3.5", "error: kozu render: --max-depth: expected an integer in [0, 1024], got 3.5\n"},
      {"--exposure nan", "error: kozu render: --exposure: expected a number in [-64, 64], got the string \"nan\"\n"},
      {"--spp -1", "error: kozu render: --spp: expected an integer in [0, 2147483647], got -1\n"},
      {"--spp 0x10", "error: kozu render: --spp: expected an integer in [0, 2147483647], got the string \"0x10\"\n"},
      {"--spp 1e300", "error: kozu render: --spp: expected an integer in [0, 2147483647], got 1e+300\n"},
      {"--threads -2", "error: kozu render: --threads: expected an integer in [0, 2147483647], got -2\n"},
      {"--resolution 12",
       "error: kozu render: --resolution: expected WIDTHxHEIGHT with each an integer in [1, 65536] (e.g. "
       "1920x1080), got '12'\n"},
      {"--resolution 0x10",
       "error: kozu render: --resolution: expected WIDTHxHEIGHT with each an integer in [1, 65536] (e.g. "
       "1920x1080), got '0x10'\n"},
      {"--direct LTC",
       "error: kozu render: --direct: expected one of sample, ltc, ltc-ratio, ltc-preview, got 'LTC'\n"},
  };
  for (const Case& c : cases) {
    std::string out;
    EXPECT_EQ(run_command(fmt::format("{} render '{}' {} -o '{}'", kozu(), scene.string(), c.flags, x.string()), &out), 1)
        << c.flags;
    EXPECT_EQ(out, c.message) << c.flags;
  }
  EXPECT_FALSE(std::filesystem::exists(x));
  // The scene gives the same messages for the same values.
  const auto bad = dir.write("bad.json", R"({"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0]},
    "render": {"max_depth": 100000}, "shapes": []})");
  std::string out;
  EXPECT_EQ(run_command(fmt::format("{} render '{}' -o '{}'", kozu(), bad.string(), x.string()), &out), 1);
  EXPECT_EQ(out, fmt::format("error: {}: /render/max_depth: expected an integer in [0, 1024], got 100000\n",
                             bad.string()));
}

// "--spp 010" was read as octal (8 samples); it is decimal, as in a scene.
TEST(CliFlags, LeadingZerosAreDecimal) {
  TempDir dir;
  const auto scene = dir.write("s.json", kFurnace);
  const auto stats = dir.path() / "s.stats.json";
  std::string out;
  ASSERT_EQ(run_command(fmt::format("{} render '{}' --spp 010 --seed 007 -o '{}' --stats '{}'", kozu(),
                                    scene.string(), (dir.path() / "a.exr").string(), stats.string()),
                        &out),
            0)
      << out;
  const nlohmann::json j = read_json(stats);
  EXPECT_EQ(j["spp"].get<double>(), 10.0);
  EXPECT_EQ(j["seed"].get<uint64_t>(), 7u);
}

// --threads 10000000 crashed inside TBB; counts above 4 × the cores are lowered with a warning and the stats
// report the threads really used.
TEST(CliFlags, ThreadsAreBoundedAndReportedAsUsed) {
  TempDir dir;
  const auto scene = dir.write("s.json", kFurnace);
  const auto stats = dir.path() / "s.stats.json";
  std::string out;
  ASSERT_EQ(run_command(fmt::format("{} render '{}' --spp 1 --threads 10000000 -o '{}' --stats '{}'", kozu(),
                                    scene.string(), (dir.path() / "a.exr").string(), stats.string()),
                        &out),
            0)
      << out;
  const int max_threads = max_render_threads();
  EXPECT_NE(out.find(fmt::format("warning: --threads 10000000: using {}", max_threads)), std::string::npos) << out;
  EXPECT_EQ(read_json(stats)["threads"].get<int>(), max_threads);
}

// ---- outputs are checked before any work -------------------------------------------------------------------

TEST(CliOutputs, CheckedBeforeRendering) {
  TempDir dir;
  const auto scene = dir.write("s.json", kFurnace);
  const std::string scene_text = kFurnace;
  std::filesystem::create_directories(dir.path() / "folder");
  dir.write("file", "x");
  struct Case {
    std::string args, message;
  };
  const std::string d = dir.path().string();
  const std::vector<Case> cases = {
      // --stats equal to the scene overwrote the scene.
      {fmt::format("-o '{}/a.exr' --stats '{}'", d, scene.string()),
       fmt::format("error: --stats {}: would overwrite {}, an input of the render\n", scene.string(), scene.string())},
      {fmt::format("-o '{}/a.exr' -o '{}/./a.exr'", d, d),
       fmt::format("error: -o {}/./a.exr: the same file as -o {}/a.exr; every output needs its own file\n", d, d)},
      {fmt::format("-o '{}/folder'", d), ""},  // unsupported format (no extension) comes first
      {fmt::format("-o '{}/file/x.exr'", d), ""},
      {"-o /proc/kozu-test.exr", ""},
  };
  std::filesystem::create_directories(dir.path() / "folder.exr");
  for (const Case& c : cases) {
    std::string out;
    EXPECT_EQ(run_command(fmt::format("{} render '{}' {}", kozu(), scene.string(), c.args), &out), 1) << c.args;
    if (!c.message.empty()) {
      EXPECT_EQ(out, c.message) << c.args;
    }
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  }
  // Nothing was rendered or written, and the scene is intact.
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "a.exr"));
  std::ifstream in(scene);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), scene_text);
  std::string out;
  EXPECT_EQ(run_command(fmt::format("{} render '{}' -o '{}/folder.exr'", kozu(), scene.string(), d), &out), 1);
  EXPECT_EQ(out, fmt::format("error: -o {}/folder.exr: is a folder, not a file\n", d));
  EXPECT_EQ(run_command(fmt::format("{} render '{}' -o '{}/file/x.exr'", kozu(), scene.string(), d), &out), 1);
  EXPECT_NE(out.find("cannot create the folder"), std::string::npos) << out;
}

// A disk that fills up during the write: the output that did not fit is reported with the system's reason, the
// other outputs are still written and named, no temporary file is left, and the exit status is 1. The full disk is
// a 64 KiB tmpfs, which needs the right to mount (root in a container that allows it); otherwise skipped.
TEST(CliOutputs, AFullDiskLosesOnlyTheOutputThatDidNotFit) {
  TempDir dir;
  const auto full = dir.path() / "full", ok = dir.path() / "ok";
  std::filesystem::create_directories(full);
  std::string out;
  if (run_command(fmt::format("mount -t tmpfs -o size=64k tmpfs '{}'", full.string()), &out) != 0)
    GTEST_SKIP() << "cannot mount a tmpfs here: " << out;
  const auto exr = full / "a.exr", png = ok / "b.png", stats = ok / "s.json";
  const int code = run_command(fmt::format("{} render --demo --spp 1 --resolution 256x256 -o '{}' -o '{}' --stats '{}'",
                                           kozu(), exr.string(), png.string(), stats.string()),
                               &out);
  const int files_left = temp_files(full);
  const bool exr_written = std::filesystem::exists(exr);
  run_command(fmt::format("umount '{}'", full.string()), nullptr);
  EXPECT_EQ(code, 1) << out;
  EXPECT_FALSE(exr_written);
  EXPECT_EQ(files_left, 0);
  EXPECT_NE(out.find(fmt::format("error: {}: cannot write image", exr.string())), std::string::npos) << out;
  EXPECT_NE(out.find("(no space left on device: "), std::string::npos) << out;
  EXPECT_NE(out.find(fmt::format("error: 1 output failed; written: {}", png.string())), std::string::npos) << out;
  EXPECT_EQ(read_image(png).width, 256);
  EXPECT_EQ(read_json(stats)["outputs"], nlohmann::json::array({png.string()}));
}

// --resolution 20000x20000 (which the docs allow) ended in an uncaught std::bad_alloc; the need is estimated
// first and compared with the memory limit: here KOZU_MEMORY_LIMIT (as a render farm would set it) and, where
// the build has no sanitizer (whose shadow memory needs terabytes of address space), a 4 GiB RLIMIT_AS.
TEST(CliMemory, RenderTooLargeForTheMemoryLimitIsRefused) {
  TempDir dir;
  std::string out;
  const auto x = dir.path() / "x.exr";
  EXPECT_EQ(run_command(fmt::format("KOZU_MEMORY_LIMIT=4G {} render --demo --resolution 20000x20000 -o '{}'", kozu(),
                                    x.string()),
                        &out),
            1)
      << out;
  EXPECT_NE(out.find("error: <demo>: a 20000x20000 render needs about"), std::string::npos) << out;
  EXPECT_NE(out.find("of the 4.0 GiB limit (KOZU_MEMORY_LIMIT) is left; lower the resolution"), std::string::npos)
      << out;
  // A render that fits still runs under the same limit.
  EXPECT_EQ(run_command(fmt::format("KOZU_MEMORY_LIMIT=4G {} render --demo --spp 1 --resolution 64x36 -q -o '{}'",
                                    kozu(), x.string()),
                        &out),
            0)
      << out;
  if (!kSanitized) {
    EXPECT_EQ(run_command(fmt::format("ulimit -v 4194304; {} render --demo --resolution 20000x20000 -o '{}'", kozu(),
                                      (dir.path() / "y.exr").string()),
                          &out),
              1)
        << out;
    EXPECT_NE(out.find("(RLIMIT_AS)"), std::string::npos) << out;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "y.exr"));
}

TEST(MemoryLimit, ByteCounts) {
  EXPECT_EQ(parse_byte_count("4096"), 4096u);
  EXPECT_EQ(parse_byte_count("4G"), size_t{4} << 30);
  EXPECT_EQ(parse_byte_count("512MiB"), size_t{512} << 20);
  EXPECT_EQ(parse_byte_count("2t"), size_t{2} << 40);
  for (const char* bad : {"", "G", "4X", "-1", "1.5G", "4GG", "99999999999999999999"}) EXPECT_EQ(parse_byte_count(bad), 0u) << bad;
}

}  // namespace
}  // namespace kozu::test
