// image: a texture read from an image file and filtered over the lookup's footprint by OpenImageIO's
// TextureSystem (texture_cache.h prepares the file: tiled, mip-mapped, linear).
//
// Parameters
//   file        path                        required   any format OpenImageIO reads (PNG, JPEG, EXR, TIFF, .tx)
//   colorspace  auto | srgb | linear        auto       texture_cache.h: auto is sRGB for 8/16-bit colour images
//   channel     r | g | b | a               -          one channel, replicated (number keys read channel r
//                                                      otherwise; an image with one channel is grey)
//   uv_scale    [su, sv]                    [1, 1]
//   uv_offset   [ou, ov]                    [0, 0]
//   uv_rotation float (radians)             0          turns the scaled coordinates counter-clockwise (glTF's
//                                                      KHR_texture_transform)
//   filter      ewa | trilinear | closest   ewa        ewa: OpenImageIO's anisotropic filter (probes along the
//                                                      footprint's major axis, each trilinear); closest: the
//                                                      nearest texel of the full-resolution image, no filtering
//   scale       float or [r, g, b]          1          multiplies the value (per channel)
//   threshold   float                       -          after the scale, values below it become 0 and the others 1
//                                                      (alpha masks: glTF's alphaMode MASK with its alphaCutoff)
//
// Mapping: (s, 1 − t) = R(ρ) (su u, sv v) + (ou, ov) with (s, t) OpenImageIO's coordinates (t = 0 the image's top
// row) and R(ρ) the rotation by uv_rotation; without rotation s = su u + ou, t = 1 − (sv v + ov), so
// (u, v) = (0, 0) is the image's bottom-left corner, as in OBJ and Blender. Lookups wrap (the texture repeats).
#pragma once

#include "textures/texture.h"
#include "textures/texture_cache.h"

#include <filesystem>

namespace kozu {

class ImageTexture final : public Texture {
 public:
  enum class Filter { Ewa, Trilinear, Closest };
  struct Options {
    int channel = -1;  // -1: RGB
    Vec2 uv_scale{1.0f}, uv_offset{0.0f};
    float uv_rotation = 0.0f;  // radians
    Filter filter = Filter::Ewa;
    Rgb scale{1.0f};
    float threshold = -1.0f;  // < 0: none
  };
  // file: a file TextureCache::prepare returned.
  ImageTexture(const TextureCache& cache, const std::filesystem::path& file, const Options& options);
  Rgb eval(const TextureQuery& q) const override;
  // OpenImageIO's (s, t) for (u, v) (the mapping above).
  static Vec2 lookup_coordinates(const Options& options, const Vec2& uv);

 private:
  OIIO::TextureSystem& ts_;
  void* handle_;  // OIIO::TextureSystem::TextureHandle
  Options options_;
};

}  // namespace kozu
