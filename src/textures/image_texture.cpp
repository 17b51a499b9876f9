#include "textures/image_texture.h"

#include <OpenImageIO/texture.h>

namespace kozu {

ImageTexture::ImageTexture(const TextureCache& cache, const std::filesystem::path& file, const Options& options)
    : ts_(cache.system()), handle_(ts_.get_texture_handle(OIIO::ustring(file.string()))), options_(options) {}

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
      opt.interpmode = OIIO::TextureOpt::InterpBilinear;
      opt.mipmode = OIIO::TextureOpt::MipModeAniso;
      break;
  }
  const Vec2& k = options_.uv_scale;
  const float s = k.x * q.uv.x + options_.uv_offset.x, t = 1.0f - (k.y * q.uv.y + options_.uv_offset.y);
  // t runs down the image: its derivatives change sign.
  const float dsdx = k.x * q.duvdx.x, dtdx = -k.y * q.duvdx.y, dsdy = k.x * q.duvdy.x, dtdy = -k.y * q.duvdy.y;
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
  return options_.scale * Rgb(result[0], result[1], result[2]);
}

}  // namespace kozu
