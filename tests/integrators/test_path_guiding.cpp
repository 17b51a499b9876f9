// Path guiding in whole renders (integrators/path.h, render/guiding_training.h): unbiased (the Cornell box against
// its stored 65536-spp reference, and a scene of indirect light against its unguided render), deterministic at any
// thread count with its training, and learning where indirect light comes from.
#include "render/guiding_training.h"
#include "support/render_test.h"

#include "core/file_io.h"
#include "core/rng.h"
#include "core/warp.h"

#include <gtest/gtest.h>

#include <cstring>

namespace kozu::test {
namespace {

struct GuidedRender {
  Film film;
  GuidingTraining training;
};

enum class Guiding { Off, InImage, OnTheSide };

GuidedRender render_with(Scene& scene, Vec2i res, int spp, uint64_t seed, int threads, Guiding guiding) {
  scene.camera.set_resolution(res);
  GuidedRender out{Film(res.x, res.y), {}};
  PathIntegrator integrator(scene, scene.settings.max_depth);
  RenderSettings opt;
  opt.spp = spp;
  opt.seed = seed;
  opt.threads = threads;
  opt.tile_size = 7;  // tiles that do not divide the image
  GuidingField field(scene.center(), scene.radius());
  RenderResult r;
  if (guiding == Guiding::InImage) {
    r = render_guided(scene, integrator, field, out.film, opt, nullptr, {}, &out.training);
    EXPECT_TRUE(out.training.in_image);
  } else {
    if (guiding == Guiding::OnTheSide) out.training = train_guiding(scene, integrator, field, out.film, opt);
    r = render(scene, integrator, out.film, opt);
  }
  EXPECT_EQ(r.film.discarded_samples, 0u);
  EXPECT_EQ(r.film.min_spp, uint32_t(spp));
  return out;
}

std::unique_ptr<Scene> cornell() {
  return load_scene_text(read_input_file(source_dir() / "scenes/cornell.json"), "cornell.json",
                         source_dir() / "scenes");
}

TEST(PathGuiding, CornellMatchesStoredReference) {
  const Image ref = read_image(source_dir() / "tests/data/cornell_ref.exr");
  auto scene = cornell();
  const GuidedRender g = render_with(*scene, Vec2i(64, 64), 256, 7, 0, Guiding::InImage);
  // The training ran (passes of 1, 2, .., 64 samples leave 129 ≥ 2 × 64) and the field split.
  EXPECT_EQ(g.training.passes, 7);
  EXPECT_EQ(g.training.samples, 127);
  EXPECT_GE(g.training.leaves, 2u);
  expect_matches_reference(g.film, ref);
}

TEST(PathGuiding, BitIdenticalForAnyThreadCount) {
  auto scene = cornell();
  const GuidedRender one = render_with(*scene, Vec2i(40, 24), 37, 3, 1, Guiding::InImage);
  ASSERT_GT(one.training.passes, 0);
  const std::vector<float> a = one.film.rgb();
  for (int threads : {2, 3}) {
    const GuidedRender other = render_with(*scene, Vec2i(40, 24), 37, 3, threads, Guiding::InImage);
    EXPECT_EQ(other.training.leaves, one.training.leaves) << threads << " threads";
    const std::vector<float> b = other.film.rgb();
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << threads << " threads";
  }
  // And guiding changed the image (the test above would hold trivially if the field were never used).
  const GuidedRender plain = render_with(*scene, Vec2i(40, 24), 37, 3, 1, Guiding::Off);
  EXPECT_NE(std::memcmp(a.data(), plain.film.rgb().data(), a.size() * sizeof(float)), 0);
}

// A floor lit only by a bright patch of wall that a spot light shines on: the floor's light comes from a small solid
// angle, which the learnt distributions must find.
constexpr const char* kIndirectScene = R"({
  "camera": { "position": [0, 3, -6], "look_at": [0, 0, 0], "fov": 50, "resolution": [48, 32] },
  "render": { "max_depth": 3 },
  "materials": { "white": { "type": "diffuse", "albedo": [0.8, 0.8, 0.8] } },
  "shapes": [
    { "type": "quad", "material": "white", "vertices": [[-4, 0, -4], [-4, 0, 4], [4, 0, 4], [4, 0, -4]] },
    { "type": "quad", "material": "white", "vertices": [[-4, 0, 3], [-4, 4, 3], [4, 4, 3], [4, 0, 3]] }
  ],
  "lights": [
    { "type": "spot", "position": [0, 3.5, 0], "look_at": [0, 2, 3], "intensity": 100, "cone_angle": 15 }
  ]
})";

// The share of directions from p that hit the lit patch (the 2 × 2 square around (0, 2, 3) on the wall).
template <class Sample>
double share_to_patch(const Vec3& p, Sample&& sample) {
  Pcg32 rng(1);
  constexpr int kCount = 100'000;
  int in = 0;
  for (int i = 0; i < kCount; ++i) {
    const Vec3 w = sample(Vec2(rng.next_float(), rng.next_float()));
    if (!(w.z > 0.0f)) continue;
    const Vec3 h = p + ((3.0f - p.z) / w.z) * w;
    in += std::abs(h.x) < 1.0f && std::abs(h.y - 2.0f) < 1.0f;
  }
  return double(in) / kCount;
}

TEST(PathGuiding, LearnsWhereIndirectLightComesFrom) {
  auto scene = load_scene_text(kIndirectScene, "scene.json", ".");
  PathIntegrator integrator(*scene, scene->settings.max_depth);
  RenderSettings opt;
  opt.spp = 128;
  opt.seed = 5;
  Film film(48, 32);
  GuidingField field(scene->center(), scene->radius());
  const GuidingTraining t = train_guiding(*scene, integrator, field, film, opt);
  EXPECT_GE(t.passes, 5);
  for (const Vec3 p : {Vec3(1.0f, 0.0f, -1.0f), Vec3(-2.0f, 0.0f, 1.0f)}) {
    const DirectionalQuadtree* d = field.distribution(p);
    ASSERT_NE(d, nullptr);
    const double guided = share_to_patch(p, [&](const Vec2& u) {
      float pdf;
      return d->sample(u, &pdf);
    });
    const double cosine = share_to_patch(p, [](const Vec2& u) {
      const Vec3 l = warp::square_to_cosine_hemisphere(u);
      return Vec3(l.x, l.z, l.y);  // about the floor's normal, +y
    });
    EXPECT_GT(guided, 2.5 * cosine) << "at " << p.x << ", " << p.y << ", " << p.z;
  }
}

// Whatever the field learnt, the image's expectation is the unguided one's.
TEST(PathGuiding, IndirectSceneMeanIsTheUnguidedOne) {
  auto scene = load_scene_text(kIndirectScene, "scene.json", ".");
  const GuidedRender plain = render_with(*scene, Vec2i(48, 32), 128, 5, 0, Guiding::Off);
  // Both ways of training: in the image, and on the side (a resumed render's).
  for (const Guiding mode : {Guiding::InImage, Guiding::OnTheSide}) {
    const GuidedRender guided = render_with(*scene, Vec2i(48, 32), 128, 6, 0, mode);
    EXPECT_GE(guided.training.passes, 4);
    const ImageStats a = image_stats(plain.film), b = image_stats(guided.film);
    for (int c = 0; c < 3; ++c)
      EXPECT_LT(std::abs(a.mean[c] - b.mean[c]), 4.0 * std::hypot(a.standard_error[c], b.standard_error[c]))
          << "channel " << c << ": " << a.mean[c] << " vs " << b.mean[c];
  }
}

}  // namespace
}  // namespace kozu::test
