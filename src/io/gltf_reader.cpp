#include "io/gltf_reader.h"

#include "core/json_path_walker.h"
#include "core/load_cache.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/input_bounds.h"
#include "core/memory.h"

#include <fmt/format.h>
#include <tiny_gltf.h>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <set>

namespace kozu {

namespace {

namespace fs = std::filesystem;
using tinygltf::Model;
using tinygltf::Value;

// The extensions whose content is imported (everything else in extensionsUsed is named in the warning).
const std::set<std::string> kSupportedExtensions = {"KHR_texture_transform", "KHR_materials_emissive_strength",
                                                    "KHR_materials_ior",     "KHR_materials_transmission",
                                                    "KHR_materials_volume",  "KHR_materials_clearcoat",
                                                    "KHR_materials_sheen",   "KHR_materials_specular",
                                                    "KHR_lights_punctual",   "KHR_mesh_quantization"};

// An accessor's elements may hold at most this many vertices or indices when no buffer bounds them (an accessor
// without a bufferView is all zeros).
constexpr size_t kMaxZeroAccessorCount = size_t{1} << 26;

// ---------------------------------------------------------------------------------------------
// The JSON before tinygltf sees it. tinygltf parses recursively (a document nested 30,000 deep overflows the
// stack), so the nesting depth is checked first with the scene parser's limit (kMaxJsonDepth); the same walk
// refuses negative offsets, lengths and counts (tinygltf reads them into unsigned integers) and notes which URIs
// name images, so that image files are not read whole here (the texture cache reads them once, later).

class JsonPrecheck : public JsonPathWalker {
 public:
  bool number_integer(number_integer_t x) { return number(double(x)); }
  bool number_float(number_float_t x, const string_t&) { return number(x); }
  bool string(string_t& s) {
    begin_value();
    // "/images/N/uri" and "/buffers/N/uri".
    const auto& levels = stack();
    if (levels.size() == 3 && !levels[1].object && levels[2].key == "uri") {
      if (levels[0].key == "images") image_uris.push_back(s);
      if (levels[0].key == "buffers") buffer_uris.push_back(s);
    }
    return true;
  }

  // The message of the walk's stop: a check's, or the parser's without nlohmann's "[json.exception...] " prefix.
  std::string error() const {
    if (!syntax_error()) return message();
    std::string m = parser_message();
    if (const auto p = m.find("] "); p != std::string::npos) m = m.substr(p + 2);
    return "invalid JSON: " + text_excerpt(m, 200);
  }

  std::vector<std::string> image_uris, buffer_uris;

 private:
  // Offsets, lengths, strides and counts of buffers, buffer views and accessors (sparse ones included).
  bool number(double x) {
    begin_value();
    const auto& levels = stack();
    if (x >= 0.0 || levels.empty() || !levels.back().object || levels.size() > 5) return true;
    static const std::set<std::string> kTop = {"buffers", "bufferViews", "accessors"};
    static const std::set<std::string> kKeys = {"byteOffset", "byteLength", "byteStride", "count"};
    if (!kTop.count(levels[0].key) || !kKeys.count(levels.back().key)) return true;
    for (const Level& l : levels)
      if (l.object && (l.key == "extras" || l.key == "extensions")) return true;
    return stop(fmt::format("{} must be >= 0, got {:g}", levels.back().key, x));
  }
};

// ---------------------------------------------------------------------------------------------
// Files and images: tinygltf reads through these callbacks, so every file gets kozu's size checks, is recorded
// as an input of the render, and no image is decoded or read whole.

// How many bytes of an image file are read to tell its format and whether it has alpha (the PNG chunks before
// the first IDAT: header, palette, transparency).
constexpr size_t kImageProbeBytes = 64 * 1024;

struct FsContext {
  std::set<fs::path> images;          // the external images' files (lexically normal)
  std::vector<fs::path> files;        // every file read, in order
  std::map<fs::path, uint64_t> size;  // their sizes
};

fs::path normal_path(const std::string& p) { return fs::path(p).lexically_normal(); }

// Reads `file` into *out: whole (its size checked against kozu's input limit and the memory left before the
// allocation), or at most `probe` bytes when probe > 0 (any size up to the input limit).
void read_file_bytes(const fs::path& file, std::vector<unsigned char>* out, size_t probe) {
  std::ifstream in = open_input_file(file);
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  if (size < 0 || !in) throw InputError(file.string(), "", "cannot determine the file size");
  // tinygltf takes buffer lengths as 32-bit integers.
  const uint64_t max_bytes = probe > 0 ? kMaxInputFileBytes : std::min<uint64_t>(kMaxInputFileBytes, UINT32_MAX);
  if (uint64_t(size) > max_bytes)
    throw InputError(file.string(), "",
                     fmt::format("the file is {}; kozu reads at most {} from one input file",
                                 format_bytes(double(size)), format_bytes(double(max_bytes))));
  const size_t n = probe > 0 ? std::min(size_t(size), probe) : size_t(size);
  const MemoryLimit limit = memory_limit();
  if (double(n) > memory_left(limit))
    throw InputError(file.string(), "",
                     fmt::format("the file is {}, more than is left of the {} memory limit ({})",
                                 format_bytes(double(size)), format_bytes(double(limit.bytes)), limit.source));
  out->resize(n);
  in.read(reinterpret_cast<char*>(out->data()), std::streamsize(n));
  if (size_t(in.gcount()) != n)
    throw InputError(file.string(), "", "read error: file ended early or could not be read");
}

bool fs_exists(const std::string& path, void*) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}
// tinygltf's default expands shell words (wordexp); a path in a file is taken literally.
std::string fs_expand(const std::string& path, void*) { return path; }
bool fs_read(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  auto& ctx = *static_cast<FsContext*>(user);
  try {
    const fs::path p = normal_path(path);
    // An image is only probed: the texture cache reads it, once, when the render needs it.
    read_file_bytes(p, out, ctx.images.count(p) ? kImageProbeBytes : 0);
    ctx.files.push_back(p);
    return true;
  } catch (const std::exception& e) {
    if (err) *err += std::string(e.what()) + "\n";
    return false;
  }
}
bool fs_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "writing is not supported\n";
  return false;
}

// What the image callback keeps of each image: its bytes when embedded, and whether it has an alpha channel.
struct ImageRecord {
  std::vector<unsigned char> bytes;  // embedded images only
  bool has_alpha = false;
  std::string extension;  // ".png", ".jpg", or "" when the format is not recognised
};

bool png_has_alpha(const unsigned char* b, size_t n) {
  if (n < 33) return false;
  const int color_type = b[25];
  if (color_type == 4 || color_type == 6) return true;
  // A palette or grey image is transparent with a tRNS chunk (before IDAT).
  for (size_t p = 8; p + 8 <= n;) {
    const uint32_t len = (uint32_t(b[p]) << 24) | (uint32_t(b[p + 1]) << 16) | (uint32_t(b[p + 2]) << 8) | b[p + 3];
    if (std::memcmp(b + p + 4, "tRNS", 4) == 0) return true;
    if (std::memcmp(b + p + 4, "IDAT", 4) == 0) return false;
    if (len > n) return false;
    p += 12 + size_t(len);
  }
  return false;
}

void classify_image(ImageRecord& r, const unsigned char* bytes, size_t n) {
  if (n >= 8 && std::memcmp(bytes, "\x89PNG\r\n\x1a\n", 8) == 0) {
    r.extension = ".png";
    r.has_alpha = png_has_alpha(bytes, n);
  } else if (n >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF) {
    r.extension = ".jpg";
  }
}

bool record_image(tinygltf::Image* image, const int index, std::string*, std::string*, int, int,
                  const unsigned char* bytes, int size, void* user) {
  auto& records = *static_cast<std::vector<ImageRecord>*>(user);
  if (index < 0) return false;
  if (records.size() <= size_t(index)) records.resize(size_t(index) + 1);
  ImageRecord& r = records[size_t(index)];
  // Images in a bufferView are read later from the checked buffer (tinygltf does not check the view's bounds).
  if (image->bufferView >= 0) return true;
  const size_t n = size > 0 ? size_t(size) : 0;
  classify_image(r, bytes, n);
  if (image->uri.empty()) r.bytes.assign(bytes, bytes + n);  // a data URI: written out later
  return true;
}

uint64_t fnv1a(const std::vector<unsigned char>& bytes) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
  return h;
}

