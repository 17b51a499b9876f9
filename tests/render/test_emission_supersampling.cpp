// The visible emission supersampled apart (render/emission_supersampling.h) on an emitter whose slanted edge crosses
// every row of pixels, against each pixel's numerically integrated share of it (emitter_edge_scene.h).
#include "render/emission_supersampling.h"

#include "emitter_edge_scene.h"
#include "support/render_test.h"

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>

namespace kozu::test {
namespace {

constexpr int kRes = kEdgeRes, kSpp = 4;
constexpr float kLe = kEdgeLe;

// The edge scene (kDark), and the same edge with a grey wall right of it and the emitter's own surface grey too,
// both lit by a point light behind the camera (kLit): there the samples' light without the visible emission is not
// zero either.
const char* kDark = kEdgeScene;
const char* kLit = R"({
  "camera": {"type": "orthographic", "position": [0, 0, 5], "look_at": [0, 0, 0], "scale": 16,
             "resolution": [16, 16]},
  "render": {"filter": "box", "max_depth": 4},
  "materials": {"grey": {"type": "diffuse", "albedo": 0.5}},
  "lights": [{"type": "point", "position": [3, 2, 9], "intensity": 200}],
  "shapes": [{"type": "polygon", "material": "grey", "emission": [5, 5, 5],
              "vertices": [[-20, -20, 0], [-7.1, -20, 0], [7.7, 20, 0], [-20, 20, 0]]},
             {"type": "polygon", "material": "grey",
              "vertices": [[-30, -30, -1], [30, -30, -1], [30, 30, -1], [-30, 30, -1]]}]
})";

struct EdgeScene {
  std::unique_ptr<Scene> scene;
  std::unique_ptr<PathIntegrator> integrator;
};

EdgeScene load_edge(const char* text) {
  EdgeScene s;
  s.scene = load_scene_text(text, "edge.json", ".");
  s.integrator = std::make_unique<PathIntegrator>(*s.scene, s.scene->settings.max_depth);
  return s;
}

RenderSettings settings_for(const Scene& scene, uint64_t seed, int threads = 0) {
  RenderSettings o;
  o.spp = kSpp;
  o.seed = seed;
  o.threads = threads;
  o.filter = scene.settings.filter;
  return o;
}

// Enough budget for every edge pixel of this small image.
EmissionSupersamplingSettings generous() {
  EmissionSupersamplingSettings s;
  s.budget = 16.0;
  return s;
}

// A render with the visible emission supersampled apart (`apart`) or not; its image's red channel.
std::vector<float> render_image(const EdgeScene& s, uint64_t seed, bool apart,
                                EmissionSupersamplingStats* stats = nullptr, int threads = 0) {
  Film film(kRes, kRes);
  RenderSettings o = settings_for(*s.scene, seed, threads);
  o.emission_supersampling = false;  // decided here, with the test's budget
  if (apart) {
    const std::atomic<bool> never{false};
    film.set_emission_apart(supersample_emission(*s.scene, *s.integrator, film, o, never, generous(), stats));
  }
  render(*s.scene, *s.integrator, film, o);
  const std::vector<float> rgb = film.rgb();
  std::vector<float> red(kRes * kRes);
  for (size_t i = 0; i < red.size(); ++i) red[i] = rgb[3 * i];
  return red;
}

bool on_edge(float truth) { return truth > 0.0f && truth < kLe; }

// Per pixel, the mean and the variance of the mean over renders of seeds 1 .. n.
struct SeedStats {
  std::vector<double> mean, var_of_mean;
};
SeedStats over_seeds(const EdgeScene& s, int n, bool apart) {
  SeedStats st{std::vector<double>(kRes * kRes, 0.0), std::vector<double>(kRes * kRes, 0.0)};
  std::vector<double> sq(kRes * kRes, 0.0);
  for (int seed = 1; seed <= n; ++seed) {
    const std::vector<float> img = render_image(s, static_cast<uint64_t>(seed), apart);
    for (size_t i = 0; i < img.size(); ++i) {
      st.mean[i] += img[i];
      sq[i] += double(img[i]) * img[i];
    }
  }
  for (size_t i = 0; i < sq.size(); ++i) {
    st.mean[i] /= n;
    st.var_of_mean[i] = std::max(0.0, sq[i] / n - st.mean[i] * st.mean[i]) / (n - 1);
  }
  return st;
}

