// Bad scene input: every problem gives one message naming the file and the JSON path.
#include "core/error.h"
#include "core/file_io.h"
#include "io/image_io.h"
#include "materials/diffuse.h"
#include "media/voxel_grid.h"
#include "scene/scene_loader.h"
#include "support/memory_limit_env.h"
#include "support/render_test.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>

namespace kozu::test {
namespace {

// A valid minimal scene with one replaceable fragment.
std::string scene_with(const std::string& materials, const std::string& shapes, const std::string& extra = "") {
  return fmt::format(R"({{
  "camera": {{"position": [0, 1, 5], "look_at": [0, 0, 0], "resolution": [8, 8]}},
  "materials": {{{}}},
  "shapes": [{}]{}
}})",
                     materials, shapes, extra);
}
const std::string kMat = R"("m": {"type": "diffuse", "albedo": 0.5})";
const std::string kSphere = R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"})";

struct ErrorCase {
  const char* name;
  std::string json;
  std::string message;  // the exact what() of the error
};

std::vector<ErrorCase> cases() {
  return {
      {"MalformedJson", "{\n  \"camera\": {,\n}",
       "scene.json: line 2, column 14: invalid JSON: syntax error while parsing object key - unexpected ','; expected "
       "string literal"},
      {"ClampNotPositive", scene_with(kMat, kSphere, R"(, "render": {"clamp": 0})"),
       "scene.json: /render/clamp: expected a number > 0, got 0"},
      {"UnknownMaterialType", scene_with(R"("gold": {"type": "metal"})", kSphere),
       "scene.json: /materials/gold/type: unknown value 'metal' (expected one of 'diffuse', 'conductor', "
       "'dielectric', 'plastic', 'subsurface', 'standard')"},
      {"SubsurfaceWithoutLength", scene_with(R"("m": {"type": "subsurface", "albedo": [0.8, 0.5, 0.4]})", kSphere),
       "scene.json: /materials/m/mfp: give exactly one of \"mfp\" (volume mean free path) and \"dmfp\" (diffuse "
       "mean free path), per color channel, in scene units"},
      {"SubsurfaceBothLengths",
       scene_with(R"("m": {"type": "subsurface", "mfp": [1, 1, 1], "dmfp": [1, 1, 1]})", kSphere),
       "scene.json: /materials/m/dmfp: give exactly one of \"mfp\" (volume mean free path) and \"dmfp\" (diffuse "
       "mean free path), per color channel, in scene units"},
      {"SubsurfaceDmfpParameterizationNeedsDmfp",
       scene_with(R"("m": {"type": "subsurface", "mfp": [1, 1, 1], "parameterization": "dmfp"})", kSphere),
       "scene.json: /materials/m/parameterization: \"dmfp\" needs the \"dmfp\" key instead of \"mfp\""},
      {"SubsurfaceSearchlightNeedsMfp",
       scene_with(R"("m": {"type": "subsurface", "dmfp": [1, 1, 1], "parameterization": "searchlight"})", kSphere),
       "scene.json: /materials/m/parameterization: \"searchlight\" is a parameterization of the mean free path: use "
       "\"mfp\""},
      {"SubsurfaceNegativeMfp", scene_with(R"("m": {"type": "subsurface", "mfp": [1, -1, 1]})", kSphere),
       "scene.json: /materials/m/mfp/1: expected a number > 0, got -1"},
      {"SubsurfaceAlbedoAboveOne", scene_with(R"("m": {"type": "subsurface", "mfp": 1, "albedo": 1.2})", kSphere),
       "scene.json: /materials/m/albedo: expected a number in [0, 1], got 1.2"},
      {"SubsurfaceStochasticBoundary",
       scene_with(R"("m": {"type": "subsurface", "mfp": 1, "roughness": 0.3, "multiscatter": "stochastic"})", kSphere),
       "scene.json: /materials/m/multiscatter: unknown value 'stochastic' (expected one of 'none', 'compensated')"},
      {"UnknownMediumType",
       R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]}, "media": {"fog": {"type": "smoke"}},
           "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "fog"}]})",
       "scene.json: /media/fog/type: unknown value 'smoke' (expected one of 'homogeneous', 'grid', 'sggx')"},
      {"UnknownInteriorMedium",
       R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
           "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "fog"}]})",
       "scene.json: /shapes/0/interior: unknown medium 'fog' (defined: none)"},
      {"UnknownCameraMedium",
       R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "medium": "air"},
           "media": {"fog": {"type": "homogeneous"}},
           "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "fog"}]})",
       "scene.json: /camera/medium: unknown medium 'air' (defined: 'fog')"},
      {"NegativeMediumDensity",
       R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]}, "media": {"fog": {"type": "homogeneous", "density": -1}},
           "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "fog"}]})",
       "scene.json: /media/fog/density: expected a number >= 0, got -1"},
      {"SggxVolumeNonUniformScale",
       R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
           "media": {"bush": {"type": "sggx", "file": "bush.kvox", "transform": {"scale": [1, 2, 1]}}},
           "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "bush"}]})",
       "scene.json: /media/bush/transform: an SGGX volume takes rotations, uniform scales and translations only (a "
       "non-uniform scale or shear would reshape its microflakes)"},
      {"GridMediumSingularTransform",
       R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
           "media": {"smoke": {"type": "grid", "file": "smoke.kvox", "transform": {"scale": [1, 0, 1]}}},
           "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "smoke"}]})",
       "scene.json: /media/smoke/transform/scale: scale factors must be nonzero"},
      {"HgPhaseOutOfRange",
       R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
           "media": {"fog": {"type": "homogeneous", "phase": {"type": "hg", "g": 1}}},
           "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "fog"}]})",
       "scene.json: /media/fog/phase/g: expected a number in (-1, 1), got 1"},
      {"SubsurfaceUnknownKey", scene_with(R"("m": {"type": "subsurface", "mfp": 1, "radius": 1})", kSphere),
       "scene.json: /materials/m/radius: unknown key 'radius'"},
      {"RoughnessAndGloss", scene_with(R"("m": {"type": "conductor", "roughness": 0.5, "gloss": 0.5})", kSphere),
       "scene.json: /materials/m/gloss: give only one of 'roughness', 'alpha', 'alpha_u'/'alpha_v' or 'gloss' (also "
       "got 'roughness')"},
      {"AlphaUWithoutAlphaV", scene_with(R"("m": {"type": "conductor", "alpha_u": 0.5})", kSphere),
       "scene.json: /materials/m/alpha_u: give both 'alpha_u' and 'alpha_v'"},
      {"GlossModelWithoutGloss",
       scene_with(R"("m": {"type": "dielectric", "roughness": 0.3, "gloss_model": "aw"})", kSphere),
       "scene.json: /materials/m/gloss_model: applies only with 'gloss'"},
      {"RoughnessOutOfRange", scene_with(R"("m": {"type": "plastic", "roughness": 1.5})", kSphere),
       "scene.json: /materials/m/roughness: expected a number in [0, 1], got 1.5"},
      {"TexturedRoughnessOutOfRange",
       scene_with(R"("m": {"type": "conductor", "roughness": {"type": "constant", "value": 2}})", kSphere),
       "scene.json: /materials/m/roughness/value: expected a number in [0, 1], got 2"},
      {"TexturedAlphaCheckerOutOfRange",
       scene_with(R"("m": {"type": "dielectric", "alpha_u": 0.1, "alpha_v": {"type": "checker", "a": 1.5}})", kSphere),
       "scene.json: /materials/m/alpha_v/a: expected a number in [0, 1], got 1.5"},
      {"UnknownMultiscatter",
       scene_with(R"("m": {"type": "conductor", "roughness": 0.5, "multiscatter": "kc"})", kSphere),
       "scene.json: /materials/m/multiscatter: unknown value 'kc' (expected one of 'none', 'compensated', "
       "'stochastic')"},
      {"MsFresnelWithoutCompensation",
       scene_with(R"("m": {"type": "conductor", "roughness": 0.5, "ms_fresnel": "series"})", kSphere),
       "scene.json: /materials/m/ms_fresnel: applies only to \"multiscatter\": \"compensated\""},
      {"NegativeIor", scene_with(R"("glass": {"type": "dielectric", "ior": -1})", kSphere),
       "scene.json: /materials/glass/ior: expected a number > 0, got -1"},
      {"WrongType", scene_with(R"("glass": {"type": "dielectric", "ior": "1.5"})", kSphere),
       "scene.json: /materials/glass/ior: expected a number > 0, got the string \"1.5\""},
      {"AlbedoOutOfRange", scene_with(R"("m": {"type": "diffuse", "albedo": [0.5, 1.5, 0.5]})", kSphere),
       "scene.json: /materials/m/albedo/1: expected a number in [0, 1], got 1.5"},
      {"UnknownKey", scene_with(R"("m": {"type": "diffuse", "albdo": 0.5})", kSphere),
       "scene.json: /materials/m/albdo: unknown key 'albdo' (did you mean 'albedo'?)"},
      {"MissingKey", scene_with(kMat, R"({"type": "sphere", "center": [0, 0, 0], "material": "m"})"),
       "scene.json: /shapes/0: missing required key 'radius'"},
      {"UnknownShapeType", scene_with(kMat, R"({"type": "cube", "material": "m"})"),
       "scene.json: /shapes/0/type: unknown value 'cube' (expected one of 'sphere', 'quad', 'polygon', 'mesh', "
       "'gltf', 'instance')"},
      {"UndefinedMaterial",
       scene_with(kMat, R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "gold"})"),
       "scene.json: /shapes/0/material: unknown material 'gold' (defined: 'm')"},
      {"MissingMeshFile", scene_with(kMat, R"({"type": "mesh", "file": "no_such_mesh.obj", "material": "m"})"),
       "scene.json: /shapes/0/file: no_such_mesh.obj: cannot open file: No such file or directory"},
      {"DegenerateQuad",
       scene_with(kMat,
                  R"({"type": "quad", "material": "m", "vertices": [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]})"),
       "scene.json: /shapes/0/vertices: degenerate polygon (zero area)"},
      {"DegenerateInlineTriangle",
       scene_with(
           kMat,
           R"({"type": "mesh", "material": "m", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], "indices": [0, 1, 2, 0, 1, 3]})"),
       "scene.json: /shapes/0: triangle 1 is degenerate (zero area); set \"skip_degenerate\": true to drop such "
       "triangles"},
      {"SelfCrossingPentagon",  // a pentagram: ear clipping alone would triangulate it
       scene_with(kMat, R"({"type": "polygon", "material": "m", "vertices": [[0, 1, 0], [0.588, -0.809, 0],
                           [-0.951, 0.309, 0], [0.951, 0.309, 0], [-0.588, -0.809, 0]]})"),
       "scene.json: /shapes/0/vertices: polygon is self-intersecting (edges 0-1 and 2-3 meet)"},
      {"NonPlanarQuad",
       scene_with(kMat,
                  R"({"type": "quad", "material": "m", "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0.5], [0, 1, 0]]})"),
       "scene.json: /shapes/0/vertices: polygon is not planar (vertex 0 is 0.118 off its plane)"},
      {"InfiniteNumber",
       scene_with(kMat, R"({"type": "sphere", "center": [0, 1e999, 0], "radius": 1, "material": "m"})"),
       "scene.json: /shapes/0/center/1: number 1e999 is out of range"},
      {"FloatOverflow",
       scene_with(kMat, R"({"type": "sphere", "center": [0, 1e300, 0], "radius": 1, "material": "m"})"),
       "scene.json: /shapes/0/center/1: expected a number of magnitude below 3.4e38, got 1e+300"},
      {"OverflowInArray",
       R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]}, "shapes": [{}, {"type": "quad", "vertices": [[0, 0, 0], [1, 0, 0], [1, -1e400, 0]]}]})",
       "scene.json: /shapes/1/vertices/2/1: number -1e400 is out of range"},
      {"BadResolution",
       R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [0, 8]}, "shapes": []})",
       "scene.json: /camera/resolution/0: expected an integer in [1, 65536], got 0"},
      {"BadMaxDepth", scene_with(kMat, kSphere, R"(, "render": {"max_depth": 2.5})"),
       "scene.json: /render/max_depth: expected an integer in [0, 1024], got 2.5"},
      {"UnknownTopLevelKey", scene_with(kMat, kSphere, R"(, "lihgts": [])"),
       "scene.json: /lihgts: unknown key 'lihgts' (did you mean 'lights'?)"},
      {"EnvironmentBothForms",
       scene_with(kMat, kSphere, R"(, "lights": [{"type": "environment", "radiance": 1, "file": "x.exr"}])"),
       "scene.json: /lights/0: give exactly one of 'radiance' (uniform) or 'file' (lat-long image)"},
      {"MissingEnvironmentImage",
       scene_with(kMat, kSphere, R"(, "lights": [{"type": "environment", "file": "missing.exr"}])"),
       "scene.json: /lights/0/file: missing.exr: image file not found"},
      {"UnknownMetal", scene_with(R"("m": {"type": "conductor", "metal": "unobtainium"})", kSphere),
       "scene.json: /materials/m/metal: unknown metal 'unobtainium' (known: Au, Ag, Cu, Al, Cr, Ti, Fe, Ni, Pt, W, "
       "Pb)"},
      {"ShapeWithoutMaterial", scene_with(kMat, R"({"type": "sphere", "center": [0, 0, 0], "radius": 1})"),
       "scene.json: /shapes/0: missing required key 'material' (only emitters and medium boundaries may omit it)"},
      {"SppZeroWithoutTimeLimit", scene_with(kMat, kSphere, R"(, "render": {"spp": 0})"),
       "scene.json: /render/spp: spp 0 (no sample limit) needs a time limit > 0"},
      {"CameraUpParallel", R"({"camera": {"position": [0, 5, 0], "look_at": [0, 0, 0]}, "shapes": []})",
       "scene.json: /camera/up: up is parallel to the view direction"},
      {"NotAnObject", R"([1, 2, 3])", "scene.json: expected an object, got an array"},
      {"DiffuseKeyOfAnotherModel",
       scene_with(R"("m": {"type": "diffuse", "model": "cod-multiscatter", "gloss": 0.3, "f0": 0.04})", kSphere),
       "scene.json: /materials/m/f0: 'f0' is read only by model 'shirley' (this material's model is "
       "'cod-multiscatter')"},
      {"GlossWithLambert", scene_with(R"("m": {"type": "diffuse", "albedo": 0.5, "gloss": 0.3})", kSphere),
       "scene.json: /materials/m/gloss: 'gloss' is read only by model 'cod-multiscatter' (this material's model is "
       "'lambert')"},
      {"UnknownDiffuseModel", scene_with(R"("m": {"type": "diffuse", "model": "oren-nayar"})", kSphere),
       "scene.json: /materials/m/model: unknown value 'oren-nayar' (expected one of 'lambert', 'cod-multiscatter', "
       "'shirley')"},
      {"DiffuseDistribution",
       scene_with(R"("m": {"type": "diffuse", "model": "cod-multiscatter", "distribution": "ggx"})", kSphere),
       "scene.json: /materials/m/distribution: no diffuse model has a microfacet distribution"},
      {"DiffuseGlossOutOfRange",
       scene_with(R"("m": {"type": "diffuse", "model": "cod-multiscatter", "gloss": 1.5})", kSphere),
       "scene.json: /materials/m/gloss: expected a number in [0, 1], got 1.5"},
      {"ShirleyF0OutOfRange", scene_with(R"("m": {"type": "diffuse", "model": "shirley", "f0": -0.1})", kSphere),
       "scene.json: /materials/m/f0: expected a number in [0, 1], got -0.1"},
      // Issue 11 regressions: duplicate keys, integer rule, seeds, thin-lens keys, overflowing lights, excerpts.
      {"DuplicateTopLevelKey", scene_with(kMat, kSphere, R"(, "render": {"spp": 4}, "render": {"spp": 8})"),
       "scene.json: /render: key 'render' appears twice in this object"},
      {"DuplicateMaterialName", scene_with(kMat + ", " + kMat, kSphere),
       "scene.json: /materials/m: key 'm' appears twice in this object"},
      {"DuplicateNestedKey", scene_with(R"("m": {"type": "diffuse", "albedo": 0.5, "albedo": 0.7})", kSphere),
       "scene.json: /materials/m/albedo: key 'albedo' appears twice in this object"},
      {"FractionalResolution",
       R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [64.5, 8]}, "shapes": []})",
       "scene.json: /camera/resolution/0: expected an integer in [1, 65536], got 64.5"},
      {"FractionalSpp", scene_with(kMat, kSphere, R"(, "render": {"spp": 4.5})"),
       "scene.json: /render/spp: expected an integer in [0, 2147483647], got 4.5"},
      {"NegativeSeed", scene_with(kMat, kSphere, R"(, "render": {"seed": -1})"),
       "scene.json: /render/seed: expected an integer in [0, 18446744073709551615], got -1"},
      {"FractionalVertexIndex",
       scene_with(
           kMat,
           R"({"type": "mesh", "material": "m", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "indices": [0, 1, 2.5]})"),
       "scene.json: /shapes/0/indices/2: expected an integer in [0, 3), got 2.5"},
      {"ApertureOnPinhole",
       R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "aperture_radius": 0.1}, "shapes": []})",
       "scene.json: /camera/aperture_radius: 'aperture_radius' needs a thin-lens camera: add \"type\": \"thinlens\""},
      {"FocusDistanceOnPinhole",
       R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "focus_distance": 3}, "shapes": []})",
       "scene.json: /camera/focus_distance: 'focus_distance' needs a thin-lens camera: add \"type\": \"thinlens\""},
      {"EmissionPowerOverflows",
       scene_with(kMat, R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "emission": 3e38})"),
       "scene.json: /shapes/0/emission: the light's power (inf) is beyond kozu's range (at most 1e+30); lower its "
       "emission or its size"},
      {"TexturedEmissionOnSphere",
       scene_with(kMat, R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "emission": {"type": "checker"}})"),
       "scene.json: /shapes/0/emission: a textured emission needs a quad or polygon shape, not a sphere"},
      {"TexturedEmissionNegativeChecker",
       scene_with(
           kMat,
           R"({"type": "quad", "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], "emission": {"type": "checker", "a": -1}})"),
       "scene.json: /shapes/0/emission/a: expected a number >= 0, got -1"},
      {"PointIntensityOverflows",
       scene_with(kMat, kSphere, R"(, "lights": [{"type": "point", "position": [0, 3, 0], "intensity": 1e38}])"),
       "scene.json: /lights/0: the light's power (inf) is beyond kozu's range (at most 1e+30); lower its emission or "
       "its size"},
      {"EnvironmentRadianceTimesScaleOverflows",
       scene_with(kMat, kSphere, R"(, "lights": [{"type": "environment", "radiance": 3e38, "scale": 3e38}])"),
       "scene.json: /lights/0/scale: radiance times scale is 9e+76, beyond kozu's range (at most 1e+30)"},
      {"SphereBeyondCoordinateBounds",
       scene_with(kMat, R"({"type": "sphere", "center": [1e38, 0, 0], "radius": 1, "material": "m"})"),
       "scene.json: /shapes/0/center: coordinates must lie within ±1e+15, got (1e+38, 0, 0)"},
      {"HugeRadius", scene_with(kMat, R"({"type": "sphere", "center": [0, 0, 0], "radius": 1e20, "material": "m"})"),
       "scene.json: /shapes/0/radius: expected a number in (0, 1e+15], got 1e+20"},
      {"HugeAperture",
       R"({"camera": {"type": "thinlens", "position": [0, 0, 5], "look_at": [0, 0, 0], "aperture_radius": 1e30}, "shapes": []})",
       "scene.json: /camera/aperture_radius: expected a number in (0, 1e+15], got 1e+30"},
      {"MeshBeyondCoordinateBoundsAfterTransform",
       scene_with(
           kMat,
           R"({"type": "mesh", "material": "m", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "indices": [0, 1, 2], "transform": {"scale": 1e16}})"),
       "scene.json: /shapes/0: mesh vertex 1: coordinates must lie within ±1e+15, got (1e+16, 0, 0) after the "
       "transform"},
      // Keyed shapes (scene/animation.h).
      {"AnimatedUnknownShape",
       scene_with(kMat, kSphere, R"(, "animation": {"frames": 2, "shapes": {"ball": [{"time": 0, "transform": {}}]}})"),
       "scene.json: /animation/shapes/ball: no shape is named 'ball' (named shapes: none); give the shape a \"name\""},
      {"AnimatedDuplicateName",
       scene_with(kMat, R"({"name": "b", "type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"},
                           {"name": "b", "type": "sphere", "center": [2, 0, 0], "radius": 1, "material": "m"})",
                  R"(, "animation": {"frames": 2, "shapes": {"b": [{"time": 0, "transform": {}}]}})"),
       "scene.json: /animation/shapes/b: 2 shapes are named 'b' (/shapes/0 and /shapes/1): an animated shape's name "
       "must be unique"},
      {"AnimatedSphereUnevenScale",
       scene_with(kMat, R"({"name": "b", "type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"})",
                  R"(, "animation": {"frames": 2, "shapes": {"b": [{"time": 0, "transform": {"scale": [1, 2, 1]}}]}})"),
       "scene.json: /animation/shapes/b: shape 'b' is a sphere: its keys must scale x, y and z alike"},
      {"AnimatedKeyShears",
       scene_with(
           kMat, kSphere,
           R"(, "animation": {"frames": 2, "shapes": {"b": [{"time": 0, "transform": {"matrix": [[1, 0.5, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}}]}})"),
       "scene.json: /animation/shapes/b/0/transform: a shape key's transform must be a translation, rotation and "
       "scale (it shears)"},
      {"AnimatedKeyMirrors",
       scene_with(
           kMat, kSphere,
           R"(, "animation": {"frames": 2, "shapes": {"b": [{"time": 0, "transform": {"scale": [-1, 1, 1]}}]}})"),
       "scene.json: /animation/shapes/b/0/transform: a shape key's transform must not mirror (a negative scale): "
       "mirror the shape itself"},
      {"AnimatedKeyTimesDecrease",
       scene_with(
           kMat, kSphere,
           R"(, "animation": {"frames": 2, "shapes": {"b": [{"time": 1, "transform": {}}, {"time": 0.5, "transform": {}}]}})"),
       "scene.json: /animation/shapes/b/1/time: key times must increase: 0.5 follows 1"},
      {"AnimatedKeyTranslationBeyondBounds",
       scene_with(
           kMat, kSphere,
           R"(, "animation": {"frames": 2, "shapes": {"b": [{"time": 0, "transform": {"translate": [1e20, 0, 0]}}]}})"),
       "scene.json: /animation/shapes/b/0/transform: coordinates must lie within ±1e+15, got (1e+20, 0, 0) (the "
       "translation)"},
      {"AnimatedKeyScaleTooLarge",
       scene_with(kMat, kSphere,
                  R"(, "animation": {"frames": 2, "shapes": {"b": [{"time": 0, "transform": {"scale": 1e9}}]}})"),
       "scene.json: /animation/shapes/b/0/transform: a shape key's scale factors must lie in [1e-6, 1e6]"},
      {"ShutterTooLong", scene_with(kMat, kSphere, R"(, "animation": {"frames": 2, "shutter": [-0.5, 0.75]})"),
       "scene.json: /animation/shutter: the shutter is open 1.25 frames: at most 1"},
      {"ShutterClosesBeforeItOpens",
       scene_with(kMat, kSphere, R"(, "animation": {"frames": 2, "shutter": [0.5, 0.25]})"),
       "scene.json: /animation/shutter: the shutter closes (0.25) before it opens (0.5)"},
      {"ShutterBeyondAFrame", scene_with(kMat, kSphere, R"(, "animation": {"frames": 2, "shutter": [0, 1.5]})"),
       "scene.json: /animation/shutter/1: expected a number in [-1, 1], got 1.5"},
      {"LongStringIsQuoted", scene_with(R"("m": {"type": ")" + std::string(5000, 'x') + R"("})", kSphere),
       "scene.json: /materials/m/type: unknown value 'xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx...' (expected one of "
       "'diffuse', 'conductor', 'dielectric', 'plastic', 'subsurface', 'standard')"},
      {"LongArrayIsQuoted",
       R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18]}, "shapes": []})",
       "scene.json: /camera/fov: expected a number in (0, 180), got an array"},
  };
}

