// The first-hit features the denoiser and the AOVs take (PathIntegrator::li_features): through a perfect mirror
// they are those of what the mirror shows (albedo times the mirror's reflectance, that surface's normal), with
// the depth of the mirror itself; a rough metal keeps its own. The visible emission (the sample's light from
// emitters seen directly or through perfectly specular vertices, which the denoiser re-estimates) is part of the
// sample, and PathIntegrator::visible_emission reproduces it from the same sampler stream.
#include "support/bsdf_test.h"
#include "support/render_test.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

// The features of the camera ray from (0, 0, 5) down -z, sample `sample` of pixel (0, 0).
PixelFeatures features_of(const Scene& scene, int sample = 0) {
  const PathIntegrator integrator(scene, 5);
  Sampler sampler(1);
  sampler.start(0, 0, sample);
  Arena arena;
  RayCounters counters;
  StopFlag stop(false);
  PixelFeatures f;
  integrator.li_features(Ray{Vec3(0, 0, 5), Vec3(0, 0, -1), kInfinity}, sampler, arena, counters, stop, f);
  return f;
}

// A unit ball of the given material at the origin, a red wall behind it.
std::unique_ptr<Scene> ball_scene(const std::string& sphere_material) {
  return load_scene_text(fmt::format(R"({{
  "camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [8, 8]}},
  "materials": {{"ball": {}, "red": {{"type": "diffuse", "albedo": [0.8, 0.1, 0.1]}}}},
  "shapes": [
    {{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "ball"}},
    {{"type": "quad", "material": "red", "vertices": [[-9, -9, 8], [-9, 9, 8], [9, 9, 8], [9, -9, 8]]}}
  ],
  "lights": [{{"type": "point", "position": [0, 3, 4], "intensity": 10}}]
}})",
                                     sphere_material),
                         "features.json", ".");
}

PixelFeatures features_through(const std::string& sphere_material) { return features_of(*ball_scene(sphere_material)); }

TEST(PathFeatures, PassThroughAPerfectMirror) {
  const PixelFeatures f = features_through(R"({"type": "conductor", "metal": "Ag"})");
  ASSERT_TRUE(f.set);
  // Silver reflects ~95 % at normal incidence: the red wall's albedo, a little darker.
  EXPECT_GT(f.albedo.r, 0.6f);
  EXPECT_LE(f.albedo.r, 0.8f);
  EXPECT_LT(f.albedo.g, 0.1f);
  EXPECT_GT(f.albedo.g, 0.05f);
  EXPECT_NEAR(f.normal.z, -1.0f, 1e-4f);  // the wall, facing the reflected ray
  EXPECT_NEAR(f.depth, 4.0f, 1e-4f);      // the mirror's own depth
  EXPECT_NEAR(f.position.z, 1.0f, 1e-4f);
}

TEST(PathFeatures, StayOnARoughSurface) {
  for (const char* m :
       {R"({"type": "conductor", "metal": "Ag", "roughness": 0.4})", R"({"type": "diffuse", "albedo": 0.5})"}) {
    const PixelFeatures f = features_through(m);
    ASSERT_TRUE(f.set) << m;
    EXPECT_NEAR(f.normal.z, 1.0f, 1e-4f) << m;  // the sphere's own normal
    EXPECT_NEAR(f.depth, 4.0f, 1e-4f) << m;
  }
}

