// "direct": "ltc" and "ltc-preview" (integrators/path.cpp ltc_direct, Heitz et al. 2016 with a control variate):
//  - on an unshadowed Lambertian floor "ltc" is exact with one sample: each estimate equals Lambert's closed form
//    for the quad light (an independent quadrature over the light), where "sample" is visibly noisy;
//  - with an occluder and a rough gold floor its mean equals "sample"'s within noise at points in light, penumbra
//    and umbra (unbiased), where "ltc-preview" (no shadows) is rejected by the same test;
//  - so is it under a textured light, whose closed form is only Heitz et al. 2016's approximation (eqs. 12–15);
//  - whole images (glossy and diffuse receivers, several bounces, so emission found by BSDF rays is counted once)
//    agree within noise.
#include "support/render_test.h"

#include "core/gauss_legendre.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>
#include <vector>

namespace kozu::test {
namespace {

// A 0.6 x 0.4 quad light facing down at height 1 over a floor at y = 0, an optional occluder between them; `lights`:
// the scene's other lights (a "lights" array's items).
std::string ltc_scene(const std::string& floor_material, bool occluder, const std::string& direct, int max_depth,
                      const std::string& emission = "[4, 3, 2]", const std::string& lights = "") {
  return fmt::format(R"({{
  "camera": {{ "position": [0, 2.5, 3], "look_at": [0, 0, 0], "fov": 40, "resolution": [40, 30] }},
  "lights": [{lights}],
  "render": {{ "max_depth": {max_depth}, "direct": "{direct}", "filter": "box" }},
  "materials": {{
    "floor": {floor},
    "white": {{ "type": "diffuse", "albedo": 0.6 }},
    "black": {{ "type": "diffuse", "albedo": 0 }}
  }},
  "shapes": [
    {{ "type": "quad", "material": "floor", "vertices": [[-4, 0, -4], [-4, 0, 4], [4, 0, 4], [4, 0, -4]] }},
    {{ "type": "quad", "material": "white", "vertices": [[-4, 0, -2], [4, 0, -2], [4, 3, -2], [-4, 3, -2]] }},
    {occluder}
    {{ "type": "quad", "material": "black", "emission": {emission},
      "vertices": [[-0.3, 1, -0.2], [0.3, 1, -0.2], [0.3, 1, 0.2], [-0.3, 1, 0.2]] }}
  ]
}})",
                     fmt::arg("max_depth", max_depth), fmt::arg("direct", direct), fmt::arg("floor", floor_material),
                     fmt::arg("emission", emission), fmt::arg("lights", lights),
                     fmt::arg("occluder", occluder ? R"({ "type": "quad", "material": "white",
      "vertices": [[-0.1, 0.5, -0.5], [-0.1, 0.5, 0.5], [0.5, 0.5, 0.5], [0.5, 0.5, -0.5]] },)"
                                                   : ""));
}

// One radiance estimate along the ray from `from` to the floor point p: sample index i of pixel (px, 0).
Rgb estimate(const Scene& scene, DirectLighting direct, const Vec3& from, const Vec3& p, uint32_t px, uint32_t i) {
  const PathIntegrator integrator(scene, 1, direct);
  Sampler sampler(3);
  sampler.start(px, 0, i);
  Arena arena;
  RayCounters counters;
  StopFlag stop(false);
  return integrator.li(Ray{from, glm::normalize(p - from), kInfinity}, sampler, arena, counters, stop);
}

// (1/π) ∫_light cos θ_p cos θ_l / r² dA at the floor point p (normal +y), by Gauss–Legendre over the quad.
double lambert_closed_form(const Vec3d& p) {
  const GaussLegendre gl(24);
  const int panels = 8;
  double sum = 0.0;
  for (int a = 0; a < panels; ++a)
    for (int b = 0; b < panels; ++b)
      for (size_t i = 0; i < gl.x.size(); ++i)
        for (size_t j = 0; j < gl.x.size(); ++j) {
          const double x = -0.3 + 0.6 * (a + 0.5 * (gl.x[i] + 1.0)) / panels;
          const double z = -0.2 + 0.4 * (b + 0.5 * (gl.x[j] + 1.0)) / panels;
          const Vec3d d = Vec3d(x, 1.0, z) - p;
          const double r2 = glm::dot(d, d);
          const double cos_p = d.y / std::sqrt(r2), cos_l = d.y / std::sqrt(r2);
          sum += gl.w[i] * gl.w[j] * 0.25 * (0.6 / panels) * (0.4 / panels) * cos_p * cos_l / r2;
        }
  return sum / kPi;
}

