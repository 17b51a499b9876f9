// The denoiser (render/denoiser.h) on films with known answers: flat noise is smoothed without bias, an edge that
// the albedo shows is kept sharp, and so is a strong colour edge with identical features (the variance-normalized
// colour distance rejects the other side). Each asserts a property a broken weight would fail: a filter that
// ignores features blurs the first edge, one that ignores colour the second, one without variance cancellation
// smooths less than asked.
#include "render/denoiser.h"

#include "core/rng.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

namespace kozu {
namespace {

constexpr int kW = 48, kH = 32, kSpp = 16;

// A film whose pixel (x, y) has the true value truth(x) and albedo albedo(x), with uniform noise of ±amplitude.
Film noisy_film(const std::function<float(int)>& truth, const std::function<float(int)>& albedo, float amplitude,
                uint64_t seed) {
  Film film(kW, kH);
  film.enable_features();
  Pcg32 rng(seed);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int s = 0; s < kSpp; ++s) {
        const float u = rng.next_float();
        const float v = std::max(0.0f, truth(x) + amplitude * (2.0f * u - 1.0f));
        const Rgb L(v);
        PixelFeatures f;
        f.albedo = Rgb(albedo(x));
        f.normal = Vec3(0, 0, 1);
        f.position = Vec3(float(x), float(y), 0);
        f.depth = 5.0f;
        f.set = true;
        film.add_features(x, y, f, s % 2 == 0 ? &L : nullptr);
        film.add_sample(x, y, L);
      }
  return film;
}

double mse(const std::vector<float>& img, const std::function<float(int)>& truth, int x0 = 0, int x1 = kW) {
  double e = 0.0;
  int n = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = x0; x < x1; ++x)
      for (int c = 0; c < 3; ++c, ++n) {
        const double d = img[3 * (size_t(y) * kW + x) + c] - truth(x);
        e += d * d;
      }
  return e / n;
}

TEST(Denoiser, SmoothsFlatNoiseWithoutBias) {
  const auto truth = [](int) { return 1.0f; };
  const Film film = noisy_film(
      truth, [](int) { return 0.5f; }, 0.5f, 1);
  const std::vector<float> raw = film.rgb(), clean = denoise(film);
  const double before = mse(raw, truth), after = mse(clean, truth);
  EXPECT_LT(after, before / 20.0) << before << " -> " << after;
  double mean = 0.0;
  for (float v : clean) mean += v;
  mean /= clean.size();
  EXPECT_NEAR(mean, 1.0, 3e-3);
}

// Left 0.4, right 0.6, the albedo the same, under noise of ±0.4 that the colour distance cannot see through: the
// mean of each column beside the edge stays within 0.015 of its value (a filter blind to the albedo pulls them
// about 0.04 towards each other).
TEST(Denoiser, KeepsAnEdgeTheAlbedoShows) {
  const auto truth = [](int x) { return x < kW / 2 ? 0.4f : 0.6f; };
  for (const bool blind : {false, true}) {
    const Film film = noisy_film(truth, truth, 0.4f, 2);
    DenoiseSettings settings;
    if (blind) settings.sigma_albedo = 1e3f;  // the control: features ignored
    const std::vector<float> clean = denoise(film, settings);
    double worst = 0.0;
    for (int x = kW / 2 - 1; x <= kW / 2; ++x) {
      double mean = 0.0;
      for (int y = 0; y < kH; ++y) mean += clean[3 * (size_t(y) * kW + x)] / kH;
      worst = std::max(worst, std::abs(mean - truth(x)));
    }
    if (blind)
      EXPECT_GT(worst, 0.03) << "the control should blur the edge";
    else
      EXPECT_LT(worst, 0.015);
  }
}

// Left 0.1, right 1.0, identical features: the colour distance alone keeps the edge.
TEST(Denoiser, KeepsAStrongColourEdgeWithIdenticalFeatures) {
  const auto truth = [](int x) { return x < kW / 2 ? 0.1f : 1.0f; };
  const Film film = noisy_film(
      truth, [](int) { return 0.5f; }, 0.05f, 3);
  const std::vector<float> clean = denoise(film);
  for (int y = 0; y < kH; ++y)
    for (int x = kW / 2 - 1; x <= kW / 2; ++x)
      EXPECT_NEAR(clean[3 * (size_t(y) * kW + x)], truth(x), 0.06) << x << "," << y;
}

// Stratified samples, as kozu's sampler gives at an antialiased edge: each pixel's samples are exactly 0 or 1 in a
// fixed proportion, so both halves hold the same mean although the sample variance is large. Left 1/2, right 1/4,
// identical features: the variance from the halves' difference (0) keeps the columns apart; the sample variance
// (1/4 / 8 per half) would call the two sides equal and blur them together, and the control, which fakes that
// variance by making the halves disagree without changing any pixel's mean, shows it.
TEST(Denoiser, TrustsTheHalvesAgreementOverTheSampleVariance) {
  for (const bool disagree : {false, true}) {
    Film film(kW, kH);
    film.enable_features();
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        // Left: 0 0 1 1 ... (each half 1/2); right: 0 0 1 1 0 0 0 0 ... (each half 1/4). The control puts the
        // ones in the odd samples only: the halves then differ (left 0 and 1, right 0 and 1/2), the means do not.
        static constexpr int kLeft[4] = {0, 0, 1, 1}, kRight[8] = {0, 0, 1, 1, 0, 0, 0, 0};
        for (int s = 0; s < kSpp; ++s) {
          int v = x < kW / 2 ? kLeft[s % 4] : kRight[s % 8];
          if (disagree) v = x < kW / 2 ? s % 2 : (s % 4 == 1);
          const Rgb L(static_cast<float>(v));
          PixelFeatures f;
          f.albedo = Rgb(0.5f);
          f.normal = Vec3(0, 0, 1);
          f.depth = 5.0f;
          f.set = true;
          film.add_features(x, y, f, s % 2 == 0 ? &L : nullptr);
          film.add_sample(x, y, L);
        }
      }
    const auto truth = [](int x) { return x < kW / 2 ? 0.5f : 0.25f; };
    const std::vector<float> clean = denoise(film);
    double worst = 0.0;
    for (int y = 0; y < kH; ++y)
      for (int x = kW / 2 - 1; x <= kW / 2; ++x)
        worst = std::max(worst, double(std::abs(clean[3 * (size_t(y) * kW + x)] - truth(x))));
    if (disagree)
      EXPECT_GT(worst, 0.05) << "the control should blur the edge";
    else
      EXPECT_LT(worst, 1e-3);
  }
}

}  // namespace
}  // namespace kozu
