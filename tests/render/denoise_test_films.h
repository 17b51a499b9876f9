// Films with known answers shared by the denoisers' tests (test_denoiser.cpp, test_feature_regression.cpp).
#pragma once

#include "core/rng.h"
#include "render/film.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace kozu::test {

// A w x h film of spp samples per pixel: visible emission (PixelFeatures::emission, an emitter seen directly) of 10
// in the middle third of the columns, in every sample there, over a lit surface of 0.5 ± 0.4 (uniform) everywhere,
// with flat features (albedo 0.5, normal +z, depth 5).
inline Film emission_band_film(int w, int h, int spp, bool (*inside)(int x, int w)) {
  Film film(w, h);
  film.enable_features();
  Pcg32 rng(5);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int s = 0; s < spp; ++s) {
        PixelFeatures f;
        f.albedo = Rgb(0.5f);
        f.normal = Vec3(0, 0, 1);
        f.depth = 5.0f;
        f.set = true;
        f.emission = Rgb(inside(x, w) ? 10.0f : 0.0f);
        const Rgb L = f.emission + Rgb(0.5f + 0.4f * (2.0f * rng.next_float() - 1.0f));
        film.add_features(x, y, f, s % 2 == 0 ? &L : nullptr);
        film.add_sample(x, y, L);
      }
  return film;
}

// A w x h film that varies along y as well as x, for the denoisers' bands of rows: a diagonal ramp under noise, an
// albedo edge across the rows, a normal that turns with y, depth growing with y, pixel by pixel 0 to 16 samples (one
// sample: no second half; none: a hole filled from the neighbours), and a row of visible emission.
inline Film varied_film(int w, int h, uint64_t seed) {
  Film film(w, h);
  film.enable_features();
  Pcg32 rng(seed);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int spp = (x * 7 + y * 3) % 17;
      for (int s = 0; s < spp; ++s) {
        const float truth = 0.02f * static_cast<float>(x + 2 * y);
        PixelFeatures f;
        f.albedo = Rgb(y < h / 3 ? 0.2f : 0.7f);
        f.normal = glm::normalize(Vec3(0.0f, 0.05f * static_cast<float>(y), 1.0f));
        f.depth = 3.0f + 0.1f * static_cast<float>(y);
        if (y == h / 2) f.emission = Rgb(2.0f);
        f.set = true;
        const Rgb L = f.emission + Rgb(std::max(0.0f, truth + 0.3f * (2.0f * rng.next_float() - 1.0f)), truth, 0.5f);
        film.add_features(x, y, f, s % 2 == 0 ? &L : nullptr);
        film.add_sample(x, y, L);
      }
    }
  return film;
}

// A denoiser run in bands of rows (Settings::band_rows) must give the whole image's pixels bit for bit, whatever
// the bands' height: denoise(film, settings) with bands of 1, 5 and 13 rows and the default, against one band.
template <class Settings, class Denoise>
void expect_bands_give_the_same_image(const Film& film, Denoise&& denoise) {
  Settings whole;
  whole.band_rows = film.height();
  const std::vector<float> reference = denoise(film, whole);
  for (const int rows : {1, 5, 13, 0}) {
    Settings banded;
    banded.band_rows = rows;
    EXPECT_EQ(denoise(film, banded), reference) << "bands of " << rows << " rows";
  }
}

// The emitter's columns of emission_band_film: the middle third.
inline bool middle_third(int x, int w) { return x >= w / 3 && x < 2 * w / 3; }

}  // namespace kozu::test
