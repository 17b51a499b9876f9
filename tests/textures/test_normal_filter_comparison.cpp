// How close each way of filtering a normal map's mip levels comes to the supersampled truth, near and far: Chan
// 2018's shortened normals (Algorithm 2, macro, as shipped; Algorithm 1, micro), Toksvig 2005 and LEAN mapping
// (Olano & Baker 2010), against plain mip averaging. It prints the table docs/wwii.md gives.
//
// The truth of a footprint (the level-0 texels a coarser texel covers, 2^k a side at level k) is what a renderer
// integrating level-0 lookups converges to: the mean over the footprint of each texel's own GGX lobe about its own
// normal. A model replaces it by one lobe. Both are compared by where they send the light: for a view v, the
// reflected energy (the weights of VNDF-sampled reflections, F = 1, G2 / G1) binned into 16 × 32 equal solid-angle
// cells of the macro surface's upper hemisphere. Error: Σ|H_model − H_truth| / Σ H_truth over the cells, the share of
// the reflected light the model puts in the wrong place (or loses, or adds), averaged over footprints and views
// (0°, 45°, 75°). The noise floor is the truth against itself from another random stream.
#include "core/frame.h"
#include "core/rng.h"
#include "materials/microfacet.h"
#include "textures/lean_mapping.h"
#include "textures/normal_gloss_filter.h"
#include "textures/toksvig.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace kozu {
namespace {

constexpr int kSize = 128, kThetaBins = 16, kPhiBins = 32, kSamples = 1 << 17;
constexpr double kPiD = 3.14159265358979323846;
constexpr int kLevels[] = {1, 3, 5, 7};
constexpr double kViews[] = {0.0, 45.0, 75.0};

enum Model { Truth, Floor, None, Toksvig, Lean, Micro, Macro, kModels };
const char* const kModelNames[] = {"truth", "noise floor",    "plain mips",    "Toksvig",
                                   "LEAN",  "micro (Alg. 1)", "macro (Alg. 2)"};

using Histogram = std::array<double, kThetaBins * kPhiBins>;

void bin(Histogram& h, const Vec3& l, double weight) {
  if (!(l.z > 0.0f) || !(weight > 0.0)) return;
  const int t = std::min(kThetaBins - 1, static_cast<int>(l.z * kThetaBins));
  double phi = std::atan2(double(l.y), double(l.x));
  if (phi < 0) phi += 2 * kPiD;
  const int p = std::min(kPhiBins - 1, static_cast<int>(phi / (2 * kPiD) * kPhiBins));
  h[size_t(t * kPhiBins + p)] += weight;
}

// One reflection off a GGX lobe of roughness alpha about the unit normal n, for the view v (macro frame).
void sample_ggx(Histogram& h, const Vec3& n, float alpha, const Vec3& v, Pcg32& rng) {
  const Frame frame(n);
  const Vec3 vl = frame.to_local(v);
  if (vl.z <= 0.0f) return;
  const MicrofacetDistribution dist(MicrofacetType::GGX, alpha, alpha);
  const Vec3 m = dist.sample_visible(vl, Vec2(rng.next_float(), rng.next_float()));
  const Vec3 ll = reflect(vl, m);
  if (ll.z <= 0.0f) return;
  bin(h, frame.to_world(ll), dist.G2(vl, ll) / dist.G1(vl));
}

void sample_lean(Histogram& h, const LeanLobe& lobe, const Vec3& v, Pcg32& rng) {
  const Vec3 m = lobe.sample(rng.next_double(), rng.next_double());
  const double vm = glm::dot(v, m);
  if (vm <= 0) return;
  const Vec3 l = reflect(v, m);
  if (l.z <= 0.0f) return;
  // pdf(l) = D cos θ_m / (4 v·m); f cos θ_l = D G2 / (4 cos θ_v).
  bin(h, l, vm / (double(v.z) * m.z) / (1.0 + lobe.lambda(v) + lobe.lambda(l)));
}

double relative_l1(const Histogram& model, const Histogram& truth) {
  double diff = 0, sum = 0;
  for (size_t i = 0; i < truth.size(); ++i) diff += std::abs(model[i] - truth[i]), sum += truth[i];
  return diff / sum;
}

struct Map {
  std::string name;
  std::vector<Vec3> normals;  // kSize x kSize, row-major
};

// Random facets: slopes normal with RMS 0.24 (0.24 / sqrt 2 a component), as the renderer's far-floor test.
Map facet_map() {
  Map m{"facets (white noise, RMS slope 0.24)", {}};
  std::mt19937 rng(29);
  std::normal_distribution<double> slope(0.0, 0.24 / std::sqrt(2.0));
  for (int i = 0; i < kSize * kSize; ++i) {
    const double sx = slope(rng), sy = slope(rng);
    m.normals.push_back(glm::normalize(Vec3(float(-sx), float(-sy), 1.0f)));
  }
  return m;
}

// Smooth waves: a periodic sum of sinusoids of whole periods, RMS slope 0.3 (correlated over tens of texels, so
// the near levels hardly vary within a footprint and the far ones do).
Map wave_map() {
  Map m{"waves (smooth, RMS slope 0.30)", {}};
  const int freq[][2] = {{1, 2}, {3, 1}, {2, 5}, {7, 3}, {5, 9}};
  const double phase[] = {0.3, 1.7, 4.1, 2.2, 5.0};
  std::vector<double> gx, gy;
  double sum2 = 0;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      double hx = 0, hy = 0;
      for (int k = 0; k < 5; ++k) {
        const double w = 2 * kPiD / kSize, arg = w * (freq[k][0] * (x + 0.5) + freq[k][1] * (y + 0.5)) + phase[k];
        const double a = 1.0 / (freq[k][0] + freq[k][1]);
        hx += a * w * freq[k][0] * std::cos(arg);
        hy += a * w * freq[k][1] * std::cos(arg);
      }
      gx.push_back(hx), gy.push_back(hy);
      sum2 += hx * hx + hy * hy;
    }
  const double scale = 0.3 / std::sqrt(sum2 / (kSize * kSize));
  for (size_t i = 0; i < gx.size(); ++i)
    m.normals.push_back(glm::normalize(Vec3(float(-scale * gx[i]), float(-scale * gy[i]), 1.0f)));
  return m;
}

