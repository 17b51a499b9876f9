// Regression and determinism of whole renders.
//
// Cornell box: the render at 64x64 is compared with tests/data/cornell_ref.exr, a kozu render of
// the same scene at 65536 spp (regenerate with tools/make_cornell_reference.sh after an
// intentional change of the estimator's expectation). The comparison is noise-aware: the image is
// split into 8x8-pixel blocks and each block mean must lie within z standard errors of the
// reference, the standard error coming from the test render's own per-pixel variances (the
// reference's noise is 256x smaller and is neglected). z is the two-sided normal quantile at a
// Šidák-corrected 1% level over the 64 blocks x 3 channels; the fixed seed makes the outcome
// deterministic.
#include "support/render_test.h"

#include "core/file_io.h"
#include "io/image_io.h"

#include <fmt/format.h>
#include <gtest/gtest.h>


namespace kozu::test {
namespace {

TEST(CornellBox, MatchesStoredReference) {
  const std::filesystem::path ref_path = source_dir() / "tests/data/cornell_ref.exr";
  const Image ref = read_image(ref_path);
  ASSERT_EQ(ref.width, 64);
  ASSERT_EQ(ref.height, 64);
  std::string json = read_input_file(source_dir() / "scenes/cornell.json");
  ASSERT_FALSE(json.empty());
  auto scene = load_scene_text(json, "cornell.json", source_dir() / "scenes");
  scene->camera.set_resolution(Vec2i(64, 64));
  Film film(64, 64);
  PathIntegrator integrator(*scene, scene->settings.max_depth);
  RenderSettings opt;
  opt.spp = 256;
  opt.seed = 7;  // independent of the reference's seed 0
  render(*scene, integrator, film, opt);

  expect_matches_reference(film, ref);
}

// pass_samples: RenderSettings::pass_samples (0: the renderer's growing pass schedule).
std::vector<float> render_cornell(int threads, uint64_t seed, int spp = 8, int pass_samples = 0,
                                  DirectLighting direct = DirectLighting::Sample) {
  auto scene =
      load_scene_text(read_input_file(source_dir() / "scenes/cornell.json"), "cornell.json", source_dir() / "scenes");
  scene->camera.set_resolution(Vec2i(40, 24));
  Film film(40, 24);
  PathIntegrator integrator(*scene, scene->settings.max_depth, direct);
  RenderSettings opt;
  opt.spp = spp;
  opt.threads = threads;
  opt.seed = seed;
  opt.tile_size = 7;  // tiles that do not divide the image
  opt.pass_samples = pass_samples;
  render(*scene, integrator, film, opt);
  return film.rgb();
}

TEST(Determinism, BitIdenticalForAnyThreadCount) {
  const std::vector<float> one = render_cornell(1, 3);
  for (int threads : {2, 3, 8}) {
    const std::vector<float> other = render_cornell(threads, 3);
    ASSERT_EQ(one.size(), other.size());
    EXPECT_EQ(std::memcmp(one.data(), other.data(), one.size() * sizeof(float)), 0) << threads << " threads";
  }
}

TEST(Determinism, SeedChangesTheImage) {
  const std::vector<float> a = render_cornell(2, 3), b = render_cornell(2, 4);
  EXPECT_NE(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0);
}

// Pixel (x, y) takes samples 0, 1, ..., spp − 1 in order whatever the passes (renderer.h), so 37 samples in the
// growing schedule (1, 1, 1, 1, 2, 3, 4, 6, 9, 9), in passes of 1 or 5, or all after the first at once give the
// same bits. A sample index or sampler state that depended on the pass would break this.
TEST(Determinism, PassScheduleDoesNotChangeTheResult) {
  const std::vector<float> growing = render_cornell(2, 5, 37);
  for (int pass : {1, 5, 36}) {
    const std::vector<float> other = render_cornell(2, 5, 37, pass);
    ASSERT_EQ(growing.size(), other.size());
    EXPECT_EQ(std::memcmp(growing.data(), other.data(), growing.size() * sizeof(float)), 0)
        << "passes of " << pass << " samples";
  }
}

// The thread count under a schedule other than the default (BitIdenticalForAnyThreadCount covers the default).
TEST(Determinism, ThreadCountDoesNotChangeTheResultUnderAnotherSchedule) {
  const std::vector<float> a = render_cornell(1, 5, 37, 5), b = render_cornell(3, 5, 37, 5);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0);
}

// "ltc" learns from the neighbours' samples (PixelMemory), pooled once after the pilot samples whatever the passes:
// the image is the same for any pass schedule and thread count. Pooling at the ends of passes instead breaks it.
TEST(Determinism, PixelMemoryDoesNotDependOnPassesOrThreads) {
  const std::vector<float> growing = render_cornell(2, 5, 37, 0, DirectLighting::Ltc);
  for (const auto& [threads, pass] : {std::pair{1, 0}, std::pair{3, 0}, std::pair{2, 1}, std::pair{2, 5},
                                      std::pair{3, 36}}) {
    const std::vector<float> other = render_cornell(threads, 5, 37, pass, DirectLighting::Ltc);
    ASSERT_EQ(growing.size(), other.size());
    EXPECT_EQ(std::memcmp(growing.data(), other.data(), growing.size() * sizeof(float)), 0)
        << threads << " threads, passes of " << pass;
  }
}

}  // namespace
}  // namespace kozu::test