class SceneError : public ::testing::TestWithParam<ErrorCase> {};

TEST_P(SceneError, NamesFileAndPath) {
  const ErrorCase& c = GetParam();
  try {
    load_scene_text(c.json, "scene.json", ".");
    FAIL() << "no error for " << c.name;
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), c.message);
  }
}

INSTANTIATE_TEST_SUITE_P(BadInput, SceneError, ::testing::ValuesIn(cases()),
                         [](const auto& p) { return std::string(p.param.name); });

// A 70,000-deep array crashed kozu (SIGSEGV: the message printed the value recursively); 1k-50k deep ones
// printed 60 KB lines. Nesting is bounded at parse time and messages stay short.
TEST(SceneLoader, DeepNestingIsRefusedWithAShortMessage) {
  for (int depth : {65, 1000, 70000}) {
    const std::string json = R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [)" +
                             std::string(depth, '[') + "1" + std::string(depth, ']') + R"(, 8]}, "shapes": []})";
    try {
      load_scene_text(json, "scene.json", ".");
      FAIL() << "no error at depth " << depth;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("scene.json: /camera/resolution/0/0/0/", 0), 0u) << what.substr(0, 200);
      EXPECT_NE(what.find(": arrays and objects nested deeper than 64 levels"), std::string::npos) << what;
      EXPECT_LT(what.size(), 300u);
    }
  }
  // 64 levels in all is allowed (the limit counts the top-level object).
  const std::string ok = R"({"comment": )" + std::string(63, '[') + std::string(63, ']') +
                         R"(, "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]}, "shapes": []})";
  EXPECT_NO_THROW(load_scene_text(ok, "scene.json", "."));
}

