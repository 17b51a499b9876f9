// The kozu command line, run as a process: exit codes, messages, outputs, statistics. The tests that wait on the
// clock (time limits, signals) are in test_cli_timing.cpp.
#include "core/file_io.h"
#include "support/render_test.h"

#include "io/gltf_test_files.h"
#include "io/image_io.h"
#include "media/voxel_grid.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

namespace kozu::test {
namespace {

std::string kozu() { return fmt::format("'{}'", kozu_binary().string()); }

void write_text(const std::filesystem::path& p, const std::string& s) { std::ofstream(p) << s; }

const char* kSmallScene = R"({
  "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 35, "resolution": [32, 24]},
  "render": {"spp": 4},
  "materials": {"m": {"type": "diffuse", "albedo": 1}},
  "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}],
  "lights": [{"type": "environment", "radiance": 1}] })";

TEST(Cli, VersionAndHelp) {
  std::string out;
  EXPECT_EQ(run_command(kozu() + " --version", &out), 0);
  EXPECT_NE(out.find("kozu 0."), std::string::npos) << out;
  EXPECT_EQ(run_command(kozu() + " render --help", &out), 0);
  for (const char* flag :
       {"--spp", "--time-limit", "--threads", "--seed", "--resolution", "--stats", "--quiet", "--demo", "-o"})
    EXPECT_NE(out.find(flag), std::string::npos) << flag << "\n" << out;
}

