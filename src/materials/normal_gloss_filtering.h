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
//   - the roughness: one plain number of "roughness", "alpha" or "gloss" (either gloss_model), distribution "ggx",
//     of a conductor, dielectric, plastic or subsurface material, and rough (α >= 1e-3: a smooth surface stays a
//     Dirac one).
// Then "normal_map" becomes the filtered normal chain and the roughness a WWII "gloss" texture of the filtered gloss
// chain (same uv_scale / uv_offset / uv_rotation / filter as the normal map): the material's α at a lookup is
// eq. (2) of the filtered gloss (roughness.h). Deviation: a varying gloss texture's values are rounded to 1/255
// steps (roughness.h), so α is within 2.5 % of the filtered value.
//
// Detail normal maps (materials/detail_normal_blend.h): an "image" detail_normal_map (colour space auto or linear,
// no "channel", filter not "closest") on a material filtered as above is filtered too, from gloss 1, into its own
// two chains; the material's gloss then becomes a "wwii_gloss_combine" texture (textures/wwii_gloss_combine.h) of the
// base's and the detail's gloss chains (each with its map's uv_scale / uv_offset / uv_rotation / filter), combined
// at each lookup by Chan 2018 eq. (34) ("detail_gloss": "exact", the default) or its fit eq. (37) ("fit"). A detail
// map that cannot be filtered keeps its own mip lookups (with detail_gloss given, one warning says why).
//
// Files: `<normal map stem>-<key>.normal.exr` and `.gloss.exr` in the texture cache's folder (texture_cache.h),
// built once; the key hashes the normal map's absolute path, size and modification time (as the texture cache's
// conversions), the gloss value, the model and a version. Written atomically (normal_gloss_files.h).
#pragma once

#include "core/json_reader.h"
#include "materials/material.h"

#include <memory>
#include <optional>

namespace kozu {

struct NormalGlossFilteringPlan {
  std::shared_ptr<Json> json;  // the material's description with normal_map and roughness replaced
  std::filesystem::path normal_map, out_normal, out_gloss;
  double gloss = 1;
  // A filtered detail normal map (empty: none) and its two chains, filtered from gloss 1.
  std::filesystem::path detail_normal_map, out_detail_normal, out_detail_gloss;
  // Builds the files unless they exist (a later run, or another material with the same map and gloss).
  void build() const;
};

// Reads normal_gloss_filtering from desc; nullopt when the material is left as it is.
std::optional<NormalGlossFilteringPlan> plan_normal_gloss_filtering(const JsonObject& desc,
                                                                    const MaterialParseContext& ctx);

}  // namespace kozu
