#include "io/image_io.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/json_reader.h"
#include "core/load_cache.h"
#include "core/memory.h"
#include "core/rng.h"
#include "core/temp_files.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <system_error>

namespace kozu {

namespace {

bool is_float_format(const std::string& ext) { return ext == ".exr" || ext == ".hdr"; }

// OIIO's messages can be long (a whole decoder log): keep the first line, cut.
std::string text_of(const std::string& message) { return text_excerpt(message.substr(0, message.find('\n')), 200); }

}  // namespace

std::vector<Rgb> Image::to_rgb() const {
  std::vector<Rgb> out(static_cast<size_t>(width) * height);
  for (size_t i = 0; i < out.size(); ++i) {
    const float* p = &data[i * channels];
    out[i] = channels >= 3 ? Rgb(p[0], p[1], p[2]) : Rgb(p[0]);
  }
  return out;
}

// The size of a value of an OpenEXR attribute type that OpenEXR reads as a fixed number of bytes whatever size the
// header gives it (OpenEXR 3.1's typed attributes); nothing for the types whose readers go by that size (string,
// floatvector, opaque ones) or parse a layout of their own (chlist, stringvector, preview).
std::optional<uint64_t> exr_fixed_size(const std::string& type) {
  static const std::pair<const char*, uint64_t> kSizes[] = {
      {"box2i", 16},   {"box2f", 16},      {"v2i", 8},           {"v2f", 8},           {"v2d", 16},
      {"v3i", 12},     {"v3f", 12},        {"v3d", 24},          {"m33f", 36},         {"m33d", 72},
      {"m44f", 64},    {"m44d", 128},      {"int", 4},           {"float", 4},         {"double", 8},
      {"rational", 8}, {"compression", 1}, {"lineOrder", 1},     {"envmap", 1},        {"deepImageState", 1},
      {"tiledesc", 9}, {"keycode", 28},    {"timecode", 8},      {"chromaticities", 32}};
  for (const auto& [name, bytes] : kSizes)
    if (type == name) return bytes;
  return std::nullopt;
}

// OpenEXR sizes buffers from its header when a file is opened, before any check of ours could see the header
// through OpenImageIO: an attribute claiming gigabytes is allocated whole, and a data window of 2^31 lines gets a
// line-offset table of 16 GiB. So the header is walked here first (OpenEXR 2 file layout: magic, version, then
// per part the attributes name\0 type\0 int32-size value, ending with an empty name; multi-part files end
// with one more): every attribute must fit in the file, and every data window must hold at most kMaxImagePixels
// pixels. Values are skipped, not read, so a large preview or ICC profile costs nothing.
void check_exr_header(const std::filesystem::path& file, uint64_t file_bytes) {
  const auto fail = [&](const std::string& message) -> void {
    throw InputError(file.string(), "", "not a valid OpenEXR file: " + message);
  };
  std::ifstream in = open_input_file(file);
  uint64_t pos = 0;
  const auto read = [&](char* out, uint64_t n, const char* what) {
    if (pos + n > file_bytes) fail(fmt::format("{} at byte {} runs past the end of the file", what, pos));
    in.read(out, std::streamsize(n));
    if (!in) fail(fmt::format("cannot read {} at byte {}", what, pos));
    pos += n;
  };
  const auto u32 = [&](const char* what) {
    unsigned char b[4];
    read(reinterpret_cast<char*>(b), 4, what);
    return uint32_t{b[0]} | (uint32_t{b[1]} << 8) | (uint32_t{b[2]} << 16) | (uint32_t{b[3]} << 24);
  };
  // A null-terminated name of at most `longest` characters. OpenEXR reads a longer name differently (it stops at
  // the limit), so a walk that accepted one would check other attributes than OpenEXR then reads (a fuzzed file
  // made it allocate 2 GB that way).
  const auto name = [&](const char* what, size_t longest) {
    std::string n;
    for (char c = 1; c != '\0';) {
      read(&c, 1, what);
      if (c != '\0') n += c;
      if (n.size() > longest) fail(fmt::format("{} longer than {} characters at byte {}", what, longest, pos));
    }
    return n;
  };
  if (u32("the magic number") != 20000630u) fail("bad magic number");
  const uint32_t version = u32("the version");
  const bool multipart = (version & 0x1000u) != 0;
  // Attribute names and types: 31 characters, or 255 in files with the long-names flag; channel names always 255.
  const size_t max_name = (version & 0x400u) ? 255 : 31;
  for (int part = 0;; ++part) {
    if (part > 1000) fail("more than 1000 parts");
    bool empty = true;
    // What sizes the buffers OpenEXR makes when it opens the part (its compressor's, before any check after the
    // open could run): the data window's width, the bytes of a pixel over all channels, the compression, the tiles.
    uint64_t width = 0, pixel_bytes = 0, tile_pixels = 0;
    int compression = -1;
    for (;;) {
      const std::string attribute = name("an attribute name", max_name);
      if (attribute.empty()) break;
      empty = false;
      const std::string type = name("an attribute type", max_name);
      const uint32_t size = u32("an attribute size");
      if (size > file_bytes - pos)
        fail(fmt::format("attribute '{}' claims {} bytes, past the end of the file", text_excerpt(attribute), size));
      // OpenEXR reads some values by their own layout, not by the size the header gives them: a fixed-size type its
      // own bytes, a channel list names until an empty one, a string vector strings of their own lengths, a preview
      // width × height pixels. A value whose layout
      // disagrees with its size would have OpenEXR read the attributes after it from other bytes than this walk
      // does (a fuzzed channel list 3 bytes longer than its size made it allocate 1.9 GB), so they must agree.
      const auto claims = [&](uint64_t bytes) {
        if (size != bytes)
          fail(fmt::format("attribute '{}' of type '{}' takes {} byte{}, its header claims {}", text_excerpt(attribute),
                           text_excerpt(type), bytes, bytes == 1 ? "" : "s", size));
      };
      if (const auto fixed = exr_fixed_size(type)) {
        claims(*fixed);
      } else if (type == "chlist") {
        const uint64_t start = pos;
        for (;;) {
          if (name("a channel name", 255).empty()) break;
          char fields[16];  // pixel type, pLinear and 3 reserved bytes, x and y sampling
          read(fields, sizeof fields, "a channel's fields");
          pixel_bytes += fields[0] == 1 ? 2 : 4;  // HALF; UINT and FLOAT (and anything else, to be safe) 4
        }
        claims(pos - start);
        continue;
      } else if (type == "stringvector") {
        // Strings each with its own length, which OpenEXR allocates before reading: each must lie within the value.
        for (uint64_t used = 0; used < size;) {
          if (size - used < 4) claims(used + 4);
          const uint64_t length = u32("a string's length");
          if (length > size - used - 4)
            fail(fmt::format("a string of attribute '{}' claims {} bytes, past the end of its value",
                             text_excerpt(attribute), length));
          used += 4 + length;
          pos += length;
          in.seekg(std::streamoff(pos));
        }
        continue;
      } else if (type == "preview") {
        const uint64_t w = u32("the preview's width"), h = u32("the preview's height");
        claims(8 + 4 * w * h);
        pos += size - 8;
        in.seekg(std::streamoff(pos));
        continue;
      }
      if (attribute == "dataWindow" && type == "box2i") {  // 16 bytes, as claims() checked
        int32_t box[4];
        for (int32_t& v : box) v = static_cast<int32_t>(u32("the data window"));
        const int64_t w = int64_t(box[2]) - box[0] + 1, h = int64_t(box[3]) - box[1] + 1;
        if (w <= 0 || h <= 0) fail(fmt::format("empty data window {} x {}", w, h));
        if (uint64_t(w) * uint64_t(h) > kMaxImagePixels)
          throw InputError(file.string(), "",
                           fmt::format("{} x {} pixels exceeds the limit of {} pixels", w, h, kMaxImagePixels));
        width = uint64_t(w);
        continue;
      }
      if (attribute == "compression" && type == "compression") {
        char c;
        read(&c, 1, "the compression");
        compression = static_cast<unsigned char>(c);
        continue;
      }
      if (attribute == "tiles" && type == "tiledesc") {
        const uint64_t tw = u32("the tile width"), th = u32("the tile height");
        tile_pixels = tw * th;
        pos += 1;  // the level and rounding modes
        in.seekg(std::streamoff(pos));
        continue;
      }
      pos += size;
      in.seekg(std::streamoff(pos));
    }
    // OpenEXR's compressor holds a block of the file's lines (or a tile) twice, in and out, from the moment the part
    // is opened: a fuzzed 4-million-pixel-wide ZIP file made it allocate 1.1 GB there. Lines a block: none, RLE and
    // ZIPS 1; ZIP and PXR24 16; PIZ, B44, B44A and DWAA 32; DWAB (and any other value) 256.
    if (!empty) {
      static constexpr uint64_t kLines[] = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};
      const uint64_t lines = compression >= 0 && compression < 10 ? kLines[compression] : 256;
      const uint64_t block = 2 * pixel_bytes * (tile_pixels > 0 ? tile_pixels : width * lines);
      const MemoryLimit limit = memory_limit();
      const double left = memory_left(limit);
      // Blocks under 16 MiB are left to the checks after the open (they cannot threaten the memory; a process
      // already at its limit is told so by those, naming what it was reading).
      if (block >= (uint64_t(16) << 20) && static_cast<double>(block) > left)
        throw InputError(file.string(), "",
                         fmt::format("decoding it takes blocks of {}, more than is left of the {} limit ({})",
                                     format_bytes(double(block)), format_bytes(double(limit.bytes)), limit.source));
    }
    // A single-part file has one header; a multi-part one ends with an empty header.
    if (!multipart || empty) break;
  }
}

