#include "render/denoiser.h"

#include "render/denoise_buffers.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <stdexcept>

namespace kozu {

namespace {

using namespace denoise_detail;

constexpr int kBand = 16;  // rows per task of nl_means

// Each half buffer filtered with window radius r (and the other half's colour weights), and the share of the
// pixel's own weight in its sum: ∂F_k(p)/∂y_k(p), since the weights do not depend on y_k (SURE, below).
struct Filtered {
  std::vector<Vec3> half[2];
  std::vector<float> self[2];
};

// Rows [c0, c1) of the image, index (y − c0) w + x; b must hold every row they read, [c0 − r − f, c1 + r + f) within
// the image. `expired` (optional) is polled before each band of rows; once it says true the rest is skipped and
// `stopped` set.
Filtered nl_means(const Buffers& b, const DenoiseSettings& s, int r, int c0, int c1,
                  const std::function<bool()>& expired = {}, std::atomic<bool>* stopped = nullptr) {
  const int w = b.w, h = b.h, f = std::max(0, s.patch);
  if (b.y0 > std::max(0, c0 - r - f) || b.y1 < std::min(h, c1 + r + f))
    throw std::logic_error("nl_means: the buffers do not hold the rows the window reads");
  // Buffer index of (x, y) as b.index, the first row in a local and the row offsets hoisted out of the x loops: the
  // first banded version, indexing through b per pixel, filtered 15 % slower.
  const int by0 = b.y0;
  const auto at = [w, by0](int x, int y) { return static_cast<size_t>(y - by0) * w + x; };
  const size_t n = static_cast<size_t>(w) * (c1 - c0);
  Filtered out;
  for (int k = 0; k < 2; ++k) {
    out.half[k].resize(n);
    out.self[k].resize(n);
  }
  const float inv_k2 = s.k * s.k, inv_a = 1.0f / (s.sigma_albedo * s.sigma_albedo),
              inv_n = 1.0f / (s.sigma_normal * s.sigma_normal), inv_z = 1.0f / (s.sigma_depth * s.sigma_depth);
  constexpr float kEps = 1e-10f;
  // Bands of rows in parallel; each computes, per offset, the per-pixel distances of its rows and the patch's
  // margin, box-filters them and accumulates.
  tbb::parallel_for(0, (c1 - c0 + kBand - 1) / kBand, [&](int band) {
    if (stopped && (stopped->load(std::memory_order_relaxed) || (expired && expired()))) {
      *stopped = true;
      return;
    }
    const int y0 = c0 + band * kBand, y1 = std::min(c1, y0 + kBand);
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
        for (int y = ry0; y < ry1; ++y) {
          const int qy = y + dy;
          const size_t prow = at(0, y), qrow = qy >= 0 && qy < h ? at(0, qy) : 0;
          for (int x = 0; x < w; ++x) {
            const int qx = x + dx;
            const size_t j = static_cast<size_t>(y - ry0) * w + x;
            if (qx < 0 || qx >= w || qy < 0 || qy >= h) {
              dist[0][j] = dist[1][j] = 1e30f;
              continue;
            }
            const size_t p = prow + x, q = qrow + qx;
            for (int k = 0; k < 2; ++k) {
              const float vp = b.var[p], vq = b.var[q];
              const Vec3 d = b.half[k][p] - b.half[k][q];
              const float num_d = glm::dot(d, d) / 3.0f - (vp + std::min(vp, vq));
              dist[k][j] = num_d / (kEps + inv_k2 * (vp + vq));
            }
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
        for (int y = y0; y < y1; ++y) {
          const int qy = y + dy;
          if (qy < 0 || qy >= h) continue;
          const size_t prow = at(0, y), qrow = at(0, qy);
          for (int x = 0; x < w; ++x) {
            const int qx = x + dx;
            if (qx < 0 || qx >= w) continue;
            const size_t p = prow + x, q = qrow + qx;
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
      }
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t o = static_cast<size_t>(y - y0) * w + x, p = at(x, y),
                     c = static_cast<size_t>(y - c0) * w + x;
        for (int k = 0; k < 2; ++k) {
          // The pixel itself always takes weight 1 (distance 0, identical features).
          out.half[k][c] = den[k][o] > 0.0f ? num[k][o] / den[k][o] : b.half[k][p];
          out.self[k][c] = den[k][o] > 0.0f ? 1.0f / den[k][o] : 1.0f;
        }
      }
  });
  return out;
}

// A candidate's output (the mean of its two halves) and its estimated squared error per pixel: Stein's unbiased risk
// estimate from both halves, |F_k − y_k|² − V + 2 V ∂F_k/∂y_k, averaged over the (2R + 1)² box.
struct Scored {
  std::vector<Vec3> mean;
  std::vector<float> risk;
};

Scored score(Filtered&& c, const Buffers& b, int c0, int c1, int R) {
  const int w = b.w;
  Scored out;
  std::vector<float> sure(static_cast<size_t>(w) * (c1 - c0));
  out.mean.resize(sure.size());
  for (int y = c0; y < c1; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y - c0) * w + x, p = b.index(x, y);
      float e = 0.0f;
      for (int k = 0; k < 2; ++k) {
        const Vec3 d = c.half[k][i] - b.half[k][p];
        e += glm::dot(d, d) / 3.0f - b.var[p] + 2.0f * b.var[p] * c.self[k][i];
      }
      sure[i] = std::min(0.5f * e, kUnknownVariance);
      out.mean[i] = 0.5f * (c.half[0][i] + c.half[1][i]);
    }
  c = Filtered{};  // its halves are not needed for the box
  out.risk = box_mean(sure, w, c1 - c0, R);
  return out;
}

}  // namespace

std::vector<float> denoise(const Film& film, const DenoiseSettings& s, const VisibleEmission* emission,
                           const std::function<bool()>& expired) {
  VisibleEmission own;
  const VisibleEmission& visible = emission_to_add_back(film, emission, own, "denoise");
  const int w = film.width(), h = film.height();
  const size_t n = film.pixels().size();
  std::vector<float> out(3 * n, 0.0f);
  if (n == 0) return out;
  const int r = std::max(0, s.radius), r_small = std::max(0, s.radius_small), R = std::max(0, s.risk_radius);
  const int reach = std::max(r, r_small) + std::max(0, s.patch);  // rows a candidate row reads beyond itself
  // Bands of rows, each with the rows its windows, patches and risk boxes read: memory in proportion to a band, not
  // to the image (a 1080p film's full-image buffers were 2.8 times the render's memory), the same pixels bit for bit.
  // Each band's candidates span its rows and R more either side, in tasks of kBand rows: bands of at least 192 rows
  // (24 per thread), sized so that those rows fill whole tasks, keep the extra work near 5 % (bands of 128 rows cost
  // 20 % more time: their halos, and tasks half full; at 1080p on 2 threads bands of 184 rows instead of 216 took
  // 8 MB less and no more time).
  int band = s.band_rows;
  if (band <= 0) {
    const int target = std::max(192, 24 * tbb::this_task_arena::max_concurrency());
    const int bands = (h + target - 1) / target;
    band = ((h + bands - 1) / bands + 2 * R + kBand - 1) / kBand * kBand - 2 * R;
  }
  const HalfBufferRows half_buffers(film, visible);
  std::atomic<bool> stopped{false};
  for (int y0 = 0; y0 < h; y0 += band) {
    const int y1 = std::min(h, y0 + band);
    const int c0 = std::max(0, y0 - R), c1 = std::min(h, y1 + R);  // the candidates' rows the risk boxes read
    const Buffers b = half_buffers.rows(c0 - reach, c1 + reach);
    // Two windows: the wide one smooths flat regions best, the narrow one keeps what the wide one would blur
    // (reflections, shading detail that features do not show); each pixel takes the one with the lower risk.
    // The narrow window first (a twentieth of the wide one's cost): past the deadline it is the output, here and in
    // the bands after. Each candidate is scored as soon as it is made and only its mean and risk kept (16 bytes a
    // pixel instead of its 32).
    Scored scored[2];
    scored[1] = score(nl_means(b, s, r_small, c0, c1), b, c0, c1, R);
    bool wide = false;
    if (!stopped) {
      Filtered c = nl_means(b, s, r, c0, c1, expired, &stopped);
      if (!stopped) {
        scored[0] = score(std::move(c), b, c0, c1, R);
        wide = true;
      }
    }
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = static_cast<size_t>(y - c0) * w + x;
        const int best = !wide || scored[1].risk[i] < scored[0].risk[i] ? 1 : 0;
        put_pixel(out, static_cast<size_t>(y) * w + x, scored[best].mean[i], visible);
      }
  }
  return out;
}

}  // namespace kozu
