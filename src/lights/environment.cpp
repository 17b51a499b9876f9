#include "lights/environment.h"

#include "core/error.h"
#include "core/frame.h"
#include "core/input_bounds.h"
#include "core/warp.h"
#include "io/image_io.h"
#include "lights/light_power.h"

namespace kozu {

EnvironmentLight::EnvironmentLight(const Rgb& radiance) : uniform_(radiance), mean_radiance_(radiance) {}

EnvironmentLight::EnvironmentLight(std::vector<Rgb> pixels, int width, int height, float scale, float rotate_degrees,
                                   bool compensate)
    : width_(width), height_(height), rotate_(glm::radians(rotate_degrees)) {
  // The pixels move into their texels first and their own buffer is freed, so that at most the texels, the
  // importance and the distribution are held at once (an 8k map's peak stays what it was with 12-byte pixels).
  pixels_.resize(pixels.size());
  std::vector<float> func(static_cast<size_t>(width) * height);
  double total[3] = {0, 0, 0};
  for (int y = 0; y < height; ++y) {
    const float sin_t = std::sin(kPi * (y + 0.5f) / height);
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(y) * width + x;
      Rgb c = glm::max(pixels[i] * scale, Rgb(0.0f));
      if (!is_finite(c)) c = Rgb(0.0f);
      pixels_[i].radiance = c;
      func[i] = luminance(c);
      for (int k = 0; k < 3; ++k) total[k] += static_cast<double>(c[k]) * sin_t;
    }
  }
  std::vector<Rgb>().swap(pixels);
  // Importance of a cell: the mean of the bilinear radiance lookup() returns over it, which reaches half-way into
  // the neighbouring pixels: weights 1/8, 3/4, 1/8 along each axis (wrapping in u, clamped in v, as lookup does).
  // The cell's own pixel alone under-weights the cells beside a small bright sun, whose lookups borrow up to half
  // its radiance: BSDF samples that hit them then carry the sun at a tiny light-sampling density (fireflies: a
  // diffuse plane under a 4-degree sun of radiance 1500 had pixels 30x its median at 16 spp). Uncompensated, a floor
  // keeps every density positive. Separable, in place, with one row or column of scratch (the image may be large).
  std::vector<float> line(static_cast<size_t>(std::max(width, height)));
  const auto at = [&](int x, int y) -> float& { return func[static_cast<size_t>(y) * width + x]; };
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) line[x] = at(x, y);
    for (int x = 0; x < width; ++x)
      at(x, y) = 0.125f * line[(x + width - 1) % width] + 0.75f * line[x] + 0.125f * line[(x + 1) % width];
  }
  for (int x = 0; x < width; ++x) {
    for (int y = 0; y < height; ++y) line[y] = at(x, y);
    for (int y = 0; y < height; ++y)
      at(x, y) = 0.125f * line[std::max(y - 1, 0)] + 0.75f * line[y] + 0.125f * line[std::min(y + 1, height - 1)];
  }
  // MIS compensation (Karlík et al. 2019, with α = 1): the importance less its mean over the sphere, clamped
  // at 0. Light samples then go only where the map is brighter than its mean; the rest, which BSDF sampling finds as
  // well, is left to it (every vertex that samples a light also samples its BSDF, whose density covers the
  // hemisphere, and a direction of density 0 here keeps the BSDF sample's full weight). A map without contrast keeps
  // its importance (nothing would be left).
  std::vector<float> sines(static_cast<size_t>(height));
  for (int y = 0; y < height; ++y) sines[y] = std::sin(kPi * (y + 0.5f) / height);
  float floor = 1e-6f;
  if (compensate) {
    double sum = 0.0, weight = 0.0;
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) sum += static_cast<double>(at(x, y)) * sines[y];
      weight += static_cast<double>(sines[y]) * width;
    }
    const float mean = static_cast<float>(sum / weight);
    double kept = 0.0;
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) kept += std::max(at(x, y) - mean, 0.0f) * static_cast<double>(sines[y]);
    if (kept > 1e-6 * sum) {
      for (float& f : func) f = std::max(f - mean, 0.0f);
      floor = 0.0f;
      compensated_ = true;
    }
  }
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) at(x, y) = (at(x, y) + floor) * sines[y];
  // Mean over the sphere: sum L sin(theta) dtheta dphi / 4 pi with dtheta dphi = 2 pi^2 / (w h).
  const double norm = 2.0 * kPi * kPi / (static_cast<double>(width) * height) / (4.0 * kPi);
  mean_radiance_ = Rgb(total[0] * norm, total[1] * norm, total[2] * norm);
  distribution_ = Distribution2D(func, width, height);
  std::vector<float>().swap(func);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      pixels_[static_cast<size_t>(y) * width + x].density =
          distribution_.pdf(Vec2((x + 0.5f) / width, (y + 0.5f) / height));
}