// libpng allocates a chunk's claimed length before reading it: a 445-byte file whose tEXt chunk claimed 1.9 GB cost
// 2 GB of allocations (found by fuzz_image). So the chunk list is walked first (PNG signature, then per chunk a
// big-endian length, a 4-letter type, the data and a CRC): every chunk must fit in the file, up to IEND. Data is
// skipped, not read.
void check_png_chunks(const std::filesystem::path& file, uint64_t file_bytes) {
  const auto fail = [&](const std::string& message) -> void {
    throw InputError(file.string(), "", "not a valid PNG file: " + message);
  };
  std::ifstream in = open_input_file(file);
  char signature[8];
  if (file_bytes < 8 || !in.read(signature, 8) || std::memcmp(signature, "\x89PNG\r\n\x1a\n", 8) != 0)
    fail("no PNG signature");
  uint64_t pos = 8;
  for (;;) {
    unsigned char head[8];
    if (pos + 12 > file_bytes || !in.read(reinterpret_cast<char*>(head), 8))
      fail(fmt::format("the chunk list ends at byte {} without IEND (truncated?)", pos));
    const uint64_t length = (uint64_t(head[0]) << 24) | (uint64_t(head[1]) << 16) | (uint64_t(head[2]) << 8) | head[3];
    std::string type(reinterpret_cast<const char*>(head + 4), 4);
    for (char& c : type)
      if (!std::isalpha(static_cast<unsigned char>(c))) c = '?';
    if (length > file_bytes - pos - 12)
      fail(fmt::format("chunk '{}' at byte {} claims {} bytes of a {}-byte file (truncated or corrupt)", type, pos,
                       length, file_bytes));
    if (type == "IEND") return;
    pos += 12 + length;
    in.seekg(std::streamoff(pos));
  }
}

