// voxelize_mesh: turns a triangle mesh into a VoxelGrid of area density and SGGX matrices S, the surface-to-volume
// conversion of Heitz et al. 2015, "The SGGX Microflake Distribution" (ACM TOG 34(4),
// SIGGRAPH 2015: §4.3 "parameter estimation for arbitrary distributions", §6 Fig. 17–18, whose tree is a voxelized
// surface).
//
// Box. The mesh's bounding box, enlarged to cubic voxels of edge h = L / (N - 3), with L the longest extent and N
// the resolution: the longest axis gets N voxels, every other axis floor(extent / h) + 3, and the box is centred
// on the mesh. That leaves an empty border of more than one voxel on every side (1.5 voxels on the longest axis),
// so the clamp-to-edge interpolation of VoxelGrid fades to 0 before the box ends, and faces of the mesh's
// bounding box (a cube's faces) never lie on a voxel face.
//
// Deposit. Exact clipping, not point sampling: each triangle is cut into its pieces inside each voxel (convex
// polygon clipping against the slabs x = i, then y = j, then z = k, in double precision), so each voxel receives
// exactly the area of the surface inside it, and the pieces sum to the triangle's area up to rounding. Voxels
// are half-open, [i, i + 1) in voxel units, so a triangle lying in a voxel face goes to the voxel above that
// face. Degenerate triangles are skipped.
//
// Per voxel, with A the area inside and V = h^3:
//   density ρ = A / V   (surface area per unit volume)
//   S = sggx::estimate_from_normals({(n_t, a_t)}) over the pieces (geometric normal n_t, area a_t),
// the paper's eq. (17–18) estimate for a discrete distribution of normals, which scales S so that σ(ω) is the
// area-weighted mean of |ω · n_t|. Then σ_t(ω) = ρ σ(ω) (eq. 2) = Σ a_t |ω · n_t| / V: the surface's
// projected area per unit volume, i.e. the mean number of times a line along ω crosses the surface per unit
// length. No other scaling is applied (the paper gives none): a ray through one flat surface layer sees an
// optical depth of 1 (transmittance e^-1), since the volume forgets that the surface's crossings are
// correlated (§6: "we ignore the correlation between voxels and visibility"); scenes that want an opaque
// look multiply the density. Empty voxels keep the default S (Sggx{}, isotropic), which density-weighted
// interpolation and filtering ignore.
//
// Threads. Triangles are clipped in parallel (oneTBB) in fixed chunks, the pieces are sorted by the unique key
// (voxel, triangle) (a triangle leaves at most one piece per voxel), and voxels are reduced in parallel, each in
// triangle order: the result is identical for any thread count.
#pragma once

#include "io/mesh_io.h"
#include "media/voxel_grid.h"

#include <cstddef>

namespace kozu {

struct VoxelizeStats {
  size_t triangles = 0;        // non-degenerate triangles deposited
  size_t pieces = 0;           // (triangle, voxel) pieces
  size_t occupied_voxels = 0;  // voxels with density > 0
  double mesh_area = 0;        // Σ triangle areas
  double deposited_area = 0;   // Σ density * voxel volume
};

// resolution: voxels along the longest axis, in [4, 1024]. Throws std::invalid_argument for an out-of-range
// resolution, a mesh with no triangle of positive area, or non-finite or zero-extent bounds.
VoxelGrid voxelize_mesh(const MeshData& mesh, int resolution, VoxelizeStats* stats = nullptr);

}  // namespace kozu
