#include "textures/normal_gloss_files.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/memory.h"
#include "core/temp_files.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace kozu {
namespace {

// The OpenImageIO writer of an output's extension (.tx is a TIFF).
std::string writer_of(const std::filesystem::path& file) {
  const std::string ext = lower_extension(file);
  if (ext == ".exr") return "openexr";
  if (ext == ".tx" || ext == ".tif" || ext == ".tiff") return "tiff";
  throw std::runtime_error(fmt::format("{}: a mip-mapped texture is a .exr, .tx or .tif file", file.string()));
}

}  // namespace

namespace {

// Writes the levels into `path` (a temporary file; `file` is the output named in messages).
void write_levels(const std::filesystem::path& path, const std::filesystem::path& file,
                  const std::vector<Image>& levels) {
  if (levels.empty()) throw std::invalid_argument("write_mip_levels: no levels");
  auto out = OIIO::ImageOutput::create(writer_of(file));
  if (!out) throw std::runtime_error(fmt::format("{}: no writer for this format", file.string()));
  OIIO::ImageSpec spec(levels[0].width, levels[0].height, levels[0].channels, OIIO::TypeDesc::FLOAT);
  spec.tile_width = spec.tile_height = 64;
  spec.attribute("compression", "zip");
  // "Plain Texture" makes OpenEXR's writer store a mip-mapped (round-down) file; the texture system reads it as is.
  spec.attribute("textureformat", "Plain Texture");
  spec.attribute("Software", "kozu texture filter-normals");
  if (levels[0].channels == 1) spec.channelnames = {"Y"};
  // OpenEXR appends mip levels; TIFF stores each as a further directory (a subimage), which OpenImageIO reads back
  // as mip levels of a file whose textureformat is "Plain Texture" (as maketx writes it).
  const OIIO::ImageOutput::OpenMode append =
      writer_of(file) == "tiff" ? OIIO::ImageOutput::AppendSubimage : OIIO::ImageOutput::AppendMIPLevel;
  for (size_t l = 0; l < levels.size(); ++l) {
    const Image& level = levels[l];
    spec.width = spec.full_width = level.width;
    spec.height = spec.full_height = level.height;
    const auto open = [&] { return out->open(path.string(), spec, l == 0 ? OIIO::ImageOutput::Create : append); };
    const bool ok = (l == 0 ? create_temp_file(open) : open()) &&
                    out->write_image(OIIO::TypeDesc::FLOAT, level.data.data());
    if (!ok)
      throw std::runtime_error(fmt::format("{}: cannot write mip level {}: {}", file.string(), l, out->geterror()));
  }
  if (!out->close()) throw std::runtime_error(fmt::format("{}: cannot write: {}", file.string(), out->geterror()));
}

}  // namespace

void write_mip_levels(const std::filesystem::path& file, const std::vector<Image>& levels) {
  TempFileGuard tmp(temp_path_for(file));
  write_levels(tmp.path(), file, levels);
  rename_into_place(tmp, file);
}

Image read_mip_level(const std::filesystem::path& file, int level) {
  const ImageInfo info = probe_image(file);  // the checks every input image gets
  if (level < 0 || level >= info.mip_levels)
    throw InputError(file.string(), "", fmt::format("has {} mip levels, no level {}", info.mip_levels, level));
  auto in = OIIO::ImageInput::open(file.string());
  OIIO::ImageSpec spec;
  if (!in || !in->seek_subimage(0, level, spec))
    throw InputError(file.string(), "", fmt::format("cannot read mip level {}", level));
  Image img;
  img.width = spec.width;
  img.height = spec.height;
  img.channels = spec.nchannels;
  img.data.resize(size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels));
  if (!in->read_image(0, level, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, img.data.data()))
    throw InputError(file.string(), "", fmt::format("cannot read mip level {}: {}", level, in->geterror()));
  return img;
}

