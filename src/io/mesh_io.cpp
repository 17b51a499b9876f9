// Mesh file entry point (load_mesh) and the Wavefront OBJ reader, built on tinyobjloader.
// tinyobjloader is lenient in ways a renderer should not be: it reports out-of-range indices only
// as warnings (and may read out of bounds triangulating them), silently drops faces with fewer than
// 3 corners, and turns unparsable numbers such as "nan" into 0. read_obj therefore pre-scans the
// text and turns each of those into an InputError with a line number before tinyobjloader runs.
// Before either, the memory the parse will take is estimated from a count of the file's statements and checked
// against kozu's memory limit (core/memory.h).
#include "io/mesh_io.h"
#include "core/file_io.h"
#include "core/load_cache.h"

#include "core/error.h"
#include "core/memory.h"

#include <fmt/format.h>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <new>
#include <string>
#include <string_view>
#include <system_error>
#include <unordered_map>
#include <vector>

namespace kozu {

namespace {

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& message) {
  throw InputError(file.string(), "", message);
}

// ---------------------------------------------------------------------------------------------
// OBJ pre-scan. Lines end at \n, \r\n or \r, as in tinyobjloader, so that both see the same
// statements and the line numbers in messages match what an editor shows.

bool is_blank(char c) { return c == ' ' || c == '\t'; }

template <typename Fn>
void for_each_line(std::string_view text, Fn&& fn) {
  size_t line_number = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t end = pos;
    while (end < text.size() && text[end] != '\n' && text[end] != '\r') ++end;
    fn(++line_number, text.substr(pos, end - pos));
    if (end < text.size() && text[end] == '\r' && end + 1 < text.size() && text[end + 1] == '\n') ++end;
    pos = end + 1;
  }
}

// Splits a statement into its keyword and whitespace-separated arguments.
struct Statement {
  std::string_view keyword;
  std::vector<std::string_view> args;
};

// Fills a caller-owned Statement so that its argument vector is reused from line to line.
void split_statement(std::string_view line, Statement& s) {
  s.keyword = {};
  s.args.clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_blank(line[i])) ++i;
    if (i == line.size()) break;
    const size_t start = i;
    while (i < line.size() && !is_blank(line[i])) ++i;
    if (s.keyword.empty())
      s.keyword = line.substr(start, i - start);
    else
      s.args.push_back(line.substr(start, i - start));
  }
}

enum class NumberStatus { Ok, Invalid, Overflow };

// Parses a whole token as a double; from_chars rejects a leading '+', so strip it.
NumberStatus parse_coordinate(std::string_view token, double& value) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (end != token.data() + token.size()) return NumberStatus::Invalid;
  if (ec == std::errc::result_out_of_range) {
    // from_chars leaves the value unset; a negative exponent means underflow, which is just zero.
    const size_t e = token.find_first_of("eE");
    if (e == std::string_view::npos || e + 1 == token.size() || token[e + 1] != '-') return NumberStatus::Overflow;
    value = 0.0;
    return NumberStatus::Ok;
  }
  return ec == std::errc() ? NumberStatus::Ok : NumberStatus::Invalid;
}

bool parse_integer(std::string_view token, int64_t& value) {
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && end == token.data() + token.size();
}

struct ObjCounts {
  int64_t positions = 0, normals = 0, texcoords = 0;
};

void check_coordinates(const std::filesystem::path& file, size_t line, const Statement& s, size_t required,
                       size_t used) {
  if (s.args.size() < required)
    fail(file, fmt::format("line {}: '{}' needs {} values, found {}", line, s.keyword, required, s.args.size()));
  for (size_t i = 0; i < std::min(used, s.args.size()); ++i) {
    double value = 0;
    const NumberStatus status = parse_coordinate(s.args[i], value);
    if (status == NumberStatus::Invalid)
      fail(file, fmt::format("line {}: invalid number '{}' in '{}' statement", line, s.args[i], s.keyword));
    if (status == NumberStatus::Ok && !std::isfinite(value))
      fail(file, fmt::format("line {}: non-finite coordinate '{}' in '{}' statement", line, s.args[i], s.keyword));
    if (status == NumberStatus::Overflow || std::abs(value) > std::numeric_limits<float>::max())
      fail(file, fmt::format("line {}: coordinate '{}' exceeds the float range", line, s.args[i]));
  }
}

