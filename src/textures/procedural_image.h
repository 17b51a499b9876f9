// Procedural images: textures kozu generates itself, so that a scene (the built-in demo above all) needs no image
// files. An image texture names one with "procedural" instead of "file":
//   {"type": "image", "procedural": "cobblestone_normal", "resolution": 512, "uv_scale": [60, 120]}
// At load the image is generated once into `<texture conversion folder>/procedural/NAME-RESOLUTION-vK.exr` (linear
// float RGB, written to a temporary file renamed into place, so concurrent renders sharing the folder never read a
// partial one) and the key becomes that "file": everything that reads an image texture's file (the texture cache,
// normal/gloss filtering, surface occlusion) reads it like any other. An environment light takes "procedural" too. K is
// kProceduralImageVersion: a change to a generator bumps it, and older files are simply no longer named.
//
// The images (deterministic: fixed seeds, independent of the thread count):
//   cobblestone_normal  8 × 8 jittered Voronoi stones tiling the square periodically, each a rounded dome (a
//                       circular shoulder over 0.45 of a cell from its joint, flat-ish top) slightly tilted, with
//                       sunken mortar joints, as a tangent-space normal map (OpenGL convention: +y up the image;
//                       central differences of the heights with wrap-around, encoded (n + 1) / 2): the street of
//                       the Call of Duty: WWII showcase (docs/wwii.md, scripts/wwii-showcase.py).
//   cobblestone_albedo  the stones' colour: a per-stone tint about a grey-brown basalt, darker wet mortar.
//   stained_glass       a rose window: a round leaded window of a central disc, 12 radial petals and an outer
//                       ring of 48 panes, in ruby, cobalt, amber, emerald and violet glass mottled by value noise,
//                       lead came (dark) between panes and round the rim, black stone outside the circle. Linear
//                       colour in [0, 1]: scale it.
//   dusk_sky            a lat-long sky (width = 2 × height = 2 × resolution / 2, kozu's environment mapping:
//                       the image centre towards −z): blue above a warm horizon, a glow about a low sun
//                       towards −z 3° up, a dark ground. Radiance about 1 at the horizon.
#pragma once

#include "core/json_reader.h"

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace kozu {

inline constexpr int kProceduralImageVersion = 1;
inline constexpr int kProceduralImageDefaultResolution = 512;
inline constexpr int kProceduralImageMinResolution = 16;
inline constexpr int kProceduralImageMaxResolution = 4096;

struct ProceduralImage {
  int width = 0, height = 0;
  std::vector<float> rgb;  // row-major, top row first, linear
};

// The names above, in order.
const std::vector<std::string>& procedural_image_names();

// Generates image `name` at `resolution` (its width; the sky's height is half). Throws std::invalid_argument for an
// unknown name or a resolution outside [kProceduralImageMinResolution, kProceduralImageMaxResolution].
ProceduralImage make_procedural_image(std::string_view name, int resolution);

// The file of image `name` at `resolution` in `folder`/procedural/, generated now unless already there. Throws
// std::invalid_argument as make_procedural_image, std::runtime_error when it cannot be written.
std::filesystem::path procedural_image_file(std::string_view name, int resolution, const std::filesystem::path& folder);

// Replaces, anywhere in `root`, an object {"type": "image", "procedural": NAME[, "resolution": N], ...} (or an
// environment light's {"type": "environment", "procedural": ...}) by the same object with "file": the generated
// file's absolute path (procedural_image_file in `folder`). Throws InputError
// naming `display_name` and the JSON path for an unknown name, a bad resolution, or "file" given as well.
void expand_procedural_images(Json& root, const std::string& display_name, const std::filesystem::path& folder);

}  // namespace kozu