TEST(Cli, WritesExrPngAndStats) {
  TempDir dir;
  write_text(dir.path() / "s.json", kSmallScene);
  const auto exr = dir.path() / "a.exr", png = dir.path() / "a.png", stats = dir.path() / "stats.json";
  std::string out;
  const int code =
      run_command(fmt::format("{} render '{}' -o '{}' -o '{}' --stats '{}' --spp 8 --threads 2 --seed 3 "
                              "--resolution 20x10",
                              kozu(), (dir.path() / "s.json").string(), exr.string(), png.string(), stats.string()),
                  &out);
  ASSERT_EQ(code, 0) << out;
  // Not a terminal: a one-line summary, no progress bar.
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  EXPECT_EQ(out.find('\r'), std::string::npos);
  const Image e = read_image(exr), p = read_image(png);
  EXPECT_EQ(e.width, 20);
  EXPECT_EQ(e.height, 10);
  EXPECT_EQ(p.width, 20);
  // The furnace sphere is 1 everywhere in the linear EXR.
  for (float v : e.data) EXPECT_NEAR(v, 1.0f, 1e-4f);
  std::ifstream in(stats);
  const nlohmann::json j = nlohmann::json::parse(in);
  for (const char* key :
       {"spp", "render_seconds", "load_seconds", "paths_per_second", "rays_traced", "nan_pixels", "threads"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["spp"].get<double>(), 8.0);
  EXPECT_EQ(j["threads"].get<int>(), 2);
  EXPECT_EQ(j["nan_pixels"].get<int>(), 0);
  EXPECT_EQ(j["paths"].get<uint64_t>(), 20u * 10u * 8u);
  EXPECT_GT(j["rays_traced"].get<uint64_t>(), j["paths"].get<uint64_t>());
  EXPECT_EQ(j["tentative_collisions"].get<uint64_t>(), 0u);  // no medium
  // No temporary files left behind.
  int files = 0;
  for (const auto& f : std::filesystem::directory_iterator(dir.path())) files += f.is_regular_file();
  EXPECT_EQ(files, 4);
}

// "guiding": "on": the training passes are the image's first samples (every pixel still takes exactly --spp), their
// figures are in --stats, and the furnace's expectation is unchanged (no longer noiseless: the mixture's density is
// not the cosine's). A misspelt value names its JSON path.
TEST(Cli, GuidingReportsItsTraining) {
  TempDir dir;
  write_text(dir.path() / "s.json", kSmallScene);
  const auto exr = dir.path() / "a.exr", stats = dir.path() / "stats.json";
  std::string out;
  ASSERT_EQ(run_command(fmt::format("{} render '{}' -q -o '{}' --stats '{}' --spp 16 --threads 2 --resolution 20x10 "
                                    "-D /render/guiding=on",
                                    kozu(), (dir.path() / "s.json").string(), exr.string(), stats.string()),
                        &out),
            0)
      << out;
  std::ifstream in(stats);
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_TRUE(j.contains("guiding")) << j.dump();
  EXPECT_TRUE(j["guiding"]["in_image"].get<bool>());
  EXPECT_EQ(j["guiding"]["passes"].get<int>(), 3);  // 1, 2, 4: then 16 - 7 < 2 × 8
  EXPECT_EQ(j["guiding"]["samples"].get<int>(), 7);
  EXPECT_GE(j["guiding"]["leaves"].get<int>(), 1);
  EXPECT_EQ(j["paths"].get<uint64_t>(), 20u * 10u * 16u);
  const Image e = read_image(exr);
  double sum = 0.0;
  for (float v : e.data) sum += v;
  EXPECT_NEAR(sum / double(e.data.size()), 1.0, 0.02);

  EXPECT_NE(run_command(fmt::format("{} render '{}' -q -o '{}' --spp 1 -D /render/guiding=maybe", kozu(),
                                    (dir.path() / "s.json").string(), exr.string()),
                        &out),
            0);
  EXPECT_NE(out.find("/render/guiding"), std::string::npos) << out;
}

TEST(Cli, StatsReportMediaLevelAndMemory) {
  // A 32³ SGGX grid over [-1, 1]³ seen from 6 units at 16x16 with fov 40: footprint 6 · 2 tan(20°) / 16 = 0.27
  // = 4.4 voxels of 1/16, so level round(log2 4.4) = 2.
  TempDir dir;
  VoxelGrid g(Vec3i(32), Vec3(-1.0f), Vec3(1.0f), true);
  for (float& d : g.density_data()) d = 2.0f;
  g.save_kvox(dir.path() / "v.kvox");
  write_text(dir.path() / "s.json", R"({"camera": {"position": [0, 0, 6], "look_at": [0, 0, 0], "fov": 40},
    "media": {"vol": {"type": "sggx", "file": "v.kvox"}},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 0.9, "interior": "vol"}],
    "lights": [{"type": "environment", "radiance": 1}]})");
  const auto stats = dir.path() / "stats.json";
  std::string out;
  const int code =
      run_command(fmt::format("{} render '{}' -o '{}' --stats '{}' --spp 2 --resolution 16x16", kozu(),
                              (dir.path() / "s.json").string(), (dir.path() / "a.exr").string(), stats.string()),
                  &out);
  ASSERT_EQ(code, 0) << out;
  std::ifstream in(stats);
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_TRUE(j["media"].contains("vol")) << j.dump();
  EXPECT_EQ(j["media"]["vol"]["lod"].get<int>(), 2);
  EXPECT_EQ(j["media"]["vol"]["lod_mode"].get<std::string>(), "auto");
  // The chain in compact storage (8 bytes per voxel at every level, "storage" defaults to "compact"): more than
  // the compact base, less than the float base alone; the majorant grids apart.
  VoxelGrid compact = g;
  compact.compact();
  EXPECT_GT(j["media"]["vol"]["voxel_bytes"].get<size_t>(), compact.memory_bytes());
  EXPECT_LT(j["media"]["vol"]["voxel_bytes"].get<size_t>(), g.memory_bytes());
  EXPECT_GT(j["media"]["vol"]["majorant_bytes"].get<size_t>(), 0u);
  // The work of tracking: the per-path figure is the total over the paths.
  const double per_path = j["tentative_collisions_per_path"].get<double>();
  EXPECT_GT(per_path, 0.1);  // most pixels miss the sphere; the ones through it track
  EXPECT_NEAR(per_path, double(j["tentative_collisions"].get<uint64_t>()) / double(j["paths"].get<uint64_t>()),
              1e-9 * per_path);
}

