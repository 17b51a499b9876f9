// The renderer around the integrator: non-finite samples, per-pixel counts, tone maps, filters.
#include "support/render_test.h"

#include "core/file_io.h"
#include "core/rng.h"
#include "core/tonemap.h"
#include "scene/filter.h"
#include "support/chi2.h"

#include <chrono>
#include <thread>

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

// A scene with nothing in it, for tests of the renderer around a stand-in integrator.
std::unique_ptr<Scene> empty_scene(int width, int height) {
  return load_scene_text(fmt::format(R"({{"camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0],
    "resolution": [{}, {}]}}, "shapes": []}})",
                                     width, height),
                         "scene.json", ".");
}

// Returns 1, except for rays into the left half of the image (d.x < 0), where half of the samples
// are NaN, +Inf or negative.
class PoisonedIntegrator final : public Integrator {
 public:
  Rgb li(const Ray& ray, Sampler& sampler, Arena&, RayCounters&, const StopFlag&) const override {
    if (ray.d.x >= 0.0f) return Rgb(1.0f);
    const float u = sampler.next_1d();
    if (u < 0.2f) return Rgb(std::numeric_limits<float>::quiet_NaN(), 1.0f, 1.0f);
    if (u < 0.35f) return Rgb(1.0f, std::numeric_limits<float>::infinity(), 1.0f);
    if (u < 0.5f) return Rgb(1.0f, 1.0f, -2.0f);
    return Rgb(1.0f);
  }
};

TEST(Renderer, DiscardsAndCountsNonFiniteAndNegativeSamples) {
  auto scene = load_scene_text(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [16, 8]},
    "render": {"filter": "box"}, "shapes": []})",
                               "scene.json", ".");
  Film film(16, 8);
  PoisonedIntegrator integrator;
  RenderSettings opt;
  opt.spp = 64;
  opt.filter = PixelFilter::Type::Box;
  const RenderResult r = render(*scene, integrator, film, opt);
  uint64_t discarded = 0;
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 16; ++x) {
      // Every written value is finite and every pixel is the mean of its valid samples (all 1).
      EXPECT_EQ(film.mean(x, y), Rgb(1.0f)) << x << "," << y;
      EXPECT_EQ(film.count(x, y) + film.discarded(x, y), 64u);
      if (x < 8)
        EXPECT_GT(film.discarded(x, y), 0u);
      else
        EXPECT_EQ(film.discarded(x, y), 0u);
      discarded += film.discarded(x, y);
    }
  EXPECT_EQ(r.film.pixels_with_discarded, 8u * 8u);
  EXPECT_EQ(r.film.discarded_samples, discarded);
  // About half of the left half's 4096 samples.
  EXPECT_GT(discarded, 1500u);
  EXPECT_LT(discarded, 2600u);
}

// Rare bright samples (1 in 8 is (40, 20, 10), the rest (1, 1, 1)): render.clamp 4 scales each bright sample to
// (4, 2, 1), keeping its hue, and leaves the others; without it the mean keeps them whole.
class FireflyIntegrator final : public Integrator {
 public:
  Rgb li(const Ray&, Sampler& sampler, Arena&, RayCounters&, const StopFlag&) const override {
    return sampler.next_1d() < 0.125f ? Rgb(40.0f, 20.0f, 10.0f) : Rgb(1.0f);
  }
};

TEST(Renderer, ClampScalesBrightSamplesAndKeepsTheirHue) {
  auto scene = empty_scene(8, 8);
  FireflyIntegrator integrator;
  for (const float clamp : {0.0f, 4.0f}) {
    Film film(8, 8);
    RenderSettings opt;
    opt.spp = 64;
    opt.clamp = clamp;
    render(*scene, integrator, film, opt);
    // Each pixel: n bright samples of 64 (exactly 8: the sampler stratifies its 1D dimension).
    const Rgb bright = clamp > 0.0f ? Rgb(4.0f, 2.0f, 1.0f) : Rgb(40.0f, 20.0f, 10.0f);
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) {
        const Rgb m = film.mean(x, y);
        const float n = (m.r - 1.0f) / (bright.r - 1.0f) * 64.0f;  // bright samples, from red
        EXPECT_NEAR(n, 8.0f, 1e-3f) << x << "," << y;
        EXPECT_NEAR(m.g, (n * bright.g + (64.0f - n)) / 64.0f, 1e-4f) << x << "," << y;
        EXPECT_NEAR(m.b, (n * bright.b + (64.0f - n)) / 64.0f, 1e-4f) << x << "," << y;
      }
  }
}

