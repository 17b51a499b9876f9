#include "media/sggx_medium.h"

#include "io/json_reader.h"

namespace kozu {

SggxMedium::SggxMedium(float density, const Rgb& albedo, const Sggx& S, Phase phase)
    : density_(density), albedo_(albedo), S_(S), phase_(phase), majorant_(density * sggx::max_projected_area(S)) {}

MediumProperties SggxMedium::properties(const Vec3&, const Vec3& d) const {
  const float sigma_t = density_ * sggx::projected_area(S_, d);  // eq. (2)
  return {Rgb(sigma_t), albedo_ * sigma_t};                      // eq. (3)
}

const PhaseFunction* SggxMedium::phase(const Vec3&, Arena& arena) const {
  if (phase_ == Phase::Specular) return arena.make<SggxSpecularPhase>(S_);
  return arena.make<SggxDiffusePhase>(S_);
}

void SggxMedium::majorants(const Vec3&, const Vec3&, float t0, float t1, MajorantVisitor& v) const {
  v.segment(t0, t1, majorant_);
}

Sggx read_sggx_distribution(const JsonObject& d) {
  Sggx S;
  if (d.has("S")) {
    const JsonArray a = d.get_array("S");
    if (a.size() != 6) a.fail("expected [Sxx, Syy, Szz, Sxy, Sxz, Syz]");
    S = {a.number(0), a.number(1), a.number(2), a.number(3), a.number(4), a.number(5)};
    if (!sggx::is_spd(S)) d.fail("S", "the matrix must be symmetric positive definite");
  } else {
    const std::string kind = d.get_enum("kind", {"surface", "fiber"});
    const float roughness = d.get_float("roughness", {}, Range{0.0, 1.0, true, false});
    if (kind == "surface") {
      S = sggx::surface(d.get_direction("normal"), roughness);
    } else {
      S = sggx::fiber(d.get_direction("tangent"), roughness);
    }
  }
  d.finish();
  return S;
}

std::unique_ptr<Medium> SggxMedium::create(const JsonObject& desc) {
  const float density = desc.get_float("density", 1.0f, Range::non_negative());
  const Rgb albedo = desc.get_rgb("albedo", Rgb(0.8f), Range::unit());
  const std::string phase = desc.get_enum("phase", {"specular", "diffuse"}, "specular");
  const Sggx S = read_sggx_distribution(desc.get_object("distribution"));
  return std::make_unique<SggxMedium>(density, albedo, S, phase == "specular" ? Phase::Specular : Phase::Diffuse);
}

}  // namespace kozu