// A subsurface object reports its profile's albedo A, the same for every sample: the sample's own weight (a
// reflection or a transmission through the boundary) is about 1 whichever lobe it took, colourless, and two-valued
// from sample to sample, which left the demo's jade speckled by the denoiser. The control: a rough dielectric (the
// same boundary without the subsurface) still reports its sample's weight.
TEST(PathFeatures, ASubsurfaceObjectReportsItsProfileAlbedo) {
  for (const char* boundary : {"", R"(, "roughness": 0.25)"}) {
    const std::string material =
        fmt::format(R"({{"type": "subsurface", "albedo": [0.3, 0.72, 0.42], "mfp": [0.02, 0.06, 0.035],
                        "ior": 1.6{}}})",
                    boundary);
    const auto scene = ball_scene(material);
    for (int s = 0; s < 64; ++s) {
      const PixelFeatures f = features_of(*scene, s);
      ASSERT_TRUE(f.set) << material;
      EXPECT_NEAR(f.albedo.r, 0.3f, 1e-5f) << material << " sample " << s;
      EXPECT_NEAR(f.albedo.g, 0.72f, 1e-5f) << material << " sample " << s;
      EXPECT_NEAR(f.albedo.b, 0.42f, 1e-5f) << material << " sample " << s;
      EXPECT_NEAR(f.normal.z, 1.0f, 1e-4f) << material;
      EXPECT_NEAR(f.depth, 4.0f, 1e-4f) << material;
    }
  }
  // The control: without the subsurface, the boundary's own sample weight, colourless.
  const PixelFeatures glass = features_through(R"({"type": "dielectric", "ior": 1.6, "roughness": 0.25})");
  ASSERT_TRUE(glass.set);
  EXPECT_GT(glass.albedo.r, 0.0f);
  EXPECT_NEAR(glass.albedo.r, glass.albedo.g, 1e-5f);
  EXPECT_NEAR(glass.albedo.g, glass.albedo.b, 1e-5f);
}

// A surface whose BSDF has LTC lobes reports its directional albedo, the sum of their weights (each lobe weighted by
// the exact albedo of its part: LtcLobes.EnergyMatchesTheAlbedo), the same for every sample. One sample's weight, the
// feature before, varies with the lobe it took (the plastic's coat or base, the standard's metal or specular) and its
// direction: noise the denoisers had to see through.
TEST(PathFeatures, AGlossySurfaceReportsItsDirectionalAlbedo) {
  for (const char* body : {R"("type": "plastic", "albedo": [0.6, 0.3, 0.2], "roughness": 0.3)",
                           R"("type": "conductor", "metal": "Au", "roughness": 0.4)",
                           R"("type": "standard", "base_color": [0.2, 0.5, 0.7], "metallic": 0.5, "roughness": 0.35,
                               "clearcoat": 1)"}) {
    // The lobes at normal incidence, where the camera ray meets the ball (the albedo does not depend on azimuth).
    const auto material = material_from_json(body);
    Arena arena;
    const std::optional<Rgb> lobes_albedo = material->bsdf(hit_at_uv(0.5f, 0.5f), arena)->ltc_albedo(Vec3(0, 0, 1));
    ASSERT_TRUE(lobes_albedo) << body;
    const Rgb albedo = *lobes_albedo;
    const auto scene = ball_scene(fmt::format("{{{}}}", body));
    for (int s = 0; s < 32; ++s) {
      const PixelFeatures f = features_of(*scene, s);
      ASSERT_TRUE(f.set) << body;
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(f.albedo[c], albedo[c], 1e-4f * albedo[c]) << body << " sample " << s;
      EXPECT_NEAR(f.normal.z, 1.0f, 1e-4f) << body;
    }
  }
}

// A camera ray that scatters first inside a medium reports the medium's single-scattering albedo and the axis of its
// scatterers at half length (an SGGX fiber's tangent, either sign given: largest component positive; none for
// Henyey–Greenstein), at the scattering point: the features that let the denoiser tell a fabric's threads apart.
TEST(PathFeatures, AMediumReportsItsAlbedoAndItsFibersTangent) {
  const auto features_in = [](const char* medium) {
    const auto scene = load_scene_text(fmt::format(R"({{
  "camera": {{"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [8, 8]}},
  "media": {{"m": {}}},
  "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "m"}}],
  "lights": [{{"type": "point", "position": [0, 3, 4], "intensity": 10}}]
}})",
                                                   medium),
                                       "medium_features.json", ".");
    return features_of(*scene);
  };
  // Density 400: the ray scatters within a few hundredths of the sphere's surface.
  const PixelFeatures fiber = features_in(R"({"type": "sggx", "density": 400, "albedo": [0.6, 0.4, 0.2],
      "phase": "specular", "distribution": {"kind": "fiber", "tangent": [-1, -2, 0], "roughness": 0.2}})");
  ASSERT_TRUE(fiber.set);
  EXPECT_NEAR(fiber.albedo.r, 0.6f, 1e-5f);
  EXPECT_NEAR(fiber.albedo.g, 0.4f, 1e-5f);
  EXPECT_NEAR(fiber.albedo.b, 0.2f, 1e-5f);
  EXPECT_NEAR(fiber.normal.x, 0.5f / std::sqrt(5.0f), 1e-4f);
  EXPECT_NEAR(fiber.normal.y, 1.0f / std::sqrt(5.0f), 1e-4f);
  EXPECT_NEAR(fiber.normal.z, 0.0f, 1e-4f);
  EXPECT_GT(fiber.position.z, 0.9f);
  EXPECT_LT(fiber.position.z, 1.0f);
  const PixelFeatures fog = features_in(R"({"type": "homogeneous", "density": 400, "albedo": 0.7})");
  ASSERT_TRUE(fog.set);
  EXPECT_NEAR(fog.albedo.g, 0.7f, 1e-5f);
  EXPECT_EQ(fog.normal, Vec3(0.0f));
}

