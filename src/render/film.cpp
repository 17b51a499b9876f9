#include "render/film.h"

#include <algorithm>

namespace kozu {

Film::Film(int width, int height, Vec2i origin)
    : width_(width), height_(height), origin_(origin), pixels_(static_cast<size_t>(width) * height) {}

PixelFeatures Film::features(int x, int y) const {
  PixelFeatures f;
  if (features_.empty()) return f;
  const size_t i = index(x, y);
  const FeaturePixel& p = features_[i];
  const uint32_t count = taken(x, y);
  if (count == 0) return f;
  const float inv = 1.0f / static_cast<float>(count);
  f.albedo = Rgb(p.albedo.x * inv, p.albedo.y * inv, p.albedo.z * inv);
  f.normal = p.normal * inv;
  if (!positions_.empty()) f.position = positions_[i] * inv;
  f.depth = p.depth * inv;
  // Over the samples that went into the film (the others added none).
  if (const uint32_t valid = pixels_[i].count) {
    const Vec3 e = emission_.get(i).sum / static_cast<float>(valid);
    f.emission = Rgb(e.x, e.y, e.z);
  }
  f.set = true;
  return f;
}

size_t Film::bytes_per_pixel() { return sizeof(Pixel); }

void Film::clear_pixel(size_t i) {
  pixels_[i] = Pixel{};
  if (!features_.empty()) {
    features_[i] = FeaturePixel{};
    emission_.clear(i);
  }
  if (!positions_.empty()) positions_[i] = Vec3(0.0f);
  if (!hits_.empty()) hits_[i] = 0;
  if (!memory_.empty()) memory_[i] = PixelMemory{};
}

Rgb Film::mean(int x, int y) const {
  const size_t i = index(x, y);
  const Pixel& p = pixels_[i];
  if (!p.count) return Rgb(0.0f);
  const Rgb m(p.sum / static_cast<double>(p.count));
  const ApartEmission* e = apart_value(i);
  return e ? m + e->value : m;
}

Rgb Film::variance_of_mean(int x, int y) const {
  const size_t i = index(x, y);
  const Pixel& p = pixels_[i];
  if (p.count < 2) return Rgb(0.0f);
  const double n = p.count;
  const Vec3d m = p.sum / n;
  const Vec3d var = glm::max((p.sum_sq - n * m * m) / (n - 1.0), Vec3d(0.0));
  const ApartEmission* e = apart_value(i);
  return e ? Rgb(var / n) + e->variance : Rgb(var / n);
}

void Film::set_emission_apart(std::vector<ApartEmission> values) {
  emission_decided_ = true;
  apart_values_ = std::move(values);
  if (apart_values_.empty()) {
    std::vector<uint8_t>().swap(apart_);
    return;
  }
  apart_.assign(pixels_.size(), 0);
  for (const ApartEmission& e : apart_values_)
    if (e.index < apart_.size()) apart_[e.index] = 1;
}

const ApartEmission* Film::apart_value(size_t i) const {
  if (apart_.empty() || !apart_[i]) return nullptr;  // the flag first: mean() runs for every pixel
  const auto at = std::lower_bound(apart_values_.begin(), apart_values_.end(), i,
                                   [](const ApartEmission& e, size_t j) { return e.index < j; });
  return at != apart_values_.end() && at->index == i ? &*at : nullptr;
}

namespace {

// One level of the pull-push pyramid: premultiplied colour sums and weights.
struct FillLevel {
  int w = 0, h = 0;
  std::vector<Vec3> sum;
  std::vector<float> weight;
  Vec3 value(size_t i) const { return sum[i] / weight[i]; }
};

// Fills the pixels of `rgb` whose weight is 0 (see Film::rgb).
void fill_holes(std::vector<float>& rgb, FillLevel base) {
  std::vector<FillLevel> levels;
  levels.push_back(std::move(base));
  // Pull: each parent averages its sampled children, until one pixel is left.
  while (levels.back().w > 1 || levels.back().h > 1) {
    const FillLevel& c = levels.back();
    FillLevel p;
    p.w = (c.w + 1) / 2;
    p.h = (c.h + 1) / 2;
    p.sum.assign(static_cast<size_t>(p.w) * p.h, Vec3(0.0f));
    p.weight.assign(p.sum.size(), 0.0f);
    for (int y = 0; y < c.h; ++y)
      for (int x = 0; x < c.w; ++x) {
        const size_t ci = static_cast<size_t>(y) * c.w + x, pi = static_cast<size_t>(y / 2) * p.w + x / 2;
        p.sum[pi] += c.sum[ci];
        p.weight[pi] += c.weight[ci];
      }
    levels.push_back(std::move(p));
  }
  if (!(levels.back().weight[0] > 0.0f)) return;  // nothing was sampled: the image stays black
  // Push: a hole takes the bilinear interpolation of its (already complete) parent level.
  for (size_t k = levels.size() - 1; k-- > 0;) {
    const FillLevel& p = levels[k + 1];
    FillLevel& c = levels[k];
    for (int y = 0; y < c.h; ++y)
      for (int x = 0; x < c.w; ++x) {
        const size_t ci = static_cast<size_t>(y) * c.w + x;
        if (c.weight[ci] > 0.0f) continue;
        const float u = std::clamp((x + 0.5f) * 0.5f - 0.5f, 0.0f, static_cast<float>(p.w - 1));
        const float v = std::clamp((y + 0.5f) * 0.5f - 0.5f, 0.0f, static_cast<float>(p.h - 1));
        const int x0 = static_cast<int>(u), y0 = static_cast<int>(v);
        const int x1 = std::min(x0 + 1, p.w - 1), y1 = std::min(y0 + 1, p.h - 1);
        const float fx = u - x0, fy = v - y0;
        const auto at = [&](int px, int py) { return p.value(static_cast<size_t>(py) * p.w + px); };
        const Vec3 value =
            (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x1, y0)) + fy * ((1 - fx) * at(x0, y1) + fx * at(x1, y1));
        c.sum[ci] = value;
        c.weight[ci] = 1.0f;
        if (k == 0) {
          for (int ch = 0; ch < 3; ++ch) rgb[3 * ci + ch] = value[ch];
        }
      }
  }
}

}  // namespace

