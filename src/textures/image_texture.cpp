#include "textures/image_texture.h"

#include <OpenImageIO/texture.h>

#include <cmath>

namespace kozu {

ImageTexture::ImageTexture(const TextureCache& cache, const std::filesystem::path& file, const Options& options)
    : ts_(cache.system()), handle_(ts_.get_texture_handle(OIIO::ustring(file.string()))), options_(options) {}

Vec2 ImageTexture::lookup_coordinates(const Options& o, const Vec2& uv) {
  const Vec2 a = o.uv_scale * uv;
  if (o.uv_rotation == 0.0f) return Vec2(a.x + o.uv_offset.x, 1.0f - (a.y + o.uv_offset.y));
  const float c = std::cos(o.uv_rotation), n = std::sin(o.uv_rotation);
  return Vec2(c * a.x - n * a.y + o.uv_offset.x, 1.0f - (n * a.x + c * a.y + o.uv_offset.y));
}

Rgb ImageTexture::eval(const TextureQuery& q) const {
  OIIO::TextureOpt opt;
  opt.swrap = opt.twrap = OIIO::TextureOpt::WrapPeriodic;
  switch (options_.filter) {
    case Filter::Closest:
      opt.interpmode = OIIO::TextureOpt::InterpClosest;
      opt.mipmode = OIIO::TextureOpt::MipModeNoMIP;
      break;
    case Filter::Trilinear:
      opt.interpmode = OIIO::TextureOpt::InterpBilinear;
      opt.mipmode = OIIO::TextureOpt::MipModeTrilinear;
      break;
    case Filter::Ewa:
      // At indirect hits one trilinear probe (TextureQuery::fine): OpenImageIO's anisotropic lookups took 37 % of
      // a textured interior's render, and trilinear ones read 42 % of their tiles (bench/cycles "interior").
      opt.interpmode = OIIO::TextureOpt::InterpBilinear;
      opt.mipmode = q.fine ? OIIO::TextureOpt::MipModeAniso : OIIO::TextureOpt::MipModeTrilinear;
      break;
  }
  const Vec2 st = lookup_coordinates(options_, q.uv);
  const float s = st.x, t = st.y;
  // The derivatives go through the linear part of the map; t runs down the image, so its derivatives change sign.
  const Vec2& k = options_.uv_scale;
  const float c = std::cos(options_.uv_rotation), n = std::sin(options_.uv_rotation);
  const auto ds = [&](const Vec2& d) { return c * k.x * d.x - n * k.y * d.y; };
  const auto dt = [&](const Vec2& d) { return -(n * k.x * d.x + c * k.y * d.y); };
  const float dsdx = ds(q.duvdx), dtdx = dt(q.duvdx), dsdy = ds(q.duvdy), dtdy = dt(q.duvdy);
  float result[3] = {0.0f, 0.0f, 0.0f};
  auto* handle = static_cast<OIIO::TextureSystem::TextureHandle*>(handle_);
  OIIO::TextureSystem::Perthread* thread = ts_.get_perthread_info();
  if (options_.channel >= 0) {
    opt.firstchannel = options_.channel;
    ts_.texture(handle, thread, opt, s, t, dsdx, dtdx, dsdy, dtdy, 1, result);
    result[1] = result[2] = result[0];
  } else {
    ts_.texture(handle, thread, opt, s, t, dsdx, dtdx, dsdy, dtdy, 3, result);
  }
  Rgb value = options_.scale * Rgb(result[0], result[1], result[2]);
  if (options_.threshold >= 0.0f)
    for (int ch = 0; ch < 3; ++ch) value[ch] = value[ch] >= options_.threshold ? 1.0f : 0.0f;
  return value;
}

}  // namespace kozu
