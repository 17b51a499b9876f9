// Replacing a hit's shading normal (normal and bump maps) so that it cannot leak light.
//
// A perturbed shading normal can leave the direction towards the viewer wo below its hemisphere while wo is above
// the geometric surface (or the reverse, seen from the back of a two-sided material): the BSDF would then be asked
// for reflection on the wrong side of the shading frame. As is common practice for bump and normal maps (the
// problem and the alternatives are surveyed by Schüssler et al. 2017, "Microfacet-based Normal Mapping for Robust
// Monte Carlo Path Tracing", ACM TOG 36(6), §2), kozu bends the normal towards wo just enough: with v = wo on the
// side of the geometric normal ng that wo is on and c = min(kMinCos, |v · ng|),
//     n' = normalize(n + (c − v · n) v)   when v · n < c,
// which gives v · n' = c / sqrt(1 + c² − (v · n)²) ≥ c / sqrt(1 + c²) > 0 (the sum's length squared is
// 1 + c² − (v · n)²) and moves n towards ng's side (v · ng > 0). A normal still behind ng after that falls back
// to ng. Only perturbed normals are bent; a mesh's interpolated normals are used as before.
//
// What stays: the integrator's guard (integrators/path.cpp, sides_agree) rejects every direction on which the
// shading frame and the geometric normal disagree about reflection versus transmission, so no light passes
// through an opaque surface. The cost is energy: a diffuse lobe tilted by an angle a from ng loses the fraction
// (1 − cos a) / 2 of its cosine-weighted directions below the geometric horizon (a white furnace shows it);
// Schüssler et al.'s microfacet model would conserve it and is not implemented.
#pragma once

#include "geometry/interaction.h"

namespace kozu {

// The least cosine the bent normal keeps with wo (where wo itself is farther than that from the horizon).
inline constexpr float kMinShadingCos = 0.01f;

// Replaces si.shading by the frame around n (bent as above) whose first axis is tangent orthogonalized against it
// (an arbitrary axis when tangent is parallel to n). A zero or non-finite n leaves si unchanged.
void set_shading_normal(SurfaceInteraction& si, const Vec3& n, const Vec3& tangent);

// The bend alone: n (unit) adjusted for the unit view direction wo and the unit geometric normal ng.
Vec3 bend_shading_normal(const Vec3& n, const Vec3& wo, const Vec3& ng);

}  // namespace kozu
