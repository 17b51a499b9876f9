// Keyframed camera animation (the scene's "animation" block; docs/production.md#animation): the camera's position,
// look-at point and field of view at any time, from keys at given times. Positions and look-at points follow a
// Catmull–Rom spline through the keys (Catmull & Rom 1974) in its non-uniform form: a cubic Hermite segment between
// keys i and i+1 with tangents m_i = (p_{i+1} − p_{i−1}) / (t_{i+1} − t_{i−1}) (one-sided at the ends), so uneven
// key spacing keeps a smooth speed; the field of view takes the same spline. Before the first key and after the
// last the camera holds still.
//
// Shapes move by keyed transforms ("shapes": {NAME: [{time, transform}]}), each key split into translation,
// rotation and scale (T·R·S, no shear): the translation follows the same Catmull–Rom spline, the rotation a
// spherical linear interpolation (Shoemake 1985, "Animating rotation with quaternion curves") between the two keys
// around the time, the scale a linear one (a spline could overshoot through zero). A key's transform replaces the
// shape's own "transform": it places the shape's geometry as authored before that transform.
#pragma once

#include "core/json_reader.h"
#include "core/math.h"
#include "scene/camera.h"

#include <glm/gtc/quaternion.hpp>

#include <optional>
#include <utility>

#include <string>
#include <vector>

namespace kozu {

struct CameraKey {
  double time = 0.0;  // seconds
  Vec3 position{0.0f}, look_at{0.0f, 0.0f, -1.0f};
  float fov = 40.0f;  // degrees, vertical
};

// The camera's pose as a key (time 0): the still an animation's keys take what they leave out from.
inline CameraKey camera_key(const Camera& c) { return {0.0, c.position(), c.look_at(), c.fov()}; }

// One key of a shape: its transform at `time`, split as T·R·S.
struct ShapeKey {
  double time = 0.0;
  Vec3 translate{0.0f};
  glm::quat rotate{1.0f, 0.0f, 0.0f, 0.0f};
  Vec3 scale{1.0f};
};

// The keys of the shapes with one name.
struct ShapeTrack {
  std::string name;
  std::string json_path;       // "/animation/shapes/NAME", for messages
  std::vector<ShapeKey> keys;  // increasing times, at least one
  // The object-to-world transform at `time` (held before the first key and after the last).
  Mat4 transform_at(double time) const;
  bool uniform_scale() const;  // every key scales x, y and z alike (spheres need it)
};

struct Animation {
  static constexpr int kMaxFrames = 1000000;
  double fps = 24.0;
  int frames = 0;                 // 0: no animation
  std::vector<CameraKey> camera;  // increasing times; empty: the scene's camera in every frame
  std::vector<ShapeTrack> shapes;  // in the file's order
  // Camera motion blur: the shutter is open from frame + open to frame + close, in frames (e.g. [-0.25, 0.25], a
  // 180° shutter centred on the frame). Each camera sample takes a time in it; shapes stand at its middle.
  std::optional<std::pair<double, double>> shutter;
  static constexpr int kShutterSteps = 256;  // camera poses tabulated across the open shutter

  bool animated() const { return frames > 0; }
  // The camera's pose at `time` (seconds); `still` when there are no keys.
  CameraKey camera_at(double time, const CameraKey& still) const;
  // The time (seconds) the frame's shapes stand at: the middle of the open shutter, or the frame's own time.
  double frame_time(int frame) const;
  // The times (seconds) of the camera poses a frame's samples choose from: kShutterSteps equally spaced across the
  // open shutter (the midpoints of equal intervals), or the frame's time alone without a shutter.
  std::vector<double> shutter_times(int frame) const;
};

// Reads an "animation" object; keys may leave out position, look_at or fov, which then come from `still` (the
// scene's camera). Fails at the JSON path for unsorted times, a key whose look_at is its position, a shape key
// whose transform shears or mirrors, and a shutter open longer than a frame or beyond the neighbouring frames,
// rather than ignoring them. Shape names are matched to the scene's shapes by the loader.
Animation parse_animation(const JsonObject& a, const CameraKey& still);

}  // namespace kozu
