// Planar polygons (the `polygon` shape): checked and triangulated by ear clipping in their plane.
#pragma once

#include "core/math.h"

#include <stdexcept>
#include <vector>

namespace kozu {

// A polygon that cannot be triangulated: degenerate, not planar, self-intersecting. The scene loader attaches
// the JSON path.
struct PolygonError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Triangle indices (3 per triangle) into `v` for a simple, planar polygon whose vertices run counter-clockwise
// seen from the front; non-convex polygons are handled. Throws PolygonError.
std::vector<uint32_t> triangulate_polygon(const std::vector<Vec3>& v);

}  // namespace kozu