// Every roughness key of conductor, dielectric, plastic and subsurface takes a texture (materials/roughness.h).
TEST(SceneLoader, TexturedRoughnessKeysAreAccepted) {
  const std::string checker = R"({"type": "checker", "a": 0.2, "b": 0.6})";
  for (const std::string& m :
       {R"({"type": "conductor", "metal": "Au", "roughness": )" + checker + "}",
        R"({"type": "conductor", "alpha_u": )" + checker + R"(, "alpha_v": 0.3, "multiscatter": "compensated"})",
        R"({"type": "dielectric", "gloss": )" + checker + R"(, "gloss_model": "aw"})",
        std::string(R"({"type": "plastic", "alpha": {"type": "constant", "value": 0.1}})"),
        R"({"type": "subsurface", "mfp": 1, "roughness": )" + checker + "}"})
    EXPECT_NO_THROW(load_scene_text(scene_with(R"("m": )" + m, kSphere), "scene.json", ".")) << m;
}

// "comment" in any object, with any value, user-named maps included (it names no material).
TEST(SceneLoader, CommentsAreAllowedInEveryObject) {
  auto scene = load_scene_text(
      R"({"comment": "top", "camera": {"comment": "c", "position": [0, 0, 5], "look_at": [0, 0, 0]},
          "render": {"comment": ["r", 1], "spp": 1},
          "materials": {"comment": "the map",
                        "m": {"comment": "m", "type": "diffuse",
                              "albedo": {"comment": {"by": "x"}, "type": "checker", "a": 0.2, "b": 0.6}}},
          "shapes": [{"comment": "s", "type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}],
          "lights": [{"comment": 3, "type": "environment", "radiance": 1}]})",
      "scene.json", ".");
  EXPECT_EQ(scene->settings.spp, 1);
  EXPECT_EQ(scene->materials.size(), 1u);
}

