#include "lights/environment_portal.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace kozu {

namespace {

constexpr double kHalfPi = std::numbers::pi / 2.0;

// The unit direction at (α, β) in the portal's frame: (tan α, tan β, 1) normalized, multiplied through by
// cos α cos β so that it stays finite towards ±π/2 (Bitterli et al. 2015 §4.1).
Vec3 rectified_direction(float alpha, float beta) {
  const float sa = std::sin(alpha), ca = std::cos(alpha), sb = std::sin(beta), cb = std::cos(beta);
  return glm::normalize(Vec3(sa * cb, ca * sb, ca * cb));
}

// dω / (dα dβ) at the unit direction d of the portal's frame (environment_portal.h).
float jacobian(const Vec3& d) { return (1.0f - d.x * d.x) * (1.0f - d.y * d.y) / d.z; }

}  // namespace

EnvironmentPortal::EnvironmentPortal(const std::array<Vec3, 4>& c, const std::function<float(const Vec3&)>& luminance,
                                     int resolution)
    : origin_(c[0]), n_(std::max(resolution, 1)), cell_(std::numbers::pi / n_) {
  const Vec3d e1 = Vec3d(c[1]) - Vec3d(c[0]), e3 = Vec3d(c[3]) - Vec3d(c[0]);
  width_ = glm::length(e1);
  height_ = glm::length(e3);
  // The front (a quad light's lit side, cross(v1 − v0, v2 − v0)) faces the scene: the environment is behind it.
  const Vec3d outward = -glm::normalize(glm::cross(e1, Vec3d(c[2]) - Vec3d(c[0])));
  frame_ = Frame(Vec3(e1 / width_), Vec3(e3 / height_), Vec3(outward));

  // The table: each cell the mean of luminance × J over 2 × 2 points (eq. map: f); a cell is about a texel wide.
  const int n = n_;
  f_.assign(static_cast<size_t>(n) * n, 0.0f);
  constexpr int kSub = 2;
  tbb::parallel_for(0, n, [&](int i) {
    for (int j = 0; j < n; ++j) {
      double sum = 0.0;
      for (int a = 0; a < kSub; ++a)
        for (int b = 0; b < kSub; ++b) {
          const double alpha = (i + (a + 0.5) / kSub) * cell_ - kHalfPi;
          const double beta = (j + (b + 0.5) / kSub) * cell_ - kHalfPi;
          const Vec3 d = rectified_direction(static_cast<float>(alpha), static_cast<float>(beta));
          const float L = luminance(glm::normalize(frame_.to_world(d)));
          if (std::isfinite(L) && L > 0.0f) sum += static_cast<double>(L) * jacobian(d);
        }
      f_[static_cast<size_t>(i) * n + j] = static_cast<float>(sum / (kSub * kSub));
    }
  });
  double mean = 0.0;
  for (const float v : f_) mean += v;
  mean /= static_cast<double>(f_.size());
  // A floor keeps every direction through the window samplable (a black sky's table stays empty: mass 0, and the
  // light falls back to its map).
  const float floor = static_cast<float>(1e-4 * mean);
  for (float& v : f_) v += floor;

  sat_.assign(static_cast<size_t>(n + 1) * (n + 1), 0.0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      sat_[static_cast<size_t>(i + 1) * (n + 1) + j + 1] =
          static_cast<double>(cell(i, j)) + sat(i, j + 1) + sat(i + 1, j) - sat(i, j);
}

double EnvironmentPortal::integral(double x, double y) const {
  // Piecewise constant cells: the integral is bilinear across a cell, from the table at its corner.
  const int i = std::clamp(static_cast<int>(x), 0, n_ - 1), j = std::clamp(static_cast<int>(y), 0, n_ - 1);
  const double fx = x - i, fy = y - j;
  const double s00 = sat(i, j);
  return s00 + fx * (sat(i + 1, j) - s00) + fy * (sat(i, j + 1) - s00) + fx * fy * cell(i, j);
}

double EnvironmentPortal::column(int i, double y0, double y) const {
  const auto cumulative = [&](double t) {
    const int j = std::clamp(static_cast<int>(t), 0, n_ - 1);
    return (sat(i + 1, j) - sat(i, j)) + (t - j) * cell(i, j);
  };
  return cumulative(y) - cumulative(y0);
}

EnvironmentPortal::View EnvironmentPortal::view(const Vec3& p) const {
  View v;
  const Vec3d lp = Vec3d(p) - Vec3d(origin_);
  const double lx = glm::dot(lp, Vec3d(frame_.s)), ly = glm::dot(lp, Vec3d(frame_.t)), h = -glm::dot(lp, Vec3d(frame_.n));
  // From the environment's side, or within about a millionth of the portal's size of its plane: not through it.
  if (!(h > 1e-6 * std::max(width_, height_))) return v;
  const double to_cells = 1.0 / cell_;
  const auto edge = [&](double a, double b) {
    return std::clamp((fast_atan2(static_cast<float>(a), static_cast<float>(b)) + kHalfPi) * to_cells, 0.0,
                      static_cast<double>(n_));
  };
  v.x0 = edge(-lx, h);
  v.x1 = edge(width_ - lx, h);
  v.y0 = edge(-ly, h);
  v.y1 = edge(height_ - ly, h);
  v.base = integral(v.x0, v.y1) - integral(v.x0, v.y0);
  const double mass = integral(v.x1, v.y1) - integral(v.x1, v.y0) - v.base;
  v.mass = std::isfinite(mass) && mass > 0.0 ? mass : 0.0;
  return v;
}

Vec3 EnvironmentPortal::sample(const View& v, const Vec2& u, float* pdf) const {
  *pdf = 0.0f;
  if (v.empty()) return Vec3(0.0f);
  // α: the rectangle's marginal G(x) = ∫ over [x0, x] × [y0, y1], searched over the columns it spans, then solved
  // within the column, where it is linear (eq. map: sampling). At a column's edge k the table is linear in y within
  // a row: G(k) = S(k, y1) − S(k, y0) − G0, read from two neighbouring entries of the table per y.
  const int n = n_;
  const int j0 = std::clamp(static_cast<int>(v.y0), 0, n - 1), j1 = std::clamp(static_cast<int>(v.y1), 0, n - 1);
  const double fy0 = v.y0 - j0, fy1 = v.y1 - j1;
  const auto at_edge = [&](int k) {
    const double* row = &sat_[static_cast<size_t>(k) * (n + 1)];
    return (row[j1] + fy1 * (row[j1 + 1] - row[j1])) - (row[j0] + fy0 * (row[j0 + 1] - row[j0]));
  };
  const double base = v.base;
  const double t = static_cast<double>(u.x) * v.mass + base;  // the target, on the scale of at_edge
  int lo = std::clamp(static_cast<int>(v.x0), 0, n - 1);
  int hi = std::clamp(static_cast<int>(std::ceil(v.x1)) - 1, lo, n - 1);
  // The last edge at or below t (lo's always is): halving steps whose outcome only moves the base, so that the
  // unpredictable comparisons become conditional moves.
  // Each step also prefetches both edges the next step may read (the table does not stay in the cache: each step
  // would otherwise wait for its own miss).
  const auto prefetch_edge = [&](int k) {
    const double* row = &sat_[static_cast<size_t>(k) * (n + 1)];
    __builtin_prefetch(row + j0);
    __builtin_prefetch(row + j1);
  };
  for (int len = hi - lo + 1; len > 1;) {
    const int half = len / 2, next = (len - half) / 2;
    prefetch_edge(lo + next);
    prefetch_edge(lo + half + next);
    lo = at_edge(lo + half) <= t ? lo + half : lo;
    len -= half;
  }
  const int i = lo;
  const double w = column(i, v.y0, v.y1);  // G's slope in column i
  if (!(w > 0.0)) return Vec3(0.0f);
  const double left = std::max(static_cast<double>(i), v.x0), right = std::min(static_cast<double>(i + 1), v.x1);
  const double at_left = left == i ? at_edge(i) : base;
  const double x = std::clamp(left + (t - at_left) / w, left, right);

  // β in column i: the column's cdf from y0, searched over the rows it spans, linear within a row.
  const double* col = &sat_[static_cast<size_t>(i + 1) * (n + 1)];
  const double* prev = &sat_[static_cast<size_t>(i) * (n + 1)];
  const float* fcol = &f_[static_cast<size_t>(i) * n];
  const double c0 = (col[j0] - prev[j0]) + fy0 * fcol[j0];  // the column's integral over [0, y0]
  const double t2 = static_cast<double>(u.y) * w + c0;
  lo = j0;
  hi = std::max(std::clamp(static_cast<int>(std::ceil(v.y1)) - 1, 0, n - 1), lo);
  for (int len = hi - lo + 1; len > 1;) {
    const int half = len / 2, next = (len - half) / 2;
    for (const int k : {lo + next, lo + half + next}) {
      __builtin_prefetch(col + k);
      __builtin_prefetch(prev + k);
    }
    lo = col[lo + half] - prev[lo + half] <= t2 ? lo + half : lo;
    len -= half;
  }
  const int j = lo;
  const double fij = fcol[j];
  if (!(fij > 0.0)) return Vec3(0.0f);
  const double bottom = std::max(static_cast<double>(j), v.y0), top = std::min(static_cast<double>(j + 1), v.y1);
  const double at_bottom = bottom == j ? col[j] - prev[j] : c0;
  const double y = std::clamp(bottom + (t2 - at_bottom) / fij, bottom, top);

  const Vec3 d = rectified_direction(static_cast<float>(x * cell_ - kHalfPi), static_cast<float>(y * cell_ - kHalfPi));
  const float J = jacobian(d);
  if (!(J > 0.0f)) return Vec3(0.0f);
  *pdf = static_cast<float>(fij / (v.mass * cell_ * cell_)) / J;  // eq. map: pdf(ω) = f / (M Δ² J)
  return glm::normalize(frame_.to_world(d));
}

float EnvironmentPortal::pdf(const View& v, const Vec3& dir) const {
  if (v.empty()) return 0.0f;
  const Vec3 d = frame_.to_local(dir);
  if (!(d.z > 0.0f)) return 0.0f;
  // fast_atan2 (core/math.h, within 5e-7 rad) against cells of π/n: a direction within that of a cell's edge may
  // read its neighbour, as sample's own rounding may.
  const double to_cells = 1.0 / cell_;
  const double x = (fast_atan2(d.x, d.z) + kHalfPi) * to_cells, y = (fast_atan2(d.y, d.z) + kHalfPi) * to_cells;
  if (x < v.x0 || x > v.x1 || y < v.y0 || y > v.y1) return 0.0f;  // misses the window
  const int i = std::clamp(static_cast<int>(x), 0, n_ - 1), j = std::clamp(static_cast<int>(y), 0, n_ - 1);
  const float J = jacobian(d);
  if (!(J > 0.0f)) return 0.0f;
  return static_cast<float>(cell(i, j) / (v.mass * cell_ * cell_)) / J;
}

}  // namespace kozu