// Each estimate at points of the unshadowed Lambertian floor equals Lambert's closed form for the quad light (times
// the floor's albedo 0.5), within 1e-4, where "sample"'s single estimates scatter by more than 1e-2. With
// `other_light`, a point light under the floor (it lights none of these points) is chosen for light sampling more
// often than the quad: the control variate's closed form is added whichever light was chosen, so the estimates stay
// exact.
void expect_exact_with_one_sample(const std::string& other_light) {
  const auto scene =
      load_scene_text(ltc_scene(R"({ "type": "diffuse", "albedo": 0.5 })", false, "ltc", 1, "[4, 3, 2]", other_light),
                      "scene.json", ".");
  const Rgb Le(4.0f, 3.0f, 2.0f);
  double worst = 0.0, worst_sampled = 0.0;
  int n = 0;
  for (float x = -1.4f; x <= 1.41f; x += 0.35f)
    for (float z = -1.0f; z <= 1.01f; z += 0.5f) {
      const Vec3 p(x, 0.0f, z);
      const double expected = 0.5 * lambert_closed_form(Vec3d(p));
      const Vec3 from = p + Vec3(0.2f, 0.4f, 0.1f);  // below the light: nothing between the eye and p
      for (uint32_t i = 0; i < 3; ++i) {
        const Rgb ltc = estimate(*scene, DirectLighting::Ltc, from, p, static_cast<uint32_t>(n), i);
        const Rgb sampled = estimate(*scene, DirectLighting::Sample, from, p, static_cast<uint32_t>(n), i);
        for (int c = 0; c < 3; ++c) {
          const double e = expected * Le[c];
          const double err = std::abs(ltc[c] - e) / e;
          worst = std::max(worst, err);
          worst_sampled = std::max(worst_sampled, std::abs(sampled[c] - e) / e);
          EXPECT_LT(err, 1e-4) << fmt::format("p = ({}, {}), sample {}, channel {}: {} vs {}", x, z, i, c, ltc[c], e);
        }
      }
      ++n;
    }
  // The same one-sample check would fail for light sampling: its single estimates scatter.
  EXPECT_GT(worst_sampled, 1e-2);
  std::printf("%d points x 3 samples: worst relative error %.2e with ltc, %.2e with one light sample\n", n, worst,
              worst_sampled);
}

TEST(PathLtc, ExactWithOneSampleOnAnUnshadowedLambertianFloor) { expect_exact_with_one_sample(""); }

// The point light's power 4π 0.25 against the quad's π 3 0.24: the quad is chosen 42 % of the time.
TEST(PathLtc, ExactWithOneSampleWhicheverLightIsChosen) {
  expect_exact_with_one_sample(R"({ "type": "point", "position": [0, -1, 0], "intensity": [0.25, 0.25, 0.25] })");
}

struct MeanEstimate {
  Rgb mean{0.0f}, standard_error{0.0f};
};

MeanEstimate mean_of(const Scene& scene, DirectLighting direct, const Vec3& from, const Vec3& p, int n) {
  Vec3d sum(0.0), sum2(0.0);
  for (int i = 0; i < n; ++i) {
    const Rgb v = estimate(scene, direct, from, p, 0, static_cast<uint32_t>(i));
    for (int c = 0; c < 3; ++c) {
      sum[c] += v[c];
      sum2[c] += double(v[c]) * v[c];
    }
  }
  MeanEstimate m;
  for (int c = 0; c < 3; ++c) {
    const double mean = sum[c] / n;
    m.mean[c] = static_cast<float>(mean);
    m.standard_error[c] = static_cast<float>(std::sqrt(std::max(0.0, sum2[c] / n - mean * mean) / (n - 1)));
  }
  return m;
}

