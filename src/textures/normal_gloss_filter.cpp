#include "textures/normal_gloss_filter.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace kozu {
namespace {

// alpha^2 and a = sqrt(1 - alpha^2) (eq. (27)), kept apart so that neither end loses digits: near alpha = 0 the
// closed forms need 1 - a^2 = alpha^2 itself, not 1 minus a number close to 1.
struct Roughness {
  double alpha2, a;
};

Roughness from_alpha(double alpha) {
  const double alpha2 = std::clamp(alpha, 0.0, 1.0) * std::clamp(alpha, 0.0, 1.0);
  return {alpha2, std::sqrt(1.0 - alpha2)};
}

// Chan 2018 eq. (2): alpha^2 = 2 / (1 + 2^(18 g)), so a^2 = (2^(18 g) - 1) / (2^(18 g) + 1), by expm1 near g = 0.
Roughness from_gloss(double gloss) {
  const double g = std::clamp(gloss, 0.0, 1.0);
  const double e = std::expm1(18.0 * g * std::log(2.0));  // 2^(18 g) - 1
  return {2.0 / (2.0 + e), std::sqrt(e / (e + 2.0))};
}

// atanh(a) / a, finite at a = 0 (alpha = 1); near a = 1 atanh(a) = ln((1 + a) / alpha) keeps the digits that
// 1 - a has lost.
double atanh_over_a(const Roughness& r) {
  if (r.a < 1e-4) return 1.0 + r.a * r.a / 3.0;
  if (r.a < 0.5) return std::atanh(r.a) / r.a;
  return (std::log1p(r.a) - 0.5 * std::log(r.alpha2)) / r.a;
}

// Chan 2018 eq. (24): a / (a + (1 - a^2) atanh(a)), divided through by a.
double length_micro(const Roughness& r) { return 1.0 / (1.0 + r.alpha2 * atanh_over_a(r)); }

// Chan 2018 eq. (26): (a - (1 - a^2) atanh(a)) / a^3. Its numerator cancels to 2 a^3 / 3 as a -> 0, so small a takes
// the series sum_{k >= 1} 2 a^(2k - 2) / (4 k^2 - 1) (from atanh's series; terms below 1e-17 at a < 0.25).
double length_macro(const Roughness& r) {
  if (r.a < 0.25) {
    const double a2 = r.a * r.a;
    double sum = 0, power = 1;
    for (int k = 1; k <= 30; ++k, power *= a2) sum += 2.0 * power / (4.0 * k * k - 1.0);
    return sum;
  }
  return (1.0 - r.alpha2 * atanh_over_a(r)) / (r.a * r.a);
}

double length(const Roughness& r, ShortenedNormalModel model) {
  if (r.alpha2 == 0) return 1.0;  // a mirror: every micro-facet normal is n (and log(alpha) below is -inf)
  return model == ShortenedNormalModel::Micro ? length_micro(r) : length_macro(r);
}

}  // namespace

double wwii_gloss_to_alpha(double gloss) { return std::sqrt(from_gloss(gloss).alpha2); }  // Chan 2018 eq. (2)

double wwii_alpha_to_gloss(double alpha) {
  // eq. (2) solved for g: 2^(18 g) = 2 / alpha^2 - 1.
  const double alpha2 = std::max(alpha * alpha, 1e-300);
  return std::clamp(std::log2(std::max(2.0 / alpha2 - 1.0, 1.0)) / 18.0, 0.0, 1.0);
}

double shortened_normal_length_micro(double alpha) { return length(from_alpha(alpha), ShortenedNormalModel::Micro); }
double shortened_normal_length_macro(double alpha) { return length(from_alpha(alpha), ShortenedNormalModel::Macro); }
double shortened_normal_length(double alpha, ShortenedNormalModel model) { return length(from_alpha(alpha), model); }

// Algorithm 3's GlossToNormalLength.
double gloss_to_normal_length(double gloss, ShortenedNormalModel model) { return length(from_gloss(gloss), model); }

namespace {

// L(g) at g = i / 4096, to bracket an inverse in one cell before refining it.
constexpr int kCells = 4096;
struct LengthTable {
  std::vector<double> length;
  explicit LengthTable(ShortenedNormalModel model) : length(kCells + 1) {
    for (int i = 0; i <= kCells; ++i) length[size_t(i)] = gloss_to_normal_length(double(i) / kCells, model);
  }
};
const LengthTable& length_table(ShortenedNormalModel model) {
  static const LengthTable macro(ShortenedNormalModel::Macro), micro(ShortenedNormalModel::Micro);
  return model == ShortenedNormalModel::Micro ? micro : macro;
}

}  // namespace