TEST(Cli, BadSceneExitsWithOneMessageAndNoOutput) {
  TempDir dir;
  write_text(dir.path() / "bad.json", R"({"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0]},
    "materials": {"g": {"type": "dielectric", "ior": 0}}, "shapes": []})");
  const auto exr = dir.path() / "out.exr";
  std::string out;
  const int code = run_command(
      fmt::format("{} render '{}' -o '{}'", kozu(), (dir.path() / "bad.json").string(), exr.string()), &out);
  EXPECT_EQ(code, 1);
  EXPECT_EQ(out, fmt::format("error: {}: /materials/g/ior: expected a number > 0, got 0\n",
                             (dir.path() / "bad.json").string()));
  EXPECT_FALSE(std::filesystem::exists(exr));
}

// -D PATH=VALUE sets a scene key before the scene is read (before or after the scene's name); a bad one is the
// file's message with the override named, exit status 1 and no image.
TEST(Cli, DefineOverridesSceneKeys) {
  TempDir dir;
  const auto scene = dir.path() / "s.json", exr = dir.path() / "a.exr";
  write_text(scene, kSmallScene);
  std::string out;
  ASSERT_EQ(run_command(fmt::format("{} render -D /camera/resolution=[12,6] '{}' -D /render/spp=1 -q -o '{}'", kozu(),
                                    scene.string(), exr.string()),
                        &out),
            0)
      << out;
  const Image e = read_image(exr);
  EXPECT_EQ(e.width, 12);
  EXPECT_EQ(e.height, 6);
  std::filesystem::remove(exr);
  EXPECT_EQ(run_command(fmt::format("{} render '{}' -D /materials/m/type=conductor -q -o '{}'", kozu(), scene.string(),
                                    exr.string()),
                        &out),
            1);
  EXPECT_EQ(out, fmt::format("error: {}: /materials/m/albedo: unknown key 'albedo' (set by -D "
                             "/materials/m/type=conductor)\n",
                             scene.string()));
  EXPECT_EQ(
      run_command(fmt::format("{} render '{}' -D camera/fov=3 -q -o '{}'", kozu(), scene.string(), exr.string()), &out),
      1);
  EXPECT_NE(out.find("-D 'camera/fov=3': expected PATH=VALUE"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(exr));
}

// A scene without a light renders black: a warning on stderr and under "warnings" in --stats (empty otherwise).
TEST(Cli, WarnsOfASceneWithoutLight) {
  TempDir dir;
  std::string dark = kSmallScene;
  dark.replace(dark.find(R"("lights")"), std::string::npos, R"("lights": [] })");
  for (const bool lit : {true, false}) {
    const auto scene = dir.path() / "s.json", stats = dir.path() / "s.stats.json";
    write_text(scene, lit ? kSmallScene : dark);
    std::string out;
    ASSERT_EQ(run_command(fmt::format("{} render '{}' --spp 1 -q -o '{}' --stats '{}'", kozu(), scene.string(),
                                      (dir.path() / "a.exr").string(), stats.string()),
                          &out),
              0)
        << out;
    std::ifstream in(stats);
    const nlohmann::json j = nlohmann::json::parse(in);
    if (lit) {
      EXPECT_EQ(out, "");
      EXPECT_TRUE(j["warnings"].empty()) << j["warnings"];
    } else {
      const std::string w = fmt::format(
          "{}: the scene has no light, so the image is black: add a light, an "
          "emissive shape or an environment",
          scene.string());
      EXPECT_EQ(out, "warning: " + w + "\n");
      ASSERT_EQ(j["warnings"].size(), 1u);
      EXPECT_EQ(j["warnings"][0], w);
    }
  }
}

// Usage errors are one line of kozu's own with exit status 2: an unknown command or option names itself and the
// closest valid one.
TEST(Cli, UnknownCommandsAndOptionsNameTheClosest) {
  std::string out;
  EXPECT_EQ(run_command(kozu() + " renderr scene.json", &out), 2);
  EXPECT_EQ(out.rfind("error: unknown command 'renderr' (did you mean 'render'?); the commands: render, ", 0), 0u)
      << out;
  EXPECT_EQ(run_command(kozu() + " render --sppp 4 --demo", &out), 2);
  EXPECT_EQ(out, "error: kozu render: unknown option '--sppp' (did you mean '--spp'?) (kozu render --help)\n");
  EXPECT_EQ(run_command(kozu() + " merge --outptu x.exr a.exr", &out), 2);
  EXPECT_EQ(out, "error: kozu merge: unknown option '--outptu' (did you mean '--output'?) (kozu merge --help)\n");
  EXPECT_EQ(run_command(kozu(), &out), 2);
  EXPECT_EQ(out.rfind("error: kozu: a command is required: render, ", 0), 0u) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  // A command group's commands: the innermost command names the error, a misspelt one is named with the closest.
  EXPECT_EQ(run_command(kozu() + " texture filter-normal a.png", &out), 2);
  EXPECT_EQ(out.rfind("error: kozu texture: unknown command 'filter-normal' (did you mean 'filter-normals'?); the "
                      "commands: filter-normals, ",
                      0),
            0u)
      << out;
  EXPECT_EQ(run_command(kozu() + " texture", &out), 2);
  EXPECT_EQ(out.rfind("error: kozu texture: a command is required: filter-normals, ", 0), 0u) << out;
  EXPECT_EQ(run_command(kozu() + " texture height a.png --bogus", &out), 2);
  EXPECT_EQ(out.rfind("error: kozu texture height: unknown option '--bogus'", 0), 0u) << out;
}

// kozu maketx: an 8-bit sRGB image becomes a tiled mip-mapped linear texture; a bad output or input is one
// message and exit status 1.
TEST(Cli, MaketxWritesATiledMipMappedTexture) {
  TempDir dir;
  const auto png = dir.path() / "a.png", tx = dir.path() / "a.tx";
  write_image(png, 64, 32, std::vector<float>(64 * 32 * 3, 0.5f), ToneMap{});
  std::string out;
  ASSERT_EQ(run_command(fmt::format("{} maketx '{}' -o '{}'", kozu(), png.string(), tx.string()), &out), 0) << out;
  const ImageInfo info = probe_image(tx);
  EXPECT_EQ(info.width, 64);
  EXPECT_TRUE(info.tiled);
  EXPECT_EQ(info.mip_levels, 7);  // 64 x 32 down to 1 x 1
  EXPECT_EQ(info.bits, 16);       // decoded sRGB kept in 16-bit integers
  EXPECT_EQ(
      run_command(fmt::format("{} maketx '{}' -o '{}'", kozu(), png.string(), (dir.path() / "a.jpg").string()), &out),
      1);
  EXPECT_EQ(out, fmt::format("error: kozu maketx: {}: the output must be a .tx, .tif or .exr file\n",
                             (dir.path() / "a.jpg").string()));
  EXPECT_EQ(
      run_command(fmt::format("{} maketx '{}' -o '{}'", kozu(), (dir.path() / "none.png").string(), tx.string()), &out),
      1);
  EXPECT_EQ(out, fmt::format("error: kozu maketx: {}: image file not found\n", (dir.path() / "none.png").string()));
}

TEST(Cli, FitLtcWritesATable) {
  TempDir dir;
  const auto table = dir.path() / "ggx.json";
  std::string out;
  ASSERT_EQ(
      run_command(fmt::format("{} fit-ltc --brdf ggx --size 4 --threads 1 -o '{}'", kozu(), table.string()), &out), 0)
      << out;
  const nlohmann::json j = nlohmann::json::parse(read_input_file(table));
  EXPECT_EQ(j["size"], 4);
  EXPECT_EQ(j["entries"]["m_inv"].size(), 64u);  // 16 entries of 4 numbers
  EXPECT_EQ(j["entries"]["l1_error"].size(), 16u);
  // Entry (alpha index 3 = alpha 1, theta 0): the norm is GGX's albedo at normal incidence, 0.3069 (the tables).
  EXPECT_NEAR(j["entries"]["norm"][3 * 4 + 0].get<double>(), 0.3069, 1e-3);
  // Deterministic: the same command writes the same file.
  const std::string first = read_input_file(table);
  ASSERT_EQ(
      run_command(fmt::format("{} fit-ltc --brdf ggx --size 4 --threads 1 -o '{}'", kozu(), table.string()), &out), 0);
  EXPECT_EQ(read_input_file(table), first);
  // A bad value is bad input (exit 1), not a usage error (2).
  EXPECT_EQ(run_command(fmt::format("{} fit-ltc --size 1 -o '{}'", kozu(), table.string()), &out), 1);
}

TEST(Cli, MissingSceneFile) {
  std::string out;
  EXPECT_EQ(run_command(kozu() + " render /nonexistent/scene.json -o /tmp/kozu-never.exr", &out), 1);
  EXPECT_EQ(out, "error: /nonexistent/scene.json: cannot open file: No such file or directory\n");
  EXPECT_FALSE(std::filesystem::exists("/tmp/kozu-never.exr"));
}

TEST(Cli, UnsupportedOutputFailsBeforeRendering) {
  TempDir dir;
  write_text(dir.path() / "s.json", kSmallScene);
  std::string out;
  EXPECT_EQ(run_command(fmt::format("{} render '{}' -o '{}'", kozu(), (dir.path() / "s.json").string(),
                                    (dir.path() / "x.bmpx").string()),
                        &out),
            1);
  EXPECT_NE(out.find("unsupported output format"), std::string::npos) << out;
}

TEST(Cli, BadResolutionFlag) {
  std::string out;
  EXPECT_EQ(run_command(kozu() + " render --demo --resolution 640by480 -o /tmp/kozu-never.png", &out), 1);
  EXPECT_NE(out.find("--resolution: expected WIDTHxHEIGHT"), std::string::npos) << out;
}

// With both limits, whichever comes first ends the render: here the sample cap.
TEST(Cli, SppCapWithTimeLimit) {
  TempDir dir;
  write_text(dir.path() / "s.json", kSmallScene);
  const auto stats = dir.path() / "t.json";
  std::string out;
  ASSERT_EQ(run_command(fmt::format("{} render '{}' -o '{}' --stats '{}' --spp 3 --time-limit 100", kozu(),
                                    (dir.path() / "s.json").string(), (dir.path() / "t.exr").string(), stats.string()),
                        &out),
            0)
      << out;
  std::ifstream in(stats);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["spp"].get<double>(), 3.0);
  EXPECT_FALSE(j["hit_time_limit"].get<bool>());
  EXPECT_LT(j["render_seconds"].get<double>(), 100.0);
}