// |a − b| within z standard errors of the difference, per channel.
bool agree(const MeanEstimate& a, const MeanEstimate& b, double z) {
  for (int c = 0; c < 3; ++c) {
    const double se = std::hypot(double(a.standard_error[c]), double(b.standard_error[c]));
    if (std::abs(double(a.mean[c]) - double(b.mean[c])) > z * se + 1e-6 * std::abs(double(b.mean[c]))) return false;
  }
  return true;
}

// "ltc" at the points of a floor against "sample"; "ltc-preview" must fail the same comparison at least
// min_preview_rejected times (the test can tell a biased estimator).
void expect_unbiased(const Scene& scene, const std::vector<float>& xs, int min_preview_rejected) {
  const int n = kSanitized ? 4096 : 16384;
  int preview_rejected = 0;
  for (const float x : xs) {
    const Vec3 p(x, 0.0f, 0.05f);
    const Vec3 from = p + Vec3(-0.25f, 0.3f, 0.05f);  // under the occluder's plane, left of the occluder
    const MeanEstimate ltc = mean_of(scene, DirectLighting::Ltc, from, p, n);
    const MeanEstimate sampled = mean_of(scene, DirectLighting::Sample, from, p, n);
    const MeanEstimate preview = mean_of(scene, DirectLighting::LtcPreview, from, p, n);
    EXPECT_TRUE(agree(ltc, sampled, 4.5))
        << fmt::format("x = {}: ltc {:.5f} {:.5f} {:.5f} (± {:.5f}), sample {:.5f} {:.5f} {:.5f} (± {:.5f})", x,
                       ltc.mean.r, ltc.mean.g, ltc.mean.b, ltc.standard_error.g, sampled.mean.r, sampled.mean.g,
                       sampled.mean.b, sampled.standard_error.g);
    preview_rejected += !agree(preview, sampled, 4.5);
    std::printf("x = %5.2f: sample %.5f ± %.5f, ltc %.5f ± %.5f, ltc-preview %.5f (green)\n", x, sampled.mean.g,
                sampled.standard_error.g, ltc.mean.g, ltc.standard_error.g, preview.mean.g);
  }
  EXPECT_GE(preview_rejected, min_preview_rejected);
}

TEST(PathLtc, UnbiasedWithShadowsOnARoughGoldFloor) {
  // Gold, GGX roughness 0.3, compensated: the lobes miss the Fresnel's colour shift, the fit's error and the
  // coupled lobe's shape, and the occluder (y = 0.5, x in [-0.1, 0.5]) shadows part of the light.
  const std::string gold = R"({ "type": "conductor", "metal": "Au", "roughness": 0.3, "multiscatter": "compensated" })";
  const auto scene = load_scene_text(ltc_scene(gold, true, "ltc", 1), "scene.json", ".");
  // x = -0.6 sees all of the light, x = 0.1 and 0.45 are in the umbra, the others in penumbrae. The preview,
  // which ignores the occluder, fails in the shadows.
  expect_unbiased(*scene, {-0.6f, -0.25f, -0.1f, 0.1f, 0.45f, 0.8f}, 3);
}

TEST(PathLtc, UnbiasedWithATexturedLight) {
  // A checker of two colours 8:1 apart on the light (lights/ltc_texture.h) over a glossy floor: the closed form
  // takes each lobe's prefiltered fetch I_L, an approximation, and the residual the texture's true values.
  const std::string steel = R"({ "type": "conductor", "roughness": 0.15, "eta": 2.5, "k": 3.1 })";
  const std::string checker = R"({ "type": "checker", "scale": [3, 2], "a": [8, 2, 1], "b": [1, 2, 6] })";
  const auto scene = load_scene_text(ltc_scene(steel, true, "ltc", 1, checker), "scene.json", ".");
  expect_unbiased(*scene, {-0.6f, -0.4f, -0.25f, -0.1f, 0.1f, 0.8f}, 2);
}

