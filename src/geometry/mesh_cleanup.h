// Preparing a loaded triangle mesh for the accelerator: placing it in the scene and finding the triangles Embree
// cannot use (zero area).
#pragma once

#include "core/transform.h"
#include "io/mesh_io.h"

#include <optional>

namespace kozu {

// Transforms positions, normals and tangents; a mirroring transform swaps two corners of every triangle so that the
// front side stays the front.
void transform_mesh(MeshData& mesh, const Transform& t);

// A triangle has zero area when twice its area is not above 1e-12 times its longest squared edge (or all its
// corners coincide).
bool is_degenerate_triangle(const Vec3& a, const Vec3& b, const Vec3& c);
// The index of the first degenerate triangle, if any.
std::optional<size_t> first_degenerate_triangle(const MeshData& mesh);
// Removes the degenerate triangles; returns how many were removed.
size_t remove_degenerate_triangles(MeshData& mesh);

}  // namespace kozu
