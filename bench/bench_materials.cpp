// Costs of the BSDF models, in ns per call of eval / sample / pdf (virtual calls through Bsdf, as the
// integrator makes them), and of the microfacet module's D, Λ, G2 and VNDF sampling.
//
//   build-bench/bench/bench_materials --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Every BSDF is built through its Material's constructor and material->bsdf() once, outside the timed
// loop. Inputs are a fixed-seed table of 4096 (wo, wi, u_lobe, u) tuples, cycled through so that the
// branches (below-horizon, TIR, lobe choice, Beckmann's Λ early out) are not trivially predicted:
//   reflection set    wo uniform on the upper hemisphere, 1/16 of them mirrored below (two-sided
//                     models); wi uniform on wo's hemisphere, 1/16 of them on the other side
//   transmission set  (dielectric) wo outside with probability 3/4, inside otherwise; wi uniform on the
//                     sphere, so half the pairs are refraction pairs
// One iteration is one call: Time (wall) and CPU are ns per call. Rows are named
//   <model>/<distribution>/a<alpha>/<multiscatter>/<eval|sample|pdf>
// and the ms_ratio/... rows time `none` and `compensated` on the same inputs in interleaved blocks;
// their counters none_ns and comp_ns are ns of thread CPU time per call and comp/none the cost ratio
// (robust to the machine's load drifting between two separate rows). On a shared machine compare the
// CPU column of the other rows: the Time column (wall) also counts time spent preempted.
//
// multiscatter: stochastic (Heitz et al. 2016, the microsurface walk) rows run for α = 0.3 and α = 1,
// next to none / compensated at α = 1. A stochastic row whose bsdf() is not a Stochastic*Bsdf is
// skipped with an error message rather than timing the wrong model.
#include "core/arena.h"
#include "core/rng.h"
#include "core/warp.h"
#include "materials/conductor.h"
#include "materials/dielectric.h"
#include "materials/diffuse.h"
#include "materials/metal_data.h"
#include "materials/microfacet.h"
#include "materials/plastic.h"

#include <benchmark/benchmark.h>

#include <ctime>
#include <memory>
#include <string>
#include <vector>

