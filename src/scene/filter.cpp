#include "scene/filter.h"

#include "core/warp.h"

#include <stdexcept>

namespace kozu {

PixelFilter::PixelFilter(Type type) : type_(type) {
  if (type == Type::Tent) radius_ = 1.0f;
  if (type != Type::Gaussian) return;
  radius_ = 1.5f;
  constexpr float kSigma = 0.5f;
  // Tabulate the CDF of the Gaussian truncated at 3 sigma, then invert it on a uniform grid of
  // probabilities. The density is not shifted to reach zero at the edge: a density that vanishes
  // there gives an inverse CDF with infinite slope at p = 0 and 1, which a table of uniform p
  // steps cannot follow, while exp(-4.5) = 1.1% of the peak keeps the inverse smooth.
  constexpr int kN = 4096;
  std::vector<double> cdf(kN + 1, 0.0);
  for (int i = 0; i < kN; ++i) {
    const double a = -radius_ + i * (2.0 * radius_ / kN), b = a + 2.0 * radius_ / kN;
    cdf[i + 1] = cdf[i] + (std::erf(b / (std::sqrt(2.0) * kSigma)) - std::erf(a / (std::sqrt(2.0) * kSigma)));
  }
  for (double& c : cdf) c /= cdf[kN];
  inverse_cdf_.resize(kN + 1);
  int j = 0;
  for (int i = 0; i <= kN; ++i) {
    const double p = static_cast<double>(i) / kN;
    while (j < kN - 1 && cdf[j + 1] < p) ++j;
    const double w = cdf[j + 1] - cdf[j];
    const double t = w > 0 ? (p - cdf[j]) / w : 0.0;
    inverse_cdf_[i] = static_cast<float>(-radius_ + (j + std::clamp(t, 0.0, 1.0)) * (2.0 * radius_ / kN));
  }
}

PixelFilter::Type PixelFilter::parse(const std::string& name) {
  if (name == "box") return Type::Box;
  if (name == "tent") return Type::Tent;
  if (name == "gaussian") return Type::Gaussian;
  throw std::invalid_argument("unknown filter " + name);
}

const char* PixelFilter::name(Type type) {
  switch (type) {
    case Type::Box:
      return "box";
    case Type::Tent:
      return "tent";
    case Type::Gaussian:
      return "gaussian";
  }
  return "?";
}

float PixelFilter::sample_1d(float u) const {
  switch (type_) {
    case Type::Box:
      return u - 0.5f;
    case Type::Tent:
      return warp::sample_tent(u, radius_);
    case Type::Gaussian: {
      const float x = u * (inverse_cdf_.size() - 1);
      const size_t i = std::min(static_cast<size_t>(x), inverse_cdf_.size() - 2);
      const float t = x - static_cast<float>(i);
      return inverse_cdf_[i] + t * (inverse_cdf_[i + 1] - inverse_cdf_[i]);
    }
  }
  return 0.0f;
}

}  // namespace kozu
