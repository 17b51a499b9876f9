#include "render/checkpoint.h"

#include "core/error.h"
#include "io/checkpoint_file.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <type_traits>

namespace kozu {

// The payload is the film's pixels as they lie in memory.
static_assert(std::endian::native == std::endian::little, "checkpoints are little-endian");
static_assert(std::is_trivially_copyable_v<Film::Pixel> && sizeof(Film::Pixel) == 56,
              "the checkpoint payload is 56 bytes per pixel: 6 doubles and 2 counts");
static_assert(std::is_trivially_copyable_v<Film::FeaturePixel> && sizeof(Film::FeaturePixel) == 44,
              "features add 44 bytes per pixel: 10 floats and a count");
static_assert(std::is_trivially_copyable_v<EmissionSums::Pixel> && sizeof(EmissionSums::Pixel) == 28,
              "and the visible emission 28 (stored densely): 7 floats");
static_assert(sizeof(Vec3) == 12, "positions add 12 bytes per pixel");
static_assert(sizeof(PixelMemory) == 56, "\"ltc\"'s pixel memory adds 56 bytes per pixel");

// Format 2's feature pixel, as its files hold it: read and converted (its count is the pixel's samples taken, its
// visible emission goes to the sparse sums, and its position is kept only when the render needs it).
struct FeaturePixelV2 {
  Vec3 albedo, normal, position;
  float depth;
  uint32_t count;
  Vec3 even_sum;
  uint32_t even_count;
  Vec3 emission, emission_even;
  float emission_sq;
};
static_assert(std::is_trivially_copyable_v<FeaturePixelV2> && sizeof(FeaturePixelV2) == 88);

// Pixels per piece of a section converted on its way to or from the file.
constexpr size_t kBatch = 4096;

nlohmann::json RenderIdentity::to_json() const {
  return {{"kozu_version", kozu_version},
          {"scene_hash", fmt::format("{:016x}", scene_hash)},
          {"seed", seed},
          {"max_depth", max_depth},
          {"direct", direct},
          {"filter", filter},
          {"resolution", {resolution.x, resolution.y}},
          {"window", {window_origin.x, window_origin.y, window_size.x, window_size.y}},
          {"sample_begin", sample_begin},
          {"features", features},
          {"positions", positions},
          {"alpha", alpha}};
}

std::optional<std::string> RenderIdentity::difference(const RenderIdentity& c) const {
  const auto pair = [](Vec2i v) { return fmt::format("{}x{}", v.x, v.y); };
  if (c.kozu_version != kozu_version)
    return fmt::format("it was written by kozu {} (this is kozu {})", c.kozu_version, kozu_version);
  if (c.scene_hash != scene_hash)
    return std::string("it belongs to another scene (the scene file or the size of one of its inputs differs)");
  if (c.seed != seed) return fmt::format("its seed is {} (this render: {})", c.seed, seed);
  if (c.max_depth != max_depth) return fmt::format("its max_depth is {} (this render: {})", c.max_depth, max_depth);
  if (c.direct != direct) return fmt::format("its direct lighting is {} (this render: {})", c.direct, direct);
  if (c.filter != filter) return fmt::format("its pixel filter is {} (this render: {})", c.filter, filter);
  if (c.resolution != resolution)
    return fmt::format("its resolution is {} (this render: {})", pair(c.resolution), pair(resolution));
  if (c.window_origin != window_origin || c.window_size != window_size)
    return fmt::format("it covers the window {} at {},{} (this render: {} at {},{})", pair(c.window_size),
                       c.window_origin.x, c.window_origin.y, pair(window_size), window_origin.x, window_origin.y);
  if (c.sample_begin != sample_begin)
    return fmt::format("its sample range starts at {} (this render: {})", c.sample_begin, sample_begin);
  if (c.features != features)
    return fmt::format("it was saved {} the features of --aov albedo/normal/depth/position (this render {} them)",
                       c.features ? "with" : "without", features ? "needs" : "does not keep");
  if (positions && !c.positions)
    return std::string("it was saved without the positions of --aov position (this render needs them)");
  if (c.alpha != alpha)
    return fmt::format("it was saved {} the coverage of --alpha (this render {} it)", c.alpha ? "with" : "without",
                       alpha ? "needs" : "does not keep");
  return std::nullopt;
}

void save_checkpoint(const std::filesystem::path& file, const RenderIdentity& identity, const Film& film) {
  nlohmann::json header = identity.to_json();
  header["pixels"] = film.pixels().size();
  header["positions"] = film.has_positions();  // what the payload holds
  header["memory"] = film.has_memory();
  if (film.has_memory()) header["memory_pooled_at"] = film.memory_pooled_at();
  const size_t n = film.pixels().size();
  if (!film.has_features() && !film.has_alpha() && !film.has_memory()) {
    write_checkpoint_file(file, header, film.pixels().data(), n * sizeof(Film::Pixel));
    return;
  }
  // The pixels, then the features and their visible emission, the positions, the coverage counts and "ltc"'s pixel
  // memory when the film keeps them, written as they lie in the film: a copy of the whole payload was as large as the
  // film (265 MB at 1920 × 1080 with features).
  const size_t features = film.has_features() ? n * sizeof(Film::FeaturePixel) : 0;
  const size_t emission = film.has_features() ? n * sizeof(EmissionSums::Pixel) : 0;
  const size_t positions = film.has_positions() ? n * sizeof(Vec3) : 0;
  const size_t hits = film.has_alpha() ? n * sizeof(uint32_t) : 0;
  const size_t memory = film.has_memory() ? n * sizeof(PixelMemory) : 0;
  write_checkpoint_file(file, header, n * sizeof(Film::Pixel) + features + emission + positions + hits + memory,
                        [&](const PayloadPut& put) {
                          put(film.pixels().data(), n * sizeof(Film::Pixel));
                          if (features) put(film.feature_pixels().data(), features);
                          if (emission) {
                            // Dense in the file, a batch of pixels at a time.
                            std::vector<EmissionSums::Pixel> batch;
                            batch.reserve(kBatch);
                            for (size_t i = 0; i < n; ++i) {
                              batch.push_back(film.emission_sums().get(i));
                              if (batch.size() == kBatch || i + 1 == n) {
                                put(batch.data(), batch.size() * sizeof(EmissionSums::Pixel));
                                batch.clear();
                              }
                            }
                          }
                          if (positions) put(film.position_sums().data(), positions);
                          if (hits) put(film.hit_counts().data(), hits);
                          if (memory) put(film.memory().data(), memory);
                        });
}

namespace {

// Every value a checkpoint's payload holds, checked once it is read: the hash proves the payload is the one
// written, not that what was written is a film (a file made or edited by hand, a bug): a NaN there resumes into an
// image of NaN. What every film satisfies: finite sums; sums of squares >= 0; no sum without a sample, and
// sum^2 <= count x sum of squares (Cauchy-Schwarz, so the variance is >= 0); at most 2^31 - 1 samples a pixel
// (--spp's range); features and positions finite, with half-buffer counts within the samples;
// coverage hits within the valid samples. Sums may be negative: some integrators' samples are signed.
void check_film_values(const Film& film, const std::filesystem::path& file) {
  const int w = film.width();
  const Vec2i o = film.origin();
  const auto fail = [&](size_t i, const std::string& what) {
    throw InputError(file.string(), "",
                     fmt::format("the checkpoint holds a value no render writes (damaged or forged): pixel ({}, {}): "
                                 "{}",
                                 o.x + int(i % size_t(w)), o.y + int(i / size_t(w)), what));
  };
  static constexpr const char* kChannel[3] = {"red", "green", "blue"};
  const auto& pixels = film.pixels();
  for (size_t i = 0; i < pixels.size(); ++i) {
    const Film::Pixel& p = pixels[i];
    if (uint64_t(p.count) + uint64_t(p.discarded) > uint64_t{2147483647})
      fail(i, fmt::format("{} + {} samples, more than 2147483647", p.count, p.discarded));
    for (int c = 0; c < 3; ++c) {
      const double s = p.sum[c], q = p.sum_sq[c];
      if (!std::isfinite(s) || !std::isfinite(q) || q < 0.0)
        fail(i, fmt::format("the {} sum is {} and its sum of squares {}", kChannel[c], s, q));
      if (p.count == 0 && (s != 0.0 || q != 0.0))
        fail(i, fmt::format("a {} sum of {} without a sample", kChannel[c], s));
      if (s * s > double(p.count) * q * (1.0 + 1e-6))
        fail(i, fmt::format("the {} sum {} is inconsistent with its sum of squares {} over {} samples", kChannel[c], s,
                            q, p.count));
    }
  }
  if (film.has_features()) {
    const auto& features = film.feature_pixels();
    for (size_t i = 0; i < features.size(); ++i) {
      const Film::FeaturePixel& f = features[i];
      const EmissionSums::Pixel e = film.emission_sums().get(i);
      const float values[] = {f.albedo.x, f.albedo.y, f.albedo.z, f.normal.x, f.normal.y, f.normal.z,
                              f.depth,    f.even_sum.x, f.even_sum.y, f.even_sum.z, e.sum.x, e.sum.y,
                              e.sum.z,    e.even.x,     e.even.y,     e.even.z,     e.sq};
      for (float v : values)
        if (!std::isfinite(v)) fail(i, fmt::format("a feature (AOV) sum is {}", v));
      if (f.even_count > pixels[i].count)
        fail(i, fmt::format("{} even samples of {} valid ones", f.even_count, pixels[i].count));
    }
    for (size_t i = 0; i < film.position_sums().size(); ++i)
      for (int c = 0; c < 3; ++c)
        if (!std::isfinite(film.position_sums()[i][c]))
          fail(i, fmt::format("a position (AOV) sum is {}", film.position_sums()[i][c]));
  }
  if (film.has_alpha())
    for (size_t i = 0; i < film.hit_counts().size(); ++i)
      if (film.hit_counts()[i] > pixels[i].count)
        fail(i, fmt::format("{} coverage hits for {} samples", film.hit_counts()[i], pixels[i].count));
  // "ltc"'s memory: light names within the integrator's list (checked again where used), finite sums, sums of squares
  // >= 0, at most as many samples as the pixel took and the pilots a part of the samples traced again before its
  // range (PixelMemory::kPilotSamples), a share in [0, 1], a flag 0 or 1.
  for (size_t i = 0; i < film.memory().size(); ++i) {
    const PixelMemory& m = film.memory()[i];
    const float values[] = {m.seen,       m.all,      m.learnt_share, m.samples,     m.sum,         m.sum2,
                            m.cv_samples, m.with_sum, m.with_sum2,    m.without_sum, m.without_sum2};
    for (float v : values)
      if (!std::isfinite(v)) fail(i, fmt::format("a value of \"ltc\"'s pixel memory is {}", v));
    const double taken = double(pixels[i].count) + double(pixels[i].discarded);
    if (m.light > PixelMemory::kMaxLights || m.learnt_light > PixelMemory::kMaxLights || m.learnt_skip > 1 ||
        m.seen < 0.0f || m.all < 0.0f || m.sum2 < 0.0f || m.with_sum2 < 0.0f || m.without_sum2 < 0.0f ||
        !(m.learnt_share >= 0.0f && m.learnt_share <= 1.0f) || m.cv_samples < 0.0f || m.cv_samples > m.samples ||
        double(m.samples) > taken + PixelMemory::kPilotSamples)
      fail(i, fmt::format("\"ltc\"'s pixel memory is not one a render makes (light {}, {} samples of {} taken)",
                          m.light, m.samples, taken));
  }
}

}  // namespace

RenderIdentity checkpoint_identity(const nlohmann::json& h, const std::filesystem::path& file) {
  const auto fail = [&](const std::string& message) -> void { throw InputError(file.string(), "", message); };
  RenderIdentity stored;
  // Each field by name, so a message names the one that is missing or of the wrong type (never a library's text).
  const char* key = "";
  const auto at = [&](const char* k) -> const nlohmann::json& {
    key = k;
    if (!h.is_object() || !h.contains(k)) fail(fmt::format("not a kozu checkpoint: its header lacks '{}'", k));
    return h.at(k);
  };
  try {
    stored.kozu_version = at("kozu_version").get<std::string>();
    stored.scene_hash = std::stoull(at("scene_hash").get<std::string>(), nullptr, 16);
    stored.seed = at("seed").get<uint64_t>();
    stored.max_depth = at("max_depth").get<int>();
    stored.direct = at("direct").get<std::string>();
    stored.filter = at("filter").get<std::string>();
    const auto r = at("resolution").get<std::vector<int>>();
    const auto w = at("window").get<std::vector<int>>();
    if (r.size() != 2 || w.size() != 4) fail("not a kozu checkpoint: bad resolution or window in its header");
    stored.resolution = {r[0], r[1]};
    stored.window_origin = {w[0], w[1]};
    stored.window_size = {w[2], w[3]};
    stored.sample_begin = at("sample_begin").get<int>();
    stored.features = at("features").get<bool>();
    // Absent before format 3, whose features held the positions.
    stored.positions = h.contains("positions") ? at("positions").get<bool>() : stored.features;
    if (stored.positions && !stored.features)
      fail("not a kozu checkpoint: its header's positions come without the features they follow");
    stored.alpha = h.contains("alpha") && at("alpha").get<bool>();  // absent in checkpoints of earlier kozus
  } catch (const InputError&) {
    throw;
  } catch (const std::exception&) {
    fail(fmt::format("not a kozu checkpoint: its header's '{}' has a wrong type or value", key));
  }
  return stored;
}

namespace {

// Format 2's features, read and converted a batch at a time; `positions`: where their positions go (null: dropped).
// Returns the first pixel whose count is not its samples taken (no render's), or the pixel count when none.
size_t read_features_v2(CheckpointFileReader& reader, Film& film, PixelBuffer<Vec3>* positions) {
  auto& features = film.feature_pixels();
  const size_t n = features.size();
  size_t bad = n;
  std::vector<FeaturePixelV2> batch(std::min(n, kBatch));
  for (size_t i0 = 0; i0 < n; i0 += kBatch) {
    const size_t m = std::min(kBatch, n - i0);
    reader.read(batch.data(), m * sizeof(FeaturePixelV2));
    for (size_t k = 0; k < m; ++k) {
      const size_t i = i0 + k;
      const FeaturePixelV2& v = batch[k];
      const Film::Pixel& p = film.pixels()[i];
      if (v.count != p.count + p.discarded && bad == n) bad = i;
      features[i] = {v.albedo, v.normal, v.depth, v.even_sum, v.even_count};
      film.emission_sums().set(i, {v.emission, v.emission_even, v.emission_sq});
      if (positions) (*positions)[i] = v.position;
    }
  }
  return bad;
}

}  // namespace

Film load_checkpoint(const std::filesystem::path& file, const RenderIdentity& expected) {
  CheckpointFileReader reader(file);
  const auto fail = [&](const std::string& message) -> void { throw InputError(file.string(), "", message); };
  const RenderIdentity stored = checkpoint_identity(reader.header(), file);
  if (const auto diff = expected.difference(stored)) fail("cannot resume this render from it: " + *diff);
  const bool v2 = reader.format() == 2;
  const uint64_t pixels = uint64_t(expected.window_size.x) * uint64_t(expected.window_size.y);
  const uint64_t features = !expected.features ? 0
                            : v2                ? sizeof(FeaturePixelV2)
                                                : sizeof(Film::FeaturePixel) + sizeof(EmissionSums::Pixel);
  const uint64_t positions = stored.positions && !v2 ? sizeof(Vec3) : 0;  // format 2's are in its features
  const uint64_t hits = expected.alpha ? sizeof(uint32_t) : 0;
  // Absent before "ltc"'s memory was carried: such a render resumes knowing nothing of it (PixelMemory).
  const auto& header = reader.header();
  const bool has_memory =
      header.contains("memory") && header.at("memory").is_boolean() && header.at("memory").get<bool>();
  const uint64_t memory = has_memory ? sizeof(PixelMemory) : 0;
  if (reader.payload_bytes() != pixels * (sizeof(Film::Pixel) + features + positions + hits + memory))
    fail(fmt::format("not a kozu checkpoint: {} bytes of samples for {} pixels", reader.payload_bytes(), pixels));
  Film film(expected.window_size.x, expected.window_size.y, expected.window_origin);
  if (!expected.features && !expected.alpha && !positions && !memory) {
    reader.read_payload(film.pixels().data());
    check_film_values(film, file);
    return film;
  }
  if (expected.features) film.enable_features();
  if (expected.positions) film.enable_positions();
  if (expected.alpha) film.enable_alpha();
  if (memory) {
    film.enable_memory();
    const auto& at = header.contains("memory_pooled_at") ? header.at("memory_pooled_at") : nlohmann::json();
    if (!at.is_number_integer() || at.get<int64_t>() < 0 || at.get<int64_t>() > int64_t{2147483647})
      fail("not a kozu checkpoint: its header's 'memory_pooled_at' is missing or not a sample count");
    film.set_memory_pooled_at(int(at.get<int64_t>()));
  }
  // Each section read straight into the film (a copy of the payload was as large as the film), the hash checked
  // at the end, before any value is.
  reader.read(film.pixels().data(), pixels * sizeof(Film::Pixel));
  size_t bad_v2_count = pixels;
  if (v2 && features) {
    bad_v2_count = read_features_v2(reader, film, expected.positions ? &film.position_sums() : nullptr);
  } else if (features) {
    reader.read(film.feature_pixels().data(), pixels * sizeof(Film::FeaturePixel));
    std::vector<EmissionSums::Pixel> batch(std::min<uint64_t>(pixels, kBatch));
    for (size_t i0 = 0; i0 < pixels; i0 += kBatch) {
      const size_t m = std::min<uint64_t>(kBatch, pixels - i0);
      reader.read(batch.data(), m * sizeof(EmissionSums::Pixel));
      for (size_t k = 0; k < m; ++k) film.emission_sums().set(i0 + k, batch[k]);
    }
  }
  // Positions the render does not need are skipped.
  reader.read(expected.positions ? film.position_sums().data() : nullptr, pixels * positions);
  if (hits) reader.read(film.hit_counts().data(), pixels * hits);
  if (memory) reader.read(film.memory().data(), pixels * memory);
  reader.finish();
  if (bad_v2_count < pixels) {
    const Film::Pixel& p = film.pixels()[bad_v2_count];
    fail(fmt::format("the checkpoint holds a value no render writes (damaged or forged): pixel {}: feature samples "
                     "other than the {} samples taken",
                     bad_v2_count, p.count + p.discarded));
  }
  check_film_values(film, file);
  return film;
}

}  // namespace kozu