// The two films' image means agree within 5 standard errors of their difference in every channel; prints the red
// channel's, labelled.
void expect_equal_means(const Film& film_a, const Film& film_b, const char* a_name, const char* b_name,
                        const std::string& what = "") {
  const ImageStats a = image_stats(film_a), b = image_stats(film_b);
  for (int c = 0; c < 3; ++c) {
    const double se = std::hypot(double(a.standard_error[c]), double(b.standard_error[c]));
    EXPECT_NEAR(a.mean[c], b.mean[c], 5.0 * se) << what << " channel " << c;
  }
  std::printf("image mean (red): %s %.5f ± %.5f, %s %.5f ± %.5f\n", a_name, a.mean.r, a.standard_error.r, b_name,
              b.mean.r, b.standard_error.r);
}

TEST(PathLtc, ImagesEqualLightSamplingWithinNoise) {
  // Several bounces, so a BSDF ray that finds the light after an "ltc" vertex must not count it a second time.
  const std::string glossy =
      R"({ "type": "conductor", "roughness": 0.2, "eta": [0.2, 0.4, 1.4], "k": [3.6, 2.5, 1.9] })";
  const std::string diffuse = R"({ "type": "diffuse", "albedo": [0.7, 0.5, 0.3] })";
  const std::string checker = R"({ "type": "checker", "scale": [3, 2], "a": [8, 2, 1], "b": [1, 2, 6] })";
  for (const auto& [floor, emission] : {std::pair{glossy, std::string("[4, 3, 2]")},
                                        std::pair{diffuse, std::string("[4, 3, 2]")}, std::pair{glossy, checker}}) {
    const int spp = kSanitized ? 32 : 128;
    const TestRender ltc = render_json(ltc_scene(floor, true, "ltc", 4, emission), spp, 0, 5);
    const TestRender sampled = render_json(ltc_scene(floor, true, "sample", 4, emission), spp, 0, 6);
    expect_equal_means(ltc.film, sampled.film, "ltc", "sample", floor + " " + emission);
  }
}

// "ltc" learns its coefficient from the neighbours' pilot samples (PixelMemory, pooled once), never from
// the pixel's own: those are stratified against the sample's own directions, and a coefficient learnt from them
// biases the control variate. A glossy floor under the half-shadowed light at few samples a pixel, where each pixel's
// first samples weigh most, in light, penumbra and umbra: the image mean equals light sampling's within the noise,
// and the probes' shadow rays are saved.
TEST(PathLtc, PixelMemoryLeavesImagesUnbiased) {
  const std::string glossy = R"({ "type": "conductor", "roughness": 0.1, "eta": 1.5, "k": 3.0 })";
  std::string ltc_json = ltc_scene(glossy, true, "ltc", 1), sample_json = ltc_scene(glossy, true, "sample", 1);
  for (std::string* json : {&ltc_json, &sample_json}) {
    const size_t at = json->find("[40, 30]");
    json->replace(at, 8, "[160, 120]");
  }
  const int spp = kSanitized ? 4 : 8;
  const TestRender ltc = render_json(ltc_json, spp, 0, 11);
  const TestRender sampled = render_json(sample_json, spp, 0, 12);
  expect_equal_means(ltc.film, sampled.film, "ltc", "sample");
  // The memory is used: after a pixel's pilot samples the probes' two shadow rays are traced only where the
  // neighbours have not seen the light, so "ltc" traces about 1 + 2 kPilotSamples / spp shadow rays for each of
  // "sample"'s (3 without the memory).
  const double ratio = double(ltc.result.rays.shadow_rays) / double(sampled.result.rays.shadow_rays);
  EXPECT_LT(ratio, 1.0 + (2.0 * PixelMemory::kPilotSamples + 1.0) / spp);
  std::printf("shadow rays: ltc / sample = %.3f at %d spp\n", ratio, spp);
}

