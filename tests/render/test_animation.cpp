// The keyframed camera (scene/animation.h): it passes through every key, its path and speed are continuous across
// keys (first derivatives from both sides agree, the Catmull–Rom property a linear blend lacks), and it holds still
// outside the keys' times. Keyed shapes: rotations turn at a constant rate on the shorter arc, and a scene whose
// shapes are posed at a time intersects like the same scene authored in that pose.
#include "scene/animation.h"

#include "core/transform.h"
#include "geometry/shape.h"
#include "integrators/path.h"
#include "render/renderer.h"
#include "scene/scene.h"
#include "scene/scene_loader.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

namespace kozu {
namespace {

Animation three_keys() {
  Animation a;
  a.fps = 24;
  a.frames = 48;
  a.camera = {{0.0, Vec3(0, 1, 5), Vec3(0), 40.0f},
              {0.5, Vec3(3, 1, 3), Vec3(0, 0.5f, 0), 30.0f},
              {2.0, Vec3(4, 2, -2), Vec3(1, 0, 0), 50.0f}};
  return a;
}

TEST(Animation, PassesThroughTheKeys) {
  const Animation a = three_keys();
  for (const CameraKey& k : a.camera) {
    const CameraKey c = a.camera_at(k.time, {});
    EXPECT_NEAR(glm::length(c.position - k.position), 0.0f, 1e-5f) << k.time;
    EXPECT_NEAR(glm::length(c.look_at - k.look_at), 0.0f, 1e-5f) << k.time;
    EXPECT_NEAR(c.fov, k.fov, 1e-4f) << k.time;
  }
}

TEST(Animation, VelocityIsContinuousAtAnInteriorKey) {
  const Animation a = three_keys();
  constexpr double h = 1e-3;
  const double t = 0.5;
  const Vec3 left = (a.camera_at(t, {}).position - a.camera_at(t - h, {}).position) / float(h);
  const Vec3 right = (a.camera_at(t + h, {}).position - a.camera_at(t, {}).position) / float(h);
  // Non-uniform Catmull–Rom tangent at the key: (p2 - p0) / (t2 - t0).
  const Vec3 expected = (a.camera[2].position - a.camera[0].position) / 2.0f;
  EXPECT_LT(glm::length(left - expected), 0.02f);
  EXPECT_LT(glm::length(right - expected), 0.02f);
  // A linear blend would jump from (p1 - p0) / 0.5 to (p2 - p1) / 1.5 here.
  EXPECT_GT(glm::length((a.camera[1].position - a.camera[0].position) / 0.5f - expected), 1.0f);
}

TEST(Animation, HoldsStillOutsideTheKeys) {
  const Animation a = three_keys();
  EXPECT_EQ(a.camera_at(-1.0, {}).position, a.camera.front().position);
  EXPECT_EQ(a.camera_at(10.0, {}).position, a.camera.back().position);
  CameraKey still;
  still.position = Vec3(7, 8, 9);
  EXPECT_EQ(Animation{}.camera_at(0.3, still).position, still.position);
}

// A key from its parts, and the matrix T·R·S it stands for, built by glm on its own.
ShapeKey key(double time, const Vec3& t, float degrees = 0.0f, const Vec3& axis = Vec3(0, 1, 0),
             const Vec3& scale = Vec3(1.0f)) {
  ShapeKey k;
  k.time = time;
  k.translate = t;
  k.rotate = glm::angleAxis(glm::radians(degrees), glm::normalize(axis));
  k.scale = scale;
  return k;
}
Mat4 matrix(const Vec3& t, float degrees = 0.0f, const Vec3& axis = Vec3(0, 1, 0), const Vec3& scale = Vec3(1.0f)) {
  return glm::translate(Mat4(1.0f), t) * glm::rotate(Mat4(1.0f), glm::radians(degrees), glm::normalize(axis)) *
         glm::scale(Mat4(1.0f), scale);
}

float max_difference(const Mat4& a, const Mat4& b) {
  float d = 0.0f;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) d = std::max(d, std::abs(a[c][r] - b[c][r]));
  return d;
}

TEST(ShapeTrack, PassesThroughTheKeysAndHoldsOutside) {
  ShapeTrack t;
  const Vec3 tilted = Vec3(1, 1, 0);
  t.keys = {key(0.5, Vec3(1, 2, 3), 0.0f, tilted, Vec3(2.0f)), key(1.0, Vec3(-4, 0, 1), 130.0f, tilted),
            key(3.0, Vec3(0.0f), -60.0f, Vec3(0, 0, 1), Vec3(1, 2, 0.5f))};
  const Mat4 m0 = matrix(Vec3(1, 2, 3), 0.0f, tilted, Vec3(2.0f)), m1 = matrix(Vec3(-4, 0, 1), 130.0f, tilted),
             m2 = matrix(Vec3(0.0f), -60.0f, Vec3(0, 0, 1), Vec3(1, 2, 0.5f));
  EXPECT_LT(max_difference(t.transform_at(0.5), m0), 1e-5f);
  EXPECT_LT(max_difference(t.transform_at(1.0), m1), 1e-5f);
  EXPECT_LT(max_difference(t.transform_at(3.0), m2), 1e-5f);
  EXPECT_LT(max_difference(t.transform_at(0.0), m0), 1e-5f);
  EXPECT_LT(max_difference(t.transform_at(9.0), m2), 1e-5f);
}

// Slerp: the angle grows linearly with time, about the keys' common axis; a 270° key is reached the short way
// (−90°), as a quaternion blend of the matrices' rotations must.
TEST(ShapeTrack, RotationsTurnAtAConstantRateTheShortWay) {
  const Vec3 axis = glm::normalize(Vec3(0.3f, 1.0f, -0.2f));
  for (float end : {90.0f, 170.0f, 270.0f}) {
    ShapeTrack t;
    t.keys = {key(0.0, Vec3(0.0f)), key(2.0, Vec3(0.0f), end, axis)};
    const float arc = end > 180.0f ? end - 360.0f : end;
    for (double time : {0.25, 0.5, 1.0, 1.5}) {
      const Mat4 expected = matrix(Vec3(0.0f), arc * float(time / 2.0), axis);
      EXPECT_LT(max_difference(t.transform_at(time), expected), 2e-5f) << end << " at " << time;
    }
  }
}

TEST(ShapeTrack, ScaleIsInterpolatedLinearlyAndTranslationThroughTheSpline) {
  ShapeTrack t;
  t.keys = {key(0.0, Vec3(0.0f)), key(1.0, Vec3(2, 0, 0), 0.0f, Vec3(0, 1, 0), Vec3(3.0f))};
  const Mat4 m = t.transform_at(0.25);
  EXPECT_NEAR(glm::length(Vec3(m[0])), 1.5f, 1e-5f);
  // Two keys: the non-uniform Catmull–Rom tangents are both the chord, so the path is the straight line.
  EXPECT_NEAR(m[3].x, 0.5f, 1e-5f);
  EXPECT_TRUE(t.uniform_scale());
  t.keys[1].scale.y = 2.0f;
  EXPECT_FALSE(t.uniform_scale());
}

// Closest hits of a grid of camera rays: the shape hit (its index in the scene) and the distance.
std::vector<std::pair<int, float>> hits(const Scene& scene) {
  std::vector<std::pair<int, float>> out;
  const Vec2i res = scene.camera.resolution();
  for (int y = 0; y < res.y; ++y)
    for (int x = 0; x < res.x; ++x) {
      const Ray r = scene.camera.generate_ray(Vec2(x + 0.5f, y + 0.5f), Vec2(0.5f));
      SurfaceInteraction si;
      if (!scene.intersect(r, si)) {
        out.emplace_back(-1, 0.0f);
        continue;
      }
      int index = -1;
      for (size_t i = 0; i < scene.shapes.size(); ++i)
        if (scene.shapes[i].get() == si.shape) index = static_cast<int>(i);
      out.emplace_back(index, si.t);
    }
  return out;
}

// A ball and a card (a quad with its own transform, which the keys replace), keyed at t = 0 and t = 1.
std::string animated_scene(const std::string& ball_pose, const std::string& card_transform,
                           const std::string& animation) {
  return fmt::format(R"({{
  "camera": {{"position": [0, 1.5, 6], "look_at": [0, 0.5, 0], "fov": 50, "resolution": [64, 48]}},
  "materials": {{"m": {{"type": "diffuse", "albedo": 0.5}}}},
  "shapes": [
    {{"type": "quad", "material": "m", "vertices": [[-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]]}},
    {{"name": "ball", "type": "sphere", {}, "material": "m"}},
    {{"name": "card", "type": "quad", "material": "m", "vertices": [[-0.5, 0, 0], [0.5, 0, 0], [0.5, 1, 0], [-0.5, 1, 0]],
      "transform": {}}}
  ]{}
}})",
                     ball_pose, card_transform, animation);
}