TEST(Cli, DemoRenders) {
  TempDir dir;
  std::string out;
  ASSERT_EQ(run_command(fmt::format("{} render --demo --spp 1 --resolution 64x36 -q -o '{}'", kozu(),
                                    (dir.path() / "demo.png").string()),
                        &out),
            0)
      << out;
  EXPECT_TRUE(out.empty()) << out;  // --quiet
  EXPECT_EQ(read_image(dir.path() / "demo.png").width, 64);
}

// --print-scene: the built-in scene as written (what scenes/demo.json holds), or with -D applied; it renders nothing.
TEST(Cli, PrintSceneIsTheDemoAsJson) {
  TempDir dir;
  std::string out;
  ASSERT_EQ(run_command(fmt::format("cd '{}' && {} render --demo --print-scene 2>&1", dir.path().string(), kozu()), &out),
            0)
      << out;
  const nlohmann::json printed = nlohmann::json::parse(out);
  EXPECT_EQ(printed, nlohmann::json::parse(read_input_file(source_dir() / "scenes/demo.json")));
  EXPECT_EQ(printed["camera"]["resolution"], nlohmann::json::parse("[1920, 1080]"));
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));  // nothing rendered, no cache made
  ASSERT_EQ(run_command(fmt::format("{} render --demo --print-scene -D /camera/fov=20 2>&1", kozu()), &out), 0) << out;
  EXPECT_EQ(nlohmann::json::parse(out)["camera"]["fov"], 20);
  // A scene file is printed too; a bad override is an error naming it.
  const auto scene = dir.write("s.json", R"({"camera": {"position": [0, 0, 1], "look_at": [0, 0, 0]}})");
  ASSERT_EQ(run_command(fmt::format("{} render '{}' --print-scene 2>&1", kozu(), scene.string()), &out), 0) << out;
  EXPECT_EQ(nlohmann::json::parse(out)["camera"]["look_at"], nlohmann::json::parse("[0, 0, 0]"));
  EXPECT_EQ(run_command(fmt::format("{} render --demo --print-scene -D camera=1 2>&1", kozu()), &out), 1);
  EXPECT_NE(out.find("error:"), std::string::npos) << out;
}

