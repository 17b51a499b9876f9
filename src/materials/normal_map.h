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
//   detail_normal_map      texture  —         a second tangent-space normal map (own uv_scale / uv_offset), decoded
//                                             and flipped as normal_map, blended into it in tangent space
//   detail_blend           string   "blendxy" "blendxy" (Chan 2018 Algorithm 4, the game's) or "rnm" (reoriented
//                                             normal mapping, Barré-Brisebois & Hill 2012):
//                                             materials/detail_normal_blend.h
// With a detail map, the strength scales the base's X and Y (then the base is renormalised), the detail is blended
// into it, and the blend's (unit) result is mapped into the frame; without one the arithmetic is the one above.
// Detail gloss (Chan 2018 eq. 34) is the gloss side of a detail map: materials/normal_gloss_filtering.h.
// The new normal replaces the shading frame through set_shading_normal (materials/shading_normal.h), which keeps
// wo above it; the frame's first axis follows the tangent (anisotropic BSDFs align with dp/du).
#pragma once

#include "geometry/interaction.h"
#include "materials/detail_normal_blend.h"
#include "textures/texture.h"

#include <memory>

namespace kozu {

class NormalMap {
 public:
  NormalMap(std::unique_ptr<const Texture> texture, float strength, bool flip_y,
            std::unique_ptr<const Texture> detail = nullptr, DetailBlend blend = DetailBlend::BlendXY)
      : texture_(std::move(texture)), detail_(std::move(detail)), strength_(strength), flip_y_(flip_y), blend_(blend) {}
  // Replaces si.shading (si.shape must be set).
  void apply(SurfaceInteraction& si) const;
  // The perturbed normal for the tangent-space texel m_rgb in the unit frame (t, b = w cross(n, t), n), unnormalized.
  Vec3 perturbed_normal(const Rgb& texel, const Vec3& t, float w, const Vec3& n) const;
  // The same with a detail texel blended in (tangent space, the map's blend), unit length.
  Vec3 perturbed_normal(const Rgb& texel, const Rgb& detail_texel, const Vec3& t, float w, const Vec3& n) const;
  // The tangent-space normal of a base and a detail texel, blended (what the frame receives), unit length.
  Vec3 blended_tangent_normal(const Rgb& texel, const Rgb& detail_texel) const;
  bool has_detail() const { return detail_ != nullptr; }

 private:
  Vec3 decode(const Rgb& texel) const;

  std::unique_ptr<const Texture> texture_;
  std::unique_ptr<const Texture> detail_;  // null: no detail map
  float strength_;
  bool flip_y_;
  DetailBlend blend_;
};

}  // namespace kozu