// Camera rays over a scene where the camera sees an emitter directly, in a mirror, through smooth glass and not at
// all (a diffuse floor it lights): for each sample, visible_emission (the refinement's cheap path) gives exactly the
// emission li_features recorded, which is at most the sample's radiance, and nonzero only where a chain of perfectly
// specular vertices reached an emitter.
TEST(PathFeatures, VisibleEmissionIsReproducedFromTheSameStream) {
  const auto scene = load_scene_text(R"({
  "camera": {"position": [0, 1, 6], "look_at": [0, 0.8, 0], "fov": 50, "resolution": [24, 16]},
  "materials": {
    "mirror": {"type": "conductor", "metal": "Ag"},
    "glass": {"type": "dielectric", "ior": 1.5},
    "floor": {"type": "diffuse", "albedo": 0.6},
    "grey": {"type": "diffuse", "albedo": 0.5}
  },
  "shapes": [
    {"type": "quad", "material": "floor", "vertices": [[-9, 0, 9], [9, 0, 9], [9, 0, -9], [-9, 0, -9]]},
    {"type": "sphere", "center": [-1.2, 0.8, 0], "radius": 0.8, "material": "mirror"},
    {"type": "sphere", "center": [1.2, 0.8, 0], "radius": 0.8, "material": "glass"},
    {"type": "quad", "material": "grey", "emission": [4, 3, 2],
     "vertices": [[-3, 1.7, -2], [3, 1.7, -2], [3, 3.7, -2], [-3, 3.7, -2]]}
  ]
})",
                                     "visible.json", ".");
  const PathIntegrator integrator(*scene, 8);
  const PixelFilter filter(PixelFilter::Type::Gaussian);
  Sampler a(3), b(3);
  Arena arena;
  RayCounters counters;
  StopFlag stop(false);
  int with_emission = 0, mixed = 0, floor_lit = 0;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 24; ++x)
      for (int s = 0; s < 8; ++s) {
        PixelFeatures f;
        const Rgb L = integrator.li_features(camera_sample(*scene, filter, a, x, y, s), a, arena, counters, stop, f);
        arena.reset();
        const Rgb e = integrator.visible_emission(camera_sample(*scene, filter, b, x, y, s), b, arena, counters, stop);
        arena.reset();
        ASSERT_EQ(e.r, f.emission.r) << x << "," << y << " sample " << s;
        ASSERT_EQ(e.g, f.emission.g);
        ASSERT_EQ(e.b, f.emission.b);
        for (int c = 0; c < 3; ++c) ASSERT_LE(f.emission[c], L[c] * (1.0f + 1e-5f) + 1e-6f);
        with_emission += !is_black(f.emission);
        mixed += !is_black(f.emission) && luminance(L) > luminance(f.emission) * 1.001f;
        // The floor seen directly: lit, but by light sampling and sampled bounces, none of it visible emission.
        floor_lit += is_black(f.emission) && luminance(L) > 0.01f;
      }
  // Each case occurs: the emitter seen (directly, in the mirror, through the glass), samples that hold both kinds
  // of light (the emitter, grey, also reflects the light the floor sends back), and the lit floor alone.
  EXPECT_GT(with_emission, 300);
  EXPECT_GT(mixed, 50);
  EXPECT_GT(floor_lit, 500);
}

}  // namespace
}  // namespace kozu::test
