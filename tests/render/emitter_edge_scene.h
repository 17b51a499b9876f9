// An emitter whose slanted edge crosses every row of a 16 × 16 image, seen by an orthographic camera through a box
// filter, so that each pixel's visible emission is the emitter's radiance times the share of the pixel it covers:
// that share is integrated numerically (a 64 × 64 grid of camera rays per pixel, through the scene's own
// intersection), independently of the sampler. The tests of the visible emission's re-estimate for the denoiser
// (test_emission_refine.cpp) and of its supersampling for the raw image (test_emission_supersampling.cpp) use it.
#pragma once

#include "scene/scene.h"

#include <vector>

namespace kozu::test {

constexpr int kEdgeRes = 16;
constexpr float kEdgeLe = 5.0f;

// The edge x = 0.3 + 0.37 y (scene units = pixels): left of it the emitter, right of it black.
inline const char* kEdgeScene = R"({
  "camera": {"type": "orthographic", "position": [0, 0, 5], "look_at": [0, 0, 0], "scale": 16,
             "resolution": [16, 16]},
  "render": {"filter": "box", "max_depth": 4},
  "materials": {"black": {"type": "diffuse", "albedo": 0}},
  "shapes": [{"type": "polygon", "material": "black", "emission": [5, 5, 5],
              "vertices": [[-20, -20, 0], [-7.1, -20, 0], [7.7, 20, 0], [-20, 20, 0]]}]
})";

// The emitters' share of each pixel times their radiance (kEdgeLe), by a 64 × 64 grid of camera rays; other
// surfaces count as black.
inline std::vector<float> true_edge_emission(const Scene& scene) {
  std::vector<float> truth(kEdgeRes * kEdgeRes);
  constexpr int kGrid = 64;
  for (int y = 0; y < kEdgeRes; ++y)
    for (int x = 0; x < kEdgeRes; ++x) {
      int hits = 0;
      for (int j = 0; j < kGrid; ++j)
        for (int i = 0; i < kGrid; ++i) {
          const Vec2 p(x + (i + 0.5f) / kGrid, y + (j + 0.5f) / kGrid);
          SurfaceInteraction si;
          hits += scene.intersect(scene.camera.generate_ray(p, Vec2(0.5f)), si) && si.shape->light(si.prim);
        }
      truth[y * kEdgeRes + x] = kEdgeLe * static_cast<float>(hits) / (kGrid * kGrid);
    }
  return truth;
}

}  // namespace kozu::test
