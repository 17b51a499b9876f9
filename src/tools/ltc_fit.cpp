#include "tools/ltc_fit.h"

#include "core/arena.h"
#include "core/ltc.h"
#include "materials/conductor.h"
#include "materials/microfacet.h"
#include "materials/microfacet_albedo.h"
#include "materials/plastic.h"
#include "tools/nelder_mead.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>

namespace kozu {

Mat3 LtcFitEntry::m() const {
  Mat3 m(0.0f);  // glm: m[column][row]
  m[0][0] = a;
  m[2][0] = b;
  m[1][1] = c;
  m[0][2] = d;
  m[2][2] = 1.0f;
  return m;
}

Mat3 LtcFitEntry::m_inv_normalized() const {
  const Mat3 inv = glm::inverse(m());
  return inv / inv[2][2];
}

float ltc_table_theta(int j, int size) {
  return std::min(1.57f, static_cast<float>(j) / static_cast<float>(size - 1) * 0.5f * kPi);
}

float ltc_table_alpha(int i, int size) {
  const float s = static_cast<float>(i) / static_cast<float>(size - 1);
  return std::max(s * s, MicrofacetDistribution::kMinAlpha);
}

namespace {

// The BRDF's side of the estimates: stratified samples of the BSDF with their values and densities, and the norms.
struct TargetSamples {
  struct Sample {
    Vec3 w;
    float f, pdf;  // ρ cos / n and the BSDF's density
  };
  std::vector<Sample> s;
  float norm = 0, fresnel_norm = 0;
};

TargetSamples target_samples(const Bsdf& bsdf, const Vec3& wv, int n) {
  TargetSamples t;
  double norm = 0, fresnel = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const Vec2 u((static_cast<float>(x) + 0.5f) / static_cast<float>(n),
                   (static_cast<float>(y) + 0.5f) / static_cast<float>(n));
      // The lobe choice (of a mixture: the compensated conductor) from its own equidistributed sequence.
      const float u_lobe = static_cast<float>(std::fmod(0.5 + (double(y) * n + x) * 0.6180339887498949, 1.0));
      const BsdfSample bs = bsdf.sample(wv, u_lobe, u, TransportMode::Radiance);
      if (!bs.valid() || !(bs.wi.z > 0.0f)) continue;
      const float f = bs.f.g;
      norm += f / bs.pdf;
      const Vec3 h = glm::normalize(wv + bs.wi);
      fresnel += f / bs.pdf * std::pow(1.0 - std::clamp(double(glm::dot(wv, h)), 0.0, 1.0), 5.0);
      t.s.push_back({bs.wi, f, bs.pdf});
    }
  const double count = double(n) * n;
  t.norm = static_cast<float>(norm / count);
  t.fresnel_norm = static_cast<float>(fresnel / count);
  for (auto& s : t.s) s.f /= t.norm;
  return t;
}

// ∫ |D − F|^p dω by the balance heuristic over the BSDF's samples and n × n stratified samples of D.
double distance(const Bsdf& bsdf, const Vec3& wv, const TargetSamples& t, const Ltc& ltc, int n, int p) {
  const auto power = [p](double x) { return p == 1 ? x : x * x * x; };
  const double count = double(n) * n;  // both strategies draw n² (rejected BSDF samples count as drawn)
  const double target_count = count;
  double sum = 0;
  for (const auto& s : t.s) {
    const double d = ltc.eval(s.w);
    sum += power(std::abs(d - s.f)) / (target_count * s.pdf + count * d);
  }
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const Vec2 u((static_cast<float>(x) + 0.5f) / static_cast<float>(n),
                   (static_cast<float>(y) + 0.5f) / static_cast<float>(n));
      const Vec3 w = ltc.sample(u);
      const double d = ltc.pdf(w);
      if (!(d > 0.0)) continue;
      double f = 0, pdf = 0;
      if (w.z > 0.0f) {
        float bp;
        f = bsdf.eval_pdf(wv, w, &bp, TransportMode::Radiance).g / t.norm;
        pdf = bp;
      }
      sum += power(std::abs(d - f)) / (target_count * pdf + count * d);
    }
  return sum;
}

}  // namespace

LtcFitEntry fit_ltc_entry(const Bsdf& bsdf, const Vec3& wv, const LtcFitEntry& start, const LtcFitOptions& o) {
  const TargetSamples fit = target_samples(bsdf, wv, o.fit_samples);
  LtcFitEntry e = start;
  if (fit.norm > 0.0f) {
    const auto objective = [&](const std::vector<double>& x) {
      LtcFitEntry t;
      t.a = static_cast<float>(x[0]), t.b = static_cast<float>(x[1]), t.c = static_cast<float>(x[2]);
      t.d = static_cast<float>(x[3]);
      if (!(t.a > 1e-5f) || !(t.c > 1e-5f) || !(std::abs(t.a - t.b * t.d) > 1e-7f)) return 1e300;
      return distance(bsdf, wv, fit, Ltc(t.m()), o.fit_samples, 3);
    };
    NelderMeadOptions nm;
    nm.initial_step = 0.05;
    nm.tolerance = 1e-9;
    nm.max_evaluations = 1500;
    // Two rounds: a restart from the first minimum escapes a collapsed simplex.
    std::vector<double> x = {start.a, start.b, start.c, start.d};
    for (int round = 0; round < 2; ++round) x = nelder_mead(objective, x, nm).x;
    e.a = static_cast<float>(x[0]), e.b = static_cast<float>(x[1]), e.c = static_cast<float>(x[2]);
    e.d = static_cast<float>(x[3]);
  }
  const TargetSamples report = target_samples(bsdf, wv, o.report_samples);
  e.norm = report.norm;
  e.fresnel_norm = report.fresnel_norm;
  e.error = ltc_fit_error(bsdf, wv, e, o.report_samples);
  return e;
}

