#include "scene/animation.h"

#include "core/input_bounds.h"
#include "core/transform.h"

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

// The index i of the key segment [t_i, t_{i+1}) holding `time`, for t.front() < time < t.back().
size_t segment(const std::vector<double>& t, double time) {
  return static_cast<size_t>(std::upper_bound(t.begin(), t.end(), time) - t.begin()) - 1;
}

// A key's transform split as T·R·S; fails at the key for a shear or a mirror, which have no such split.
ShapeKey split_transform(const Mat4& m, double time, const JsonObject& key) {
  ShapeKey k;
  k.time = time;
  k.translate = Vec3(m[3]);
  Mat3 r(m);
  for (int c = 0; c < 3; ++c) {
    k.scale[c] = glm::length(r[c]);
    r[c] /= k.scale[c];
  }
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b)
      if (std::abs(glm::dot(r[a], r[b])) > 1e-4f)
        key.fail("transform", "a shape key's transform must be a translation, rotation and scale (it shears)");
  if (glm::determinant(r) < 0.0f)
    key.fail("transform", "a shape key's transform must not mirror (a negative scale): mirror the shape itself");
  k.rotate = glm::normalize(glm::quat_cast(r));
  return k;
}

}  // namespace

Mat4 ShapeTrack::transform_at(double time) const {
  const auto compose = [](const Vec3& t, const glm::quat& r, const Vec3& s) {
    Mat4 m = glm::mat4_cast(r);
    for (int c = 0; c < 3; ++c) m[c] *= s[c];
    m[3] = Vec4(t, 1.0f);
    return m;
  };
  if (keys.size() == 1 || time <= keys.front().time) return compose(keys[0].translate, keys[0].rotate, keys[0].scale);
  if (time >= keys.back().time) return compose(keys.back().translate, keys.back().rotate, keys.back().scale);
  std::vector<double> t;
  std::vector<Vec3> p;
  for (const ShapeKey& k : keys) {
    t.push_back(k.time);
    p.push_back(k.translate);
  }
  const size_t i = segment(t, time);
  const float s = static_cast<float>((time - t[i]) / (t[i + 1] - t[i]));
  // glm::slerp takes the shorter arc (it flips a quaternion whose dot with the other is negative).
  return compose(catmull_rom(t, p, i, time), glm::slerp(keys[i].rotate, keys[i + 1].rotate, s),
                 glm::mix(keys[i].scale, keys[i + 1].scale, s));
}

bool ShapeTrack::uniform_scale() const {
  for (const ShapeKey& k : keys)
    if (std::abs(k.scale.x - k.scale.y) > 1e-5f * k.scale.x || std::abs(k.scale.x - k.scale.z) > 1e-5f * k.scale.x)
      return false;
  return true;
}

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
  const size_t i = segment(t, time);
  CameraKey out;
  out.time = time;
  out.position = catmull_rom(t, p, i, time);
  out.look_at = catmull_rom(t, l, i, time);
  out.fov = std::clamp(catmull_rom(t, f, i, time), 1e-3f, 179.0f);
  return out;
}

double Animation::frame_time(int frame) const {
  const double mid = shutter ? 0.5 * (shutter->first + shutter->second) : 0.0;
  return (frame + mid) / fps;
}

std::vector<double> Animation::shutter_times(int frame) const {
  if (!shutter || !(shutter->second > shutter->first)) return {frame_time(frame)};
  std::vector<double> t(kShutterSteps);
  const double open = shutter->first, length = shutter->second - shutter->first;
  for (int i = 0; i < kShutterSteps; ++i) t[i] = (frame + open + length * (i + 0.5) / kShutterSteps) / fps;
  return t;
}

Animation parse_animation(const JsonObject& a, const CameraKey& still) {
  Animation anim;
  anim.fps = a.get_double("fps", 24.0, Range{0.0, 1000.0, true, false});
  anim.frames = a.get_int("frames", {}, Range::closed(1, Animation::kMaxFrames));
  if (a.has("shapes")) {
    const JsonObject shapes = a.get_object("shapes");
    for (const std::string& name : shapes.keys()) {
      const JsonArray keys = shapes.get_array(name);
      if (keys.size() == 0) keys.fail("expected at least one key");
      ShapeTrack track;
      track.name = name;
      track.json_path = shapes.path_of(name);
      for (size_t i = 0; i < keys.size(); ++i) {
        const JsonObject k = keys.object(i);
        const double time = k.get_double("time", {}, Range::non_negative());
        if (!track.keys.empty() && !(time > track.keys.back().time))
          k.fail("time", fmt::format("key times must increase: {} follows {}", time, track.keys.back().time));
        const ShapeKey key = split_transform(read_transform(k.get_object("transform")).matrix(), time, k);
        // Posed geometry must stay inside kozu's coordinate range: translations within it, scales bounded.
        if (!within_bounds(key.translate)) k.fail("transform", bounds_message(key.translate) + " (the translation)");
        if (!(min_component(key.scale) >= 1e-6f && max_component(key.scale) <= 1e6f))
          k.fail("transform", "a shape key's scale factors must lie in [1e-6, 1e6]");
        track.keys.push_back(key);
        k.finish();
      }
      anim.shapes.push_back(std::move(track));
    }
    shapes.finish(shapes.keys());
  }
  if (a.has("shutter")) {
    const JsonArray sh = a.get_array("shutter");
    if (sh.size() != 2) sh.fail("expected [open, close] in frames, e.g. [-0.25, 0.25]");
    const Range frames{-1.0, 1.0, false, false};
    const double open = sh.number(0, frames), close = sh.number(1, frames);
    if (!(close >= open)) sh.fail(fmt::format("the shutter closes ({}) before it opens ({})", close, open));
    if (close - open > 1.0) sh.fail(fmt::format("the shutter is open {} frames: at most 1", close - open));
    anim.shutter = std::make_pair(open, close);
  }
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
      k.finish();
      anim.camera.push_back(key);
    }
  }
  a.finish({"fps", "frames", "camera", "shapes", "shutter"});
  return anim;
}

}  // namespace kozu