TEST(EmissionSupersampling, EdgePixelsAreUnbiasedAndLessNoisy) {
  const EdgeScene s = load_edge(kDark);
  const std::vector<float> truth = true_edge_emission(*s.scene);
  constexpr int kSeeds = 24;
  const SeedStats on = over_seeds(s, kSeeds, true), off = over_seeds(s, kSeeds, false);
  double err_on = 0.0, err_off = 0.0;
  int edge = 0;
  for (size_t i = 0; i < truth.size(); ++i) {
    if (!on_edge(truth[i])) {
      EXPECT_NEAR(on.mean[i], truth[i], 1e-5) << i;  // wholly inside or outside: exact either way
      continue;
    }
    ++edge;
    // Unbiased: within 4.5 standard errors of the numerical truth (whose own error, a 64 × 64 grid's, is far below).
    // The seeds' spread underestimates the error of a sliver of coverage that few samples hit: the standard error
    // of 64 independent samples a render (more than a stratified estimate's) bounds it from below.
    const double p = truth[i] / kLe;
    const double se = std::max(std::sqrt(on.var_of_mean[i]), kLe * std::sqrt(p * (1.0 - p) / (64.0 * kSeeds)));
    EXPECT_LT(std::abs(on.mean[i] - truth[i]), 4.5 * se) << "pixel " << i << " truth " << truth[i];
    err_on += on.var_of_mean[i];
    err_off += off.var_of_mean[i];
  }
  ASSERT_GE(edge, kRes);
  // 64 samples against 4 of a stratified estimate of a straight edge: the variance falls by about 16^1.5 (64);
  // asserted 10, beyond what 16 × independent samples would give.
  EXPECT_LT(err_on, err_off / 10.0) << "edge pixels " << edge;
}

TEST(EmissionSupersampling, KeepsTheRestOfTheLight) {
  // Lit surfaces on both sides of the edge: a pixel apart takes its samples without the visible emission, and the
  // image adds the estimate back; the means must agree with renders that keep it in the samples.
  const EdgeScene s = load_edge(kLit);
  constexpr int kSeeds = 24;
  const SeedStats on = over_seeds(s, kSeeds, true), off = over_seeds(s, kSeeds, false);
  EmissionSupersamplingStats stats;
  render_image(s, 1, true, &stats);
  ASSERT_GE(stats.pixels, static_cast<uint64_t>(kRes));
  double lit = 0.0;
  for (size_t i = 0; i < on.mean.size(); ++i) {
    const double se = std::sqrt(on.var_of_mean[i] + off.var_of_mean[i]) + 1e-4;
    EXPECT_LT(std::abs(on.mean[i] - off.mean[i]), 4.5 * se) << "pixel " << i;
    lit += off.mean[i];
  }
  EXPECT_GT(lit / on.mean.size(), 0.1);  // the light reaches the pixels: the test sees the rest of L
}

