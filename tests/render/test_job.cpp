// The render job in-process (render/job.h), without spawning the kozu command: a frame range writes its numbered
// files, a checkpoint is written and a resumed render equals one never stopped, the budget stops the frames with
// status 1, and an output collision is refused before the scene is loaded. The process-level behaviour (signals,
// exit codes, messages of the command) stays with tests/apps/test_cli*.cpp.
#include "render/job.h"

#include "core/process_clock.h"
#include "io/image_io.h"
#include "scene/scene.h"
#include "scene/scene_loader.h"
#include "support/render_test.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

namespace kozu {
namespace {

using test::TempDir;

// A sphere under a white sky; with `frames`, a camera that moves over them.
std::string sphere_scene(int frames, int width = 16, int height = 12) {
  const std::string animation = frames > 0 ? fmt::format(R"("animation": {{"fps": 10, "frames": {},
                   "camera": [{{"time": 0}}, {{"time": {}, "position": [2, 1, 4]}}]}},)",
                                                         frames, 0.1 * frames)
                                           : std::string();
  return fmt::format(R"({{
    "camera": {{"position": [0, 1, 4], "look_at": [0, 0.5, 0], "fov": 40, "resolution": [{}, {}]}},
    {}
    "render": {{"spp": 2, "seed": 7}},
    "materials": {{"m": {{"type": "diffuse", "albedo": 0.6}}}},
    "shapes": [{{"type": "sphere", "center": [0, 0.6, 0], "radius": 0.6, "material": "m"}}],
    "lights": [{{"type": "environment", "radiance": 0.8}}] }})",
                     width, height, animation);
}

RenderJobSettings settings_for(const std::filesystem::path& scene) {
  RenderJobSettings s;
  s.scene = scene.string();
  s.quiet = true;
  return s;
}

// --demo left open is the camp's still (--budget 123, denoised by the ensemble) and --demo-animation the camp's
// sequence (--budget 256, the camera move at 640 x 360, NL-means); anything that sets how long to sample leaves the
// budget and the denoiser to the user, and a --denoiser given is kept.
TEST(DemoDefaults, TheCampsRulesUnlessToldOtherwise) {
  RenderJobSettings still;
  still.demo = true;
  apply_demo_defaults(still, false);
  EXPECT_EQ(still.budget, "123");
  EXPECT_TRUE(still.denoise);
  EXPECT_EQ(still.denoiser, "ensemble");
  EXPECT_FALSE(still.resolution);  // the scene's own 1920 x 1080
  EXPECT_TRUE(still.defines.empty());

  RenderJobSettings animation;
  apply_demo_defaults(animation, true);
  EXPECT_TRUE(animation.demo);
  EXPECT_EQ(animation.budget, "256");
  EXPECT_TRUE(animation.denoise);
  EXPECT_FALSE(animation.denoiser);  // NL-means, the default filter
  EXPECT_EQ(animation.resolution, "640x360");
  ASSERT_EQ(animation.defines.size(), 1u);
  EXPECT_EQ(animation.defines[0].rfind("/animation=", 0), 0u);

  RenderJobSettings chosen;
  chosen.demo = true;
  chosen.denoiser = "nlmeans";
  chosen.denoise_only = true;
  apply_demo_defaults(chosen, false);
  EXPECT_EQ(chosen.denoiser, "nlmeans");
  EXPECT_FALSE(chosen.denoise);  // --denoise-only stays the only denoised output
  EXPECT_EQ(chosen.budget, "123");

  for (auto set : {+[](RenderJobSettings& a) { a.spp = "4"; }, +[](RenderJobSettings& a) { a.time_limit = "9"; },
                   +[](RenderJobSettings& a) { a.budget = "30"; }, +[](RenderJobSettings& a) { a.resume = "c.kzck"; },
                   +[](RenderJobSettings& a) { a.sample_range = "0:4"; }}) {
    RenderJobSettings told;
    told.demo = true;
    set(told);
    const auto budget = told.budget;
    apply_demo_defaults(told, false);
    EXPECT_EQ(told.budget, budget);
    EXPECT_FALSE(told.denoise);
    EXPECT_FALSE(told.denoiser);
  }
  // A scene of one's own is left alone.
  RenderJobSettings scene;
  scene.scene = "s.json";
  apply_demo_defaults(scene, false);
  EXPECT_FALSE(scene.budget);
  EXPECT_FALSE(scene.denoise);
}