TEST(PathLtc, ImagesEqualLightSamplingWithSeveralLights) {
  // A bright quad light and a dim one (each takes the control variate where the light hierarchy chooses it more
  // likely than the other), a sphere and a point light: the control variate's closed form is added whichever light
  // was chosen, and BSDF rays after an "ltc" vertex meet every light with the usual weights (Path::emission).
  const auto scene = [](const char* direct) {
    return fmt::format(R"({{
  "camera": {{ "position": [0, 2.5, 3], "look_at": [0, 0, 0], "fov": 45, "resolution": [40, 30] }},
  "render": {{ "max_depth": 3, "direct": "{direct}", "filter": "box" }},
  "materials": {{
    "floor": {{ "type": "conductor", "roughness": 0.25, "eta": [0.2, 0.4, 1.4], "k": [3.6, 2.5, 1.9] }},
    "white": {{ "type": "diffuse", "albedo": 0.6 }},
    "black": {{ "type": "diffuse", "albedo": 0 }}
  }},
  "shapes": [
    {{ "type": "quad", "material": "floor", "vertices": [[-4, 0, -4], [-4, 0, 4], [4, 0, 4], [4, 0, -4]] }},
    {{ "type": "quad", "material": "white", "vertices": [[-4, 0, -2], [4, 0, -2], [4, 3, -2], [-4, 3, -2]] }},
    {{ "type": "quad", "material": "white",
      "vertices": [[-0.1, 0.5, -0.5], [-0.1, 0.5, 0.5], [0.5, 0.5, 0.5], [0.5, 0.5, -0.5]] }},
    {{ "type": "quad", "material": "black", "emission": [6, 4.5, 3],
      "vertices": [[-0.3, 1, -0.2], [0.3, 1, -0.2], [0.3, 1, 0.2], [-0.3, 1, 0.2]] }},
    {{ "type": "quad", "material": "black", "emission": [0.6, 0.8, 1.2],
      "vertices": [[-2.5, 1.5, -1.9], [-1.5, 1.5, -1.9], [-1.5, 2.2, -1.9], [-2.5, 2.2, -1.9]] }},
    {{ "type": "sphere", "material": "black", "emission": [2, 2, 2], "center": [1.8, 0.6, -1], "radius": 0.15 }}
  ],
  "lights": [ {{ "type": "point", "position": [-1.5, 1.2, 1], "intensity": [0.5, 0.5, 0.4] }} ]
}})",
                       fmt::arg("direct", direct));
  };
  const int spp = kSanitized ? 128 : 1024;
  const TestRender ltc = render_json(scene("ltc"), spp, 0, 7);
  const TestRender sampled = render_json(scene("sample"), spp, 0, 8);
  expect_equal_means(ltc.film, sampled.film, "ltc", "sample");
}

// Without an analytic, untextured polygon light no vertex can take the control variate, and "ltc" is "sample" to
// the random number: the same image bit for bit and the same rays, no signed samples, no pixel memory (nothing of the
// mode's cost in a scene it cannot help). Lights: a textured quad (not a candidate) and a point light.
TEST(PathLtc, IsSampleWhereNoLightCanTakeTheControlVariate) {
  const auto scene = [](const char* direct) {
    return ltc_scene(R"({ "type": "conductor", "roughness": 0.25, "eta": [0.2, 0.4, 1.4], "k": [3.6, 2.5, 1.9] })",
                     false, direct, 3, R"({ "type": "checker", "scale": [3, 2], "a": [8, 2, 1], "b": [1, 2, 6] })",
                     R"({ "type": "point", "position": [-1.5, 1.2, 1], "intensity": [0.5, 0.5, 0.4] })");
  };
  const TestRender ltc = render_json(scene("ltc"), 8, 0, 3);
  const TestRender sampled = render_json(scene("sample"), 8, 0, 3);
  const PathIntegrator integrator(*ltc.scene, 3, DirectLighting::Ltc);
  EXPECT_FALSE(integrator.signed_samples());
  EXPECT_FALSE(integrator.pixel_memory());
  EXPECT_EQ(ltc.result.rays.total(), sampled.result.rays.total());
  int differ = 0;
  for (int y = 0; y < ltc.film.height(); ++y)
    for (int x = 0; x < ltc.film.width(); ++x) differ += ltc.film.mean(x, y) != sampled.film.mean(x, y);
  EXPECT_EQ(differ, 0);
  // And with a polygon light that can take it, the mode is on.
  const std::string json = ltc_scene(R"({ "type": "diffuse", "albedo": 0.5 })", false, "ltc", 1);
  const TestRender with_quad = render_json(json, 1, 0, 3);
  const PathIntegrator on(*with_quad.scene, 1, DirectLighting::Ltc);
  EXPECT_TRUE(on.signed_samples());
  EXPECT_TRUE(on.pixel_memory());
}

