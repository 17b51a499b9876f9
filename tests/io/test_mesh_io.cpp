// Tests for triangle-mesh loading: OBJ (through tinyobjloader) and the hand-written PLY reader.
// Every test writes its own inputs into a fresh temporary directory; binary PLY files are produced
// by the small PlyBody writer below, so no binary fixtures live in the repository.
#include "io/mesh_io.h"

#include "core/error.h"
#include "support/render_test.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

namespace kozu {
namespace {

namespace fs = std::filesystem;

class MeshIoTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(fs::is_directory(dir_)) << dir_; }
  fs::path write(const std::string& name, std::string_view contents) const { return tmp_.write(name, contents); }

  // Loads the file expecting an InputError that names it and contains every given fragment.
  static void expect_error(const fs::path& path, std::initializer_list<std::string_view> fragments) {
    try {
      const MeshData mesh = load_mesh(path);
      ADD_FAILURE() << "expected an InputError for " << path << ", got " << mesh.indices.size() / 3 << " triangles";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path.string());
      EXPECT_EQ(e.json_path(), "");
      const std::string what = e.what();
      EXPECT_NE(what.find(path.filename().string()), std::string::npos) << what;
      for (std::string_view fragment : fragments)
        EXPECT_NE(what.find(fragment), std::string::npos) << "'" << fragment << "' missing from: " << what;
    }
  }

  test::TempDir tmp_;
  const fs::path& dir_ = tmp_.path();
};

Vec3 triangle_cross(const MeshData& mesh, size_t t) {
  const Vec3 p0 = mesh.positions.at(mesh.indices.at(3 * t));
  const Vec3 p1 = mesh.positions.at(mesh.indices.at(3 * t + 1));
  const Vec3 p2 = mesh.positions.at(mesh.indices.at(3 * t + 2));
  return glm::cross(p1 - p0, p2 - p0);
}

void expect_indices_valid(const MeshData& mesh) {
  ASSERT_EQ(mesh.indices.size() % 3, 0u);
  for (uint32_t i : mesh.indices) ASSERT_LT(i, mesh.positions.size());
  if (!mesh.normals.empty()) {
    EXPECT_EQ(mesh.normals.size(), mesh.positions.size());
  }
  if (!mesh.uvs.empty()) {
    EXPECT_EQ(mesh.uvs.size(), mesh.positions.size());
  }
}

// ---------------------------------------------------------------------------------------------
// OBJ

TEST_F(MeshIoTest, ObjCubeSplitsSharedPositionsByNormal) {
  // 8 positions shared by 6 quads, each quad with its own outward normal.
  const fs::path path = write("cube.obj", R"(# unit cube
v -1 -1 -1
v  1 -1 -1
v  1  1 -1
v -1  1 -1
v -1 -1  1
v  1 -1  1
v  1  1  1
v -1  1  1
vn 0 0 -1
vn 0 0 1
vn -1 0 0
vn 1 0 0
vn 0 -1 0
vn 0 1 0
f 1//1 4//1 3//1 2//1
f 5//2 6//2 7//2 8//2
f 1//3 5//3 8//3 4//3
f 2//4 3//4 7//4 6//4
f 1//5 2//5 6//5 5//5
f 4//6 8//6 7//6 3//6
)");
  const MeshData mesh = load_mesh(path);
  expect_indices_valid(mesh);
  EXPECT_EQ(mesh.positions.size(), 24u);
  EXPECT_EQ(mesh.normals.size(), 24u);
  EXPECT_TRUE(mesh.uvs.empty());
  ASSERT_EQ(mesh.indices.size(), 36u);

  float area = 0;
  for (size_t t = 0; t < 12; ++t) {
    const Vec3 c = triangle_cross(mesh, t);
    area += 0.5f * glm::length(c);
    for (int k = 0; k < 3; ++k) {
      // Outward winding: the geometric normal agrees with the file's normal at every corner.
      const Vec3 n = mesh.normals[mesh.indices[3 * t + k]];
      EXPECT_FLOAT_EQ(glm::dot(glm::normalize(c), n), 1.0f) << "triangle " << t;
    }
  }
  EXPECT_FLOAT_EQ(area, 24.0f);
  // Each cube corner appears once per adjacent face.
  for (const Vec3& p : mesh.positions) {
    EXPECT_EQ(std::abs(p.x), 1.0f);
    EXPECT_EQ(std::abs(p.y), 1.0f);
    EXPECT_EQ(std::abs(p.z), 1.0f);
    EXPECT_EQ(std::count(mesh.positions.begin(), mesh.positions.end(), p), 3);
  }
}