// Checks one OBJ index (1-based, or negative = relative to the elements defined so far).
void check_index(const std::filesystem::path& file, size_t line, int64_t index, int64_t defined_so_far, int64_t total,
                 const char* what, const char* plural) {
  if (index == 0) fail(file, fmt::format("line {}: {} index 0 is invalid (OBJ indices start at 1)", line, what));
  if (index > total)
    fail(file, fmt::format("line {}: {} index {} out of range (mesh has {} {})", line, what, index, total, plural));
  if (index < 0 && defined_so_far + index < 0)
    fail(file, fmt::format("line {}: relative {} index {} out of range ({} {} defined before this line)", line, what,
                           index, defined_so_far, plural));
}

// Validates numbers and face corners; tinyobjloader itself would accept or silently patch them.
// Returns the material names `usemtl` gives, in order of first use.
std::vector<std::string> prescan_obj(const std::filesystem::path& file, std::string_view text) {
  ObjCounts total;
  Statement s;
  std::vector<std::string> usemtl;
  for_each_line(text, [&](size_t line, std::string_view content) {
    // A bare keyword (which tinyobjloader would skip) fails the argument count checks.
    split_statement(content, s);
    if (s.keyword == "usemtl") {
      if (s.args.size() != 1) fail(file, fmt::format("line {}: usemtl takes one material name", line));
      const std::string name(s.args[0]);
      if (std::find(usemtl.begin(), usemtl.end(), name) == usemtl.end()) usemtl.push_back(name);
    } else if (s.keyword == "v") {
      check_coordinates(file, line, s, 3, 3);
      ++total.positions;
    } else if (s.keyword == "vn") {
      check_coordinates(file, line, s, 3, 3);
      ++total.normals;
    } else if (s.keyword == "vt") {
      check_coordinates(file, line, s, 1, 2);
      ++total.texcoords;
    }
  });

  ObjCounts so_far;
  for_each_line(text, [&](size_t line, std::string_view content) {
    split_statement(content, s);
    if (s.keyword == "v") ++so_far.positions;
    if (s.keyword == "vn") ++so_far.normals;
    if (s.keyword == "vt") ++so_far.texcoords;
    if (s.keyword != "f") return;
    if (s.args.size() < 3)
      fail(file, fmt::format("line {}: face has {} vertices (at least 3 required)", line, s.args.size()));
    for (std::string_view corner : s.args) {
      // Forms: v, v/vt, v//vn, v/vt/vn.
      std::string_view parts[3];
      size_t part_count = 0;
      size_t start = 0;
      while (true) {
        const size_t slash = corner.find('/', start);
        if (part_count == 3) fail(file, fmt::format("line {}: malformed face vertex '{}'", line, corner));
        parts[part_count++] = corner.substr(start, slash == std::string_view::npos ? slash : slash - start);
        if (slash == std::string_view::npos) break;
        start = slash + 1;
      }
      int64_t v = 0, vt = 0, vn = 0;
      const bool ok = parse_integer(parts[0], v) &&
                      (part_count < 2 || (part_count == 3 && parts[1].empty()) || parse_integer(parts[1], vt)) &&
                      (part_count < 3 || parse_integer(parts[2], vn));
      if (!ok) fail(file, fmt::format("line {}: malformed face vertex '{}'", line, corner));
      check_index(file, line, v, so_far.positions, total.positions, "face", "vertices");
      if (part_count >= 2 && !parts[1].empty())
        check_index(file, line, vt, so_far.texcoords, total.texcoords, "texture coordinate", "texture coordinates");
      if (part_count == 3) check_index(file, line, vn, so_far.normals, total.normals, "normal", "normals");
    }
  });
  return usemtl;
}