NormalGlossFilterSummary filter_normal_gloss_files(const NormalGlossFilterJob& job) {
  const ImageInfo info = probe_image(job.normal_map);
  // Memory before any pixel: the decoded input (16 bytes a texel), level 0 and the chain (16 x 4 / 3) and the
  // output levels (about as much again).
  const double need = 80.0 * double(info.width) * double(info.height) + 64.0 * 1024 * 1024;
  const MemoryLimit limit = memory_limit();
  if (need > memory_left(limit))
    throw InputError(
        job.normal_map.string(), "",
        fmt::format("filtering this {} x {} normal map needs about {}, more than is left of the {} memory "
                    "limit ({})",
                    info.width, info.height, format_bytes(need), format_bytes(double(limit.bytes)), limit.source));
  if (info.channels < 2)
    throw InputError(job.normal_map.string(), "", "a normal map has 2 (x, y) or 3 (x, y, z) channels, this has 1");
  NormalGlossLevel level0;
  {
    const Image normal = read_image(job.normal_map);
    level0.width = normal.width;
    level0.height = normal.height;
    const size_t texels = size_t(normal.width) * size_t(normal.height);
    level0.normal.resize(3 * texels);
    for (size_t i = 0; i < texels; ++i) {
      const float* c = &normal.data[i * size_t(normal.channels)];
      const float x0 = 2.0f * c[0] - 1.0f, y0 = 2.0f * c[1] - 1.0f;  // n = 2 c - 1, as the renderer decodes
      const float z = normal.channels >= 3 ? 2.0f * c[2] - 1.0f : std::sqrt(std::max(0.0f, 1.0f - x0 * x0 - y0 * y0));
      const float x = static_cast<float>(job.strength) * x0, y = static_cast<float>(job.strength) * y0;
      const float len = std::sqrt(x * x + y * y + z * z);
      if (!(len > 1e-6f) || !std::isfinite(len))
        throw InputError(job.normal_map.string(), "",
                         fmt::format("texel ({}, {}) decodes to a normal of length {} (n = 2 c - 1)",
                                     i % size_t(normal.width), i / size_t(normal.width), len));
      level0.normal[3 * i] = x / len, level0.normal[3 * i + 1] = y / len, level0.normal[3 * i + 2] = z / len;
    }
    level0.gloss.assign(texels, static_cast<float>(job.gloss_value));
  }
  if (!job.gloss_map.empty()) {
    const Image gloss = read_image(job.gloss_map);
    if (gloss.width != level0.width || gloss.height != level0.height)
      throw InputError(job.gloss_map.string(), "",
                       fmt::format("the gloss map is {} x {}, the normal map {} x {}: they must be the same size",
                                   gloss.width, gloss.height, level0.width, level0.height));
    for (size_t i = 0; i < level0.gloss.size(); ++i) {
      const float g = gloss.data[i * size_t(gloss.channels)];
      if (!(g >= 0.0f && g <= 1.0f))
        throw InputError(job.gloss_map.string(), "",
                         fmt::format("texel ({}, {}) has gloss {}, outside [0, 1]", i % size_t(gloss.width),
                                     i / size_t(gloss.width), g));
      level0.gloss[i] = g;
    }
  }
  NormalGlossFilterSummary summary;
  summary.width = level0.width;
  summary.height = level0.height;
  double sum = 0;
  for (float g : level0.gloss) sum += g;
  summary.mean_gloss_level0 = sum / double(level0.gloss.size());
  const std::vector<NormalGlossLevel> levels = filter_normal_gloss(std::move(level0), job.model);
  summary.levels = static_cast<int>(levels.size());
  summary.mean_gloss_last = levels.back().gloss[0];
  std::vector<Image> normals, glosses;
  for (const NormalGlossLevel& l : levels) {
    Image n, g;
    n.width = g.width = l.width;
    n.height = g.height = l.height;
    n.channels = 3, g.channels = 1;
    n.data.resize(l.normal.size());
    for (size_t i = 0; i < l.normal.size(); ++i) n.data[i] = 0.5f * (l.normal[i] + 1.0f);  // c = (n + 1) / 2
    g.data = l.gloss;
    normals.push_back(std::move(n));
    glosses.push_back(std::move(g));
  }
  // Both written before either is renamed into place: a failure leaves neither.
  TempFileGuard tmp_normal(temp_path_for(job.out_normal)), tmp_gloss(temp_path_for(job.out_gloss));
  write_levels(tmp_normal.path(), job.out_normal, normals);
  write_levels(tmp_gloss.path(), job.out_gloss, glosses);
  rename_into_place(tmp_normal, job.out_normal);
  rename_into_place(tmp_gloss, job.out_gloss);
  return summary;
}

}  // namespace kozu