TEST_F(MeshIoTest, ObjQuadBecomesTwoTrianglesWithInputWinding) {
  const std::string attributes = "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n";
  const fs::path ccw = write("ccw.obj", attributes + "f 1/1/1 2/2/1 3/3/1 4/4/1\n");
  const fs::path cw = write("cw.obj", attributes + "f 4/4/1 3/3/1 2/2/1 1/1/1\n");

  const MeshData mesh = load_mesh(ccw);
  expect_indices_valid(mesh);
  ASSERT_EQ(mesh.positions.size(), 4u);
  ASSERT_EQ(mesh.indices.size(), 6u);
  ASSERT_EQ(mesh.uvs.size(), 4u);
  ASSERT_EQ(mesh.normals.size(), 4u);
  float area = 0;
  for (size_t t = 0; t < 2; ++t) {
    const Vec3 c = triangle_cross(mesh, t);
    EXPECT_EQ(c.x, 0.0f);
    EXPECT_EQ(c.y, 0.0f);
    EXPECT_GT(c.z, 0.0f) << "triangle " << t << " is not counter-clockwise";
    area += 0.5f * c.z;
  }
  EXPECT_FLOAT_EQ(area, 2.0f);
  for (size_t i = 0; i < 4; ++i) {
    // uv = (x / 2, y) by construction, so attributes stayed attached to their corners.
    EXPECT_EQ(mesh.uvs[i], Vec2(mesh.positions[i].x / 2, mesh.positions[i].y));
    EXPECT_EQ(mesh.normals[i], Vec3(0, 0, 1));
  }

  const MeshData reversed = load_mesh(cw);
  ASSERT_EQ(reversed.indices.size(), 6u);
  for (size_t t = 0; t < 2; ++t) EXPECT_LT(triangle_cross(reversed, t).z, 0.0f) << "triangle " << t;
}

TEST_F(MeshIoTest, ObjConvexPolygonKeepsWindingAndArea) {
  const fs::path path = write("pentagon.obj", "v 0 0 0\nv 2 0 0\nv 3 1 0\nv 1 2 0\nv -1 1 0\nf 1 2 3 4 5\n");
  const MeshData mesh = load_mesh(path);
  expect_indices_valid(mesh);
  ASSERT_EQ(mesh.indices.size(), 9u);
  float area = 0;
  for (size_t t = 0; t < 3; ++t) {
    const Vec3 c = triangle_cross(mesh, t);
    EXPECT_GT(c.z, 0.0f) << "triangle " << t;
    area += 0.5f * c.z;
  }
  EXPECT_FLOAT_EQ(area, 5.0f);  // shoelace formula for the five corners above
}

TEST_F(MeshIoTest, ObjWithoutNormalsLeavesNormalsEmpty) {
  const fs::path path = write("no_normals.obj",
                              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                              "vt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\n"
                              "f 1/1 2/2 3/3\nf 2/2 4/4 3/3\n");
  const MeshData mesh = load_mesh(path);
  expect_indices_valid(mesh);
  EXPECT_TRUE(mesh.normals.empty());
  ASSERT_EQ(mesh.uvs.size(), 4u);
  EXPECT_EQ(mesh.positions.size(), 4u);  // corners shared between the two faces are merged
  ASSERT_EQ(mesh.indices.size(), 6u);
  EXPECT_EQ(mesh.indices[1], mesh.indices[3]);
  EXPECT_EQ(mesh.indices[2], mesh.indices[5]);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(mesh.uvs[i], Vec2(mesh.positions[i].x, mesh.positions[i].y));
}

