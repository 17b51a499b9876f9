// The feature-regression denoiser (render/feature_regression.h) on films with known answers. Each test asserts a
// property a broken part would fail, with a control that shows the test can fail: flat noise smoothed without bias
// (a filter that never picks a wide window smooths too little), a texture the albedo shows kept (hidden from the
// features, it cannot be), a shadow edge no feature shows kept by the cross-validated window choice (one wide
// window blurs it), a lit gradient along a curved surface followed by the normal (the constant fit's window bends
// it), the visible emission added back unfiltered, and the deadline honoured.
#include "render/feature_regression.h"

#include "core/rng.h"
#include "render/denoise_test_films.h"
#include "render/denoiser.h"
#include "render/job_budget.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

namespace kozu {
namespace {

constexpr int kW = 64, kH = 48, kSpp = 16;

struct Truth {
  std::function<float(int, int)> value;  // the pixel's radiance
  std::function<float(int, int)> albedo = [](int, int) { return 0.5f; };
  std::function<Vec3(int, int)> normal = [](int, int) { return Vec3(0, 0, 1); };
};

// Samples of truth.value ± amplitude (uniform; values stay above amplitude, so no sample is clipped at 0 and the
// pixel means are unbiased), with the truth's features.
Film noisy_film(const Truth& t, float amplitude, uint64_t seed) {
  Film film(kW, kH);
  film.enable_features();
  Pcg32 rng(seed);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int s = 0; s < kSpp; ++s) {
        const float v = t.value(x, y) + amplitude * (2.0f * rng.next_float() - 1.0f);
        const Rgb L(v);
        PixelFeatures f;
        f.albedo = Rgb(t.albedo(x, y));
        f.normal = t.normal(x, y);
        f.depth = 5.0f;
        f.set = true;
        film.add_features(x, y, f, s % 2 == 0 ? &L : nullptr);
        film.add_sample(x, y, L);
      }
  return film;
}

double mse(const std::vector<float>& img, const Truth& t, int x0 = 0, int x1 = kW) {
  double e = 0.0;
  int n = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = x0; x < x1; ++x, ++n) {
      const double d = img[3 * (size_t(y) * kW + x)] - t.value(x, y);
      e += d * d;
    }
  return e / n;
}

TEST(FeatureRegression, SmoothsFlatNoiseWithoutBias) {
  const Truth t{[](int, int) { return 1.0f; }};
  const Film film = noisy_film(t, 0.5f, 1);
  const double before = mse(film.rgb(), t);
  const std::vector<float> clean = denoise_regression(film);
  EXPECT_LT(mse(clean, t), before / 30.0) << before << " -> " << mse(clean, t);
  double mean = 0.0;
  for (float v : clean) mean += v;
  EXPECT_NEAR(mean / clean.size(), 1.0, 3e-3);
  // The control: the narrowest window alone leaves most of the noise.
  RegressionSettings narrow;
  narrow.radii = {1};
  EXPECT_GT(mse(denoise_regression(film, narrow), t), before / 12.0);
}

// A fine checker texture (2-pixel squares, albedo 0.3 and 0.9) under uniform light: the fit keeps every texel and
// smooths the noise 20x. The control: the same pixels with an albedo feature that does not show the texture (as for
// a texture the first surface does not carry), where only narrow windows can keep it.
TEST(FeatureRegression, KeepsATextureTheAlbedoShows) {
  const auto albedo = [](int x, int y) { return ((x / 2 + y / 2) % 2) ? 0.9f : 0.3f; };
  const Truth t{[&](int x, int y) { return albedo(x, y); }, albedo};
  const Film film = noisy_film(t, 0.3f, 2);
  const double before = mse(film.rgb(), t);
  EXPECT_LT(mse(denoise_regression(film), t), before / 20.0);
  const Truth hidden{t.value, [](int, int) { return 0.6f; }};
  const Film blind = noisy_film(hidden, 0.3f, 2);
  EXPECT_GT(mse(denoise_regression(blind), hidden), before / 4.0);
}

