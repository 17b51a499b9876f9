// The visible emission's re-estimation (render/emission_refine.h) on an emitter whose slanted edge crosses every row
// of pixels, against each pixel's numerically integrated share of it (emitter_edge_scene.h).
#include "render/emission_refine.h"

#include "emitter_edge_scene.h"
#include "support/render_test.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>

namespace kozu::test {
namespace {

constexpr int kRes = kEdgeRes, kSpp = 16;
constexpr float kLe = kEdgeLe;

struct EdgeRender {
  std::unique_ptr<Scene> scene;
  std::unique_ptr<PathIntegrator> integrator;
  Film film;
  RenderSettings options;
};

EdgeRender render_edge(int threads) {
  EdgeRender s;
  s.scene = load_scene_text(kEdgeScene, "edge.json", ".");
  s.integrator = std::make_unique<PathIntegrator>(*s.scene, s.scene->settings.max_depth);
  s.film = Film(kRes, kRes);
  s.film.enable_features();
  s.options.spp = kSpp;
  s.options.seed = 11;
  s.options.threads = threads;
  s.options.filter = s.scene->settings.filter;
  render(*s.scene, *s.integrator, s.film, s.options);
  return s;
}

bool on_edge(float truth) { return truth > 0.02f * kLe && truth < 0.98f * kLe; }

TEST(EmissionRefine, EstimatesTheEmittersShareOfEdgePixels) {
  const EdgeRender s = render_edge(0);
  const std::vector<float> truth = true_edge_emission(*s.scene);
  EmissionRefineSettings settings;
  settings.samples_per_pixel = 64.0;  // enough for every edge pixel of this small image
  EmissionRefineStats stats;
  const VisibleEmission e = refine_emission(*s.scene, *s.integrator, s.film, s.options, settings, &stats);
  double raw_err = 0.0, refined_err = 0.0;
  int edge = 0;
  for (int y = 0; y < kRes; ++y)
    for (int x = 0; x < kRes; ++x) {
      const size_t i = static_cast<size_t>(y) * kRes + x;
      const float raw = s.film.mean(x, y).r;
      EXPECT_TRUE(e.apart(i)) << x << "," << y;  // every pixel: refined, or quiet and exact
      if (on_edge(truth[i])) {
        ++edge;
        raw_err += (raw - truth[i]) * (raw - truth[i]);
        refined_err += (e.value(i).x - truth[i]) * (e.value(i).x - truth[i]);
      } else if (truth[i] == 0.0f || truth[i] == kLe) {
        EXPECT_EQ(e.value(i).x, truth[i]) << x << "," << y;  // wholly inside or outside: exact from the film
      }
    }
  ASSERT_GE(edge, kRes);  // the edge crosses every row
  EXPECT_GE(stats.pixels, static_cast<uint64_t>(edge));
  EXPECT_LE(stats.samples, static_cast<uint64_t>(settings.samples_per_pixel * kRes * kRes));
  // 8 × the samples of a stratified estimate of a straight edge: the squared error falls by about 8^1.5 (≈ 23);
  // asserted 5, well beyond what 8 × independent samples would give (8).
  EXPECT_LT(refined_err, raw_err / 5.0) << "edge pixels " << edge << ", raw " << raw_err << ", refined " << refined_err;
}

TEST(EmissionRefine, TheRendersOwnSamplesComeFirst) {
  // With as many samples as the render took, the re-estimate is the film's own mean: the same streams, in order.
  const EdgeRender s = render_edge(0);
  EmissionRefineSettings settings;
  settings.factor = 1;
  settings.min_samples = 1;
  settings.samples_per_pixel = 64.0;
  EmissionRefineStats stats;
  const VisibleEmission e = refine_emission(*s.scene, *s.integrator, s.film, s.options, settings, &stats);
  ASSERT_GT(stats.pixels, 0u);
  for (int y = 0; y < kRes; ++y)
    for (int x = 0; x < kRes; ++x)
      EXPECT_NEAR(e.value(static_cast<size_t>(y) * kRes + x).x, s.film.mean(x, y).r, 1e-5f) << x << "," << y;
}

TEST(EmissionRefine, IsDeterministicAndKeepsWithinItsBudget) {
  const EdgeRender one = render_edge(1), two = render_edge(2);
  EmissionRefineSettings settings;  // 4 samples per pixel: 1024, 8 pixels at 128
  EmissionRefineStats stats_one, stats_two;
  const VisibleEmission a = refine_emission(*one.scene, *one.integrator, one.film, one.options, settings, &stats_one);
  const VisibleEmission b = refine_emission(*two.scene, *two.integrator, two.film, two.options, settings, &stats_two);
  EXPECT_EQ(stats_one.pixels, stats_two.pixels);
  EXPECT_LE(stats_one.samples, static_cast<uint64_t>(settings.samples_per_pixel * kRes * kRes));
  EXPECT_EQ(stats_one.pixels, 8u);
  int noisy_left = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a.value(i).x, b.value(i).x);
    EXPECT_EQ(a.apart(i), b.apart(i));
    noisy_left += !a.apart(i);
  }
  // The noisy pixels the budget left are filtered with the rest of the radiance (not apart).
  EXPECT_GT(noisy_left, 0);
  // Without the scene, from the film alone: the same pixels not apart, and the film's own means.
  const VisibleEmission own = visible_emission(one.film);
  int own_noisy = 0;
  for (size_t i = 0; i < own.size(); ++i) own_noisy += !own.apart(i);
  EXPECT_EQ(own_noisy, noisy_left + static_cast<int>(stats_one.pixels));
}

// --budget's deadline: past it the pass begins no more pixels. Expired from the start, it re-estimates none, and
// every pixel is as the film alone gives it; expiring after three polls, it stops after at most three pixels
// (the default settings re-estimate 8 here), and those it reached are the same as without a deadline.
TEST(EmissionRefine, StopsAtItsDeadline) {
  const EdgeRender s = render_edge(1);
  const EmissionRefineSettings settings;
  const VisibleEmission own = visible_emission(s.film),
                        full = refine_emission(*s.scene, *s.integrator, s.film, s.options, settings);
  EmissionRefineStats none_stats;
  const VisibleEmission none =
      refine_emission(*s.scene, *s.integrator, s.film, s.options, settings, &none_stats, [] { return true; });
  EXPECT_EQ(none_stats.pixels, 0u);
  EXPECT_EQ(none_stats.samples, 0u);
  for (size_t i = 0; i < none.size(); ++i) {
    EXPECT_EQ(none.apart(i), own.apart(i)) << i;
    if (none.apart(i)) {
      EXPECT_EQ(none.value(i).x, own.value(i).x) << i;
    }
  }
  std::atomic<int> polls{0};
  EmissionRefineStats some_stats;
  const VisibleEmission some =
      refine_emission(*s.scene, *s.integrator, s.film, s.options, settings, &some_stats, [&] { return ++polls > 3; });
  EXPECT_LE(some_stats.pixels, 3u);
  int reached = 0;
  for (size_t i = 0; i < some.size(); ++i) {
    if (some.apart(i) && !own.apart(i)) {
      ++reached;
      EXPECT_EQ(some.value(i).x, full.value(i).x) << i;
    }
    if (!some.apart(i)) {
      EXPECT_FALSE(own.apart(i)) << i;
    }
  }
  EXPECT_EQ(reached, static_cast<int>(some_stats.pixels));
}

}  // namespace
}  // namespace kozu::test
