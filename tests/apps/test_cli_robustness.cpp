// `kozu render` against hostile input, run as a process: flags are validated by the rules of their scene keys,
// outputs are checked before any work, absurd sizes are refused before any allocation, and non-finite time limits
// are rejected. Each test is the regression case of a defect found by a round of hostile input. The deadline and
// stop-signal tests, which wait on the clock, are in test_cli_timing.cpp.
#include "apps/cli_helpers.h"

#include "core/file_io.h"
#include "core/memory.h"
#include "io/image_io.h"
#include "render/renderer.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/stat.h>
#include <sys/sysmacros.h>

#include <cerrno>
#include <chrono>
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
  ASSERT_EQ(
      run_command(fmt::format("{} render '{}' --time-limit 1e10 --spp 2 -o '{}'", kozu(), scene.string(), exr.string()),
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
    EXPECT_EQ(run_command(fmt::format("{} render '{}' {} -o '{}'", kozu(), scene.string(), c.flags, x.string()), &out),
              1)
        << c.flags;
    EXPECT_EQ(out, c.message) << c.flags;
  }
  EXPECT_FALSE(std::filesystem::exists(x));
  // The scene gives the same messages for the same values.
  const auto bad = dir.write("bad.json", R"({"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0]},
    "render": {"max_depth": 100000}, "shapes": []})");
  std::string out;
  EXPECT_EQ(run_command(fmt::format("{} render '{}' -o '{}'", kozu(), bad.string(), x.string()), &out), 1);
  EXPECT_EQ(out,
            fmt::format("error: {}: /render/max_depth: expected an integer in [0, 1024], got 100000\n", bad.string()));
}

