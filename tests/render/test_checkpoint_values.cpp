// Checkpoints: every value of the payload is checked when it is read. A payload with a valid hash can still hold
// values no render writes (NaN resumed into an all-NaN image): each is refused with the pixel and the value.
#include "core/error.h"
#include "io/checkpoint_file.h"
#include "render/checkpoint.h"
#include "support/render_test.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <limits>

namespace kozu::test {
namespace {

RenderIdentity identity(bool features, bool alpha, bool positions = false) {
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
  id.positions = positions;
  id.alpha = alpha;
  return id;
}

Film sampled_film(bool features, bool alpha, bool positions = false) {
  Film film(4, 3);
  if (features) film.enable_features();
  if (positions) film.enable_positions();
  if (alpha) film.enable_alpha();
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x)
      for (int s = 0; s < 3; ++s) {
        const Rgb L(0.1f * float(x + s), 0.2f, 0.3f * float(y));
        // The last sample of the last column is discarded (NaN): it still has features.
        const bool valid = !(s == 2 && x == 3);
        PixelFeatures pf;
        pf.albedo = Rgb(0.5f, 0.25f * float(s), 0.1f * float(x));
        pf.normal = Vec3(0.0f, 1.0f, 0.1f * float(y));
        pf.position = Vec3(float(x), float(y), float(s));
        pf.depth = 1.0f + float(s);
        pf.emission = Rgb(x == 1 ? 2.0f : 0.0f);
        if (features) film.add_features(x, y, pf, valid && s % 2 == 0 ? &L : nullptr);
        if (alpha && s == 0) film.add_hit(x, y);
        if (valid)
          film.add_sample(x, y, L);
        else
          film.add_discarded(x, y);
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
  e = load_error([&](Film& f) { f.feature_pixels()[1].even_count = 99; }, true);
  EXPECT_NE(e.find("pixel (1, 0): 99 even samples of 3 valid ones"), std::string::npos) << e;
  e = load_error([&](Film& f) { f.hit_counts()[6] = 4; }, false, true);
  EXPECT_NE(e.find("pixel (2, 1): 4 coverage hits for 3 samples"), std::string::npos) << e;
}

// "ltc"'s pixel memory (PixelMemory): carried field for field with when it was last pooled; light names past the
// integrator's list, non-finite sums, more samples than the pixel took and the pilots a part traces again before its
// range (PixelMemory::kPilotSamples), a share outside [0, 1] are refused.
TEST(CheckpointValues, PixelMemoryRoundTripsAndForgedValuesAreRefused) {
  const auto with_memory = [](Film& f) {
    f.enable_memory();
    f.set_memory_pooled_at(2);
    for (size_t i = 0; i < f.memory().size(); ++i) {
      PixelMemory& m = f.memory()[i];
      m.light = 1 + uint32_t(i % 2);
      m.seen = 0.5f * float(i);
      m.all = float(i) + 1.0f;
      m.learnt_light = 2;
      m.learnt_share = 0.25f;
      m.samples = 2.0f, m.sum = 1.0f, m.sum2 = 0.75f;
      m.cv_samples = 2.0f, m.with_sum = 1.0f, m.with_sum2 = 0.75f, m.without_sum = 1.5f, m.without_sum2 = 1.5f;
      m.learnt_skip = uint32_t(i % 3 == 0);
    }
  };
  {
    TempDir dir;
    Film film = sampled_film(false, false);
    with_memory(film);
    const auto file = dir.path() / "m.ckpt";
    save_checkpoint(file, identity(false, false), film);
    const Film back = load_checkpoint(file, identity(false, false));
    ASSERT_TRUE(back.has_memory());
    EXPECT_EQ(back.memory_pooled_at(), 2);
    EXPECT_EQ(std::memcmp(back.memory().data(), film.memory().data(), film.memory().size() * sizeof(PixelMemory)), 0);
  }
  EXPECT_EQ(load_error(with_memory), "");
  std::string e = load_error([&](Film& f) { with_memory(f), f.memory()[5].light = 9; });
  EXPECT_NE(e.find("pixel (1, 1): \"ltc\"'s pixel memory is not one a render makes (light 9"), std::string::npos) << e;
  e = load_error([&](Film& f) { with_memory(f), f.memory()[2].with_sum = std::numeric_limits<float>::infinity(); });
  EXPECT_NE(e.find("pixel (2, 0): a value of \"ltc\"'s pixel memory is inf"), std::string::npos) << e;
  EXPECT_EQ(load_error([&](Film& f) { with_memory(f), f.memory()[0].samples = 3.0f + PixelMemory::kPilotSamples; }),
            "");
  e = load_error([&](Film& f) { with_memory(f), f.memory()[0].samples = 4.0f + PixelMemory::kPilotSamples; });
  EXPECT_NE(e.find(fmt::format("{} samples of 3 taken", 4 + PixelMemory::kPilotSamples)), std::string::npos) << e;
  e = load_error([&](Film& f) { with_memory(f), f.memory()[0].learnt_share = 1.5f; });
  EXPECT_NE(e.find("pixel (0, 0): \"ltc\"'s pixel memory is not one a render makes"), std::string::npos) << e;
  e = load_error([&](Film& f) { with_memory(f), f.memory()[0].learnt_skip = 2; });
  EXPECT_NE(e.find("pixel (0, 0): \"ltc\"'s pixel memory is not one a render makes"), std::string::npos) << e;
}

void expect_same_features(const Film& a, const Film& b) {
  ASSERT_EQ(a.feature_pixels().size(), b.feature_pixels().size());
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x) {
      const PixelFeatures fa = a.features(x, y), fb = b.features(x, y);
      EXPECT_EQ(fa.albedo.r, fb.albedo.r);
      EXPECT_EQ(fa.albedo.g, fb.albedo.g);
      EXPECT_EQ(fa.normal, fb.normal);
      EXPECT_EQ(fa.depth, fb.depth);
      EXPECT_EQ(fa.position, fb.position);
      EXPECT_EQ(fa.emission.r, fb.emission.r);
      const size_t i = size_t(y) * a.width() + x;
      EXPECT_EQ(a.feature_pixels()[i].even_sum, b.feature_pixels()[i].even_sum);
      EXPECT_EQ(a.feature_pixels()[i].even_count, b.feature_pixels()[i].even_count);
      EXPECT_EQ(a.emission_sums().get(i).sum, b.emission_sums().get(i).sum);
      EXPECT_EQ(a.emission_sums().get(i).even, b.emission_sums().get(i).even);
      EXPECT_EQ(a.emission_sums().get(i).sq, b.emission_sums().get(i).sq);
    }
}

// Positions (--aov position) are stored only when the render keeps them; a checkpoint with them resumes a render
// without them, not the other way round.
TEST(CheckpointValues, PositionsAreKeptOnlyWhenNeeded) {
  TempDir dir;
  const auto with = dir.path() / "with.ckpt", without = dir.path() / "without.ckpt";
  const Film film = sampled_film(true, true, true);
  save_checkpoint(with, identity(true, true, true), film);
  Film plain = sampled_film(true, true);
  save_checkpoint(without, identity(true, true), plain);
  // 12 bytes a pixel more, and nothing else (the header's "true" is a character shorter than "false").
  ASSERT_GT(film.emission_sums().blocks(), 0u);  // the column of visible emission
  EXPECT_EQ(std::filesystem::file_size(with), std::filesystem::file_size(without) + 12u * 12u - 1u);
  const Film back = load_checkpoint(with, identity(true, true, true));
  ASSERT_TRUE(back.has_positions());
  expect_same_features(film, back);
  EXPECT_EQ(back.hit_counts(), film.hit_counts());
  const Film dropped = load_checkpoint(with, identity(true, true));
  EXPECT_FALSE(dropped.has_positions());
  expect_same_features(plain, dropped);
  EXPECT_EQ(dropped.hit_counts(), film.hit_counts());
  try {
    load_checkpoint(without, identity(true, true, true));
    ADD_FAILURE() << "a checkpoint without positions resumed a render that needs them";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("saved without the positions of --aov position"), std::string::npos)
        << e.what();
  }
  Film bad = sampled_film(true, false, true);
  bad.position_sums()[7].y = std::numeric_limits<float>::infinity();
  save_checkpoint(with, identity(true, false, true), bad);
  try {
    load_checkpoint(with, identity(true, false, true));
    ADD_FAILURE() << "an infinite position loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pixel (3, 1): a position (AOV) sum is inf"), std::string::npos) << e.what();
  }
}