// --demo-animation: the demo's camera move as numbered frames, and the ffmpeg command for the video.
TEST(Cli, DemoAnimationWritesNumberedFrames) {
  TempDir dir;
  std::string out;
  ASSERT_EQ(run_command(fmt::format("{} render --demo-animation --frames 0:1 --spp 1 --resolution 32x18 -o "
                                    "'{}/f%04d.png' 2>&1",
                                    kozu(), dir.path().string()),
                        &out),
            0)
      << out;
  EXPECT_EQ(read_image(dir.path() / "f0000.png").width, 32);
  EXPECT_EQ(read_image(dir.path() / "f0001.png").width, 32);
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "f0002.png"));
  EXPECT_NE(out.find(fmt::format("ffmpeg -framerate 24 -i '{}/f%04d.png'", dir.path().string())), std::string::npos)
      << out;
  // Frames 0 and 1 differ: the camera moves.
  EXPECT_NE(read_image(dir.path() / "f0000.png").data, read_image(dir.path() / "f0001.png").data);
  // It renders the built-in scene only.
  const auto scene = dir.write("s.json", "{}");
  EXPECT_EQ(run_command(fmt::format("{} render '{}' --demo-animation 2>&1", kozu(), scene.string()), &out), 1);
  EXPECT_NE(out.find("--demo-animation renders the built-in scene"), std::string::npos) << out;
}