namespace {

// Opens an image for reading after the checks every reader of an input image needs: a regular readable file, the
// reader of its extension only, a sane header (OpenEXR's and PNG's checked before their libraries allocate), at most
// kMaxImagePixels.
std::unique_ptr<OIIO::ImageInput> open_checked(const std::filesystem::path& file, uintmax_t* file_bytes) {
  const auto fail = [&](const std::string& message) -> void { throw InputError(file.string(), "", message); };
  std::error_code ec;
  // exists() is false too when the file cannot be looked at (a folder on its path without search permission):
  // that is not "not found", and the message says why.
  const std::filesystem::file_status st = std::filesystem::status(file, ec);
  if (ec && ec != std::errc::no_such_file_or_directory && ec != std::errc::not_a_directory)
    fail("cannot be read: " + ec.message());
  if (!std::filesystem::exists(st)) fail("image file not found");
  open_input_file(file);  // a regular, readable file (not a device or FIFO that OIIO would read forever)
  *file_bytes = std::filesystem::file_size(file, ec);
  if (ec) fail(fmt::format("cannot read image: {}", ec.message()));
  // The reader of the file's extension only: OpenImageIO would otherwise try every format it knows on a file
  // that fails (FFmpeg, GDAL and OpenCV probes among them), slow and a wide surface for a hostile file.
  const std::string ext = lower_extension(file);
  if (ext.empty()) fail("image file has no extension (kozu picks the reader by it)");
  if (ext == ".exr") check_exr_header(file, *file_bytes);
  if (ext == ".png") check_png_chunks(file, *file_bytes);
  auto in = OIIO::ImageInput::create(ext == ".tx" ? "tiff" : ext.substr(1));  // "exr": OIIO 2.4 takes no dot
  if (!in) fail(fmt::format("unsupported image format '{}'", ext));
  OIIO::ImageSpec opened;
  if (!in->open(file.string(), opened)) fail(fmt::format("cannot read image: {}", text_of(in->geterror())));
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) fail("image is empty");
  if (spec.depth > 1) fail("volume images are not supported");
  const uint64_t pixels = uint64_t(spec.width) * uint64_t(spec.height);
  if (pixels > kMaxImagePixels)
    fail(fmt::format("{} x {} pixels exceeds the limit of {} pixels", spec.width, spec.height, kMaxImagePixels));
  return in;
}

}  // namespace