// A key that does nothing is a warning (Scene::warnings: stderr and --stats), not silence: multiscatter on a smooth
// conductor or dielectric. The rough ones take it without a word.
TEST(SceneLoader, MultiscatterOnASmoothSurfaceIsWarnedAbout) {
  for (const bool rough : {false, true}) {
    const std::string r = rough ? R"(, "roughness": 0.4)" : "";
    auto scene = load_scene_text(
        scene_with(R"("c": {"type": "conductor", "metal": "Au", "multiscatter": "compensated")" + r + R"(},
                      "g": {"type": "dielectric", "multiscatter": "stochastic")" +
                       r + "}",
                   R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "c"},
                      {"type": "sphere", "center": [3, 0, 0], "radius": 1, "material": "g"})",
                   R"(, "lights": [{"type": "environment", "radiance": 1}])"),
        "scene.json", ".");
    if (rough) {
      EXPECT_TRUE(scene->warnings.empty()) << scene->warnings.front();
    } else {
      ASSERT_EQ(scene->warnings.size(), 2u);
      EXPECT_EQ(scene->warnings[0],
                "scene.json: /materials/c/multiscatter: has no effect on a smooth conductor (a mirror scatters once); "
                "give it a roughness");
      EXPECT_EQ(scene->warnings[1],
                "scene.json: /materials/g/multiscatter: has no effect on a smooth dielectric (it reflects or refracts "
                "once); give it a roughness");
    }
  }
}