// Format 2 (the features' 88-byte layout with their count and position, no "positions" key) is still read.
TEST(CheckpointValues, Format2IsRead) {
  struct V2 {  // the layout format 2's files hold
    Vec3 albedo, normal, position;
    float depth;
    uint32_t count;
    Vec3 even_sum;
    uint32_t even_count;
    Vec3 emission, emission_even;
    float emission_sq;
  };
  static_assert(sizeof(V2) == 88);
  const Film film = sampled_film(true, true, true);
  const size_t n = film.pixels().size();
  const auto write_v2 = [&](const std::filesystem::path& file, uint32_t count_offset) {
    std::vector<unsigned char> payload(n * (sizeof(Film::Pixel) + sizeof(V2) + 4));
    std::memcpy(payload.data(), film.pixels().data(), n * sizeof(Film::Pixel));
    for (size_t i = 0; i < n; ++i) {
      const Film::FeaturePixel& f = film.feature_pixels()[i];
      const Film::Pixel& p = film.pixels()[i];
      const EmissionSums::Pixel e = film.emission_sums().get(i);
      const V2 v{f.albedo,   f.normal,      film.position_sums()[i],
                 f.depth,    p.count + p.discarded + (i == 5 ? count_offset : 0u),
                 f.even_sum, f.even_count,  e.sum,
                 e.even,     e.sq};
      std::memcpy(payload.data() + n * sizeof(Film::Pixel) + i * sizeof(V2), &v, sizeof v);
    }
    std::memcpy(payload.data() + n * (sizeof(Film::Pixel) + sizeof(V2)), film.hit_counts().data(), n * 4);
    nlohmann::json header = identity(true, true).to_json();
    header.erase("positions");
    header["pixels"] = n;
    write_checkpoint_file(file, header, payload.data(), payload.size(), 2);
  };
  TempDir dir;
  const auto file = dir.path() / "v2.ckpt";
  write_v2(file, 0);
  const Film with = load_checkpoint(file, identity(true, true, true));
  expect_same_features(film, with);
  EXPECT_EQ(with.hit_counts(), film.hit_counts());
  const Film without = load_checkpoint(file, identity(true, true));
  EXPECT_FALSE(without.has_positions());
  EXPECT_EQ(without.features(2, 1).albedo.g, film.features(2, 1).albedo.g);
  // A count other than the samples taken is no render's.
  write_v2(file, 1);
  try {
    load_checkpoint(file, identity(true, true));
    ADD_FAILURE() << "a format-2 count unlike the samples taken loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pixel 5: feature samples other than the 3 samples taken"), std::string::npos)
        << e.what();
  }
}

