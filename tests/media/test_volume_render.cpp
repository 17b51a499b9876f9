// Volumetric path tracing (integrators/path.cpp with media/): image-level checks against closed forms.
//  - White furnace: a sphere of albedo-1 medium behind an index-matched boundary, in a uniform environment
//    of radiance 1, renders 1 in every pixel (isotropic with spectrally varying density, Henyey–Greenstein
//    forward and backward), with the camera outside and inside the medium.
//  - Beer–Lambert: a purely absorbing sphere with density (σr, σg, σb) seen against the environment shows
//    exp(−σ · chord) per channel, the chord 2 sqrt(R² − b²) at impact parameter b.
#include "support/render_test.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace kozu::test {
namespace {

constexpr int kSize = 48;

std::string scene(const std::string& medium, const std::string& camera_extra = "") {
  return fmt::format(R"({{
    "camera": {{"type": "perspective", "position": [0, 0, 10], "look_at": [0, 0, 0], "fov": 6.5,
               "resolution": [{0}, {0}] {2}}},
    "render": {{"max_depth": 1024, "filter": "box"}},
    "media": {{"m": {1}}},
    "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 0.5, "interior": "m"}}],
    "lights": [{{"type": "environment", "radiance": [1, 1, 1]}}]
  }})",
                     kSize, medium, camera_extra);
}

// Mean over the pixels whose centre sees the sphere at impact parameter b/R in [lo, hi).
struct Ring {
  Rgb mean{0.0f}, err{0.0f};
  double b_mean = 0;
  int pixels = 0;
};
Ring ring(const TestRender& r, double lo, double hi) {
  const double radius_px = 0.5 / std::sqrt(100.0 - 0.25) / std::tan(3.25 * kPi / 180.0) * kSize * 0.5;
  Ring out;
  Rgb var(0.0f);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const double dx = (x + 0.5 - kSize * 0.5) / radius_px, dy = (y + 0.5 - kSize * 0.5) / radius_px;
      const double b = std::sqrt(dx * dx + dy * dy);
      if (b < lo || b >= hi) continue;
      out.mean += r.film.mean(x, y);
      var += r.film.variance_of_mean(x, y);
      out.b_mean += b;
      ++out.pixels;
    }
  out.mean /= float(out.pixels);
  out.err = sqrt(var) / float(out.pixels);
  out.b_mean /= out.pixels;
  return out;
}

TEST(VolumeFurnace, AlbedoOneRendersOne) {
  const char* media[] = {
      R"({"type": "homogeneous", "density": [1, 3, 8], "albedo": 1})",
      R"({"type": "homogeneous", "density": 5, "albedo": 1, "phase": {"type": "hg", "g": 0.8}})",
      R"({"type": "homogeneous", "density": 5, "albedo": 1, "phase": {"type": "hg", "g": -0.6}})",
      R"({"type": "sggx", "density": 6, "albedo": 1, "phase": "specular",
          "distribution": {"kind": "surface", "normal": [0.3, 0.8, 0.5], "roughness": 0.2}})",
      R"({"type": "sggx", "density": 6, "albedo": 1, "phase": "diffuse",
          "distribution": {"kind": "surface", "normal": [0.3, 0.8, 0.5], "roughness": 0.2}})",
      R"({"type": "sggx", "density": 6, "albedo": 1, "phase": "specular",
          "distribution": {"kind": "fiber", "tangent": [1, 1, 0], "roughness": 0.3}})",
      R"({"type": "sggx", "density": 6, "albedo": 1, "phase": "diffuse",
          "distribution": {"S": [1.0, 0.5, 0.2, 0.1, -0.05, 0.08]}})",
  };
  for (const char* m : media) {
    const TestRender r = render_json(scene(m), 64, 0, 5);
    const Ring s = ring(r, 0.0, 0.97);  // the sphere's pixels only (the background is exactly 1)
    fmt::print("{}: {:.4f} {:.4f} {:.4f} +- {:.4f}\n", m, s.mean.r, s.mean.g, s.mean.b, s.err.g);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.mean[c], 1.0, 5 * s.err[c] + 1e-4) << m << " channel " << c;
  }
}

