// Keyframed camera animation (the scene's "animation" block; docs/production.md#animation): the camera's position,
// look-at point and field of view at any time, from keys at given times. Positions and look-at points follow a
// Catmull–Rom spline through the keys (Catmull & Rom 1974) in its non-uniform form: a cubic Hermite segment between
// keys i and i+1 with tangents m_i = (p_{i+1} − p_{i−1}) / (t_{i+1} − t_{i−1}) (one-sided at the ends), so uneven
// key spacing keeps a smooth speed; the field of view takes the same spline. Before the first key and after the
// last the camera holds still.
#pragma once

#include "core/json_reader.h"
#include "core/math.h"
#include "scene/camera.h"

#include <vector>

namespace kozu {

struct CameraKey {
  double time = 0.0;  // seconds
  Vec3 position{0.0f}, look_at{0.0f, 0.0f, -1.0f};
  float fov = 40.0f;  // degrees, vertical
};

// The camera's pose as a key (time 0): the still an animation's keys take what they leave out from.
inline CameraKey camera_key(const Camera& c) { return {0.0, c.position(), c.look_at(), c.fov()}; }

struct Animation {
  static constexpr int kMaxFrames = 1000000;
  double fps = 24.0;
  int frames = 0;                 // 0: no animation
  std::vector<CameraKey> camera;  // increasing times; empty: the scene's camera in every frame

  bool animated() const { return frames > 0; }
  // The camera's pose at `time` (seconds); `still` when there are no keys.
  CameraKey camera_at(double time, const CameraKey& still) const;
};

// Reads an "animation" object; keys may leave out position, look_at or fov, which then come from `still` (the
// scene's camera). Fails at the JSON path for unsorted times, a key whose look_at is its position, and the parts
// not implemented yet ("shapes", "shutter") rather than ignoring them.
Animation parse_animation(const JsonObject& a, const CameraKey& still);

}  // namespace kozu