TEST(EmissionSupersampling, IsDeterministicAndKeepsWithinItsBudget) {
  const EdgeScene s = load_edge(kDark);
  EmissionSupersamplingStats one, two;
  EXPECT_EQ(render_image(s, 3, true, &one, 1), render_image(s, 3, true, &two, 2));
  EXPECT_EQ(one.pixels, two.pixels);
  EXPECT_EQ(one.samples, two.samples);
  // The default budget: a quarter of the render's samples, k = max(64, 8 × 4) each, so 4 of the edge pixels.
  Film film(kRes, kRes);
  const RenderSettings o = settings_for(*s.scene, 3);
  const std::atomic<bool> never{false};
  EmissionSupersamplingStats stats;
  const auto values = supersample_emission(*s.scene, *s.integrator, film, o, never, {}, &stats);
  EXPECT_EQ(values.size(), 4u);
  EXPECT_EQ(stats.samples, 1u * kRes * kRes + 4u * 64u);  // the pilot's one a pixel, then 64 each
  for (size_t i = 1; i < values.size(); ++i) EXPECT_LT(values[i - 1].index, values[i].index);
  // A raised stop flag: nothing chosen, nothing apart.
  const std::atomic<bool> stopped{true};
  EXPECT_TRUE(supersample_emission(*s.scene, *s.integrator, film, o, stopped).empty());
}

// The pilot looks for the visible emission's jumps; it needs no low-variance estimate of the rest, so "ltc" takes no
// control variate there (its probes and closed form at every pixel were 4 % of the render of the stained glass
// lit directly, docs/lights.md). A two-sided emitter lights the grey wall behind it, a candidate of the control
// variate at every wall pixel the camera sees; one bounce: the "ltc" pilot's first vertex draws the numbers of the
// "sample" one, so it must trace the same rays, where the probes would add two shadow rays at each wall pixel.
TEST(EmissionSupersampling, ThePilotTakesNoControlVariate) {
  const auto scene = load_scene_text(R"({
  "camera": {"type": "orthographic", "position": [0, 0, 5], "look_at": [0, 0, 0], "scale": 16,
             "resolution": [16, 16]},
  "render": {"filter": "box", "max_depth": 1},
  "materials": {"grey": {"type": "diffuse", "albedo": 0.5}},
  "shapes": [{"type": "polygon", "material": "grey", "emission": [5, 5, 5], "two_sided": true,
              "vertices": [[-20, -20, 0], [-7.1, -20, 0], [7.7, 20, 0], [-20, 20, 0]]},
             {"type": "polygon", "material": "grey",
              "vertices": [[-30, -30, -1], [30, -30, -1], [30, 30, -1], [-30, 30, -1]]}]
})",
                                     "edge.json", ".");
  const std::atomic<bool> never{false};
  std::array<RayCounters, 2> rays;
  std::array<uint64_t, 2> pixels{};
  for (const DirectLighting direct : {DirectLighting::Sample, DirectLighting::Ltc}) {
    const PathIntegrator integrator(*scene, scene->settings.max_depth, direct);
    Film film(kRes, kRes);
    EmissionSupersamplingStats stats;
    supersample_emission(*scene, integrator, film, settings_for(*scene, 5), never, generous(), &stats);
    const size_t i = direct == DirectLighting::Ltc;
    rays[i] = stats.rays;
    pixels[i] = stats.pixels;
  }
  EXPECT_GT(pixels[0], 0u);
  EXPECT_EQ(pixels[1], pixels[0]);
  EXPECT_GT(rays[0].shadow_rays, 0u);
  EXPECT_EQ(rays[1].shadow_rays, rays[0].shadow_rays);
  EXPECT_EQ(rays[1].total(), rays[0].total());
}

TEST(EmissionSupersampling, RenderDecidesOncePerFilm) {
  const EdgeScene s = load_edge(kDark);
  RenderSettings o = settings_for(*s.scene, 5);
  o.spp = 15;  // below EmissionSupersamplingSettings::min_spp: not worth its pilot
  Film few(kRes, kRes);
  EXPECT_EQ(render(*s.scene, *s.integrator, few, o).emission.pixels, 0u);
  EXPECT_FALSE(few.emission_decided());
  o.spp = 16;
  Film film(kRes, kRes);
  const RenderResult r = render(*s.scene, *s.integrator, film, o);
  EXPECT_TRUE(film.emission_decided());
  EXPECT_GT(r.emission.pixels, 0u);
  EXPECT_EQ(r.emission.pixels, film.emission_apart_values().size());
  // Not with the denoiser's features (it splits the visible emission itself), nor when turned off.
  Film featured(kRes, kRes);
  featured.enable_features();
  EXPECT_EQ(render(*s.scene, *s.integrator, featured, o).emission.pixels, 0u);
  EXPECT_TRUE(featured.emission_apart_values().empty());
  o.emission_supersampling = false;
  Film off(kRes, kRes);
  EXPECT_EQ(render(*s.scene, *s.integrator, off, o).emission.pixels, 0u);
  EXPECT_FALSE(off.emission_decided());
}

