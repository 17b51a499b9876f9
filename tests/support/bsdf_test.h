// Shared pieces of the BSDF tests: directions, and the directional albedo estimated with a BSDF's own sampling
// (the white-furnace measurement).
#pragma once

#include "core/rng.h"
#include "materials/bsdf.h"
#include "materials/material.h"

#include <cstdint>
#include <memory>
#include <string>

namespace kozu::test {

// The unit direction at polar angle theta and azimuth phi (degrees) about +z.
Vec3 direction_from_angles(double theta_deg, double phi_deg);

// A direction uniform on the sphere.
Vec3 uniform_sphere(Pcg32& rng);

double max_rgb(const Rgb& c);

struct AlbedoEstimate {
  Rgb mean{0.0f};
  Rgb se{0.0f};  // standard error of the mean
};

// ∫ eval dωi at wo, estimated as the mean of sample()'s weights f / pdf.
// kReplicas independent estimates, each on a jittered kSide³ grid over (u_lobe, u.x, u.y): every draw is
// uniform on [0,1)³, so each replica is unbiased, and the standard error comes from the spread of the
// replicas. The weight f/pdf is discontinuous (samples lost below the horizon weigh 0, the lobe choice moves wi)
// along surfaces that cut across all three dimensions, which a stratification of all three resolves: 16 x 17³
// = 78608 draws per angle reach standard errors ≤ 8.7e-4 on the rough materials, where as many independent draws
// give up to 2e-3.
AlbedoEstimate directional_albedo(const Bsdf& bsdf, const Vec3& wo, TransportMode mode, uint64_t seed);

// A material parsed from the body of its JSON object (`"type": ..., ...` without braces), at /materials/m of a
// file test.json; image textures are refused.
std::unique_ptr<Material> material_from_json(const std::string& body);

// A hit at texture coordinates (u, v), built by hand: the shading frame is the standard basis (the BSDF's local
// directions are world directions), wo the normal.
SurfaceInteraction hit_at_uv(float u, float v);

}  // namespace kozu::test
