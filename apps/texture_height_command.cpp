// `kozu texture height` and `kozu texture occlusion`: registered here into the `texture` group
// (apps/texture_command.cpp). Material surface occlusion after D. Chan, "Material Advances in Call of Duty: WWII",
// SIGGRAPH 2018 course Advances in Real-Time Rendering in Games, §4:
//   height     NORMAL -o HEIGHT.exr [--mesh OUT.ply] [--height-scale S] [--flip-y]
//              the height field behind a normal map (§4.2, Algorithm 5; textures/height_from_normals.h)
//   occlusion  NORMAL|HEIGHT -o AO.exr [--cone CONE.exr] [--height-scale S] [--radius R] [--directions D]
//              [--albedo A] [--adjust MODEL] [--flip-y]
//              cosine-weighted visibility (eq. 43), its interreflection adjustment (eqs. 45-49) and the
//              equal-area cone (eqs. 50-56) (textures/surface_occlusion.h)
// Exit codes: 0 success, 1 bad input or failure to write, 2 usage errors (kozu.cpp).
#include "apps/command_errors.h"
#include "apps/commands.h"
#include "core/error.h"
#include "core/file_io.h"
#include "core/memory.h"
#include "core/temp_files.h"
#include "io/image_io.h"
#include "render/output_paths.h"
#include "textures/height_from_normals.h"
#include "textures/surface_occlusion.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace kozu::app {
namespace {

// Working memory per texel: the height solver's levels (two doubles, 4/3 for the chain), its edge and residual
// scratch (three doubles), the slopes (two floats), the image as floats (four), the outputs (two floats).
constexpr double kBytesPerTexel = 16 * 4.0 / 3.0 + 24 + 8 + 16 + 8;
// A binary PLY height-field mesh: a vertex (five floats) and two triangles (a count byte and three ints each).
constexpr double kMeshBytesPerTexel = 20 + 2 * 13;

void check_memory(const ImageInfo& info, bool mesh, const std::filesystem::path& file) {
  const double texels = double(info.width) * info.height;
  const double need = texels * (kBytesPerTexel + (mesh ? 2 * kMeshBytesPerTexel : 0.0));
  const MemoryLimit limit = memory_limit();
  const double left = memory_left(limit);
  if (limit.bytes > 0 && need > left)
    throw InputError(file.string(), "",
                     fmt::format("{} x {} texels need about {} of memory, {} is left ({})", info.width, info.height,
                                 format_bytes(need), format_bytes(std::max(left, 0.0)), limit.source));
}

// Reads the input image with its checks (size, memory, truncation) and refuses non-finite values.
Image read_checked(const std::filesystem::path& file, bool mesh) {
  check_memory(probe_image(file), mesh, file);
  Image img = read_image(file);
  for (size_t i = 0; i < img.data.size(); ++i)
    if (!std::isfinite(img.data[i])) {
      const size_t texel = i / size_t(img.channels);
      throw InputError(
          file.string(), "",
          fmt::format("texel ({}, {}) is not a finite number", texel % size_t(img.width), texel / size_t(img.width)));
    }
  return img;
}

// The height field as a binary PLY mesh for displaced-geometry references: one vertex per texel centre at
// (x + 0.5, H - y - 0.5, S h) in texel widths (+y up the image, so that +v of the uv is +y), uv as the renderer
// reads the map (v = 0 at the image's bottom), two triangles per quad of neighbouring centres, counter-clockwise
// seen from +z. The mesh covers the centres only: it does not wrap.
void write_height_mesh(const std::filesystem::path& file, const HeightField& hf, float scale) {
  const int w = hf.width, h = hf.height;
  const size_t faces = size_t(std::max(w - 1, 0)) * size_t(std::max(h - 1, 0)) * 2;
  std::string out = fmt::format(
      "ply\nformat binary_little_endian 1.0\ncomment kozu texture height: a height field, texel widths\n"
      "element vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty float u\nproperty float v\n"
      "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
      size_t(w) * h, faces);
  const size_t header = out.size();
  out.resize(header + size_t(w) * h * 20 + faces * 13);
  char* p = out.data() + header;
  auto put = [&p](const void* src, size_t n) {
    std::memcpy(p, src, n);  // the host is little-endian (x86-64, AArch64), as the format line says
    p += n;
  };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float v[5] = {float(x + 0.5), float(h - y - 0.5), scale * hf.h[size_t(y) * w + x], float((x + 0.5) / w),
                          float(1.0 - (y + 0.5) / h)};
      put(v, sizeof v);
    }
  const unsigned char three = 3;
  for (int y = 0; y + 1 < h; ++y)
    for (int x = 0; x + 1 < w; ++x) {
      // Row y is above row y + 1 in +y: (x, y+1), (x+1, y+1), (x+1, y) is counter-clockwise from +z.
      const int a = y * w + x, b = a + 1, c = a + w, d = c + 1;
      const int t0[3] = {c, d, b}, t1[3] = {c, b, a};
      put(&three, 1);
      put(t0, sizeof t0);
      put(&three, 1);
      put(t1, sizeof t1);
    }
  write_file_atomic(file, out);
}

