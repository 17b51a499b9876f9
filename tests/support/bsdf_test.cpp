#include "support/bsdf_test.h"

#include "core/json_reader.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace kozu::test {

Vec3 direction_from_angles(double theta_deg, double phi_deg) {
  const double t = theta_deg * std::numbers::pi / 180.0, p = phi_deg * std::numbers::pi / 180.0;
  return Vec3(static_cast<float>(std::sin(t) * std::cos(p)), static_cast<float>(std::sin(t) * std::sin(p)),
              static_cast<float>(std::cos(t)));
}

Vec3 uniform_sphere(Pcg32& rng) {
  const float z = 1.0f - 2.0f * rng.next_float(), phi = kTwoPi * rng.next_float();
  const float r = safe_sqrt(1.0f - z * z);
  return Vec3(r * std::cos(phi), r * std::sin(phi), z);
}

double max_rgb(const Rgb& c) { return std::max({c.r, c.g, c.b}); }

AlbedoEstimate directional_albedo(const Bsdf& bsdf, const Vec3& wo, TransportMode mode, uint64_t seed) {
  constexpr int kReplicas = 16, kSide = 17;
  const auto jitter = [](int cell, float xi) { return std::min((cell + xi) / kSide, 0x1.fffffep-1f); };
  Pcg32 rng(seed);
  glm::dvec3 sum(0.0), sum2(0.0);
  for (int r = 0; r < kReplicas; ++r) {
    glm::dvec3 replica(0.0);
    for (int i = 0; i < kSide; ++i)
      for (int j = 0; j < kSide; ++j)
        for (int k = 0; k < kSide; ++k) {
          const float u_lobe = jitter(i, rng.next_float());
          const Vec2 u(jitter(j, rng.next_float()), jitter(k, rng.next_float()));
          const BsdfSample s = bsdf.sample(wo, u_lobe, u, mode);
          if (s.valid()) replica += glm::dvec3(s.weight());
        }
    replica /= double(kSide * kSide * kSide);
    sum += replica;
    sum2 += replica * replica;
  }
  const glm::dvec3 mean = sum / double(kReplicas);
  const glm::dvec3 var =
      glm::max(sum2 / double(kReplicas) - mean * mean, glm::dvec3(0.0)) * (double(kReplicas) / (kReplicas - 1));
  return {Rgb(mean), Rgb(glm::sqrt(var / double(kReplicas)))};
}

std::unique_ptr<Material> material_from_json(const std::string& body) {
  const Json json = Json::parse("{" + body + "}");
  const JsonObject desc(json, "/materials/m", std::make_shared<JsonSource>(JsonSource{"test.json", "."}));
  return parse_material(desc, MaterialParseContext{}).take();
}

SurfaceInteraction hit_at_uv(float u, float v) {
  SurfaceInteraction si;
  si.p = Vec3(0.0f);
  si.ng = Vec3(0.0f, 0.0f, 1.0f);
  si.shading = Frame(si.ng);
  si.uv = Vec2(u, v);
  si.wo = si.ng;
  return si;
}

}  // namespace kozu::test