TEST(ShapeAnimation, PosedShapesIntersectLikeTheSceneAuthoredInThatPose) {
  const std::string keys = R"(, "animation": {"fps": 10, "frames": 11, "shapes": {
    "ball": [{"time": 0, "transform": {"translate": [-1.5, 0, 0]}},
             {"time": 1, "transform": {"translate": [1.5, 0.2, 0], "scale": 0.5}}],
    "card": [{"time": 0, "transform": {"translate": [1.5, 0, 0]}},
             {"time": 1, "transform": {"translate": [-1.5, 0, 0.5], "rotate": [0, 1, 0, 60]}}]}})";
  const auto scene = load_scene_text(
      animated_scene(R"("center": [0, 0.5, 0], "radius": 0.5)", R"({"translate": [3, 0, 0]})", keys), "a.json", ".");
  ASSERT_EQ(scene->animated_shapes.size(), 2u);
  const auto at_end = load_scene_text(animated_scene(R"("center": [1.5, 0.45, 0], "radius": 0.25)",
                                                     R"({"translate": [-1.5, 0, 0.5], "rotate": [0, 1, 0, 60]})", ""),
                                      "b.json", ".");
  const auto at_start = load_scene_text(
      animated_scene(R"("center": [-1.5, 0.5, 0], "radius": 0.5)", R"({"translate": [1.5, 0, 0]})", ""), "c.json", ".");
  const auto compare = [](const Scene& a, const Scene& b, const char* what) {
    const auto ha = hits(a), hb = hits(b);
    int ball = 0, card = 0;
    for (size_t i = 0; i < ha.size(); ++i) {
      ASSERT_EQ(ha[i].first, hb[i].first) << what << ", ray " << i;
      EXPECT_NEAR(ha[i].second, hb[i].second, 1e-4f * hb[i].second) << what << ", ray " << i;
      ball += ha[i].first == 1;
      card += ha[i].first == 2;
    }
    // Both moving shapes are in view, so the comparison sees them.
    EXPECT_GT(ball, 10) << what;
    EXPECT_GT(card, 10) << what;
  };
  scene->pose_shapes(1.0);
  compare(*scene, *at_end, "t = 1");
  // Poses are taken from the geometry as loaded each time: going back leaves no drift.
  scene->pose_shapes(0.0);
  compare(*scene, *at_start, "t = 0");
  scene->pose_shapes(0.5);
  const auto* ball = dynamic_cast<const Sphere*>(scene->shapes[1].get());
  ASSERT_NE(ball, nullptr);
  EXPECT_NEAR(glm::length(ball->center() - Vec3(0.0f, 0.5f * 0.75f + 0.1f, 0.0f)), 0.0f, 1e-5f);
  EXPECT_NEAR(ball->radius(), 0.375f, 1e-6f);
}