TEST_F(MeshIoTest, ObjPartialAttributesAreDroppedWithoutSplittingVertices) {
  // Only the first face has normals and only the second has uvs: neither attribute is complete.
  const fs::path path = write("partial.obj",
                              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvn 0 0 1\n"
                              "f 1//1 2//1 3//1\nf 2/1 4/1 3/1\n");
  const MeshData mesh = load_mesh(path);
  expect_indices_valid(mesh);
  EXPECT_TRUE(mesh.normals.empty());
  EXPECT_TRUE(mesh.uvs.empty());
  EXPECT_EQ(mesh.positions.size(), 4u);
  EXPECT_EQ(mesh.indices.size(), 6u);
}

TEST_F(MeshIoTest, ObjMergesGroupsAndResolvesRelativeIndices) {
  // The .mtl file does not exist: kozu ignores OBJ materials, so this must still load.
  const fs::path path = write("groups.OBJ", R"(mtllib missing.mtl
o first
v 0 0 0
v 1 0 0
v 0 1 0
usemtl red
f -3 -2 -1
g second
v 0 0 1
v 1 0 1
v 0 1 1
usemtl blue
f 4 5 6
)");
  const MeshData mesh = load_mesh(path);  // upper-case extension dispatches too
  expect_indices_valid(mesh);
  ASSERT_EQ(mesh.indices.size(), 6u);
  ASSERT_EQ(mesh.positions.size(), 6u);
  const Vec3 expected[6] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  for (size_t k = 0; k < 6; ++k) EXPECT_EQ(mesh.positions[mesh.indices[k]], expected[k]) << "corner " << k;
}

TEST_F(MeshIoTest, ObjIndexOutOfRange) {
  expect_error(write("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n# comment\nf 1 2 9\n"),
               {"line 5", "face index 9 out of range (mesh has 3 vertices)"});
  expect_error(write("bad_relative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 -2 -1\n"),
               {"line 4", "relative face index -4 out of range"});
  expect_error(write("bad_normal.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n"),
               {"line 5", "normal index 2 out of range"});
  expect_error(write("zero_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"), {"line 4", "index 0 is invalid"});
}

TEST_F(MeshIoTest, ObjRejectsBadNumbersAndShortFaces) {
  expect_error(write("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"), {"line 2", "non-finite coordinate 'nan'"});
  expect_error(write("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1e39 0\nf 1 2 3\n"), {"line 3", "exceeds the float range"});
  expect_error(write("junk.obj", "v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n"), {"line 2", "invalid number 'zero'"});
  expect_error(write("short_v.obj", "v 0 0\n"), {"line 1", "'v' needs 3 values, found 2"});
  expect_error(write("two.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n"), {"line 4", "face has 2 vertices"});
  expect_error(write("slash.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/ 2 3\n"), {"line 4", "malformed face vertex '1/'"});
}

// ---------------------------------------------------------------------------------------------
// Dispatch and file errors

TEST_F(MeshIoTest, MissingFile) {
  expect_error(dir_ / "missing.obj", {"cannot open file", "No such file or directory"});
  expect_error(dir_ / "missing.ply", {"cannot open file", "No such file or directory"});
}

TEST_F(MeshIoTest, UnknownExtension) {
  expect_error(write("mesh.xyz", "v 0 0 0\n"), {"unsupported mesh format '.xyz' (expected .obj or .ply)"});
  expect_error(write("mesh", "v 0 0 0\n"), {"no extension"});
}

// ---------------------------------------------------------------------------------------------
// PLY

enum class PlyFormat { Ascii, LittleEndian, BigEndian };

const char* format_name(PlyFormat f) {
  switch (f) {
    case PlyFormat::Ascii:
      return "ascii";
    case PlyFormat::LittleEndian:
      return "binary_little_endian";
    case PlyFormat::BigEndian:
      return "binary_big_endian";
  }
  return "";
}

