// What the integrator knows about a ray's hit with a surface.
#pragma once

#include "core/frame.h"
#include "geometry/ray.h"

namespace kozu {

class Shape;
class Instance;
class Material;
class Light;

struct SurfaceInteraction {
  Vec3 p;         // hit position (reconstructed on the surface, not o + t d)
  Vec3 ng;        // unit geometric normal on the shape's front side
  Frame shading;  // shading frame; shading.n lies on the same side as ng
  Vec2 uv;
  Vec3 wo;  // unit direction back toward the ray origin
  float t = 0;
  const Shape* shape = nullptr;
  // The instance (geometry/instance.h) whose object holds `shape`; null for a shape placed in the scene itself.
  const Instance* instance = nullptr;
  uint32_t prim = 0;
  bool front_face = true;  // the ray arrived on the side ng points to
  // Distance along ng within which the surface may lie, beyond the rounding of p that offset_ray_origin covers:
  // the intersection error of analytic shapes, which grows with their size and distance from the origin.
  float p_error = 0;
  // Width of the ray cone (Akenine-Möller et al. 2019, Ray Tracing Gems ch. 20) that found this hit, for texture
  // footprints (uv_footprint); 0: none (the lookup is a point lookup).
  float cone_width = 0;
  // Texture filtering at this hit: true, the image's own filter (EWA by default) where the camera sees the hit
  // directly or through perfectly specular vertices; false after a rough or diffuse bounce, where one trilinear
  // probe does (the bounce's integral blurs what EWA would keep; textures.md, "Footprints").
  bool fine_filtering = true;

  // Origin of a ray leaving towards w, offset to the side of the surface w points to.
  Vec3 spawn_origin(const Vec3& w) const { return offset_point(p, glm::dot(w, ng) > 0.0f ? ng : -ng, p_error); }
  Ray spawn_ray(const Vec3& w) const { return Ray{spawn_origin(w), w, kInfinity}; }
  // Shadow ray towards a point on another surface with unit normal n_target (zero for points in space) and
  // error bound target_error (as p_error).
  Ray spawn_ray_to(const Vec3& target, const Vec3& n_target, float target_error = 0.0f) const {
    const Vec3 d = target - p;
    const Vec3 o = spawn_origin(d);
    const Vec3 t = glm::dot(n_target, n_target) > 0.0f
                       ? offset_point(target, glm::dot(-d, n_target) > 0.0f ? n_target : -n_target, target_error)
                       : target;
    const Vec3 dd = t - o;
    const float len = glm::length(dd);
    return Ray{o, dd / len, len};
  }
};

}  // namespace kozu
