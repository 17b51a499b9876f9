// Bump maps: a height texture that displaces the surface along its shading normal for shading only (Blinn 1978,
// "Simulation of Wrinkled Surfaces", SIGGRAPH; in the form of Pharr, Jakob and Humphreys, "Physically Based
// Rendering", 3rd ed. 2016, §9.3).
//
// With h(u, v) = bump_scale · height(u, v) in scene units, the displaced surface p' = p + h n has the tangents
//   dp'/du ≈ dp/du + (dh/du) n,   dp'/dv ≈ dp/dv + (dh/dv) n
// (the term h dn/du of a curved surface is dropped, as is usual: it matters only for heights comparable to the
// radius of curvature), and the shading normal becomes n' = ± normalize(dp'/du × dp'/dv), the sign that keeps it on
// n's side (so a mirrored (u, v) mapping bumps the same way). dp/du and dp/dv are the shape's
// (Shape::uv_derivatives), first projected onto the plane of the shading normal so that interpolated normals
// are kept.
//
// The derivatives are central differences of two texture lookups each, at (u ± Δu, v) and (u, v ± Δv), with the
// hit's footprint: Δu = ½ (|du/dx| + |du/dy|), the half-width of the pixel's footprint along u (likewise Δv), or
// Δ = 0.0005 in (u, v) units where the ray has no footprint (after the first bounce). A linear ramp's slope is
// exact for any Δ.
//
// Parameters (keys every surface material accepts, materials/registry.cpp)
//   bump_map    texture  —  the height (first channel, read linear as data); a plain number is a flat map
//   bump_scale  float    1  multiplies the height (scene units per texture unit); negative values invert it
// A material takes a normal map or a bump map, not both.
#pragma once

#include "geometry/interaction.h"
#include "textures/texture.h"

#include <memory>

namespace kozu {

class BumpMap {
 public:
  BumpMap(std::unique_ptr<const Texture> height, float scale) : height_(std::move(height)), scale_(scale) {}
  // Replaces si.shading (si.shape must be set).
  void apply(SurfaceInteraction& si) const;
  // The bumped normal (unit) for the height's derivatives dh/du, dh/dv at a point with tangents dp/du, dp/dv and
  // unit shading normal n.
  static Vec3 bumped_normal(const Vec3& dpdu, const Vec3& dpdv, const Vec3& n, float dhdu, float dhdv);

  static constexpr float kDefaultDelta = 0.0005f;

 private:
  std::unique_ptr<const Texture> height_;
  float scale_;
};

}  // namespace kozu