// Keys are bounded one by one, but a large shape scaled up still leaves the coordinate range: posing it fails with
// a message instead of handing Embree infinite coordinates.
TEST(ShapeAnimation, APoseBeyondTheCoordinateRangeIsRefused) {
  const auto scene = load_scene_text(
      animated_scene(R"("center": [0, 0, 0], "radius": 1e12)", R"({"translate": [0, 0, 0]})",
                     R"(, "animation": {"frames": 2, "shapes": {"ball": [{"time": 0, "transform": {"scale": 1e5}}]}})"),
      "big.json", ".");
  try {
    scene->pose_shapes(0.0);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'ball' leaves kozu's coordinate range"), std::string::npos) << e.what();
  }
}

// Three keyed emitters (a textured quad, a sphere, a two-triangle mesh) and the scene authored in their pose at
// t = 1: after posing, every area light of the first is the second's (its power, its share of light selection, and
// for the same numbers the same sample: point, direction, density and radiance), and posing back to t = 0 gives the
// lights of the scene authored there. A light that kept its loaded geometry would sample where the shape was.
std::string lamps_scene(const std::string& panel, const std::string& bulb, const std::string& strip,
                        const std::string& animation) {
  return fmt::format(R"({{
  "camera": {{"position": [0, 1.5, 6], "look_at": [0, 0.5, 0], "fov": 50, "resolution": [32, 24]}},
  "materials": {{"m": {{"type": "diffuse", "albedo": 0.5}}}},
  "shapes": [
    {{"type": "quad", "material": "m", "vertices": [[-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]]}},
    {{"name": "panel", "type": "quad", "vertices": [[-0.5, 0, 0], [0.5, 0, 0], [0.5, 0.6, 0], [-0.5, 0.6, 0]],
      "emission": {{"type": "checker", "scale": [3, 2], "a": [4, 2, 1], "b": [0.1, 0.2, 0.2]}}, "transform": {}}},
    {{"name": "bulb", "type": "sphere", {}, "emission": 5}},
    {{"name": "strip", "type": "mesh", "positions": [[0, 0, 0], [1, 0, 0], [1, 0.2, 0], [0, 0.2, 0]],
      "indices": [0, 1, 2, 0, 2, 3], "emission": [3, 3, 2], "transform": {}}}
  ]{}
}})",
                     panel, bulb, strip, animation);
}