struct Case {
  const Map* map;
  double gloss;
  std::vector<NormalGlossLevel> macro, micro;
};

struct Job {
  int c, level, x, y, view;
};

// The errors of every model for one footprint and view.
std::array<double, kModels> measure(const Case& cs, const Job& job, uint64_t seed) {
  const int side = 1 << job.level;
  const float alpha0 = static_cast<float>(wwii_gloss_to_alpha(cs.gloss));
  const double t = kViews[job.view] * kPiD / 180.0;
  const Vec3 v(float(std::sin(t)), 0.0f, float(std::cos(t)));
  std::vector<Vec3> texels;
  LeanMoments moments;
  Vec3 sum(0.0f);
  for (int y = job.y * side; y < (job.y + 1) * side; ++y)
    for (int x = job.x * side; x < (job.x + 1) * side; ++x) {
      const Vec3& n = cs.map->normals[size_t(y) * kSize + size_t(x)];
      texels.push_back(n);
      moments.add(n);
      sum += n;
    }
  const Vec3 mean = sum / float(texels.size());
  const float mean_length = glm::length(mean);
  const float toksvig = static_cast<float>(toksvig_alpha(alpha0, mean_length));
  const LeanLobe lean(moments, alpha0);
  const auto chain = [&](const std::vector<NormalGlossLevel>& levels, Vec3* n, float* alpha) {
    const NormalGlossLevel& l = levels[size_t(job.level)];
    const size_t i = size_t(job.y) * size_t(l.width) + size_t(job.x);
    *n = glm::normalize(Vec3(l.normal[3 * i], l.normal[3 * i + 1], l.normal[3 * i + 2]));
    *alpha = static_cast<float>(wwii_gloss_to_alpha(l.gloss[i]));
  };
  Vec3 n_macro, n_micro;
  float a_macro, a_micro;
  chain(cs.macro, &n_macro, &a_macro);
  chain(cs.micro, &n_micro, &a_micro);

  std::array<Histogram, kModels> h{};
  Pcg32 rng(seed, 7);
  for (int s = 0; s < kSamples; ++s) {
    sample_ggx(h[Truth], texels[rng.next_u32() % texels.size()], alpha0, v, rng);
    sample_ggx(h[Floor], texels[rng.next_u32() % texels.size()], alpha0, v, rng);
    sample_ggx(h[None], glm::normalize(mean), alpha0, v, rng);
    sample_ggx(h[Toksvig], glm::normalize(mean), toksvig, v, rng);
    sample_lean(h[Lean], lean, v, rng);
    sample_ggx(h[Micro], n_micro, a_micro, v, rng);
    sample_ggx(h[Macro], n_macro, a_macro, v, rng);
  }
  std::array<double, kModels> e{};
  for (int m = 0; m < kModels; ++m) e[size_t(m)] = relative_l1(h[size_t(m)], h[Truth]);
  return e;
}

