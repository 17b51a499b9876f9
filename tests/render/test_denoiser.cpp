// The denoiser (render/denoiser.h) on films with known answers: flat noise is smoothed without bias, an edge that
// the albedo shows is kept sharp, and so is a strong colour edge with identical features (the variance-normalized
// colour distance rejects the other side). Each asserts a property a broken weight would fail: a filter that
// ignores features blurs the first edge, one that ignores colour the second, one without variance cancellation
// smooths less than asked. The visible emission is added back, not filtered.
#include "render/denoiser.h"

#include "core/rng.h"
#include "render/denoise_buffers.h"
#include "render/denoise_test_films.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>

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

// Visible emission (PixelFeatures::emission: an emitter seen directly) of 10 in the middle columns, in every sample
// there, over a lit surface of 0.5 ± 0.4 everywhere: the surface is filtered without the emission, and the
// emission added back as VisibleEmission gives it (the columns beside its edge keep it in the filtered radiance). Given
// as 7 instead of the film's 10, the middle comes out 7.5 (the filtered rest plus what was given); kept in the filtered
// radiance (not apart), it comes out 10.5.
TEST(Denoiser, AddsTheVisibleEmissionBackUnfiltered) {
  const auto inside = [](int x) { return test::middle_third(x, kW); };
  const Film film = test::emission_band_film(kW, kH, kSpp, &test::middle_third);
  const std::vector<float> raw = film.rgb();
  for (const float given : {-1.0f, 7.0f, 0.0f}) {  // the film's own; 7 added back; 10 kept in the filtered radiance
    VisibleEmission e = visible_emission(film);
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        const size_t i = size_t(y) * kW + x;
        // Every sample agrees; apart, but for the columns beside the emitter's edge (a neighbour differs).
        const bool edge = inside(x) != inside(std::max(x - 1, 0)) || inside(x) != inside(std::min(x + 1, kW - 1));
        EXPECT_EQ(e.apart(i), !edge) << x;
        EXPECT_EQ(e.value(i).x, inside(x) ? 10.0f : 0.0f);
        if (given > 0.0f && inside(x)) e.set(i, Vec3(given));
        if (given == 0.0f) e.keep_in_radiance(i);
      }
    const std::vector<float> clean = denoise(film, {}, &e);
    const float middle = given > 0.0f ? given + 0.5f : 10.5f;
    const auto truth = [&](int x) { return inside(x) ? middle : 0.5f; };
    // Each region's mean within 0.01 of its truth (the cases differ by 3), no pixel beyond 0.25 (a pixel mixing the
    // emitter with the surface would be off by 10 × its share), and the noise smoothed 20x.
    double sum[2] = {0.0, 0.0};
    int count[2] = {0, 0};
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        const float v = clean[3 * (size_t(y) * kW + x)];
        ASSERT_NEAR(v, truth(x), 0.25f) << x << "," << y << " given " << given;
        sum[inside(x)] += v;
        ++count[inside(x)];
      }
    EXPECT_NEAR(sum[1] / count[1], middle, 0.01) << "given " << given;
    EXPECT_NEAR(sum[0] / count[0], 0.5, 0.01) << "given " << given;
    if (given != 7.0f) {  // (with 7 the raw image is not an estimate of this truth)
      EXPECT_LT(mse(clean, truth), mse(raw, truth) / 20.0) << "given " << given;
    }
  }
}