TEST(VolumeFurnace, CameraInsideTheMedium) {
  // The camera at z = 10 inside a medium sphere of radius 20 that holds the small sphere too.
  const std::string json = fmt::format(R"({{
    "camera": {{"type": "perspective", "position": [0, 0, 10], "look_at": [0, 0, 0], "fov": 20,
               "resolution": [24, 24], "medium": "fog"}},
    "render": {{"max_depth": 1024}},
    "media": {{"fog": {{"type": "homogeneous", "density": [0.05, 0.1, 0.2], "albedo": 1,
                        "phase": {{"type": "hg", "g": 0.4}}}}}},
    "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 20, "interior": "fog"}}],
    "lights": [{{"type": "environment", "radiance": [1, 1, 1]}}]
  }})");
  const TestRender r = render_json(json, 64, 0, 6);
  const ImageStats s = image_stats(r.film);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.mean[c], 1.0, 5 * s.standard_error[c] + 1e-4) << "channel " << c;
}

TEST(BeerLambert, AbsorbingSphere) {
  const Rgb sigma(0.5f, 1.0f, 2.0f);
  const TestRender r = render_json(scene(R"({"type": "homogeneous", "density": [0.5, 1, 2], "albedo": 0})"), 64, 0, 7);
  for (double lo : {0.0, 0.3, 0.6, 0.85}) {
    const Ring g = ring(r, lo, lo + 0.1);
    for (int c = 0; c < 3; ++c) {
      // Average the closed form over the ring's pixels through b_mean: the rings are narrow (0.1 R), so the
      // curvature of exp(−σ·chord) across one ring stays below the tolerance's 2e-3.
      const double chord = 2.0 * 0.5 * std::sqrt(1.0 - g.b_mean * g.b_mean);
      const double expect = std::exp(-sigma[c] * chord);
      EXPECT_NEAR(g.mean[c], expect, 5 * g.err[c] + 2e-3) << "b " << g.b_mean << " channel " << c;
    }
  }
}

// An absorbing fiber-like SGGX medium (tangent z, σ = 0.2) seen along different axes transmits
// exp(−ρ σ(ω) d) (eqs. 2 and 11): the image covers only the sphere's centre (chord 2R to 2e-5).
TEST(BeerLambert, SggxDependsOnTheViewDirection) {
  const float rho = 1.5f;
  for (const Vec3& dir : {Vec3(0, 0, 1), Vec3(1, 0, 0), Vec3(0, 1, 0.001f), Vec3(1, 1, 1), Vec3(0.2f, -0.5f, 1)}) {
    const Vec3 w = glm::normalize(dir);
    const Vec3 eye = 10.0f * w;
    const std::string json = fmt::format(R"({{
      "camera": {{"type": "perspective", "position": [{}, {}, {}], "look_at": [0, 0, 0], "fov": 0.05,
                 "resolution": [4, 4]}},
      "render": {{"max_depth": 8}},
      "media": {{"m": {{"type": "sggx", "density": {}, "albedo": 0,
                        "distribution": {{"kind": "fiber", "tangent": [0, 0, 1], "roughness": 0.2}}}}}},
      "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 0.5, "interior": "m"}}],
      "lights": [{{"type": "environment", "radiance": [1, 1, 1]}}]
    }})",
                                         eye.x, eye.y, eye.z, rho);
    const TestRender r = render_json(json, 2048, 0, 8);
    const ImageStats s = image_stats(r.film);
    // σ(ω) of the fiber distribution with tangent z (eqs. 15–16): S = diag(1, 1, σ²).
    const double sigma = std::sqrt(w.x * w.x + w.y * w.y + 0.04 * w.z * w.z);
    const double expect = std::exp(-rho * sigma * 1.0);
    fmt::print("view ({:.3f}, {:.3f}, {:.3f}): T = {:.4f} +- {:.4f}, exp(-rho sigma d) = {:.4f}\n", w.x, w.y, w.z,
               s.mean.g, s.standard_error.g, expect);
    EXPECT_NEAR(s.mean.g, expect, 4 * s.standard_error.g + 1e-3) << "view along " << w.x << " " << w.y << " " << w.z;
  }
}

}  // namespace
}  // namespace kozu::test