namespace kozu {
namespace {

constexpr size_t kInputs = 4096;  // power of two: indices wrap with a mask
constexpr size_t kMask = kInputs - 1;
constexpr float kAlpha = 0.3f;

struct Tuple {
  Vec3 wo, wi;
  float u_lobe;
  Vec2 u;
};

enum class InputSet { Reflection, Transmission };

std::vector<Tuple> make_inputs(InputSet set) {
  std::vector<Tuple> v(kInputs);
  Pcg32 rng(0x6b6f7a75u, set == InputSet::Reflection ? 1 : 2);
  auto uniform2 = [&] {
    const float a = rng.next_float();
    return Vec2(a, rng.next_float());
  };
  for (Tuple& t : v) {
    if (set == InputSet::Reflection) {
      t.wo = warp::square_to_uniform_hemisphere(uniform2());
      if ((rng.next_u32() & 15) == 0) t.wo.z = -t.wo.z;
      t.wi = warp::square_to_uniform_hemisphere(uniform2());
      if (t.wo.z < 0.0f) t.wi.z = -t.wi.z;
      if ((rng.next_u32() & 15) == 0) t.wi.z = -t.wi.z;
    } else {
      t.wo = warp::square_to_uniform_hemisphere(uniform2());
      if ((rng.next_u32() & 3) == 0) t.wo.z = -t.wo.z;
      t.wi = warp::square_to_uniform_sphere(uniform2());
    }
    t.u_lobe = rng.next_float();
    t.u = uniform2();
  }
  return v;
}

const std::vector<Tuple>& inputs(InputSet set) {
  static const std::vector<Tuple> reflection = make_inputs(InputSet::Reflection);
  static const std::vector<Tuple> transmission = make_inputs(InputSet::Transmission);
  return set == InputSet::Reflection ? reflection : transmission;
}

enum class Op { Eval, Sample, Pdf };
constexpr const char* kOpNames[] = {"eval", "sample", "pdf"};

// n calls of op on inputs i, i + 1, ... (wrapping).
template <Op op>
inline void run_calls(const Bsdf* bsdf, const std::vector<Tuple>& in, size_t i, size_t n) {
  for (size_t k = 0; k < n; ++k) {
    const Tuple& t = in[(i + k) & kMask];
    if constexpr (op == Op::Eval) {
      Rgb r = bsdf->eval(t.wo, t.wi, TransportMode::Radiance);
      benchmark::DoNotOptimize(r);
    } else if constexpr (op == Op::Sample) {
      BsdfSample r = bsdf->sample(t.wo, t.u_lobe, t.u, TransportMode::Radiance);
      benchmark::DoNotOptimize(r);
    } else {
      float r = bsdf->pdf(t.wo, t.wi);
      benchmark::DoNotOptimize(r);
    }
  }
}

template <Op op>
void time_op(benchmark::State& state, const Bsdf* bsdf, const std::vector<Tuple>& in) {
  size_t i = 0;
  for (auto _ : state) run_calls<op>(bsdf, in, i++, 1);
  state.SetItemsProcessed(state.iterations());
}

void time_op(benchmark::State& state, Op op, const Bsdf* bsdf, const std::vector<Tuple>& in) {
  switch (op) {
    case Op::Eval:
      return time_op<Op::Eval>(state, bsdf, in);
    case Op::Sample:
      return time_op<Op::Sample>(state, bsdf, in);
    case Op::Pdf:
      return time_op<Op::Pdf>(state, bsdf, in);
  }
}

// This thread's CPU time in ns: unlike wall time it leaves out the time the thread sits preempted on
// the shared machine, which would otherwise land on whichever block happened to be running.
double thread_cpu_ns() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e9 + static_cast<double>(ts.tv_nsec);
}

// `none` and `compensated` on the same inputs, in interleaved blocks of kBlock calls each (the order
// alternates per iteration), each block timed by thread CPU time. One iteration is 2 kBlock calls.
template <Op op>
void time_ratio(benchmark::State& state, const Bsdf* none, const Bsdf* comp, const std::vector<Tuple>& in) {
  constexpr size_t kBlock = 1024;  // the clock read (~0.1-0.5 us) stays below 1% of a block
  double t_none = 0.0, t_comp = 0.0;
  size_t i = 0;
  bool none_first = true;
  for (auto _ : state) {
    const Bsdf* first = none_first ? none : comp;
    const Bsdf* second = none_first ? comp : none;
    const double t0 = thread_cpu_ns();
    run_calls<op>(first, in, i, kBlock);
    const double t1 = thread_cpu_ns();
    run_calls<op>(second, in, i, kBlock);
    const double t2 = thread_cpu_ns();
    (none_first ? t_none : t_comp) += t1 - t0;
    (none_first ? t_comp : t_none) += t2 - t1;
    none_first = !none_first;
    i += kBlock;
  }
  const double calls = static_cast<double>(state.iterations()) * kBlock;
  state.counters["none_ns"] = calls > 0 ? t_none / calls : 0.0;
  state.counters["comp_ns"] = calls > 0 ? t_comp / calls : 0.0;
  state.counters["comp/none"] = t_none > 0 ? t_comp / t_none : 0.0;
  state.SetItemsProcessed(static_cast<int64_t>(2 * calls));
}

void time_ratio(benchmark::State& state, Op op, const Bsdf* none, const Bsdf* comp, const std::vector<Tuple>& in) {
  switch (op) {
    case Op::Eval:
      return time_ratio<Op::Eval>(state, none, comp, in);
    case Op::Sample:
      return time_ratio<Op::Sample>(state, none, comp, in);
    case Op::Pdf:
      return time_ratio<Op::Pdf>(state, none, comp, in);
  }
}

// ---- materials --------------------------------------------------------------------------------------

// Materials live for the whole run; benchmarks hold plain pointers.
std::vector<std::unique_ptr<Material>>& materials() {
  static std::vector<std::unique_ptr<Material>> m;
  return m;
}

const Material* keep(std::unique_ptr<Material> m) {
  materials().push_back(std::move(m));
  return materials().back().get();
}

ConductorFresnel gold() {
  const MetalIor* au = find_metal("Au");
  ConductorFresnel f;
  f.eta = au->eta;
  f.k = au->k;
  f.perfect = false;
  return f;
}

const char* distribution_name(MicrofacetType t) { return t == MicrofacetType::GGX ? "ggx" : "beckmann"; }
const char* mode_name(MultiscatterMode m) {
  switch (m) {
    case MultiscatterMode::None:
      return "none";
    case MultiscatterMode::Compensated:
      return "compensated";
    case MultiscatterMode::Stochastic:
      return "stochastic";
  }
  return "?";
}
std::string alpha_name(float alpha) { return alpha == 1.0f ? "a1" : alpha == kAlpha ? "a0.3" : "a?"; }

void register_bsdf_rows(const std::string& prefix, const Material* material, InputSet set) {
  for (const Op op : {Op::Eval, Op::Sample, Op::Pdf}) {
    benchmark::RegisterBenchmark((prefix + "/" + kOpNames[static_cast<int>(op)]).c_str(),
                                 [material, set, op](benchmark::State& state) {
                                   Arena arena;
                                   const Bsdf* bsdf = material->bsdf(SurfaceInteraction{}, arena);
                                   time_op(state, op, bsdf, inputs(set));
                                 });
  }
}

void register_ratio_rows(const std::string& prefix, const Material* none, const Material* comp, InputSet set) {
  for (const Op op : {Op::Eval, Op::Sample, Op::Pdf}) {
    benchmark::RegisterBenchmark(("ms_ratio/" + prefix + "/" + kOpNames[static_cast<int>(op)]).c_str(),
                                 [none, comp, set, op](benchmark::State& state) {
                                   Arena arena;
                                   const Bsdf* b_none = none->bsdf(SurfaceInteraction{}, arena);
                                   const Bsdf* b_comp = comp->bsdf(SurfaceInteraction{}, arena);
                                   time_ratio(state, op, b_none, b_comp, inputs(set));
                                 });
  }
}

// ---- multiscatter: stochastic -----------------------------------------------------------------------
// The rows time StochasticConductorBsdf / StochasticDielectricBsdf; should bsdf() return another
// BSDF for MultiscatterMode::Stochastic, each row reports the error below and takes no time.

bool is_stochastic(const Bsdf* bsdf) {
  return dynamic_cast<const StochasticConductorBsdf*>(bsdf) != nullptr ||
         dynamic_cast<const StochasticDielectricBsdf*>(bsdf) != nullptr;
}

void register_stochastic_rows(const std::string& prefix, const Material* material, InputSet set) {
  for (const Op op : {Op::Eval, Op::Sample, Op::Pdf}) {
    benchmark::RegisterBenchmark(
        (prefix + "/" + kOpNames[static_cast<int>(op)]).c_str(), [material, set, op](benchmark::State& state) {
          Arena arena;
          const Bsdf* bsdf = material->bsdf(SurfaceInteraction{}, arena);
          if (!is_stochastic(bsdf)) {
            state.SkipWithError("multiscatter: stochastic: bsdf() did not return a Stochastic*Bsdf");
            return;
          }
          time_op(state, op, bsdf, inputs(set));
        });
  }
}

// ---- microfacet module ------------------------------------------------------------------------------

struct MicrofacetTuple {
  Vec3 m, wo, wi;  // all upper hemisphere; m the half vector of (wo, wi)
  Vec2 u;
};

const std::vector<MicrofacetTuple>& microfacet_inputs() {
  static const std::vector<MicrofacetTuple> v = [] {
    std::vector<MicrofacetTuple> r(kInputs);
    Pcg32 rng(0x6b6f7a75u, 3);
    auto uniform2 = [&] {
      const float a = rng.next_float();
      return Vec2(a, rng.next_float());
    };
    for (MicrofacetTuple& t : r) {
      t.wo = warp::square_to_uniform_hemisphere(uniform2());
      t.wi = warp::square_to_uniform_hemisphere(uniform2());
      t.m = glm::normalize(t.wo + t.wi);
      t.u = uniform2();
    }
    return r;
  }();
  return v;
}

enum class MfOp { D, Lambda, G2, SampleVisible };

template <MfOp op>
void time_microfacet(benchmark::State& state, const MicrofacetDistribution d) {
  const auto& in = microfacet_inputs();
  size_t i = 0;
  for (auto _ : state) {
    const MicrofacetTuple& t = in[i++ & kMask];
    if constexpr (op == MfOp::D) {
      float r = d.D(t.m);
      benchmark::DoNotOptimize(r);
    } else if constexpr (op == MfOp::Lambda) {
      float r = d.lambda(t.wo);
      benchmark::DoNotOptimize(r);
    } else if constexpr (op == MfOp::G2) {
      float r = d.G2(t.wo, t.wi);
      benchmark::DoNotOptimize(r);
    } else {
      Vec3 r = d.sample_visible(t.wo, t.u);
      benchmark::DoNotOptimize(r);
    }
  }
  state.SetItemsProcessed(state.iterations());
}

void register_microfacet_rows(MicrofacetType type) {
  const MicrofacetDistribution d(type, kAlpha, kAlpha);
  const std::string prefix = std::string("microfacet/") + distribution_name(type) + "/" + alpha_name(kAlpha) + "/";
  benchmark::RegisterBenchmark((prefix + "D").c_str(), [d](benchmark::State& s) { time_microfacet<MfOp::D>(s, d); });
  benchmark::RegisterBenchmark((prefix + "lambda").c_str(),
                               [d](benchmark::State& s) { time_microfacet<MfOp::Lambda>(s, d); });
  benchmark::RegisterBenchmark((prefix + "G2").c_str(), [d](benchmark::State& s) { time_microfacet<MfOp::G2>(s, d); });
  benchmark::RegisterBenchmark((prefix + "sample_visible").c_str(),
                               [d](benchmark::State& s) { time_microfacet<MfOp::SampleVisible>(s, d); });
}

// ---- the rows -----------------------------------------------------------------------------------------

void register_all() {
  constexpr InputSet kR = InputSet::Reflection, kT = InputSet::Transmission;
  const MicrofacetType kTypes[] = {MicrofacetType::GGX, MicrofacetType::Beckmann};

  // diffuse
  register_bsdf_rows("diffuse/lambert", keep(std::make_unique<DiffuseMaterial>(Rgb(0.5f))), kR);
  register_bsdf_rows(
      "diffuse/cod-multiscatter",
      keep(std::make_unique<DiffuseMaterial>(DiffuseParams{DiffuseModel::CodMultiscatter, Rgb(0.5f), 0.5f, 0.04f})),
      kR);
  register_bsdf_rows(
      "diffuse/shirley",
      keep(std::make_unique<DiffuseMaterial>(DiffuseParams{DiffuseModel::Shirley, Rgb(0.5f), 0.5f, 0.04f})), kR);

  // conductor (gold, exact Fresnel)
  const ConductorFresnel au = gold();
  register_bsdf_rows(
      "conductor/smooth",
      keep(std::make_unique<ConductorMaterial>(au, true, MicrofacetDistribution(), MultiscatterMode::None)), kR);
  for (const MicrofacetType type : kTypes) {
    const MicrofacetDistribution d(type, kAlpha, kAlpha);
    const std::string prefix = std::string("conductor/") + distribution_name(type) + "/" + alpha_name(kAlpha);
    const Material* none = keep(std::make_unique<ConductorMaterial>(au, false, d, MultiscatterMode::None));
    const Material* comp = keep(std::make_unique<ConductorMaterial>(au, false, d, MultiscatterMode::Compensated));
    register_bsdf_rows(prefix + "/none", none, kR);
    register_bsdf_rows(prefix + "/compensated", comp, kR);
  }

  // dielectric (IOR 1.5)
  register_bsdf_rows("dielectric/smooth", keep(std::make_unique<DielectricMaterial>(1.5f, true)), kT);
  for (const MicrofacetType type : kTypes) {
    const MicrofacetDistribution d(type, kAlpha, kAlpha);
    const std::string prefix = std::string("dielectric/") + distribution_name(type) + "/" + alpha_name(kAlpha);
    const Material* none = keep(std::make_unique<DielectricMaterial>(1.5f, false, d, MultiscatterMode::None));
    const Material* comp = keep(std::make_unique<DielectricMaterial>(1.5f, false, d, MultiscatterMode::Compensated));
    register_bsdf_rows(prefix + "/none", none, kT);
    register_bsdf_rows(prefix + "/compensated", comp, kT);
  }

  // plastic (k = 0.5, IOR 1.5)
  register_bsdf_rows("plastic/ggx/" + alpha_name(kAlpha),
                     keep(std::make_unique<PlasticMaterial>(
                         Rgb(0.5f), 1.5f, false, MicrofacetDistribution(MicrofacetType::GGX, kAlpha, kAlpha))),
                     kR);
  register_bsdf_rows("plastic/smooth",
                     keep(std::make_unique<PlasticMaterial>(Rgb(0.5f), 1.5f, true, MicrofacetDistribution())), kR);

  // microfacet module alone
  for (const MicrofacetType type : kTypes) register_microfacet_rows(type);

  // compensated / none, same inputs, interleaved
  for (const MicrofacetType type : kTypes) {
    const MicrofacetDistribution d(type, kAlpha, kAlpha);
    const std::string tail = std::string(distribution_name(type)) + "/" + alpha_name(kAlpha);
    register_ratio_rows("conductor/" + tail,
                        keep(std::make_unique<ConductorMaterial>(au, false, d, MultiscatterMode::None)),
                        keep(std::make_unique<ConductorMaterial>(au, false, d, MultiscatterMode::Compensated)), kR);
    register_ratio_rows("dielectric/" + tail,
                        keep(std::make_unique<DielectricMaterial>(1.5f, false, d, MultiscatterMode::None)),
                        keep(std::make_unique<DielectricMaterial>(1.5f, false, d, MultiscatterMode::Compensated)), kT);
  }

  // ---- walk-based rows: multiscatter: stochastic at α = 0.3 and α = 1, with none / compensated at α = 1
  // for reference (the α = 0.3 ones are above).
  for (const float alpha : {kAlpha, 1.0f}) {
    for (const MicrofacetType type : kTypes) {
      const MicrofacetDistribution d(type, alpha, alpha);
      const std::string tail = std::string(distribution_name(type)) + "/" + alpha_name(alpha) + "/";
      if (alpha == 1.0f) {
        for (const MultiscatterMode mode : {MultiscatterMode::None, MultiscatterMode::Compensated}) {
          register_bsdf_rows("conductor/" + tail + mode_name(mode),
                             keep(std::make_unique<ConductorMaterial>(au, false, d, mode)), kR);
          register_bsdf_rows("dielectric/" + tail + mode_name(mode),
                             keep(std::make_unique<DielectricMaterial>(1.5f, false, d, mode)), kT);
        }
      }
      register_stochastic_rows("conductor/" + tail + "stochastic",
                               keep(std::make_unique<ConductorMaterial>(au, false, d, MultiscatterMode::Stochastic)),
                               kR);
      register_stochastic_rows("dielectric/" + tail + "stochastic",
                               keep(std::make_unique<DielectricMaterial>(1.5f, false, d, MultiscatterMode::Stochastic)),
                               kT);
    }
  }
}

}  // namespace
}  // namespace kozu

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  kozu::register_all();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
