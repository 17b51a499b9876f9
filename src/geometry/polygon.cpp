#include "geometry/polygon.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace kozu {

namespace {

using DVec2 = glm::dvec2;
using DVec3 = glm::dvec3;

// Twice the signed area of the triangle a, b, c (> 0 when counter-clockwise).
double cross2(const DVec2& a, const DVec2& b, const DVec2& c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

}  // namespace

std::vector<uint32_t> triangulate_polygon(const std::vector<Vec3>& v) {
  const size_t n = v.size();
  // Every test below runs on the vertices moved to their centroid and divided by their extent, in double: its
  // tolerances are then fractions of the polygon's size, so a polygon 10^-6 wide and one 2·10^10 wide (whose
  // squared lengths overflowed float: the normal became 0 and every edge seemed to touch every other) are judged
  // alike.
  DVec3 centroid(0.0);
  for (const Vec3& p : v) centroid += DVec3(p);
  centroid /= static_cast<double>(n);
  double extent = 0.0;
  for (const Vec3& p : v) extent = std::max(extent, glm::length(DVec3(p) - centroid));
  if (!(extent > 0.0) || !std::isfinite(extent)) throw PolygonError("degenerate polygon (zero area)");
  std::vector<DVec3> q(n);
  for (size_t i = 0; i < n; ++i) q[i] = (DVec3(v[i]) - centroid) / extent;
  // Newell's method: robust polygon normal with length = 2 * area (here in units of extent^2).
  DVec3 normal(0.0);
  for (size_t i = 0; i < n; ++i) {
    const DVec3& a = q[i];
    const DVec3& b = q[(i + 1) % n];
    normal += DVec3((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
  }
  const double len = glm::length(normal);
  if (!(len > 1e-10)) throw PolygonError("degenerate polygon (zero area)");
  normal /= len;
  for (size_t i = 0; i < n; ++i) {
    const double d = std::abs(glm::dot(q[i], normal));
    if (d > 1e-4)
      throw PolygonError(fmt::format("polygon is not planar (vertex {} is {:.3g} off its plane)", i, d * extent));
  }
  // Project to 2D (an orthonormal basis of the plane) and clip ears.
  const DVec3 axis = std::abs(normal.x) < 0.5 ? DVec3(1, 0, 0) : DVec3(0, 1, 0);
  const DVec3 s = glm::normalize(glm::cross(axis, normal)), t = glm::cross(normal, s);
  std::vector<DVec2> p2(n);
  for (size_t i = 0; i < n; ++i) p2[i] = DVec2(glm::dot(q[i], s), glm::dot(q[i], t));
  // Ear clipping can succeed on a self-crossing outline (a pentagram) and return triangles that cover it wrongly:
  // any two edges that are not neighbours must be disjoint. Doubled areas (about distances here) within kTouch of
  // the unit extent count as zero: float input puts a vertex meant to lie on an edge some 1e-7 of the extent off
  // it, on either side, and an outline that comes closer than that to itself is no simple polygon either.
  constexpr double kTouch = 1e-6;
  const auto sign = [](double x) { return x > kTouch ? 1 : x < -kTouch ? -1 : 0; };
  const auto on_segment = [](const DVec2& a, const DVec2& b, const DVec2& p) {
    return std::min(a.x, b.x) - kTouch <= p.x && p.x <= std::max(a.x, b.x) + kTouch &&
           std::min(a.y, b.y) - kTouch <= p.y && p.y <= std::max(a.y, b.y) + kTouch;
  };
  const auto segments_meet = [&](const DVec2& a, const DVec2& b, const DVec2& c, const DVec2& d) {
    const int d1 = sign(cross2(c, d, a)), d2 = sign(cross2(c, d, b)), d3 = sign(cross2(a, b, c)),
              d4 = sign(cross2(a, b, d));
    if (d1 * d2 < 0 && d3 * d4 < 0) return true;
    return (d1 == 0 && on_segment(c, d, a)) || (d2 == 0 && on_segment(c, d, b)) || (d3 == 0 && on_segment(a, b, c)) ||
           (d4 == 0 && on_segment(a, b, d));
  };
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // neighbours through the closing edge
      if (segments_meet(p2[i], p2[(i + 1) % n], p2[j], p2[(j + 1) % n]))
        throw PolygonError(
            fmt::format("polygon is self-intersecting (edges {}-{} and {}-{} meet)", i, (i + 1) % n, j, (j + 1) % n));
    }
  // Ear clipping's sign tests, on the same normalized coordinates: a vertex that lies on a diagonal in the input
  // may compute a hair outside it (rounding of the normalization, or a fused multiply-add), and an ear accepted for
  // that overlaps the rest. kRoundoff is far above double rounding on unit coordinates and far below any real
  // corner (a 1000-gon's corners have doubled areas of 2.5e-7).
  constexpr double kRoundoff = 1e-12;
  std::vector<uint32_t> remaining(n);
  for (size_t i = 0; i < n; ++i) remaining[i] = static_cast<uint32_t>(i);
  std::vector<uint32_t> indices;
  size_t guard = 0;
  while (remaining.size() > 3) {
    bool clipped = false;
    const size_t m = remaining.size();
    for (size_t i = 0; i < m; ++i) {
      const uint32_t a = remaining[(i + m - 1) % m], b = remaining[i], c = remaining[(i + 1) % m];
      if (cross2(p2[a], p2[b], p2[c]) <= kRoundoff) continue;  // reflex or collinear corner
      bool contains = false;
      for (uint32_t r : remaining) {
        if (r == a || r == b || r == c) continue;
        // A vertex on the ear's edge counts as inside (clipping that ear would overlap the rest).
        if (cross2(p2[a], p2[b], p2[r]) >= -kRoundoff && cross2(p2[b], p2[c], p2[r]) >= -kRoundoff &&
            cross2(p2[c], p2[a], p2[r]) >= -kRoundoff) {
          contains = true;
          break;
        }
      }
      if (contains) continue;
      indices.insert(indices.end(), {a, b, c});
      remaining.erase(remaining.begin() + static_cast<ptrdiff_t>(i));
      clipped = true;
      break;
    }
    if (!clipped || ++guard > 4 * n) throw PolygonError("polygon is self-intersecting or has collinear edges");
  }
  indices.insert(indices.end(), {remaining[0], remaining[1], remaining[2]});
  return indices;
}

}  // namespace kozu