TEST(Renderer, CancelStopsWithCorrectlyNormalisedPixels) {
  auto scene = empty_scene(32, 32);
  Film film(32, 32);
  PoisonedIntegrator integrator;
  RenderSettings opt;
  opt.spp = 1000000;
  RenderProgress progress;
  std::thread canceller([&] {
    while (progress.samples_done.load() < 32 * 32 * 4) std::this_thread::yield();
    progress.cancel.store(true);
  });
  const RenderResult r = render(*scene, integrator, film, opt, &progress);
  canceller.join();
  EXPECT_LT(r.film.max_spp, 1000000u);
  // Samples taken (valid + discarded) stay within one pass of each other (passes are at most 16).
  uint32_t lo = ~0u, hi = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      const uint32_t taken = film.count(x, y) + film.discarded(x, y);
      lo = std::min(lo, taken);
      hi = std::max(hi, taken);
      if (film.count(x, y) > 0) {
        EXPECT_EQ(film.mean(x, y), Rgb(1.0f));
      }
    }
  EXPECT_GE(lo, 4u);
  EXPECT_LE(hi - lo, 16u);
}

// A sample that never ends on its own (it only returns once the stop flag is raised, as the media loops do)
// used to hold the render past its deadline forever: the watchdog raises the flag at the deadline, the sample
// is dropped, and the render returns at once with no sample counted.
class EndlessIntegrator final : public Integrator {
 public:
  Rgb li(const Ray&, Sampler&, Arena&, RayCounters&, const StopFlag& stop) const override {
    while (!stop.load(std::memory_order_relaxed)) std::this_thread::yield();
    return Rgb(1.0f);
  }
};

TEST(Renderer, DeadlineHoldsWhateverOneSampleCosts) {
  auto scene = empty_scene(8, 8);
  Film film(8, 8);
  EndlessIntegrator integrator;
  RenderSettings opt;
  opt.spp = 4;
  opt.time_limit = 0.2;
  const auto t0 = std::chrono::steady_clock::now();
  const RenderResult r = render(*scene, integrator, film, opt);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(seconds, 0.2 + 0.1);
  EXPECT_TRUE(r.hit_time_limit);
  EXPECT_EQ(r.paths, 0u);
  EXPECT_EQ(r.film.unsampled_pixels, 64u);
  // Nothing was sampled: the image stays black (no NaN from the fill).
  for (float v : film.rgb()) EXPECT_EQ(v, 0.0f);
}

// Returns 1 after a short wait, so that a render can be stopped part-way through its first pass.
class SlowIntegrator final : public Integrator {
 public:
  Rgb li(const Ray&, Sampler&, Arena&, RayCounters&, const StopFlag&) const override {
    std::this_thread::sleep_for(std::chrono::microseconds(300));
    return Rgb(1.0f);
  }
};

