// environment: radiance arriving from infinitely far away, either uniform or from a lat-long image.
//
// Parameters
//   radiance  rgb     -    uniform radiance (exclusive with file)
//   file      path    -    lat-long (equirectangular) image (EXR/HDR/PNG/...)
//   colorspace string "auto" "auto" (integer images are sRGB-decoded, float images linear), "srgb" or "linear"
//   scale     float   1    multiplies the radiance, >= 0
//   rotate    float   0    degrees about the +y axis, right-handed as a shape's rotate (turns the image around
//                           the scene: what the unturned image shows towards d is shown towards R_y(rotate) d)
//   mis_compensation bool true  sample the image by its importance less its mean (Karlík, Šik, Vévoda, Skřivan and
//                           Křivánek 2019, "MIS Compensation"): light samples only where the map is brighter than its
//                           mean, BSDF samples (always taken beside them, under MIS) for the rest
//   portals   array   []   up to 16 rectangles {"vertices": [4 corners]}, in a quad light's order, front towards the
//                           scene: the openings (windows) through which the environment lights an interior
//                           (lights/environment_portal.h)
//
// Mapping (+y up): u = 1/2 + atan2(x, -z) / (2 pi), v = acos(y) / pi, so the image centre is the
// -z direction and the top row is the zenith. The image is importance-sampled with a piecewise-
// constant 2D distribution of luminance (less its mean, compensated) * sin(theta) (the Jacobian of the lat-long map),
// pdf(omega) = pdf(u, v) / (2 pi^2 sin theta). The uniform case samples the cosine-weighted
// hemisphere around the shading normal when one is known (exact for an unoccluded Lambertian
// surface) and the whole sphere otherwise.
// With portals, a point on the scene's side of at least one portal samples through them instead (Bitterli, Novák
// and Jarosz 2015, lights/environment_portal.h): a portal chosen in proportion to the radiance it lets through, then
// a direction through it in proportion to the radiance; pdf(ω) = Σ_k P(k) pdf_k(ω). Directions that miss every
// portal have light-sampling density 0 there, so a BSDF ray that escapes past the portals (another opening) keeps its
// full MIS weight: unbiased whatever the portals cover; they only have to cover the openings to lower the variance.
#pragma once

#include "core/distribution.h"
#include "core/registry.h"
#include "lights/environment_portal.h"
#include "lights/light.h"

#include <array>
#include <filesystem>
#include <vector>

namespace kozu {

class EnvironmentLight final : public Light {
 public:
  explicit EnvironmentLight(const Rgb& radiance);
  // Image of width x height linear RGB pixels, row 0 at the zenith; compensate: sample by the importance less its
  // mean (MIS compensation, above).
  EnvironmentLight(std::vector<Rgb> pixels, int width, int height, float scale, float rotate_degrees,
                   bool compensate = true);
  // From the scene's description; an image file is read by the returned job (core/registry.h).
  static Deferred<Light> parse(const JsonObject& desc);

  LightSample sample(const LightSampleContext& ctx, const Vec2& u) const override;
  Rgb power() const override;
  // Infinite: the irradiance it gives a surface open to the whole sky, π L̄.
  LightBounds bounds() const override {
    LightBounds b;
    b.infinite = true;
    b.phi = kPi * average(mean_radiance_);
    return b;
  }
  void preprocess(const Vec3& center, float radius) override;
  // Radiance arriving from hit.wi (pointing away from the scene).
  Rgb eval(const LightHit& hit) const override;
  float pdf(const LightSampleContext& ctx, const LightHit& hit) const override;
  Rgb eval_pdf(const LightSampleContext& ctx, const LightHit& hit, float* pdf) const override;
  bool is_infinite() const override { return true; }

  bool is_uniform() const { return pixels_.empty(); }
  // Whether sample() draws from the compensated importance (false for a uniform sky or a map without contrast).
  bool compensated() const { return compensated_; }

  static constexpr size_t kMaxPortals = 16;
  // Builds the portals' tables (each a rectangle given as a quad light's corners, front towards the scene; the
  // scene key's parser checks them). Replaces any portals given before.
  void set_portals(const std::vector<std::array<Vec3, 4>>& corners);
  size_t portal_count() const { return portals_.size(); }

 private:
  // What a point sees through the portals: each portal's view and the radiance it lets through.
  struct PortalViews {
    std::array<EnvironmentPortal::View, kMaxPortals> view;
    std::array<double, kMaxPortals> flux{};
    double total = 0;
  };
  // False where the point sees no portal (from outside, or every window black): the map's sampling then.
  bool portal_views(const Vec3& p, PortalViews* pv) const;
  float portal_pdf(const PortalViews& pv, const Vec3& dir) const;

  Vec2 dir_to_uv(const Vec3& d) const;
  Rgb lookup(const Vec2& uv) const;  // bilinear
  // The solid-angle density of sample() towards d, whose map coordinates are uv.
  float density(const Vec2& uv, const Vec3& d) const;

  // A pixel: its radiance, and the density over the map (u, v) with which sample() draws the points of its cell
  // (Distribution2D::pdf there). Beside the radiance so that a BSDF ray that escapes reads both from the lines its
  // bilinear lookup brings into the cache, instead of a second random access to the distribution.
  struct Texel {
    Rgb radiance;
    float density;
  };

  Rgb uniform_{0.0f};
  std::vector<Texel> pixels_;
  int width_ = 0, height_ = 0;
  float rotate_ = 0;  // radians
  Distribution2D distribution_;
  Rgb mean_radiance_{0.0f};  // (1 / 4 pi) * integral of L over the sphere
  bool compensated_ = false;
  float scene_radius_ = 1;
  std::vector<EnvironmentPortal> portals_;
};

}  // namespace kozu
