// Blending a detail normal map into a base normal map, in tangent space (+z out of the surface), before the result
// goes into the shading frame (materials/normal_map.h).
//
// Sources:
//   BlendXY: D. Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in Real-Time
//     Rendering in Games, §2.4, Algorithm 4: the detail normal's X and Y offsets are added to the base's and Z is
//     recomputed.
//   RNM: C. Barré-Brisebois and S. Hill, "Blending in Detail", 2012 (reoriented normal mapping): the detail normal
//     rotated by the rotation that takes +z to the base normal (the shortest arc), in closed form
//       t = b + (0, 0, 1),  u = d · (−1, −1, 1),  r = t (t · u) / t_z − u.
//
// Equation map
//   n = (b_x + d_x, b_y + d_y, sqrt(max(0, 1 − x² − y²)))     Algorithm 4 (BlendXY)      blend_xy
//   R(+z → b) d                                              Barré-Brisebois & Hill     blend_rnm
// The lengths these blends give to averaged (shortened) normals, and so the detail gloss, are eq. (34)
// (textures/detail_gloss.h).
//
// Inputs: both normals are normalised first (a texel's decoded normal is close to unit, not exactly). Outputs:
// unit vectors, except BlendXY where the summed offsets reach beyond the unit disc: then z = 0 and (x, y) is
// scaled back onto the unit circle (the paper's Z recomputation leaves the vector unnormalised there; the shading
// frame normalises it either way, so scaling only makes the result a unit vector). A base normal pointing straight
// down (b_z = −1, where the shortest arc is undefined) gives the base itself for RNM.
#pragma once

#include "core/math.h"

namespace kozu {

enum class DetailBlend { BlendXY, Rnm };

// Chan 2018 Algorithm 4.
Vec3 blend_xy(const Vec3& base, const Vec3& detail);
// Barré-Brisebois and Hill 2012, reoriented normal mapping.
Vec3 blend_rnm(const Vec3& base, const Vec3& detail);
inline Vec3 blend_detail_normal(DetailBlend blend, const Vec3& base, const Vec3& detail) {
  return blend == DetailBlend::BlendXY ? blend_xy(base, detail) : blend_rnm(base, detail);
}

}  // namespace kozu