TEST(RenderJob, FrameRangeWritesTheNumberedFiles) {
  TempDir dir;
  RenderJobSettings s = settings_for(dir.write("anim.json", sphere_scene(6)));
  s.frames = "2:4";
  s.spp = "1";
  s.outputs = {(dir.path() / "f" / "%03d.exr").string()};
  RenderJob job(s);
  ASSERT_EQ(job.run(), 0);
  ASSERT_EQ(job.frames().size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const RenderFrameReport& r = job.frames()[static_cast<size_t>(i)];
    EXPECT_EQ(r.frame, 2 + i);
    EXPECT_EQ(r.status, 0);
    EXPECT_DOUBLE_EQ(r.film.mean_spp, 1.0);
    const auto file = dir.path() / "f" / fmt::format("{:03}.exr", 2 + i);
    ASSERT_EQ(r.written, std::vector<std::string>{file.string()});
    EXPECT_TRUE(std::filesystem::is_regular_file(file)) << file;
  }
  // Only the frames asked for.
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "f" / "001.exr"));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "f" / "005.exr"));
}

// A render stopped at 2 spp with a checkpoint and resumed to 5 equals the render of 5 spp never stopped.
TEST(RenderJob, CheckpointIsWrittenAndResumed) {
  TempDir dir;
  const auto scene = dir.write("still.json", sphere_scene(0));
  const auto checkpoint = dir.path() / "still.kzc";
  RenderJobSettings first = settings_for(scene);
  first.spp = "2";
  first.outputs = {(dir.path() / "part.exr").string()};
  first.checkpoint = checkpoint.string();
  RenderJob part(first);
  ASSERT_EQ(part.run(), 0);
  ASSERT_TRUE(std::filesystem::is_regular_file(checkpoint));
  EXPECT_EQ(part.frames().at(0).written.back(), checkpoint.string());

  RenderJobSettings resume = settings_for(scene);
  resume.spp = "5";
  resume.outputs = {(dir.path() / "resumed.exr").string()};
  resume.resume = checkpoint.string();
  RenderJob resumed(resume);
  ASSERT_EQ(resumed.run(), 0);

  RenderJobSettings whole = settings_for(scene);
  whole.spp = "5";
  whole.outputs = {(dir.path() / "whole.exr").string()};
  RenderJob direct(whole);
  ASSERT_EQ(direct.run(), 0);

  EXPECT_DOUBLE_EQ(resumed.film().summary().mean_spp, 5.0);
  EXPECT_EQ(resumed.film().summary().total_samples, direct.film().summary().total_samples);
  EXPECT_EQ(resumed.film().rgb(), direct.film().rgb());  // bit-identical
  // A checkpoint of another seed is not continued.
  RenderJobSettings other = resume;
  other.seed = "8";
  other.outputs = {(dir.path() / "other.exr").string()};
  RenderJob refused(other);
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(refused.run(), 1);
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(log.find("cannot resume this render from it: its seed is 7"), std::string::npos) << log;
  EXPECT_TRUE(refused.frames().empty() || refused.frames().front().status == 1);
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "other.exr"));
}

// The frames stop when the budget does: 1,000 frames cannot all be set up and written in a second, so the job
// renders the frames that fit, reports status 1 and is done inside the budget.
TEST(RenderJob, BudgetStopsTheFrames) {
  TempDir dir;
  // 20,000 frames of 16 x 12 pixels: more than a fast machine renders in the budget's second.
  RenderJobSettings s = settings_for(dir.write("anim.json", sphere_scene(20000)));
  const double budget = seconds_since_process_start() + 1.0;
  s.budget = fmt::format("{}", budget);
  s.outputs = {(dir.path() / "f" / "%04d.png").string()};
  RenderJob job(s);
  ::testing::internal::CaptureStderr();
  const int status = job.run();
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(status, 1) << log;
  EXPECT_LT(seconds_since_process_start(), budget) << log;
  EXPECT_NE(log.find("were not rendered"), std::string::npos) << log;
  ASSERT_FALSE(job.frames().empty()) << log;
  EXPECT_LT(job.frames().size(), 20000u);
  for (const RenderFrameReport& r : job.frames()) {
    EXPECT_EQ(r.status, 0) << r.frame;
    EXPECT_TRUE(std::filesystem::is_regular_file(dir.path() / "f" / fmt::format("{:04}.png", r.frame))) << r.frame;
  }
  // A frame not rendered was not written.
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "f" / "19999.png"));
  EXPECT_TRUE(job.exit_without_teardown());
}

// A job given a scene loaded already renders what the job that loads the file does, bit for bit.
TEST(RenderJob, RendersASceneLoadedAlready) {
  TempDir dir;
  const auto file = dir.write("still.json", sphere_scene(0));
  RenderJobSettings s = settings_for(file);
  s.outputs = {(dir.path() / "loaded.exr").string()};
  RenderJob loaded(load_scene_file(file), s);
  ASSERT_EQ(loaded.run(), 0);
  s.outputs = {(dir.path() / "file.exr").string()};
  RenderJob from_file(s);
  ASSERT_EQ(from_file.run(), 0);
  EXPECT_DOUBLE_EQ(loaded.film().summary().mean_spp, 2.0);  // the scene's spp
  EXPECT_EQ(loaded.film().rgb(), from_file.film().rgb());
  // Overrides act on loading: refused for a scene loaded already.
  s.defines = {"/render/spp=3"};
  RenderJob overridden(load_scene_file(file), s);
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(overridden.run(), 1);
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(log.find("kozu render: -D: the scene is loaded already"), std::string::npos) << log;
}