// ---------------------------------------------------------------------------------------------
// Memory. Bytes per element at the peak of a load, beyond the file's bytes already in memory, measured with the
// peak resident memory of `kozu voxelize MESH --resolution 4` (VmHWM, reset through /proc/self/clear_refs before
// each phase to separate tinyobjloader's parse from kozu's conversion) on generated grids (glibc 2.36,
// tinyobjloader 2.0, GCC 12 Release): N x N quads for N = 500, 700, 1000, 1414, 1500 (0.25 to 2.25 M quads, 10 to
// 100 MB of text), the 1000 x 1000 grid as triangles, with v/vt/vn corners, and with a usemtl every row.
//
// tinyobjloader's parse is the peak: its copy of the text (a second copy when kozu puts an mtllib in front, for
// usemtl), its vertex arrays (v: 12 bytes and a 4-byte weight, vt: 8 and a 4-byte w, vn: 12; arrays that grow by
// doubling, so up to twice that while one moves), each face as a 32-byte record (64 while the array moves) with
// a heap block of its corners (16 + 12 a corner), and for each triangle the exported index triple (36 bytes),
// its corner count, material and smoothing ids (45 in all, 90 while growing). Faces are stored only until the
// next g, o or usemtl statement, so only the largest such run counts. Measured: 373 to 381 bytes a quad for the
// quad grids (the constants give 381 to 385), 472 MB for 2 M triangle faces (estimate 501 MB), 558 MB for the
// v/vt/vn grid (estimate 574 MB), 273 MB with a usemtl every row (estimate 295 MB).
constexpr double kObjPosition = 32, kObjTexcoord = 56, kObjNormal = 56;
constexpr double kObjFace = 80, kObjCorner = 12, kObjTriangle = 90;
// After the parse: what stays of it (the vertex arrays, the exported triangles, and the faces' corner blocks,
// which malloc keeps for reuse) while kozu converts it: 36 bytes a triangle (its indices and the corner table's
// buckets), 60 an output vertex (a 48-byte corner-table node and its position, which the mesh's padding vertex
// may move once more), 12 more with normals, 8 with uvs. Measured: 126 MB for the usemtl grid's 2 M triangles and
// 1 M vertices (estimate 132 MB); the quad grid's conversion reuses the freed face blocks.
constexpr double kObjKeptPosition = 16, kObjKeptTexcoord = 24, kObjKeptNormal = 24, kObjKeptTriangle = 45;
constexpr double kObjKeptFace = 16;
constexpr double kMeshTriangle = 36, kMeshVertex = 60, kMeshNormal = 12, kMeshUv = 8;
// PLY: the reader reserves kozu's arrays from the header's counts (12 bytes a position, normal and index, 8 a uv),
// and the mesh's padding vertex moves the positions once more.
constexpr double kPlyVertex = 24, kPlyNormal = 12, kPlyUv = 8, kPlyTriangle = 12;

// Loads that run at once (the scene loader reads its meshes in parallel) each count what the others expect to
// allocate and have not yet, so that two meshes that fit only one at a time are not both let through.
std::atomic<uint64_t> g_reserved_bytes{0};

// Runs a reader, an allocation that fails anyway (the estimate is approximate; other threads allocate too)
// turned into a message naming the file.
template <typename Fn>
MeshData guard_memory(const std::filesystem::path& file, Fn&& fn) {
  try {
    return fn();
  } catch (const std::bad_alloc&) {
    fail(file, "out of memory while reading the mesh");
  } catch (const std::length_error&) {
    fail(file, "out of memory while reading the mesh (an array beyond the largest size)");
  }
}

// ---------------------------------------------------------------------------------------------
// Corner de-duplication: one output vertex per distinct (position, normal, uv) index triple.

struct CornerKey {
  int v, vn, vt;
  bool operator==(const CornerKey&) const = default;
};

struct CornerKeyHash {
  size_t operator()(const CornerKey& k) const {
    uint64_t h = static_cast<uint32_t>(k.v);
    h = h * 0x9E3779B97F4A7C15ull ^ static_cast<uint32_t>(k.vn);
    h = h * 0x9E3779B97F4A7C15ull ^ static_cast<uint32_t>(k.vt);
    return static_cast<size_t>(h ^ (h >> 29));
  }
};

// tinyobjloader's parse and the conversion into kozu's mesh, after the memory check.
MeshData parse_obj_text(const std::filesystem::path& file, const std::string& text);

}  // namespace

MeshMemoryReservation::MeshMemoryReservation(const std::filesystem::path& file, double need, uint64_t triangles) {
  const MemoryLimit limit = memory_limit();
  const double others = double(g_reserved_bytes.load());
  const double left = std::max(0.0, memory_left(limit) - others);
  if (need > left)
    fail(file, fmt::format("the mesh needs about {} ({} triangles) but only {} of the {} limit ({}) is left",
                           format_bytes(need), triangles, format_bytes(left), format_bytes(double(limit.bytes)),
                           limit.source));
  bytes_ = static_cast<uint64_t>(need);
  g_reserved_bytes += bytes_;
}

MeshMemoryReservation::~MeshMemoryReservation() { g_reserved_bytes -= bytes_; }