// A render stopped early had black bands (tiles never reached). The first sample is taken coarse to fine: once
// 64 samples of a 64 x 64 image are done, every pixel of the stride-8 lattice has one, and the image written is
// complete: the unsampled pixels are filled from their neighbours (all 1 here), counted in the summary.
TEST(Renderer, FirstPassCoversTheImageCoarseToFine) {
  auto scene = empty_scene(64, 64);
  Film film(64, 64);
  SlowIntegrator integrator;
  RenderSettings opt;
  opt.spp = 16;
  opt.threads = 2;
  RenderProgress progress;
  std::thread canceller([&] {
    while (progress.samples_done.load() < 64) std::this_thread::sleep_for(std::chrono::microseconds(100));
    progress.cancel.store(true);
  });
  const RenderResult r = render(*scene, integrator, film, opt, &progress);
  canceller.join();
  EXPECT_TRUE(r.cancelled);
  for (int y = 0; y < 64; y += 8)
    for (int x = 0; x < 64; x += 8) EXPECT_GE(film.count(x, y), 1u) << x << "," << y;
  // Stopped within the first pass: most pixels have no sample yet.
  EXPECT_GT(r.film.unsampled_pixels, 64u * 64u / 2u);
  EXPECT_EQ(r.film.unsampled_pixels + r.paths, 64u * 64u);
  for (float v : film.rgb()) EXPECT_EQ(v, 1.0f);
}

// Pull-push filling: sampled pixels keep their value exactly; holes take values between their sampled
// neighbours (a linear ramp stays within its range and close to it), and a film without samples stays black.
TEST(Film, UnsampledPixelsAreFilledFromTheirNeighbours) {
  const int w = 37, h = 21;  // not powers of two
  Film film(w, h);
  const auto ramp = [&](int x, int y) { return 0.2f + 0.6f * float(x) / (w - 1) + 0.1f * float(y) / (h - 1); };
  for (int y = 0; y < h; y += 4)
    for (int x = 0; x < w; x += 4) film.add_sample(x, y, Rgb(ramp(x, y), 1.0f, 0.0f));
  const Film::Summary sum = film.summary();
  EXPECT_EQ(sum.unsampled_pixels, uint64_t(w) * h - uint64_t((w + 3) / 4) * ((h + 3) / 4));
  const std::vector<float> rgb = film.rgb();
  double worst = 0.0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float* p = &rgb[3 * (size_t(y) * w + x)];
      if (x % 4 == 0 && y % 4 == 0) {
        EXPECT_EQ(p[0], ramp(x, y));
      } else {
        EXPECT_GE(p[0], 0.2f - 1e-6f);
        EXPECT_LE(p[0], 0.9f + 1e-6f);
        worst = std::max(worst, double(std::abs(p[0] - ramp(x, y))));
      }
      EXPECT_NEAR(p[1], 1.0f, 1e-6f);  // a constant channel stays constant
      EXPECT_EQ(p[2], 0.0f);
    }
  // Interpolation across a 4-pixel lattice of a ramp with slope 0.6 / 36 per pixel: within ~4 pixels' change.
  EXPECT_LT(worst, 4.0 * 0.6 / 36.0);
  Film empty(5, 3);
  for (float v : empty.rgb()) EXPECT_EQ(v, 0.0f);
  EXPECT_EQ(empty.summary().unsampled_pixels, 15u);
}