ImageInfo probe_image(const std::filesystem::path& file) {
  uintmax_t file_bytes = 0;
  try {
    auto in = open_checked(file, &file_bytes);
    const OIIO::ImageSpec spec = in->spec();
    ImageInfo info;
    info.width = spec.width;
    info.height = spec.height;
    info.channels = spec.nchannels;
    info.bits = static_cast<int>(spec.format.size() * 8);
    info.is_float = spec.format.is_floating_point();
    info.tiled = spec.tile_width > 0;
    info.tile_width = spec.tile_width;
    info.tile_height = spec.tile_height;
    info.mip_levels = 1;
    OIIO::ImageSpec level;
    while (info.mip_levels < 64 && in->seek_subimage(0, info.mip_levels, level)) ++info.mip_levels;
    in->close();
    return info;
  } catch (const std::bad_alloc&) {
    throw InputError(file.string(), "",
                     "cannot decode image: its header asks for more memory than there is (corrupt?)");
  }
}

static Image read_image_checked(const std::filesystem::path& file, bool all_channels, bool read_pixels = true) {
  const auto fail = [&](const std::string& message) -> void { throw InputError(file.string(), "", message); };
  uintmax_t file_bytes = 0;
  auto in = open_checked(file, &file_bytes);
  const OIIO::ImageSpec& spec = in->spec();
  Image img;
  img.width = spec.width;
  img.height = spec.height;
  // Only the colour channels are read (and alpha, which to_rgb drops), unless all are asked for.
  img.channels = std::min(spec.nchannels, 4);
  if (all_channels) {
    if (spec.nchannels > kMaxImageChannels)
      fail(fmt::format("{} channels exceed the limit of {}", spec.nchannels, kMaxImageChannels));
    img.channels = spec.nchannels;
    for (int c = 0; c < spec.nchannels; ++c) img.channel_names.push_back(spec.channel_name(c));
    img.origin = {spec.x, spec.y};
    img.full_size = {spec.full_width, spec.full_height};
    for (const OIIO::ParamValue& p : spec.extra_attribs) {
      const std::string name = p.name().string();
      if (name.rfind("kozu:", 0) == 0 && p.type() == OIIO::TypeDesc::STRING)
        img.attributes.emplace_back(name, p.get_string());
      if (p.type() == OIIO::TypeMatrix44 && p.nvalues() == 1) {
        std::array<float, 16> m;
        std::copy_n(static_cast<const float*>(p.data()), 16, m.begin());
        img.matrices.emplace_back(name, m);
      }
    }
  }
  img.source_bits = static_cast<int>(spec.format.size() * 8);
  img.source_is_float = spec.format.is_floating_point();
  if (!read_pixels) return img;
  // The header's claims are checked before anything is allocated: the pixel cap (open_checked), the memory left,
  // and for uncompressed formats the file's own length.
  const uint64_t pixels = uint64_t(img.width) * uint64_t(img.height);
  const uint64_t bytes = pixels * uint64_t(img.channels) * sizeof(float);
  const MemoryLimit limit = memory_limit();
  const double left = memory_left(limit);
  if (static_cast<double>(bytes) > left)
    fail(fmt::format("{} x {} pixels need {}, more than is left of the {} limit ({})", img.width, img.height,
                     format_bytes(double(bytes)), format_bytes(double(limit.bytes)), limit.source));
  // A decoder reads whole blocks of scanlines in the file's own format (OpenEXR: up to 256 for DWAB compression)
  // whatever rows are asked: a forged 16-million-pixel-wide data window made it ask for 25 GB (found by fuzz_image).
  const uint64_t block_bytes =
      spec.tile_width > 0
          ? uint64_t(spec.tile_width) * uint64_t(std::max(1, spec.tile_height)) * uint64_t(spec.pixel_bytes(true))
          : uint64_t(img.width) * uint64_t(spec.pixel_bytes(true)) * 256u;
  if (static_cast<double>(bytes + block_bytes) > left)
    fail(fmt::format("{} x {} pixels: decoding them takes blocks of {} besides the image's {}, more than is left of "
                     "the {} limit ({})",
                     img.width, img.height, format_bytes(double(block_bytes)), format_bytes(double(bytes)),
                     format_bytes(double(limit.bytes)), limit.source));
  const std::string format = in->format_name();
  if (format == "pnm" || format == "pfm" || format == "bmp") {
    const uint64_t raw = pixels * uint64_t(spec.nchannels) * spec.format.size();
    if (raw > file_bytes)
      fail(fmt::format("truncated: a {} x {} {} image needs {} bytes of pixels, the file has {}", img.width, img.height,
                       format, raw, file_bytes));
  }
  // Rows grow with what decodes (bands of 64 scanlines, or one row of tiles), so a header that lies about a short
  // file costs little.
  const size_t row_floats = size_t(img.width) * size_t(img.channels);
  const int band = spec.tile_width > 0 ? std::max(1, spec.tile_height) : 64;
  // The capacity doubles, capped at the whole image: resize alone would double past it (a copy of up to 3 times
  // the image at the last step), reserve to the image's size makes the last copy at most 1.5 times it.
  const size_t total_floats = size_t(img.height) * row_floats;
  for (int y = 0; y < img.height; y += band) {
    const int rows = std::min(band, img.height - y);
    const size_t needed = size_t(y + rows) * row_floats;
    if (needed > img.data.capacity())
      img.data.reserve(std::min(total_floats, std::max(needed, 2 * img.data.capacity())));
    img.data.resize(needed);
    float* dst = img.data.data() + size_t(y) * row_floats;
    const bool ok =
        spec.tile_width > 0
            ? in->read_tiles(0, 0, spec.x, spec.x + img.width, spec.y + y, spec.y + y + rows, spec.z, spec.z + 1, 0,
                             img.channels, OIIO::TypeDesc::FLOAT, dst)
            : in->read_scanlines(0, 0, spec.y + y, spec.y + y + rows, 0, 0, img.channels, OIIO::TypeDesc::FLOAT, dst);
    if (!ok) fail(fmt::format("cannot decode image (row {}): {}", y, text_of(in->geterror())));
  }
  in->close();
  for (float& v : img.data)
    if (!std::isfinite(v)) fail("image contains NaN or infinite values");
  return img;
}