// A shape bounding a medium or with a subsurface material should be closed: an open one is warned about (it is
// not an error: a ground plane may bound an atmosphere); a closed one, or an open one with neither, is not.
TEST(SceneLoader, OpenShapesAroundMediaOrSubsurfaceAreWarnedAbout) {
  const std::string quad = R"("vertices": [[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]])";
  const auto warnings = [&](const std::string& shape) {
    return load_scene_text(
               scene_with(R"("m": {"type": "diffuse", "albedo": 0.5}, "s": {"type": "subsurface", "mfp": 1})", shape,
                          R"(, "media": {"fog": {"type": "homogeneous", "density": 0.2}},
                             "lights": [{"type": "environment", "radiance": 1}])"),
               "scene.json", ".")
        ->warnings;
  };
  EXPECT_EQ(warnings(R"({"type": "quad", "material": "s", )" + quad + "}"),
            std::vector<std::string>{"scene.json: /shapes/0: the shape has a subsurface material but is not closed (4 "
                                     "edges on one triangle only): paths can cross it once and end up inside without "
                                     "a way out; close the mesh"});
  const auto fog = warnings(R"({"type": "quad", "material": "m", "interior": "fog", )" + quad + "}");
  ASSERT_EQ(fog.size(), 1u);
  EXPECT_NE(fog[0].find("bounds a medium but is not closed"), std::string::npos) << fog[0];
  EXPECT_TRUE(
      warnings(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "s", "interior": "fog"})").empty());
  EXPECT_TRUE(warnings(R"({"type": "quad", "material": "m", )" + quad + "}").empty());
}

// An SGGX grid seen so small that the level of detail it asks for is beyond its chain is warned about (the
// coarsest voxels are still smaller than a pixel, so it aliases); seen close, it is not. A changed resolution
// recomputes the warning.
TEST(SceneLoader, ClampedLevelOfDetailIsWarnedAbout) {
  test::TempDir dir;
  VoxelGrid grid(Vec3i(8), Vec3(-1.0f), Vec3(1.0f), true);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 8; ++i) grid.set_voxel(i, j, k, 1.0f, Sggx{});
  grid.save_kvox(dir.path() / "g.kvox");
  const auto load = [&](float distance) {
    return load_scene_text(fmt::format(R"({{"camera": {{"position": [0, 0, {}], "look_at": [0, 0, 0],
        "resolution": [64, 64]}}, "media": {{"cloud": {{"type": "sggx", "file": "g.kvox"}}}},
        "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 2, "interior": "cloud"}}],
        "lights": [{{"type": "environment", "radiance": 1}}]}})",
                                       distance),
                           "scene.json", dir.path());
  };
  auto far = load(1000.0f);
  ASSERT_EQ(far->view_warnings.size(), 1u);
  EXPECT_EQ(far->view_warnings[0].rfind("medium 'cloud': the level of detail is clamped: the view asks for level 6, "
                                        "the grid's coarsest is 3",
                                        0),
            0u)
      << far->view_warnings[0];
  EXPECT_EQ(far->all_warnings().size(), far->warnings.size() + 1);
  EXPECT_TRUE(load(5.0f)->view_warnings.empty());
  // At 4096 pixels the same view asks for level 0.
  far->camera.set_resolution(Vec2i(4096, 4096));
  far->set_media_view();
  EXPECT_TRUE(far->view_warnings.empty());
}

// One rule for integers: an integral value is accepted wherever an integer is, whether written 64 or 64.0
// ("spp": 4.0 was accepted but "resolution": [64.0, 64] was not).
TEST(SceneLoader, IntegralFloatsAreIntegersEverywhere) {
  auto scene = load_scene_text(
      R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [64.0, 32]},
          "render": {"spp": 4.0, "max_depth": 7.0, "seed": 3.0}, "shapes": []})",
      "scene.json", ".");
  EXPECT_EQ(scene->camera.resolution(), Vec2i(64, 32));
  EXPECT_EQ(scene->settings.spp, 4);
  EXPECT_EQ(scene->settings.max_depth, 7);
  EXPECT_EQ(scene->settings.seed, 3u);
}

// Negative pixels in an environment image were clamped silently.
TEST(SceneLoader, NegativeEnvironmentPixelsAreRefused) {
  TempDir dir;
  std::vector<float> px(4 * 2 * 3, 1.0f);
  px[3 * 5 + 1] = -0.25f;  // pixel (1, 1), green
  write_image(dir.path() / "sky.exr", 4, 2, px, ToneMap{});
  try {
    load_scene_text(scene_with(kMat, kSphere, R"(, "lights": [{"type": "environment", "file": "sky.exr"}])"),
                    "scene.json", dir.path());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(
        std::string(e.what()),
        fmt::format("scene.json: /lights/0/file: {}: radiance must be >= 0, and pixel (1, 1) channel 1 is "
                    "-0.25: its 1 negative value carries 0.011 of its energy and reaches 0.25 of its largest value "
                    "(filtering noise, clamped to 0, carries at most 1e-4 and reaches at most 1e-3)",
                    (dir.path() / "sky.exr").lexically_normal().string()));
  }
}

// An 8-bit environment image is sRGB-encoded, as 8-bit colour textures are (it was read as linear): its 128 is
// radiance 0.2158 under "auto" and "srgb", 128/255 under "linear"; a float image stays linear.
TEST(SceneLoader, EightBitEnvironmentImagesAreDecodedAsSrgb) {
  TempDir dir;
  {
    // Written directly, as 8 bits (kozu's own PNG writer tone-maps and dithers).
    const std::vector<unsigned char> px(4 * 2 * 3, 128);
    auto out = OIIO::ImageOutput::create((dir.path() / "sky.png").string());
    ASSERT_TRUE(out && out->open((dir.path() / "sky.png").string(), OIIO::ImageSpec(4, 2, 3, OIIO::TypeDesc::UINT8)));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px.data()));
    out->close();
  }
  write_image(dir.path() / "sky.exr", 4, 2, std::vector<float>(4 * 2 * 3, 0.5f), ToneMap{});
  const auto radiance = [&](const std::string& file, const std::string& colorspace) {
    auto scene = load_scene_text(
        scene_with(kMat, kSphere,
                   R"(, "lights": [{"type": "environment", "file": ")" + file + "\"" + colorspace + "}]"),
        "scene.json", dir.path());
    return scene->lights.at(0)->eval(LightHit{Vec3(0, 0, -1)}).g;
  };
  EXPECT_NEAR(radiance("sky.png", ""), srgb_to_linear(128.0f / 255.0f), 1e-5f);
  EXPECT_NEAR(radiance("sky.png", R"(, "colorspace": "srgb")"), srgb_to_linear(128.0f / 255.0f), 1e-5f);
  EXPECT_NEAR(radiance("sky.png", R"(, "colorspace": "linear")"), 128.0f / 255.0f, 1e-5f);
  EXPECT_NEAR(radiance("sky.exr", ""), 0.5f, 1e-6f);
}