// A header that promises positions without features (no render writes one) is refused before its payload is read:
// its payload's length matches the pixels and the positions, and a film without features reads the pixels alone.
TEST(CheckpointValues, PositionsWithoutFeaturesAreRefused) {
  TempDir dir;
  const auto file = dir.path() / "forged.ckpt";
  const Film film = sampled_film(false, false);
  const size_t n = film.pixels().size();
  std::vector<unsigned char> payload(n * (sizeof(Film::Pixel) + sizeof(Vec3)), 0);
  std::memcpy(payload.data(), film.pixels().data(), n * sizeof(Film::Pixel));
  nlohmann::json header = identity(false, false).to_json();
  header["positions"] = true;
  header["pixels"] = n;
  write_checkpoint_file(file, header, payload.data(), payload.size());
  try {
    load_checkpoint(file, identity(false, false));
    ADD_FAILURE() << "positions without features loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("positions come without the features"), std::string::npos) << e.what();
  }
}

// The payload written and read in pieces: the hash of pieces of any size is that of the whole.
TEST(CheckpointValues, PiecewiseHashIsTheWholeHash) {
  std::vector<unsigned char> bytes(1000);
  for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<unsigned char>(i * 7 + 3);
  for (const size_t total : {size_t{0}, size_t{5}, size_t{8}, size_t{999}, size_t{1000}}) {
    const uint64_t whole = hash_words(bytes.data(), total);
    for (const size_t piece : {size_t{1}, size_t{3}, size_t{8}, size_t{13}, size_t{1000}}) {
      WordHasher h;
      for (size_t at = 0; at < total; at += piece) h.update(bytes.data() + at, std::min(piece, total - at));
      EXPECT_EQ(h.digest(), whole) << total << " in pieces of " << piece;
    }
  }
  // A changed byte changes it.
  WordHasher h;
  bytes[500] ^= 1;
  h.update(bytes.data(), 1000);
  bytes[500] ^= 1;
  EXPECT_NE(h.digest(), hash_words(bytes.data(), 1000));
}

}  // namespace
}  // namespace kozu::test