// The ray counters behind rays/s figures count exactly the rays handed to Embree.
// render.noise_threshold: pixels stop at a pass boundary once they have min_spp samples and their error estimate, and
// their neighbours', is under the threshold (render/adaptive_sampling.h; the rule itself: test_adaptive_sampling);
// noiseless sky stops at min_spp, the noisy floor takes more; the same film for 1 and 2 threads.
TEST(Renderer, AdaptiveSamplingStopsConvergedPixelsDeterministically) {
  const std::string json = R"({
    "camera": {"position": [0, 1, 4], "look_at": [0, 0.3, 0], "fov": 40, "resolution": [32, 24]},
    "render": {"noise_threshold": 0.005, "min_spp": 16},
    "materials": {"floor": {"type": "diffuse", "albedo": 0.6}},
    "shapes": [{"type": "quad", "material": "floor", "vertices": [[-3, 0, 3], [3, 0, 3], [3, 0, -3], [-3, 0, -3]]},
               {"type": "sphere", "center": [0.5, 3, 1], "radius": 0.1, "material": "floor", "emission": 40}],
    "lights": [{"type": "environment", "radiance": 0.2}] })";
  const auto run = [&](int threads, float threshold) {
    auto scene = load_scene_text(json, "scene.json", ".");
    EXPECT_EQ(scene->settings.noise_threshold, 0.005f);
    EXPECT_EQ(scene->settings.min_spp, 16);
    Film film(32, 24);
    PathIntegrator integrator(*scene, scene->settings.max_depth, scene->settings.direct);
    RenderSettings opt = scene->settings;
    opt.noise_threshold = threshold;
    opt.spp = 200;
    opt.threads = threads;
    opt.seed = 11;
    render(*scene, integrator, film, opt);
    return film;
  };
  const Film a = run(1, 0.005f), b = run(2, 0.005f), full = run(2, 0.0f);
  // The pass boundaries (renderer.cpp): 1 sample, then passes of 1, 1, 1, 2, 3, 4, 6, 9, 14, 16, 16, ... (1, 2, 3,
  // 4, 6, 9, 13, 19, 28, 42, 58, ...)
  std::vector<uint32_t> boundaries = {1};
  for (int done = 1; done < 200;) {
    done += std::min(200 - done, std::clamp(done / 2, 1, 16));
    boundaries.push_back(static_cast<uint32_t>(done));
  }
  int stopped = 0, sky = 0;
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 32; ++x) {
      ASSERT_EQ(a.count(x, y), b.count(x, y)) << x << "," << y;
      ASSERT_EQ(a.mean(x, y), b.mean(x, y)) << x << "," << y;
      EXPECT_EQ(full.count(x, y), 200u);
      const uint32_t n = a.count(x, y);
      EXPECT_GE(n, 16u);
      EXPECT_NE(std::find(boundaries.begin(), boundaries.end(), n), boundaries.end()) << n;
      if (n < 200) {
        ++stopped;
        // Stopped pixels met the criterion: the standard error of the luminance mean over the square root of the
        // luminance at most 0.005 (render/adaptive_sampling.h).
        const Rgb m = a.mean(x, y), v = a.variance_of_mean(x, y);
        const double lum = 0.2126 * m.r + 0.7152 * m.g + 0.0722 * m.b;
        const double se = std::sqrt(0.2126 * 0.2126 * v.r + 0.7152 * 0.7152 * v.g + 0.0722 * 0.0722 * v.b);
        EXPECT_LE(se, 0.005 * std::sqrt(std::max(lum, 0.01)) * (1 + 1e-5)) << x << "," << y;
      }
      // The sky (the top rows, above the floor's horizon) is noiseless: it stops at the first boundary >= 16, 19.
      if (y < 3) sky += n == 19;
    }
  EXPECT_EQ(sky, 3 * 32);
  EXPECT_GT(stopped, 3 * 32);
  EXPECT_LT(stopped, 32 * 24);  // some floor pixels need all 200
  // Bad values are one clear error; the same scene with good ones loads.
  const auto scene_with = [](const char* render) {
    return fmt::format(R"({{"camera": {{"position": [0, 0, 4], "look_at": [0, 0, 0]}}, "render": {{{}}},
      "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}}],
      "materials": {{"m": {{"type": "diffuse"}}}}, "lights": [{{"type": "environment", "radiance": 1}}]}})",
                       render);
  };
  EXPECT_NO_THROW(load_scene_text(scene_with(R"("noise_threshold": 0.1, "min_spp": 2)"), "scene.json", "."));
  for (const char* bad : {R"("noise_threshold": -0.1)", R"("min_spp": 1)", R"("noise_threshold": "low")"})
    EXPECT_THROW(load_scene_text(scene_with(bad), "scene.json", "."), InputError) << bad;
}

