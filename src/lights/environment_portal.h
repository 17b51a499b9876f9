// environment_portal: an environment's light sampled through a rectangular portal (a window), in proportion to the
// radiance the shading point sees through it.
//
// Bitterli, Novák and Jarosz 2015, "Portal-Masked Environment Map Sampling", Computer Graphics Forum 34(4)
// (Eurographics Symposium on Rendering). Equation map:
//   - the rectified parameterization (§4.1): a direction ω on the environment's side of the portal's plane as
//     (α, β) = (atan(ω·x / ω·z), atan(ω·y / ω·z)) in the portal's frame (x and y along its edges, z towards the
//     environment). From any point on the scene's side the portal is then the axis-aligned rectangle
//     [α0, α1] × [β0, β1]: its gnomonic projection onto the plane z = 1 is one, and atan is monotonic per axis;
//   - its Jacobian (§4.1): dω = J dα dβ. With ω's components (dx, dy, dz) this is
//     J = (1 − dx²)(1 − dy²) / dz (= (1 + tan²α)(1 + tan²β) / (1 + tan²α + tan²β)^{3/2});
//   - the map resampled in (α, β) on n × n cells, f = luminance × J, and its summed-area table (§4.2);
//   - sampling (§4.2): α from the rectangle's marginal, whose cdf is read from the table (monotone: searched),
//     then β in that column; continuous inside a cell (the table is bilinear across a cell), so
//     pdf(ω) = f / (M Δ² J) with M the rectangle's mass and Δ = π / n the cell's width.
// Deviations: the paper's table holds the map's texels. Here each cell, about a texel wide, holds the mean of the
// environment's own bilinear lookup (what a ray that escapes receives) over 2 × 2 points, plus a floor of 10⁻⁴ of the mean so that
// no direction through the portal has density 0. Several portals: one is chosen in proportion to the radiance
// each lets through (EnvironmentLight).
//
// Parameters (an environment's "portals", docs/lights.md): each portal is a rectangle given by its four corners
// in a quad light's order: its front, the side a quad light with those vertices would light, faces the scene.
#pragma once

#include "core/frame.h"
#include "core/math.h"

#include <array>
#include <functional>
#include <vector>

namespace kozu {

class EnvironmentPortal {
 public:
  // corners: a rectangle (the caller checks it). luminance(ω): the environment's luminance arriving from ω.
  // resolution: n, the cells along each axis of the rectified table.
  EnvironmentPortal(const std::array<Vec3, 4>& corners, const std::function<float(const Vec3&)>& luminance,
                    int resolution);

  // The portal as seen from a point: its rectangle in cell coordinates (x = (α + π/2) / Δ, y likewise) and the
  // table's mass in it. Empty (mass 0) from the environment's side of the portal's plane or from within it.
  struct View {
    double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
    double mass = 0;
    double base = 0;  // the table's integral over [0, x0] × [y0, y1] (sample's search starts from it)
    bool empty() const { return !(mass > 0.0); }
  };
  View view(const Vec3& p) const;
  // About the luminance arriving through the portal, ∫ L dω over the window (the mass in solid angle): the weight
  // with which a point chooses among portals.
  double flux(const View& v) const { return v.mass * cell_ * cell_; }

  // A unit direction through the portal and its solid-angle density (pdf 0: no sample; v must not be empty).
  Vec3 sample(const View& v, const Vec2& u, float* pdf) const;
  // The solid-angle density of sample towards the unit direction dir: 0 where dir does not pass through the portal.
  float pdf(const View& v, const Vec3& dir) const;

 private:
  // The table's integral over [0, x] × [0, y] (cell coordinates in [0, n]).
  double integral(double x, double y) const;
  // The table's integral over [y0, y] in column i (the density along x of that column's part of the rectangle).
  double column(int i, double y0, double y) const;
  float cell(int i, int j) const { return f_[static_cast<size_t>(i) * n_ + j]; }
  double sat(int i, int j) const { return sat_[static_cast<size_t>(i) * (n_ + 1) + j]; }

  Vec3 origin_;  // corner 0
  Frame frame_;  // s, t along the edges from corner 0 (α, β); n the normal towards the environment
  double width_ = 0, height_ = 0;
  int n_ = 0;
  double cell_ = 0;           // Δ = π / n, in radians
  std::vector<float> f_;      // n × n: f_[i n + j], i along α, j along β
  std::vector<double> sat_;   // (n + 1)²: sat_[i (n + 1) + j] = Σ f over cells [0, i) × [0, j)
};

}  // namespace kozu
