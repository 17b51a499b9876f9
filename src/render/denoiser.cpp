#include "render/denoiser.h"

#include "render/denoise_buffers.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <stdexcept>

namespace kozu {

namespace {

using namespace denoise_detail;

// Each half buffer filtered with window radius r (and the other half's colour weights), and the share of the
// pixel's own weight in its sum: ∂F_k(p)/∂y_k(p), since the weights do not depend on y_k (SURE, below).
struct Filtered {
  std::vector<Vec3> half[2];
  std::vector<float> self[2];
};

// `expired` (optional) is polled before each band of rows; once it says true the rest is skipped and `stopped` set.
Filtered nl_means(const Buffers& b, const DenoiseSettings& s, int r, const std::function<bool()>& expired = {},
                  std::atomic<bool>* stopped = nullptr) {
  const int w = b.w, h = b.h, f = std::max(0, s.patch);
  const size_t n = static_cast<size_t>(w) * h;
  Filtered out;
  for (int k = 0; k < 2; ++k) {
    out.half[k].resize(n);
    out.self[k].resize(n);
  }
  const float inv_k2 = s.k * s.k, inv_a = 1.0f / (s.sigma_albedo * s.sigma_albedo),
              inv_n = 1.0f / (s.sigma_normal * s.sigma_normal), inv_z = 1.0f / (s.sigma_depth * s.sigma_depth);
  constexpr float kEps = 1e-10f;
  constexpr int kBand = 16;
  // Bands of rows in parallel; each computes, per offset, the per-pixel distances of its rows and the patch's
  // margin, box-filters them and accumulates.
  tbb::parallel_for(0, (h + kBand - 1) / kBand, [&](int band) {
    if (stopped && (stopped->load(std::memory_order_relaxed) || (expired && expired()))) {
      *stopped = true;
      return;
    }
    const int y0 = band * kBand, y1 = std::min(h, y0 + kBand);
    const int ry0 = std::max(0, y0 - f), ry1 = std::min(h, y1 + f);  // rows whose distances the patches read
    const int rows = ry1 - ry0;
    std::vector<float> dist[2], rowsum[2];
    for (int k = 0; k < 2; ++k) {
      dist[k].resize(static_cast<size_t>(rows) * w);
      rowsum[k].resize(static_cast<size_t>(rows) * w);
    }
    std::vector<Vec3> num[2];
    std::vector<float> den[2];
    for (int k = 0; k < 2; ++k) {
      num[k].assign(static_cast<size_t>(y1 - y0) * w, Vec3(0.0f));
      den[k].assign(static_cast<size_t>(y1 - y0) * w, 0.0f);
    }
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        // Per-pixel colour distance of each half buffer to its neighbour at (dx, dy); out-of-image: +inf.
        for (int y = ry0; y < ry1; ++y)
          for (int x = 0; x < w; ++x) {
            const int qx = x + dx, qy = y + dy;
            const size_t j = static_cast<size_t>(y - ry0) * w + x;
            if (qx < 0 || qx >= w || qy < 0 || qy >= h) {
              dist[0][j] = dist[1][j] = 1e30f;
              continue;
            }
            const size_t p = static_cast<size_t>(y) * w + x, q = static_cast<size_t>(qy) * w + qx;
            for (int k = 0; k < 2; ++k) {
              const float vp = b.var[p], vq = b.var[q];
              const Vec3 d = b.half[k][p] - b.half[k][q];
              const float num_d = glm::dot(d, d) / 3.0f - (vp + std::min(vp, vq));
              dist[k][j] = num_d / (kEps + inv_k2 * (vp + vq));
            }
          }
        // Box filter over the patch: along x, then along y.
        for (int k = 0; k < 2; ++k) {
          for (int y = 0; y < rows; ++y) {
            const float* d = &dist[k][static_cast<size_t>(y) * w];
            float* o = &rowsum[k][static_cast<size_t>(y) * w];
            for (int x = 0; x < w; ++x) {
              float sum = 0.0f;
              int cnt = 0;
              for (int t = std::max(0, x - f); t <= std::min(w - 1, x + f); ++t, ++cnt) sum += d[t];
              o[x] = sum / static_cast<float>(cnt);
            }
          }
        }
        for (int y = y0; y < y1; ++y)
          for (int x = 0; x < w; ++x) {
            const int qx = x + dx, qy = y + dy;
            if (qx < 0 || qx >= w || qy < 0 || qy >= h) continue;
            const size_t p = static_cast<size_t>(y) * w + x, q = static_cast<size_t>(qy) * w + qx;
            // Feature weight, shared by both halves.
            const Vec3 da = b.albedo[p] - b.albedo[q], dn = b.normal[p] - b.normal[q];
            const float zp = std::max(std::abs(b.depth[p]), 1e-6f);
            const float dz = (b.depth[p] - b.depth[q]) / zp;
            const float wf = std::exp(-(glm::dot(da, da) * inv_a + glm::dot(dn, dn) * inv_n + dz * dz * inv_z));
            if (!(wf > 1e-6f)) continue;
            float dpatch[2];
            for (int k = 0; k < 2; ++k) {
              float sum = 0.0f;
              int cnt = 0;
              for (int t = std::max(ry0, y - f); t <= std::min(ry1 - 1, y + f); ++t, ++cnt)
                sum += rowsum[k][static_cast<size_t>(t - ry0) * w + x];
              dpatch[k] = sum / static_cast<float>(cnt);
            }
            const size_t o = static_cast<size_t>(y - y0) * w + x;
            // Half A takes the weights of B's colours, and B those of A's.
            for (int k = 0; k < 2; ++k) {
              const float wc = std::exp(-std::max(0.0f, dpatch[1 - k]));
              const float wt = wc * wf;
              num[k][o] += wt * b.half[k][q];
              den[k][o] += wt;
            }
          }
      }
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t o = static_cast<size_t>(y - y0) * w + x, p = static_cast<size_t>(y) * w + x;
        for (int k = 0; k < 2; ++k) {
          // The pixel itself always takes weight 1 (distance 0, identical features).
          out.half[k][p] = den[k][o] > 0.0f ? num[k][o] / den[k][o] : b.half[k][p];
          out.self[k][p] = den[k][o] > 0.0f ? 1.0f / den[k][o] : 1.0f;
        }
      }
  });
  return out;
}

}  // namespace

