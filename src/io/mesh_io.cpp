// Mesh file entry point (load_mesh) and the Wavefront OBJ reader, built on tinyobjloader.
// tinyobjloader is lenient in ways a renderer should not be: it reports out-of-range indices only
// as warnings (and may read out of bounds triangulating them), silently drops faces with fewer than
// 3 corners, and turns unparsable numbers such as "nan" into 0. read_obj therefore pre-scans the
// text and turns each of those into an InputError with a line number before tinyobjloader runs.
#include "io/mesh_io.h"
#include "core/file_io.h"

#include "core/error.h"

#include <fmt/format.h>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
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

}  // namespace

MeshData load_mesh(const std::filesystem::path& file) {
  const std::string ext = lower_extension(file);
  if (ext == ".obj") return read_obj(file);
  if (ext == ".ply") return read_ply(file);
  if (ext.empty()) fail(file, "mesh file has no extension (expected .obj or .ply)");
  fail(file, fmt::format("unsupported mesh format '{}' (expected .obj or .ply)", file.extension().string()));
}

MeshData read_obj(const std::filesystem::path& file) { return parse_obj(file, read_input_file(file)); }

MeshData parse_obj(const std::filesystem::path& file, const std::string& text) {
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

}  // namespace kozu