std::string exr_extension_error(const std::string& flag, const std::string& path) {
  return fmt::format("{}: {}: the output must be an .exr file", flag, path);
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

HeightField height_of_normal_map(const Image& img, const std::filesystem::path& file, bool flip_y, double* residual) {
  if (img.channels < 3)
    throw InputError(file.string(), "",
                     fmt::format("a normal map needs three channels (x, y, z), this image has {}", img.channels));
  const SlopeField g = normal_slopes(img.data.data(), img.width, img.height, img.channels, flip_y);
  HeightField hf = height_from_slopes(g);
  *residual = slope_residual(g, hf);
  return hf;
}

// `kozu texture height NORMAL -o HEIGHT.exr [--mesh OUT.ply] [--height-scale S] [--flip-y]`
Command add_height_command(CLI::App& group) {
  CLI::App* cmd = group.add_subcommand(
      "height", "The height field behind a normal map (Chan 2018 §4.2, Algorithm 5), in texel widths, mean zero");
  auto normal = std::make_shared<std::string>();
  auto output = std::make_shared<std::string>();
  auto mesh = std::make_shared<std::string>();
  auto scale = std::make_shared<double>(1.0);
  auto flip_y = std::make_shared<bool>(false);
  cmd->add_option("normal", *normal, "Tangent-space normal map (OpenGL convention, n = 2 c - 1)")->required();
  cmd->add_option("-o,--output", *output, "Height map (.exr, one float channel Y, texel widths)")->required();
  cmd->add_option("--mesh", *mesh, "Also write the height field as a binary PLY mesh (one vertex a texel, with uv)");
  cmd->add_option("--height-scale", *scale, "Scale of the mesh's heights (the .exr stays in texel widths)")
      ->capture_default_str();
  cmd->add_flag("--flip-y", *flip_y, "The map is DirectX convention (green down)");
  return [cmd, normal, output, mesh, scale, flip_y]() -> int {
    if (!cmd->parsed()) return 2;
    try {
      if (lower_extension(*output) != ".exr") throw std::runtime_error(exr_extension_error("-o", *output));
      // An empty name is refused as given, never read as "no mesh".
      const bool want_mesh = cmd->count("--mesh") > 0;
      if (want_mesh && mesh->empty()) throw std::runtime_error("--mesh: an empty file name");
      if (want_mesh && lower_extension(*mesh) != ".ply")
        throw std::runtime_error(fmt::format("--mesh: {}: the mesh must be a .ply file", *mesh));
      if (!(std::isfinite(*scale) && std::abs(*scale) <= 1e6))
        throw std::runtime_error(fmt::format("--height-scale: expected a number in [-1e6, 1e6], got {}", *scale));
      const std::vector<std::filesystem::path> inputs = {*normal};
      std::vector<OutputFile> outs = {OutputFile{*output, "-o", false, false, false}};
      if (want_mesh) outs.push_back(OutputFile{*mesh, "--mesh", false, false, false});
      check_outputs(outs, inputs);
      const auto start = std::chrono::steady_clock::now();
      const Image img = read_checked(*normal, want_mesh);
      double residual = 0;
      const HeightField hf = height_of_normal_map(img, *normal, *flip_y, &residual);
      double rms = 0, lo = 0, hi = 0;
      for (float v : hf.h) {
        rms += double(v) * v;
        lo = std::min(lo, double(v));
        hi = std::max(hi, double(v));
      }
      rms = std::sqrt(rms / double(hf.h.size()));
      write_single_channel_exr(*output, hf.width, hf.height, hf.h,
                               {{"kozu:content", "height, texel widths, mean zero"},
                                {"kozu:curl_residual", fmt::format("{:.6g}", residual)},
                                {"kozu:height_rms", fmt::format("{:.6g}", rms)}});
      if (want_mesh) write_height_mesh(*mesh, hf, float(*scale));
      std::fprintf(stderr,
                   "%s: %d x %d, height RMS %.4g, range [%.4g, %.4g] texel widths; curl residual %.4g (RMS of the "
                   "slopes no height field has, over RMS slope) in %.2f s\n",
                   output->c_str(), hf.width, hf.height, rms, lo, hi, residual, seconds_since(start));
    } catch (const std::exception& e) {
      return report_failure("texture height", e);
    }
    return 0;
  };
}

// --adjust's name: what occluded directions send back (Chan 2018 eqs. 45-49); throws std::runtime_error.
OcclusionAdjustment occlusion_adjustment(const std::string& name) {
  if (name == "black") return OcclusionAdjustment::Black;
  if (name == "white") return OcclusionAdjustment::WhiteOccluded;
  if (name == "albedo") return OcclusionAdjustment::SameAlbedo;
  if (name == "albedo-occluded") return OcclusionAdjustment::SameAlbedoOccluded;
  if (name == "interreflection") return OcclusionAdjustment::Interreflection;
  throw std::runtime_error(
      fmt::format("--adjust: '{}' is not one of black, white, albedo, albedo-occluded, interreflection", name));
}

// `kozu texture occlusion NORMAL|HEIGHT -o AO.exr [--cone CONE.exr] [--height-scale S] [--radius R] ...`
Command add_occlusion_command(CLI::App& group) {
  CLI::App* cmd = group.add_subcommand(
      "occlusion",
      "Material surface occlusion (Chan 2018 §4.3-4.5): visibility from a height or normal map, adjusted for "
      "interreflection, and its equal-area cone");
  auto input = std::make_shared<std::string>();
  auto output = std::make_shared<std::string>();
  auto cone = std::make_shared<std::string>();
  auto scale = std::make_shared<double>(1.0);
  auto radius = std::make_shared<double>(32.0);
  auto directions = std::make_shared<int>(16);
  auto albedo = std::make_shared<double>(0.5);
  auto adjust = std::make_shared<std::string>("interreflection");
  auto flip_y = std::make_shared<bool>(false);
  cmd->add_option("input", *input, "Normal map (three channels or more) or height map (one channel, texel widths)")
      ->required();
  cmd->add_option("-o,--output", *output,
                  "Ambient occlusion (.exr, one float channel Y): eq. (43) adjusted by --adjust")
      ->required();
  cmd->add_option("--cone", *cone,
                  "Also write the equal-area cone's cos(half angle) (.exr, eq. 56 of the unadjusted visibility)");
  cmd->add_option("--height-scale", *scale, "Scale of the heights (texel widths) before the horizons are found")
      ->capture_default_str();
  cmd->add_option("--radius", *radius, "Horizon search distance in texels, in [1, 1024]")->capture_default_str();
  cmd->add_option("--directions", *directions, "Slice directions over 180 degrees, in [1, 256]")
      ->transform(decimal_integer())
      ->capture_default_str();
  cmd->add_option("--albedo", *albedo, "Diffuse albedo for the adjustment, in [0, 1]")->capture_default_str();
  cmd->add_option("--adjust", *adjust,
                  "What occluded directions send back: black (eq. 45), white (46), albedo (47), albedo-occluded (48), "
                  "interreflection (49)")
      ->capture_default_str();
  cmd->add_flag("--flip-y", *flip_y, "A normal map input is DirectX convention (green down)");
  return [=]() -> int {
    if (!cmd->parsed()) return 2;
    try {
      if (lower_extension(*output) != ".exr") throw std::runtime_error(exr_extension_error("-o", *output));
      const bool want_cone = cmd->count("--cone") > 0;
      if (want_cone && cone->empty()) throw std::runtime_error("--cone: an empty file name");
      if (want_cone && lower_extension(*cone) != ".exr") throw std::runtime_error(exr_extension_error("--cone", *cone));
      if (!(std::isfinite(*scale) && *scale >= 0 && *scale <= 1e6))
        throw std::runtime_error(fmt::format("--height-scale: expected a number in [0, 1e6], got {}", *scale));
      if (!(*radius >= 1 && *radius <= 1024))
        throw std::runtime_error(fmt::format("--radius: expected a number in [1, 1024], got {}", *radius));
      if (*directions < 1 || *directions > 256)
        throw std::runtime_error(fmt::format("--directions: expected an integer in [1, 256], got {}", *directions));
      if (!(*albedo >= 0 && *albedo <= 1))
        throw std::runtime_error(fmt::format("--albedo: expected a number in [0, 1], got {}", *albedo));
      const OcclusionAdjustment model = occlusion_adjustment(*adjust);
      std::vector<OutputFile> outs = {OutputFile{*output, "-o", false, false, false}};
      if (want_cone) outs.push_back(OutputFile{*cone, "--cone", false, false, false});
      check_outputs(outs, {std::filesystem::path(*input)});

      const auto start = std::chrono::steady_clock::now();
      const Image img = read_checked(*input, false);
      HeightField hf;
      std::string source = "height map";
      if (img.channels >= 3) {
        double residual = 0;
        hf = height_of_normal_map(img, *input, *flip_y, &residual);
        source = fmt::format("normal map (curl residual {:.4g})", residual);
      } else {
        hf.width = img.width;
        hf.height = img.height;
        hf.h.resize(size_t(img.width) * img.height);
        for (size_t i = 0; i < hf.h.size(); ++i) hf.h[i] = img.data[i * size_t(img.channels)];
      }
      OcclusionOptions o;
      o.height_scale = float(*scale);
      o.radius = float(*radius);
      o.directions = *directions;
      const std::vector<float> v = visibility(hf, o);
      std::vector<float> ao(v.size()), cone_cos_map;
      double mean_v = 0, mean_ao = 0, min_v = 1;
      for (size_t i = 0; i < v.size(); ++i) {
        ao[i] = float(adjusted_visibility(v[i], *albedo, model));
        mean_v += v[i];
        mean_ao += ao[i];
        min_v = std::min(min_v, double(v[i]));
      }
      mean_v /= double(v.size());
      mean_ao /= double(v.size());
      const std::vector<std::pair<std::string, std::string>> common = {
          {"kozu:height_scale", fmt::format("{}", *scale)},
          {"kozu:radius", fmt::format("{}", *radius)},
          {"kozu:directions", fmt::format("{}", *directions)},
          {"kozu:visibility_mean", fmt::format("{:.6g}", mean_v)}};
      auto attributes = common;
      attributes.emplace_back("kozu:content", "ambient occlusion (cosine-weighted visibility, adjusted)");
      attributes.emplace_back("kozu:adjust", *adjust);
      attributes.emplace_back("kozu:albedo", fmt::format("{}", *albedo));
      write_single_channel_exr(*output, hf.width, hf.height, ao, attributes);
      if (want_cone) {
        cone_cos_map.resize(v.size());
        for (size_t i = 0; i < v.size(); ++i) cone_cos_map[i] = float(cone_cos(v[i]));  // Chan 2018 eq. (56)
        attributes = common;
        attributes.emplace_back("kozu:content", "cos of the equal-area cone's half angle, sqrt(1 - visibility)");
        write_single_channel_exr(*cone, hf.width, hf.height, cone_cos_map, attributes);
      }
      std::fprintf(stderr,
                   "%s: %d x %d from a %s: visibility mean %.4f, min %.4f; adjusted (%s, albedo %.3g) mean %.4f "
                   "in %.2f s\n",
                   output->c_str(), hf.width, hf.height, source.c_str(), mean_v, min_v, adjust->c_str(), *albedo,
                   mean_ao, seconds_since(start));
    } catch (const std::exception& e) {
      return report_failure("texture occlusion", e);
    }
    return 0;
  };
}

}  // namespace

void add_texture_height_commands(CLI::App& texture, std::vector<std::pair<std::string, Command>>& run) {
  run.emplace_back("height", add_height_command(texture));
  run.emplace_back("occlusion", add_occlusion_command(texture));
}

}  // namespace kozu::app