// "--spp 010" was read as octal (8 samples); it is decimal, as in a scene.
TEST(CliFlags, LeadingZerosAreDecimal) {
  TempDir dir;
  const auto scene = dir.write("s.json", kFurnace);
  const auto stats = dir.path() / "s.stats.json";
  std::string out;
  ASSERT_EQ(run_command(fmt::format("{} render '{}' --spp 010 --seed 007 -o '{}' --stats '{}'", kozu(), scene.string(),
                                    (dir.path() / "a.exr").string(), stats.string()),
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
  // The sphere studio: no texture to convert into the full disk's cache folder (.kozu-tx beside the first output).
  const int code = run_command(fmt::format("{} render {} --spp 1 --resolution 256x256 -o '{}' -o '{}' --stats '{}'",
                                           kozu(), spheres(), exr.string(), png.string(), stats.string()),
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

// ---- every output of every command: a regular file or new ------------------------------------------------------

// The node an output names before and after a command: what it is, so that a test sees it was not replaced.
std::string node_kind(const std::filesystem::path& p) {
  struct stat st {};
  if (::lstat(p.c_str(), &st) != 0) return "missing";
  if (S_ISLNK(st.st_mode)) {
    std::error_code ec;
    return "link to " + std::filesystem::read_symlink(p, ec).string();
  }
  if (S_ISFIFO(st.st_mode)) return "fifo";
  if (S_ISCHR(st.st_mode)) return "character device";
  if (S_ISDIR(st.st_mode)) return "folder";
  if (S_ISREG(st.st_mode)) return "regular file";
  return "other";
}

// Inputs the commands read: a scene, two EXR parts of one render (merge), a mesh (voxelize).
struct CommandInputs {
  std::filesystem::path scene, part_a, part_b, mesh;
};

CommandInputs make_command_inputs(const TempDir& dir, bool parts = true) {
  CommandInputs in;
  in.scene = dir.write("s.json", kFurnace);
  in.part_a = dir.path() / "part_a.exr";
  in.part_b = dir.path() / "part_b.exr";
  std::string out;
  if (parts) {
    for (const auto& [range, part] : {std::pair{"0:1", in.part_a}, std::pair{"1:2", in.part_b}}) {
      EXPECT_EQ(run_command(fmt::format("{} render '{}' -q --sample-range {} -o '{}'", kozu(), in.scene.string(), range,
                                        part.string()),
                            &out),
                0)
          << out;
    }
  }
  in.mesh = dir.write("tetra.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  return in;
}

// Every output flag of every command, as a command line writing OUT (which has the extension the flag needs).
struct OutputFlag {
  std::string name, extension;
  std::string (*command)(const CommandInputs&, const std::filesystem::path& dir, const std::string& out);
};

const std::vector<OutputFlag>& output_flags() {
  static const std::vector<OutputFlag> flags = {
      {"render -o", ".exr",
       [](const CommandInputs& in, const std::filesystem::path&, const std::string& out) {
         return fmt::format("render '{}' -q --spp 1 -o '{}'", in.scene.string(), out);
       }},
      {"render --stats", ".json",
       [](const CommandInputs& in, const std::filesystem::path& dir, const std::string& out) {
         return fmt::format("render '{}' -q --spp 1 -o '{}/r1.exr' --stats '{}'", in.scene.string(), dir.string(), out);
       }},
      {"render --checkpoint", ".ckpt",
       [](const CommandInputs& in, const std::filesystem::path& dir, const std::string& out) {
         return fmt::format("render '{}' -q --spp 1 -o '{}/r2.exr' --checkpoint '{}'", in.scene.string(), dir.string(),
                            out);
       }},
      {"merge -o", ".exr",
       [](const CommandInputs& in, const std::filesystem::path&, const std::string& out) {
         return fmt::format("merge '{}' '{}' -o '{}'", in.part_a.string(), in.part_b.string(), out);
       }},
      {"maketx -o", ".tx",
       [](const CommandInputs& in, const std::filesystem::path&, const std::string& out) {
         return fmt::format("maketx '{}' -o '{}'", in.part_a.string(), out);
       }},
      {"fit-ltc -o", ".json",
       [](const CommandInputs&, const std::filesystem::path&, const std::string& out) {
         return fmt::format("fit-ltc --size 2 --threads 1 -o '{}'", out);
       }},
      {"precompute -o", ".inc",
       [](const CommandInputs&, const std::filesystem::path&, const std::string& out) {
         return fmt::format("precompute microfacet-albedo --grid 4 -o '{}'", out);
       }},
      {"procedural -o", ".kvox",
       [](const CommandInputs&, const std::filesystem::path&, const std::string& out) {
         return fmt::format("procedural smoke --resolution 8 -o '{}'", out);
       }},
      {"voxelize -o", ".kvox",
       [](const CommandInputs& in, const std::filesystem::path&, const std::string& out) {
         return fmt::format("voxelize '{}' --resolution 4 -o '{}'", in.mesh.string(), out);
       }},
      {"sss-reference -o", ".csv",
       [](const CommandInputs&, const std::filesystem::path&, const std::string& out) {
         return fmt::format("sss-reference --albedo 0.5 --photons 10 -o '{}'", out);
       }},
      {"sss-reference --json", ".json",
       [](const CommandInputs&, const std::filesystem::path&, const std::string& out) {
         return fmt::format("sss-reference --table --photons 1 --json '{}'", out);
       }},
  };
  return flags;
}

// A FIFO, a device node or a symbolic link to one given as any output was replaced by a regular file (as root,
// `--stats /dev/null` turned the device into a file). Each is refused with one line, exit status 1, before any
// work, and is still what it was; no temporary file is left. The device is a copy of /dev/null made in the test's
// folder (where mknod is allowed), so that no failure of this test can replace the system's.
TEST(CliOutputs, SpecialFilesAreNeverReplaced) {
  TempDir dir;
  const CommandInputs in = make_command_inputs(dir);
  const auto work = dir.path() / "work";
  std::filesystem::create_directories(work);
  for (const OutputFlag& flag : output_flags()) {
    struct Target {
      std::string name, reason;
    };
    // Every flag gets a FIFO and a link to /dev/null; three flags (the render's, a tool's, merge's) every other
    // kind too, to keep the test short: they all go through the same check.
    const std::string ext = flag.extension;
    const bool all_kinds = flag.name == "render --stats" || flag.name == "fit-ltc -o" || flag.name == "merge -o";
    std::vector<Target> targets;
    std::error_code ec;
    if (::mkfifo((work / ("fifo" + ext)).c_str(), 0600) == 0 || errno == EEXIST)
      targets.push_back({"fifo" + ext, "is a FIFO, not a regular file"});
    std::filesystem::create_symlink("/dev/null", work / ("devnull" + ext), ec);
    if (!ec) targets.push_back({"devnull" + ext, "is a symbolic link to a character device, not a regular file"});
    if (all_kinds) {
      if (::mknod((work / ("null" + ext)).c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0)  // needs root (CAP_MKNOD)
        targets.push_back({"null" + ext, "is a character device, not a regular file"});
      std::filesystem::create_symlink("/dev/full", work / ("devfull" + ext), ec);
      if (!ec) targets.push_back({"devfull" + ext, "is a symbolic link to a character device"});
      std::filesystem::create_symlink("fifo" + ext, work / ("fifolink" + ext), ec);
      if (!ec) targets.push_back({"fifolink" + ext, "is a symbolic link to a FIFO"});
      std::filesystem::create_directories(work / ("folder" + ext), ec);
      if (!ec) targets.push_back({"folder" + ext, "is a folder, not a file"});
    }
    for (const Target& t : targets) {
      const auto target = work / t.name;
      const std::string before = node_kind(target);
      std::string out;
      const int code =
          run_command(fmt::format("timeout 60 {} {}", kozu(), flag.command(in, work, target.string())), &out);
      const std::string what = fmt::format("{} {}", flag.name, t.name);
      EXPECT_EQ(code, 1) << what << "\n" << out;
      EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << what << "\n" << out;
      EXPECT_TRUE(out.starts_with("error: ")) << what << "\n" << out;
      EXPECT_NE(out.find(t.reason), std::string::npos) << what << "\n" << out;
      EXPECT_EQ(node_kind(target), before) << what;
    }
    EXPECT_EQ(temp_files(work), 0) << flag.name;
  }
  // None of the commands wrote its other outputs either (checked before the work).
  EXPECT_FALSE(std::filesystem::exists(work / "r1.exr"));
  EXPECT_FALSE(std::filesystem::exists(work / "r2.exr"));
}

// The final rename refuses a special file too: a FIFO made between the check of the outputs and the write (here
// simulated by calling the writer directly) is not replaced.
TEST(CliOutputs, TheWriterDoesNotRenameOverASpecialFile) {
  TempDir dir;
  const auto fifo = dir.path() / "late.json";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  try {
    write_file_atomic(fifo, "{}\n");
    ADD_FAILURE() << "the FIFO was replaced";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), fifo.string() + ": is a FIFO, not a regular file; not replaced");
  }
  EXPECT_EQ(node_kind(fifo), "fifo");
  EXPECT_EQ(temp_files(dir.path()), 0);
  // A link to a regular file is still replaced by the new file (the old one is left as it was).
  const auto file = dir.write("old.json", "old");
  std::filesystem::create_symlink(file, dir.path() / "link.json");
  write_file_atomic(dir.path() / "link.json", "new");
  EXPECT_EQ(node_kind(dir.path() / "link.json"), "regular file");
  EXPECT_EQ(node_kind(file), "regular file");
}

// `fit-ltc -o /proc/t.json` failed only after the fit (minutes at --size 256); every tool command checks its output
// before its work. Each command below would run for minutes (or allocate gigabytes) if it started.
TEST(CliOutputs, ToolOutputsAreCheckedBeforeTheWork) {
  TempDir dir;
  const CommandInputs in = make_command_inputs(dir, false);
  const std::vector<std::string> commands = {
      "fit-ltc --size 256 -o /proc/t.json",
      "precompute microfacet-albedo --grid 4096 -o /proc/t.inc",
      "procedural fabric --resolution 1024 -o /proc/t.kvox",
      fmt::format("voxelize '{}' --resolution 1024 -o /proc/t.kvox", in.mesh.string()),
      "sss-reference --albedo 0.9 --photons 1e12 -o /proc/t.csv",
      "sss-reference --table --photons 1e12 --json /proc/t.json",
      // The tools write into a folder that exists (a render creates its own).
      fmt::format("fit-ltc --size 256 -o '{}/no/such/folder/t.json'", dir.path().string()),
  };
  for (const std::string& c : commands) {
    std::string out;
    const auto start = std::chrono::steady_clock::now();
    EXPECT_EQ(run_command(fmt::format("timeout 30 {} {}", kozu(), c), &out), 1) << c << "\n" << out;
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10.0) << c;
    EXPECT_TRUE(out.starts_with("error: kozu ")) << c << "\n" << out;
    EXPECT_NE(out.find("cannot be written"), std::string::npos) << c << "\n" << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << c << "\n" << out;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "no"));
  // voxelize -o may not overwrite its mesh (here named .kvox to pass the extension check).
  const auto mesh_kvox = dir.path() / "m.kvox";
  std::filesystem::copy_file(in.mesh, mesh_kvox);
  std::string out;
  EXPECT_EQ(run_command(fmt::format("{} voxelize '{}' -o '{}'", kozu(), mesh_kvox.string(), mesh_kvox.string()), &out),
            1);
  EXPECT_NE(out.find(fmt::format("would overwrite {}", mesh_kvox.string())), std::string::npos) << out;
}

// fit-ltc, voxelize, procedural, precompute and sss-reference exited 2 (CLI11's usage error) for a bad value; a bad
// value is exit status 1 with one line naming the command and the flag, by the rules `kozu render` applies to its
// own flags. Usage errors (an unknown option, a missing argument) stay 2.
TEST(CliFlags, ToolValuesAreBadInputNotUsageErrors) {
  TempDir dir;
  const CommandInputs in = make_command_inputs(dir, false);
  const std::string d = dir.path().string(), mesh = in.mesh.string();
  struct Case {
    std::string args, message;
  };
  const std::vector<Case> cases = {
      {"fit-ltc --size 1 -o " + d + "/t.json", "error: kozu fit-ltc: --size: expected an integer in [2, 256], got 1\n"},
      {"fit-ltc --size 0x10 -o " + d + "/t.json",
       "error: kozu fit-ltc: --size: expected an integer in [2, 256], got the string \"0x10\"\n"},
      {"fit-ltc --size 8 --threads -1 -o " + d + "/t.json",
       "error: kozu fit-ltc: --threads: expected an integer in [0, 1024], got -1\n"},
      {"fit-ltc --brdf gxx -o " + d + "/t.json",
       "error: kozu fit-ltc: --brdf: expected one of ggx, beckmann, ggx-compensated, beckmann-compensated, "
       "ggx-specular, beckmann-specular, got 'gxx' (did you mean 'ggx'?)\n"},
      {"voxelize '" + mesh + "' --resolution 2 -o " + d + "/t.kvox",
       "error: kozu voxelize: --resolution: expected an integer in [4, 1024], got 2\n"},
      {"voxelize '" + mesh + "' --resolution 8.5 -o " + d + "/t.kvox",
       "error: kozu voxelize: --resolution: expected an integer in [4, 1024], got 8.5\n"},
      {"procedural smoke --resolution 7 -o " + d + "/t.kvox",
       "error: kozu procedural: --resolution: expected an integer in [8, 1024], got 7\n"},
      {"procedural carpet -o " + d + "/t.kvox",
       "error: kozu procedural: the volume: expected one of smoke, yarn, fabric, got 'carpet'\n"},
      {"precompute microfacet-albedo --grid 3 -o " + d + "/t.inc",
       "error: kozu precompute: --grid: expected an integer in [4, 4096], got 3\n"},
      {"sss-reference --albedo x", "error: kozu sss-reference: --albedo: expected a number, got the string \"x\"\n"},
      {"sss-reference --albedo 0.5 --bins 0",
       "error: kozu sss-reference: --bins: expected an integer in [1, 100000], got 0\n"},
      {"sss-reference --albedo 0.5 --seed -1",
       "error: kozu sss-reference: --seed: expected an integer in [0, 18446744073709551615], got -1\n"},
      {"sss-reference --albedo 0.5 --mfp 0", "error: kozu sss-reference: --mfp: expected a number > 0, got 0\n"},
      {"sss-reference --table --json " + d + "/t.json --rmax-scan 1,x",
       "error: kozu sss-reference: --rmax-scan: expected a number, got the string \"x\"\n"},
  };
  for (const Case& c : cases) {
    std::string out;
    EXPECT_EQ(run_command(fmt::format("{} {}", kozu(), c.args), &out), 1) << c.args << "\n" << out;
    EXPECT_EQ(out, c.message) << c.args;
  }
  for (const char* usage : {"fit-ltc --sise 8 -o t.json", "fit-ltc --size", "fit-ltc --size 8", "voxelize -o t.kvox",
                            "procedural smoke", "precompute microfacet-albedo --grid 8", "sss-reference --albedo"}) {
    std::string out;
    EXPECT_EQ(run_command(fmt::format("cd '{}' && {} {}", d, kozu(), usage), &out), 2) << usage << "\n" << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << usage << "\n" << out;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "t.json"));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "t.kvox"));
}