TEST(Renderer, RayCountersMatchTracedRays) {
  auto scene =
      load_scene_text(read_input_file(source_dir() / "scenes/cornell.json"), "cornell.json", source_dir() / "scenes");
  scene->camera.set_resolution(Vec2i(48, 48));
  PathIntegrator integrator(*scene, scene->settings.max_depth);
  RenderSettings opt;
  opt.spp = 8;
  opt.threads = 1;  // the ray log is single-threaded
  Film film(48, 48);
  RayLog log;
  scene->set_ray_log(&log);
  const RenderResult r = render(*scene, integrator, film, opt);
  scene->set_ray_log(nullptr);
  EXPECT_EQ(r.rays.camera_rays, 48u * 48u * 8u);
  EXPECT_EQ(r.rays.camera_rays + r.rays.extension_rays, log.closest.size());
  EXPECT_EQ(r.rays.shadow_rays, log.shadow.size());
}

// PixelMemory (integrators/integrator.h): a pixel learns the pooled share of its eight neighbours and never its own
// (its samples are stratified against the one that reads it); pixels whose neighbours saw different lights, or none,
// learn nothing.
TEST(PixelMemory, PoolsTheNeighboursAndNeverThePixelItself) {
  const int w = 5, h = 4;
  const uint32_t light_a = 1, light_b = 2;  // lights by their names (PixelMemory)
  std::vector<PixelMemory> memory(size_t(w * h));
  const auto at = [&](int x, int y) -> PixelMemory& { return memory[size_t(y * w + x)]; };
  at(1, 1) = PixelMemory{light_a, 3.0f, 4.0f};  // seen 3 of 4
  at(2, 1) = PixelMemory{light_a, 0.0f, 4.0f};  // seen none
  at(4, 3) = PixelMemory{light_b, 1.0f, 1.0f};
  pool_pixel_memory(memory, w, h, 0.0);
  EXPECT_EQ(at(1, 1).learnt_light, light_a);  // only (2, 1) around it
  EXPECT_FLOAT_EQ(at(1, 1).learnt_share, 0.0f);
  EXPECT_EQ(at(2, 1).learnt_light, light_a);  // only (1, 1)
  EXPECT_FLOAT_EQ(at(2, 1).learnt_share, 0.75f);
  EXPECT_EQ(at(1, 2).learnt_light, light_a);  // both
  EXPECT_FLOAT_EQ(at(1, 2).learnt_share, 3.0f / 8.0f);
  EXPECT_EQ(at(3, 3).learnt_light, light_b);
  EXPECT_FLOAT_EQ(at(3, 3).learnt_share, 1.0f);
  EXPECT_EQ(at(3, 2).learnt_light, 0u);  // (2, 1) and (4, 3) saw different lights
  EXPECT_EQ(at(4, 3).learnt_light, 0u);  // no neighbour saw a light
  EXPECT_EQ(at(0, 3).learnt_light, 0u);
  // A pixel's own sums are left as they were.
  EXPECT_EQ(at(1, 1).light, light_a);
  EXPECT_FLOAT_EQ(at(1, 1).seen, 3.0f);
  EXPECT_FLOAT_EQ(at(1, 1).all, 4.0f);
}

// A part of a split render pools what the memories outside its window (or of another part's tiles) hold, as the
// renderer hands them over (`other`): the pixels by the window's edge learn what the whole render's do.
TEST(PixelMemory, PoolsTheNeighboursOutsideTheWindowItIsGiven) {
  const int w = 3, h = 2;
  const uint32_t light_a = 1;
  std::vector<PixelMemory> memory(size_t(w * h));
  memory[1] = PixelMemory{light_a, 1.0f, 4.0f};  // (1, 0)
  const PixelMemory left{light_a, 3.0f, 4.0f}, none;
  // (-1, 0) and (-1, 1) hold `left`; (1, 1) belongs to another part, which saw nothing; (0, 0) is ours.
  const auto other = [&](int x, int y) -> const PixelMemory* {
    if (x == -1 && (y == 0 || y == 1)) return &left;
    if (x == 1 && y == 1) return &none;
    return nullptr;
  };
  pool_pixel_memory(memory, w, h, 0.0, other);
  EXPECT_EQ(memory[0].learnt_light, light_a);  // (0, 0): (-1, 0), (-1, 1) and (1, 0)
  EXPECT_FLOAT_EQ(memory[0].learnt_share, 7.0f / 12.0f);
  EXPECT_FLOAT_EQ(memory[3].learnt_share, 7.0f / 12.0f);  // (0, 1): the same three
  EXPECT_FLOAT_EQ(memory[2].learnt_share, 0.25f);         // (2, 0): (1, 0) alone
  pool_pixel_memory(memory, w, h, 0.0);                   // without them: (1, 0) alone
  EXPECT_FLOAT_EQ(memory[0].learnt_share, 0.25f);
}

