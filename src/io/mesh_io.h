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

// What a mesh file holds, counted before it is parsed: by a scan of an OBJ's lines (count_obj, no allocation) or
// from a PLY's header, for the memory check that runs before the parse allocates anything.
struct MeshCounts {
  uint64_t positions = 0, normals = 0, texcoords = 0;  // OBJ v, vn, vt; PLY vertices (normals, uvs: 0 or vertices)
  uint64_t triangles = 0;                              // after fan triangulation (PLY: one per face)
  // OBJ only: the text's size, whether it has usemtl statements (the parse then copies the text twice), and the
  // most faces and face corners between two statements that make tinyobjloader store its faces (g, o, usemtl).
  uint64_t text_bytes = 0;
  bool usemtl = false;
  uint64_t run_faces = 0, run_corners = 0;
};
MeshCounts count_obj(std::string_view text);
// The memory, in bytes, that parsing a file with these counts takes at its peak beyond the file's bytes already
// in memory: tinyobjloader's structures and kozu's mesh (OBJ), kozu's mesh (PLY). Measured constants; see
// mesh_io.cpp.
double obj_memory_bytes(const MeshCounts& counts);
double ply_memory_bytes(const MeshCounts& counts);
// The check: throws InputError(file, "", "the mesh needs about X (N triangles) but only Y of the Z limit (SOURCE) is
// left") when `need` bytes do not fit in the limit less the resident memory and what other loads running at once
// have reserved; else holds `need` reserved until destroyed.
class MeshMemoryReservation {
 public:
  MeshMemoryReservation(const std::filesystem::path& file, double need, uint64_t triangles);
  ~MeshMemoryReservation();
  MeshMemoryReservation(const MeshMemoryReservation&) = delete;
  MeshMemoryReservation& operator=(const MeshMemoryReservation&) = delete;

 private:
  uint64_t bytes_ = 0;
};

// Dispatches on the extension (.obj or .ply, case-insensitive). Polygons are fan-triangulated.
// Throws InputError(file, "", message) for a missing, unreadable or malformed file, an index
// out of range, a non-finite coordinate, or a mesh that needs more memory than is left of kozu's limit
// (core/memory.h; checked before parsing, and any allocation failure while parsing becomes such a message too).
MeshData load_mesh(const std::filesystem::path& file);

MeshData read_obj(const std::filesystem::path& file);
MeshData read_ply(const std::filesystem::path& file);
// The same from bytes already in memory; `file` names them in messages.
MeshData parse_obj(const std::filesystem::path& file, const std::string& text);
MeshData parse_ply(const std::filesystem::path& file, std::string_view data);

}  // namespace kozu
