#include "render/aov.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace kozu {

namespace {

struct AovInfo {
  Aov aov;
  const char* name;
  std::vector<const char*> channels;
};

const std::vector<AovInfo>& aov_table() {
  static const std::vector<AovInfo> table = {
      {Aov::Albedo, "albedo", {"albedo.R", "albedo.G", "albedo.B"}},
      {Aov::Normal, "normal", {"N.X", "N.Y", "N.Z"}},
      {Aov::Depth, "depth", {"Z"}},
      {Aov::Position, "position", {"P.X", "P.Y", "P.Z"}},
      {Aov::Variance, "variance", {"variance.R", "variance.G", "variance.B"}},
      {Aov::SampleCount, "sample_count", {"sample_count"}},
      {Aov::Emission, "emission", {"emission.R", "emission.G", "emission.B"}},
  };
  return table;
}

const AovInfo& info(Aov a) {
  for (const AovInfo& i : aov_table())
    if (i.aov == a) return i;
  throw std::logic_error("unknown AOV");
}

}  // namespace

std::vector<Aov> parse_aovs(std::string_view list) {
  std::vector<Aov> out;
  size_t start = 0;
  while (start <= list.size()) {
    const size_t comma = std::min(list.find(',', start), list.size());
    const std::string_view name = list.substr(start, comma - start);
    const auto it =
        std::find_if(aov_table().begin(), aov_table().end(), [&](const AovInfo& i) { return name == i.name; });
    if (it == aov_table().end())
      throw std::invalid_argument("unknown AOV '" + std::string(name) +
                                  "' (albedo, normal, depth, position, variance, sample_count, emission)");
    if (std::find(out.begin(), out.end(), it->aov) != out.end())
      throw std::invalid_argument("AOV '" + std::string(name) + "' given twice");
    out.push_back(it->aov);
    start = comma + 1;
  }
  return out;
}

std::string_view aov_name(Aov a) { return info(a).name; }
size_t aov_channel_count(Aov a) { return info(a).channels.size(); }

bool needs_features(const std::vector<Aov>& aovs) {
  return std::any_of(aovs.begin(), aovs.end(), [](Aov a) {
    return a == Aov::Albedo || a == Aov::Normal || a == Aov::Depth || a == Aov::Position || a == Aov::Emission;
  });
}

bool needs_positions(const std::vector<Aov>& aovs) {
  return std::find(aovs.begin(), aovs.end(), Aov::Position) != aovs.end();
}

void add_aov_channels(const Film& film, const std::vector<Aov>& aovs, ImageExtras& extras) {
  const size_t old = extras.channels.size();
  size_t added = 0;
  for (Aov a : aovs) added += info(a).channels.size();
  if (added == 0) return;
  const size_t stride = old + added;
  const size_t n = static_cast<size_t>(film.width()) * film.height();
  // Re-interleave what is there with the new channels.
  std::vector<float> data(n * stride);
  for (size_t i = 0; i < n && old > 0; ++i) std::copy_n(&extras.data[i * old], old, &data[i * stride]);
  for (Aov a : aovs)
    for (const char* c : info(a).channels) extras.channels.emplace_back(c);
  const Vec2i o = film.origin();
  for (int y = 0; y < film.height(); ++y)
    for (int x = 0; x < film.width(); ++x) {
      const size_t i = static_cast<size_t>(y) * film.width() + x;
      float* out = &data[i * stride + old];
      const PixelFeatures f = film.features(o.x + x, o.y + y);
      for (Aov a : aovs) switch (a) {
          case Aov::Albedo:
            *out++ = f.albedo.r, *out++ = f.albedo.g, *out++ = f.albedo.b;
            break;
          case Aov::Normal:
            *out++ = f.normal.x, *out++ = f.normal.y, *out++ = f.normal.z;
            break;
          case Aov::Depth:
            *out++ = f.depth;
            break;
          case Aov::Position:
            *out++ = f.position.x, *out++ = f.position.y, *out++ = f.position.z;
            break;
          case Aov::Variance: {
            const Rgb v = film.variance_of_mean(o.x + x, o.y + y);
            *out++ = v.r, *out++ = v.g, *out++ = v.b;
            break;
          }
          case Aov::SampleCount:
            *out++ = static_cast<float>(film.count(o.x + x, o.y + y));
            break;
          case Aov::Emission:
            *out++ = f.emission.r, *out++ = f.emission.g, *out++ = f.emission.b;
            break;
        }
    }
  extras.data = std::move(data);
}

}  // namespace kozu