// The image's mean variance of a sample within a pixel: the pixels' squared deviations over their degrees of
// freedom, pooled; pixels of fewer than two samples, and absent ones, add nothing.
TEST(PixelMemory, ImageVarianceIsThePooledVarianceWithinPixels) {
  PixelMemory a, b, c;
  a.samples = 4.0f, a.sum = 2.0f, a.sum2 = 2.0f;  // 0, 1, 0, 1: 1 over 3
  b.samples = 2.0f, b.sum = 2.0f, b.sum2 = 4.0f;  // 0, 2: 2 over 1
  c.samples = 1.0f, c.sum = 5.0f, c.sum2 = 25.0f;
  EXPECT_DOUBLE_EQ(pixel_memory_variance({&a, &b, &c, nullptr}), 3.0 / 4.0);
  EXPECT_DOUBLE_EQ(pixel_memory_variance({&c}), 0.0);
}

// The control variate is skipped where the variance it removed within the neighbours' pixels (their samples'
// variance without it less that with it, over the samples that took it) is below PixelMemory::kCost times the image's
// mean variance of a sample within a pixel: there its cost buys more elsewhere. Variance between pixels (an edge) does
// not count, nor does the light's own variance where the control variate did not remove it.
TEST(PixelMemory, SkipsTheControlVariateWhereItRemovesLessThanItCosts) {
  std::vector<PixelMemory> row(9);
  // Samples 0, 1, 0, 1 (squared deviations 1, 3 degrees of freedom), all with the control variate; without it they
  // were 0, 1.05, 0, 1.05 (1.1025): it removed 0.1025.
  row[0].samples = 4.0f, row[0].sum = 2.0f, row[0].sum2 = 2.0f;
  row[0].cv_samples = 4.0f, row[0].with_sum = 2.0f, row[0].with_sum2 = 2.0f;
  row[0].without_sum = 2.1f, row[0].without_sum2 = 2.205f;
  // The same samples; without the control variate 0, 3, 0, 3 (9): it removed 8.
  row[3] = row[0];
  row[3].without_sum = 6.0f, row[3].without_sum2 = 18.0f;
  // Samples 0 and 2 (2, one degree of freedom), the same without the control variate: it removed nothing.
  row[6].samples = 2.0f, row[6].sum = 2.0f, row[6].sum2 = 4.0f;
  row[6].cv_samples = 2.0f, row[6].with_sum = 2.0f, row[6].with_sum2 = 4.0f;
  row[6].without_sum = 2.0f, row[6].without_sum2 = 4.0f;
  // Samples 3 and 3: none within the pixel, much between it and row[6].
  row[8].samples = 2.0f, row[8].sum = 6.0f, row[8].sum2 = 18.0f;
  row[8].cv_samples = 2.0f, row[8].with_sum = 6.0f, row[8].with_sum2 = 18.0f;
  row[8].without_sum = 6.0f, row[8].without_sum2 = 18.0f;
  // The image's mean variance of a sample (pixel_memory_variance): (1 + 1 + 2 + 0) / (3 + 3 + 1 + 1) = 0.5; kCost
  // times it, 0.15 per degree of freedom.
  std::vector<const PixelMemory*> all;
  for (const PixelMemory& m : row) all.push_back(&m);
  ASSERT_DOUBLE_EQ(pixel_memory_variance(all), 0.5);
  pool_pixel_memory(row, 9, 1, 0.5);
  EXPECT_TRUE(row[1].learnt_skip);   // (0): 0.1025 / 3
  EXPECT_FALSE(row[2].learnt_skip);  // (3): 8 / 3
  EXPECT_FALSE(row[4].learnt_skip);  // (3): 8 / 3
  EXPECT_FALSE(row[0].learnt_skip);  // no neighbour that took it twice
  EXPECT_TRUE(row[5].learnt_skip);   // (6): its variance, but none removed
  EXPECT_TRUE(row[7].learnt_skip);   // (6, 8): none removed, whatever lies between them
}

