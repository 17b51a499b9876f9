// Checkpoints: every value of the payload is checked when it is read. A payload with a valid hash can still hold
// values no render writes (NaN resumed into an all-NaN image): each is refused with the pixel and the value.
#include "core/error.h"
#include "render/checkpoint.h"
#include "support/render_test.h"

#include <gtest/gtest.h>

#include <functional>
#include <limits>

namespace kozu::test {
namespace {

RenderIdentity identity(bool features, bool alpha) {
  RenderIdentity id;
  id.kozu_version = "test";
  id.scene_hash = 42;
  id.seed = 7;
  id.max_depth = 5;
  id.direct = "sample";
  id.filter = "box";
  id.resolution = {4, 3};
  id.window_origin = {0, 0};
  id.window_size = {4, 3};
  id.features = features;
  id.alpha = alpha;
  return id;
}

Film sampled_film(bool features, bool alpha) {
  Film film(4, 3);
  if (features) film.enable_features();
  if (alpha) film.enable_alpha();
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x)
      for (int s = 0; s < 3; ++s) {
        const Rgb L(0.1f * float(x + s), 0.2f, 0.3f * float(y));
        film.add_sample(x, y, L);
        if (features) film.add_features(x, y, PixelFeatures{}, s % 2 == 0 ? &L : nullptr);
        if (alpha && s == 0) film.add_hit(x, y);
      }
  return film;
}

// Saves film, changed by edit, under a valid hash and returns load_checkpoint's message ("" if it loads).
std::string load_error(const std::function<void(Film&)>& edit, bool features = false, bool alpha = false) {
  TempDir dir;
  Film film = sampled_film(features, alpha);
  edit(film);
  const auto file = dir.path() / "c.ckpt";
  save_checkpoint(file, identity(features, alpha), film);
  try {
    load_checkpoint(file, identity(features, alpha));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(CheckpointValues, AWholeFilmLoads) {
  EXPECT_EQ(load_error([](Film&) {}), "");
  EXPECT_EQ(load_error([](Film&) {}, true, true), "");
}

TEST(CheckpointValues, NonFiniteAndInconsistentValuesAreRefused) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::string e = load_error([&](Film& f) { f.pixels()[5].sum.g = nan; });
  EXPECT_NE(e.find("c.ckpt: the checkpoint holds a value no render writes (damaged or forged): pixel (1, 1): the "
                   "green sum is nan"),
            std::string::npos)
      << e;
  e = load_error([&](Film& f) { f.pixels()[0].sum_sq.r = std::numeric_limits<double>::infinity(); });
  EXPECT_NE(e.find("pixel (0, 0): the red sum"), std::string::npos) << e;
  e = load_error([&](Film& f) { f.pixels()[2].sum_sq.b = -1.0; });
  EXPECT_NE(e.find("pixel (2, 0): the blue sum"), std::string::npos) << e;
  // A sum without a sample, and a sum too large for its sum of squares (a variance < 0).
  e = load_error([&](Film& f) { f.pixels()[3].count = 0; });
  EXPECT_NE(e.find("without a sample"), std::string::npos) << e;
  e = load_error([&](Film& f) { f.pixels()[4].sum.r = 1e3; });
  EXPECT_NE(e.find("inconsistent with its sum of squares"), std::string::npos) << e;
  e = load_error([&](Film& f) { f.pixels()[4].discarded = 0xffffffffu; });
  EXPECT_NE(e.find("more than 2147483647"), std::string::npos) << e;
  // Features and coverage.
  e = load_error([&](Film& f) { f.feature_pixels()[1].depth = std::numeric_limits<float>::quiet_NaN(); }, true);
  EXPECT_NE(e.find("pixel (1, 0): a feature (AOV) sum is nan"), std::string::npos) << e;
  e = load_error([&](Film& f) { f.feature_pixels()[1].count = 99; }, true);
  EXPECT_NE(e.find("99 feature samples"), std::string::npos) << e;
  e = load_error([&](Film& f) { f.hit_counts()[6] = 4; }, false, true);
  EXPECT_NE(e.find("pixel (2, 1): 4 coverage hits for 3 samples"), std::string::npos) << e;
}

}  // namespace
}  // namespace kozu::test
