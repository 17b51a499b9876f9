#include "tools/chandrasekhar_h.h"

#include "core/gauss_legendre.h"

#include "core/math.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace kozu {

namespace {

// The rule for ∫₀^{π/2} f(θ) dθ: an m-point Gauss rule after θ = (π/2) g(u), g(u) = u³(10 − 15u + 6u²), which
// flattens the logarithmic end-point singularity of the conservative case at θ = 0 and the narrow peak of
// width ~μ at θ = π/2 for small μ.
struct ThetaRule {
  std::vector<double> theta, weight, log_term;
};

ThetaRule theta_rule(double omega, int m) {
  std::vector<double> u, w;
  gauss_legendre_unit(m, &u, &w);
  ThetaRule rule;
  for (int i = 0; i < m; ++i) {
    const double x = u[i];
    const double g = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x);
    const double dg = 30.0 * x * x * (1.0 - x) * (1.0 - x);
    const double theta = 0.5 * std::numbers::pi * g;
    // 1 − ϖ θ cot θ = (1 − ϖ) + ϖ (1 − θ cot θ); near θ = 0 the series 1 − θ cot θ = θ²/3 + θ⁴/45 + …
    // keeps the digits that the conservative case's logarithm needs.
    const double t2 = theta * theta;
    const double one_minus_theta_cot = t2 < 1e-4 ? t2 / 3.0 + t2 * t2 / 45.0 : 1.0 - theta / std::tan(theta);
    const double one_minus = (1.0 - omega) + omega * one_minus_theta_cot;
    rule.theta.push_back(theta);
    rule.weight.push_back(0.5 * std::numbers::pi * dg * w[i]);
    rule.log_term.push_back(std::log(one_minus));
  }
  return rule;
}

}  // namespace

ChandrasekharH::ChandrasekharH(double omega, int nodes) : omega_(omega) {
  if (!(omega >= 0.0 && omega <= 1.0)) throw std::invalid_argument("H-function: omega must lie in [0, 1]");
  if (nodes < 2) throw std::invalid_argument("H-function: needs at least 2 nodes");
  gauss_legendre_unit(nodes, &mu_, &weight_);
  const ThetaRule rule = theta_rule(omega, kThetaNodes);
  for (size_t i = 0; i < rule.theta.size(); ++i) {
    cos2_.push_back(sqr(std::cos(rule.theta[i])));
    sin2_.push_back(sqr(std::sin(rule.theta[i])));
    weighted_log_.push_back(rule.weight[i] * rule.log_term[i]);
  }
  h_.resize(nodes);
  for (int j = 0; j < nodes; ++j) h_[j] = (*this)(mu_[j]);
}

double ChandrasekharH::operator()(double mu) const {
  if (omega_ == 0.0 || mu <= 0.0) return 1.0;
  double sum = 0.0;
  for (size_t i = 0; i < cos2_.size(); ++i) sum += weighted_log_[i] / (cos2_[i] + mu * mu * sin2_[i]);
  return std::exp(-mu / std::numbers::pi * sum);  // the closed form of H
}

double ChandrasekharH::moment(int k) const {
  double sum = 0.0;
  for (size_t j = 0; j < mu_.size(); ++j) sum += weight_[j] * std::pow(mu_[j], k) * h_[j];
  return sum;
}

namespace chandrasekhar {

double surface_albedo(SubsurfaceIllumination illumination, double alpha) {
  if (alpha <= 0.0) return 0.0;
  const ChandrasekharH h(alpha);
  const double root = std::sqrt(1.0 - alpha);
  if (illumination == SubsurfaceIllumination::Searchlight) return 1.0 - h(1.0) * root;
  return 1.0 - 2.0 * root * h.moment(1);
}

double single_scattering_albedo(SubsurfaceIllumination illumination, double A) {
  if (!(A >= 0.0 && A <= 1.0)) throw std::invalid_argument("surface albedo must lie in [0, 1]");
  if (A == 0.0) return 0.0;
  if (A == 1.0) return 1.0;
  // A decreases with t = sqrt(1 − α): A(t = 0) = 1, A(t = 1) = 0.
  double lo = 0.0, hi = 1.0;
  for (int it = 0; it < 56 && hi - lo > 1e-15; ++it) {
    const double t = 0.5 * (lo + hi);
    if (surface_albedo(illumination, 1.0 - t * t) > A)
      lo = t;
    else
      hi = t;
  }
  const double t = 0.5 * (lo + hi);
  return 1.0 - t * t;
}

}  // namespace chandrasekhar

}  // namespace kozu