// The gold floor under the quad light, half in the occluder's shadow, under "ltc" with two bounces.
std::string shadowed_gold_floor(float roughness) {
  return ltc_scene(fmt::format(R"({{ "type": "conductor", "roughness": {}, "eta": [0.2, 0.4, 1.4],
                                   "k": [3.6, 2.5, 1.9] }})",
                               roughness),
                   true, "ltc", 2);
}

// "ltc"'s pixel memory lives in the film (a checkpoint carries it, render/checkpoint.h): a render continued on the
// same film, at a whole pass or after a cancel that cut a pass short at any moment, gives the uninterrupted image bit
// for bit. It fails when the memory is not the film's (a fresh one per call), when a dropped sample's lessons are kept,
// or when a pass cut short is pooled (measured: one stop in three then differed).
TEST(PathLtc, AContinuedRenderIsTheUninterruptedOne) {
  const auto scene = load_scene_text(shadowed_gold_floor(0.3f), "scene.json", ".");
  const PathIntegrator integrator(*scene, 2, DirectLighting::Ltc);
  ASSERT_TRUE(integrator.pixel_memory());
  RenderSettings opt = scene->settings;
  opt.spp = 16;
  opt.seed = 4;
  opt.emission_supersampling = false;  // a checkpoint's renders do without (render/emission_supersampling.h)
  const Vec2i res = scene->camera.resolution();
  Film whole(res.x, res.y);
  render(*scene, integrator, whole, opt);
  const auto same = [&](const Film& film) {
    int differ = 0;
    for (int y = 0; y < res.y; ++y)
      for (int x = 0; x < res.x; ++x) differ += film.mean(x, y) != whole.mean(x, y) || film.taken(x, y) != 16;
    return differ;
  };
  // Stopped at 3 samples, then continued.
  {
    Film film(res.x, res.y);
    RenderSettings first = opt;
    first.spp = 3;
    render(*scene, integrator, film, first);
    render(*scene, integrator, film, opt);
    EXPECT_EQ(same(film), 0) << "continued from 3 spp";
  }
  // Cancelled after 0 to 6 ms of sampling (mid-pass, at uneven counts), then continued: on 2 threads the 1200 pixels
  // take about 0.3 ms a sample each.
  int uneven = 0;
  for (int ms = 0; ms <= 6; ++ms) {
    Film film(res.x, res.y);
    RenderProgress progress;
    std::thread canceller([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(ms));
      progress.cancel = true;
    });
    render(*scene, integrator, film, opt, &progress);
    canceller.join();
    int lo = 1 << 30, hi = 0;
    for (int y = 0; y < res.y; ++y)
      for (int x = 0; x < res.x; ++x) {
        lo = std::min(lo, int(film.taken(x, y)));
        hi = std::max(hi, int(film.taken(x, y)));
      }
    uneven += lo < hi;
    render(*scene, integrator, film, opt);
    EXPECT_EQ(same(film), 0) << "cancelled at " << lo << " .. " << hi << " spp";
  }
  std::printf("%d of 7 cancels cut a pass short\n", uneven);
}