Image read_image(const std::filesystem::path& file) {
  // OpenEXR and the other decoders size some buffers from the header before any check of ours can see them: a
  // forged header can make them ask for more memory than there is.
  try {
    return cached_load<Image>("image", file, "", [&] { return read_image_checked(file, false); });
  } catch (const std::bad_alloc&) {
    throw InputError(file.string(), "",
                     "cannot decode image: its header asks for more memory than there is (corrupt?)");
  }
}

Image read_image_all(const std::filesystem::path& file) {
  try {
    return read_image_checked(file, true);
  } catch (const std::bad_alloc&) {
    throw InputError(file.string(), "",
                     "cannot decode image: its header asks for more memory than there is (corrupt?)");
  }
}

Image read_image_header(const std::filesystem::path& file) {
  try {
    return read_image_checked(file, true, false);
  } catch (const std::bad_alloc&) {
    throw InputError(file.string(), "",
                     "cannot decode image: its header asks for more memory than there is (corrupt?)");
  }
}

std::mutex& image_warning_mutex() {
  static std::mutex mutex;
  return mutex;
}

std::string NegativeValues::why_not_noise() const {
  return fmt::format(
      "its {} negative value{} {} {:.2g} of its energy and {} {:.2g} of its largest value (filtering noise, "
      "clamped to 0, carries at most 1e-4 and reaches at most 1e-3)",
      count, count == 1 ? "" : "s", count == 1 ? "carries" : "carry",
      positive_sum > 0 ? negative_sum / positive_sum : 1.0, count == 1 ? "reaches" : "reach",
      largest > 0 ? -most_negative / largest : 1.0);
}