constexpr PlyFormat kAllFormats[] = {PlyFormat::Ascii, PlyFormat::LittleEndian, PlyFormat::BigEndian};

// The data section of a PLY file as typed values, encoded as text or as binary in either byte order.
class PlyBody {
 public:
  PlyBody& put(std::string_view type, double value) {
    values_.push_back({std::string(type), value, false});
    return *this;
  }
  PlyBody& put(std::string_view type, std::initializer_list<double> values) {
    for (double v : values) put(type, v);
    return *this;
  }
  PlyBody& end_element() {
    values_.back().ends_line = true;
    return *this;
  }

  std::string encode(PlyFormat format) const {
    std::string out;
    for (const Value& v : values_) {
      if (format == PlyFormat::Ascii) {
        const bool is_float = v.type == "float" || v.type == "float32" || v.type == "double" || v.type == "float64";
        out += is_float ? fmt::format("{}", v.value) : fmt::format("{}", int64_t(v.value));
        out += v.ends_line ? '\n' : ' ';
        continue;
      }
      const bool big = format == PlyFormat::BigEndian;
      if (v.type == "char" || v.type == "int8")
        append(out, uint8_t(int8_t(v.value)), big);
      else if (v.type == "uchar" || v.type == "uint8")
        append(out, uint8_t(v.value), big);
      else if (v.type == "short" || v.type == "int16")
        append(out, uint16_t(int16_t(v.value)), big);
      else if (v.type == "ushort" || v.type == "uint16")
        append(out, uint16_t(v.value), big);
      else if (v.type == "int" || v.type == "int32")
        append(out, uint32_t(int32_t(v.value)), big);
      else if (v.type == "uint" || v.type == "uint32")
        append(out, uint32_t(v.value), big);
      else if (v.type == "float" || v.type == "float32")
        append(out, std::bit_cast<uint32_t>(float(v.value)), big);
      else if (v.type == "double" || v.type == "float64")
        append(out, std::bit_cast<uint64_t>(v.value), big);
      else
        ADD_FAILURE() << "unknown type in test writer: " << v.type;
    }
    return out;
  }

 private:
  struct Value {
    std::string type;
    double value;
    bool ends_line;
  };

  template <typename U>
  static void append(std::string& out, U bits, bool big_endian) {
    for (size_t i = 0; i < sizeof(U); ++i) {
      const size_t shift = 8 * (big_endian ? sizeof(U) - 1 - i : i);
      out += char((uint64_t(bits) >> shift) & 0xff);
    }
  }

  std::vector<Value> values_;
};

std::string ply_file(PlyFormat format, std::string_view header_lines, const PlyBody& body) {
  return fmt::format("ply\nformat {} 1.0\n{}end_header\n", format_name(format), header_lines) + body.encode(format);
}

// Two faces, a quad and a triangle, over five vertices with normals and uvs (uv = (x / 2, y)).
constexpr std::string_view kQuadAndTriangleHeader =
    "comment written by test_mesh_io\n"
    "element vertex 5\n"
    "property float x\nproperty float y\nproperty float z\n"
    "property float nx\nproperty float ny\nproperty float nz\n"
    "property float u\nproperty float v\n"
    "element face 2\n"
    "property list uchar int vertex_indices\n";

PlyBody quad_and_triangle_body() {
  PlyBody b;
  const float xy[5][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {2, 0.5f}};
  for (const auto& p : xy) b.put("float", {p[0], p[1], 0, 0, 0, 1, p[0] / 2, p[1]}).end_element();
  b.put("uchar", 4).put("int", {0, 1, 2, 3}).end_element();
  b.put("uchar", 3).put("int", {1, 4, 2}).end_element();
  return b;
}