// A split render's pixels are the whole render's bit for bit under "ltc" (PixelMemory): what a pixel learns depends
// on its neighbours' pilot samples and the lattice's alone, which each part traces again where its film does not hold
// them. Crops (a window inside the image, one at its corner), the tiles of one rank of three (as MPI splits them),
// and parts of the samples that begin within, just after and after the pilots. It fails when a part pools without
// the pixels around its window (the crops' edges then differ), takes the image's variance from its own pixels, or
// pools a sample range's memories without the pilots before its range.
TEST(PathLtc, SplitRendersAreTheWholeRenderBitForBit) {
  const auto scene = load_scene_text(shadowed_gold_floor(0.2f), "scene.json", ".");
  const PathIntegrator integrator(*scene, 2, DirectLighting::Ltc);
  RenderSettings opt = scene->settings;
  opt.spp = 6;
  opt.seed = 9;
  opt.tile_size = 8;
  opt.emission_supersampling = false;  // decided over the film's window (render/emission_supersampling.h)
  const Vec2i res = scene->camera.resolution();
  Film whole(res.x, res.y);
  const RenderResult all = render(*scene, integrator, whole, opt);
  ASSERT_GT(all.control_variate.pixels_taking, 0u);
  ASSERT_LT(all.control_variate.pixels_taking, all.control_variate.pixels) << "some pixels skip it, some take it";
  // The pixels of `part` that it rendered (all of them: every), against the whole render's.
  const auto differing = [&](const Film& part, const RenderSettings& o) {
    int differ = 0, compared = 0;
    for (int y = part.origin().y; y < part.origin().y + part.height(); ++y)
      for (int x = part.origin().x; x < part.origin().x + part.width(); ++x) {
        if (!renders_pixel(part, o, Vec2i(x, y))) continue;
        ++compared;
        differ += part.mean(x, y) != whole.mean(x, y);
      }
    EXPECT_GT(compared, 0);
    return differ;
  };
  for (const auto& [origin, size] : {std::pair{Vec2i(13, 9), Vec2i(11, 7)}, std::pair{Vec2i(0, 0), Vec2i(20, 12)},
                                     std::pair{Vec2i(25, 17), Vec2i(15, 13)}}) {
    Film crop(size.x, size.y, origin);
    render(*scene, integrator, crop, opt);
    EXPECT_EQ(differing(crop, opt), 0) << "crop at " << origin.x << ", " << origin.y;
  }
  for (int rank = 0; rank < 3; ++rank) {
    RenderSettings o = opt;
    o.tile_rank = rank;
    o.tile_ranks = 3;
    Film film(res.x, res.y);
    render(*scene, integrator, film, o);
    EXPECT_EQ(differing(film, o), 0) << "rank " << rank << " of 3";
  }
  for (const int split : {1, PixelMemory::kPilotSamples, PixelMemory::kPilotSamples + 1}) {
    RenderSettings first = opt, second = opt;
    first.spp = split;
    second.sample_begin = split;
    Film a(res.x, res.y), b(res.x, res.y);
    render(*scene, integrator, a, first);
    render(*scene, integrator, b, second);
    double worst = 0.0;
    for (int y = 0; y < res.y; ++y)
      for (int x = 0; x < res.x; ++x) {
        ASSERT_EQ(b.taken(x, y), uint64_t(opt.spp - split));
        const Vec3d merged =
            (Vec3d(a.mean(x, y)) * double(split) + Vec3d(b.mean(x, y)) * double(opt.spp - split)) / double(opt.spp);
        const Vec3d w(whole.mean(x, y));
        for (int c = 0; c < 3; ++c)
          worst = std::max(worst, std::abs(merged[c] - w[c]) / std::max(1e-6, std::abs(w[c])));
      }
    // The parts' float means, recombined: within float rounding of the whole's (a pixel that learnt otherwise
    // differs by its noise, percent).
    EXPECT_LT(worst, 1e-6) << "samples split at " << split;
  }
}

// RenderResult::control_variate (`--stats` "ltc"): how much of the image took the control variate. On the
// unshadowed Lambertian floor under the quad it removes all of the floor's noise, and only the pixels far from the
// light, whose little noise is not worth its cost, skip it (measured: 1045 of 1200 take it); under a bright sky that
// holds the noise, beside a dim quad, it removes too little to pay and every pixel skips it (0 take it);
// "sample" keeps no memory and reports nothing.
TEST(PathLtc, ReportsHowMuchOfTheImageTookTheControlVariate) {
  const auto run = [](const std::string& json) { return render_json(json, 16).result.control_variate; };
  const std::string lambert = R"({ "type": "diffuse", "albedo": 0.5 })";
  const ControlVariateStats paying = run(ltc_scene(lambert, false, "ltc", 1));
  const ControlVariateStats hidden = run(
      ltc_scene(lambert, false, "ltc", 1, "[0.05, 0.05, 0.05]", R"({ "type": "environment", "radiance": [2, 2, 2] })"));
  const ControlVariateStats none = run(ltc_scene(lambert, false, "sample", 1));
  std::printf("taking it: %llu and %llu of %llu pixels, a share %.3f and %.3f of the samples\n",
              (unsigned long long)paying.pixels_taking, (unsigned long long)hidden.pixels_taking,
              (unsigned long long)paying.pixels, paying.samples_taking / paying.samples,
              hidden.samples_taking / hidden.samples);
  EXPECT_EQ(paying.pixels, 40u * 30u);
  EXPECT_EQ(paying.samples, 40.0 * 30.0 * 16.0);
  EXPECT_GT(paying.pixels_taking, paying.pixels * 3 / 4);
  EXPECT_GT(paying.samples_taking, 0.5 * paying.samples);  // the floor fills most of the image
  EXPECT_LT(hidden.pixels_taking, hidden.pixels / 10);
  EXPECT_LT(hidden.samples_taking, 0.5 * paying.samples_taking);
  EXPECT_EQ(none.pixels, 0u);
}

