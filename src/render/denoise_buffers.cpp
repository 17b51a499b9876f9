#include "render/denoise_buffers.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace kozu::denoise_detail {

// The mean of v over the (2R+1)² box around each pixel (clipped at the borders).
std::vector<float> box_mean(const std::vector<float>& v, int w, int h, int R) {
  std::vector<float> rows(v.size()), out(v.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float sum = 0.0f;
      int cnt = 0;
      for (int t = std::max(0, x - R); t <= std::min(w - 1, x + R); ++t, ++cnt) sum += v[size_t(y) * w + t];
      rows[size_t(y) * w + x] = sum / static_cast<float>(cnt);
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float sum = 0.0f;
      int cnt = 0;
      for (int t = std::max(0, y - R); t <= std::min(h - 1, y + R); ++t, ++cnt) sum += rows[size_t(t) * w + x];
      out[size_t(y) * w + x] = sum / static_cast<float>(cnt);
    }
  return out;
}

const VisibleEmission& emission_to_add_back(const Film& film, const VisibleEmission* given, VisibleEmission& own,
                                            const char* who) {
  if (!film.has_features()) throw std::logic_error(std::string(who) + ": the film keeps no features");
  if (!given) return own = visible_emission(film);
  const size_t n = film.pixels().size();
  if (given->value.size() != n || given->apart.size() != n)
    throw std::logic_error(std::string(who) + ": one visible emission per pixel expected");
  return *given;
}

void put_pixel(std::vector<float>& out, size_t i, const Vec3& filtered, const VisibleEmission& emission) {
  const Vec3 v = filtered + (emission.apart[i] ? emission.value[i] : Vec3(0.0f));
  for (int c = 0; c < 3; ++c) out[3 * i + c] = std::isfinite(v[c]) ? std::max(v[c], 0.0f) : 0.0f;
}

// The half buffers of the radiance without the visible emission (emission_refine.h), which is added back after.
Buffers split(const Film& film, const VisibleEmission& emission) {
  Buffers b;
  b.w = film.width();
  b.h = film.height();
  const size_t n = static_cast<size_t>(b.w) * b.h;
  const std::vector<float> filled = film.rgb();  // holes filled from their neighbours
  for (auto& v : b.half) v.resize(n);
  b.var.resize(n);
  b.albedo.resize(n);
  b.normal.resize(n);
  b.depth.resize(n);
  std::vector<float> dual(n);
  const Vec2i o = film.origin();
  for (int y = 0; y < b.h; ++y)
    for (int x = 0; x < b.w; ++x) {
      const size_t i = static_cast<size_t>(y) * b.w + x;
      const Film::Pixel& p = film.pixels()[i];
      const Film::FeaturePixel& f = film.feature_pixels()[i];
      const uint32_t odd_count = p.count - std::min(p.count, f.even_count);
      const bool apart = emission.apart[i];
      if (f.even_count == 0 || odd_count == 0) {
        const Vec3 mean = Vec3(filled[3 * i], filled[3 * i + 1], filled[3 * i + 2]);
        b.half[0][i] = b.half[1][i] = apart ? mean - f.emission / static_cast<float>(std::max(p.count, 1u)) : mean;
        dual[i] = kUnknownVariance;  // the colour distance then accepts every neighbour
      } else {
        const Vec3 e_even = apart ? f.emission_even : Vec3(0.0f), e_all = apart ? f.emission : Vec3(0.0f);
        b.half[0][i] = (f.even_sum - e_even) / static_cast<float>(f.even_count);
        b.half[1][i] = Vec3((p.sum - Vec3d(f.even_sum) - Vec3d(e_all - e_even)) / static_cast<double>(odd_count));
        // E[(A − B)²] = Var A + Var B: half of it estimates one half's variance.
        const Vec3 d = b.half[0][i] - b.half[1][i];
        dual[i] = 0.5f * glm::dot(d, d) / 3.0f;
      }
      const PixelFeatures pf = film.features(o.x + x, o.y + y);
      b.albedo[i] = Vec3(pf.albedo.r, pf.albedo.g, pf.albedo.b);
      b.normal[i] = pf.normal;
      b.depth[i] = pf.depth;
    }
  // The two-buffer estimate has one degree of freedom per pixel: a 3 × 3 box mean steadies it.
  b.var = box_mean(dual, b.w, b.h, 1);
  for (float& v : b.var) v = std::min(v, kUnknownVariance);
  return b;
}

}  // namespace kozu::denoise_detail