TEST_F(MeshIoTest, PlyAsciiAndBinaryGiveIdenticalMeshes) {
  std::vector<MeshData> meshes;
  for (PlyFormat f : kAllFormats) {
    SCOPED_TRACE(format_name(f));
    const fs::path path = write(fmt::format("mesh_{}.ply", format_name(f)),
                                ply_file(f, kQuadAndTriangleHeader, quad_and_triangle_body()));
    meshes.push_back(load_mesh(path));
    const MeshData& mesh = meshes.back();
    expect_indices_valid(mesh);
    ASSERT_EQ(mesh.positions.size(), 5u);
    ASSERT_EQ(mesh.normals.size(), 5u);
    ASSERT_EQ(mesh.uvs.size(), 5u);
    EXPECT_EQ(mesh.positions[4], Vec3(2, 0.5f, 0));
    EXPECT_EQ(mesh.normals[4], Vec3(0, 0, 1));
    EXPECT_EQ(mesh.uvs[4], Vec2(1, 0.5f));
    // The quad is fan-triangulated from its first corner.
    EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 1, 4, 2}));
    for (size_t t = 0; t < 3; ++t) EXPECT_GT(triangle_cross(mesh, t).z, 0.0f);
  }
  for (size_t i = 1; i < meshes.size(); ++i) {
    EXPECT_EQ(meshes[i].positions, meshes[0].positions) << format_name(kAllFormats[i]);
    EXPECT_EQ(meshes[i].normals, meshes[0].normals) << format_name(kAllFormats[i]);
    EXPECT_EQ(meshes[i].uvs, meshes[0].uvs) << format_name(kAllFormats[i]);
    EXPECT_EQ(meshes[i].indices, meshes[0].indices) << format_name(kAllFormats[i]);
  }
}

TEST_F(MeshIoTest, PlySkipsUnknownElementsAndProperties) {
  // Unknown elements before, between and after the known ones, unknown scalar and list properties
  // inside vertex and face, and the face element ahead of the vertex element.
  constexpr std::string_view header =
      "obj_info unknown elements everywhere\n"
      "element material 2\n"
      "property uchar red\nproperty list ushort double weights\nproperty float shininess\n"
      "element face 1\n"
      "property int flags\nproperty list uint8 int32 vertex_index\nproperty list int float texcoord\n"
      "element vertex 4\n"
      "property double x\nproperty double y\nproperty double z\n"
      "property list uchar float extra\nproperty uchar red\nproperty int8 flag\n"
      "element edge 2\n"
      "property int vertex1\nproperty int vertex2\n"
      "element marker 1000000000000\n";  // no properties, so no data despite the count
  PlyBody body;
  body.put("uchar", 255).put("ushort", 3).put("double", {0.5, 0.25, 0.125}).put("float", 10.5).end_element();
  body.put("uchar", 0).put("ushort", 0).put("float", 1).end_element();
  body.put("int", -1).put("uint8", 4).put("int32", {0, 1, 2, 3});
  body.put("int", 8).put("float", {0, 0, 1, 0, 1, 1, 0, 1}).end_element();
  const double xyz[4][3] = {{0.1, 0, 0}, {1, 0, 0}, {1, 1, -0.3}, {0, 1, 1e-3}};
  for (size_t i = 0; i < 4; ++i) {
    body.put("double", {xyz[i][0], xyz[i][1], xyz[i][2]});
    body.put("uchar", double(i));  // the unknown list has i entries
    for (size_t k = 0; k < i; ++k) body.put("float", 7.5 + double(k));
    body.put("uchar", 200).put("int8", -3).end_element();
  }
  body.put("int", {0, 1}).end_element().put("int", {2, 3}).end_element();

  for (PlyFormat f : kAllFormats) {
    SCOPED_TRACE(format_name(f));
    const fs::path path = write(fmt::format("unknown_{}.ply", format_name(f)), ply_file(f, header, body));
    const MeshData mesh = load_mesh(path);
    expect_indices_valid(mesh);
    EXPECT_TRUE(mesh.normals.empty());
    EXPECT_TRUE(mesh.uvs.empty());
    ASSERT_EQ(mesh.positions.size(), 4u);
    for (size_t i = 0; i < 4; ++i)
      EXPECT_EQ(mesh.positions[i], Vec3(float(xyz[i][0]), float(xyz[i][1]), float(xyz[i][2]))) << "vertex " << i;
    EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  }
}