// Two outputs naming one file: refused before the scene is even loaded, nothing rendered or written.
TEST(RenderJob, OutputCollisionIsRefusedBeforeRendering) {
  TempDir dir;
  RenderJobSettings s = settings_for(dir.write("still.json", sphere_scene(0)));
  const auto out = dir.path() / "a.exr";
  s.outputs = {out.string(), (dir.path() / "." / "a.exr").string()};
  RenderJob job(s);
  ::testing::internal::CaptureStderr();
  const int status = job.run();
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(status, 1);
  EXPECT_NE(log.find("every output needs its own file"), std::string::npos) << log;
  EXPECT_EQ(job.scene(), nullptr);
  EXPECT_TRUE(job.frames().empty());
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_FALSE(job.exit_without_teardown());
}

// An output that is the scene file itself is refused too (an input of the render).
TEST(RenderJob, OutputOverTheSceneIsRefused) {
  TempDir dir;
  const auto scene = dir.write("still.json", sphere_scene(0));
  RenderJobSettings s = settings_for(scene);
  s.outputs = {(dir.path() / "a.exr").string()};
  s.stats = scene.string();
  RenderJob job(s);
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(job.run(), 1);
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(log.find("an input of the render"), std::string::npos) << log;
  EXPECT_TRUE(job.frames().empty());
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "a.exr"));
}

// In memory (the Python module) the job writes nothing and keeps the pixels the EXR would hold, the AOV channels
// with their names and the denoised image; progress reaches 1, and output flags are refused.
TEST(RenderJob, InMemoryKeepsWhatTheFilesWouldHold) {
  TempDir dir;
  const auto scene = dir.write("still.json", sphere_scene(0));
  RenderJobSettings to_file = settings_for(scene);
  to_file.outputs = {(dir.path() / "a.exr").string()};
  to_file.aov = "albedo,depth";
  to_file.denoise = true;
  RenderJob file_job(to_file);
  ASSERT_EQ(file_job.run(), 0);

  RenderJobSettings in_memory = settings_for(scene);
  in_memory.in_memory = true;
  in_memory.aov = "albedo,depth";
  in_memory.denoise = true;
  RenderJob job(in_memory);
  ASSERT_EQ(job.run(), 0);
  EXPECT_TRUE(job.frames().at(0).written.empty());
  EXPECT_DOUBLE_EQ(job.fraction_done(), 1.0);
  const RenderImages& im = job.images();
  ASSERT_EQ(im.width, 16);
  ASSERT_EQ(im.height, 12);
  const Image exr = read_image_all(dir.path() / "a.exr");
  ASSERT_EQ(exr.channels, 7);
  EXPECT_EQ(im.channels, (std::vector<std::string>{"albedo.R", "albedo.G", "albedo.B", "Z"}));
  EXPECT_EQ(im.layers, (std::vector<std::pair<std::string, int>>{{"albedo", 3}, {"depth", 1}}));
  const Image denoised = read_image_all(dir.path() / "a.denoised.exr");
  for (size_t i = 0; i < 16 * 12; ++i) {
    for (size_t c = 0; c < 3; ++c) {
      ASSERT_EQ(im.rgb[3 * i + c], exr.data[7 * i + c]) << i;
      ASSERT_EQ(im.denoised[3 * i + c], denoised.data[7 * i + c]) << i;
    }
    for (size_t c = 0; c < 4; ++c) {
      // The file orders its channels its own way: matched by name.
      const auto at = std::find(exr.channel_names.begin(), exr.channel_names.end(), im.channels[c]);
      ASSERT_NE(at, exr.channel_names.end()) << im.channels[c];
      ASSERT_EQ(im.data[4 * i + c], exr.data[7 * i + static_cast<size_t>(at - exr.channel_names.begin())]) << i;
    }
  }
  std::vector<std::string> errors;
  RenderJobHooks hooks;
  hooks.error = [&](const std::string& m) { errors.push_back(m); };
  RenderJobSettings bad = in_memory;
  bad.outputs = {(dir.path() / "b.exr").string()};
  RenderJob refused(bad, hooks);
  EXPECT_EQ(refused.run(), 1);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("writes no files"), std::string::npos) << errors[0];
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "b.exr"));
}

}  // namespace
}  // namespace kozu