uint64_t clamp_small_negatives(Image& img, const std::filesystem::path& file, int channels, const std::string& what) {
  const size_t nc = static_cast<size_t>(img.channels);
  const size_t checked = channels <= 0 ? nc : std::min(nc, static_cast<size_t>(channels));
  NegativeValues n;
  size_t worst = 0;
  for (size_t i = 0; i < img.data.size(); ++i) {
    if (i % nc >= checked) continue;
    const float v = img.data[i];
    if (v < 0.0f) {
      ++n.count;
      n.negative_sum -= v;
      if (v < n.most_negative) {
        n.most_negative = v;
        worst = i;
      }
    } else if (v > 0.0f) {
      n.positive_sum += v;
      n.largest = std::max(n.largest, double(v));
    }
  }
  if (!n.noise()) {
    const size_t pixel = worst / nc;
    throw InputError(
        file.string(), "",
        fmt::format("{} must be >= 0, and pixel ({}, {}) channel {} is {:g}: {}", what, pixel % size_t(img.width),
                    pixel / size_t(img.width), worst % nc, n.most_negative, n.why_not_noise()));
  }
  for (size_t i = 0; i < img.data.size(); ++i)
    if (i % nc < checked && img.data[i] < 0.0f) img.data[i] = 0.0f;
  return n.count;
}

