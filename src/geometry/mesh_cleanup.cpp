#include "geometry/mesh_cleanup.h"

#include <algorithm>

namespace kozu {

void transform_mesh(MeshData& mesh, const Transform& t) {
  for (Vec3& p : mesh.positions) p = t.point(p);
  for (Vec3& n : mesh.normals) n = t.normal(n);
  // Tangents move as vectors; a mirroring transform reverses the frame's handedness: det[Mt, Mb, M^-T n] has the
  // sign of det M times that of det[t, b, n].
  const float handedness = t.determinant() < 0.0f ? -1.0f : 1.0f;
  for (Vec4& tw : mesh.tangents) tw = Vec4(t.vector(Vec3(tw)), tw.w * handedness);
  if (t.determinant() < 0.0f)
    for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) std::swap(mesh.indices[i + 1], mesh.indices[i + 2]);
}

bool is_degenerate_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const float area2 = glm::length(glm::cross(b - a, c - a));
  const float edge2 = std::max({length_sq(b - a), length_sq(c - b), length_sq(a - c)});
  return !(area2 > 1e-12f * edge2) || edge2 == 0.0f;
}

namespace {
bool degenerate_at(const MeshData& mesh, size_t i) {
  return is_degenerate_triangle(mesh.positions[mesh.indices[i]], mesh.positions[mesh.indices[i + 1]],
                                mesh.positions[mesh.indices[i + 2]]);
}
}  // namespace

std::optional<size_t> first_degenerate_triangle(const MeshData& mesh) {
  for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3)
    if (degenerate_at(mesh, i)) return i / 3;
  return std::nullopt;
}

size_t remove_degenerate_triangles(MeshData& mesh) {
  std::vector<uint32_t> kept, kept_groups;
  kept.reserve(mesh.indices.size());
  const bool grouped = mesh.groups.size() * 3 == mesh.indices.size() && !mesh.groups.empty();
  size_t removed = 0;
  for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
    if (degenerate_at(mesh, i)) {
      ++removed;
      continue;
    }
    kept.insert(kept.end(), {mesh.indices[i], mesh.indices[i + 1], mesh.indices[i + 2]});
    if (grouped) kept_groups.push_back(mesh.groups[i / 3]);
  }
  mesh.indices = std::move(kept);
  if (grouped) mesh.groups = std::move(kept_groups);
  return removed;
}

}  // namespace kozu
