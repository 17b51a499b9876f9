// `kozu maketx IN -o OUT.tx [--colorspace auto|srgb|linear] [--data]`: converts an image into the tiled,
// mip-mapped, linear texture that renders read (src/textures/texture_cache.h), ahead of time. A render converts
// the images it needs itself (once, into a cache folder); maketx is for preparing assets once for many renders.
// Exit codes: 0 success, 1 bad input or failure to write.
#include "apps/commands.h"
#include "core/file_io.h"
#include "io/image_io.h"
#include "render/output_paths.h"
#include "textures/texture_cache.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

namespace kozu::app {

Command add_maketx_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "maketx", "Convert an image into a tiled, mip-mapped, linear texture (.tx) for fast filtered lookups");
  auto input = std::make_shared<std::string>();
  auto output = std::make_shared<std::string>();
  auto colorspace = std::make_shared<std::string>("auto");
  auto data = std::make_shared<bool>(false);
  cmd->add_option("image", *input, "Input image (PNG, JPEG, EXR, HDR, TIFF, ...)")->required();
  cmd->add_option("-o,--output", *output, "Output texture (.tx, .tif or .exr)")->required();
  // The value is checked by the command, not by CLI11: a bad value is bad input (exit 1), not a usage error (2).
  cmd->add_option("--colorspace", *colorspace,
                  "How the values are encoded: auto (sRGB for 8/16-bit colour images, else linear), srgb, linear")
      ->capture_default_str();
  cmd->add_flag("--data", *data, "The image holds data (roughness, normals, masks): never decoded as sRGB");
  return [cmd, input, output, colorspace, data]() -> int {
    if (!cmd->parsed()) return 2;
    const std::string ext = lower_extension(*output);
    if (ext != ".tx" && ext != ".tif" && ext != ".tiff" && ext != ".exr") {
      std::fprintf(stderr, "error: kozu maketx: %s: the output must be a .tx, .tif or .exr file\n", output->c_str());
      return 1;
    }
    if (*colorspace != "auto" && *colorspace != "srgb" && *colorspace != "linear") {
      std::fprintf(stderr, "error: kozu maketx: --colorspace: '%s' is not one of auto, srgb, linear\n",
                   colorspace->c_str());
      return 1;
    }
    const ColorSpace space = *colorspace == "srgb"     ? ColorSpace::Srgb
                             : *colorspace == "linear" ? ColorSpace::Linear
                                                       : ColorSpace::Auto;
    const auto start = std::chrono::steady_clock::now();
    try {
      // The output is checked before the conversion (it must not be the input, a folder or a device); the memory
      // the conversion needs is checked by make_tiled_texture before it reads a pixel.
      check_outputs({OutputFile{*output, "-o", false}}, {std::filesystem::path(*input)});
      const uint64_t clamped = make_tiled_texture(*input, *output, space, *data ? TextureUse::Data : TextureUse::Color);
      if (clamped > 0)
        std::fprintf(stderr, "warning: %s: %llu tiny negative value%s (filtering noise) clamped to 0\n", input->c_str(),
                     static_cast<unsigned long long>(clamped), clamped == 1 ? "" : "s");
      const ImageInfo info = probe_image(*output);
      std::fprintf(stderr, "%s: %d x %d, %d channel%s, %d-bit %s, %d mip levels, in %.2f s\n", output->c_str(),
                   info.width, info.height, info.channels, info.channels == 1 ? "" : "s", info.bits,
                   info.is_float ? "float" : "integer", info.mip_levels,
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: kozu maketx: %s\n", e.what());
      return 1;
    }
    return 0;
  };
}

}  // namespace kozu::app