// An image header claiming 100000^2 pixels failed with std::bad_alloc and no file name; a 24-byte PFM claiming
// 30000 x 20000 allocated 7.2 GB before decoding. Headers are checked against the pixel cap and, for raw
// formats, the file's length, before any allocation.
TEST(SceneLoader, ImageHeadersAreCheckedBeforeAllocating) {
  TempDir dir;
  struct Case {
    const char* name;
    std::string bytes, fragment;
  };
  const std::vector<Case> cases = {
      {"huge.pfm", "PF\n100000 100000\n-1.0\n", "100000 x 100000 pixels exceeds the limit of 268435456 pixels"},
      {"big.pfm", "PF\n30000 20000\n-1.0\n", "30000 x 20000 pixels exceeds the limit"},
      {"short.pfm", "PF\n4000 4000\n-1.0\nabcdefgh", "truncated: a 4000 x 4000"},
      {"garbage.exr", "not an image", "not a valid OpenEXR file: bad magic number"},
      {"garbage.png", "not an image", "not a valid PNG file: no PNG signature"},
      {"noextension", "PF\n2 2\n-1.0\n", "image file has no extension"},
  };
  for (const Case& c : cases) {
    dir.write(c.name, c.bytes);
    try {
      load_scene_text(
          scene_with(kMat, kSphere, fmt::format(R"(, "lights": [{{"type": "environment", "file": "{}"}}])", c.name)),
          "scene.json", dir.path());
      ADD_FAILURE() << "no error for " << c.name;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("scene.json: /lights/0/file: ", 0), 0u) << what;
      EXPECT_NE(what.find(c.name), std::string::npos) << what;
      EXPECT_NE(what.find(c.fragment), std::string::npos) << what;
    }
  }
}

// A forged image file: written into a test folder under name, read_image must refuse it with fragment in the message.
struct ForgedImage {
  const char* name;
  std::string bytes, fragment;
};
void expect_refused(const TempDir& dir, const std::vector<ForgedImage>& cases) {
  for (const ForgedImage& c : cases) {
    dir.write(c.name, c.bytes);
    try {
      read_image(dir.path() / c.name);
      ADD_FAILURE() << "no error for " << c.name;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.fragment), std::string::npos) << e.what();
    }
  }
}

// libpng allocates what a chunk claims before reading it (a 445-byte file whose tEXt chunk claimed 1.9 GB cost 2 GB,
// found by fuzz_image): kozu walks the chunk list first. Forged from a valid PNG written by kozu.
TEST(SceneLoader, PngChunksAreCheckedBeforeLibpngAllocates) {
  TempDir dir;
  std::vector<float> px(6 * 4 * 3, 0.5f);
  write_image(dir.path() / "sky.png", 6, 4, px, ToneMap{});
  const std::string valid = read_input_file(dir.path() / "sky.png");
  std::string lying = valid;
  const size_t idat = lying.find("IDAT");
  ASSERT_NE(idat, std::string::npos);
  lying.replace(idat - 4, 4, std::string("\x78\x00\x00\x00", 4));  // 0x78000000 bytes
  expect_refused(dir,
                 {
                     {"lying.png", lying, fmt::format("chunk 'IDAT' at byte {} claims 2013265920 bytes", idat - 4)},
                     {"cut.png", valid.substr(0, valid.size() - 12), "without IEND (truncated?)"},
                     {"text.png", "not a png at all", "no PNG signature"},
                 });
  EXPECT_EQ(read_image(dir.path() / "sky.png").width, 6);  // the valid file still reads
}