void expect_same_lights(const Scene& a, const Scene& b, const char* what) {
  ASSERT_EQ(a.lights.size(), b.lights.size()) << what;
  ASSERT_EQ(a.lights.size(), 4u) << what;  // the panel, the bulb, two triangles
  const LightSampleContext refs[] = {{Vec3(0.3f, 0.1f, 2.0f), Vec3(0.0f)}, {Vec3(-2.0f, 3.0f, 1.0f), Vec3(0.0f)}};
  for (size_t i = 0; i < a.lights.size(); ++i) {
    const Light& la = *a.lights[i];
    const Light& lb = *b.lights[i];
    const Rgb pa = la.power(), pb = lb.power();
    EXPECT_NEAR(pa.r, pb.r, 1e-4f * pb.r) << what << ", light " << i;
    EXPECT_NEAR(a.light_sampler().pmf(&la), b.light_sampler().pmf(&lb), 1e-5f) << what << ", light " << i;
    for (const LightSampleContext& ctx : refs)
      for (const Vec2 u : {Vec2(0.2f, 0.7f), Vec2(0.9f, 0.1f), Vec2(0.5f, 0.5f)}) {
        const LightSample sa = la.sample(ctx, u), sb = lb.sample(ctx, u);
        ASSERT_EQ(sa.valid(), sb.valid()) << what << ", light " << i;
        if (!sb.valid()) continue;
        EXPECT_NEAR(glm::length(sa.p - sb.p), 0.0f, 1e-4f) << what << ", light " << i;
        EXPECT_NEAR(sa.pdf, sb.pdf, 1e-3f * sb.pdf) << what << ", light " << i;
        EXPECT_NEAR(sa.radiance.r, sb.radiance.r, 1e-4f * (1.0f + sb.radiance.r)) << what << ", light " << i;
      }
  }
}

// A keyed emitter is held to a still's power range at its keys (a lamp scaled 10^6 with an emission of 10^20 emits
// 3e32 W and was rendered), refused at load naming the key; a frame posed between keys is checked again.
TEST(ShapeAnimation, AKeyedEmitterBeyondThePowerRangeIsRefused) {
  const auto scene_with = [](const std::string& scale) {
    return fmt::format(R"({{
  "camera": {{"position": [0, 1.5, 6], "look_at": [0, 0.5, 0], "fov": 50, "resolution": [32, 24]}},
  "shapes": [{{"name": "lamp", "type": "quad", "vertices": [[-0.5, 0, 0], [0.5, 0, 0], [0.5, 1, 0], [-0.5, 1, 0]],
               "emission": 1e18}}],
  "animation": {{"fps": 10, "frames": 3, "shapes": {{
    "lamp": [{{"time": 0, "transform": {{}}}}, {{"time": 0.2, "transform": {{"scale": {}}}}}]}}}} }})",
                       scale);
  };
  // pi * 1e18 W per m^2 over 1 m^2 times the scale squared: 3.1e30 W at a scale of 1e6 (a still that size is
  // refused for the same power).
  try {
    load_scene_text(scene_with("1e6"), "big.json", ".");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("big.json: /animation/shapes/lamp/1: 'lamp' emits 3.14e+30 W"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("beyond kozu's range"), std::string::npos) << e.what();
  }
  // Within range at the keys, the control: loads and poses.
  const auto fine = load_scene_text(scene_with("1e5"), "fine.json", ".");
  EXPECT_NO_THROW(fine->pose_shapes(0.1));
}