// "light_sampling": "lobe" (integrators/lobe_light_sampler.h) against "light": the same image mean within the noise. A
// glossy floor and a glossy plastic box seen directly and in a mirror sphere (a specular chain: those vertices shape
// too), a quad light, a mesh emitter of two triangles, a sphere light and a point light under the light hierarchy,
// three bounces: BSDF rays after a shaping vertex meet lights it did not choose and count them with the density it
// would have sampled them with (Path::emission). It fails (by 12 % in red) when the last vertex's choice to shape is
// read after its own state moved on.
TEST(PathLobeLightSampling, ImagesEqualLightSamplingWithinNoise) {
  const auto scene = [](const char* mode) {
    return fmt::format(R"({{
  "camera": {{ "position": [0, 2.0, 3], "look_at": [0, 0.3, 0], "fov": 50, "resolution": [40, 30] }},
  "render": {{ "max_depth": 3, "light_sampling": "{mode}", "filter": "box" }},
  "materials": {{
    "floor": {{ "type": "conductor", "roughness": 0.12, "eta": [0.2, 0.4, 1.4], "k": [3.6, 2.5, 1.9] }},
    "coat": {{ "type": "plastic", "roughness": 0.1, "albedo": [0.2, 0.4, 0.6] }},
    "mirror": {{ "type": "conductor", "roughness": 0 }},
    "white": {{ "type": "diffuse", "albedo": 0.6 }},
    "black": {{ "type": "diffuse", "albedo": 0 }}
  }},
  "shapes": [
    {{ "type": "quad", "material": "floor", "vertices": [[-4, 0, -4], [-4, 0, 4], [4, 0, 4], [4, 0, -4]] }},
    {{ "type": "quad", "material": "white", "vertices": [[-4, 0, -2], [4, 0, -2], [4, 3, -2], [-4, 3, -2]] }},
    {{ "type": "quad", "material": "coat",
      "vertices": [[-0.1, 0.5, -0.5], [-0.1, 0.5, 0.5], [0.5, 0.5, 0.5], [0.5, 0.5, -0.5]] }},
    {{ "type": "sphere", "material": "mirror", "center": [-0.9, 0.35, 0.2], "radius": 0.35 }},
    {{ "type": "quad", "material": "black", "emission": [6, 4.5, 3],
      "vertices": [[-0.3, 1, -0.2], [0.3, 1, -0.2], [0.3, 1, 0.2], [-0.3, 1, 0.2]] }},
    {{ "type": "mesh", "material": "black", "emission": [0.6, 0.8, 1.2],
      "positions": [[-2.5, 1.5, -1.9], [-1.5, 1.5, -1.9], [-1.5, 2.2, -1.9], [-2.5, 2.2, -1.9]],
      "indices": [0, 1, 2, 0, 2, 3] }},
    {{ "type": "sphere", "material": "black", "emission": [2, 2, 2], "center": [1.8, 0.6, -1], "radius": 0.15 }}
  ],
  "lights": [ {{ "type": "point", "position": [-1.5, 1.2, 1], "intensity": [0.5, 0.5, 0.4] }} ]
}})",
                       fmt::arg("mode", mode));
  };
  const int spp = kSanitized ? 128 : 1024;
  const TestRender lobe = render_json(scene("lobe"), spp, 0, 9);
  const TestRender light = render_json(scene("light"), spp, 0, 10);
  expect_equal_means(lobe.film, light.film, "lobe", "light");
}

}  // namespace
}  // namespace kozu::test
