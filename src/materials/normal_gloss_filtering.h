// Normal and gloss mip filtering in the renderer: a material's normal map and its roughness are replaced, at load
// time, by the two mip chains of Chan 2018's Algorithm 3 (textures/normal_gloss_filter.h), so that the ray-cone
// footprints that select a normal map's mip levels also select a gloss that keeps the bumps a level averages away.
//
// Source: D. Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course Advances in Real-Time Rendering
// in Games, §2 (Algorithm 3, Algorithm 2's macro-surface model; eq. (2) converts the material's α to gloss and the
// filtered gloss back to α).
//
// Parameters (keys of every surface material, read in materials/registry.cpp)
//   normal_gloss_filtering  bool    true     filter the normal map and the roughness together
//   detail_gloss            string  "exact"  with a detail_normal_map: "exact" (eq. 34) or "fit" (eq. 37)
//
// What is filtered (the rest keeps its level-0 lookups; with the key given as true, one warning says why not):
//   - the normal map: an "image" texture, colour space auto or linear, no "channel", normal_map_strength 1, filter
//     "ewa" or "trilinear" ("closest" reads level 0 only, where filtering changes nothing: left as it is);
//   - the roughness, distribution "ggx" and isotropic (anisotropic and Beckmann roughness: skipped with the warning):
//     a conductor's, dielectric's, plastic's or subsurface's "roughness", "alpha" or "gloss" (either gloss_model),
//     or a standard material's "roughness" (0.5 when absent), given
//       - as one plain number (a conductor etc. must be rough, α >= 1e-3: a smooth surface stays a Dirac one;
//         standard clamps α to 1e-3 and is always rough), or
//       - as an "image" texture (colour space auto or linear, any "channel", a "scale" that is one number, no
//         "threshold") with the normal map's uv_scale, uv_offset and uv_rotation (else its texels would not be the
//         map's: skipped). Its values (the channel times the scale, clamped to [0, 1]) are converted per texel to
//         α and to WWII gloss (eq. 2 inverted) before Algorithm 3. An image of another size than the normal map is
//         resampled to the map's texel centres (bilinear, wrapping); its finer detail is then lost at level 0.
// Then "normal_map" becomes the filtered normal chain and the roughness a WWII "gloss" texture of the filtered gloss
// chain (same uv_scale / uv_offset / uv_rotation / filter as the normal map): the material's α at a lookup is
// eq. (2) of the filtered gloss (roughness.h). A standard material's "roughness" becomes the chain r = sqrt(α) of it
// instead (its own convention, α = r²), written beside the gloss chain. Deviation: a varying gloss texture's values
// are rounded to 1/255 steps (roughness.h), so α is within 2.5 % of the filtered value.
//
// Detail normal maps (materials/detail_normal_blend.h): an "image" detail_normal_map (colour space auto or linear,
// no "channel", filter not "closest") on a material filtered as above is filtered too, from gloss 1, into its own
// two chains; the material's gloss then becomes a "wwii_gloss_combine" texture (textures/wwii_gloss_combine.h) of the
// base's and the detail's gloss chains (each with its map's uv_scale / uv_offset / uv_rotation / filter), combined
// at each lookup by Chan 2018 eq. (34) ("detail_gloss": "exact", the default) or its fit eq. (37) ("fit"); a
// standard material's roughness becomes the same texture with "output": "roughness" (r = sqrt(α)). A detail
// map that cannot be filtered keeps its own mip lookups (with detail_gloss given, one warning says why).
//
// Files: `<normal map stem>-<key>.normal.exr` and `.gloss.exr` in the texture cache's folder (texture_cache.h),
// with `.source-gloss.exr` (level 0 of a textured roughness's gloss) and `.roughness.exr` (standard) beside them,
// built once; the key hashes the normal map's absolute path, size and modification time (as the texture cache's
// conversions), the gloss value, the model and a version, and a roughness image's path, size, time, channel and
// scale, the roughness key and the material kind. Written atomically (normal_gloss_files.h).
#pragma once

#include "core/json_reader.h"
#include "materials/material.h"

#include <memory>
#include <optional>

namespace kozu {

// Which key gave the roughness, and so how its values become α (materials/roughness.h).
enum class RoughnessKind { Roughness, Alpha, Gloss, GlossAw };

struct NormalGlossFilteringPlan {
  std::shared_ptr<Json> json;  // the material's description with normal_map and roughness replaced
  std::filesystem::path normal_map, out_normal, out_gloss;
  double gloss = 1;     // a plain roughness's WWII gloss
  double strength = 1;  // normal_map_strength, applied to the map's texels before filtering (the chain has 1)
  RoughnessKind roughness_kind = RoughnessKind::Roughness;
  bool standard = false;
  // A textured roughness (empty: plain): its image, channel (0-3) and scale; level 0 of its gloss (source_gloss).
  std::filesystem::path roughness_map, source_gloss;
  std::string roughness_key_name;  // "roughness", "alpha" or "gloss"
  int roughness_channel = 0;
  double roughness_scale = 1;
  // standard: the roughness chain r = sqrt(α(g)) of the filtered gloss chain.
  std::filesystem::path out_roughness;
  // A filtered detail normal map (empty: none) and its two chains, filtered from gloss 1.
  std::filesystem::path detail_normal_map, out_detail_normal, out_detail_gloss;
  // Builds the files unless they exist (a later run, or another material with the same map and gloss). *key: the
  // material key whose file is being read when an InputError leaves ("normal_map", the roughness key or
  // "detail_normal_map").
  void build(std::string* key = nullptr) const;
};

// Reads normal_gloss_filtering from desc; nullopt when the material is left as it is.
std::optional<NormalGlossFilteringPlan> plan_normal_gloss_filtering(const JsonObject& desc,
                                                                    const MaterialParseContext& ctx);

}  // namespace kozu