void EnvironmentLight::set_portals(const std::vector<std::array<Vec3, 4>>& corners) {
  portals_.clear();
  // The rectified table's cells about a texel wide at the portal's centre (π / n against the map's 2π / width), at
  // most 1024 x 1024 (12 MB); a uniform sky's table only carries the Jacobian.
  const int resolution = pixels_.empty() ? 128 : std::clamp(width_, 64, 1024);
  const auto luminance_from = [this](const Vec3& d) { return luminance(eval(LightHit{d})); };
  for (const auto& c : corners) portals_.emplace_back(c, luminance_from, resolution);
}

bool EnvironmentLight::portal_views(const Vec3& p, PortalViews* pv) const {
  pv->total = 0;
  for (size_t k = 0; k < portals_.size(); ++k) {
    pv->view[k] = portals_[k].view(p);
    pv->flux[k] = pv->view[k].empty() ? 0.0 : portals_[k].flux(pv->view[k]);
    pv->total += pv->flux[k];
  }
  return pv->total > 0.0;
}

float EnvironmentLight::portal_pdf(const PortalViews& pv, const Vec3& dir) const {
  double pdf = 0;
  for (size_t k = 0; k < portals_.size(); ++k)
    if (pv.flux[k] > 0.0) pdf += pv.flux[k] / pv.total * portals_[k].pdf(pv.view[k], dir);
  return static_cast<float>(pdf);
}

void EnvironmentLight::preprocess(const Vec3&, float radius) { scene_radius_ = std::max(radius, 1e-3f); }

Rgb EnvironmentLight::power() const {
  // Power through the scene's bounding disk: pi R^2 * integral of L over the sphere.
  return mean_radiance_ * (4.0f * kPi * kPi * scene_radius_ * scene_radius_);
}

Vec2 EnvironmentLight::dir_to_uv(const Vec3& d) const {
  // The image turned by rotate_ about +y, right-handed like a shape's "rotate": look up R_y(-rotate_) d.
  // fast_atan2 and fast_acos (core/math.h): std::atan2f and std::acosf were a quarter of a lookup.
  float phi = fast_atan2(d.x, -d.z) + rotate_;
  phi = phi - kTwoPi * std::floor(phi * kInv2Pi + 0.5f);  // wrap to [-pi, pi)
  return Vec2(std::clamp(0.5f + phi * kInv2Pi, 0.0f, kOneMinusEpsilon),
              std::clamp(fast_acos(d.y) * kInvPi, 0.0f, 1.0f));
}

Rgb EnvironmentLight::lookup(const Vec2& uv) const {
  // Bilinear, wrapping in u and clamping in v. For uv in [0, 1]² the columns are at most one step outside the image:
  // a compare wraps them (the integer modulo, eight per lookup, took a tenth of an environment-lit render); the modulo
  // is left for what lies farther out.
  const float x = uv.x * width_ - 0.5f, y = uv.y * height_ - 0.5f;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float fx = x - x0, fy = y - y0;
  const auto wrap = [w = width_](int xi) {
    if (xi < 0)
      xi += w;
    else if (xi >= w)
      xi -= w;
    return xi >= 0 && xi < w ? xi : ((xi % w) + w) % w;
  };
  const int xa = wrap(x0), xb = wrap(x0 + 1);
  const Texel* row0 = &pixels_[static_cast<size_t>(std::clamp(y0, 0, height_ - 1)) * width_];
  const Texel* row1 = &pixels_[static_cast<size_t>(std::clamp(y0 + 1, 0, height_ - 1)) * width_];
  return (1 - fy) * ((1 - fx) * row0[xa].radiance + fx * row0[xb].radiance) +
         fy * ((1 - fx) * row1[xa].radiance + fx * row1[xb].radiance);
}

// The lat-long Jacobian (environment.h): pdf(ω) = pdf(u, v) / (2 π² sin θ), sin θ from the direction itself (its y
// is cos θ).
float EnvironmentLight::density(const Vec2& uv, const Vec3& d) const {
  const float sin_t = std::sqrt(std::max(0.0f, 1.0f - d.y * d.y));
  if (sin_t <= 0.0f) return 0.0f;
  const int col = std::clamp(static_cast<int>(uv.x * width_), 0, width_ - 1);
  const int row = std::clamp(static_cast<int>(uv.y * height_), 0, height_ - 1);
  return pixels_[static_cast<size_t>(row) * width_ + col].density / (2.0f * kPi * kPi * sin_t);
}

Rgb EnvironmentLight::eval(const LightHit& hit) const {
  if (pixels_.empty()) return uniform_;
  return lookup(dir_to_uv(hit.wi));
}