MeshCounts count_obj(std::string_view text) {
  MeshCounts c;
  c.text_bytes = text.size();
  uint64_t run_faces = 0, run_corners = 0;
  const auto end_run = [&] {
    if (run_faces > c.run_faces) c.run_faces = run_faces, c.run_corners = run_corners;
    run_faces = run_corners = 0;
  };
  const char* p = text.data();
  const char* const end = p + text.size();
  // Statements as tinyobjloader reads them: lines end at \n or \r, leading blanks skipped, keyword then a blank.
  const auto keyword_is = [&](const char* q, std::string_view k) {
    return size_t(end - q) > k.size() && std::string_view(q, k.size()) == k && is_blank(q[k.size()]);
  };
  while (p < end) {
    while (p < end && is_blank(*p)) ++p;
    if (p < end && *p == 'f' && end - p > 1 && is_blank(p[1])) {
      // Corners are the blank-separated words after "f".
      uint64_t corners = 0;
      bool in_word = false;
      for (++p; p < end && *p != '\n' && *p != '\r'; ++p) {
        const bool blank = is_blank(*p);
        if (!blank && !in_word) ++corners;
        in_word = !blank;
      }
      ++run_faces;
      run_corners += corners;
      if (corners >= 3) c.triangles += corners - 2;
    } else if (p < end) {
      if (keyword_is(p, "v"))
        ++c.positions;
      else if (keyword_is(p, "vn"))
        ++c.normals;
      else if (keyword_is(p, "vt"))
        ++c.texcoords;
      else if (keyword_is(p, "g") || keyword_is(p, "o"))
        end_run();
      else if (keyword_is(p, "usemtl")) {
        c.usemtl = true;
        end_run();
      }
      const void* nl = std::memchr(p, '\n', size_t(end - p));
      const char* line_end = nl ? static_cast<const char*>(nl) : end;
      // A file with \r alone as line end: the line stops at the first \r.
      const void* cr = std::memchr(p, '\r', size_t(line_end - p));
      p = cr ? static_cast<const char*>(cr) : line_end;
    }
    if (p < end) ++p;  // the line end (a \r\n's \n is an empty line)
  }
  end_run();
  return c;
}

double obj_memory_bytes(const MeshCounts& c) {
  const double text = double(c.text_bytes) * (c.usemtl ? 2.0 : 1.0);
  const double parse = text + kObjPosition * double(c.positions) + kObjTexcoord * double(c.texcoords) +
                       kObjNormal * double(c.normals) + kObjFace * double(c.run_faces) +
                       kObjCorner * double(c.run_corners) + kObjTriangle * double(c.triangles);
  const double kept = kObjKeptPosition * double(c.positions) + kObjKeptTexcoord * double(c.texcoords) +
                      kObjKeptNormal * double(c.normals) + kObjKeptTriangle * double(c.triangles) +
                      kObjKeptFace * double(c.run_faces) + kObjCorner * double(c.run_corners);
  // One output vertex per distinct corner: about as many as the file's largest attribute array.
  const double vertices = double(std::max({c.positions, c.texcoords, c.normals}));
  const double mesh = kMeshTriangle * double(c.triangles) +
                      (kMeshVertex + (c.normals ? kMeshNormal : 0.0) + (c.texcoords ? kMeshUv : 0.0)) * vertices;
  return std::max(parse, kept + mesh);
}

double ply_memory_bytes(const MeshCounts& c) {
  return kPlyVertex * double(c.positions) + kPlyNormal * double(c.normals) + kPlyUv * double(c.texcoords) +
         kPlyTriangle * double(c.triangles);
}

MeshData load_mesh(const std::filesystem::path& file) {
  const std::string ext = lower_extension(file);
  if (ext == ".obj") return cached_load<MeshData>("mesh", file, "", [&] { return read_obj(file); });
  if (ext == ".ply") return cached_load<MeshData>("mesh", file, "", [&] { return read_ply(file); });
  if (ext.empty()) fail(file, "mesh file has no extension (expected .obj or .ply)");
  fail(file, fmt::format("unsupported mesh format '{}' (expected .obj or .ply)", file.extension().string()));
}

MeshData read_obj(const std::filesystem::path& file) {
  return guard_memory(file, [&] { return parse_obj(file, read_input_file(file)); });
}

MeshData parse_obj(const std::filesystem::path& file, const std::string& text) {
  const MeshCounts counts = count_obj(text);
  const MeshMemoryReservation reservation(file, obj_memory_bytes(counts), counts.triangles);
  return guard_memory(file, [&] { return parse_obj_text(file, text); });
}