// Percent-decoding of a relative URI (glTF §3.3.2: URIs are RFC 3986).
std::string uri_decode(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(static_cast<unsigned char>(s[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(s[i + 2]))) {
      out += static_cast<char>(std::stoi(s.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += s[i];
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Reading tinygltf's extension values.

const Value* ext_object(const tinygltf::ExtensionMap& m, const std::string& name) {
  const auto it = m.find(name);
  return it != m.end() && it->second.IsObject() ? &it->second : nullptr;
}
double num(const Value* o, const std::string& key, double def) {
  if (!o || !o->Has(key)) return def;
  const Value& v = o->Get(key);
  return v.IsNumber() ? v.GetNumberAsDouble() : def;
}
std::vector<double> nums(const Value* o, const std::string& key, std::vector<double> def) {
  if (!o || !o->Has(key)) return def;
  const Value& v = o->Get(key);
  if (!v.IsArray() || v.ArrayLen() != def.size()) return def;
  for (size_t i = 0; i < def.size(); ++i)
    if (v.Get(int(i)).IsNumber()) def[i] = v.Get(int(i)).GetNumberAsDouble();
  return def;
}
// A textureInfo object inside an extension: {index, texCoord, extensions}.
struct TexRef {
  int index = -1;
  int tex_coord = 0;
  const tinygltf::ExtensionMap* extensions = nullptr;
  tinygltf::ExtensionMap own;  // for references read from extension values
};
TexRef tex_ref(const tinygltf::TextureInfo& t) { return {t.index, t.texCoord, &t.extensions, {}}; }
TexRef tex_ref(const Value* o, const std::string& key) {
  TexRef r;
  if (!o || !o->Has(key) || !o->Get(key).IsObject()) return r;
  const Value& t = o->Get(key);
  r.index = static_cast<int>(num(&t, "index", -1));
  r.tex_coord = static_cast<int>(num(&t, "texCoord", 0));
  if (t.Has("extensions") && t.Get("extensions").IsObject()) {
    const Value& e = t.Get("extensions");
    for (const std::string& k : e.Keys()) r.own[k] = e.Get(k);
  }
  return r;
}

// ---------------------------------------------------------------------------------------------
// The importer.

class Importer {
 public:
  Importer(const fs::path& file, const GltfImportOptions& options) : file_(file), options_(options) {}

  GltfScene run() {
    load();
    // An extension the file requires changes what its data means (compressed meshes, other image formats):
    // without it the file cannot be read correctly (glTF 2.0 §3.12).
    std::string required;
    for (const std::string& e : model_.extensionsRequired)
      if (!kSupportedExtensions.count(e)) required += (required.empty() ? "" : ", ") + e;
    if (!required.empty()) fail("/extensionsRequired", "requires extensions kozu does not support: " + required);
    for (const std::string& e : model_.extensionsUsed)
      if (!kSupportedExtensions.count(e)) unsupported_[e] += 1;
    if (!model_.skins.empty()) unsupported_["skins"] += int(model_.skins.size());
    if (!model_.animations.empty()) unsupported_["animations"] += int(model_.animations.size());
    // Every accessor against its buffer view and buffer before anything is allocated for it.
    for (size_t i = 0; i < model_.accessors.size(); ++i) check_accessor(int(i));
    convert_materials();
    traverse_scene();
    convert_meshes();
    if (!unsupported_.empty()) {
      std::string list;
      // Extension names (upper case) first, then features with their counts, each alphabetically.
      for (const auto& [name, count] : unsupported_) {
        list += (list.empty() ? "" : ", ") + name;
        if (!is_extension_name(name)) list += fmt::format(" ({})", count);
      }
      out_.warnings.push_back(fmt::format("{}: not supported, ignored: {}", file_.filename().string(), list));
    }
    if (!clamped_.empty()) {
      // One warning for the file: the values kozu's models cannot represent, each with what it became.
      std::string list;
      size_t shown = 0;
      for (const auto& [path, what] : clamped_)
        if (shown++ < 8) list += (list.empty() ? "" : ", ") + path + " " + what;
      if (clamped_.size() > 8) list += fmt::format(" and {} more", clamped_.size() - 8);
      out_.warnings.push_back(fmt::format("{}: values beyond what kozu's models represent were clamped: {}",
                                          file_.filename().string(), list));
    }
    std::set<fs::path> seen;
    for (const fs::path& f : fs_.files)
      if (seen.insert(f).second) out_.input_files.push_back(f);
    for (const auto& [index, f] : image_files_)
      if (!model_.images[size_t(index)].uri.empty() && seen.insert(f).second) out_.input_files.push_back(f);
    return std::move(out_);
  }

 private:
  static bool is_extension_name(const std::string& s) {
    return !s.empty() && std::isupper(static_cast<unsigned char>(s[0])) && s.find('_') != std::string::npos;
  }
  [[noreturn]] void fail(const std::string& path, const std::string& message) const {
    throw InputError(file_.string(), path, message);
  }

  // The JSON text (the whole .gltf, or the JSON chunk of a .glb) checked before tinygltf parses it; a .glb must
  // be version 2 (glTF 2.0 §4.4.2).
  void precheck(const std::string& data, bool binary) {
    std::string_view json(data);
    if (binary) {
      if (data.size() < 20) return;  // tinygltf says what is wrong
      uint32_t version = 0, length = 0, type = 0;
      std::memcpy(&version, data.data() + 4, 4);
      std::memcpy(&length, data.data() + 12, 4);
      std::memcpy(&type, data.data() + 16, 4);
      if (version != 2) fail("", fmt::format("GLB version {}: kozu reads version 2 (glTF 2.0) only", version));
      if (type != 0x4E4F534A || uint64_t(length) > data.size() - 20) return;  // tinygltf says what is wrong
      json = json.substr(20, length);
    }
    // The JSON chunk may be padded with spaces (and, from some writers, NULs).
    while (!json.empty() && (json.back() == ' ' || json.back() == '\0')) json.remove_suffix(1);
    JsonPrecheck check;
    Json::sax_parse(json.begin(), json.end(), &check, nlohmann::detail::input_format_t::json, /*strict=*/true,
                    /*ignore_comments=*/false);
    if (check.failed()) fail(check.path(), check.error());
    fs::path base = file_.parent_path();
    for (const std::string& uri : check.image_uris)
      if (uri.rfind("data:", 0) != 0) fs_.images.insert((base / uri_decode(uri)).lexically_normal());
    // A file named both as a buffer and as an image is read whole.
    for (const std::string& uri : check.buffer_uris) fs_.images.erase((base / uri).lexically_normal());
  }

  void load() {
    const std::string data = read_input_file(file_, std::numeric_limits<uint32_t>::max());
    const bool binary = data.size() >= 4 && std::memcmp(data.data(), "glTF", 4) == 0;
    precheck(data, binary);
    tinygltf::TinyGLTF loader;
    loader.SetFsCallbacks({&fs_exists, &fs_expand, &fs_read, &fs_write, &fs_});
    loader.SetImageLoader(&record_image, &images_);
    std::string err, warn;
    fs::path base = file_.parent_path();
    if (base.empty()) base = ".";
    const bool ok =
        binary ? loader.LoadBinaryFromMemory(&model_, &err, &warn, reinterpret_cast<const unsigned char*>(data.data()),
                                             static_cast<unsigned>(data.size()), base.string())
               : loader.LoadASCIIFromString(&model_, &err, &warn, data.data(), static_cast<unsigned>(data.size()),
                                            base.string());
    if (!ok || model_.asset.version.empty()) {
      std::string message = err.empty() ? (warn.empty() ? "not a valid glTF 2.0 file" : warn) : err;
      while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) message.pop_back();
      std::replace(message.begin(), message.end(), '\n', ';');
      fail("", "invalid glTF: " + message);
    }
    // Buffers a glTF names must all be there (tinygltf leaves a missing .bin empty in some versions).
    for (size_t i = 0; i < model_.buffers.size(); ++i)
      if (model_.buffers[i].data.empty()) fail(fmt::format("/buffers/{}", i), "buffer has no data");
  }

  // --- accessors -------------------------------------------------------------------------------

  // The element bytes of accessor `index`, checked: the pointer to element 0, the stride, and the count; a null
  // pointer for an accessor without a bufferView (zeros).
  struct View {
    const unsigned char* data = nullptr;
    size_t stride = 0, count = 0;
    int component_type = 0, components = 0;
    bool normalized = false;
  };
  View view(int index, const std::string& use) const {
    const std::string path = fmt::format("/accessors/{}", index);
    if (index < 0 || size_t(index) >= model_.accessors.size())
      fail(use, fmt::format("accessor {} does not exist (the file has {})", index, model_.accessors.size()));
    const tinygltf::Accessor& a = model_.accessors[size_t(index)];
    View v;
    v.count = a.count;
    v.component_type = a.componentType;
    v.components = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type));
    v.normalized = a.normalized;
    const int csize = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.componentType));
    if (csize <= 0 || v.components <= 0) fail(path, "invalid componentType or type");
    const size_t elem = size_t(csize) * size_t(v.components);
    if (a.bufferView < 0) {
      if (a.count > kMaxZeroAccessorCount) fail(path, fmt::format("count {} is too large", a.count));
      return v;
    }
    const unsigned char* view_bytes = nullptr;
    const tinygltf::BufferView& bv = checked_view(a.bufferView, json_pointer_append(path, "bufferView"), &view_bytes);
    const std::string bv_path = fmt::format("/bufferViews/{}", a.bufferView);
    v.stride = bv.byteStride ? bv.byteStride : elem;
    if (v.stride < elem) fail(json_pointer_append(bv_path, "byteStride"), "byteStride is smaller than an element");
    // byteOffset + (count − 1) · stride + element size ≤ byteLength, without overflow.
    if (a.count > 0) {
      const size_t room = bv.byteLength;
      if (a.byteOffset > room || elem > room - a.byteOffset || (a.count - 1) > (room - a.byteOffset - elem) / v.stride)
        fail(path, fmt::format("byteOffset {} with {} elements of stride {} exceeds bufferView {} ({} bytes)",
                               a.byteOffset, a.count, v.stride, a.bufferView, bv.byteLength));
    }
    v.data = view_bytes + a.byteOffset;
    return v;
  }

  // Component c of element i as a float: floats as stored, normalized integers mapped to [0, 1] or [−1, 1]
  // (§3.11), other integers as their value (KHR_mesh_quantization).
  static float component(const View& v, size_t i, int c) {
    if (!v.data) return 0.0f;
    const unsigned char* p = v.data + i * v.stride;
    switch (v.component_type) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float x;
        std::memcpy(&x, p + 4 * c, 4);
        return x;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return v.normalized ? float(p[c]) / 255.0f : float(p[c]);
      case TINYGLTF_COMPONENT_TYPE_BYTE: {
        const auto x = static_cast<int8_t>(p[c]);
        return v.normalized ? std::max(float(x) / 127.0f, -1.0f) : float(x);
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t x;
        std::memcpy(&x, p + 2 * c, 2);
        return v.normalized ? float(x) / 65535.0f : float(x);
      }
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t x;
        std::memcpy(&x, p + 2 * c, 2);
        return v.normalized ? std::max(float(x) / 32767.0f, -1.0f) : float(x);
      }
      default:
        return 0.0f;
    }
  }

  // A float attribute of `components` per element: floats, or 8- and 16-bit integers, normalized or not (glTF
  // allows these for TEXCOORD, KHR_mesh_quantization for every attribute).
  std::vector<float> floats(int index, int components, const std::string& use) const {
    const View v = view(index, use);
    const std::string path = fmt::format("/accessors/{}", index);
    if (v.components != components)
      fail(path, fmt::format("{}: expected {} components, got {}", use, components, v.components));
    const int t = v.component_type;
    const bool ok = t == TINYGLTF_COMPONENT_TYPE_FLOAT || t == TINYGLTF_COMPONENT_TYPE_BYTE ||
                    t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || t == TINYGLTF_COMPONENT_TYPE_SHORT ||
                    t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    if (!ok) fail(path, fmt::format("{}: unsupported componentType {}", use, v.component_type));
    std::vector<float> out(v.count * size_t(components));
    for (size_t i = 0; i < v.count; ++i)
      for (int c = 0; c < components; ++c) {
        const float x = component(v, i, c);
        if (!std::isfinite(x)) fail(path, fmt::format("{}: element {} is not a finite number", use, i));
        out[i * size_t(components) + size_t(c)] = x;
      }
    apply_sparse(index, components, out, use);
    return out;
  }

  // Buffer view `index`, checked to exist and to lie within its buffer; *bytes gets its first byte. A missing
  // view is reported at `path` (where the index was read).
  const tinygltf::BufferView& checked_view(int index, const std::string& path, const unsigned char** bytes) const {
    if (index < 0 || size_t(index) >= model_.bufferViews.size())
      fail(path, fmt::format("bufferView {} does not exist", index));
    const tinygltf::BufferView& bv = model_.bufferViews[size_t(index)];
    const std::string bv_path = fmt::format("/bufferViews/{}", index);
    if (bv.buffer < 0 || size_t(bv.buffer) >= model_.buffers.size())
      fail(json_pointer_append(bv_path, "buffer"), fmt::format("buffer {} does not exist", bv.buffer));
    const std::vector<unsigned char>& buf = model_.buffers[size_t(bv.buffer)].data;
    if (bv.byteOffset > buf.size() || bv.byteLength > buf.size() - bv.byteOffset)
      fail(bv_path, fmt::format("byteOffset {} + byteLength {} exceed the buffer's {} bytes", bv.byteOffset,
                                bv.byteLength, buf.size()));
    *bytes = buf.data() + bv.byteOffset;
    return bv;
  }

  // The checked bytes [offset, offset + bytes) of buffer view `index`.
  const unsigned char* region(int index, size_t offset, size_t bytes, const std::string& path) const {
    const unsigned char* view_bytes = nullptr;
    const tinygltf::BufferView& bv = checked_view(index, path, &view_bytes);
    if (offset > bv.byteLength || bytes > bv.byteLength - offset)
      fail(path, fmt::format("byteOffset {} + {} bytes exceed bufferView {} ({} bytes)", offset, bytes, index,
                             bv.byteLength));
    return view_bytes + offset;
  }

  // The checked parts of a sparse accessor (§3.6.2.3): its indices' bytes and its values, tightly packed in the
  // accessor's own component type.
  struct Sparse {
    const unsigned char* indices = nullptr;
    int index_size = 0;
    View values;
  };
  Sparse sparse_view(int index, int components) const {
    const tinygltf::Accessor& a = model_.accessors[size_t(index)];
    const std::string path = fmt::format("/accessors/{}/sparse", index);
    if (a.sparse.count <= 0 || size_t(a.sparse.count) > a.count)
      fail(json_pointer_append(path, "count"), fmt::format("count {} is not in [1, {}]", a.sparse.count, a.count));
    const size_t n = size_t(a.sparse.count);
    Sparse s;
    s.index_size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.sparse.indices.componentType));
    const int csize = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.componentType));
    if (s.index_size <= 0 || csize <= 0 || a.sparse.indices.byteOffset < 0 || a.sparse.values.byteOffset < 0)
      fail(path, "invalid sparse indices or values");
    s.indices = region(a.sparse.indices.bufferView, size_t(a.sparse.indices.byteOffset), n * size_t(s.index_size),
                       path + "/indices");
    s.values.component_type = a.componentType;
    s.values.components = components;
    s.values.stride = size_t(csize) * size_t(components);
    s.values.count = n;
    s.values.data =
        region(a.sparse.values.bufferView, size_t(a.sparse.values.byteOffset), n * s.values.stride, path + "/values");
    return s;
  }

  // Accessor `index` checked whole before any of it is read: its elements lie within its buffer view, the view
  // within its buffer, and so do its sparse parts.
  void check_accessor(int index) const {
    const std::string path = fmt::format("/accessors/{}", index);
    const View v = view(index, path);
    if (model_.accessors[size_t(index)].sparse.isSparse) sparse_view(index, v.components);
  }

  // Sparse substitutions (§3.6.2.3): element indices[k] of accessor `index` takes the k-th of the values.
  void apply_sparse(int index, int components, std::vector<float>& out, const std::string& use) const {
    const tinygltf::Accessor& a = model_.accessors[size_t(index)];
    if (!a.sparse.isSparse) return;
    const std::string path = fmt::format("/accessors/{}/sparse", index);
    const Sparse s = sparse_view(index, components);
    for (size_t k = 0; k < s.values.count; ++k) {
      const uint32_t at =
          read_index(s.indices + k * size_t(s.index_size), a.sparse.indices.componentType, path + "/indices");
      if (at >= a.count) fail(path + "/indices", fmt::format("index {} is out of range (count {})", at, a.count));
      for (int c = 0; c < components; ++c) {
        const float x = component(s.values, k, c);
        if (!std::isfinite(x)) fail(path + "/values", fmt::format("{}: element {} is not a finite number", use, k));
        out[at * size_t(components) + size_t(c)] = x;
      }
    }
  }

  uint32_t read_index(const unsigned char* p, int component_type, const std::string& path) const {
    switch (component_type) {
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return p[0];
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t s;
        std::memcpy(&s, p, 2);
        return s;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t x;
        std::memcpy(&x, p, 4);
        return x;
      }
      default:
        fail(path, fmt::format("unsupported index componentType {}", component_type));
    }
  }

  std::vector<uint32_t> indices(int index, size_t vertex_count, const std::string& use) const {
    const View v = view(index, use);
    const std::string path = fmt::format("/accessors/{}", index);
    if (v.components != 1) fail(path, "indices must be scalars");
    if (model_.accessors[size_t(index)].sparse.isSparse) fail(path, "sparse index accessors are not supported");
    std::vector<uint32_t> out(v.count);
    for (size_t i = 0; i < v.count; ++i) {
      const uint32_t x = v.data ? read_index(v.data + i * v.stride, v.component_type, path) : 0;
      if (x >= vertex_count)
        fail(path,
             fmt::format("index {} (element {}) is out of range: the primitive has {} vertices", x, i, vertex_count));
      out[i] = x;
    }
    return out;
  }

  // --- textures and materials ------------------------------------------------------------------

  // The file an image is read from: its own for external images, else its bytes written once to image_dir.
  std::string image_file(int image_index) {
    if (auto it = image_files_.find(image_index); it != image_files_.end()) return it->second;
    const tinygltf::Image& img = model_.images[size_t(image_index)];
    fs::path path;
    if (!img.uri.empty()) {
      fs::path base = file_.parent_path();
      path = base / uri_decode(img.uri);
      // Refused here, before anything reads it, when it is larger than kozu reads (the texture cache reads it
      // once, later, and says what is wrong with a file that is missing or no image).
      std::error_code ec;
      if (fs::exists(path, ec)) {
        std::vector<unsigned char> probe;
        try {
          read_file_bytes(path, &probe, 1);
        } catch (const InputError& e) {
          fail(fmt::format("/images/{}/uri", image_index), e.what());
        }
      }
    } else {
      if (images_.size() <= size_t(image_index)) images_.resize(size_t(image_index) + 1);
      ImageRecord* r = &images_[size_t(image_index)];
      if (img.bufferView >= 0) read_view_image(img.bufferView, image_index, *r);
      if (r->bytes.empty()) fail(fmt::format("/images/{}", image_index), "image has no data");
      std::string ext = r->extension;
      if (ext.empty()) ext = img.mimeType == "image/jpeg" ? ".jpg" : img.mimeType == "image/png" ? ".png" : ".img";
      fs::path dir = options_.image_dir.empty() ? fs::temp_directory_path() / "kozu-gltf" : options_.image_dir;
      std::error_code ec;
      fs::create_directories(dir, ec);
      path = dir / fmt::format("{}-image{}-{:016x}{}", file_.stem().string(), image_index, fnv1a(r->bytes), ext);
      // The name holds the content's hash: a file already there with the same size is this image.
      if (!(fs::is_regular_file(path, ec) && fs::file_size(path, ec) == r->bytes.size())) {
        try {
          write_file_atomic(path, std::string(r->bytes.begin(), r->bytes.end()));
        } catch (const std::exception& e) {
          fail(fmt::format("/images/{}", image_index), e.what());
        }
      }
    }
    // Absolute: the description's paths would otherwise resolve against the glTF file's folder.
    std::error_code ec;
    path = fs::absolute(path, ec).lexically_normal();
    image_files_[image_index] = path.string();
    return path.string();
  }

  // The bytes of an image stored in a bufferView, within the checked bounds of its buffer.
  void read_view_image(int view_index, int image_index, ImageRecord& r) const {
    const std::string path = fmt::format("/images/{}/bufferView", image_index);
    if (size_t(view_index) >= model_.bufferViews.size())
      fail(path, fmt::format("bufferView {} does not exist", view_index));
    const tinygltf::BufferView& bv = model_.bufferViews[size_t(view_index)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= model_.buffers.size())
      fail(fmt::format("/bufferViews/{}/buffer", view_index), fmt::format("buffer {} does not exist", bv.buffer));
    const std::vector<unsigned char>& buf = model_.buffers[size_t(bv.buffer)].data;
    if (bv.byteOffset > buf.size() || bv.byteLength > buf.size() - bv.byteOffset)
      fail(fmt::format("/bufferViews/{}", view_index),
           fmt::format("byteOffset {} + byteLength {} exceed the buffer's {} bytes", bv.byteOffset, bv.byteLength,
                       buf.size()));
    r.bytes.assign(buf.begin() + std::ptrdiff_t(bv.byteOffset),
                   buf.begin() + std::ptrdiff_t(bv.byteOffset + bv.byteLength));
    classify_image(r, r.bytes.data(), r.bytes.size());
  }

  // Whether an image has an alpha channel (embedded images are read out first).
  bool image_has_alpha(int image_index) {
    const tinygltf::Image& img = model_.images[size_t(image_index)];
    if (img.uri.empty()) image_file(image_index);
    return size_t(image_index) < images_.size() && images_[size_t(image_index)].has_alpha;
  }

  // The image index of texture reference r, or -1 (and a warning) when kozu cannot use it.
  int texture_image(const TexRef& r, const std::string& path) {
    if (r.index < 0) return -1;
    if (size_t(r.index) >= model_.textures.size()) fail(path, fmt::format("texture {} does not exist", r.index));
    const tinygltf::Texture& t = model_.textures[size_t(r.index)];
    if (t.source < 0 || size_t(t.source) >= model_.images.size()) {
      unsupported_["textures without a PNG or JPEG source"] += 1;
      return -1;
    }
    const Value* tt = ext_object(r.extensions ? *r.extensions : r.own, "KHR_texture_transform");
    const int tex_coord = tt && tt->Has("texCoord") ? int(num(tt, "texCoord", 0)) : r.tex_coord;
    if (tex_coord != 0) {
      unsupported_["textures using TEXCOORD_1 or higher"] += 1;
      return -1;
    }
    if (t.sampler >= 0 && size_t(t.sampler) < model_.samplers.size()) {
      const tinygltf::Sampler& s = model_.samplers[size_t(t.sampler)];
      if (s.wrapS != TINYGLTF_TEXTURE_WRAP_REPEAT || s.wrapT != TINYGLTF_TEXTURE_WRAP_REPEAT)
        unsupported_["texture wrap modes other than REPEAT"] += 1;
    }
    return t.source;
  }

  // A value the file may give but kozu's model cannot represent becomes `to`, and the file's one warning names it.
  double clamp_note(const std::string& path, double x, double to) {
    clamped_[path] = fmt::format("{:g} → {:g}", x, to);
    return to;
  }
  // A glTF factor whose schema minimum is 0 (every factor in [0, 1] and specularColorFactor): below it the file
  // is invalid and refused; above 1 kozu's model has no meaning for it alone, and it is clamped.
  double unit_factor(double x, const std::string& path, bool clamp) {
    if (!(x >= 0.0)) fail(path, fmt::format("expected a number >= 0, got {:g}", x));
    return clamp && x > 1.0 ? clamp_note(path, x, 1.0) : x;
  }
  // Texture-transform values beyond kozu's ±1e6 (they repeat a texture a million times: a value that large is
  // no pattern a pixel can show).
  double transform_value(double x, const std::string& path) {
    return std::abs(x) > 1e6 ? clamp_note(path, x, std::copysign(1e6, x)) : x;
  }

  // A kozu image texture for reference r: channel ("" for RGB), colour space, scale (a number or [r, g, b]);
  // null when the texture cannot be used. last_image_ gets the image's index.
  Json texture(const TexRef& r, const std::string& path, const std::string& channel, const std::string& colorspace,
               const Json& scale) {
    last_image_ = texture_image(r, path);
    const int image = last_image_;
    if (image < 0) return nullptr;
    Json t = {{"type", "image"}, {"file", image_file(image)}, {"colorspace", colorspace}};
    if (!channel.empty()) t["channel"] = channel;
    if (!scale.is_null()) t["scale"] = scale;
    // KHR_texture_transform: glTF looks up uv' = T R S uv (offset o, rotation θ, scale s) in a space whose v runs
    // down the image. kozu's v runs up (v_k = 1 − v) and an image texture looks up (s, 1 − t) with
    // (s, t) = R(ρ) diag(su, sv) (u, v_k) + (ou, ov). Substituting v = 1 − v_k into the glTF map gives
    // su = sx, sv = sy, ρ = θ, ou = ox + sin θ · sy, ov = 1 − oy − cos θ · sy (docs/scene-format.md).
    const Value* tt = ext_object(r.extensions ? *r.extensions : r.own, "KHR_texture_transform");
    const std::string tp = path + "/extensions/KHR_texture_transform";
    std::vector<double> o = nums(tt, "offset", {0.0, 0.0}), s = nums(tt, "scale", {1.0, 1.0});
    for (size_t i = 0; i < 2; ++i) {
      o[i] = transform_value(o[i], fmt::format("{}/offset/{}", tp, i));
      s[i] = transform_value(s[i], fmt::format("{}/scale/{}", tp, i));
    }
    const double theta = transform_value(num(tt, "rotation", 0.0), tp + "/rotation");
    const double ou = o[0] + std::sin(theta) * s[1], ov = 1.0 - o[1] - std::cos(theta) * s[1];
    if (s[0] != 1.0 || s[1] != 1.0) t["uv_scale"] = {s[0], s[1]};
    if (ou != 0.0 || ov != 0.0) t["uv_offset"] = {ou, ov};
    if (theta != 0.0) t["uv_rotation"] = theta;
    return t;
  }

  static Json rgb_json(const std::vector<double>& c) { return Json::array({c[0], c[1], c[2]}); }
  static bool is_white(const std::vector<double>& c) { return c[0] == 1.0 && c[1] == 1.0 && c[2] == 1.0; }

  // The glTF paths of material key `key` (under the material being converted): its texture (and that texture's
  // image file) or its factor.
  void map_key(const std::string& key, const Json& tex, const std::string& tex_path, const std::string& factor_path) {
    const std::string k = mat_path_ + "/" + key;
    if (tex.is_null()) {
      out_.paths.emplace_back(k, factor_path);
      return;
    }
    out_.paths.emplace_back(k, tex_path);
    out_.paths.emplace_back(k + "/scale", factor_path);
    out_.paths.emplace_back(k + "/threshold", mat_path_ + "/alphaCutoff");
    if (last_image_ >= 0) {
      const tinygltf::Image& img = model_.images[size_t(last_image_)];
      out_.paths.emplace_back(k + "/file", fmt::format("/images/{}{}", last_image_, img.uri.empty() ? "" : "/uri"));
    }
  }

  // m[key] = texture × factor (the factor alone without a usable texture); left out when both are the default
  // (def NaN: always written). A factor alone is clamped to [0, 1]; a texture's scale may exceed 1 (kozu clamps
  // the product per lookup, as glTF does).
  void set_param(Json& m, const std::string& key, const Json& tex, const std::string& tex_path, double factor,
                 const std::string& factor_path, double def) {
    map_key(key, tex, tex_path, factor_path);
    factor = unit_factor(factor, factor_path, tex.is_null());
    if (!tex.is_null()) {
      m[key] = tex;
      if (factor != 1.0) m[key]["scale"] = factor;
    } else if (factor != def) {
      m[key] = factor;
    }
  }
  void set_rgb_param(Json& m, const std::string& key, const Json& tex, const std::string& tex_path,
                     std::vector<double> factor, const std::string& factor_path, double def) {
    map_key(key, tex, tex_path, factor_path);
    for (size_t c = 0; c < 3; ++c)
      factor[c] = unit_factor(factor[c], fmt::format("{}/{}", factor_path, c), tex.is_null());
    if (!tex.is_null()) {
      m[key] = tex;
      if (!is_white(factor)) m[key]["scale"] = rgb_json(factor);
    } else if (!(factor[0] == def && factor[1] == def && factor[2] == def)) {
      m[key] = rgb_json(factor);
    }
  }

  void convert_materials() {
    bool need_default = false;
    for (const tinygltf::Mesh& mesh : model_.meshes)
      for (const tinygltf::Primitive& p : mesh.primitives) need_default |= p.material < 0;
    const size_t n = model_.materials.size();
    for (size_t i = 0; i < n + (need_default ? 1 : 0); ++i) {
      const tinygltf::Material def;  // glTF's default material (§3.9.6): white, metallic 1, roughness 1
      const tinygltf::Material& mat = i < n ? model_.materials[i] : def;
      mat_path_ = fmt::format("/materials/{}", i);
      convert_material(mat, mat_path_);
      out_.material_names.push_back(i < n && !mat.name.empty() ? mat.name : fmt::format("material{}", i));
    }
    default_material_ = int(n);
  }

  // The base colour's texture and alpha, which the opacity reads again.
  struct BaseColor {
    TexRef ref;
    Json texture;
    double alpha = 1.0;
  };

  void convert_material(const tinygltf::Material& mat, const std::string& path) {
    Json m = {{"type", "standard"}};
    const BaseColor base = convert_metallic_roughness(mat, path, m);
    convert_normal_map(mat, path, m);
    if (mat.occlusionTexture.index >= 0) unsupported_["occlusion textures"] += 1;
    convert_alpha(mat, path, base, m);
    convert_emission(mat, path);
    convert_lobe_extensions(mat, path, m);
    convert_specular(mat, path, m);
    out_.media.push_back(convert_volume(mat, path));
    out_.materials.push_back(std::move(m));
  }

  // pbrMetallicRoughness (§3.9.2): base colour, metallic and roughness.
  BaseColor convert_metallic_roughness(const tinygltf::Material& mat, const std::string& path, Json& m) {
    constexpr double kAlways = std::numeric_limits<double>::quiet_NaN();
    const tinygltf::PbrMetallicRoughness& pbr = mat.pbrMetallicRoughness;
    const std::string pbr_path = path + "/pbrMetallicRoughness";
    std::vector<double> base = pbr.baseColorFactor;
    if (base.size() != 4) base = {1.0, 1.0, 1.0, 1.0};
    const TexRef base_ref = tex_ref(pbr.baseColorTexture);
    const Json base_tex = texture(base_ref, pbr_path + "/baseColorTexture", "", "srgb", nullptr);
    // base_color's default in kozu is 0.8; glTF's is 1, so it is always written.
    set_rgb_param(m, "base_color", base_tex, pbr_path + "/baseColorTexture", {base[0], base[1], base[2]},
                  pbr_path + "/baseColorFactor", kAlways);
    const double alpha = unit_factor(base[3], pbr_path + "/baseColorFactor/3", true);
    // Metallic in B, roughness in G of one linear texture (§3.9.2), times the factors.
    const TexRef mr_ref = tex_ref(pbr.metallicRoughnessTexture);
    const std::string mr_path = pbr_path + "/metallicRoughnessTexture";
    const Json mr_tex = texture(mr_ref, mr_path, "", "linear", nullptr);
    const auto channel = [](Json t, const char* c) {
      if (!t.is_null()) t["channel"] = c;
      return t;
    };
    // Both always written: kozu's defaults differ from glTF's.
    set_param(m, "metallic", channel(mr_tex, "b"), mr_path, pbr.metallicFactor, pbr_path + "/metallicFactor", kAlways);
    set_param(m, "roughness", channel(mr_tex, "g"), mr_path, pbr.roughnessFactor, pbr_path + "/roughnessFactor",
              kAlways);

    return {base_ref, base_tex, alpha};
  }

  void convert_normal_map(const tinygltf::Material& mat, const std::string& path, Json& m) {
    if (mat.normalTexture.index >= 0) {
      TexRef r{mat.normalTexture.index, mat.normalTexture.texCoord, &mat.normalTexture.extensions, {}};
      const Json t = texture(r, path + "/normalTexture", "", "linear", nullptr);
      if (!t.is_null()) {
        map_key("normal_map", t, path + "/normalTexture", path + "/normalTexture/scale");
        m["normal_map"] = t;
        out_.paths.emplace_back(path + "/normal_map_strength", path + "/normalTexture/scale");
        // A negative scale (legal glTF) would turn the normals inside out; kozu's strength is >= 0.
        double strength = mat.normalTexture.scale;
        if (strength < 0.0) strength = clamp_note(path + "/normalTexture/scale", strength, 0.0);
        if (strength != 1.0) m["normal_map_strength"] = strength;
      }
    }
  }

  void convert_alpha(const tinygltf::Material& mat, const std::string& path, const BaseColor& base, Json& m) {
    const std::string pbr_path = path + "/pbrMetallicRoughness";
    const Json& base_tex = base.texture;
    const TexRef& base_ref = base.ref;
    const double alpha = base.alpha;
    // Alpha (§3.9.4): OPAQUE ignores it; BLEND takes the base colour's alpha (texture × factor) as opacity, MASK
    // makes it 1 where that alpha reaches alphaCutoff and 0 elsewhere.
    if (mat.alphaMode == "BLEND" || mat.alphaMode == "MASK") {
      const bool mask = mat.alphaMode == "MASK";
      if (mask && !(mat.alphaCutoff >= 0.0))
        fail(path + "/alphaCutoff", fmt::format("expected a number >= 0, got {:g}", mat.alphaCutoff));
      const int image = base_tex.is_null() ? -1 : model_.textures[size_t(base_ref.index)].source;
      if (image >= 0 && image_has_alpha(image)) {
        Json t = base_tex;
        t["channel"] = "a";
        t["colorspace"] = "linear";  // alpha is never sRGB-encoded
        t.erase("scale");
        if (alpha != 1.0) t["scale"] = alpha;
        if (mask) t["threshold"] = mat.alphaCutoff;
        last_image_ = image;
        map_key("opacity", t, pbr_path + "/baseColorTexture", pbr_path + "/baseColorFactor/3");
        m["opacity"] = t;
      } else if (mask) {
        if (alpha < mat.alphaCutoff) m["opacity"] = 0.0;
      } else if (alpha != 1.0) {
        m["opacity"] = alpha;
      }
      if (!m.contains("opacity") || !m["opacity"].is_object())
        out_.paths.emplace_back(path + "/opacity", pbr_path + "/baseColorFactor/3");
    }
  }

  void convert_emission(const tinygltf::Material& mat, const std::string& path) {
    // Emission: the factor × KHR_materials_emissive_strength, constant over the shape. Negative values (invalid
    // glTF) would give negative radiance and NaN samples.
    std::vector<double> emissive = mat.emissiveFactor.size() == 3 ? mat.emissiveFactor : std::vector<double>{0, 0, 0};
    const std::string strength_path = path + "/extensions/KHR_materials_emissive_strength/emissiveStrength";
    const double strength = num(ext_object(mat.extensions, "KHR_materials_emissive_strength"), "emissiveStrength", 1.0);
    if (!(strength >= 0.0)) fail(strength_path, fmt::format("expected a number >= 0, got {:g}", strength));
    for (size_t c = 0; c < 3; ++c) {
      const std::string cp = fmt::format("{}/emissiveFactor/{}", path, c);
      if (!(emissive[c] >= 0.0)) fail(cp, fmt::format("expected a number >= 0, got {:g}", emissive[c]));
      if (emissive[c] * strength > kMaxRadiance)
        fail(emissive[c] > 1.0 ? cp : strength_path,
             fmt::format("the emitted radiance {:g} is beyond kozu's range (at most {:g})", emissive[c] * strength,
                         kMaxRadiance));
    }
    if (mat.emissiveTexture.index >= 0) unsupported_["emissive textures (the factor is used alone)"] += 1;
    out_.double_sided.push_back(mat.doubleSided);
    out_.emission.push_back(
        Rgb(float(emissive[0] * strength), float(emissive[1] * strength), float(emissive[2] * strength)));
    emission_paths_.push_back(strength != 1.0 ? strength_path : path + "/emissiveFactor");
  }

  // KHR_materials_ior, _transmission, _clearcoat and _sheen.
  void convert_lobe_extensions(const tinygltf::Material& mat, const std::string& path, Json& m) {
    if (const Value* e = ext_object(mat.extensions, "KHR_materials_ior")) {
      // kozu's tables cover [1, 3]; 0 (a perfect mirror in later revisions of the extension) and denser media are
      // clamped to 3.
      const std::string p = path + "/extensions/KHR_materials_ior/ior";
      double ior = num(e, "ior", 1.5);
      if (ior != 0.0 && !(ior >= 1.0)) fail(p, fmt::format("expected a number >= 1, got {:g}", ior));
      if (ior == 0.0 || ior > 3.0) ior = clamp_note(p, ior, 3.0);
      out_.paths.emplace_back(path + "/ior", p);
      m["ior"] = ior;
    }
    if (const Value* e = ext_object(mat.extensions, "KHR_materials_transmission")) {
      const std::string p = path + "/extensions/KHR_materials_transmission";
      set_param(m, "transmission",
                texture(tex_ref(e, "transmissionTexture"), p + "/transmissionTexture", "r", "linear", nullptr),
                p + "/transmissionTexture", num(e, "transmissionFactor", 0.0), p + "/transmissionFactor", 0.0);
    }
    if (const Value* e = ext_object(mat.extensions, "KHR_materials_clearcoat")) {
      const std::string p = path + "/extensions/KHR_materials_clearcoat";
      set_param(m, "clearcoat",
                texture(tex_ref(e, "clearcoatTexture"), p + "/clearcoatTexture", "r", "linear", nullptr),
                p + "/clearcoatTexture", num(e, "clearcoatFactor", 0.0), p + "/clearcoatFactor", 0.0);
      set_param(
          m, "clearcoat_roughness",
          texture(tex_ref(e, "clearcoatRoughnessTexture"), p + "/clearcoatRoughnessTexture", "g", "linear", nullptr),
          p + "/clearcoatRoughnessTexture", num(e, "clearcoatRoughnessFactor", 0.0), p + "/clearcoatRoughnessFactor",
          0.0);
      if (tex_ref(e, "clearcoatNormalTexture").index >= 0) unsupported_["clearcoat normal textures"] += 1;
    }
    if (const Value* e = ext_object(mat.extensions, "KHR_materials_sheen")) {
      const std::string p = path + "/extensions/KHR_materials_sheen";
      set_rgb_param(
          m, "sheen_color", texture(tex_ref(e, "sheenColorTexture"), p + "/sheenColorTexture", "", "srgb", nullptr),
          p + "/sheenColorTexture", nums(e, "sheenColorFactor", {0.0, 0.0, 0.0}), p + "/sheenColorFactor", 0.0);
      // The sheen roughness is in the texture's alpha channel (KHR_materials_sheen).
      set_param(m, "sheen_roughness",
                texture(tex_ref(e, "sheenRoughnessTexture"), p + "/sheenRoughnessTexture", "a", "linear", nullptr),
                p + "/sheenRoughnessTexture", num(e, "sheenRoughnessFactor", 0.0), p + "/sheenRoughnessFactor", 0.0);
    }
  }

  void convert_specular(const tinygltf::Material& mat, const std::string& path, Json& m) {
    if (const Value* e = ext_object(mat.extensions, "KHR_materials_specular")) {
      const std::string p = path + "/extensions/KHR_materials_specular";
      // The specular strength is in the texture's alpha channel (KHR_materials_specular).
      const Json spec_tex = texture(tex_ref(e, "specularTexture"), p + "/specularTexture", "a", "linear", nullptr);
      const int spec_image = last_image_;
      const Json color_tex =
          texture(tex_ref(e, "specularColorTexture"), p + "/specularColorTexture", "", "srgb", nullptr);
      double factor = num(e, "specularFactor", 1.0);
      std::vector<double> color = nums(e, "specularColorFactor", {1.0, 1.0, 1.0});
      for (size_t c = 0; c < 3; ++c) unit_factor(color[c], fmt::format("{}/specularColorFactor/{}", p, c), false);
      unit_factor(factor, p + "/specularFactor", false);
      // specularColorFactor has no maximum (Blender writes values above 1), but kozu's model uses only the
      // product specular × specular_color, clamped to 1 per channel: a constant colour above 1 is carried into
      // the factor (exact while the product stays within 1), and what is left above 1 is clamped.
      const double peak = std::max({color[0], color[1], color[2]});
      if (color_tex.is_null() && peak > 1.0) {
        for (double& c : color) c /= peak;
        factor *= peak;
        if (spec_tex.is_null() && factor > 1.0) factor = clamp_note(p + "/specularColorFactor", factor, 1.0);
      }
      const int color_image = last_image_;
      last_image_ = spec_image;
      set_param(m, "specular", spec_tex, p + "/specularTexture", factor, p + "/specularFactor", 1.0);
      last_image_ = color_image;
      set_rgb_param(m, "specular_color", color_tex, p + "/specularColorTexture", color, p + "/specularColorFactor",
                    1.0);
    }
  }

  Json convert_volume(const tinygltf::Material& mat, const std::string& path) {
    // KHR_materials_volume: the attenuation of Beer's law, σa = −ln(c) / d per channel (the extension's
    // definition), becomes an absorbing homogeneous medium inside the mesh; the thickness factor is a raster
    // approximation that tracing the real geometry makes unnecessary.
    Json medium = nullptr;
    if (const Value* e = ext_object(mat.extensions, "KHR_materials_volume")) {
      const std::string p = path + "/extensions/KHR_materials_volume";
      const double d = num(e, "attenuationDistance", std::numeric_limits<double>::infinity());
      if (!(d > 0.0)) fail(p + "/attenuationDistance", fmt::format("expected a number > 0, got {:g}", d));
      std::vector<double> c = nums(e, "attenuationColor", {1.0, 1.0, 1.0});
      for (size_t i = 0; i < 3; ++i) c[i] = unit_factor(c[i], fmt::format("{}/attenuationColor/{}", p, i), true);
      out_.paths.emplace_back(p + "/density", p + "/attenuationDistance");
      if (std::isfinite(d) && !is_white(c)) {
        Json sigma = Json::array();
        for (double x : c) sigma.push_back(-std::log(std::clamp(x, 1e-6, 1.0)) / d);
        medium = {{"type", "homogeneous"}, {"density", sigma}, {"albedo", 0.0}};
      }
    }
    return medium;
  }

  // --- nodes, meshes, lights, cameras ----------------------------------------------------------

  // A node's local transform: its matrix (affine: glTF 2.0 §3.5.3 requires it) or T·R·S.
  Mat4 local_matrix(const tinygltf::Node& n, const std::string& path) const {
    const auto finite = [&](const std::vector<double>& v, const char* key) {
      for (size_t i = 0; i < v.size(); ++i)
        if (!(std::abs(v[i]) <= 3.4e38))
          fail(fmt::format("{}/{}/{}", path, key, i),
               fmt::format("expected a number of magnitude below 3.4e38, got {:g}", v[i]));
    };
    if (n.matrix.size() == 16) {
      finite(n.matrix, "matrix");
      // Column-major: the last row is elements 3, 7, 11 and 15.
      const double* m = n.matrix.data();
      if (m[3] != 0.0 || m[7] != 0.0 || m[11] != 0.0 || m[15] != 1.0)
        fail(path + "/matrix", fmt::format("the matrix is not affine: its last row is ({:g}, {:g}, {:g}, {:g}), not "
                                           "(0, 0, 0, 1)",
                                           m[3], m[7], m[11], m[15]));
      Mat4 r;
      for (int c = 0; c < 4; ++c)
        for (int k = 0; k < 4; ++k) r[c][k] = float(n.matrix[size_t(c * 4 + k)]);  // column-major (§3.5.3)
      return r;
    }
    finite(n.translation, "translation");
    finite(n.rotation, "rotation");
    finite(n.scale, "scale");
    Mat4 t(1.0f), r(1.0f), s(1.0f);
    if (n.translation.size() == 3)
      t = glm::translate(Mat4(1.0f), Vec3(float(n.translation[0]), float(n.translation[1]), float(n.translation[2])));
    if (n.rotation.size() == 4) {
      // glTF stores the unit quaternion as (x, y, z, w); glm's constructor takes (w, x, y, z).
      const glm::quat q(float(n.rotation[3]), float(n.rotation[0]), float(n.rotation[1]), float(n.rotation[2]));
      if (!(glm::length(q) > 0.0f)) fail(path + "/rotation", "the rotation quaternion has length 0");
      r = glm::mat4_cast(glm::normalize(q));
    }
    if (n.scale.size() == 3) s = glm::scale(Mat4(1.0f), Vec3(float(n.scale[0]), float(n.scale[1]), float(n.scale[2])));
    return t * r * s;  // T · R · S (§3.5.3)
  }

  // The scene's nodes, walked depth first without recursion (a chain of 10,000 nodes is as cheap as a flat
  // list): cameras and lights are converted at once, mesh uses are collected for convert_meshes.
  void traverse_scene() {
    std::vector<int> roots;
    const bool scenes = !model_.scenes.empty();
    if (scenes) {
      int s = model_.defaultScene >= 0 ? model_.defaultScene : 0;
      if (size_t(s) >= model_.scenes.size()) fail("/scene", fmt::format("scene {} does not exist", s));
      roots = model_.scenes[size_t(s)].nodes;
      if (model_.scenes.size() > 1) unsupported_["scenes other than the default"] += int(model_.scenes.size()) - 1;
    } else {
      // No scenes: every node that is nobody's child.
      std::vector<bool> child(model_.nodes.size(), false);
      for (const tinygltf::Node& n : model_.nodes)
        for (int c : n.children)
          if (c >= 0 && size_t(c) < child.size()) child[size_t(c)] = true;
      for (size_t i = 0; i < child.size(); ++i)
        if (!child[i]) roots.push_back(int(i));
    }
    visited_.assign(model_.nodes.size(), false);
    struct Pending {
      int node;
      Mat4 parent;
      std::string from;  // where the index was read, for a node that does not exist
    };
    std::vector<Pending> stack;
    for (size_t i = roots.size(); i-- > 0;)
      stack.push_back(
          {roots[i], options_.root, fmt::format("/scenes/{}/nodes/{}", std::max(model_.defaultScene, 0), i)});
    while (!stack.empty()) {
      const Pending p = std::move(stack.back());
      stack.pop_back();
      const int index = p.node;
      if (index < 0 || size_t(index) >= model_.nodes.size())
        fail(p.from, fmt::format("node {} does not exist (the file has {})", index, model_.nodes.size()));
      const std::string path = fmt::format("/nodes/{}", index);
      // The hierarchy is a forest (§3.5.2): a node reached twice is a cycle or a shared child.
      if (visited_[size_t(index)]) fail(path, "node is reached twice (the node hierarchy must be a tree)");
      visited_[size_t(index)] = true;
      const tinygltf::Node& n = model_.nodes[size_t(index)];
      const Mat4 world = p.parent * local_matrix(n, path);
      if (n.mesh >= 0) {
        if (size_t(n.mesh) >= model_.meshes.size()) fail(path + "/mesh", fmt::format("mesh {} does not exist", n.mesh));
        mesh_uses_.push_back({n.mesh, world, path});
      }
      if (n.camera >= 0) add_camera(n.camera, world, path);
      if (const Value* e = ext_object(n.extensions, "KHR_lights_punctual"))
        add_light(int(num(e, "light", -1)), world, path + "/extensions/KHR_lights_punctual/light");
      for (size_t c = n.children.size(); c-- > 0;)
        stack.push_back({n.children[c], world, fmt::format("{}/children/{}", path, c)});
    }
    // Without scenes, a node nobody reached has a parent nobody reached, and so on: the nodes form a cycle.
    if (!scenes)
      for (size_t i = 0; i < visited_.size(); ++i)
        if (!visited_[i])
          fail(fmt::format("/nodes/{}/children", i),
               "the node is part of a cycle of children (the node hierarchy must be a tree)");
    if (cameras_seen_ > 1) unsupported_["cameras beyond the first"] += cameras_seen_ - 1;
  }

  // Whether a primitive draws triangles (points and lines are left out, with a warning).
  static bool is_triangles(const tinygltf::Primitive& p) {
    const int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
    return mode == TINYGLTF_MODE_TRIANGLES || mode == TINYGLTF_MODE_TRIANGLE_STRIP ||
           mode == TINYGLTF_MODE_TRIANGLE_FAN;
  }
  int material_of(const tinygltf::Primitive& p) const { return p.material >= 0 ? p.material : default_material_; }
  bool mesh_emits(int mesh) const {
    for (const tinygltf::Primitive& p : model_.meshes[size_t(mesh)].primitives) {
      const int m = material_of(p);
      if (m >= 0 && size_t(m) < out_.emission.size() && !is_black(out_.emission[size_t(m)])) return true;
    }
    return false;
  }

  // The bytes converting mesh `mesh` once keeps (vertices, indices, and Embree's hierarchy over its triangles,
  // about 64 bytes a triangle) and the most its conversion holds at once besides (one primitive's accessor
  // copies).
  void mesh_bytes(int mesh, double* kept, double* peak) const {
    *kept = 0.0;
    *peak = 0.0;
    for (const tinygltf::Primitive& p : model_.meshes[size_t(mesh)].primitives) {
      if (!is_triangles(p)) continue;
      const auto pos = p.attributes.find("POSITION");
      if (pos == p.attributes.end() || pos->second < 0 || size_t(pos->second) >= model_.accessors.size()) continue;
      const double nv = double(model_.accessors[size_t(pos->second)].count);
      double ni = nv;
      if (p.indices >= 0 && size_t(p.indices) < model_.accessors.size())
        ni = double(model_.accessors[size_t(p.indices)].count);
      const int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
      const double tri_indices = mode == TINYGLTF_MODE_TRIANGLES ? ni : 3.0 * std::max(ni - 2.0, 0.0);
      // Position, normal, tangent, uv: 48 bytes a vertex; 4 an index; 64 a triangle for the hierarchy.
      *kept += 48.0 * nv + 4.0 * tri_indices + 64.0 / 3.0 * tri_indices;
      *peak = std::max(*peak, 48.0 * nv + 4.0 * ni);
    }
  }

  // Meshes used by one node (or emitting) become world-space primitives; meshes used by several nodes become
  // one object each, placed by instances. The memory all of it takes is estimated and checked first.
  void convert_meshes() {
    std::vector<int> uses(model_.meshes.size(), 0);
    for (const MeshUse& u : mesh_uses_) ++uses[size_t(u.mesh)];
    std::vector<int> object_of(model_.meshes.size(), -1);
    double total = 0.0, peak = 0.0;
    for (size_t m = 0; m < model_.meshes.size(); ++m) {
      if (uses[m] == 0) continue;
      const bool instanced = options_.instance_meshes && uses[m] > 1 && !mesh_emits(int(m));
      double kept = 0.0, most = 0.0;
      mesh_bytes(int(m), &kept, &most);
      total += kept * (instanced ? 1.0 : double(uses[m]));
      peak = std::max(peak, most);
      if (instanced) object_of[m] = 0;
    }
    const MemoryLimit limit = memory_limit();
    const double left = memory_left(limit);
    if (total + peak > left)
      fail("/meshes",
           fmt::format("the meshes need about {} in memory ({} mesh placements), more than is left of "
                       "the {} memory limit ({})",
                       format_bytes(total + peak), mesh_uses_.size(), format_bytes(double(limit.bytes)), limit.source));
    for (size_t m = 0; m < model_.meshes.size(); ++m) {
      if (object_of[m] < 0) continue;
      object_of[m] = int(out_.objects.size());
      GltfObject o;
      o.name = model_.meshes[m].name.empty() ? fmt::format("mesh {}", m) : model_.meshes[m].name;
      convert_mesh(int(m), Mat4(1.0f), "", o.primitives);
      out_.objects.push_back(std::move(o));
    }
    for (const MeshUse& u : mesh_uses_) {
      if (object_of[size_t(u.mesh)] < 0) {
        convert_mesh(u.mesh, u.world, u.node_path, out_.primitives);
        continue;
      }
      const GltfObject& o = out_.objects[size_t(object_of[size_t(u.mesh)])];
      // The placed mesh's corners must stay within kozu's coordinates, as copied vertices must.
      Vec3 lo(kInfinity), hi(-kInfinity);
      for (const GltfPrimitive& p : o.primitives)
        for (const Vec3& v : p.mesh.positions) {
          lo = glm::min(lo, v);
          hi = glm::max(hi, v);
        }
      for (int c = 0; c < 8 && lo.x <= hi.x; ++c) {
        const Vec3 corner(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z);
        const Vec3 w(u.world * Vec4(corner, 1.0f));
        if (!is_finite(w) || !within_bounds(w)) fail(u.node_path, bounds_message(w) + " after the node transforms");
      }
      out_.instances.push_back({size_t(object_of[size_t(u.mesh)]), u.world, u.node_path});
    }
  }

  // Mesh `mesh_index`'s triangle primitives, transformed by `world` (identity: the mesh's own space).
  void convert_mesh(int mesh_index, const Mat4& world, const std::string& node_path, std::vector<GltfPrimitive>& into) {
    const tinygltf::Mesh& mesh = model_.meshes[size_t(mesh_index)];
    for (size_t pi = 0; pi < mesh.primitives.size(); ++pi) {
      const tinygltf::Primitive& p = mesh.primitives[pi];
      const std::string path = fmt::format("/meshes/{}/primitives/{}", mesh_index, pi);
      const int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
      if (!is_triangles(p)) {
        unsupported_["points and lines primitives"] += 1;
        continue;
      }
      if (!p.targets.empty()) unsupported_["morph targets"] += 1;
      const auto pos_it = p.attributes.find("POSITION");
      if (pos_it == p.attributes.end()) fail(path + "/attributes", "primitive has no POSITION");
      GltfPrimitive out;
      out.json_path = path;
      if (p.material >= 0 && size_t(p.material) >= model_.materials.size())
        fail(path + "/material", fmt::format("material {} does not exist", p.material));
      out.material = material_of(p);
      MeshData& m = out.mesh;
      const std::vector<float> pos = floats(pos_it->second, 3, path + "/attributes/POSITION");
      const size_t nv = pos.size() / 3;
      m.positions.resize(nv);
      for (size_t i = 0; i < nv; ++i) m.positions[i] = Vec3(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
      auto attribute = [&](const char* name, int comps) -> std::vector<float> {
        const auto it = p.attributes.find(name);
        if (it == p.attributes.end()) return {};
        const std::string use = path + "/attributes/" + name;
        std::vector<float> v = floats(it->second, comps, use);
        if (v.size() != nv * size_t(comps))
          fail(use, fmt::format("{} has {} elements, POSITION {}", name, v.size() / size_t(comps), nv));
        return v;
      };
      const std::vector<float> nrm = attribute("NORMAL", 3);
      const std::vector<float> tan = nrm.empty() ? std::vector<float>{} : attribute("TANGENT", 4);
      const std::vector<float> uv = attribute("TEXCOORD_0", 2);
      for (size_t i = 0; i < nrm.size() / 3; ++i) m.normals.emplace_back(nrm[3 * i], nrm[3 * i + 1], nrm[3 * i + 2]);
      for (size_t i = 0; i < tan.size() / 4; ++i)
        m.tangents.emplace_back(tan[4 * i], tan[4 * i + 1], tan[4 * i + 2], tan[4 * i + 3] < 0.0f ? -1.0f : 1.0f);
      // glTF's v runs down the image, kozu's up.
      for (size_t i = 0; i < uv.size() / 2; ++i) m.uvs.emplace_back(uv[2 * i], 1.0f - uv[2 * i + 1]);
      std::vector<uint32_t> idx;
      if (p.indices >= 0) {
        idx = indices(p.indices, nv, path + "/indices");
      } else {
        idx.resize(nv);
        for (size_t i = 0; i < nv; ++i) idx[i] = uint32_t(i);
      }
      // Strips and fans as triangle lists, keeping each triangle's winding (§3.7.2.1).
      if (mode == TINYGLTF_MODE_TRIANGLES) {
        if (idx.size() % 3 != 0) fail(path, fmt::format("{} indices is not a multiple of 3", idx.size()));
        m.indices = std::move(idx);
      } else {
        m.indices.reserve(3 * std::max<size_t>(idx.size(), 2) - 6);
        for (size_t i = 0; i + 2 < idx.size(); ++i) {
          if (mode == TINYGLTF_MODE_TRIANGLE_STRIP)
            m.indices.insert(m.indices.end(), {idx[i], idx[i + 1 + i % 2], idx[i + 2 - i % 2]});
          else
            m.indices.insert(m.indices.end(), {idx[i + 1], idx[i + 2], idx[0]});
        }
      }
      transform(m, world);
      for (const Vec3& v : m.positions)
        if (!is_finite(v) || !within_bounds(v))
          fail(node_path.empty() ? path : node_path, bounds_message(v) + " after the node transforms");
      check_emitter_power(out, node_path.empty() ? path : node_path);
      into.push_back(std::move(out));
    }
  }

  // An emitting primitive's power (radiance × π × area, twice for a double-sided material) must stay within
  // kozu's range, or the light would overflow to infinity.
  void check_emitter_power(const GltfPrimitive& p, const std::string& where) const {
    const Rgb e = out_.emission[size_t(p.material)];
    if (is_black(e)) return;
    double area = 0.0;
    const MeshData& m = p.mesh;
    for (size_t i = 0; i + 2 < m.indices.size(); i += 3) {
      const glm::dvec3 a(m.positions[m.indices[i]]), b(m.positions[m.indices[i + 1]]), c(m.positions[m.indices[i + 2]]);
      area += 0.5 * glm::length(glm::cross(b - a, c - a));
    }
    const double power = double(max_component(e)) * kPi * area * (out_.double_sided[size_t(p.material)] ? 2.0 : 1.0);
    if (power > double(kMaxLightPower))
      fail(emission_paths_[size_t(p.material)],
           fmt::format("the emitter's power ({:.3g} W over the area {:.3g} of {} at {}) is beyond kozu's range (at "
                       "most {:g}); lower its emission or its size",
                       power, area, p.json_path, where, double(kMaxLightPower)));
  }

  // Positions by M, normals by its inverse transpose, tangents by M (their handedness flips with a mirroring M,
  // whose triangles' winding is then reversed, §3.7.2.1).
  static void transform(MeshData& m, const Mat4& M) {
    const Mat3 l(M);
    const Mat3 nm = glm::transpose(glm::inverse(l));
    const bool mirror = glm::determinant(l) < 0.0f;
    for (Vec3& p : m.positions) p = Vec3(M * Vec4(p, 1.0f));
    for (Vec3& n : m.normals) {
      const Vec3 t = nm * n;
      const float len = glm::length(t);
      n = len > 0.0f ? t / len : Vec3(0.0f, 0.0f, 1.0f);
    }
    for (Vec4& t : m.tangents) {
      Vec3 v = l * Vec3(t);
      const float len = glm::length(v);
      v = len > 0.0f ? v / len : Vec3(1.0f, 0.0f, 0.0f);
      t = Vec4(v, mirror ? -t.w : t.w);
    }
    if (mirror)
      for (size_t i = 0; i + 2 < m.indices.size(); i += 3) std::swap(m.indices[i + 1], m.indices[i + 2]);
  }

  void add_camera(int index, const Mat4& world, const std::string& node_path) {
    if (size_t(index) >= model_.cameras.size())
      fail(node_path + "/camera", fmt::format("camera {} does not exist", index));
    const tinygltf::Camera& c = model_.cameras[size_t(index)];
    if (c.type != "perspective") {
      unsupported_["orthographic cameras"] += 1;
      return;
    }
    ++cameras_seen_;
    if (out_.camera) return;
    const std::string cpath = fmt::format("/cameras/{}/perspective", index);
    // A camera looks down its local −Z with +Y up (§3.10.1).
    GltfCamera cam;
    cam.position = Vec3(world * Vec4(0, 0, 0, 1));
    if (!is_finite(cam.position) || !within_bounds(cam.position))
      fail(node_path, "the camera's position: " + bounds_message(cam.position));
    const Vec3 f = Mat3(world) * Vec3(0, 0, -1), u = Mat3(world) * Vec3(0, 1, 0);
    if (!(glm::length(f) > 0.0f) || !(glm::length(u) > 0.0f) || !is_finite(f) || !is_finite(u) ||
        !(glm::length(glm::cross(f, u)) > 0.0f))
      fail(node_path, "the camera's transform is singular");
    cam.forward = glm::normalize(f);
    cam.up = glm::normalize(u);
    // yfov has no maximum in the schema; kozu's perspective camera takes less than 180°.
    double yfov = glm::degrees(c.perspective.yfov);
    if (!(yfov > 0.0)) fail(cpath + "/yfov", fmt::format("expected a number > 0, got {:g}", c.perspective.yfov));
    if (yfov > 179.0) yfov = glm::degrees(clamp_note(cpath + "/yfov", c.perspective.yfov, glm::radians(179.0)));
    cam.yfov_degrees = float(yfov);
    // The image is kGltfImageHeight pixels high and aspectRatio times as wide: a width kozu cannot render (a
    // kozu scene's resolution is at most 65536 wide and at least 1) is refused, not silently changed.
    const double aspect = c.perspective.aspectRatio;
    if (aspect != 0.0) {
      const double width = std::round(aspect * kGltfImageHeight);
      if (!(aspect > 0.0) || !(width >= 1.0 && width <= 65536.0))
        fail(cpath + "/aspectRatio",
             fmt::format("aspect ratio {:g} gives an image {:g} pixels wide and {} high; kozu renders widths from 1 "
                         "to 65536 (aspect ratios {:.3g} to {:.3g})",
                         aspect, width, kGltfImageHeight, 0.5 / kGltfImageHeight, 65536.0 / kGltfImageHeight));
    }
    cam.aspect = float(aspect);
    out_.camera = cam;
  }

  void add_light(int index, const Mat4& world, const std::string& path) {
    if (index < 0 || size_t(index) >= model_.lights.size())
      fail(path, fmt::format("light {} does not exist (the file has {})", index, model_.lights.size()));
    const tinygltf::Light& l = model_.lights[size_t(index)];
    const std::string lpath = fmt::format("/extensions/KHR_lights_punctual/lights/{}", index);
    std::vector<double> color = l.color.size() == 3 ? l.color : std::vector<double>{1.0, 1.0, 1.0};
    for (size_t c = 0; c < 3; ++c) color[c] = unit_factor(color[c], fmt::format("{}/color/{}", lpath, c), true);
    if (!(l.intensity >= 0.0)) fail(lpath + "/intensity", fmt::format("expected a number >= 0, got {:g}", l.intensity));
    // candela (point, spot) or lux (directional) to W/sr or W/m² (docs/scene-format.md).
    const double k = l.intensity * options_.light_scale;
    // A point light's power is 4π times its intensity; a directional light's irradiance is bounded as radiance is.
    if ((l.type == "directional" ? k : 4.0 * kPi * k) >
        (l.type == "directional" ? kMaxRadiance : double(kMaxLightPower)))
      fail(lpath + "/intensity", fmt::format("intensity {:g} is beyond kozu's range (a light's power is at most {:g})",
                                             l.intensity, double(kMaxLightPower)));
    const Json value = Json::array({color[0] * k, color[1] * k, color[2] * k});
    const Vec3 p(world * Vec4(0, 0, 0, 1));
    if (l.type != "directional" && (!is_finite(p) || !within_bounds(p)))
      fail(path, "the light's position: " + bounds_message(p));
    const Vec3 d = Mat3(world) * Vec3(0, 0, -1);  // lights shine down their local −Z
    if (l.type != "point" && !(glm::length(d) > 0.0f && is_finite(d))) fail(path, "the light's transform is singular");
    const Json pos = {p.x, p.y, p.z};
    Json dir = nullptr;
    if (l.type != "point") {
      const Vec3 n = glm::normalize(d);
      dir = {n.x, n.y, n.z};
    }
    const std::string kozu_path = fmt::format("/lights/{}", out_.lights.size());
    out_.paths.emplace_back(kozu_path, lpath);
    out_.paths.emplace_back(kozu_path + "/position", path.substr(0, path.find("/extensions")));
    out_.paths.emplace_back(kozu_path + "/direction", path.substr(0, path.find("/extensions")));
    out_.paths.emplace_back(kozu_path + "/intensity", lpath + "/intensity");
    out_.paths.emplace_back(kozu_path + "/irradiance", lpath + "/intensity");
    if (l.type == "point") {
      out_.lights.push_back({{"type", "point"}, {"position", pos}, {"intensity", value}});
    } else if (l.type == "spot") {
      const double outer = l.spot.outerConeAngle, inner = l.spot.innerConeAngle;
      if (!(outer > 0.0 && outer <= double(kPiOver2) + 1e-6) || !(inner >= 0.0 && inner < outer))
        fail(lpath + "/spot", "cone angles must satisfy 0 <= innerConeAngle < outerConeAngle <= π/2");
      out_.paths.emplace_back(kozu_path + "/cone_angle", lpath + "/spot/outerConeAngle");
      out_.paths.emplace_back(kozu_path + "/falloff_angle", lpath + "/spot/innerConeAngle");
      out_.lights.push_back({{"type", "spot"},
                             {"position", pos},
                             {"direction", dir},
                             {"intensity", value},
                             {"cone_angle", glm::degrees(outer)},
                             {"falloff_angle", glm::degrees(inner)}});
    } else if (l.type == "directional") {
      out_.lights.push_back(
          {{"type", "directional"}, {"direction", dir}, {"irradiance", value}, {"angular_diameter", 0.53}});
    } else {
      fail(lpath + "/type", fmt::format("unknown light type '{}'", l.type));
    }
  }

  struct MeshUse {
    int mesh;
    Mat4 world;
    std::string node_path;
  };

  fs::path file_;
  GltfImportOptions options_;
  Model model_;
  FsContext fs_;
  std::vector<ImageRecord> images_;
  std::map<int, std::string> image_files_;
  std::map<std::string, int> unsupported_;
  std::map<std::string, std::string> clamped_;  // glTF path → "value → clamped value"
  std::vector<bool> visited_;
  std::vector<MeshUse> mesh_uses_;
  std::vector<std::string> emission_paths_;  // per material: where its emission is given
  std::string mat_path_;                     // the material being converted
  int last_image_ = -1;                      // the image of the last texture() call
  int default_material_ = -1;
  int cameras_seen_ = 0;
  GltfScene out_;
};

}  // namespace

GltfScene read_gltf(const std::filesystem::path& file, const GltfImportOptions& options) {
  // Each option changes what is read: all of them are part of the cached value's name.
  std::string variant(reinterpret_cast<const char*>(&options.root), sizeof options.root);
  variant += fmt::format("|{}|{}|{}", options.image_dir.string(), options.light_scale, options.instance_meshes);
  return cached_load<GltfScene>("gltf", file, variant, [&] { return Importer(file, options).run(); });
}

std::string GltfScene::gltf_path(const std::string& kozu_path) const {
  // The longest recorded prefix (ending at a key boundary) wins; the rest of the path follows it.
  const std::pair<std::string, std::string>* best = nullptr;
  for (const auto& entry : paths) {
    const std::string& k = entry.first;
    if (kozu_path.compare(0, k.size(), k) != 0) continue;
    if (kozu_path.size() > k.size() && kozu_path[k.size()] != '/') continue;
    if (!best || k.size() > best->first.size()) best = &entry;
  }
  return best ? best->second + kozu_path.substr(best->first.size()) : kozu_path;
}

}  // namespace kozu