TEST(EmissionSupersampling, PlansByTheTimeLeftUnderADeadline) {
  // A render bounded by time alone has no sample count: the pilot's pace and the time left stand in for it.
  const EdgeScene s = load_edge(kDark);
  RenderSettings o = settings_for(*s.scene, 5);
  o.spp = 0;
  Film film(kRes, kRes);
  EXPECT_FALSE(emission_supersampling_applies(film, o));  // nothing to plan by
  EXPECT_TRUE(emission_supersampling_applies(film, o, {}, true));
  const std::atomic<bool> never{false};
  using Clock = std::chrono::steady_clock;
  // Ten seconds left: thousands of samples a pixel at this tiny image's pace, so edge pixels are chosen.
  EmissionSupersamplingStats stats;
  const auto before = Clock::now();
  const auto values =
      supersample_emission(*s.scene, *s.integrator, film, o, never, {}, &stats, before + std::chrono::seconds(10));
  EXPECT_GE(stats.spp, EmissionSupersamplingSettings{}.min_spp);
  EXPECT_GT(values.size(), 0u);
  EXPECT_EQ(stats.pixels, values.size());
  // The plan is the time left over the pilot's time: the pilot took at most this whole call, and at least 10 s less
  // that was left after it.
  const double took = std::chrono::duration<double>(Clock::now() - before).count();
  EXPECT_GE(double(stats.spp), std::floor((10.0 - took) / took));
  // No time left: below min_spp, nothing chosen.
  EmissionSupersamplingStats late;
  EXPECT_TRUE(supersample_emission(*s.scene, *s.integrator, film, o, never, {}, &late, Clock::now()).empty());
  EXPECT_LT(late.spp, EmissionSupersamplingSettings{}.min_spp);
  // A render under a time limit alone decides for its film, and the image keeps every pixel finite. (The limit
  // leaves the pilot, which gives up after 1/17 of it, room under AddressSanitizer on a busy machine.)
  o.time_limit = 1.5;
  Film timed(kRes, kRes);
  const RenderResult r = render(*s.scene, *s.integrator, timed, o);
  EXPECT_TRUE(timed.emission_decided());
  EXPECT_GE(r.emission.spp, EmissionSupersamplingSettings{}.min_spp);
  EXPECT_GT(r.emission.pixels, 0u);
  EXPECT_EQ(r.emission.pixels, timed.emission_apart_values().size());
  for (const float v : timed.rgb()) EXPECT_TRUE(std::isfinite(v));
}

TEST(EmissionSupersampling, LeavesEdgesAgainstAsBrightASurface) {
  // A white furnace: a white diffuse sphere under a uniform sky of radiance 1 returns 1 from every path, so at its
  // silhouette the sky and the sphere are equally bright and splitting the sky off would add variance: no pixel is
  // chosen, and every pixel stays exactly 1.
  const EdgeScene s = load_edge(R"({
    "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 35, "resolution": [16, 16]},
    "render": {"filter": "box", "max_depth": 64},
    "materials": {"white": {"type": "diffuse", "albedo": 1}},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "white"}],
    "lights": [{"type": "environment", "radiance": 1}]
  })");
  EmissionSupersamplingStats stats;
  const std::vector<float> img = render_image(s, 7, true, &stats);
  EXPECT_EQ(stats.pixels, 0u);
  for (float v : img) EXPECT_NEAR(v, 1.0f, 1e-3f);
}

}  // namespace
}  // namespace kozu::test
