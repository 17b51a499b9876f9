#include "geometry/shape_registry.h"

#include "core/error.h"
#include "core/file_io.h"
#include "core/input_bounds.h"
#include "geometry/mesh_cleanup.h"
#include "geometry/polygon.h"

#include <fmt/format.h>

#include <algorithm>
#include <optional>

namespace kozu {

namespace {

std::unique_ptr<Shape> make_mesh(MeshData&& m, bool keep_groups = false) {
  auto mesh = std::make_unique<TriangleMesh>(std::move(m.positions), std::move(m.indices), std::move(m.normals),
                                             std::move(m.uvs), std::move(m.tangents));
  if (keep_groups) mesh->set_groups(std::move(m.groups), std::move(m.group_names));
  return mesh;
}

// A "transform" that keeps angles moves and scales the sphere itself; any other makes an ellipsoid, which the
// scene loader places through an instance of this sphere (geometry/instance.h).
Deferred<Shape> parse_sphere(const JsonObject& s) {
  Vec3 center = get_point(s, "center");
  float radius = s.get_float("radius", {}, kSizeRange);
  if (s.has("transform")) {
    const Transform t = read_transform(s.get_object("transform"));
    if (float scale = 1.0f; t.is_similarity(&scale)) {
      center = t.point(center);
      radius *= scale;
      if (!within_bounds(center)) s.fail("center", bounds_message(center) + " after the transform");
      if (!(radius <= kSizeRange.hi))
        s.fail("radius", fmt::format("{:g} after the transform is beyond {:g}", radius, kSizeRange.hi));
    }
  }
  return std::make_unique<Sphere>(center, radius);
}

// quad and polygon: the vertices (transformed), checked against the coordinate bounds and triangulated
// (geometry/polygon.h).
Deferred<Shape> parse_polygon(const JsonObject& s) {
  const bool quad = s.get_string("type") == "quad";
  const JsonArray verts = s.get_array("vertices");
  if (quad && verts.size() != 4) verts.fail(fmt::format("a quad needs exactly 4 vertices, got {}", verts.size()));
  if (verts.size() < 3) verts.fail(fmt::format("a polygon needs at least 3 vertices, got {}", verts.size()));
  std::vector<Vec3> v(verts.size());
  for (size_t i = 0; i < v.size(); ++i) v[i] = verts.vec3(i);
  // Texture coordinates (docs/scene-format.md): a quad's corners map to (0, 0), (1, 0), (1, 1), (0, 1); a
  // polygon's points to their coordinates in scene units along e_u = (v1 − v0) / |v1 − v0| and e_v = n × e_u.
  std::vector<Vec2> uv(v.size());
  if (quad) {
    uv = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  } else {
    const Vec3 eu = glm::normalize(v[1] - v[0]);
    Vec3 n(0.0f);  // Newell's normal: robust for any simple polygon
    for (size_t i = 0; i < v.size(); ++i) n += glm::cross(v[i], v[(i + 1) % v.size()]);
    n /= max_component(glm::abs(n));  // its squared length overflows float for polygons wider than about 4e9
    const Vec3 ev = glm::normalize(glm::cross(glm::normalize(n), eu));
    for (size_t i = 0; i < v.size(); ++i) uv[i] = Vec2(glm::dot(v[i] - v[0], eu), glm::dot(v[i] - v[0], ev));
  }
  if (s.has("transform")) {
    const Transform t = read_transform(s.get_object("transform"));
    for (Vec3& p : v) p = t.point(p);
    // Mirroring transforms reverse the winding: restore the intended front side (each corner keeps its uv).
    if (t.determinant() < 0.0f) {
      std::reverse(v.begin(), v.end());
      std::reverse(uv.begin(), uv.end());
    }
  }
  for (const Vec3& p : v)
    if (!within_bounds(p)) s.fail("vertices", bounds_message(p) + (s.has("transform") ? " after the transform" : ""));
  MeshData mesh;
  try {
    mesh.indices = triangulate_polygon(v);
  } catch (const PolygonError& e) {
    s.fail("vertices", e.what());
  }
  mesh.positions = v;
  mesh.uvs = uv;
  return make_mesh(std::move(mesh));
}

// What a mesh needs after it is read: the transform, the coordinate bounds, and the degenerate triangles
// removed (or rejected). Errors name the shape, or its file key for the file's own triangles.
struct MeshFinish {
  std::optional<Transform> transform;
  bool skip_degenerate = false;
  std::filesystem::path file;  // empty for inline meshes