// ---- messages: kozu's own words, never a library's --------------------------------------------------------

// Library texts reached the user: "[json.exception.out_of_range.404] unresolved reference token" for a -D index
// beyond size_t, "[json.exception.type_error.316] invalid UTF-8 byte" for a value that is not UTF-8 (quoted in the
// message with nlohmann's dump). Each is one line of kozu's, naming the file or flag, exit status 1.
TEST(CliMessages, NoLibraryTextReachesTheUser) {
  TempDir dir;
  const auto scene = dir.write("s.json", kFurnace);
  const std::string render =
      fmt::format("{} render '{}' -q -o '{}/x.exr'", kozu(), scene.string(), dir.path().string());
  const std::string ff = "\"$(printf '\\377')\"";  // the byte 0xFF, not UTF-8
  const std::vector<std::pair<std::string, std::string>> cases = {
      {render + " -D /shapes/99999999999999999999/radius=2",
       fmt::format("error: {}: /shapes/99999999999999999999: no such object or array in the scene", scene.string())},
      {render + " -D /materials/m/albedo=" + ff, fmt::format("error: {}: /materials/m/albedo: ", scene.string())},
      {render + " --spp " + ff, "error: kozu render: --spp: expected an integer"},
      {fmt::format("{} sss-reference --albedo {}", kozu(), ff),
       "error: kozu sss-reference: --albedo: expected a number"},
      {fmt::format("{} fit-ltc --size {} -o '{}/t.json'", kozu(), ff, dir.path().string()),
       "error: kozu fit-ltc: --size: expected an integer"},
  };
  for (const auto& [command, start] : cases) {
    std::string out;
    EXPECT_EQ(run_command(command, &out), 1) << command << "\n" << out;
    EXPECT_TRUE(out.starts_with(start)) << command << "\n" << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << command << "\n" << out;
    for (const char* library : {"json.exception", "_M_range_check", "bad_alloc", "terminate called", "what():"})
      EXPECT_EQ(out.find(library), std::string::npos) << command << "\n" << out;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "x.exr"));
}

TEST(MemoryLimit, ByteCounts) {
  EXPECT_EQ(parse_byte_count("4096"), 4096u);
  EXPECT_EQ(parse_byte_count("4G"), size_t{4} << 30);
  EXPECT_EQ(parse_byte_count("512MiB"), size_t{512} << 20);
  EXPECT_EQ(parse_byte_count("2t"), size_t{2} << 40);
  for (const char* bad : {"", "G", "4X", "-1", "1.5G", "4GG", "99999999999999999999"})
    EXPECT_EQ(parse_byte_count(bad), 0u) << bad;
}

}  // namespace
}  // namespace kozu::test