namespace {
MeshData parse_obj_text(const std::filesystem::path& file, const std::string& text) {
  const std::vector<std::string> usemtl = prescan_obj(file, text);

  // kozu takes materials from the scene file, never from a .mtl file: the materials tinyobjloader reads are a
  // generated library with one empty material per usemtl name, so that each face gets its name's id (the file's
  // own mtllib lines read the same library; one is added in front, which loads it before any usemtl). The
  // remaining warnings (bad indices, short faces) have already been turned into errors by the pre-scan.
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  std::string library;
  for (const std::string& name : usemtl) library += "newmtl " + name + "\n";
  if (!reader.ParseFromString(usemtl.empty() ? text : "mtllib kozu-usemtl.mtl\n" + text, library, config)) {
    std::string err = reader.Error();
    while (!err.empty() && std::isspace(static_cast<unsigned char>(err.back()))) err.pop_back();
    fail(file, "OBJ parse error: " + (err.empty() ? std::string("unknown error") : err));
  }

  const tinyobj::attrib_t& attrib = reader.GetAttrib();
  const auto& shapes = reader.GetShapes();

  // Attributes are kept only when every corner has them; a mesh where only some faces carry
  // normals would otherwise need invented ones for the rest.
  bool all_normals = true, all_uvs = true;
  size_t corner_count = 0;
  for (const tinyobj::shape_t& shape : shapes) {
    corner_count += shape.mesh.indices.size();
    for (const tinyobj::index_t& idx : shape.mesh.indices) {
      all_normals &= idx.normal_index >= 0;
      all_uvs &= idx.texcoord_index >= 0;
    }
  }

  MeshData mesh;
  mesh.indices.reserve(corner_count);
  std::unordered_map<CornerKey, uint32_t, CornerKeyHash> vertex_of;
  vertex_of.reserve(corner_count);
  const size_t position_count = attrib.vertices.size() / 3;
  const size_t normal_count = attrib.normals.size() / 3;
  const size_t texcoord_count = attrib.texcoords.size() / 2;

  for (const tinyobj::shape_t& shape : shapes) {
    if (shape.mesh.indices.size() % 3 != 0)
      fail(file, fmt::format("shape '{}' did not triangulate into whole triangles", shape.name));
    for (const tinyobj::index_t& idx : shape.mesh.indices) {
      // The pre-scan checked the file's indices; this guards against tinyobjloader disagreeing.
      if (idx.vertex_index < 0 || size_t(idx.vertex_index) >= position_count ||
          (all_normals && size_t(idx.normal_index) >= normal_count) ||
          (all_uvs && size_t(idx.texcoord_index) >= texcoord_count))
        fail(file, fmt::format("face index out of range after parsing (vertex {})", idx.vertex_index + 1));

      const CornerKey key{idx.vertex_index, all_normals ? idx.normal_index : -1, all_uvs ? idx.texcoord_index : -1};
      const auto [it, inserted] = vertex_of.try_emplace(key, uint32_t(mesh.positions.size()));
      if (inserted) {
        const size_t v = size_t(key.v);
        const Vec3 p(attrib.vertices[3 * v], attrib.vertices[3 * v + 1], attrib.vertices[3 * v + 2]);
        if (!is_finite(p)) fail(file, fmt::format("vertex {}: non-finite coordinate", v + 1));
        mesh.positions.push_back(p);
        if (all_normals) {
          const size_t n = size_t(key.vn);
          const Vec3 normal(attrib.normals[3 * n], attrib.normals[3 * n + 1], attrib.normals[3 * n + 2]);
          if (!is_finite(normal)) fail(file, fmt::format("normal {}: non-finite coordinate", n + 1));
          mesh.normals.push_back(normal);
        }
        if (all_uvs) {
          const size_t t = size_t(key.vt);
          const Vec2 uv(attrib.texcoords[2 * t], attrib.texcoords[2 * t + 1]);
          if (!std::isfinite(uv.x) || !std::isfinite(uv.y))
            fail(file, fmt::format("texture coordinate {}: non-finite coordinate", t + 1));
          mesh.uvs.push_back(uv);
        }
      }
      mesh.indices.push_back(it->second);
    }
    if (!usemtl.empty()) {
      // One material id per triangle (tinyobjloader triangulates the faces and repeats their ids).
      const auto& materials = reader.GetMaterials();
      if (shape.mesh.material_ids.size() * 3 != shape.mesh.indices.size())
        fail(file, fmt::format("shape '{}': face materials do not match its triangles", shape.name));
      for (const int id : shape.mesh.material_ids) {
        const std::string name = id >= 0 && size_t(id) < materials.size() ? materials[size_t(id)].name : "";
        auto g = std::find(mesh.group_names.begin(), mesh.group_names.end(), name);
        if (g == mesh.group_names.end()) g = mesh.group_names.insert(mesh.group_names.end(), name);
        mesh.groups.push_back(static_cast<uint32_t>(g - mesh.group_names.begin()));
      }
    }
  }
  return mesh;
}
}  // namespace

}  // namespace kozu