// The filter as its header defines it, pixel by pixel in double with std::exp, against the banded, vectorized
// filter (its own exponential, box filters along rows then columns): both windows the same (so the risk's choice
// does not matter) on a film with holes, pixels of one sample, an albedo edge, turning normals, growing depth and a
// row of visible emission. They agree to float rounding; a wrong patch box, feature term, cross-filtering or
// exponential does not (each of the four fails it, by 2·10⁻⁴ to 0.7: tried).
TEST(Denoiser, FiltersAsItsDefinitionSays) {
  const Film film = test::varied_film(kW, kH, 23);
  DenoiseSettings s;
  s.radius = s.radius_small = 3;
  const VisibleEmission visible = visible_emission(film);
  const denoise_detail::Buffers b = denoise_detail::split(film, visible);
  const int f = s.patch, r = s.radius;
  const auto in = [](int x, int y) { return x >= 0 && x < kW && y >= 0 && y < kH; };
  // d²(p, q) of half k, before the patch's mean; +inf (weight 0) for a neighbour outside the image.
  const auto term = [&](int k, int px, int py, int qx, int qy) {
    if (!in(qx, qy)) return std::numeric_limits<double>::infinity();
    const size_t p = b.index(px, py), q = b.index(qx, qy);
    const double vp = b.var[p], vq = b.var[q];
    const Vec3 d = b.half[k][p] - b.half[k][q];
    const double num = (double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z) / 3.0 - (vp + std::min(vp, vq));
    return num / (1e-10 + double(s.k) * s.k * (vp + vq));
  };
  std::vector<float> expected(3 * size_t(kW) * kH);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const size_t p = b.index(x, y);
      Vec3d mean(0.0);
      for (int k = 0; k < 2; ++k) {
        Vec3d num(0.0);
        double den = 0.0;
        for (int dy = -r; dy <= r; ++dy)
          for (int dx = -r; dx <= r; ++dx) {
            if (!in(x + dx, y + dy)) continue;
            const size_t q = b.index(x + dx, y + dy);
            const Vec3d da = Vec3d(b.albedo[p] - b.albedo[q]), dn = Vec3d(b.normal[p] - b.normal[q]);
            const double dz = (double(b.depth[p]) - b.depth[q]) / std::max(std::abs(double(b.depth[p])), 1e-6);
            const double fd = glm::dot(da, da) / sqr(double(s.sigma_albedo)) +
                              glm::dot(dn, dn) / sqr(double(s.sigma_normal)) + dz * dz / sqr(double(s.sigma_depth));
            if (!(std::exp(-fd) > 1e-6)) continue;
            // The patch's mean of the other half's distances, the patch clipped to the image.
            double sum = 0.0;
            int cnt = 0;
            for (int ty = -f; ty <= f; ++ty)
              for (int tx = -f; tx <= f; ++tx)
                if (in(x + tx, y + ty)) {
                  sum += term(1 - k, x + tx, y + ty, x + tx + dx, y + ty + dy);
                  ++cnt;
                }
            const double wt = std::exp(-fd - std::max(0.0, sum / cnt));
            num += wt * Vec3d(b.half[k][q]);
            den += wt;
          }
        mean += 0.5 * num / den;
      }
      denoise_detail::put_pixel(expected, size_t(y) * kW + x, Vec3(mean), visible);
    }
  const std::vector<float> got = denoise(film, s, &visible);
  double worst = 0.0;
  for (size_t i = 0; i < got.size(); ++i)
    worst = std::max(worst, std::abs(double(got[i]) - expected[i]) / (std::abs(double(expected[i])) + 1e-2));
  EXPECT_LT(worst, 1e-4);
  std::printf("worst relative difference from the definition: %.2e\n", worst);
}

// The image is filtered in bands of rows, each with the rows its windows read: any band height gives the same pixels
// bit for bit, on a film that varies along y as well as x (test::varied_film).
TEST(Denoiser, BandsOfAnyHeightGiveTheSameImage) {
  test::expect_bands_give_the_same_image<DenoiseSettings>(
      test::varied_film(kW, kH, 17), [](const Film& film, const DenoiseSettings& s) { return denoise(film, s); });
}

// Expired from the start: the wide window is abandoned, and every pixel takes the narrow one, exactly what a filter
// whose wide window is the narrow one gives; the output still smooths the noise.
TEST(Denoiser, PastTheDeadlineTakesTheNarrowWindow) {
  const auto truth = [](int) { return 1.0f; };
  const Film film = noisy_film(
      truth, [](int) { return 0.5f; }, 0.5f, 9);
  int polls = 0;
  const std::vector<float> late = denoise(film, {}, nullptr, [&] { return ++polls > 0; });
  EXPECT_GT(polls, 0);
  DenoiseSettings narrow;
  narrow.radius = narrow.radius_small;
  EXPECT_EQ(late, denoise(film, narrow));
  EXPECT_NE(late, denoise(film));
  EXPECT_LT(mse(late, truth), mse(film.rgb(), truth) / 4.0);
}

}  // namespace
}  // namespace kozu
