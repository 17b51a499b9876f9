// The adaptive-sampling rule (render/adaptive_sampling.h) on films with known contents: the estimate's
// normalization, the neighbourhood that keeps a quiet pixel beside a noisy one going, min_spp, pixels of other
// processes, and that a converged pixel stays converged.
#include "render/adaptive_sampling.h"

#include <gtest/gtest.h>

#include <cmath>

namespace kozu {
namespace {

constexpr int kN = 7;

// A kN x kN film: every pixel `count` samples of 0.5, but `noisy` (if inside) whose samples alternate 0 and 1.
Film film_with(int count, Vec2i noisy) {
  Film film(kN, kN);
  for (int y = 0; y < kN; ++y)
    for (int x = 0; x < kN; ++x)
      for (int s = 0; s < count; ++s) film.add_sample(x, y, Vec2i(x, y) == noisy ? Rgb(float(s % 2)) : Rgb(0.5f));
  return film;
}

const auto kAll = [](Vec2i) { return true; };

TEST(AdaptiveSampling, EstimateIsTheStandardErrorOverTheSquareRootOfTheLuminance) {
  // Grey: the luminance weights sum to 1, so the luminance is the grey and its variance v (0.2126² + 0.7152² +
  // 0.0722²).
  const double w2 = 0.2126 * 0.2126 + 0.7152 * 0.7152 + 0.0722 * 0.0722;
  EXPECT_NEAR(AdaptiveSampling::estimate(Rgb(0.25f), Rgb(1e-4f)), std::sqrt(1e-4 * w2 / 0.25), 1e-7);
  EXPECT_NEAR(AdaptiveSampling::estimate(Rgb(4.0f), Rgb(1e-4f)), std::sqrt(1e-4 * w2 / 4.0), 1e-7);
  // Below 0.01 the luminance is floored, so black pixels still converge.
  EXPECT_NEAR(AdaptiveSampling::estimate(Rgb(0.0f), Rgb(1e-6f)), std::sqrt(1e-6 * w2 / 0.01), 1e-7);
  EXPECT_EQ(AdaptiveSampling::estimate(Rgb(0.3f), Rgb(0.0f)), 0.0f);
}

TEST(AdaptiveSampling, AQuietPixelBesideANoisyOneGoesOn) {
  const Vec2i noisy(3, 3);
  const Film film = film_with(64, noisy);
  AdaptiveSampling a(film, 0.01f, 16, kAll);
  EXPECT_FALSE(a.update(film));
  EXPECT_GT(a.error(3, 3), 0.01f);
  for (int y = 0; y < kN; ++y)
    for (int x = 0; x < kN; ++x) {
      const bool near = std::abs(x - noisy.x) <= 1 && std::abs(y - noisy.y) <= 1;
      if (Vec2i(x, y) != noisy) {
        EXPECT_EQ(a.error(x, y), 0.0f);  // no variance of its own
      }
      EXPECT_EQ(a.converged(x, y), !near) << x << "," << y;
    }
  // Once the noisy pixel is quiet, all converge; and converged pixels stay so when a pixel turns noisy again.
  const Film quiet = film_with(64, Vec2i(-1));
  EXPECT_TRUE(a.update(quiet));
  EXPECT_TRUE(a.update(film));
  EXPECT_TRUE(a.converged(3, 3));
}

TEST(AdaptiveSampling, NothingConvergesBelowMinSppNorBesideSuchAPixel) {
  Film film = film_with(64, Vec2i(-1));
  for (int s = 0; s < 8; ++s) film.add_sample(0, 0, Rgb(0.5f));  // (0, 0): 72 samples
  AdaptiveSampling a(film, 0.01f, 70, kAll);
  EXPECT_FALSE(a.update(film));
  EXPECT_TRUE(std::isinf(a.error(1, 1)));
  EXPECT_EQ(a.error(0, 0), 0.0f);
  EXPECT_FALSE(a.converged(0, 0));  // its neighbours have no estimate yet
  EXPECT_FALSE(a.converged(4, 4));
}

TEST(AdaptiveSampling, PixelsOfAnotherProcessAreLeftOut) {
  const Vec2i noisy(3, 3);
  const Film film = film_with(64, noisy);
  AdaptiveSampling a(film, 0.01f, 16, [&](Vec2i p) { return p != noisy; });
  EXPECT_TRUE(a.update(film));  // every pixel of this process: the noisy one is another's
  EXPECT_TRUE(a.converged(2, 3));
}

}  // namespace
}  // namespace kozu
