#include "textures/detail_gloss.h"

#include "textures/normal_gloss_filter.h"

#include <algorithm>
#include <cmath>

namespace kozu {

namespace {
constexpr ShortenedNormalModel kMacro = ShortenedNormalModel::Macro;  // Algorithm 2, as the detail maps are filtered
}  // namespace

double detail_gloss_exact(double ga, double gb) {
  const double length = gloss_to_normal_length(std::clamp(ga, 0.0, 1.0), kMacro) *
                        gloss_to_normal_length(std::clamp(gb, 0.0, 1.0), kMacro);  // Chan 2018 eq. (34)
  // Below L(0) the combined NDF is wider than eq. (2)'s roughest: gloss 0 (eq. 37's clamp says the same).
  return normal_length_to_gloss(length, kMacro);
}

double detail_gloss_fit(double ga, double gb, const DetailGlossFit& f) {
  const double s = ga + gb, s2 = ga * ga + gb * gb, m = ga * gb;
  const double p = f.p[0] + f.p[1] * s + f.p[2] * s2 + f.p[3] * m;  // Chan 2018 eq. (35)
  const double q = f.q[0] + f.q[1] * s + f.q[2] * s2 + f.q[3] * m;  // eq. (36)
  return std::clamp(p / q, 0.0, 1.0);                               // eq. (37)
}

DetailGlossTable::DetailGlossTable() {
  for (int i = 0; i < kSize; ++i) {
    const double g = static_cast<double>(i) / (kSize - 1);
    e_[size_t(i)] = static_cast<float>(1.0 - gloss_to_normal_length(g, kMacro));
  }
  e_max_ = e_[0];  // 1 - L(0) = 1/3
  log_e_max_ = std::log(e_[0]);
  log_e_min_ = std::log(e_[kSize - 1]);
  for (int i = 0; i < kSize; ++i) {
    const double log_e = log_e_min_ + (log_e_max_ - log_e_min_) * static_cast<double>(i) / (kSize - 1);
    gloss_[size_t(i)] = static_cast<float>(normal_length_to_gloss(1.0 - std::exp(log_e), kMacro));
  }
}

const DetailGlossTable& DetailGlossTable::instance() {
  static const DetailGlossTable table;
  return table;
}

float DetailGlossTable::combine(float ga, float gb) const {
  const auto e_of = [this](float g) {
    const float x = (g > 0.0f ? std::min(g, 1.0f) : 0.0f) * (kSize - 1);  // NaN -> 0: a defined table index
    const int i = std::min(static_cast<int>(x), kSize - 2);
    const float f = x - static_cast<float>(i);
    return e_[size_t(i)] + f * (e_[size_t(i + 1)] - e_[size_t(i)]);
  };
  const float ea = e_of(ga), eb = e_of(gb);
  const float e = ea + eb - ea * eb;  // 1 - L_a L_b: Chan 2018 eq. (34)
  if (e >= e_max_) return 0.0f;       // below L(0): gloss 0
  const float x = (std::log(e) - log_e_min_) / (log_e_max_ - log_e_min_) * (kSize - 1);
  if (x <= 0.0f) return gloss_[0];
  const int i = std::min(static_cast<int>(x), kSize - 2);
  const float f = x - static_cast<float>(i);
  return std::clamp(gloss_[size_t(i)] + f * (gloss_[size_t(i + 1)] - gloss_[size_t(i)]), 0.0f, 1.0f);
}

}  // namespace kozu
