// Triangle-mesh files: Wavefront OBJ (through tinyobjloader) and Stanford PLY (ply_reader.cpp).
#pragma once

#include "core/math.h"

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace kozu {

// Plain triangle soup with optional per-vertex attributes (empty when the file has none).
struct MeshData {
  std::vector<Vec3> positions;
  std::vector<uint32_t> indices;  // 3 per triangle, counter-clockwise = front
  std::vector<Vec3> normals;      // empty or positions.size()
  std::vector<Vec2> uvs;          // empty or positions.size()
  // Empty or positions.size(): unit tangent along dp/du (xyz) and handedness w = ±1, the bitangent being
  // w · cross(normal, tangent) (glTF's TANGENT; OBJ and PLY have none: geometry/mesh_tangents.h computes them).
  std::vector<Vec4> tangents;
  // OBJ `usemtl`: empty, or one entry per triangle indexing group_names (the material names in the file's order;
  // "" for faces before the first usemtl).
  std::vector<uint32_t> groups;
  std::vector<std::string> group_names;
};

// Dispatches on the extension (.obj or .ply, case-insensitive). Polygons are fan-triangulated.
// Throws InputError(file, "", message) for a missing, unreadable or malformed file, an index
// out of range, or a non-finite coordinate.
MeshData load_mesh(const std::filesystem::path& file);

MeshData read_obj(const std::filesystem::path& file);
MeshData read_ply(const std::filesystem::path& file);
// The same from bytes already in memory; `file` names them in messages.
MeshData parse_obj(const std::filesystem::path& file, const std::string& text);
MeshData parse_ply(const std::filesystem::path& file, std::string_view data);

}  // namespace kozu
