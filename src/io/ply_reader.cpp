// Stanford PLY reader (ascii 1.0, binary_little_endian 1.0, binary_big_endian 1.0).
// The whole file is read into memory and parsed from the buffer. Only the vertex element
// (x, y, z; optional nx, ny, nz and u, v / s, t / texture_u, texture_v) and the face element's
// vertex_indices list are kept; every other element and property is skipped by its declared type.
#include "core/error.h"
#include "core/file_io.h"
#include "io/mesh_io.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <new>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <utility>
#include <vector>

namespace kozu {

namespace {

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& message) {
  throw InputError(file.string(), "", message);
}

// ---------------------------------------------------------------------------------------------
// Header

enum class Scalar : uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
enum class Format { Ascii, BinaryLittleEndian, BinaryBigEndian };

std::optional<Scalar> parse_scalar(std::string_view name) {
  static constexpr std::pair<std::string_view, Scalar> kNames[] = {
      {"char", Scalar::Int8},       {"int8", Scalar::Int8},       {"uchar", Scalar::UInt8},
      {"uint8", Scalar::UInt8},     {"short", Scalar::Int16},     {"int16", Scalar::Int16},
      {"ushort", Scalar::UInt16},   {"uint16", Scalar::UInt16},   {"int", Scalar::Int32},
      {"int32", Scalar::Int32},     {"uint", Scalar::UInt32},     {"uint32", Scalar::UInt32},
      {"float", Scalar::Float32},   {"float32", Scalar::Float32}, {"double", Scalar::Float64},
      {"float64", Scalar::Float64},
  };
  for (const auto& [n, s] : kNames)
    if (n == name) return s;
  return std::nullopt;
}

size_t scalar_size(Scalar s) {
  switch (s) {
    case Scalar::Int8:
    case Scalar::UInt8:
      return 1;
    case Scalar::Int16:
    case Scalar::UInt16:
      return 2;
    case Scalar::Int32:
    case Scalar::UInt32:
    case Scalar::Float32:
      return 4;
    case Scalar::Float64:
      return 8;
  }
  return 0;
}

bool is_integer(Scalar s) { return s != Scalar::Float32 && s != Scalar::Float64; }

const char* scalar_name(Scalar s) {
  switch (s) {
    case Scalar::Int8:
      return "char";
    case Scalar::UInt8:
      return "uchar";
    case Scalar::Int16:
      return "short";
    case Scalar::UInt16:
      return "ushort";
    case Scalar::Int32:
      return "int";
    case Scalar::UInt32:
      return "uint";
    case Scalar::Float32:
      return "float";
    case Scalar::Float64:
      return "double";
  }
  return "?";
}

struct Property {
  std::string name;
  Scalar type = Scalar::Float32;  // the element type for a list
  bool is_list = false;
  Scalar count_type = Scalar::UInt8;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
};

struct Header {
  Format format = Format::Ascii;
  std::vector<Element> elements;
  size_t data_offset = 0;  // first byte after the end_header line
  size_t data_line = 0;    // line number of that byte, for ascii messages
};

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    if (i == line.size()) break;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    words.push_back(line.substr(start, i - start));
  }
  return words;
}

[[noreturn]] void header_fail(const std::filesystem::path& file, size_t line, const std::string& message) {
  fail(file, fmt::format("malformed PLY header, line {}: {}", line, message));
}