TEST_F(MeshIoTest, PlyCountAndIndexTypesAndPolygonFans) {
  // A pentagon with int/uint lists, then a quad with ushort/short lists; s/t are read as uvs and
  // an incomplete normal (nx only) is ignored.
  for (const auto& [count_type, index_type] : {std::pair{"int", "uint"}, std::pair{"ushort", "short"},
                                               std::pair{"uint8", "uint32"}, std::pair{"char", "int16"}}) {
    for (PlyFormat f : kAllFormats) {
      SCOPED_TRACE(fmt::format("{} {} {}", format_name(f), count_type, index_type));
      const std::string header = fmt::format(
          "element vertex 5\nproperty float32 x\nproperty float32 y\nproperty float32 z\nproperty float nx\n"
          "property float s\nproperty float t\n"
          "element face 2\nproperty list {} {} vertex_indices\n",
          count_type, index_type);
      PlyBody body;
      const float xy[5][2] = {{0, 0}, {2, 0}, {3, 1}, {1, 2}, {-1, 1}};
      for (const auto& p : xy) body.put("float", {p[0], p[1], 0, 1, p[1], p[0]}).end_element();
      body.put(count_type, 5).put(index_type, {0, 1, 2, 3, 4}).end_element();
      body.put(count_type, 4).put(index_type, {4, 3, 2, 1}).end_element();
      const MeshData mesh = load_mesh(
          write(fmt::format("fan_{}_{}_{}.ply", format_name(f), count_type, index_type), ply_file(f, header, body)));
      expect_indices_valid(mesh);
      EXPECT_TRUE(mesh.normals.empty());
      ASSERT_EQ(mesh.uvs.size(), 5u);
      EXPECT_EQ(mesh.uvs[2], Vec2(1, 3));
      EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 4, 4, 3, 2, 4, 2, 1}));
    }
  }
}

TEST_F(MeshIoTest, PlyTruncatedBinary) {
  for (PlyFormat f : {PlyFormat::LittleEndian, PlyFormat::BigEndian}) {
    SCOPED_TRACE(format_name(f));
    const std::string full = ply_file(f, kQuadAndTriangleHeader, quad_and_triangle_body());
    // The last face is 1 + 3 * 4 bytes; cut into its second index.
    expect_error(write(fmt::format("cut_face_{}.ply", format_name(f)), full.substr(0, full.size() - 6)),
                 {"face 1", "unexpected end of file", "2 'face' elements"});
    // Vertices are 32 bytes each; stop half-way through vertex 3.
    const size_t header_size = full.find("end_header\n") + 11;
    expect_error(write(fmt::format("cut_vertex_{}.ply", format_name(f)), full.substr(0, header_size + 3 * 32 + 16)),
                 {"vertex 3", "unexpected end of file", "5 'vertex' elements"});
    // A list length far beyond the file's end fails without reading past it.
    std::string huge = ply_file(f,
                                "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                "element face 1\nproperty list uint int vertex_indices\n",
                                PlyBody().put("float", {0, 0, 0, 1, 0, 0, 0, 1, 0}).put("uint", 4000000000.0));
    expect_error(write(fmt::format("huge_list_{}.ply", format_name(f)), huge), {"face 0", "unexpected end of file"});
  }
  const std::string ascii = ply_file(PlyFormat::Ascii, kQuadAndTriangleHeader, quad_and_triangle_body());
  expect_error(write("cut.ply", ascii.substr(0, ascii.size() - 4)), {"face 1", "unexpected end of file"});
}

