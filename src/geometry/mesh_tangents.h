// Per-vertex tangent frames for normal mapping, computed the way MikkTSpace defines them as far as shading needs:
// Mikkelsen 2008, "Simulation of Wrinkled Surfaces Revisited" (M.Sc. thesis, University of Copenhagen), §4.2–4.3
// and appendix (the mikktspace reference implementation's conventions).
//
//  - per triangle, the tangent T = dp/du and bitangent B = dp/dv from its positions and texture coordinates;
//  - per vertex, both projected onto the plane of the vertex normal, normalized, and accumulated weighted by the
//    triangle's angle at that corner;
//  - the sum is orthogonalized against the vertex normal (Gram–Schmidt) and normalized; the handedness
//    w = sign(dot(cross(n, t), b)) (−1 where the texture is mirrored).
// At a hit (TriangleMesh::tangent) the corners' tangents are interpolated, re-orthogonalized against the
// interpolated shading normal, and b = w · cross(n, t): the tangent space a MikkTSpace baker assumes.
//
// Deviation from the full mikktspace.c: it splits a vertex whose corners disagree (mirrored and non-mirrored
// triangles meeting at a seam, or tangents far apart) into several tangent spaces and welds corners with equal
// position, normal and uv across the mesh. kozu keeps the mesh's vertices as they are (one tangent space per
// vertex): at a vertex where mirrored and non-mirrored triangles meet, the larger angle-weighted side decides the
// sign, so normal maps baked by MikkTSpace can differ there (along UV mirror seams only). Meshes read from OBJ
// files already have one vertex per distinct (position, normal, uv) triple.
#pragma once

#include "core/math.h"

#include <vector>

namespace kozu {

// Tangents (xyz unit, w = ±1 handedness) for every vertex; normals and uvs have one entry per position. A vertex
// whose triangles all have degenerate texture coordinates gets an arbitrary tangent perpendicular to its normal
// (w = 1).
std::vector<Vec4> compute_vertex_tangents(const std::vector<Vec3>& positions, const std::vector<uint32_t>& indices,
                                          const std::vector<Vec3>& normals, const std::vector<Vec2>& uvs);

// dp/du and dp/dv of the triangle (p0, p1, p2) with texture coordinates (uv0, uv1, uv2); false (and zeros) when
// its texture coordinates are collinear.
bool triangle_uv_derivatives(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec2& uv0, const Vec2& uv1,
                             const Vec2& uv2, Vec3* dpdu, Vec3* dpdv);

}  // namespace kozu