// OpenEXR allocates what its header claims when a file is opened: an attribute of 1.7 GB, or a line-offset
// table for a data window of 100000 lines. kozu walks the header first (found by fuzz_image). Forged from a
// valid file written by kozu, and checked against the valid file and a tiled copy of it.
TEST(SceneLoader, ExrHeadersAreCheckedBeforeOpenExrAllocates) {
  TempDir dir;
  std::vector<float> px(6 * 4 * 3, 0.5f);
  write_image(dir.path() / "sky.exr", 6, 4, px, ToneMap{});
  const std::string valid = read_input_file(dir.path() / "sky.exr");
  // Overwrites little-endian words of an attribute (offset 0: its size; 4 on: its value).
  const auto patch = [&](const std::string& attribute, std::vector<std::pair<size_t, uint32_t>> words) {
    std::string bytes = valid;
    const size_t at = bytes.find(attribute + '\0');
    EXPECT_NE(at, std::string::npos) << attribute;
    const size_t type_end = bytes.find('\0', at + attribute.size() + 1);
    for (const auto& [offset, value] : words)
      for (int b = 0; b < 4; ++b) bytes[type_end + 1 + offset + b] = static_cast<char>((value >> (8 * b)) & 0xffu);
    return bytes;
  };
  // The valid file with one more attribute before its channel list: name, type, little-endian words, then bytes.
  const auto with_attribute = [&](const std::string& name, const std::string& type, std::vector<uint32_t> words,
                                  const std::string& tail) {
    std::string attribute = name + '\0' + type + '\0';
    for (const uint32_t w : words)
      for (int b = 0; b < 4; ++b) attribute += static_cast<char>((w >> (8 * b)) & 0xffu);
    std::string b = valid;
    b.insert(b.find(std::string("channels") + '\0'), attribute + tail);
    return b;
  };
  // The channel list's size as written.
  const uint32_t channels_size = [&] {
    const size_t at = valid.find(std::string("channels") + '\0');
    const size_t type_end = valid.find('\0', at + 9);
    uint32_t v = 0;
    for (int b = 0; b < 4; ++b) v |= uint32_t(static_cast<unsigned char>(valid[type_end + 1 + b])) << (8 * b);
    return v;
  }();
  // Under a 16 GB limit, whatever the machine has (the wide file's blocks: 26 GB and more).
  const MemoryLimitEnv limit(size_t(16) << 30);
  expect_refused(
      dir, {
               {"attribute.exr", patch("channels", {{0, 0x6a000000u}}), "attribute 'channels' claims 1778384896 bytes"},
               {"window.exr", patch("dataWindow", {{4 + 8, 99999u}, {4 + 12, 99999u}}),
                "100000 x 100000 pixels exceeds the limit"},
               // 8 million pixels wide, 4 high: under the pixel cap, but OpenEXR decodes blocks of scanlines of
               // the file's width (a fuzzed file made it ask for 25 GB).
               {"wide.exr", patch("dataWindow", {{4 + 8, 8388607u}}),
                "8388608 x 4 pixels: decoding them takes blocks of"},
               {"cut.exr", valid.substr(0, 40), "runs past the end of the file"},
               // Values OpenEXR reads by their own layout must take the bytes their header gives them, or OpenEXR
               // reads what follows from other bytes than the walk (a fuzzed channel list 3 bytes longer than its
               // size made it allocate 1.9 GB): a channel list, a fixed-size value, a preview.
               {"chlist.exr", patch("channels", {{0, channels_size - 3}}),
                fmt::format("attribute 'channels' of type 'chlist' takes {} bytes, its header claims {}",
                            channels_size, channels_size - 3)},
               {"compression.exr", patch("compression", {{0, 4}}),
                "attribute 'compression' of type 'compression' takes 1 byte, its header claims 4"},
               // A 1000 x 1000 preview whose header claims only its 8 bytes of width and height.
               {"preview.exr", with_attribute("preview", "preview", {8u, 1000u, 1000u}, ""),
                "attribute 'preview' of type 'preview' takes 4000008 bytes, its header claims 8"},
               // A string vector of 8 bytes whose one string claims a million.
               {"strings.exr", with_attribute("notes", "stringvector", {8u, 1000000u, 0u}, ""),
                "a string of attribute 'notes' claims 1000000 bytes, past the end of its value"},
               // A 32-character attribute name without the long-names flag: OpenEXR reads such a file differently (a
               // fuzzed one made it allocate 2 GB), so it is refused.
               {"longname.exr",
                [&] {
                  std::string b = valid;
                  const size_t at = b.find(std::string("channels") + '\0');
                  b.replace(at, 8, std::string(32, 'c'));
                  return b;
                }(),
                "an attribute name longer than 31 characters"},
           });
  // Under a 1 GB limit the wide file is refused before OpenEXR opens it: opening makes its compressor's buffers,
  // a block of 16 lines twice (a fuzzed 4-million-pixel-wide file made it allocate 1.1 GB there).
  {
    const MemoryLimitEnv small(size_t(1) << 30);
    expect_refused(dir, {{"wide.exr", patch("dataWindow", {{4 + 8, 8388607u}}), "decoding it takes blocks of"}});
  }
  // The valid file, and the same pixels tiled (read in rows of tiles), still read.
  const Image a = read_image(dir.path() / "sky.exr");
  EXPECT_EQ(a.data, px);
  // So does the file with a well-formed string vector ("ab", "c") in its header, its chunks' offsets moved with it.
  {
    // 11 bytes: "ab" and "c", each after its length.
    const std::string value = std::string("\x02\0\0\0ab", 6) + std::string("\x01\0\0\0c", 5);
    std::string b = with_attribute("notes", "stringvector", {11u}, value);
    const size_t inserted = b.size() - valid.size();
    // The offset table follows the header's closing empty name; its first entry points just past the table.
    size_t end = 8;
    for (;;) {
      const size_t name_end = b.find('\0', end);
      if (name_end == end) break;
      const size_t type_end = b.find('\0', name_end + 1);
      uint32_t size = 0;
      for (int k = 0; k < 4; ++k) size |= uint32_t(static_cast<unsigned char>(b[type_end + 1 + k])) << (8 * k);
      end = type_end + 5 + size;
    }
    const size_t table = end + 1;
    const auto u64_at = [&](size_t at) {
      uint64_t v = 0;
      for (int k = 0; k < 8; ++k) v |= uint64_t(static_cast<unsigned char>(b[at + k])) << (8 * k);
      return v;
    };
    const size_t chunks = (u64_at(table) + inserted - table) / 8;
    ASSERT_GT(chunks, 0u);
    for (size_t c = 0; c < chunks; ++c) {
      const uint64_t moved = u64_at(table + 8 * c) + inserted;
      for (int k = 0; k < 8; ++k) b[table + 8 * c + k] = static_cast<char>((moved >> (8 * k)) & 0xffu);
    }
    dir.write("notes.exr", b);
    EXPECT_EQ(read_image(dir.path() / "notes.exr").data, px);
  }
  std::string out;
  ASSERT_EQ(run_command(fmt::format("oiiotool '{}' --tile 4 4 -o '{}'", (dir.path() / "sky.exr").string(),
                                    (dir.path() / "tiled.exr").string()),
                        &out),
            0)
      << out;
  EXPECT_EQ(read_image(dir.path() / "tiled.exr").data, px);
}

TEST(SceneLoader, MeshFileErrorsNameBothFiles) {
  TempDir dir;
  { std::ofstream(dir.path() / "bad.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"; }
  const std::string json = scene_with(kMat, R"({"type": "mesh", "file": "bad.obj", "material": "m"})");
  try {
    load_scene_text(json, "scene.json", dir.path());
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("scene.json: /shapes/0/file: ", 0), 0u) << what;
    EXPECT_NE(what.find("bad.obj"), std::string::npos) << what;
  }
}

// Loading has three phases (scene/scene_loader.h): a mistake anywhere in the scene is reported before any file
// it names is opened, here a misspelt key in the last light while a voxel grid, a mesh and an environment image
// are all missing.
std::string scene_with_missing_files(const std::string& last_light) {
  return fmt::format(R"({{
  "camera": {{"position": [0, 1, 5], "look_at": [0, 0, 0], "resolution": [8, 8]}},
  "materials": {{"m": {{"type": "diffuse"}}}},
  "media": {{"fog": {{"type": "grid", "file": "missing.kvox"}}}},
  "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "fog"}},
             {{"type": "mesh", "file": "missing.obj", "material": "m"}}],
  "lights": [{{"type": "environment", "file": "missing.exr"}}, {}]
}})",
                     last_light);
}

TEST(SceneLoader, EveryKeyIsCheckedBeforeAnyFileIsRead) {
  TempDir dir;
  try {
    load_scene_text(
        scene_with_missing_files(R"({"type": "point", "position": [0, 3, 0], "intensity": 1, "colour": 1})"),
        "scene.json", dir.path());
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("scene.json: /lights/1/colour: ", 0), 0u) << what;
  }
}

// With the scene itself valid, the files are read (in parallel) and the first failure in the order materials,
// media, shapes, lights is the one reported.
TEST(SceneLoader, LoadErrorsReportTheFirstFailingFile) {
  TempDir dir;
  try {
    load_scene_text(scene_with_missing_files(R"({"type": "point", "position": [0, 3, 0], "intensity": 1})"),
                    "scene.json", dir.path());
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("scene.json: /media/fog/file: ", 0), 0u) << what;
    EXPECT_NE(what.find("missing.kvox"), std::string::npos) << what;
  }
}

TEST(SceneLoader, SkipDegenerateDropsZeroAreaTriangles) {
  const std::string json = scene_with(
      kMat,
      R"({"type": "mesh", "material": "m", "skip_degenerate": true, "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], "indices": [0, 1, 2, 0, 1, 3]})");
  auto scene = load_scene_text(json, "scene.json", ".");
  EXPECT_EQ(scene->triangle_count(), 1u);
}

TEST(SceneLoader, NonConvexPolygonIsTriangulatedWithItsArea) {
  // An L-shaped hexagon of area 3 (a 2x2 square minus a unit square).
  const std::string json = scene_with(
      kMat,
      R"({"type": "polygon", "material": "m", "vertices": [[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]]})");
  auto scene = load_scene_text(json, "scene.json", ".");
  const Shape& s = *scene->shapes.at(0);
  ASSERT_EQ(s.primitive_count(), 4u);
  double area = 0;
  for (uint32_t i = 0; i < s.primitive_count(); ++i) area += s.primitive_area(i);
  EXPECT_NEAR(area, 3.0, 1e-5);
}

