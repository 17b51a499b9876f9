#include "geometry/polygon.h"

#include "core/frame.h"

#include <fmt/format.h>

#include <algorithm>

namespace kozu {

std::vector<uint32_t> triangulate_polygon(const std::vector<Vec3>& v) {
  const size_t n = v.size();
  // Newell's method: robust polygon normal with length = 2 * area.
  Vec3 normal(0.0f);
  for (size_t i = 0; i < n; ++i) {
    const Vec3& a = v[i];
    const Vec3& b = v[(i + 1) % n];
    normal += Vec3((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
  }
  float extent = 0.0f;
  for (size_t i = 1; i < n; ++i) extent = std::max(extent, glm::length(v[i] - v[0]));
  const float len = glm::length(normal);
  if (!(len > 1e-10f * extent * extent) || extent == 0.0f) throw PolygonError("degenerate polygon (zero area)");
  normal /= len;
  Vec3 centroid(0.0f);
  for (const Vec3& p : v) centroid += p;
  centroid /= static_cast<float>(n);
  for (size_t i = 0; i < n; ++i) {
    const float d = std::abs(glm::dot(v[i] - centroid, normal));
    if (d > 1e-4f * extent)
      throw PolygonError(fmt::format("polygon is not planar (vertex {} is {:.3g} off its plane)", i, d));
  }
  // Project to 2D and clip ears.
  const Frame frame(normal);
  std::vector<Vec2> p2(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec3 l = frame.to_local(v[i] - centroid);
    p2[i] = Vec2(l.x, l.y);
  }
  auto cross2 = [](const Vec2& a, const Vec2& b, const Vec2& c) {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  };
  // Ear clipping can succeed on a self-crossing outline (a pentagram) and return triangles that cover it wrongly:
  // any two edges that are not neighbours must be disjoint.
  const auto on_segment = [](const Vec2& a, const Vec2& b, const Vec2& q) {
    return std::min(a.x, b.x) <= q.x && q.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= q.y &&
           q.y <= std::max(a.y, b.y);
  };
  const auto segments_meet = [&](const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
    const float d1 = cross2(c, d, a), d2 = cross2(c, d, b), d3 = cross2(a, b, c), d4 = cross2(a, b, d);
    if (((d1 > 0.0f && d2 < 0.0f) || (d1 < 0.0f && d2 > 0.0f)) &&
        ((d3 > 0.0f && d4 < 0.0f) || (d3 < 0.0f && d4 > 0.0f)))
      return true;
    return (d1 == 0.0f && on_segment(c, d, a)) || (d2 == 0.0f && on_segment(c, d, b)) ||
           (d3 == 0.0f && on_segment(a, b, c)) || (d4 == 0.0f && on_segment(a, b, d));
  };
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // neighbours through the closing edge
      if (segments_meet(p2[i], p2[(i + 1) % n], p2[j], p2[(j + 1) % n]))
        throw PolygonError(
            fmt::format("polygon is self-intersecting (edges {}-{} and {}-{} meet)", i, (i + 1) % n, j, (j + 1) % n));
    }
  std::vector<uint32_t> remaining(n);
  for (size_t i = 0; i < n; ++i) remaining[i] = static_cast<uint32_t>(i);
  std::vector<uint32_t> indices;
  size_t guard = 0;
  while (remaining.size() > 3) {
    bool clipped = false;
    const size_t m = remaining.size();
    for (size_t i = 0; i < m; ++i) {
      const uint32_t a = remaining[(i + m - 1) % m], b = remaining[i], c = remaining[(i + 1) % m];
      if (cross2(p2[a], p2[b], p2[c]) <= 0.0f) continue;  // reflex or collinear corner
      bool contains = false;
      for (uint32_t q : remaining) {
        if (q == a || q == b || q == c) continue;
        if (cross2(p2[a], p2[b], p2[q]) >= 0.0f && cross2(p2[b], p2[c], p2[q]) >= 0.0f &&
            cross2(p2[c], p2[a], p2[q]) >= 0.0f) {
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