std::vector<float> Film::rgb() const {
  std::vector<float> out(pixels_.size() * 3);
  bool holes = false;
  for (size_t i = 0; i < pixels_.size(); ++i) {
    const Pixel& p = pixels_[i];
    const Rgb c = p.count ? Rgb(p.sum / static_cast<double>(p.count)) : Rgb(0.0f);
    float* o = &out[3 * i];
    o[0] = c.r;
    o[1] = c.g;
    o[2] = c.b;
    holes |= p.count == 0;
  }
  // The visible emission supersampled apart, where the pixel has samples (a hole is filled from its neighbours').
  for (const ApartEmission& e : apart_values_)
    if (e.index < pixels_.size() && pixels_[e.index].count) {
      float* o = &out[3 * e.index];
      o[0] += e.value.x;
      o[1] += e.value.y;
      o[2] += e.value.z;
    }
  if (holes) fill_unsampled(out);
  return out;
}

void Film::fill_unsampled(std::vector<float>& rgb) const {
  FillLevel base;
  base.w = width_;
  base.h = height_;
  base.sum.resize(pixels_.size());
  base.weight.resize(pixels_.size());
  for (size_t i = 0; i < pixels_.size(); ++i) {
    const bool sampled = pixels_[i].count > 0;
    base.sum[i] = sampled ? Vec3(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]) : Vec3(0.0f);
    base.weight[i] = sampled ? 1.0f : 0.0f;
  }
  fill_holes(rgb, std::move(base));
}

std::vector<float> Film::alpha() const {
  std::vector<float> out(pixels_.size(), 0.0f);
  if (hits_.empty()) return out;
  bool holes = false;
  for (size_t i = 0; i < pixels_.size(); ++i) {
    const uint32_t n = pixels_[i].count;
    // Double, then float: the value kozu merge recomputes from the integer counts, so the two agree bit for bit.
    if (n > 0) out[i] = static_cast<float>(static_cast<double>(hits_[i]) / static_cast<double>(n));
    holes |= n == 0;
  }
  if (holes) {
    // The colour's hole filling, on alpha replicated into three channels.
    std::vector<float> rgb(3 * out.size());
    for (size_t i = 0; i < out.size(); ++i) rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = out[i];
    fill_unsampled(rgb);
    for (size_t i = 0; i < out.size(); ++i) out[i] = rgb[3 * i];
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
    if (p.count == 0) ++s.unsampled_pixels;
  }
  s.mean_spp = static_cast<double>(s.total_samples) / pixels_.size();
  return s;
}

}  // namespace kozu