TEST(ToneMap, CurvesAreMonotoneAndBounded) {
  for (const char* name : {"aces", "neutral", "agx", "clamp"}) {
    ToneMap tm;
    tm.curve = ToneMap::parse(name);
    float prev = -1.0f;
    for (float x = 0.0f; x < 100.0f; x = x * 1.05f + 1e-3f) {
      const Rgb y = tm.apply(Rgb(x));
      EXPECT_GE(y.g, prev - 1e-6f) << name << " at " << x;
      EXPECT_GE(y.g, 0.0f);
      EXPECT_LE(y.g, 1.0f);
      prev = y.g;
    }
  }
  // Any input at any exposure maps into [0, 1]: huge values (whose squares overflow a float) to white, NaN to
  // black (a 3e38 pixel at --exposure 64 made ACES divide inf by inf).
  for (const char* name : {"aces", "neutral", "agx", "clamp"}) {
    ToneMap tm;
    tm.curve = ToneMap::parse(name);
    tm.exposure = 64.0f;
    const Rgb white = tm.apply(Rgb(3e38f)), nan = tm.apply(Rgb(std::numeric_limits<float>::quiet_NaN()));
    for (int c = 0; c < 3; ++c) {
      EXPECT_GE(white[c], 0.99f) << name;
      EXPECT_LE(white[c], 1.0f) << name;
      EXPECT_EQ(nan[c], 0.0f) << name;
    }
  }
  EXPECT_THROW(ToneMap::parse("filmic"), std::invalid_argument);
  EXPECT_NEAR(srgb_encode(0.0031308f), 0.04045f, 1e-4f);
  EXPECT_NEAR(srgb_encode(0.5f), 0.735357f, 1e-5f);
}