ImageScan scan_image_values(const std::filesystem::path& file) {
  const auto fail = [&](const std::string& message) -> void { throw InputError(file.string(), "", message); };
  try {
    uintmax_t file_bytes = 0;
    auto in = open_checked(file, &file_bytes);
    ImageScan scan;
    std::vector<float> buf;
    for (int level = 0; level < 64; ++level) {
      if (level > 0 && !in->seek_subimage(0, level)) break;
      const OIIO::ImageSpec spec = in->spec();
      const int w = spec.width, h = spec.height, channels = std::min(spec.nchannels, 4);
      if (w <= 0 || h <= 0 || channels <= 0 || uint64_t(w) * uint64_t(h) > kMaxImagePixels || spec.depth > 1)
        fail(fmt::format("resolution level {} is {} x {} x {}: not a valid texture", level, w, h, spec.depth));
      const bool tiled = spec.tile_width > 0;
      const int band = tiled ? std::max(1, spec.tile_height) : 64;
      // A band of at most about 16 MiB of floats: whole tiles across (a tile's width at least), all rows of the band.
      const uint64_t tile_floats = uint64_t(tiled ? spec.tile_width : 1) * uint64_t(band) * uint64_t(channels);
      const int step =
          tiled ? int(std::min<uint64_t>(uint64_t(w), std::max<uint64_t>(1, (uint64_t{4} << 20) / tile_floats) *
                                                          uint64_t(spec.tile_width)))
                : w;
      buf.resize(size_t(step) * size_t(band) * size_t(channels));
      for (int y = 0; y < h; y += band) {
        const int rows = std::min(band, h - y);
        for (int x = 0; x < w; x += step) {
          const int cols = std::min(step, w - x);
          const bool ok = tiled ? in->read_tiles(0, level, spec.x + x, spec.x + x + cols, spec.y + y, spec.y + y + rows,
                                                 spec.z, spec.z + 1, 0, channels, OIIO::TypeDesc::FLOAT, buf.data())
                                : in->read_scanlines(0, level, spec.y + y, spec.y + y + rows, 0, 0, channels,
                                                     OIIO::TypeDesc::FLOAT, buf.data());
          if (!ok) fail(fmt::format("cannot decode image (level {}, row {}): {}", level, y, text_of(in->geterror())));
          for (size_t i = 0, n = size_t(cols) * size_t(rows) * size_t(channels); i < n; ++i) {
            const float v = buf[i];
            const auto where = [&] {
              const size_t pixel = i / size_t(channels);
              scan.x = x + int(pixel % size_t(cols));
              scan.y = y + int(pixel / size_t(cols));
              scan.level = level;
              scan.channel = int(i % size_t(channels));
            };
            if (!std::isfinite(v)) {
              if (scan.nonfinite++ == 0) where();
              continue;
            }
            if (level > 0) continue;
            ++scan.values;
            scan.sum += v;
            if (v > 0.0f) {
              scan.negatives.positive_sum += v;
              scan.negatives.largest = std::max(scan.negatives.largest, double(v));
            }
            if (v < 0.0f) {
              ++scan.negative;
              ++scan.negatives.count;
              scan.negatives.negative_sum -= v;
              scan.negatives.most_negative = std::min(scan.negatives.most_negative, double(v));
              if (v < scan.most_negative) {
                scan.most_negative = v;
                if (scan.nonfinite == 0) where();
              }
            }
          }
        }
      }
    }
    in->close();
    return scan;
  } catch (const std::bad_alloc&) {
    throw InputError(file.string(), "",
                     "cannot decode image: its header asks for more memory than there is (corrupt?)");
  }
}

bool is_supported_output(const std::filesystem::path& file) {
  const std::string e = lower_extension(file);
  return e == ".exr" || e == ".hdr" || e == ".png" || e == ".jpg" || e == ".jpeg";
}

void write_image(const std::filesystem::path& file, int width, int height, const std::vector<float>& rgb,
                 const ToneMap& tonemap) {
  write_image(file, width, height, rgb, tonemap, ImageExtras{});
}

