// Arbitrary output variables: per-pixel channels written beside the colour in the EXR (`kozu render --aov`), under
// the names compositors and external denoisers look for:
//   albedo        albedo.R albedo.G albedo.B   first surface's albedo (integrator.h's PixelFeatures); a medium's
//                                              single-scattering albedo where the camera ray scatters first
//   normal        N.X N.Y N.Z                  its shading normal, world space, facing the camera; in an SGGX
//                                              medium the flakes' axis at half length (sggx::principal_axis), in
//                                              others 0
//   depth         Z                            camera-space depth (distance along the view axis); 1e10 for the sky
//   position      P.X P.Y P.Z                  world position
//   variance      variance.R variance.G variance.B   variance of the pixel's mean (sample variance / count)
//   sample_count  sample_count                 the pixel's valid samples
//   emission      emission.R emission.G emission.B   the visible emission (emitters seen directly or through
//                                              perfectly specular vertices; render/emission_refine.h), part of the
//                                              colour: colour minus it is what the denoisers filter
// Every feature is the mean over the pixel's samples, so edges are antialiased like the colour.
#pragma once

#include "io/image_io.h"
#include "render/film.h"

#include <string_view>
#include <vector>

namespace kozu {

enum class Aov { Albedo, Normal, Depth, Position, Variance, SampleCount, Emission };

// "albedo,normal,..." (any order, no repeats); throws std::invalid_argument naming the unknown one.
std::vector<Aov> parse_aovs(std::string_view list);
// An AOV's name, as --aov takes it, and how many channels it adds.
std::string_view aov_name(Aov a);
size_t aov_channel_count(Aov a);
// True for the AOVs that need the film's features (Film::enable_features).
bool needs_features(const std::vector<Aov>& aovs);
// True when the `position` AOV is among them: the film then keeps position sums too (Film::enable_positions).
bool needs_positions(const std::vector<Aov>& aovs);
// The AOVs' channel names and values over the film's window, appended to `extras`.
void add_aov_channels(const Film& film, const std::vector<Aov>& aovs, ImageExtras& extras);

}  // namespace kozu