LightSample EnvironmentLight::sample(const LightSampleContext& ctx, const Vec2& u) const {
  LightSample ls;
  ls.infinite = true;
  PortalViews pv;
  if (!portals_.empty() && portal_views(ctx.p, &pv)) {
    // A portal by the radiance it lets through (u.x reused within the chosen one's share), then a direction
    // through it.
    size_t k = 0;
    double target = static_cast<double>(u.x) * pv.total;
    while (k + 1 < portals_.size() && (pv.flux[k] <= 0.0 || target >= pv.flux[k])) target -= pv.flux[k++];
    const float ux = std::clamp(static_cast<float>(target / pv.flux[k]), 0.0f, kOneMinusEpsilon);
    float pdf_k = 0.0f;
    const Vec3 wi = portals_[k].sample(pv.view[k], Vec2(ux, u.y), &pdf_k);
    if (!(pdf_k > 0.0f)) return ls;
    ls.wi = wi;
    ls.pdf = portals_.size() == 1 ? pdf_k : portal_pdf(pv, wi);
    ls.radiance = eval(LightHit{wi});
    return ls;
  }
  if (pixels_.empty()) {
    if (glm::dot(ctx.n, ctx.n) > 0.0f) {
      const Vec3 local = warp::square_to_cosine_hemisphere(u);
      if (local.z <= 0.0f) return ls;
      ls.wi = Frame(ctx.n).to_world(local);
      ls.pdf = local.z * kInvPi;  // cos theta / pi (Malley's method, warp.h)
    } else {
      ls.wi = warp::square_to_uniform_sphere(u);
      ls.pdf = kInv4Pi;
    }
    ls.radiance = uniform_;
    return ls;
  }
  float pdf_uv;
  const Vec2 uv = distribution_.sample(u, &pdf_uv);
  // The inverse of dir_to_uv, sin θ shared with the Jacobian.
  const float phi = (uv.x - 0.5f) * kTwoPi - rotate_;
  const float theta = uv.y * kPi;
  const float sin_t = std::sin(theta), cos_t = std::cos(theta);
  if (pdf_uv <= 0.0f || sin_t <= 0.0f) return ls;
  ls.wi = Vec3(sin_t * std::sin(phi), cos_t, -sin_t * std::cos(phi));
  ls.pdf = pdf_uv / (2.0f * kPi * kPi * sin_t);  // environment.h: the lat-long Jacobian 2 pi^2 sin theta
  ls.radiance = lookup(uv);
  return ls;
}

float EnvironmentLight::pdf(const LightSampleContext& ctx, const LightHit& hit) const {
  const Vec3& dir = hit.wi;
  PortalViews pv;
  if (!portals_.empty() && portal_views(ctx.p, &pv)) return portal_pdf(pv, dir);
  if (pixels_.empty()) {
    if (glm::dot(ctx.n, ctx.n) > 0.0f) return std::max(0.0f, glm::dot(dir, ctx.n)) * kInvPi;
    return kInv4Pi;
  }
  return density(dir_to_uv(dir), dir);
}

Rgb EnvironmentLight::eval_pdf(const LightSampleContext& ctx, const LightHit& hit, float* pdf) const {
  if (!portals_.empty()) {
    *pdf = this->pdf(ctx, hit);
    return eval(hit);
  }
  if (pixels_.empty()) {
    *pdf = this->pdf(ctx, hit);
    return uniform_;
  }
  const Vec2 uv = dir_to_uv(hit.wi);
  const Rgb L = lookup(uv);
  *pdf = density(uv, hit.wi);
  return L;
}

namespace {

// The "portals" key: each a rectangle (four corners, a quad light's order), checked here so that the message names
// its JSON path.
std::vector<std::array<Vec3, 4>> parse_portals(const JsonObject& l) {
  std::vector<std::array<Vec3, 4>> portals;
  if (!l.has("portals")) return portals;
  const JsonArray list = l.get_array("portals");
  if (list.size() > EnvironmentLight::kMaxPortals)
    list.fail(fmt::format("at most {} portals, got {}", EnvironmentLight::kMaxPortals, list.size()));
  for (size_t i = 0; i < list.size(); ++i) {
    const JsonObject o = list.object(i);
    const JsonArray v = o.get_array("vertices");
    if (v.size() != 4) v.fail(fmt::format("a portal is a rectangle: 4 vertices, got {}", v.size()));
    std::array<Vec3, 4> c;
    for (size_t k = 0; k < 4; ++k) {
      c[k] = v.vec3(k);
      if (!within_bounds(c[k])) v.fail(k, bounds_message(c[k]));
    }
    o.finish({"vertices"});
    // A rectangle within a thousandth of its size: v2 = v1 + (v3 - v0), and a right angle at v0.
    const Vec3d e1 = Vec3d(c[1]) - Vec3d(c[0]), e3 = Vec3d(c[3]) - Vec3d(c[0]);
    const double a = glm::length(e1), b = glm::length(e3), size = std::max(a, b);
    if (!(std::min(a, b) > 1e-6 * size) || !(size > 0.0))
      v.fail("a portal must have an area: two of its sides have length 0");
    const double off = glm::length(Vec3d(c[2]) - (Vec3d(c[1]) + e3));
    const double skew = std::abs(glm::dot(e1, e3)) / (a * b);
    if (off > 1e-3 * size || skew > 1e-3)
      v.fail(fmt::format("a portal must be a rectangle, its corners in order around it (v2 is {:.3g} from "
                         "v1 + v3 - v0; the corner at v0 is {:.2f} degrees)",
                         off, glm::degrees(std::acos(std::clamp(glm::dot(e1, e3) / (a * b), -1.0, 1.0)))));
    portals.push_back(c);
  }
  return portals;
}

}  // namespace

