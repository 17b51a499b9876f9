// Camera projections (scene/camera.h): orthographic rays are parallel and leave a film of the given height; a
// panorama looks up exactly the lat-long layout of environment images (a camera looking down -z shows an
// environment image as stored); each projection's pixel cone; the scene keys and their refusals; a camera
// placed by "transform".
#include "core/error.h"
#include "lights/environment.h"
#include "scene/camera.h"
#include "scene/scene_loader.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace kozu {
namespace {

TEST(Camera, OrthographicRaysAreParallelFromAFilmOfHeightScale) {
  const Camera c = Camera::with_projection(Camera::Projection::Orthographic, Vec3(1, 2, 5), Vec3(1, 2, 0),
                                           Vec3(0, 1, 0), Vec2i(200, 100), 2.0f);
  const Ray centre = c.generate_ray(Vec2(100, 50), Vec2(0.5f));
  EXPECT_EQ(centre.o, Vec3(1, 2, 5));
  EXPECT_EQ(centre.d, Vec3(0, 0, -1));
  const Ray corner = c.generate_ray(Vec2(0, 0), Vec2(0.5f));  // top left: 2 wide (aspect 2) and 1 high each side
  EXPECT_NEAR(corner.o.x, 1.0f - 2.0f, 1e-6f);
  EXPECT_NEAR(corner.o.y, 2.0f + 1.0f, 1e-6f);
  EXPECT_EQ(corner.d, centre.d);
  const RayCone cone = c.pixel_cone();
  EXPECT_FLOAT_EQ(cone.width, 2.0f / 100.0f);
  EXPECT_EQ(cone.spread, 0.0f);
}

// Every pixel centre's ray of a w × h panorama looking down -z sees, in a w × h environment image, that pixel's
// value (the bilinear lookup at a texel centre is the texel): the two mappings are one.
TEST(Camera, PanoramaSeesAnEnvironmentImageAsStored) {
  const int w = 16, h = 8;
  std::vector<Rgb> px(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) px[static_cast<size_t>(y) * w + x] = Rgb(float(x), float(y), 1.0f);
  const EnvironmentLight env(px, w, h, 1.0f, 0.0f);
  const Camera c =
      Camera::with_projection(Camera::Projection::Panorama, Vec3(0, 0, 0), Vec3(0, 0, -1), Vec3(0, 1, 0), Vec2i(w, h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const Ray r = c.generate_ray(Vec2(x + 0.5f, y + 0.5f), Vec2(0.5f));
      const Rgb v = env.eval(LightHit{r.d});
      EXPECT_NEAR(v.r, float(x), 1e-3f) << x << "," << y;
      EXPECT_NEAR(v.g, float(y), 1e-3f) << x << "," << y;
    }
  // Turned to look down +x with up +y: the image centre is then +x.
  const Camera turned =
      Camera::with_projection(Camera::Projection::Panorama, Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec2i(w, h));
  const Ray centre = turned.generate_ray(Vec2(w / 2.0f, h / 2.0f), Vec2(0.5f));
  EXPECT_NEAR(centre.d.x, 1.0f, 1e-6f);
  EXPECT_NEAR(turned.pixel_cone().spread, kPi / h, 1e-7f);
}

std::string camera_error(const std::string& camera) {
  try {
    load_scene_text(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [8, 4])" + camera +
                        R"(}, "shapes": [], "lights": [{"type": "environment", "radiance": 1}]})",
                    "scene.json", ".");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Camera, ProjectionKeysAndTheirRefusals) {
  EXPECT_EQ(camera_error(R"(, "type": "orthographic", "scale": 3)"), "");
  EXPECT_EQ(camera_error(R"(, "type": "panorama")"), "");
  EXPECT_EQ(camera_error(R"(, "type": "orthographic")"), "scene.json: /camera: missing required key 'scale'");
  EXPECT_EQ(camera_error(R"(, "type": "orthographic", "scale": 0)"),
            "scene.json: /camera/scale: expected a number in (0, 1e+15], got 0");
  EXPECT_EQ(camera_error(R"(, "type": "panorama", "fov": 30)"),
            "scene.json: /camera/fov: 'fov' does not apply to a panorama camera");
  EXPECT_EQ(
      camera_error(R"(, "scale": 3)"),
      "scene.json: /camera/scale: 'scale' is the height of an orthographic camera: add \"type\": \"orthographic\"");
}

// A camera "transform" (camera to world; the camera looks down -z with +y up) places the camera as position/
// look_at/up would: rotating 90 degrees about +y and moving to (5, 1, 0) looks down -x from there.
TEST(Camera, TransformPlacesTheCameraLikeLookAt) {
  auto rays = [](const std::string& camera) {
    const auto s = load_scene_text(R"({"camera": {"resolution": [8, 4], "fov": 50, )" + camera +
                                       R"(}, "shapes": [], "lights": [{"type": "environment", "radiance": 1}]})",
                                   "scene.json", ".");
    std::vector<Ray> r;
    for (const Vec2 film : {Vec2(0.5f, 0.5f), Vec2(4.0f, 2.0f), Vec2(7.5f, 3.5f)})
      r.push_back(s->camera.generate_ray(film, Vec2(0.5f)));
    return r;
  };
  const auto expected = rays(R"("position": [5, 1, 0], "look_at": [0, 1, 0])");
  for (const char* t : {R"("transform": {"rotate": [0, 1, 0, 90], "translate": [5, 1, 0]})",
                        R"("transform": {"matrix": [[0, 0, 1, 5], [0, 1, 0, 1], [-1, 0, 0, 0], [0, 0, 0, 1]]})",
                        R"("transform": {"scale": 2, "rotate": [0, 1, 0, 90], "translate": [5, 1, 0]})"}) {
    const auto got = rays(t);
    for (size_t i = 0; i < got.size(); ++i) {
      EXPECT_LT(glm::length(got[i].o - expected[i].o), 1e-5f) << t << " ray " << i;
      EXPECT_LT(glm::length(got[i].d - expected[i].d), 1e-5f) << t << " ray " << i;
    }
  }
  EXPECT_EQ(camera_error(R"(, "transform": {"translate": [0, 0, 1]})"),
            "scene.json: /camera/position: give either 'transform' or position/look_at/up, not both ('position')");
  auto transform_error = [](const std::string& camera) {
    try {
      load_scene_text(R"({"camera": {"resolution": [8, 4], )" + camera +
                          R"(}, "shapes": [], "lights": [{"type": "environment", "radiance": 1}]})",
                      "scene.json", ".");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string rigid =
      "scene.json: /camera/transform: a camera takes rotations, translations and uniform "
      "scales only (no shear, non-uniform scale or mirror)";
  EXPECT_EQ(transform_error(R"("transform": {"scale": [1, 2, 1]})"), rigid);
  EXPECT_EQ(transform_error(R"("transform": {"scale": [-1, 1, 1]})"), rigid);
  EXPECT_EQ(transform_error(R"("transform": {"matrix": [[1, 1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]})"),
            rigid);
  EXPECT_EQ(transform_error(R"("type": "thinlens", "aperture_radius": 0.1, "transform": {"translate": [0, 0, 1]})"),
            "scene.json: /camera/focus_distance: a thin-lens camera placed by 'transform' needs 'focus_distance' (it "
            "has no look_at)");
  EXPECT_EQ(transform_error(R"("type": "orthographic", "scale": 2, "transform": {"translate": [0, 0, 1]})"), "");
}

}  // namespace
}  // namespace kozu