// AgX (core/tonemap.h): black to 0, mid grey where Wrensch's published constants put it, grey monotone from 1e-6
// to 1e30 and white at the top, each channel monotone up to display white, nothing outside [0, 1] or NaN.
TEST(ToneMap, Agx) {
  ToneMap tm;
  tm.curve = ToneMap::parse("agx");
  const Rgb black = tm.apply(Rgb(0.0f));
  for (int c = 0; c < 3; ++c) EXPECT_EQ(black[c], 0.0f);
  // 0.18: inset rows sum to 1.000136, log2 -> x = 0.606072 of the range, the polynomial gives 0.496755 (display
  // encoded; the outset moves it by < 1e-4), 0.496755^2.2 = 0.21447 linear, sRGB code 0.5005.
  const Rgb grey = tm.apply(Rgb(0.18f));
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(grey[c], 0.21450f, 1e-4f) << c;
  EXPECT_NEAR(srgb_encode(grey.g), 0.5005f, 2e-4f);
  // Grey: monotone over 36 decades, display white (0.9986^2.2 = 0.9969 of the fit) at the top.
  Rgb prev(0.0f);
  for (float x = 1e-6f; x < 1e30f; x *= 1.02f) {
    const Rgb y = tm.apply(Rgb(x));
    for (int c = 0; c < 3; ++c) {
      ASSERT_GE(y[c], prev[c]) << x;
      ASSERT_LE(y[c], 1.0f) << x;
    }
    prev = y;
  }
  for (int c = 0; c < 3; ++c) EXPECT_GT(prev[c], 0.996f);
  // One channel swept alone over other channels' values rises until it reaches display white (1, or grey white
  // 0.997 when all three saturate together); past 1 AgX's outset lets it dip, to grey white at most (0.35 %), as
  // the inset leaks it into the other channels (the path to white).
  for (const Rgb base :
       {Rgb(0.0f), Rgb(0.1f, 0.5f, 2.0f), Rgb(1.0f), Rgb(10.0f, 0.01f, 0.3f), Rgb(100.0f, 100.0f, 0.0f)})
    for (int ch = 0; ch < 3; ++ch) {
      float last = -1.0f;
      bool white = false;
      for (float x = 1e-6f; x < 1e30f; x *= 1.05f) {
        Rgb c = base;
        c[ch] = x;
        const Rgb y = tm.apply(c);
        for (int k = 0; k < 3; ++k) ASSERT_TRUE(std::isfinite(y[k]) && y[k] >= 0.0f && y[k] <= 1.0f);
        if (!white) {
          ASSERT_GE(y[ch], last) << "channel " << ch << " at " << x;
        }
        EXPECT_GE(y[ch], 0.995f * std::max(last, 0.0f)) << "channel " << ch << " at " << x;
        white = white || y[ch] >= 1.0f;
        last = std::max(last, y[ch]);
      }
      EXPECT_GT(last, 0.996f) << "channel " << ch;
    }
  // NaN and infinities (before the exposure's clamp) stay out.
  const Rgb odd = tm.apply(Rgb(std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -1.0f));
  EXPECT_EQ(odd, tm.apply(Rgb(0.0f, 1e6f, 0.0f)));
}

// Filter importance sampling: offsets follow the filter's density (checked by chi-square against
// the Gaussian, sigma 0.5, truncated at radius 1.5, integrated exactly over each bin).
TEST(PixelFilter, GaussianOffsetsFollowTheFilter) {
  const PixelFilter f(PixelFilter::Type::Gaussian);
  const double sigma = 0.5, r = 1.5;
  const double norm = std::erf(r / (std::sqrt(2.0) * sigma));
  constexpr int kBins = 60, kN = 1000000;
  std::vector<double> observed(kBins, 0.0), expected(kBins);
  Pcg32 rng(17);
  for (int i = 0; i < kN; ++i) {
    const float x = f.sample_1d(rng.next_float());
    ASSERT_GE(x, -1.5f);
    ASSERT_LE(x, 1.5f);
    observed[std::min(kBins - 1, static_cast<int>((x + r) / (2 * r) * kBins))] += 1;
  }
  for (int b = 0; b < kBins; ++b) {
    const double a = -r + 2 * r * b / kBins, c = a + 2 * r / kBins;
    expected[b] = kN * 0.5 * (std::erf(c / (std::sqrt(2.0) * sigma)) - std::erf(a / (std::sqrt(2.0) * sigma))) / norm;
  }
  const Chi2Result res = chi2_test_counts(observed, expected);
  EXPECT_TRUE(res.passed) << res.message;
  // Tent: triangle density on [-1, 1].
  const PixelFilter t(PixelFilter::Type::Tent);
  std::fill(observed.begin(), observed.end(), 0.0);
  for (int i = 0; i < kN; ++i)
    observed[std::min(kBins - 1, static_cast<int>((t.sample_1d(rng.next_float()) + 1.0) / 2.0 * kBins))] += 1;
  for (int b = 0; b < kBins; ++b) {
    const double a = -1 + 2.0 * b / kBins, c = a + 2.0 / kBins;
    auto cdf = [](double x) { return x < 0 ? 0.5 * (1 + x) * (1 + x) : 1 - 0.5 * (1 - x) * (1 - x); };
    expected[b] = kN * (cdf(c) - cdf(a));
  }
  const Chi2Result rt = chi2_test_counts(observed, expected);
  EXPECT_TRUE(rt.passed) << rt.message;
}

}  // namespace
}  // namespace kozu::test