// Algorithm 3's NormalLengthToGloss. The length grows monotonically with g: the table brackets the root in a cell of
// 1/4096 of g, where L is nearly linear, and the Illinois variant of regula falsi (kept inside the bracket, so it
// cannot diverge) refines it, in 2 or 3 evaluations of the closed form, until the bracket is under 1e-14 of g or the
// length matches to 1e-16 (measured by the round trip in test_normal_gloss_filter: |g error| < 1e-9 for g in [0, 1]).
double normal_length_to_gloss(double len, ShortenedNormalModel model) {
  const std::vector<double>& t = length_table(model).length;
  if (!(len > t.front())) return 0.0;  // NaN too
  if (len >= t.back()) return 1.0;
  const size_t i = size_t(std::upper_bound(t.begin(), t.end(), len) - t.begin()) - 1;  // t[i] <= len < t[i + 1]
  double lo = double(i) / kCells, hi = double(i + 1) / kCells, flo = t[i] - len, fhi = t[i + 1] - len;
  if (flo == 0) return lo;
  int side = 0;
  for (int it = 0; it < 40 && hi - lo > 1e-14; ++it) {
    const double g = std::clamp(lo - flo * (hi - lo) / (fhi - flo), lo, hi);
    const double f = gloss_to_normal_length(g, model) - len;
    if (std::abs(f) <= 1e-16) return g;
    if (f < 0) {
      lo = g, flo = f;
      if (side == -1) fhi *= 0.5;  // Illinois: halve the stale end's value so the next step crosses the root
      side = -1;
    } else {
      hi = g, fhi = f;
      if (side == 1) flo *= 0.5;
      side = 1;
    }
  }
  return 0.5 * (lo + hi);
}

double gloss_to_normal_length_fit(double x, int equation) {
  if (equation == 40)  // Chan 2018 eq. (40)
    return (0.66693 + x * (0.0609009 + x * (7.32398 + x * 0.600464))) / (1.0 + x * (-1.13467 + x * 8.78264));
  if (equation == 42)  // Chan 2018 eq. (42)
    return (0.6667 + x * (0.0942205 + x * (7.41935 + x * 0.56711))) / (1.0 + x * (-1.0881 + x * 8.83582));
  throw std::invalid_argument("gloss_to_normal_length_fit: the equation is 40 or 42");
}

NormalGlossLevel downsample_normal_gloss(const NormalGlossLevel& fine, ShortenedNormalModel model) {
  NormalGlossLevel coarse;
  coarse.width = std::max(1, fine.width / 2);
  coarse.height = std::max(1, fine.height / 2);
  const size_t texels = size_t(coarse.width) * size_t(coarse.height);
  coarse.normal.resize(3 * texels);
  coarse.gloss.resize(texels);
  // A coarse texel's footprint: 2 fine texels a side, 3 in the last row or column of an odd size.
  const auto span = [](int i, int coarse_size, int fine_size) {
    const int fine_end = (coarse_size == 1 || i == coarse_size - 1) ? fine_size : 2 * i + 2;
    return std::pair<int, int>(std::min(2 * i, fine_size - 1), fine_end);
  };
  tbb::parallel_for(tbb::blocked_range<int>(0, coarse.height), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y != rows.end(); ++y) {
      const auto [y0, y1] = span(y, coarse.height, fine.height);
      for (int x = 0; x < coarse.width; ++x) {
        const auto [x0, x1] = span(x, coarse.width, fine.width);
        double sum[3] = {0, 0, 0}, weight = 0;
        for (int fy = y0; fy < y1; ++fy)
          for (int fx = x0; fx < x1; ++fx) {
            const size_t i = size_t(fy) * size_t(fine.width) + size_t(fx);
            const double n[3] = {fine.normal[3 * i], fine.normal[3 * i + 1], fine.normal[3 * i + 2]};
            const double len = gloss_to_normal_length(fine.gloss[i], model);  // Algorithm 3, GlossToNormalLength
            if (model == ShortenedNormalModel::Macro) {
              // Algorithm 2: every texel the same macro-surface area; the mean of the shortened normals, eq. (3).
              for (int c = 0; c < 3; ++c) sum[c] += len * n[c];
              weight += 1.0;
            } else {
              // Algorithm 1: weighted by micro-surface area, dA / cos(theta) (eq. (13)) times the texel's own NDF's
              // micro-surface area per unit of its tilted plane, 1 / len (eq. (12)).
              const double nz = std::max(n[2], 0.01);
              for (int c = 0; c < 3; ++c) sum[c] += n[c] / nz;
              weight += 1.0 / (nz * len);
            }
          }
        const double v[3] = {sum[0] / weight, sum[1] / weight, sum[2] / weight};
        const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        const size_t o = size_t(y) * size_t(coarse.width) + size_t(x);
        // Algorithm 3: the shortened length back to gloss, the normal renormalised (normals that cancel exactly
        // leave no direction: +z, roughest gloss).
        coarse.gloss[o] = static_cast<float>(normal_length_to_gloss(len, model));
        for (int c = 0; c < 3; ++c)
          coarse.normal[3 * o + size_t(c)] = len > 0 ? static_cast<float>(v[c] / len) : (c == 2 ? 1.0f : 0.0f);
      }
    }
  });
  return coarse;
}

std::vector<NormalGlossLevel> filter_normal_gloss(NormalGlossLevel level0, ShortenedNormalModel model) {
  const size_t texels = size_t(level0.width) * size_t(level0.height);
  if (level0.width < 1 || level0.height < 1 || level0.normal.size() != 3 * texels || level0.gloss.size() != texels)
    throw std::invalid_argument("filter_normal_gloss: the level's size and its data disagree");
  for (size_t i = 0; i < texels; ++i) {
    float* n = &level0.normal[3 * i];
    const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (len > 0)
      for (int c = 0; c < 3; ++c) n[c] /= len;
    else
      n[0] = n[1] = 0, n[2] = 1;
  }
  std::vector<NormalGlossLevel> levels;
  levels.push_back(std::move(level0));
  while (levels.back().width > 1 || levels.back().height > 1)
    levels.push_back(downsample_normal_gloss(levels.back(), model));
  return levels;
}

}  // namespace kozu