Header parse_header(const std::filesystem::path& file, std::string_view buf) {
  Header h;
  bool have_format = false;
  size_t pos = 0;
  size_t line_number = 0;
  while (true) {
    const size_t nl = buf.find('\n', pos);
    if (nl == std::string_view::npos) {
      if (line_number == 0) fail(file, "not a PLY file (the first line is not 'ply')");
      fail(file, "malformed PLY header: no 'end_header' line");
    }
    std::string_view line = buf.substr(pos, nl - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = nl + 1;
    ++line_number;

    if (line_number == 1) {
      if (line != "ply") fail(file, "not a PLY file (the first line is not 'ply')");
      continue;
    }
    const std::vector<std::string_view> w = split_words(line);
    if (w.empty()) continue;
    const std::string_view keyword = w[0];
    if (keyword == "comment" || keyword == "obj_info") continue;

    if (keyword == "end_header") {
      if (!have_format) header_fail(file, line_number, "'end_header' before any 'format' line");
      h.data_offset = pos;
      h.data_line = line_number + 1;
      return h;
    }
    if (keyword == "format") {
      if (have_format) header_fail(file, line_number, "more than one 'format' line");
      if (w.size() != 3) header_fail(file, line_number, "expected 'format <type> 1.0'");
      if (w[1] == "ascii")
        h.format = Format::Ascii;
      else if (w[1] == "binary_little_endian")
        h.format = Format::BinaryLittleEndian;
      else if (w[1] == "binary_big_endian")
        h.format = Format::BinaryBigEndian;
      else
        fail(file, fmt::format("unsupported PLY format '{}' (line {})", w[1], line_number));
      if (w[2] != "1.0") fail(file, fmt::format("unsupported PLY version '{}' (line {})", w[2], line_number));
      have_format = true;
      continue;
    }
    if (keyword == "element") {
      if (w.size() != 3) header_fail(file, line_number, "expected 'element <name> <count>'");
      Element e;
      e.name = std::string(w[1]);
      const auto [end, ec] = std::from_chars(w[2].data(), w[2].data() + w[2].size(), e.count);
      if (ec != std::errc() || end != w[2].data() + w[2].size())
        header_fail(file, line_number, fmt::format("invalid element count '{}'", w[2]));
      for (const Element& other : h.elements)
        if (other.name == e.name) header_fail(file, line_number, fmt::format("duplicate element '{}'", e.name));
      h.elements.push_back(std::move(e));
      continue;
    }
    if (keyword == "property") {
      if (h.elements.empty()) header_fail(file, line_number, "'property' before any 'element'");
      Property p;
      auto scalar = [&](std::string_view name) {
        const std::optional<Scalar> s = parse_scalar(name);
        if (!s) header_fail(file, line_number, fmt::format("unknown property type '{}'", name));
        return *s;
      };
      if (w.size() >= 2 && w[1] == "list") {
        if (w.size() != 5) header_fail(file, line_number, "expected 'property list <count type> <type> <name>'");
        p.is_list = true;
        p.count_type = scalar(w[2]);
        p.type = scalar(w[3]);
        p.name = std::string(w[4]);
        if (!is_integer(p.count_type))
          header_fail(file, line_number, fmt::format("list count type '{}' is not an integer type", w[2]));
      } else {
        if (w.size() != 3) header_fail(file, line_number, "expected 'property <type> <name>'");
        p.type = scalar(w[1]);
        p.name = std::string(w[2]);
      }
      Element& e = h.elements.back();
      for (const Property& other : e.properties)
        if (other.name == p.name)
          header_fail(file, line_number, fmt::format("duplicate property '{}' in element '{}'", p.name, e.name));
      e.properties.push_back(std::move(p));
      continue;
    }
    header_fail(file, line_number, fmt::format("unexpected keyword '{}'", keyword));
  }
}

// ---------------------------------------------------------------------------------------------
// What to do with each property of the vertex and face elements.

enum class Role : uint8_t { Skip, X, Y, Z, NX, NY, NZ, U, V, Indices };
constexpr int kRoleSlots = 8;  // X..V, used as array indices (Role - 1)

struct Layout {
  const Element* vertex = nullptr;
  const Element* face = nullptr;
  std::vector<Role> vertex_roles;     // parallel to vertex->properties
  std::vector<Role> face_roles;       // parallel to face->properties
  const Property* polygon = nullptr;  // the face's vertex_indices list
  bool has_normals = false;
  bool has_uvs = false;
};

Layout make_layout(const std::filesystem::path& file, const Header& h) {
  Layout layout;
  for (const Element& e : h.elements) {
    if (e.name == "vertex") layout.vertex = &e;
    if (e.name == "face") layout.face = &e;
  }
  if (!layout.vertex) fail(file, "PLY file has no 'vertex' element");
  if (layout.vertex->count > std::numeric_limits<uint32_t>::max())
    fail(file, fmt::format("vertex count {} exceeds the 32-bit index limit", layout.vertex->count));

  const std::vector<Property>& vp = layout.vertex->properties;
  auto find = [&](std::string_view name) -> int {
    for (size_t i = 0; i < vp.size(); ++i)
      if (vp[i].name == name && !vp[i].is_list) return int(i);
    return -1;
  };
  layout.vertex_roles.assign(vp.size(), Role::Skip);
  for (const char* name : {"x", "y", "z"}) {
    const int i = find(name);
    if (i < 0) fail(file, fmt::format("PLY vertex element has no scalar property '{}'", name));
    layout.vertex_roles[size_t(i)] = name[0] == 'x' ? Role::X : name[0] == 'y' ? Role::Y : Role::Z;
  }
  // Normals and uvs are used only when complete; a lone nx or u is skipped like any unknown property.
  if (const int nx = find("nx"), ny = find("ny"), nz = find("nz"); nx >= 0 && ny >= 0 && nz >= 0) {
    layout.vertex_roles[size_t(nx)] = Role::NX;
    layout.vertex_roles[size_t(ny)] = Role::NY;
    layout.vertex_roles[size_t(nz)] = Role::NZ;
    layout.has_normals = true;
  }
  static constexpr std::pair<const char*, const char*> kUvNames[] = {
      {"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}};
  for (const auto& [u_name, v_name] : kUvNames) {
    const int u = find(u_name), v = find(v_name);
    if (u < 0 || v < 0) continue;
    layout.vertex_roles[size_t(u)] = Role::U;
    layout.vertex_roles[size_t(v)] = Role::V;
    layout.has_uvs = true;
    break;
  }

  if (layout.face) {
    const std::vector<Property>& fp = layout.face->properties;
    layout.face_roles.assign(fp.size(), Role::Skip);
    bool found = false;
    for (size_t i = 0; i < fp.size() && !found; ++i) {
      if (fp[i].name != "vertex_indices" && fp[i].name != "vertex_index") continue;
      if (!fp[i].is_list) fail(file, fmt::format("PLY face property '{}' is not a list", fp[i].name));
      if (!is_integer(fp[i].type))
        fail(file,
             fmt::format("PLY face property '{}' has non-integer type '{}'", fp[i].name, scalar_name(fp[i].type)));
      layout.face_roles[i] = Role::Indices;
      layout.polygon = &fp[i];
      found = true;
    }
    if (!found) fail(file, "PLY face element has no 'vertex_indices' list property");
  }
  return layout;
}

// ---------------------------------------------------------------------------------------------
// Data sources. Both throw DataError; read_body adds the element and index to the message.

struct DataError {
  std::string message;
  bool end_of_file = false;
};

template <typename U>
U byte_swap(U u) {
  if constexpr (sizeof(U) == 2)
    return __builtin_bswap16(u);
  else if constexpr (sizeof(U) == 4)
    return __builtin_bswap32(u);
  else if constexpr (sizeof(U) == 8)
    return __builtin_bswap64(u);
  else
    return u;
}

template <typename T, bool Swap>
T load(const char* p) {
  using U = std::conditional_t<
      sizeof(T) == 1, uint8_t,
      std::conditional_t<sizeof(T) == 2, uint16_t, std::conditional_t<sizeof(T) == 4, uint32_t, uint64_t>>>;
  U u;
  std::memcpy(&u, p, sizeof u);
  if constexpr (Swap) u = byte_swap(u);
  return std::bit_cast<T>(u);
}

template <bool Swap>
class BinarySource {
 public:
  BinarySource(const char* begin, const char* end) : p_(begin), end_(end) {}

  double read_real(Scalar s) {
    const char* p = take(scalar_size(s));
    switch (s) {
      case Scalar::Float32:
        return load<float, Swap>(p);
      case Scalar::Float64:
        return load<double, Swap>(p);
      default:
        return double(decode_int(s, p));
    }
  }
  int64_t read_int(Scalar s) { return decode_int(s, take(scalar_size(s))); }
  void skip(Scalar s) { take(scalar_size(s)); }
  void skip_many(Scalar s, uint64_t n) {
    require(s, n);
    p_ += n * scalar_size(s);
  }
  // Fails early when a list claims more values than the rest of the file can hold.
  void require(Scalar s, uint64_t n) const {
    if (n > size_t(end_ - p_) / scalar_size(s)) throw DataError{"unexpected end of file", true};
  }
  // Upper bound on how many more elements of this layout the file can hold (polygon lists have at
  // least 3 entries), so that a corrupt count cannot make reserve() allocate more than the file.
  uint64_t capacity(const Element& e, const Property* polygon) const {
    size_t bytes = 0;
    for (const Property& p : e.properties) {
      if (!p.is_list)
        bytes += scalar_size(p.type);
      else
        bytes += scalar_size(p.count_type) + (&p == polygon ? 3 * scalar_size(p.type) : 0);
    }
    return uint64_t(end_ - p_) / bytes;
  }
  std::string location() const { return {}; }

 private:
  const char* take(size_t n) {
    if (size_t(end_ - p_) < n) throw DataError{"unexpected end of file", true};
    const char* p = p_;
    p_ += n;
    return p;
  }
  static int64_t decode_int(Scalar s, const char* p) {
    switch (s) {
      case Scalar::Int8:
        return load<int8_t, Swap>(p);
      case Scalar::UInt8:
        return load<uint8_t, Swap>(p);
      case Scalar::Int16:
        return load<int16_t, Swap>(p);
      case Scalar::UInt16:
        return load<uint16_t, Swap>(p);
      case Scalar::Int32:
        return load<int32_t, Swap>(p);
      case Scalar::UInt32:
        return load<uint32_t, Swap>(p);
      default:
        break;  // make_layout only reads integers from integer-typed properties
    }
    throw DataError{fmt::format("expected an integer type, found '{}'", scalar_name(s))};
  }

  const char* p_;
  const char* end_;
};

class AsciiSource {
 public:
  AsciiSource(const char* begin, const char* end, size_t line) : p_(begin), end_(end), line_(line) {}

  double read_real(Scalar s) {
    if (is_integer(s)) return double(read_int(s));
    std::string_view t = token();
    // from_chars accepts nan and inf (rejected later with a precise message) but not a leading '+'.
    if (t.size() > 1 && t[0] == '+' && t[1] != '-') t.remove_prefix(1);
    double value = 0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
    if (ec == std::errc::result_out_of_range && end == t.data() + t.size()) {
      // from_chars leaves the value unset; a negative exponent means underflow, which is just zero.
      const size_t e = t.find_first_of("eE");
      if (e != std::string_view::npos && e + 1 < t.size() && t[e + 1] == '-') return 0.0;
      throw DataError{fmt::format("value '{}' exceeds the double range", t)};
    }
    if (ec != std::errc() || end != t.data() + t.size())
      throw DataError{fmt::format("invalid {} value '{}'", scalar_name(s), t)};
    return value;
  }
  int64_t read_int(Scalar s) {
    const std::string_view t = token();
    int64_t value = 0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
    if (ec != std::errc() || end != t.data() + t.size() || !in_range(s, value))
      throw DataError{fmt::format("invalid {} value '{}'", scalar_name(s), t)};
    return value;
  }
  void skip(Scalar) { token(); }
  void skip_many(Scalar s, uint64_t n) {
    require(s, n);
    for (uint64_t i = 0; i < n; ++i) token();
  }
  // n values need at least 2n - 1 bytes; fails early when a list claims more than the file holds.
  void require(Scalar, uint64_t n) const {
    if (n > (uint64_t(end_ - p_) + 1) / 2) throw DataError{"unexpected end of file", true};
  }
  // As BinarySource::capacity; k elements of t values each need at least 2kt - 1 bytes.
  uint64_t capacity(const Element& e, const Property* polygon) const {
    uint64_t values = 0;
    for (const Property& p : e.properties) values += &p == polygon ? 4 : 1;
    return (uint64_t(end_ - p_) + 1) / (2 * values);
  }
  std::string location() const { return fmt::format(" (line {})", line_); }

 private:
  static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

  std::string_view token() {
    while (p_ != end_ && is_space(*p_)) {
      // \r\n counts once; a lone \r (old Mac files) counts as a line break too.
      if (*p_ == '\n' || (*p_ == '\r' && (p_ + 1 == end_ || p_[1] != '\n'))) ++line_;
      ++p_;
    }
    if (p_ == end_) throw DataError{"unexpected end of file", true};
    const char* start = p_;
    while (p_ != end_ && !is_space(*p_)) ++p_;
    return {start, size_t(p_ - start)};
  }
  static bool in_range(Scalar s, int64_t v) {
    switch (s) {
      case Scalar::Int8:
        return v >= INT8_MIN && v <= INT8_MAX;
      case Scalar::UInt8:
        return v >= 0 && v <= UINT8_MAX;
      case Scalar::Int16:
        return v >= INT16_MIN && v <= INT16_MAX;
      case Scalar::UInt16:
        return v >= 0 && v <= UINT16_MAX;
      case Scalar::Int32:
        return v >= INT32_MIN && v <= INT32_MAX;
      case Scalar::UInt32:
        return v >= 0 && v <= int64_t(UINT32_MAX);
      default:
        return false;  // float-typed values are never read as integers
    }
  }

  const char* p_;
  const char* end_;
  size_t line_;
};

// ---------------------------------------------------------------------------------------------
// Body

float to_coordinate(double value, const std::string& name) {
  if (!std::isfinite(value)) throw DataError{fmt::format("non-finite coordinate {} = {}", name, value)};
  if (std::abs(value) > std::numeric_limits<float>::max())
    throw DataError{fmt::format("coordinate {} = {} exceeds the float range", name, value)};
  return float(value);
}

template <typename Source>
void skip_property(Source& src, const Property& p) {
  if (!p.is_list) return src.skip(p.type);
  const int64_t n = src.read_int(p.count_type);
  if (n < 0) throw DataError{fmt::format("negative list length {} for property '{}'", n, p.name)};
  src.skip_many(p.type, uint64_t(n));
}

template <typename Source>
void read_vertex(Source& src, const Layout& layout, MeshData& mesh) {
  float slot[kRoleSlots] = {};
  const std::vector<Property>& props = layout.vertex->properties;
  for (size_t j = 0; j < props.size(); ++j) {
    const Role role = layout.vertex_roles[j];
    if (role == Role::Skip)
      skip_property(src, props[j]);
    else
      slot[int(role) - 1] = to_coordinate(src.read_real(props[j].type), props[j].name);
  }
  mesh.positions.emplace_back(slot[0], slot[1], slot[2]);
  if (layout.has_normals) mesh.normals.emplace_back(slot[3], slot[4], slot[5]);
  if (layout.has_uvs) mesh.uvs.emplace_back(slot[6], slot[7]);
}

template <typename Source>
void read_face(Source& src, const Layout& layout, MeshData& mesh) {
  const std::vector<Property>& props = layout.face->properties;
  const uint64_t vertex_count = layout.vertex->count;
  for (size_t j = 0; j < props.size(); ++j) {
    const Property& p = props[j];
    if (layout.face_roles[j] != Role::Indices) {
      skip_property(src, p);
      continue;
    }
    const int64_t n = src.read_int(p.count_type);
    if (n < 3) throw DataError{fmt::format("face has {} vertices (at least 3 required)", n)};
    src.require(p.type, uint64_t(n));
    auto index = [&] {
      const int64_t i = src.read_int(p.type);
      if (i < 0 || uint64_t(i) >= vertex_count)
        throw DataError{fmt::format("vertex index {} out of range (mesh has {} vertices)", i, vertex_count)};
      return uint32_t(i);
    };
    // Fan triangulation keeps the polygon's winding in every triangle.
    const uint32_t first = index();
    uint32_t prev = index();
    for (int64_t k = 2; k < n; ++k) {
      const uint32_t cur = index();
      mesh.indices.insert(mesh.indices.end(), {first, prev, cur});
      prev = cur;
    }
  }
}

template <typename Source>
void read_body(const std::filesystem::path& file, Source& src, const Layout& layout,
               const std::vector<Element>& elements, MeshData& mesh) {
  // The memory check, before anything is reserved: the header's counts, bounded by what the file can hold.
  MeshCounts counts;
  counts.positions = std::min(layout.vertex->count, src.capacity(*layout.vertex, layout.polygon));
  if (layout.has_normals) counts.normals = counts.positions;
  if (layout.has_uvs) counts.texcoords = counts.positions;
  if (layout.face) counts.triangles = std::min(layout.face->count, src.capacity(*layout.face, layout.polygon));
  const MeshMemoryReservation reservation(file, ply_memory_bytes(counts), counts.triangles);
  for (const Element& e : elements) {
    if (e.properties.empty()) continue;  // holds no data, however large its count
    const uint64_t reserve = std::min(e.count, src.capacity(e, layout.polygon));
    if (&e == layout.vertex) {
      mesh.positions.reserve(reserve);
      if (layout.has_normals) mesh.normals.reserve(reserve);
      if (layout.has_uvs) mesh.uvs.reserve(reserve);
    } else if (&e == layout.face) {
      mesh.indices.reserve(mesh.indices.size() + 3 * reserve);
    }
    uint64_t i = 0;
    try {
      for (; i < e.count; ++i) {
        if (&e == layout.vertex)
          read_vertex(src, layout, mesh);
        else if (&e == layout.face)
          read_face(src, layout, mesh);
        else
          for (const Property& p : e.properties) skip_property(src, p);
      }
    } catch (const DataError& err) {
      std::string message = fmt::format("{} {}{}: {}", e.name, i, src.location(), err.message);
      if (err.end_of_file) message += fmt::format(" (the header declares {} '{}' elements)", e.count, e.name);
      fail(file, message);
    }
  }
}

MeshData parse_ply_data(const std::filesystem::path& file, std::string_view data);

}  // namespace

MeshData read_ply(const std::filesystem::path& file) {
  try {
    return parse_ply(file, read_input_file(file));
  } catch (const std::bad_alloc&) {
    fail(file, "out of memory while reading the mesh");
  }
}

MeshData parse_ply(const std::filesystem::path& file, std::string_view data) {
  // An allocation that fails anyway (the estimate is approximate; other threads allocate too) becomes a message.
  try {
    return parse_ply_data(file, data);
  } catch (const std::bad_alloc&) {
    fail(file, "out of memory while reading the mesh");
  } catch (const std::length_error&) {
    fail(file, "out of memory while reading the mesh (an array beyond the largest size)");
  }
}

namespace {
MeshData parse_ply_data(const std::filesystem::path& file, std::string_view data) {
  const Header header = parse_header(file, data);
  const Layout layout = make_layout(file, header);

  MeshData mesh;
  const char* begin = data.data() + header.data_offset;
  const char* end = data.data() + data.size();
  constexpr bool kLittleHost = std::endian::native == std::endian::little;
  switch (header.format) {
    case Format::Ascii: {
      AsciiSource src(begin, end, header.data_line);
      read_body(file, src, layout, header.elements, mesh);
      break;
    }
    case Format::BinaryLittleEndian: {
      BinarySource<!kLittleHost> src(begin, end);
      read_body(file, src, layout, header.elements, mesh);
      break;
    }
    case Format::BinaryBigEndian: {
      BinarySource<kLittleHost> src(begin, end);
      read_body(file, src, layout, header.elements, mesh);
      break;
    }
  }
  return mesh;
}
}  // namespace

}  // namespace kozu