// kozu render MODEL.glb: the file is the scene; without a camera or lights it gets the framing camera (the grey
// quad fills the image's centre) and the uniform sky (radiance 1 in the corners); what it leaves out is warned.
TEST(Cli, RendersAGlbDirectly) {
  TempDir dir;
  GltfBuilder b;
  const int pos = b.floats({-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0}, "VEC3");
  const int idx = b.indices({0, 1, 2, 0, 2, 3});
  b.doc["meshes"] = {{{"primitives", {{{"attributes", {{"POSITION", pos}}}, {"indices", idx}, {"material", 0}}}}}};
  b.doc["materials"] = {{{"pbrMetallicRoughness",
                          {{"baseColorFactor", {0.3, 0.3, 0.3, 1}}, {"metallicFactor", 0}, {"roughnessFactor", 1}}}}};
  b.doc["nodes"] = {{{"mesh", 0}}};
  b.doc["extensionsUsed"] = {"KHR_materials_iridescence"};
  write_text(dir.path() / "tiny.glb", b.glb());
  const auto exr = dir.path() / "tiny.exr";
  std::string out;
  const int code = run_command(fmt::format("{} render '{}' -o '{}' --spp 4 --resolution 32x18", kozu(),
                                           (dir.path() / "tiny.glb").string(), exr.string()),
                               &out);
  ASSERT_EQ(code, 0) << out;
  EXPECT_NE(out.find("warning: tiny.glb: not supported, ignored: KHR_materials_iridescence"), std::string::npos) << out;
  const Image e = read_image(exr);
  ASSERT_EQ(e.width, 32);
  ASSERT_EQ(e.height, 18);
  auto at = [&](int x, int y) { return e.data[size_t((y * e.width + x) * e.channels)]; };
  EXPECT_LT(at(16, 9), 0.9f);
  EXPECT_NEAR(at(0, 0), 1.0f, 1e-4f);
  EXPECT_NEAR(at(31, 17), 1.0f, 1e-4f);
  // A broken file: one error naming it, exit status 1, no image.
  write_text(dir.path() / "broken.glb", "glTF\x02");
  EXPECT_EQ(run_command(fmt::format("{} render '{}' -o '{}'", kozu(), (dir.path() / "broken.glb").string(),
                                    (dir.path() / "broken.exr").string()),
                        &out),
            1);
  EXPECT_NE(out.find("error: " + (dir.path() / "broken.glb").string() + ": "), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "broken.exr"));
}

}  // namespace
}  // namespace kozu::test
