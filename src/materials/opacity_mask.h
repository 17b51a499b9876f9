// Opacity cut-outs ("opacity", a key every surface material accepts): a texture or number in [0, 1] giving the
// probability that a ray stops where it meets the surface; elsewhere the surface is not there (leaves, fences,
// glTF's alphaMode MASK/BLEND coverage). Fractional values are stochastic transparency (Enderton et al. 2010,
// "Stochastic Transparency", I3D): a hit is kept with probability = opacity, so the expected image is that of a
// surface covering that fraction of each point.
//
// The accelerator applies it to candidate hits (geometry/embree_scene.h: an Embree intersection and occlusion
// filter on each shape whose material has one), so camera, bounce, shadow and probe rays all see the same holes;
// the lookup is a point lookup at the hit's (u, v) (the filter runs before a hit is accepted, without a footprint).
// Values outside [0, 1] (a texture's scale) are clamped.
//
// Parameters
//   opacity  float or texture  1  in [0, 1]; a texture reads its first channel (an image's "channel": "a" picks
//                                 the alpha channel), decoded linear (TextureUse::Data)
#pragma once

#include "geometry/shape.h"
#include "textures/texture.h"

#include <memory>

namespace kozu {

class TextureOpacity final : public OpacityMask {
 public:
  explicit TextureOpacity(std::unique_ptr<const Texture> texture) : texture_(std::move(texture)) {}
  float opacity(const Vec2& uv) const override;

 private:
  std::unique_ptr<const Texture> texture_;
};

}  // namespace kozu
