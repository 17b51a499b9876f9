// Tangent-space normal maps: a texture whose texels are unit normals in the surface's tangent frame, replacing the
// shading normal (Cohen et al. 1998, "Appearance-Preserving Simplification", SIGGRAPH; the tangent frame is
// MikkTSpace's, Mikkelsen 2008, geometry/mesh_tangents.h).
//
// Encoding (OpenGL convention, glTF 2.0 §3.9.3 normalTexture): a texel (r, g, b) in [0, 1] (read linear, as data)
// is the vector m = (2r − 1, 2g − 1, 2b − 1) in the frame (t, b, n): t along dp/du, b = w · cross(n, t) along
// dp/dv (Shape::tangent), n the shading normal, so +Y points towards increasing v (up in the image, whose
// bottom row is v = 0). "directx" maps (+Y towards decreasing v) negate m.y. The strength s scales m.x and m.y
// before normalization, as glTF's normalTexture.scale: n' = normalize(s m.x t + s m.y b + m.z n). A flat texel
// (0.5, 0.5, 1) gives n' = n; s = 0 turns the map off.
//
// Parameters (keys every surface material accepts, materials/registry.cpp)
//   normal_map             texture  —         tangent-space normals (textures/texture_parse.h; TextureUse::Data)
//   normal_map_strength    float    1         >= 0, multiplies the tangent-space X and Y
//   normal_map_convention  string   "opengl"  "opengl" (+Y = +v, glTF, Blender) or "directx" (+Y = −v)
// The new normal replaces the shading frame through set_shading_normal (materials/shading_normal.h), which keeps
// wo above it; the frame's first axis follows the tangent (anisotropic BSDFs align with dp/du).
#pragma once

#include "geometry/interaction.h"
#include "textures/texture.h"

#include <memory>

namespace kozu {

class NormalMap {
 public:
  NormalMap(std::unique_ptr<const Texture> texture, float strength, bool flip_y)
      : texture_(std::move(texture)), strength_(strength), flip_y_(flip_y) {}
  // Replaces si.shading (si.shape must be set).
  void apply(SurfaceInteraction& si) const;
  // The perturbed normal for the tangent-space texel m_rgb in the unit frame (t, b = w cross(n, t), n), unnormalized.
  Vec3 perturbed_normal(const Rgb& texel, const Vec3& t, float w, const Vec3& n) const;

 private:
  std::unique_ptr<const Texture> texture_;
  float strength_;
  bool flip_y_;
};

}  // namespace kozu
