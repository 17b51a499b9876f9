#include "textures/surface_occlusion.h"

#include <tbb/parallel_for.h>

#include <limits>

namespace kozu {
namespace {

constexpr double kPi = 3.14159265358979323846;

inline int wrap_index(int i, int n) {
  i %= n;
  return i < 0 ? i + n : i;
}

// Bilinear height at a point in texel-centre coordinates (texel (x, y) is at (x, y)), wrapping: the tile repeats.
inline double height_at(const HeightField& hf, double x, double y) {
  const double fx = std::floor(x), fy = std::floor(y);
  const double tx = x - fx, ty = y - fy;
  const int x0 = wrap_index(int(fx), hf.width), x1 = wrap_index(int(fx) + 1, hf.width);
  const int y0 = wrap_index(int(fy), hf.height), y1 = wrap_index(int(fy) + 1, hf.height);
  const float* h = hf.h.data();
  const size_t w = size_t(hf.width);
  const double top = (1 - tx) * h[y0 * w + x0] + tx * h[y0 * w + x1];
  const double bottom = (1 - tx) * h[y1 * w + x0] + tx * h[y1 * w + x1];
  return (1 - ty) * top + ty * bottom;
}

// GTAO's inner integral for one side of a slice: ∫ from 0 to h of |sin θ| cos(θ - γ) dθ (h of either sign).
inline double side_integral(double gamma, double h) {
  return 0.25 * (-std::cos(2.0 * h - gamma) + std::cos(gamma) + 2.0 * h * std::sin(gamma));
}

}  // namespace

double slice_visibility(double gamma, double projected_length, double h_minus, double h_plus) {
  // The normal's hemisphere bounds the arc (a horizon below it hides nothing more).
  h_plus = std::min(h_plus, gamma + 0.5 * kPi);
  h_minus = std::max(h_minus, gamma - 0.5 * kPi);
  return projected_length * (side_integral(gamma, h_plus) + side_integral(gamma, h_minus));
}

std::vector<float> visibility(const HeightField& hf, const OcclusionOptions& o) {
  const int w = hf.width, h = hf.height;
  std::vector<float> out(size_t(w) * h, 1.0f);
  const int directions = std::max(1, o.directions);
  const double step = o.step > 0 ? double(o.step) : 1.0;
  const int steps = int(std::floor(double(o.radius) / step + 1e-9));
  const double scale = o.height_scale;
  std::vector<double> dir_x(static_cast<size_t>(directions)), dir_y(static_cast<size_t>(directions));
  for (int k = 0; k < directions; ++k) {  // evenly over [0, π), the axes included
    dir_x[size_t(k)] = std::cos(kPi * k / directions);
    dir_y[size_t(k)] = std::sin(kPi * k / directions);
  }
  // The highest point of the map bounds what any farther sample can add: a march stops once it cannot raise the
  // horizon (exact, and most of the work on maps of small bumps).
  double z_top = -std::numeric_limits<double>::infinity();
  for (float v : hf.h) z_top = std::max(z_top, scale * v);
  tbb::parallel_for(0, h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const double z0 = scale * hf.h[size_t(y) * w + x];
      // The height field's normal (central differences), in image axes (x right, y down, z up).
      const double dzdx = 0.5 * scale * (height_at(hf, x + 1, y) - height_at(hf, x - 1, y));
      const double dzdy = 0.5 * scale * (height_at(hf, x, y + 1) - height_at(hf, x, y - 1));
      const double inv = 1.0 / std::sqrt(dzdx * dzdx + dzdy * dzdy + 1.0);
      const double nx = -dzdx * inv, ny = -dzdy * inv, nz = inv;
      double sum = 0;
      for (int k = 0; k < directions; ++k) {
        const double dx = dir_x[size_t(k)], dy = dir_y[size_t(k)];
        // The normal projected into the slice plane (d, z): its angle from +z towards +d and its length.
        const double nd = nx * dx + ny * dy;
        const double gamma = std::atan2(nd, nz);
        const double length = std::sqrt(nd * nd + nz * nz);
        // The highest horizon on each side, as the largest tangent of elevation seen from the texel.
        double best[2] = {-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
        for (int side = 0; side < 2; ++side) {
          const double s = side == 0 ? 1.0 : -1.0;
          for (int i = 1; i <= steps; ++i) {
            const double t = i * step;
            if ((z_top - z0) / t <= best[side]) break;
            const double dz = scale * height_at(hf, x + s * t * dx, y + s * t * dy) - z0;
            best[side] = std::max(best[side], dz / t);
          }
        }
        // Horizon angles from +z: π/2 minus the elevation (an empty march leaves the normal's hemisphere).
        const double h_plus = std::isinf(best[0]) ? kPi : 0.5 * kPi - std::atan(best[0]);
        const double h_minus = std::isinf(best[1]) ? -kPi : -(0.5 * kPi - std::atan(best[1]));
        sum += slice_visibility(gamma, length, h_minus, h_plus);  // Chan 2018 eq. (43), one slice
      }
      out[size_t(y) * w + x] = float(std::clamp(sum / directions, 0.0, 1.0));
    }
  });
  return out;
}

double adjusted_visibility(double a, double rho, OcclusionAdjustment model) {
  switch (model) {
    case OcclusionAdjustment::Black:
      return a;  // Chan 2018 eq. (45)
    case OcclusionAdjustment::WhiteOccluded:
      return a * (1.0 - a) + a;  // Chan 2018 eq. (46)
    case OcclusionAdjustment::SameAlbedo:
      return rho * (1.0 - a) + a;  // Chan 2018 eq. (47)
    case OcclusionAdjustment::SameAlbedoOccluded:
      return rho * a * (1.0 - a) + a;             // Chan 2018 eq. (48)
    case OcclusionAdjustment::Interreflection: {  // Chan 2018 eq. (49)
      const double d = 1.0 - rho + rho * a;
      return d > 0 ? a / d : 1.0;
    }
  }
  return a;
}

}  // namespace kozu
