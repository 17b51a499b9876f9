// EmissionSums: the film's sparse sums of the visible emission. Blocks are allocated only where a pixel sees an
// emitter; reads elsewhere are zero; copies are deep; threads adding to pixels of one block at once lose nothing.
#include "render/emission_sums.h"
#include "render/film.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

namespace kozu::test {
namespace {

TEST(EmissionSums, AllocatesOnlyTheBlocksThatSeeEmission) {
  EmissionSums s(37, 21);  // 5 × 3 blocks of 8 × 8, the last ones partial
  EXPECT_EQ(s.blocks(), 0u);
  EXPECT_EQ(s.get(36, 20).sum, Vec3(0.0f));
  s.at(36, 20).sum = Vec3(1.0f, 2.0f, 3.0f);
  s.at(33, 17).sq = 4.0f;  // the same block
  s.at(0, 0).even = Vec3(5.0f);
  EXPECT_EQ(s.blocks(), 2u);
  EXPECT_EQ(s.get(36, 20).sum, Vec3(1.0f, 2.0f, 3.0f));
  EXPECT_EQ(s.get(size_t(20) * 37 + 36).sum, Vec3(1.0f, 2.0f, 3.0f));  // by row-major index
  EXPECT_EQ(s.get(33, 17).sq, 4.0f);
  EXPECT_EQ(s.get(1, 0).even, Vec3(0.0f));
  // Copies are deep; clearing does not allocate.
  EmissionSums c = s;
  c.at(36, 20).sum = Vec3(0.0f);
  EXPECT_EQ(s.get(36, 20).sum, Vec3(1.0f, 2.0f, 3.0f));
  s.clear(size_t(20) * 37 + 36);
  s.clear(size_t(10) * 37 + 10);
  EXPECT_EQ(s.get(36, 20).sum, Vec3(0.0f));
  EXPECT_EQ(s.blocks(), 2u);
  EmissionSums moved = std::move(c);
  EXPECT_EQ(moved.get(0, 0).even, Vec3(5.0f));
  // set: zero sums allocate nothing (and clear what is there), others allocate.
  s.set(size_t(20) * 37 + 20, EmissionSums::Pixel{});
  EXPECT_EQ(s.blocks(), 2u);
  s.set(size_t(20) * 37 + 20, {Vec3(1.0f), Vec3(0.5f), 2.0f});
  EXPECT_EQ(s.blocks(), 3u);
  EXPECT_EQ(s.get(20, 20).sq, 2.0f);
  s.set(size_t(20) * 37 + 20, EmissionSums::Pixel{});
  EXPECT_EQ(s.get(20, 20).sum, Vec3(0.0f));
}

// Every pixel of a 64 × 64 image sampled by tasks of one pixel each, in parallel: each block's first pixels race to
// allocate it. The sums equal the serial ones.
TEST(EmissionSums, ConcurrentAllocationLosesNothing) {
  constexpr int kW = 64, kSamples = 16;
  for (int round = 0; round < 4; ++round) {
    EmissionSums s(kW, kW);
    tbb::parallel_for(0, kW * kW, [&](int i) {
      for (int k = 0; k < kSamples; ++k) s.at(i % kW, i / kW).sum += Vec3(float(i % 7 + 1));
    });
    EXPECT_EQ(s.blocks(), 64u);
    for (int i = 0; i < kW * kW; ++i) ASSERT_EQ(s.get(size_t(i)).sum.x, float(kSamples * (i % 7 + 1))) << i;
  }
}

// Through the film: only the pixels whose samples see an emitter take memory, and the features' means read it back.
TEST(EmissionSums, TheFilmKeepsOnlyTheEmitterPixels) {
  Film film(64, 48, Vec2i(100, 200));  // a crop window: blocks are in the window's coordinates
  film.enable_features();
  for (int y = 200; y < 248; ++y)
    for (int x = 100; x < 164; ++x) {
      PixelFeatures f;
      f.emission = (x == 130 && y == 230) ? Rgb(2.0f, 4.0f, 6.0f) : Rgb(0.0f);
      const Rgb L(1.0f);
      film.add_features(x, y, f, &L);
      film.add_sample(x, y, L + f.emission);
    }
  EXPECT_EQ(film.emission_sums().blocks(), 1u);
  EXPECT_EQ(film.features(130, 230).emission.g, 4.0f);
  EXPECT_EQ(film.features(131, 230).emission.g, 0.0f);
  EXPECT_EQ(film.emission_sums().get(30, 30).even, Vec3(2.0f, 4.0f, 6.0f));
  // A pixel cleared (a rank's resumed pixel it does not render) has no sample, feature or emission left.
  film.clear_pixel(size_t(30) * 64 + 30);
  EXPECT_EQ(film.taken(130, 230), 0u);
  EXPECT_FALSE(film.features(130, 230).set);
  EXPECT_EQ(film.emission_sums().get(30, 30).sum, Vec3(0.0f));
  EXPECT_EQ(film.feature_pixels()[size_t(30) * 64 + 30].even_count, 0u);
}

}  // namespace
}  // namespace kozu::test