Deferred<Light> EnvironmentLight::parse(const JsonObject& l) {
  refuse_power(l, "radiance' or 'file",
               "an environment's power depends on the scene's size (docs/lights.md \"Light power in watts\")");
  if (l.has("file") == l.has("radiance")) l.fail("give exactly one of 'radiance' (uniform) or 'file' (lat-long image)");
  const bool camera_visible = l.has("camera_visible") ? l.get_bool("camera_visible") : true;
  const std::vector<std::array<Vec3, 4>> portals = parse_portals(l);
  const bool compensate = l.get_bool("mis_compensation", true);
  if (l.has("radiance")) {
    const Rgb radiance = l.get_rgb("radiance");
    const double scale = l.get_float("scale", 1.0f, Range::non_negative());
    if (max_component(radiance) * scale > kMaxRadiance)
      l.fail("scale", fmt::format("radiance times scale is {:.3g}, beyond kozu's range (at most {:g})",
                                  max_component(radiance) * scale, kMaxRadiance));
    auto light = std::make_unique<EnvironmentLight>(radiance * static_cast<float>(scale));
    light->camera_visible = camera_visible;
    light->set_portals(portals);
    return light;
  }
  const std::filesystem::path file = l.get_path("file");
  const float scale = l.get_float("scale", 1.0f, Range::non_negative());
  const float rotate = l.get_float("rotate", 0.0f);
  const std::string colorspace = l.get_enum("colorspace", {"auto", "srgb", "linear"}, std::string("auto"));
  return Deferred<Light>([=]() -> std::unique_ptr<Light> {
    Image img;
    try {
      img = read_image(file);
    } catch (const InputError& e) {
      l.fail("file", e.what());
    }
    // As for colour textures: "auto" decodes integer images (8-bit PNG, JPEG) as sRGB; float images are linear.
    if (colorspace == "srgb" || (colorspace == "auto" && !img.source_is_float)) {
      const size_t colour = static_cast<size_t>(std::min(img.channels, 3));  // alpha stays linear
      for (size_t i = 0; i < img.data.size(); ++i)
        if (i % static_cast<size_t>(img.channels) < colour) img.data[i] = srgb_to_linear(img.data[i]);
    }
    // Radiance is >= 0: tiny negative values (filtering noise, as in every HDRI shipped with Blender) are clamped
    // to 0 with one warning, others refused (NegativeValues, io/image_io.h). Alpha is not radiance.
    uint64_t clamped = 0;
    try {
      clamped = clamp_small_negatives(img, file, 3, "radiance");
    } catch (const InputError& e) {
      l.fail("file", e.what());
    }
    if (clamped > 0) {
      std::lock_guard lock(image_warning_mutex());
      l.warn("file", fmt::format("{}: {} tiny negative value{} (filtering noise) clamped to 0", file.string(), clamped,
                                 clamped == 1 ? "" : "s"));
    }
    // Scaled, radiance must stay within float range (checked in double).
    for (size_t i = 0; i < img.data.size(); ++i) {
      const double v = img.data[i];
      const size_t pixel = i / static_cast<size_t>(img.channels);
      const auto where = [&] {
        return fmt::format("{}: pixel ({}, {}) channel {}", file.string(), pixel % static_cast<size_t>(img.width),
                           pixel / static_cast<size_t>(img.width), i % static_cast<size_t>(img.channels));
      };
      if (v * scale > kMaxRadiance)
        l.fail("scale", fmt::format("{} times scale is {:.3g}, beyond kozu's range (at most {:g})", where(), v * scale,
                                    kMaxRadiance));
    }
    auto light = std::make_unique<EnvironmentLight>(img.to_rgb(), img.width, img.height, scale, rotate, compensate);
    light->camera_visible = camera_visible;
    light->set_portals(portals);
    return light;
  });
}

}  // namespace kozu
