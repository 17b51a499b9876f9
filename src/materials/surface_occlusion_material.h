// Material surface occlusion in the renderer: the cosine-weighted visibility V of the bumps a normal map draws (a
// texture, or computed at load from the normal map), turned into the equal-area cone about the shading normal, and
// the two factors the path tracer takes from it: on direct light (eq. 58, or eq. 57's hard cone) and on the
// indirect light a sampled continuation brings (the specular lobe's fraction inside the cone, §4.7's table, or the
// cosine lobe's, V).
//
// Source: D. Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in Real-Time Rendering
// in Games, §4 (§4.3–4.7).
//
// Equation map:
//   eq. (43)   V: the texture "ao", or textures/surface_occlusion.h's visibility() of the height field that
//              textures/height_from_normals.h's Algorithm 5 gives the normal map (the command's defaults:
//              radius 32 texels, 16 directions, heights × normal_map_strength)
//   eq. (56)   cos θ = sqrt(1 − V)                                          cone_cos()
//   eq. (57)   vis = 1 if cos θ < n·l, else 0                              "direct": "hard"
//   eq. (58)   vis = clamp(n·l / cos θ, 0, 1)²                             "direct": "smooth" (default)
//   §4.7       specular: T(n·v, gloss, cos θ) / T(n·v, gloss, 0)           "specular": "table" (default)
//   eqs. (59)–(60)  the game's cone widening and gloss bias before that    "specular": "game"
//   eq. (54)   a cosine lobe's fraction inside the cone is sin²θ = V       diffuse continuations
//   eq. (49)   A' = V / (1 − ρ + ρ V)                                      diffuse continuations with "albedo" ρ
//
// Which light each factor scales (the macro geometry is flat: the path tracer sees none of the bumps, so the
// factors stand for what the missing bumps would hide; the path tracer's own shadow rays are the macro scale):
//   - direct: the emission the path receives straight from an emitter at this vertex, both by light sampling (the
//     BSDF value towards the light times vis(n·l)) and where a BSDF-sampled ray meets an emitter (its radiance
//     times vis(n·l) of that ray), so the two MIS strategies estimate the same integrand ∫ f vis L_e; the MIS
//     weights are unchanged. Reflection only (a transmitted direction is not occluded by the outer bumps).
//   - indirect: everything else the continuation brings (what the next vertex reflects, media scattering on the
//     way), scaled by the sampled lobe's fraction inside the cone: the table's ratio for a glossy lobe, V (eq. 54)
//     or eq. (49)'s A' for a diffuse one, the hard cone for a Dirac one, 1 for transmission.
//   No light is scaled twice: a path's contribution arrives either directly (factor 1) or through a later vertex
//   (factor 2 at this vertex), never both; later vertices apply their own factors to their own light.
//
// Parameters ("surface_occlusion" on a surface material with a normal_map; true = {}, false or absent = off)
//   mode      string   "cone"    "cone" or "off"
//   ao        texture  computed  V in [0, 1] (eq. 43, unadjusted: `kozu texture occlusion --adjust black`)
//   direct    string   "smooth"  "smooth" (eq. 58) or "hard" (eq. 57)
//   specular  string   "table"   "table", "game" (eqs. 59–60 first) or "off"
//   albedo    number   0         ρ of eq. (49) for diffuse continuations (0: V itself)
//   gloss     number   material  the gloss (eq. 2) the table is read at; default: the material's plain roughness,
//                                alpha or gloss converted by eq. (2)
// Without "ao" the visibility map is built once into the texture cache's folder, `<map>-<key>.ao.exr`, the key
// hashing the normal map's absolute path, size, modification time, convention, strength and a version; it is
// read with the normal map's uv_scale, uv_offset, uv_rotation and filter.
//
// Deviations: eq. (59)–(60) are the game's run-time compromise against its normal-centred cone; a path tracer needs
// neither (default off). Not applied to polygon lights integrated in closed form ("direct": "ltc" modes).
#pragma once

#include "core/json_reader.h"
#include "core/registry.h"
#include "geometry/interaction.h"
#include "textures/texture.h"
#include "textures/texture_cache.h"

#include <algorithm>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace kozu {

class SurfaceOcclusion {
 public:
  enum class Direct { Smooth, Hard };
  enum class Specular { Table, Game, Off };
  struct Settings {
    Direct direct = Direct::Smooth;
    Specular specular = Specular::Table;
    float albedo = 0.0f;
    float gloss = -1.0f;  // < 0: unknown (no glossy lobe, or specular off)
  };

  SurfaceOcclusion(std::unique_ptr<const Texture> visibility, const Settings& s)
      : visibility_(std::move(visibility)), s_(s) {}

  // cos θ of the equal-area cone at si (eq. 56).
  float cone_cos(const SurfaceInteraction& si) const;
  // The factor on direct light from a direction at cosine n_dot_l to the shading normal (eq. 58 or 57).
  float direct(float cone_cos, float n_dot_l) const {
    return s_.direct == Direct::Smooth ? smooth_cone(cone_cos, n_dot_l) : hard_cone(cone_cos, n_dot_l);
  }
  // The factor on the indirect light a continuation sampled from the lobe `flags` (BsdfSample::flags) brings;
  // n_dot_v and n_dot_l on the same side (both positive for a reflection).
  float indirect(float cone_cos, float n_dot_v, float n_dot_l, uint32_t flags) const;
  const Settings& settings() const { return s_; }

  static float smooth_cone(float cone_cos, float n_dot_l) {
    if (!(cone_cos > 0.0f)) return n_dot_l > 0.0f ? 1.0f : 0.0f;  // the open hemisphere
    const float x = std::clamp(n_dot_l / cone_cos, 0.0f, 1.0f);
    return x * x;  // Chan 2018 eq. (58)
  }
  static float hard_cone(float cone_cos, float n_dot_l) { return cone_cos < n_dot_l ? 1.0f : 0.0f; }  // eq. (57)

 private:
  std::unique_ptr<const Texture> visibility_;
  Settings s_;
};

// The load-time build of a visibility map from a normal map (cached; see above).
struct SurfaceOcclusionBuild {
  std::filesystem::path normal_map, out;
  bool flip_y = false;
  float height_scale = 1.0f;
  void build() const;  // unless `out` exists; throws InputError naming the normal map
};

// What parse_surface_occlusion read: load() runs the build (if any) and takes the texture.
struct SurfaceOcclusionDesc {
  std::shared_ptr<Json> json;  // the synthesized {"ao": ...} of a computed map, kept alive for its parser
  Deferred<Texture> ao;
  std::optional<SurfaceOcclusionBuild> build;
  SurfaceOcclusion::Settings settings;
  std::string json_path;
  std::unique_ptr<const SurfaceOcclusion> load();
};

// Reads "surface_occlusion" of a surface material: desc is the description the material is parsed from (its keys
// are marked read), original the one the scene gave (its normal map and roughness, before normal_gloss_filtering
// replaced them). Null when absent or off.
std::shared_ptr<SurfaceOcclusionDesc> parse_surface_occlusion(const JsonObject& desc, const JsonObject& original,
                                                              const std::function<TextureCache*()>& textures);

}  // namespace kozu