// A shadow edge (0.15 left of the middle, 0.9 right) that no feature shows: the cross-validated choice keeps the
// columns beside it within 0.08 of their values; a wide window forced everywhere pulls them together.
TEST(FeatureRegression, KeepsAShadowEdgeNoFeatureShows) {
  const Truth t{[](int x, int) { return x < kW / 2 ? 0.15f : 0.9f; }};  // noise 0.1: no sample clipped
  const Film film = noisy_film(t, 0.1f, 3);
  const auto worst_at_edge = [&](const std::vector<float>& img) {
    double worst = 0.0;
    for (int y = 0; y < kH; ++y)
      for (int x = kW / 2 - 2; x <= kW / 2 + 1; ++x)
        worst = std::max(worst, std::abs(double(img[3 * (size_t(y) * kW + x)]) - t.value(x, y)));
    return worst;
  };
  EXPECT_LT(worst_at_edge(denoise_regression(film)), 0.08);
  RegressionSettings wide;  // the control: the widest window everywhere
  wide.select = false;
  EXPECT_GT(worst_at_edge(denoise_regression(film, wide)), 0.2);
}

// Light falling off across a cylinder (normal turning with x, radiance following n · l): the first-order fit in the
// normal follows it over a wide window, where a constant would bend it.
TEST(FeatureRegression, FollowsShadingTheNormalExplains) {
  const auto normal = [](int x, int) {
    const float a = (static_cast<float>(x) / (kW - 1) - 0.5f) * 2.4f;  // ±69°
    return Vec3(std::sin(a), 0.0f, std::cos(a));
  };
  const Vec3 light = glm::normalize(Vec3(0.8f, 0.0f, 0.6f));
  const Truth t{[&](int x, int y) { return 0.5f + std::max(0.0f, glm::dot(normal(x, y), light)); },
                [](int, int) { return 0.5f; }, normal};
  const Film film = noisy_film(t, 0.4f, 4);
  const double before = mse(film.rgb(), t);
  EXPECT_LT(mse(denoise_regression(film), t), before / 15.0);
}

TEST(FeatureRegression, AddsTheVisibleEmissionBackUnfiltered) {
  const auto inside = [](int x) { return test::middle_third(x, kW); };
  const Film film = test::emission_band_film(kW, kH, kSpp, &test::middle_third);
  const std::vector<float> clean = denoise_regression(film);
  double sum[2] = {0.0, 0.0};
  int count[2] = {0, 0};
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const float v = clean[3 * (size_t(y) * kW + x)];
      ASSERT_NEAR(v, inside(x) ? 10.5f : 0.5f, 0.25f) << x << "," << y;
      sum[inside(x)] += v;
      ++count[inside(x)];
    }
  EXPECT_NEAR(sum[1] / count[1], 10.5, 0.02);
  EXPECT_NEAR(sum[0] / count[0], 0.5, 0.01);
}

// The image is filtered in bands of rows, each with the rows its windows and risk boxes read: any band height gives the
// same pixels bit for bit, on a film that varies along y as well as x (test::varied_film).
TEST(FeatureRegression, BandsOfAnyHeightGiveTheSameImage) {
  test::expect_bands_give_the_same_image<RegressionSettings>(
      test::varied_film(kW, kH, 17), [](const Film& film, const RegressionSettings& s) { return denoise_regression(film, s); });
}

// Expired from the start: every pixel is the raw mean of its two halves (the radius-0 candidate); the denoiser
// neither waits nor fails.
TEST(FeatureRegression, StopsAtTheDeadlineWithTheBestSoFar) {
  const Truth t{[](int, int) { return 1.0f; }};
  const Film film = noisy_film(t, 0.5f, 6);
  int polls = 0;
  const std::vector<float> clean = denoise_regression(film, {}, nullptr, [&] { return ++polls > 0; });
  EXPECT_GT(polls, 0);
  const std::vector<float> raw = film.rgb();
  for (size_t i = 0; i < raw.size(); ++i) ASSERT_NEAR(clean[i], raw[i], 1e-5f) << i;
}

