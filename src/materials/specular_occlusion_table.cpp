#include "materials/specular_occlusion_table.h"

#include "materials/microfacet.h"
#include "materials/roughness.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>

namespace kozu {

namespace {

// The i-th of n Hammersley points: (i + 1/2) / n and the base-2 radical inverse of i.
Vec2 hammersley(uint32_t i, uint32_t n) {
  uint32_t b = i;
  b = (b << 16u) | (b >> 16u);
  b = ((b & 0x55555555u) << 1u) | ((b & 0xAAAAAAAAu) >> 1u);
  b = ((b & 0x33333333u) << 2u) | ((b & 0xCCCCCCCCu) >> 2u);
  b = ((b & 0x0F0F0F0Fu) << 4u) | ((b & 0xF0F0F0F0u) >> 4u);
  b = ((b & 0x00FF00FFu) << 8u) | ((b & 0xFF00FF00u) >> 8u);
  return Vec2((float(i) + 0.5f) / float(n), float(b) * 2.3283064365386963e-10f);
}

// Linear weights between the nodes x_0 < ... of a uniform grid of n nodes over [0, 1] (first node possibly moved up).
void bracket(float x, int n, float first, int* i0, float* w) {
  x = std::clamp(x, 0.0f, 1.0f);
  const float s = x * float(n - 1);
  int i = std::min(int(s), n - 2);
  const float lo = i == 0 ? first : float(i) / float(n - 1), hi = float(i + 1) / float(n - 1);
  *i0 = i;
  *w = std::clamp((x - lo) / (hi - lo), 0.0f, 1.0f);
}

}  // namespace

float SpecularOcclusionTable::alpha_of_gloss(float gloss) {
  return std::max(gloss_to_alpha(std::clamp(gloss, 0.0f, 1.0f)), MicrofacetDistribution::kMinAlpha);  // eq. (2)
}

void SpecularOcclusionTable::integrate_node(float mu, float alpha, std::array<double, kCone>* t,
                                            std::array<double, kCone>* se) {
  const MicrofacetDistribution d(MicrofacetType::GGX, alpha, alpha);
  const Vec3 v(std::sqrt(std::max(0.0f, 1.0f - mu * mu)), 0.0f, mu);
  std::array<double, kCone> sum{}, sum2{};
  for (uint32_t s = 0; s < uint32_t(kSamples); ++s) {
    // Visible normals: l = reflect(v, m) has weight f (n·l) / pdf = G2(v, l) / G1(v) with F = 1.
    const Vec3 m = d.sample_visible(v, hammersley(s, uint32_t(kSamples)));
    const Vec3 l = 2.0f * glm::dot(v, m) * m - v;
    if (!(l.z > 0.0f)) continue;
    const double w = double(d.G2(v, l)) / double(d.G1(v));
    // Chan 2018 §4.7: directions outside the cone (n·l <= cos θ) are rejected.
    for (int k = 0; k + 1 < kCone; ++k)  // the last slice, the closed cone, keeps nothing
      if (l.z > cone_node(k)) {
        sum[size_t(k)] += w;
        sum2[size_t(k)] += w * w;
      }
  }
  for (int k = 0; k < kCone; ++k) {
    const double mean = sum[size_t(k)] / kSamples;
    (*t)[size_t(k)] = mean;
    if (se) (*se)[size_t(k)] = std::sqrt(std::max(0.0, sum2[size_t(k)] / kSamples - mean * mean) / kSamples);
  }
}

SpecularOcclusionTable::SpecularOcclusionTable() {
  // Isolated: this runs inside get()'s one-time initialisation, and a thread waiting in the loop must not pick up an
  // outer task (another material's load job) that would call get() again.
  tbb::this_task_arena::isolate([&] {
    tbb::parallel_for(0, kMu * kGloss, [&](int ij) {
      const int i = ij / kGloss, j = ij % kGloss;
      std::array<double, kCone> t{};
      integrate_node(mu_node(i), alpha_of_gloss(gloss_node(j)), &t, nullptr);
      for (int k = 0; k < kCone; ++k) t_[size_t(ij) * kCone + size_t(k)] = float(t[size_t(k)]);
    });
  });
}

const SpecularOcclusionTable& SpecularOcclusionTable::get() {
  static const SpecularOcclusionTable table;  // thread-safe initialisation (C++11 magic statics)
  return table;
}

float SpecularOcclusionTable::lookup(float mu, float gloss, float cone_cos) const {
  int i, j, k;
  float wi, wj, wk;
  bracket(mu, kMu, mu_node(0), &i, &wi);
  bracket(gloss, kGloss, 0.0f, &j, &wj);
  bracket(cone_cos, kCone, 0.0f, &k, &wk);
  float r = 0.0f;
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 2; ++c)
        r += (a ? wi : 1.0f - wi) * (b ? wj : 1.0f - wj) * (c ? wk : 1.0f - wk) * node(i + a, j + b, k + c);
  return r;
}

float specular_occlusion(float mu, float gloss, float cone_cos) {
  const SpecularOcclusionTable& t = SpecularOcclusionTable::get();
  const float full = t.lookup(mu, gloss, 0.0f);
  if (!(full > 0.0f)) return 1.0f;
  return std::clamp(t.lookup(mu, gloss, cone_cos) / full, 0.0f, 1.0f);  // Chan 2018 §4.7
}

float game_cone_cos(float cone_cos, float mu, float gloss, float* gloss_out) {
  const float g = std::clamp(1.5f * gloss, 0.0f, 1.0f);  // Chan 2018 eq. (60)
  if (gloss_out) *gloss_out = g;
  const float mu4 = mu * mu * mu * mu;
  return cone_cos * (1.0f - g * g) * (1.0f - (1.0f - mu4));  // Chan 2018 eq. (59)
}

}  // namespace kozu
