#include "scene/animation.h"

#include "core/input_bounds.h"

#include <fmt/format.h>

#include <algorithm>

namespace kozu {

namespace {

// The non-uniform Catmull–Rom value at time t between keys i and i+1 of (times, values).
template <class T>
T catmull_rom(const std::vector<double>& t, const std::vector<T>& v, size_t i, double time) {
  const size_t n = t.size();
  const auto tangent = [&](size_t k) -> T {
    const size_t a = k == 0 ? 0 : k - 1, b = std::min(k + 1, n - 1);
    return (v[b] - v[a]) * static_cast<float>(1.0 / (t[b] - t[a]));
  };
  const double h = t[i + 1] - t[i];
  const float s = static_cast<float>((time - t[i]) / h);
  const float s2 = s * s, s3 = s2 * s;
  // Cubic Hermite basis.
  const float h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
  const float hf = static_cast<float>(h);
  return v[i] * h00 + tangent(i) * (h10 * hf) + v[i + 1] * h01 + tangent(i + 1) * (h11 * hf);
}

}  // namespace

CameraKey Animation::camera_at(double time, const CameraKey& still) const {
  if (camera.empty()) return still;
  if (camera.size() == 1 || time <= camera.front().time) return camera.front();
  if (time >= camera.back().time) return camera.back();
  std::vector<double> t;
  std::vector<Vec3> p, l;
  std::vector<float> f;
  for (const CameraKey& k : camera) {
    t.push_back(k.time);
    p.push_back(k.position);
    l.push_back(k.look_at);
    f.push_back(k.fov);
  }
  const size_t i = static_cast<size_t>(std::upper_bound(t.begin(), t.end(), time) - t.begin()) - 1;
  CameraKey out;
  out.time = time;
  out.position = catmull_rom(t, p, i, time);
  out.look_at = catmull_rom(t, l, i, time);
  out.fov = std::clamp(catmull_rom(t, f, i, time), 1e-3f, 179.0f);
  return out;
}

Animation parse_animation(const JsonObject& a, const CameraKey& still) {
  Animation anim;
  anim.fps = a.get_double("fps", 24.0, Range{0.0, 1000.0, true, false});
  anim.frames = a.get_int("frames", {}, Range::closed(1, Animation::kMaxFrames));
  if (a.has("shapes"))
    a.fail("shapes", "shape keyframes are not implemented yet: only the camera can be animated (docs/production.md)");
  if (a.has("shutter")) a.fail("shutter", "motion blur is not implemented yet (docs/production.md)");
  if (a.has("camera")) {
    const JsonArray keys = a.get_array("camera");
    if (keys.size() == 0) keys.fail("expected at least one key");
    for (size_t i = 0; i < keys.size(); ++i) {
      const JsonObject k = keys.object(i);
      CameraKey key;
      key.time = k.get_double("time", {}, Range::non_negative());
      key.position = k.has("position") ? get_point(k, "position") : still.position;
      key.look_at = k.has("look_at") ? get_point(k, "look_at") : still.look_at;
      key.fov = k.get_float("fov", still.fov, Range{0.0, 180.0, true, true});
      if (!(glm::length(key.look_at - key.position) > 0.0f)) k.fail("look_at", "look_at must differ from position");
      if (!anim.camera.empty() && !(key.time > anim.camera.back().time))
        k.fail("time", fmt::format("key times must increase: {} follows {}", key.time, anim.camera.back().time));
      k.ignore("comment");
      k.finish();
      anim.camera.push_back(key);
    }
  }
  a.ignore("comment");
  a.finish({"fps", "frames", "camera"});
  return anim;
}

}  // namespace kozu
