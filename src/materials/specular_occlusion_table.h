// Cone-based specular occlusion: the GGX specular lobe's directional albedo restricted to a cone about the normal,
// tabulated over n·v, gloss and the cone's half angle, and the fraction of the lobe's light inside the cone.
//
// Source: D. Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in Real-Time Rendering
// in Games, §4.7 (the 32 x 32 x 8 table of the specular BRDF integrated over the visibility cone: the 2D
// split-sum albedo table of Karis 2013 extended by the cone angle; eqs. (59)–(60), the game's ad-hoc biases).
//
// Equation map:
//   §4.7 table   T(μ, g, c) = ∫_{n·l > c} f_GGX(v, l) (n·l) dl with F = 1     SpecularOcclusionTable (nodes)
//   §4.7 ratio   T(μ, g, c) / T(μ, g, 0): the part of the lobe's light inside the cone   specular_occlusion()
//   eq. (2)      α = sqrt(2 / (1 + 2^(18 g)))                                  materials/roughness.h
//   eq. (59)     cos θ' = cos θ (1 − gloss²)(1 − (1 − (n·v)⁴))                  game_cone_cos()
//   eq. (60)     gloss' = clamp(1.5 gloss, 0, 1)                                game_cone_cos()
//
// Layout: 32 nodes of μ = n·v (μ_i = i / 31, the first at 1 / 64: at μ = 0 the lobe is undefined), 32 nodes of
// gloss g_j = j / 31 (eq. (2)'s α from 1 at g = 0 to 0.0055 at g = 1, clamped at the materials' smallest α), 8 nodes
// of the cone's cosine c_k = k / 7: slice 0 is the whole hemisphere (c = 0; the ordinary directional albedo of a
// GGX conductor with F = 1, materials/microfacet_albedo.h), slice 7 the closed cone (c = 1, exactly 0). Lookups
// are trilinear between nodes, and the ratio divides two trilinear lookups (so it is 1 for c = 0 and 0 for c = 1).
//
// Deviations: the paper importance-samples the GGX NDF; here the visible normals (exact VNDF sampling), the same
// integral with a lower variance at grazing μ, each weight G2 / G1(v). Fresnel is left out (F = 1): the ratio is
// the fraction of the lobe's directions weighted by the BRDF, which F shifts only at grazing l. The table is
// computed on first use (0.16 s on 2 cores; 4096 Hammersley directions per (μ, g) node, every cone slice from the same
// directions), not stored.
#pragma once

#include <array>

namespace kozu {

class SpecularOcclusionTable {
 public:
  static constexpr int kMu = 32, kGloss = 32, kCone = 8;
  static constexpr int kSamples = 4096;  // directions per (μ, g) node

  // The table, computed once (thread-safe).
  static const SpecularOcclusionTable& get();

  static float mu_node(int i) { return i == 0 ? 1.0f / 64.0f : float(i) / float(kMu - 1); }
  static float gloss_node(int j) { return float(j) / float(kGloss - 1); }
  static float cone_node(int k) { return float(k) / float(kCone - 1); }
  // α of gloss g: eq. (2), clamped to the materials' smallest α.
  static float alpha_of_gloss(float gloss);

  float node(int i, int j, int k) const { return t_[(size_t(i) * kGloss + size_t(j)) * kCone + size_t(k)]; }
  // T at any (μ, g, c) in [0, 1]³ (clamped), trilinear.
  float lookup(float mu, float gloss, float cone_cos) const;

  // One node's integral and the standard error it would have as a plain Monte Carlo estimate (for tests).
  static void integrate_node(float mu, float alpha, std::array<double, kCone>* t, std::array<double, kCone>* se);

 private:
  SpecularOcclusionTable();
  std::array<float, size_t(kMu) * kGloss * kCone> t_{};
};

// The fraction of a GGX specular lobe's light (at n·v = mu, gloss g) that arrives inside the cone of half angle θ
// about the normal, cos θ = cone_cos: T(μ, g, cos θ) / T(μ, g, 0), in [0, 1]. Chan 2018 §4.7.
float specular_occlusion(float mu, float gloss, float cone_cos);

// The game's cone for the lookup: eq. (60)'s gloss bias, then eq. (59)'s widening towards the open hemisphere as
// gloss rises and at grazing views. Returns cos θ'; *gloss_out receives gloss'.
float game_cone_cos(float cone_cos, float mu, float gloss, float* gloss_out);

}  // namespace kozu