TEST(SceneLoader, TransformsApplyScaleRotateTranslate) {
  const std::string json = scene_with(
      kMat,
      R"({"type": "mesh", "material": "m", "positions": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "indices": [0, 1, 2],
          "transform": {"scale": 2, "rotate": [0, 0, 1, 90], "translate": [10, 0, 0]}})");
  auto scene = load_scene_text(json, "scene.json", ".");
  const auto* mesh = dynamic_cast<const TriangleMesh*>(scene->shapes.at(0).get());
  ASSERT_NE(mesh, nullptr);
  // (1,0,0) -> scale (2,0,0) -> rotate 90 about z (0,2,0) -> translate (10,2,0).
  EXPECT_NEAR(mesh->position(0).x, 10.0f, 1e-5f);
  EXPECT_NEAR(mesh->position(0).y, 2.0f, 1e-5f);
  EXPECT_NEAR(mesh->position(0).z, 0.0f, 1e-5f);
}

// One rule for scale, a number or a vector: nonzero; a negative one mirrors (it used to be refused as a number
// and accepted as a vector).
TEST(SceneLoader, ScaleIsNonzeroAsANumberOrAVector) {
  const auto mesh_with = [](const std::string& scale) {
    return scene_with(kMat, R"({"type": "mesh", "material": "m", "positions": [[1, 0, 0], [0, 1, 0], [0, 0, 1]],
        "indices": [0, 1, 2], "transform": {"scale": )" +
                                scale + "}}");
  };
  for (const std::string scale : {"-2", "[-2, -2, -2]"}) {
    auto scene = load_scene_text(mesh_with(scale), "scene.json", ".");
    const auto* mesh = dynamic_cast<const TriangleMesh*>(scene->shapes.at(0).get());
    ASSERT_NE(mesh, nullptr);
    EXPECT_EQ(mesh->position(0), Vec3(-2, 0, 0)) << scale;
  }
  for (const std::string scale : {"0", "[1, 0, 1]"}) {
    try {
      load_scene_text(mesh_with(scale), "scene.json", ".");
      ADD_FAILURE() << scale << " accepted";
    } catch (const InputError& e) {
      EXPECT_STREQ(e.what(), "scene.json: /shapes/0/transform/scale: scale factors must be nonzero") << scale;
    }
  }
}

// Mesh files referenced by a scene, relative to the scene's folder, with a transform; the loaded
// triangles render as a diffuse floor under a uniform sky (rho * L).
TEST(SceneLoader, ObjAndPlyMeshesThroughTheScene) {
  TempDir dir;
  std::filesystem::create_directories(dir.path() / "meshes");
  std::ofstream(dir.path() / "meshes/quad.obj") << "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 4 3 2\n";
  std::ofstream(dir.path() / "meshes/quad.ply") << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                                                   "property float y\nproperty float z\nelement face 1\n"
                                                   "property list uchar int vertex_indices\nend_header\n"
                                                   "-1 0 -1\n1 0 -1\n1 0 1\n-1 0 1\n4 0 3 2 1\n";
  const std::string json = R"({
    "camera": {"position": [0, 3, 0.01], "look_at": [0, 0, 0], "fov": 20, "resolution": [8, 8]},
    "render": {"max_depth": 3},
    "materials": {"m": {"type": "diffuse", "albedo": 0.4}},
    "shapes": [{"type": "mesh", "file": "meshes/quad.obj", "material": "m", "transform": {"scale": 4}},
               {"type": "mesh", "file": "meshes/quad.ply", "material": "m", "transform": {"translate": [0, -1, 0], "scale": 10}}],
    "lights": [{"type": "environment", "radiance": 2}]})";
  std::ofstream(dir.path() / "scene.json") << json;
  auto scene = load_scene_file(dir.path() / "scene.json");
  EXPECT_EQ(scene->triangle_count(), 4u);
  const auto* obj = dynamic_cast<const TriangleMesh*>(scene->shapes.at(0).get());
  ASSERT_NE(obj, nullptr);
  bool found = false;  // the corner (1, 0, 1) scaled by 4, wherever the reader put it
  for (size_t i = 0; i < obj->vertex_count(); ++i) found |= obj->position(static_cast<uint32_t>(i)) == Vec3(4, 0, 4);
  EXPECT_TRUE(found);
  // Both files' faces are counter-clockwise seen from +y: the upper quad is front-facing.
  SurfaceInteraction si;
  ASSERT_TRUE(scene->intersect(Ray{Vec3(0.3f, 5.0f, 0.2f), Vec3(0, -1, 0), kInfinity}, si));
  EXPECT_TRUE(si.front_face);
  EXPECT_EQ(si.ng, Vec3(0, 1, 0));
  const TestRender t = render_json(json, 4, 0, 0, dir.path());
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) EXPECT_NEAR(t.film.mean(x, y).g, 0.8f, 1e-5f);
}

// The diffuse material's `model` and the keys each model reads; defaults where a key is omitted.
TEST(SceneLoader, DiffuseModelsParse) {
  const std::string json = scene_with(R"("lambert": {"type": "diffuse", "albedo": 0.3},
      "cod": {"type": "diffuse", "model": "cod-multiscatter", "albedo": [0.2, 0.4, 0.6], "gloss": 0.3},
      "cod_default": {"type": "diffuse", "model": "cod-multiscatter"},
      "cod_rough": {"type": "diffuse", "model": "cod-multiscatter", "roughness": 1},
      "shirley": {"type": "diffuse", "model": "shirley", "f0": 0.1},
      "shirley_default": {"type": "diffuse", "model": "shirley"})",
                                      R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "cod"})");
  auto scene = load_scene_text(json, "scene.json", ".");
  const auto params = [&](const std::string& name) {
    for (const auto& m : scene->materials)
      if (m->name == name) {
        const auto* d = dynamic_cast<const DiffuseMaterial*>(m.get());
        if (d) return d->params();
      }
    ADD_FAILURE() << "no diffuse material " << name;
    return DiffuseParams{};
  };
  EXPECT_EQ(params("lambert").model, DiffuseModel::Lambert);
  EXPECT_EQ(params("lambert").albedo, Rgb(0.3f));
  EXPECT_EQ(params("cod").model, DiffuseModel::CodMultiscatter);
  EXPECT_EQ(params("cod").albedo, Rgb(0.2f, 0.4f, 0.6f));
  EXPECT_FLOAT_EQ(params("cod").gloss, 0.3f);
  EXPECT_FLOAT_EQ(params("cod_default").gloss, 0.5f);
  EXPECT_EQ(params("cod_default").albedo, Rgb(0.5f));
  // roughness 1 -> alpha 1 -> gloss 0 (Chan 2018 eq. (2) inverted).
  EXPECT_NEAR(params("cod_rough").gloss, 0.0f, 1e-6f);
  EXPECT_EQ(params("shirley").model, DiffuseModel::Shirley);
  EXPECT_FLOAT_EQ(params("shirley").f0, 0.1f);
  EXPECT_FLOAT_EQ(params("shirley_default").f0, 0.04f);
}

TEST(SceneLoader, DemoSceneLoads) {
  auto scene = load_demo_scene();
  EXPECT_GT(scene->shapes.size(), 5u);
  EXPECT_GT(scene->lights.size(), 1u);
}

}  // namespace
}  // namespace kozu::test