std::vector<float> denoise(const Film& film, const DenoiseSettings& s, const VisibleEmission* emission,
                           const std::function<bool()>& expired) {
  VisibleEmission own;
  const VisibleEmission& visible = emission_to_add_back(film, emission, own, "denoise");
  const size_t n = film.pixels().size();
  const Buffers b = split(film, visible);
  const int w = b.w, h = b.h;
  std::vector<float> out(3 * n, 0.0f);
  if (n == 0) return out;
  // Two windows: the wide one smooths flat regions best, the narrow one keeps what the wide one would blur
  // (reflections, shading detail that features do not show); each pixel takes the one with the lower risk.
  // The narrow window first (a twentieth of the wide one's cost): past the deadline it is the output.
  Filtered candidates[2];
  candidates[1] = nl_means(b, s, std::max(0, s.radius_small));
  std::atomic<bool> stopped{false};
  candidates[0] = nl_means(b, s, std::max(0, s.radius), expired, &stopped);
  if (stopped) candidates[0] = candidates[1];
  // Stein's unbiased risk estimate of each candidate's squared error per pixel, from both halves:
  // |F_k − y_k|² − V + 2 V ∂F_k/∂y_k, smoothed, and the candidate with the least taken.
  std::vector<float> risk[2];
  for (int j = 0; j < 2; ++j) {
    const Filtered& c = candidates[j];
    std::vector<float> sure(n);
    for (size_t p = 0; p < n; ++p) {
      float e = 0.0f;
      for (int k = 0; k < 2; ++k) {
        const Vec3 d = c.half[k][p] - b.half[k][p];
        e += glm::dot(d, d) / 3.0f - b.var[p] + 2.0f * b.var[p] * c.self[k][p];
      }
      sure[p] = std::min(0.5f * e, kUnknownVariance);
    }
    risk[j] = box_mean(sure, w, h, std::max(0, s.risk_radius));
  }
  for (size_t p = 0; p < n; ++p) {
    const int best = risk[1][p] < risk[0][p] ? 1 : 0;
    put_pixel(out, p, 0.5f * (candidates[best].half[0][p] + candidates[best].half[1][p]), visible);
  }
  return out;
}

}  // namespace kozu