TEST(NormalFilterComparison, ShortenedNormalsAgainstToksvigAndLean) {
  const Map maps[] = {facet_map(), wave_map()};
  std::vector<Case> cases;
  for (const Map& map : maps)
    for (double gloss : {0.9, 0.5}) {
      NormalGlossLevel level0;
      level0.width = level0.height = kSize;
      for (const Vec3& n : map.normals) {
        level0.normal.insert(level0.normal.end(), {n.x, n.y, n.z});
        level0.gloss.push_back(static_cast<float>(gloss));
      }
      cases.push_back({&map, gloss, filter_normal_gloss(level0, ShortenedNormalModel::Macro),
                       filter_normal_gloss(level0, ShortenedNormalModel::Micro)});
    }
  // Up to 4 footprints a level, drawn with a fixed seed.
  std::vector<Job> jobs;
  Pcg32 pick(2018);
  for (int c = 0; c < int(cases.size()); ++c)
    for (int level : kLevels) {
      const int n = kSize >> level;
      for (int f = 0; f < std::min(4, n * n); ++f) {
        const int x = int(pick.next_u32() % uint32_t(n)), y = int(pick.next_u32() % uint32_t(n));
        for (int view = 0; view < 3; ++view) jobs.push_back({c, level, x, y, view});
      }
    }
  std::vector<std::array<double, kModels>> errors(jobs.size());
  tbb::parallel_for(size_t(0), jobs.size(),
                    [&](size_t j) { errors[j] = measure(cases[size_t(jobs[j].c)], jobs[j], 1000 + j); });

  std::printf("| normal map | gloss | footprint |");
  for (int m = Floor; m < kModels; ++m) std::printf(" %s |", kModelNames[m]);
  std::printf("\n");
  for (int c = 0; c < int(cases.size()); ++c)
    for (int level : kLevels) {
      std::array<double, kModels> mean{};
      int count = 0;
      for (size_t j = 0; j < jobs.size(); ++j)
        if (jobs[j].c == c && jobs[j].level == level) {
          for (int m = 0; m < kModels; ++m) mean[size_t(m)] += errors[j][size_t(m)];
          ++count;
        }
      for (double& e : mean) e /= count;
      std::printf("| %s | %.1f | %d × %d |", cases[size_t(c)].map->name.c_str(), cases[size_t(c)].gloss, 1 << level,
                  1 << level);
      for (int m = Floor; m < kModels; ++m) std::printf(" %.1f %% |", 100.0 * mean[size_t(m)]);
      std::printf("\n");
      const std::string where = cases[size_t(c)].map->name + " level " + std::to_string(level);
      // The comparison must resolve the models: the noise floor (two truths from independent streams) well below
      // the differences it is read for.
      EXPECT_LT(mean[Floor], 0.05) << where;
      // What shortened normals are for: far levels (footprints of 8 texels a side and more) whose bumps the plain
      // mips average away must be closer to the truth than plain mips, by at least the noise floor's margin.
      if (level >= 3) {
        EXPECT_LT(mean[Macro] + 2 * mean[Floor], mean[None]) << where;
      }
    }
}

}  // namespace
}  // namespace kozu
