#include "render/film.h"

namespace kozu {

Film::Film(int width, int height) : width_(width), height_(height), pixels_(static_cast<size_t>(width) * height) {}

Rgb Film::mean(int x, int y) const {
  const Pixel& p = pixels_[index(x, y)];
  return p.count ? Rgb(p.sum / static_cast<double>(p.count)) : Rgb(0.0f);
}

Rgb Film::variance_of_mean(int x, int y) const {
  const Pixel& p = pixels_[index(x, y)];
  if (p.count < 2) return Rgb(0.0f);
  const double n = p.count;
  const Vec3d m = p.sum / n;
  const Vec3d var = glm::max((p.sum_sq - n * m * m) / (n - 1.0), Vec3d(0.0));
  return Rgb(var / n);
}

std::vector<float> Film::rgb() const {
  std::vector<float> out(pixels_.size() * 3);
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x) {
      const Rgb c = mean(x, y);
      float* o = &out[3 * index(x, y)];
      o[0] = c.r;
      o[1] = c.g;
      o[2] = c.b;
    }
  return out;
}

Film::Summary Film::summary() const {
  Summary s;
  if (pixels_.empty()) return s;
  s.min_spp = pixels_[0].count;
  for (const Pixel& p : pixels_) {
    s.min_spp = std::min(s.min_spp, p.count);
    s.max_spp = std::max(s.max_spp, p.count);
    s.total_samples += p.count;
    s.discarded_samples += p.discarded;
    if (p.discarded) ++s.pixels_with_discarded;
  }
  s.mean_spp = static_cast<double>(s.total_samples) / pixels_.size();
  return s;
}

}  // namespace kozu
