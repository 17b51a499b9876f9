// Every scene in scenes/ renders finite samples: valid input never gives NaN or Inf (nan_samples is 0) and no
// path reaches the per-path work cap (render_json checks both). The voxelized bush the scenes read is made small
// here with the kozu command (kozu voxelize, as scripts/make-volumes.sh does), the procedural volumes are generated
// coarse (a "resolution" added to each "procedural" key), and each scene renders at 24 x 16 with 4 samples per pixel.
#include "support/render_test.h"

#include "core/file_io.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

class ShowcaseScenes : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    const auto& d = dir_->path();
    std::filesystem::create_directory_symlink(source_dir() / "scenes/meshes", d / "meshes");
    std::filesystem::create_directory_symlink(source_dir() / "scenes/textures", d / "textures");
    std::filesystem::create_directories(d / "volumes");
    const std::string kozu = fmt::format("'{}'", kozu_binary().string());
    std::string out;
    ASSERT_EQ(run_command(fmt::format("{} voxelize '{}' --resolution 32 -o '{}'", kozu,
                                      (source_dir() / "scenes/meshes/bush.ply").string(),
                                      (d / "volumes/bush.kvox").string()),
                          &out),
              0)
        << out;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static TempDir* dir_;
};
TempDir* ShowcaseScenes::dir_ = nullptr;

TEST_F(ShowcaseScenes, RenderFiniteSamples) {
  int scenes = 0;
  for (const auto& entry : std::filesystem::directory_iterator(source_dir() / "scenes")) {
    if (entry.path().extension() != ".json") continue;
    ++scenes;
    SCOPED_TRACE(entry.path().filename().string());
    std::string json = read_input_file(entry.path());
    // The procedural volumes coarse but not empty (the fabric's threads need 48 voxels across).
    for (const auto& [kind, resolution] : {std::pair{"smoke", 24}, std::pair{"yarn", 24}, std::pair{"fabric", 48}}) {
      const std::string key = fmt::format("\"procedural\": \"{}\"", kind);
      for (size_t at = json.find(key); at != std::string::npos; at = json.find(key, at + 1))
        json.insert(at + key.size(), fmt::format(", \"resolution\": {}", resolution));
    }
    // Small: the resolution is overridden after loading.
    TestRender t;
    t.scene = load_scene_text(json, entry.path().filename().string(), dir_->path());
    t.scene->camera.set_resolution(Vec2i(24, 16));
    t.scene->set_media_view();
    t.film = Film(24, 16);
    PathIntegrator integrator(*t.scene, t.scene->settings.max_depth);
    RenderSettings opt;
    opt.spp = 4;
    t.result = render(*t.scene, integrator, t.film, opt);
    EXPECT_EQ(t.result.film.discarded_samples, 0u);
    EXPECT_EQ(t.result.rays.truncated_paths, 0u);
    EXPECT_EQ(t.result.film.unsampled_pixels, 0u);
  }
  EXPECT_GE(scenes, 15);  // every showcase scene was found
}

}  // namespace
}  // namespace kozu::test
