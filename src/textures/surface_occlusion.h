// Material surface occlusion: the cosine-weighted visibility of a height field (a horizon-based estimate in
// orthographic space), its interreflection adjustment, and the equal-area cone that stands for it.
//
// D. Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in Real-Time Rendering in
// Games, §4.3–4.5, after J. Jimenez, X. Wu, A. Pesce, A. Jarabo, "Practical Real-Time Strategies for Accurate
// Indirect Occlusion" (GTAO), SIGGRAPH 2016 course Physically Based Shading in Theory and Practice.
//
// Equation map:
//   eq. (43)  A_p = 1/pi ∫ V cos θ dω          visibility(): per texel, D slices through the normal's view axis
//                                              (+z, orthographic); on each side of a slice the highest horizon
//                                              within R texels (wrapping); the cosine-weighted visible arc between
//                                              the two horizons in closed form (GTAO's inner integral, the slice
//                                              Jacobian |sin θ| included), times the projected normal's length;
//                                              the mean over the slices is A_p exactly when each slice's visible
//                                              set is one arc
//   eqs. (45)–(49)                             adjusted_visibility(): what the occluded directions send back,
//                                              from black (45) to the interreflection of Stewart & Langer 1996 (49)
//   eqs. (50)–(56)                             cone_cos(): the cone about the normal with the same cosine-weighted
//                                              visibility (Nusselt analog): V = sin²θ, cos θ = sqrt(1 - V)
//
// Parameters (OcclusionOptions): height_scale (default 1: heights in texel widths), radius R in texels (default
// 32), slice directions D (default 16, over [0, π): each slice looks both ways), step along a slice in texels
// (default 1; heights read bilinearly, wrapping).
//
// Deviations: GTAO reads a perspective depth buffer and jitters its slices per pixel; here the depth is the height
// itself (orthographic, as the paper's offline tool uses it) and the slices are fixed and evenly spaced, so the map
// has no noise to filter. The normal is the height field's own (central differences of the scaled height), so the
// visibility and the heights agree whatever the height scale.
#pragma once

#include "textures/height_from_normals.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace kozu {

struct OcclusionOptions {
  float height_scale = 1.0f;
  float radius = 32.0f;
  int directions = 16;
  float step = 1.0f;
};

// Chan 2018 eq. (43): the cosine-weighted visibility of every texel in [0, 1] (1: nothing above its horizon).
std::vector<float> visibility(const HeightField& h, const OcclusionOptions& options = {});

// The cosine-weighted visible part of one slice through the view axis +z whose normal projects to angle gamma
// from +z (towards the slice's +side) with length `projected_length`, between horizons h_minus <= 0 <= h_plus
// measured from +z (clamped to the normal's hemisphere). The integral of |sin θ| cos(θ - γ) dθ over the arc.
double slice_visibility(double gamma, double projected_length, double h_minus, double h_plus);

// Chan 2018 eqs. (45)–(49): the ambient occlusion adjusted for the light the occluded directions bring back.
enum class OcclusionAdjustment {
  Black,               // eq. (45): occluded directions are black, A' = A
  WhiteOccluded,       // eq. (46): they are white and themselves as occluded, A' = A (1 - A) + A
  SameAlbedo,          // eq. (47): they have the point's albedo and are unoccluded, A' = ρ (1 - A) + A
  SameAlbedoOccluded,  // eq. (48): the point's albedo, as occluded, A' = ρ A (1 - A) + A
  Interreflection,     // eq. (49): they send the point's own radiance back, A' = A / (1 - ρ + ρ A)
};
double adjusted_visibility(double a, double albedo, OcclusionAdjustment model = OcclusionAdjustment::Interreflection);

// Chan 2018 eqs. (50)–(56): the cosine of the half angle of the cone about the normal whose cosine-weighted
// visibility is v.
inline double cone_cos(double v) { return std::sqrt(std::clamp(1.0 - v, 0.0, 1.0)); }  // Chan 2018 eq. (56)

// The cosine-weighted visibility of a cone of half angle θ about the normal, sin²θ = 1 - cos²θ (Chan 2018
// eqs. (54)–(55)): cone_cos's inverse.
inline double cone_visibility(double cos_theta) { return 1.0 - cos_theta * cos_theta; }

}  // namespace kozu