float ltc_fit_error(const Bsdf& bsdf, const Vec3& wv, const LtcFitEntry& e, int n) {
  const TargetSamples t = target_samples(bsdf, wv, n);
  return t.norm > 0.0f ? static_cast<float>(distance(bsdf, wv, t, Ltc(e.m()), n, 1)) : 0.0f;
}

namespace {

enum class TargetKind { Single, Compensated, Specular };

TargetKind target_kind(LtcBrdf brdf) {
  switch (brdf) {
    case LtcBrdf::GgxCompensated:
    case LtcBrdf::BeckmannCompensated:
      return TargetKind::Compensated;
    case LtcBrdf::GgxSpecular:
    case LtcBrdf::BeckmannSpecular:
      return TargetKind::Specular;
    default:
      return TargetKind::Single;
  }
}

MicrofacetType target_type(LtcBrdf brdf) {
  return brdf == LtcBrdf::Ggx || brdf == LtcBrdf::GgxCompensated || brdf == LtcBrdf::GgxSpecular
             ? MicrofacetType::GGX
             : MicrofacetType::Beckmann;
}

constexpr float kSpecularIor = 1.5f;  // the specular tables' IOR (plastic's and standard's default)

}  // namespace

LtcTargetBsdf ltc_target(LtcBrdf brdf, int size) {
  const TargetKind kind = target_kind(brdf);
  const MicrofacetType type = target_type(brdf);
  struct Tables {
    ConductorFresnel fresnel;  // F = 1
    std::map<float, ConductorCompensation> compensation;
    std::map<float, PlasticTables> plastic;
  };
  auto t = std::make_shared<Tables>();
  // Built before the fit, for the grid's roughnesses, so the parallel fit only reads them.
  for (int i = 0; i < size; ++i) {
    const float alpha = ltc_table_alpha(i, size);
    if (kind == TargetKind::Compensated)
      t->compensation.emplace(alpha, ConductorCompensation::make(type, alpha, t->fresnel, true));
    if (kind == TargetKind::Specular) t->plastic.emplace(alpha, PlasticTables::make_rough(type, alpha, kSpecularIor));
  }
  return [t, kind, type](float alpha, Arena& arena) -> const Bsdf* {
    const MicrofacetDistribution d(type, alpha, alpha);
    switch (kind) {
      case TargetKind::Compensated: {
        const auto it = t->compensation.find(alpha);
        if (it == t->compensation.end()) throw std::invalid_argument("ltc_target: α is not on the table's grid");
        return arena.make<RoughConductorBsdf>(d, &t->fresnel, &it->second);
      }
      case TargetKind::Specular: {
        const auto it = t->plastic.find(alpha);
        if (it == t->plastic.end()) throw std::invalid_argument("ltc_target: α is not on the table's grid");
        return arena.make<PlasticBsdf>(d, false, kSpecularIor, Rgb(0.0f), &it->second);  // albedo 0: the coat alone
      }
      case TargetKind::Single:
        break;
    }
    return arena.make<RoughConductorBsdf>(d, &t->fresnel, nullptr);
  };
}

float ltc_target_norm(LtcBrdf brdf, float cos_theta_v, float alpha) {
  const MicrofacetType type = target_type(brdf);
  const MicrofacetDistribution d(type, alpha, alpha);
  constexpr int n = 256;
  switch (target_kind(brdf)) {
    case TargetKind::Compensated:  // single scattering plus the coupled lobe's albedo F_ms (1 − E(μ)), F_ms = 1
      return static_cast<float>(albedo::integrate_conductor(d, cos_theta_v, n)) + 1.0f -
             albedo::conductor_E(type, cos_theta_v, alpha);
    case TargetKind::Specular: {
      double reflect = 0, total = 0;
      albedo::integrate_dielectric(d, cos_theta_v, kSpecularIor, n, &reflect, &total);
      return static_cast<float>(reflect);
    }
    case TargetKind::Single:
      break;
  }
  return static_cast<float>(albedo::integrate_conductor(d, cos_theta_v, n));
}

std::vector<LtcFitEntry> fit_ltc_table(const LtcTargetBsdf& target, const LtcFitOptions& o) {
  const int n = o.size;
  std::vector<LtcFitEntry> table(size_t(n) * n);
  tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(0, n, [&](int j) {
      const float theta = ltc_table_theta(j, n);
      const Vec3 wv(std::sin(theta), 0.0f, std::cos(theta));
      LtcFitEntry start;  // α = 1 starts from the cosine tilted halfway to the mirror direction
      start.b = 0.5f * std::tan(0.5f * theta);
      for (int i = n - 1; i >= 0; --i) {
        Arena mem;
        const Bsdf* bsdf = target(ltc_table_alpha(i, n), mem);
        const LtcFitEntry e = fit_ltc_entry(*bsdf, wv, start, o);
        table[size_t(i) * n + j] = e;
        start = e;
      }
    });
  });
  return table;
}

}  // namespace kozu
