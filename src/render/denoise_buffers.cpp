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
  if (given->size() != n)
    throw std::logic_error(std::string(who) + ": one visible emission per pixel expected");
  return *given;
}

void put_pixel(std::vector<float>& out, size_t i, const Vec3& filtered, const VisibleEmission& emission) {
  const Vec3 v = filtered + (emission.apart(i) ? emission.value(i) : Vec3(0.0f));
  for (int c = 0; c < 3; ++c) out[3 * i + c] = std::isfinite(v[c]) ? std::max(v[c], 0.0f) : 0.0f;
}

namespace {

bool film_has_holes(const Film& film) {
  for (const Film::Pixel& p : film.pixels())
    if (p.count == 0) return true;
  return false;
}

// Rows [y0, y1) of the half buffers of the radiance without the visible emission (emission_refine.h), which is added
// back after; `filled`: film.rgb(), read where a pixel has no sample (null when none lacks one).
Buffers split_rows(const Film& film, const VisibleEmission& emission, int y0, int y1, const std::vector<float>* filled) {
  Buffers b;
  b.w = film.width();
  b.h = film.height();
  b.y0 = std::clamp(y0, 0, b.h);
  b.y1 = std::clamp(y1, b.y0, b.h);
  // The variance's box reads a row either side: its two-buffer estimates cover [d0, d1).
  const int d0 = std::max(0, b.y0 - 1), d1 = std::min(b.h, b.y1 + 1);
  const size_t n = static_cast<size_t>(b.w) * (b.y1 - b.y0);
  for (auto& v : b.half) v.resize(n);
  b.albedo.resize(n);
  b.normal.resize(n);
  b.depth.resize(n);
  std::vector<float> dual(static_cast<size_t>(b.w) * (d1 - d0));
  const Vec2i o = film.origin();
  for (int y = d0; y < d1; ++y)
    for (int x = 0; x < b.w; ++x) {
      const size_t i = static_cast<size_t>(y) * b.w + x;
      const Film::Pixel& p = film.pixels()[i];
      const Film::FeaturePixel& f = film.feature_pixels()[i];
      const uint32_t odd_count = p.count - std::min(p.count, f.even_count);
      const bool apart = emission.apart(i);
      Vec3 half[2];
      float& d = dual[static_cast<size_t>(y - d0) * b.w + x];
      if (f.even_count == 0 || odd_count == 0) {
        // Film::rgb's mean; a pixel without samples takes its neighbours' (filled).
        Vec3 mean(0.0f);
        if (p.count > 0)
          mean = Vec3(Rgb(p.sum / static_cast<double>(p.count)));
        else if (filled)
          mean = Vec3(filled->at(3 * i), filled->at(3 * i + 1), filled->at(3 * i + 2));
        half[0] = half[1] =
            apart ? mean - film.emission_sums().get(i).sum / static_cast<float>(std::max(p.count, 1u)) : mean;
        d = kUnknownVariance;  // the colour distance then accepts every neighbour
      } else {
        const EmissionSums::Pixel e = apart ? film.emission_sums().get(i) : EmissionSums::Pixel{};
        const Vec3 e_even = e.even, e_all = e.sum;
        half[0] = (f.even_sum - e_even) / static_cast<float>(f.even_count);
        half[1] = Vec3((p.sum - Vec3d(f.even_sum) - Vec3d(e_all - e_even)) / static_cast<double>(odd_count));
        // E[(A − B)²] = Var A + Var B: half of it estimates one half's variance.
        const Vec3 diff = half[0] - half[1];
        d = 0.5f * glm::dot(diff, diff) / 3.0f;
      }
      if (y < b.y0 || y >= b.y1) continue;
      const size_t j = b.index(x, y);
      b.half[0][j] = half[0];
      b.half[1][j] = half[1];
      const PixelFeatures pf = film.features(o.x + x, o.y + y);
      b.albedo[j] = Vec3(pf.albedo.r, pf.albedo.g, pf.albedo.b);
      b.normal[j] = pf.normal;
      b.depth[j] = pf.depth;
    }
  // The two-buffer estimate has one degree of freedom per pixel: a 3 × 3 box mean steadies it. The box is clipped
  // at the image's edges only: [d0, d1) holds every row it reads for rows [y0, y1).
  const std::vector<float> var = box_mean(dual, b.w, d1 - d0, 1);
  b.var.assign(var.begin() + static_cast<ptrdiff_t>(b.y0 - d0) * b.w,
               var.begin() + static_cast<ptrdiff_t>(b.y1 - d0) * b.w);
  for (float& v : b.var) v = std::min(v, kUnknownVariance);
  return b;
}

}  // namespace

HalfBufferRows::HalfBufferRows(const Film& film, const VisibleEmission& emission)
    : film_(film), emission_(emission), filled_(film_has_holes(film) ? film.rgb() : std::vector<float>{}) {}

Buffers HalfBufferRows::rows(int y0, int y1) const {
  return split_rows(film_, emission_, y0, y1, filled_.empty() ? nullptr : &filled_);
}

Buffers split(const Film& film, const VisibleEmission& emission) {
  return HalfBufferRows(film, emission).rows(0, film.height());
}

}  // namespace kozu::denoise_detail