TEST(ShapeAnimation, KeyedEmittersTakeTheirLightsAlong) {
  const std::string panel_end = R"({"translate": [1, 1.5, -1], "rotate": [0, 1, 0, 40], "scale": [2, 1, 1]})";
  const std::string strip_end = R"({"translate": [-2, 0.5, 0], "rotate": [1, 0, 0, -30]})";
  const std::string keys = fmt::format(R"(, "animation": {{"fps": 10, "frames": 11, "shapes": {{
    "panel": [{{"time": 0, "transform": {{"translate": [0, 1, 0]}}}}, {{"time": 1, "transform": {}}}],
    "bulb": [{{"time": 0, "transform": {{}}}}, {{"time": 1, "transform": {{"translate": [0.5, 2, 0], "scale": 0.5}}}}],
    "strip": [{{"time": 0, "transform": {{"translate": [1, 0.3, 0]}}}}, {{"time": 1, "transform": {}}}]}}}})",
                                       panel_end, strip_end);
  const auto scene = load_scene_text(
      lamps_scene(R"({"translate": [9, 9, 9]})", R"("center": [0, 0, 0], "radius": 0.3)", "{}", keys), "a.json", ".");
  ASSERT_EQ(scene->animated_shapes.size(), 3u);
  const auto at_end =
      load_scene_text(lamps_scene(panel_end, R"("center": [0.5, 2, 0], "radius": 0.15)", strip_end, ""), "b.json", ".");
  const auto at_start =
      load_scene_text(lamps_scene(R"({"translate": [0, 1, 0]})", R"("center": [0, 0, 0], "radius": 0.3)",
                                  R"({"translate": [1, 0.3, 0]})", ""),
                      "c.json", ".");
  scene->pose_shapes(1.0);
  expect_same_lights(*scene, *at_end, "t = 1");
  scene->pose_shapes(0.0);
  expect_same_lights(*scene, *at_start, "t = 0");
  // The control: the two poses' lights differ, so the comparison can tell them apart.
  const LightSampleContext ctx{Vec3(0.3f, 0.1f, 2.0f), Vec3(0.0f)};
  EXPECT_GT(glm::length(at_end->lights[0]->sample(ctx, Vec2(0.5f)).p - at_start->lights[0]->sample(ctx, Vec2(0.5f)).p),
            0.5f);
  EXPECT_GT(at_end->lights[0]->power().r, 1.5f * at_start->lights[0]->power().r);  // scaled 2x in x
}

TEST(Shutter, TimesSpanTheOpenShutterAndShapesStandAtItsMiddle) {
  Animation a;
  a.fps = 25;
  a.frames = 10;
  EXPECT_EQ(a.shutter_times(4), std::vector<double>{4 / 25.0});
  a.shutter = std::make_pair(-0.25, 0.5);
  const std::vector<double> t = a.shutter_times(4);
  ASSERT_EQ(t.size(), size_t(Animation::kShutterSteps));
  EXPECT_NEAR(t.front(), (4 - 0.25 + 0.75 * 0.5 / Animation::kShutterSteps) / 25.0, 1e-12);
  EXPECT_NEAR(t.back(), (4 + 0.5 - 0.75 * 0.5 / Animation::kShutterSteps) / 25.0, 1e-12);
  EXPECT_NEAR(a.frame_time(4), (4 + 0.125) / 25.0, 1e-12);
}

// Motion blur: a frame whose samples choose between two camera poses is, pixel by pixel, the mean of the two
// stills. A directly seen emitter without other light makes each sample's value its ray's alone (0 or 1), so the
// only error is the coverage each pose's half of the samples estimates: a random half of 1024 stratified samples,
// standard deviation at most sqrt(0.25 / 512 · 0.5) = 0.016 per pose and 0.011 for the mean of the two; the bound
// 0.04 is over 3.5 of those at the worst edge pixel. A renderer that kept one pose, or split the samples 70/30,
// would be off by 0.5 or 0.2 there; the control shows the poses differ.
TEST(Shutter, BlurredFrameIsTheMeanOfItsPoses) {
  const auto scene = load_scene_text(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 30,
    "resolution": [48, 32]}, "render": {"filter": "box"},
    "shapes": [{"type": "quad", "emission": 1, "vertices": [[-0.5, -0.5, 0], [0.5, -0.5, 0], [0.5, 0.5, 0], [-0.5, 0.5, 0]]}]})",
                                     "blur.json", ".");
  const Camera a = scene->camera, b = a.moved(Vec3(0.6f, 0.1f, 5.0f), Vec3(0.6f, 0.1f, 0.0f), 30.0f);
  const PathIntegrator integrator(*scene, 0);
  RenderSettings opt;
  opt.spp = 1024;
  opt.filter = PixelFilter::Type::Box;
  const auto image = [&](const std::vector<Camera>& shutter) {
    scene->shutter_cameras = shutter;
    Film film(48, 32);
    render(*scene, integrator, film, opt);
    return film.rgb();
  };
  const std::vector<float> ia = image({a}), ib = image({b}), blurred = image({a, b});
  float worst = 0.0f, control = 0.0f;
  for (size_t i = 0; i < blurred.size(); ++i) {
    worst = std::max(worst, std::abs(blurred[i] - 0.5f * (ia[i] + ib[i])));
    control = std::max(control, std::abs(ia[i] - 0.5f * (ia[i] + ib[i])));
  }
  EXPECT_LT(worst, 0.04f);
  EXPECT_GT(control, 0.45f);
}

}  // namespace
}  // namespace kozu