  void operator()(MeshData& mesh, const JsonObject& s) const {
    if (transform) transform_mesh(mesh, *transform);
    for (const Vec3& p : mesh.positions)
      if (!is_finite(p) || !within_bounds(p))
        s.fail(fmt::format("mesh vertex {}: {}", static_cast<size_t>(&p - mesh.positions.data()),
                           bounds_message(p) + (transform ? " after the transform" : "")));
    if (!skip_degenerate)
      if (const std::optional<size_t> t = first_degenerate_triangle(mesh)) {
        const std::string message =
            fmt::format("{}triangle {} is degenerate (zero area); set \"skip_degenerate\": true to drop such triangles",
                        file.empty() ? "" : file.filename().string() + ": ", *t);
        if (file.empty()) s.fail(message);
        s.fail("file", message);
      }
    remove_degenerate_triangles(mesh);
    if (mesh.indices.empty()) s.fail("mesh has no triangles");
  }
};

// mesh: a file (read by the load job) or inline positions and indices (and normals).
Deferred<Shape> parse_mesh(const JsonObject& s) {
  MeshFinish finish;
  MeshData inline_mesh;
  if (s.has("file")) {
    finish.file = s.get_path("file");
    if (s.has("positions")) s.fail("positions", "give either 'file' or inline 'positions'/'indices', not both");
  } else {
    const JsonArray pos = s.get_array("positions");
    const JsonArray idx = s.get_array("indices");
    for (size_t i = 0; i < pos.size(); ++i) inline_mesh.positions.push_back(pos.vec3(i));
    if (idx.size() % 3 != 0 || idx.size() == 0) idx.fail("expected a nonzero multiple of 3 vertex indices");
    const Range vertex{0.0, static_cast<double>(pos.size()), false, true};
    for (size_t i = 0; i < idx.size(); ++i)
      inline_mesh.indices.push_back(static_cast<uint32_t>(idx.integer(i, vertex)));
    if (s.has("normals")) {
      const JsonArray nrm = s.get_array("normals");
      if (nrm.size() != pos.size()) nrm.fail("expected one normal per position");
      for (size_t i = 0; i < nrm.size(); ++i) inline_mesh.normals.push_back(nrm.vec3(i));
    }
  }
  if (s.has("transform")) finish.transform = read_transform(s.get_object("transform"));
  finish.skip_degenerate = s.get_bool("skip_degenerate", false);
  // OBJ usemtl groups mapped to the scene's materials by name (the scene loader splits the mesh by them).
  const bool by_name = s.get_bool("materials_by_name", false);
  if (by_name && lower_extension(finish.file) != ".obj")
    s.fail("materials_by_name", "needs an OBJ file (its usemtl names are matched to the scene's materials)");
  if (finish.file.empty()) {
    finish(inline_mesh, s);
    return make_mesh(std::move(inline_mesh));
  }
  return Deferred<Shape>([s, finish, by_name]() -> std::unique_ptr<Shape> {
    MeshData mesh;
    try {
      mesh = load_mesh(finish.file);
    } catch (const InputError& e) {
      s.fail("file", e.what());
    } catch (const std::exception& e) {
      s.fail("file", fmt::format("{}: {}", finish.file.string(), e.what()));
    }
    finish(mesh, s);
    if (by_name && mesh.groups.empty()) {  // no usemtl: every face takes the shape's "material"
      mesh.groups.assign(mesh.indices.size() / 3, 0);
      mesh.group_names = {""};
    }
    return make_mesh(std::move(mesh), by_name);
  });
}

// "gltf" and "instance" shapes are read by the scene loader (a glTF file becomes shapes, materials and lights; an
// instance places one of the scene's "objects"), above this layer, so it never passes them here. Their rows make
// this table the one list of shape types, which the error for an unknown type quotes whole.
Deferred<Shape> parse_by_scene_loader(const JsonObject& s) {
  s.fail("type", "this shape type is read by the scene loader, not by parse_shape");
}

constexpr RegistryEntry<Shape> kShapes[] = {
    {"sphere", &parse_sphere}, {"quad", &parse_polygon},         {"polygon", &parse_polygon},
    {"mesh", &parse_mesh},     {"gltf", &parse_by_scene_loader}, {"instance", &parse_by_scene_loader},
};

}  // namespace

Deferred<Shape> parse_shape(const JsonObject& desc, std::string* type) {
  return parse_by_type(desc, kShapes, {}, type);
}

}  // namespace kozu