// `--denoiser ensemble` on a shadow edge no feature shows (0.15 left of the middle, 0.9 right), where the two filters
// err differently. Each filter's risk map (its estimated squared error per pixel) tracks its real error: higher beside
// the edge than away from it, and its mean within a factor 3 of the real mean squared error (a misplaced or zeroed map
// fails both). The ensemble's every pixel lies between the two filters' (a convex weighting), and its error is below
// the worse filter's and the plain mean's. Expired from the start it is NL-means' image: the regression is not
// started past the deadline.
TEST(DenoiserEnsemble, WeighsTheTwoFiltersByTheirEstimatedErrors) {
  const Truth t{[](int x, int) { return x < kW / 2 ? 0.15f : 0.9f; }};
  const Film film = noisy_film(t, 0.12f, 23);
  std::vector<float> risk_nl, risk_reg;
  const std::vector<float> a = denoise(film, {}, nullptr, {}, &risk_nl);
  const std::vector<float> b = denoise_regression(film, {}, nullptr, {}, &risk_reg);
  ASSERT_EQ(risk_nl.size(), size_t(kW) * kH);
  ASSERT_EQ(risk_reg.size(), size_t(kW) * kH);
  for (const auto& [img, risk] : {std::pair{&a, &risk_nl}, std::pair{&b, &risk_reg}}) {
    double near_edge = 0.0, far = 0.0, mean_risk = 0.0;
    int n_near = 0, n_far = 0;
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        const float r = (*risk)[size_t(y) * kW + x];
        mean_risk += r;
        if (std::abs(x - kW / 2) <= 2) {
          near_edge += r;
          ++n_near;
        } else if (std::abs(x - kW / 2) >= 12) {
          far += r;
          ++n_far;
        }
      }
    mean_risk /= double(kW) * kH;
    const double real = mse(*img, t);
    EXPECT_GT(near_edge / n_near, 2.0 * far / n_far);
    EXPECT_GT(mean_risk, real / 3.0) << real;
    EXPECT_LT(mean_risk, real * 3.0) << real;
  }
  const std::vector<float> e = render_job::run_denoiser(DenoiserKind::Ensemble, film);
  ASSERT_EQ(e.size(), a.size());
  double off_mean = 0.0;
  for (size_t i = 0; i < e.size(); ++i) {
    ASSERT_GE(e[i], std::min(a[i], b[i]) - 1e-6f) << i;
    ASSERT_LE(e[i], std::max(a[i], b[i]) + 1e-6f) << i;
    off_mean = std::max(off_mean, double(std::abs(e[i] - 0.5f * (a[i] + b[i]))));
  }
  EXPECT_GT(off_mean, 1e-3);
  // Here one filter errs several times more than the other: the weighting must do better than the plain mean (and
  // swapped weights would do worse).
  std::vector<float> plain(a.size());
  for (size_t i = 0; i < plain.size(); ++i) plain[i] = 0.5f * (a[i] + b[i]);
  fmt::print("edge MSE: NL-means {:.3g}, regression {:.3g}, ensemble {:.3g}, their mean {:.3g}\n", mse(a, t), mse(b, t),
             mse(e, t), mse(plain, t));
  EXPECT_LT(mse(e, t), std::max(mse(a, t), mse(b, t)));
  EXPECT_LT(mse(e, t), mse(plain, t));
  const auto expired = [] { return true; };
  const std::vector<float> late = render_job::run_denoiser(DenoiserKind::Ensemble, film, nullptr, expired);
  const std::vector<float> nl_late = denoise(film, {}, nullptr, expired);
  ASSERT_EQ(late.size(), nl_late.size());
  for (size_t i = 0; i < late.size(); ++i) ASSERT_EQ(late[i], nl_late[i]) << i;
}

}  // namespace
}  // namespace kozu