TEST_F(MeshIoTest, PlyRejectsNonFiniteCoordinates) {
  constexpr std::string_view header =
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\n";
  // Appended, not concatenated with +: GCC 12 at -O3 warns falsely (-Warray-bounds) on operator+ of these strings.
  std::string ascii = "ply\nformat ascii 1.0\n";
  ascii.append(header).append("end_header\n0 0 0\n1 0 0\n0 nan 0\n3 0 1 2\n");
  expect_error(write("nan.ply", ascii), {"vertex 2 (line 12)", "non-finite coordinate y = nan"});

  for (PlyFormat f : {PlyFormat::LittleEndian, PlyFormat::BigEndian}) {
    PlyBody body;
    body.put("float", {0, 0, 0, 1, 0, 0, 0, 1, INFINITY}).put("uchar", 3).put("int", {0, 1, 2});
    expect_error(write(fmt::format("inf_{}.ply", format_name(f)), ply_file(f, header, body)),
                 {"vertex 2", "non-finite coordinate z = inf"});
  }
  PlyBody big;
  big.put("double", {0, 0, 0, 1, 0, 0, 0, 1e300, 0}).put("uchar", 3).put("int", {0, 1, 2});
  expect_error(
      write("double_range.ply", ply_file(PlyFormat::LittleEndian,
                                         "element vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
                                         "element face 1\nproperty list uchar int vertex_indices\n",
                                         big)),
      {"vertex 2", "exceeds the float range"});
}

TEST_F(MeshIoTest, PlyRejectsBadFaces) {
  constexpr std::string_view header =
      "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 2\nproperty list uchar uint vertex_indices\n";
  for (PlyFormat f : kAllFormats) {
    SCOPED_TRACE(format_name(f));
    PlyBody vertices;
    vertices.put("float", {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});

    PlyBody out_of_range = vertices;
    out_of_range.put("uchar", 3).put("uint", {0, 1, 2}).end_element().put("uchar", 3).put("uint", {0, 2, 9});
    expect_error(write(fmt::format("range_{}.ply", format_name(f)), ply_file(f, header, out_of_range)),
                 {"face 1", "vertex index 9 out of range (mesh has 4 vertices)"});

    PlyBody two = vertices;
    two.put("uchar", 2).put("uint", {0, 1}).end_element().put("uchar", 3).put("uint", {0, 2, 3});
    expect_error(write(fmt::format("two_{}.ply", format_name(f)), ply_file(f, header, two)),
                 {"face 0", "face has 2 vertices (at least 3 required)"});
  }
}

TEST_F(MeshIoTest, PlyRejectsMalformedHeaders) {
  const std::string vertex = "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string data = "end_header\n0 0 0\n";
  expect_error(write("magic.ply", "plx\nformat ascii 1.0\n" + vertex + data), {"not a PLY file"});
  expect_error(write("format.ply", "ply\nformat binary_foo 1.0\n" + vertex + data),
               {"unsupported PLY format 'binary_foo'"});
  expect_error(write("version.ply", "ply\nformat ascii 2.0\n" + vertex + data), {"unsupported PLY version '2.0'"});
  expect_error(write("type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\n" + data),
               {"line 4", "unknown property type 'flaot'"});
  expect_error(write("orphan.ply", "ply\nformat ascii 1.0\nproperty float x\n" + vertex + data),
               {"line 3", "'property' before any 'element'"});
  expect_error(write("count.ply", "ply\nformat ascii 1.0\nelement vertex many\n" + data),
               {"line 3", "invalid element count 'many'"});
  expect_error(write("keyword.ply", "ply\nformat ascii 1.0\n" + vertex + "elements face 0\n" + data),
               {"line 7", "unexpected keyword 'elements'"});
  expect_error(write("float_count.ply", "ply\nformat ascii 1.0\n" + vertex +
                                            "element face 0\nproperty list float int vertex_indices\n" + data),
               {"line 8", "list count type 'float' is not an integer type"});
  expect_error(write("no_end.ply", "ply\nformat ascii 1.0\n" + vertex), {"no 'end_header' line"});
  expect_error(
      write("no_z.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n" + data),
      {"no scalar property 'z'"});
  expect_error(write("no_indices.ply",
                     "ply\nformat ascii 1.0\n" + vertex + "element face 0\nproperty list uchar int corners\n" + data),
               {"no 'vertex_indices' list property"});
}

}  // namespace
}  // namespace kozu
