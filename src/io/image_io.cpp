#include "io/image_io.h"

#include "core/error.h"
#include "core/rng.h"
#include "io/file_io.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <stdexcept>
#include <system_error>

namespace kozu {

namespace {

bool is_float_format(const std::string& ext) { return ext == ".exr" || ext == ".hdr"; }

}  // namespace

std::vector<Rgb> Image::to_rgb() const {
  std::vector<Rgb> out(static_cast<size_t>(width) * height);
  for (size_t i = 0; i < out.size(); ++i) {
    const float* p = &data[i * channels];
    out[i] = channels >= 3 ? Rgb(p[0], p[1], p[2]) : Rgb(p[0]);
  }
  return out;
}

Image read_image(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) throw InputError(file.string(), "", "image file not found");
  auto in = OIIO::ImageInput::open(file.string());
  if (!in) throw InputError(file.string(), "", fmt::format("cannot read image: {}", OIIO::geterror()));
  const OIIO::ImageSpec& spec = in->spec();
  Image img;
  img.width = spec.width;
  img.height = spec.height;
  img.channels = spec.nchannels;
  if (img.width <= 0 || img.height <= 0 || img.channels <= 0) throw InputError(file.string(), "", "image is empty");
  img.data.resize(static_cast<size_t>(img.width) * img.height * img.channels);
  if (!in->read_image(0, 0, 0, img.channels, OIIO::TypeDesc::FLOAT, img.data.data()))
    throw InputError(file.string(), "", fmt::format("cannot decode image: {}", in->geterror()));
  in->close();
  for (float& v : img.data)
    if (!std::isfinite(v)) throw InputError(file.string(), "", "image contains NaN or infinite values");
  return img;
}

bool is_supported_output(const std::filesystem::path& file) {
  const std::string e = lower_extension(file);
  return e == ".exr" || e == ".hdr" || e == ".png" || e == ".jpg" || e == ".jpeg";
}

void write_image(const std::filesystem::path& file, int width, int height, const std::vector<float>& rgb,
                 const ToneMap& tonemap) {
  const std::string ext = lower_extension(file);
  if (!is_supported_output(file))
    throw std::runtime_error(
        fmt::format("{}: unsupported output format '{}' (use .exr, .hdr, .png or .jpg)", file.string(), ext));
  std::filesystem::path dir = file.parent_path();
  if (!dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw std::runtime_error(fmt::format("{}: cannot create folder: {}", dir.string(), ec.message()));
  }
  // Same folder (so rename is atomic), same extension (OIIO picks the writer by it).
  const std::filesystem::path tmp =
      file.parent_path() / fmt::format(".{}.{}.tmp{}", file.stem().string(), static_cast<long>(getpid()), ext);

  auto out = OIIO::ImageOutput::create(file.string());
  if (!out)
    throw std::runtime_error(fmt::format("{}: cannot create image writer: {}", file.string(), OIIO::geterror()));
  bool ok;
  if (is_float_format(ext)) {
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::FLOAT);
    spec.attribute("compression", "zip");
    spec.attribute("Software", "kozu");
    ok = out->open(tmp.string(), spec) && out->write_image(OIIO::TypeDesc::FLOAT, rgb.data());
  } else {
    std::vector<uint8_t> ldr(rgb.size());
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        const size_t i = 3 * (static_cast<size_t>(y) * width + x);
        const Rgb mapped = tonemap.apply(Rgb(rgb[i], rgb[i + 1], rgb[i + 2]));
        // Triangular dither of +-1 code value, deterministic per pixel.
        const uint32_t h = hash_u32(static_cast<uint32_t>(y) * 0x9e3779b1U ^ static_cast<uint32_t>(x));
        const float d = (u32_to_unit_float(h) + u32_to_unit_float(hash_u32(h)) - 1.0f);
        for (int c = 0; c < 3; ++c) {
          const float v = srgb_encode(mapped[c]) * 255.0f + 0.5f + d;
          ldr[i + c] = static_cast<uint8_t>(std::clamp(v, 0.0f, 255.0f));
        }
      }
    }
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("Software", "kozu");
    ok = out->open(tmp.string(), spec) && out->write_image(OIIO::TypeDesc::UINT8, ldr.data());
  }
  std::string err = ok ? "" : out->geterror();
  if (!out->close() && ok) {
    ok = false;
    err = out->geterror();
  }
  out.reset();
  std::error_code ec;
  if (!ok) {
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error(fmt::format("{}: cannot write image: {}", file.string(), err));
  }
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error(fmt::format("{}: cannot move image into place: {}", file.string(), ec.message()));
  }
}

}  // namespace kozu