void write_image(const std::filesystem::path& file, int width, int height, const std::vector<float>& rgb,
                 const ToneMap& tonemap, const ImageExtras& extras) {
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
  TempFileGuard tmp(temp_path_for(file));

  auto out = OIIO::ImageOutput::create(file.string());
  if (!out)
    throw std::runtime_error(fmt::format("{}: cannot create image writer: {}", file.string(), OIIO::geterror()));
  bool ok;
  if (ext == ".exr") {
    // R, G, B then the extra channels, interleaved.
    const int extra = static_cast<int>(extras.channels.size());
    const int channels = 3 + extra;
    OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::FLOAT);
    std::vector<std::string> names = {"R", "G", "B"};
    names.insert(names.end(), extras.channels.begin(), extras.channels.end());
    spec.channelnames = names;
    spec.x = extras.origin.x;
    spec.y = extras.origin.y;
    spec.full_x = spec.full_y = 0;
    spec.full_width = extras.full_size.x > 0 ? extras.full_size.x : width;
    spec.full_height = extras.full_size.y > 0 ? extras.full_size.y : height;
    spec.attribute("compression", extras.exr_compression);
    spec.attribute("Software", "kozu");
    for (const auto& [name, value] : extras.attributes) spec.attribute(name, value);
    // Imath's M44f is 16 floats, row-major: OIIO writes a TypeMatrix44 attribute as one.
    for (const auto& [name, m] : extras.matrices) spec.attribute(name, OIIO::TypeMatrix44, m.data());
    std::vector<float> pixels;
    const float* data = rgb.data();
    if (extra > 0) {
      const size_t n = static_cast<size_t>(width) * height;
      pixels.resize(n * channels);
      for (size_t i = 0; i < n; ++i) {
        std::copy_n(&rgb[3 * i], 3, &pixels[i * channels]);
        std::copy_n(&extras.data[i * extra], extra, &pixels[i * channels + 3]);
      }
      data = pixels.data();
    }
    ok = create_temp_file([&] { return out->open(tmp.path().string(), spec); }) &&
         out->write_image(OIIO::TypeDesc::FLOAT, data);
  } else if (is_float_format(ext)) {
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::FLOAT);
    spec.attribute("Software", "kozu");
    ok = create_temp_file([&] { return out->open(tmp.path().string(), spec); }) &&
         out->write_image(OIIO::TypeDesc::FLOAT, rgb.data());
  } else {
    std::vector<uint8_t> ldr(rgb.size());
    // Rows in parallel: the tone map is half of a PNG's write time.
    tbb::parallel_for(0, height, [&](int y) {
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
    });
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("Software", "kozu");
    // zlib level 3 instead of OIIO's 6: the demo's 1280x720 PNG in 0.16 s instead of 0.21 s (docs/production.md).
    if (ext == ".png") spec.attribute("png:compressionLevel", 3);
    ok = create_temp_file([&] { return out->open(tmp.path().string(), spec); }) &&
         out->write_image(OIIO::TypeDesc::UINT8, ldr.data());
  }
  std::string err = ok ? "" : out->geterror();
  if (!out->close() && ok) {
    ok = false;
    err = out->geterror();
  }
  out.reset();
  if (!ok) {
    // Writers rarely say why a write failed; a full disk is the common reason, so name it when it is the case.
    std::string why = text_of(err);
    std::error_code ec;
    const std::filesystem::space_info space =
        std::filesystem::space(file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path(), ec);
    const uint64_t raw = uint64_t(width) * uint64_t(height) * (is_float_format(ext) ? 12u : 3u);
    if (!ec && space.available < raw)
      why += fmt::format(" (no space left on device: {} free)", format_bytes(double(space.available)));
    throw std::runtime_error(fmt::format("{}: cannot write image: {}", file.string(), why));
  }
  rename_into_place(tmp, file);
}

void write_single_channel_exr(const std::filesystem::path& file, int width, int height,
                              const std::vector<float>& values,
                              const std::vector<std::pair<std::string, std::string>>& attributes) {
  TempFileGuard tmp(temp_path_for(file));
  auto out = OIIO::ImageOutput::create(file.string());
  if (!out)
    throw std::runtime_error(fmt::format("{}: cannot create image writer: {}", file.string(), OIIO::geterror()));
  OIIO::ImageSpec spec(width, height, 1, OIIO::TypeDesc::FLOAT);
  spec.channelnames = {"Y"};
  spec.attribute("compression", "zip");
  spec.attribute("Software", "kozu");
  for (const auto& [name, value] : attributes) spec.attribute(name, value);
  if (!create_temp_file([&] { return out->open(tmp.path().string(), spec); }) ||
      !out->write_image(OIIO::TypeDesc::FLOAT, values.data()) || !out->close())
    throw std::runtime_error(fmt::format("{}: cannot write: {}", file.string(), out->geterror()));
  out.reset();
  rename_into_place(tmp, file);
}

}  // namespace kozu
