// `kozu cod-diffuse-reference --gloss G [--samples N] [--resolution R] [--f0 F | --no-fresnel] [--seed S]
// -o SLICE.csv`: the reference BRDF slice of Chan 2018 §5.4–§5.6 (D. Chan, "Material Advances in Call of Duty:
// WWII", SIGGRAPH 2018 course Advances in Real-Time Rendering in Games) simulated by the random walk on a GGX
// microsurface with Lambertian facets of albedo 1 under the diffuse Fresnel of eq. (62)
// (materials/lambertian_microsurface.h), α from the gloss by eq. (2).
//
// The slice is R × R cells equiangular in θ_h, θ_d ∈ (0°, 90°) (cell centres) at φ_d = 90°, written as CSV with the
// header `x,y,value`: x = n·h = cos θ_h, y = l·h = cos θ_d (the variables of eq. (63)) and value = π f, the BRDF
// normalised so that Lambert is 1 (the fd + fb of eqs. (67)–(69)), so that `kozu fit-rational` reads it. It prints
// the error of the hand fit, eqs. (64)–(69) (cod_multiscatter_diffuse.h), against the slice: max and RMS of
// fit − simulation over the cells (all, and those with n·l > 0.2), and the slice's largest standard error.
// Exit codes: 0 success, 1 a bad value or an output that cannot be written (checked before the work), 2 usage.
#include "apps/command_errors.h"
#include "apps/commands.h"
#include "core/error.h"
#include "core/file_io.h"
#include "core/json_reader.h"
#include "core/rng.h"
#include "materials/cod_multiscatter_diffuse.h"
#include "materials/lambertian_microsurface.h"
#include "materials/roughness.h"
#include "render/output_paths.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace kozu::app {

namespace {

const std::string kCommand = "kozu cod-diffuse-reference";

struct Flags {
  std::string gloss, samples = "1024", resolution = "90", f0 = "0.04", seed = "1", output;
  bool no_fresnel = false;
};

int run_reference(const Flags& f) {
  const double gloss = number_flag_value(f.gloss, kCommand, "--gloss", Range::closed(0.0, 1.0));
  const int samples = static_cast<int>(integer_flag_value(f.samples, kCommand, "--samples", Range::closed(1, 1e7)));
  const int res = static_cast<int>(integer_flag_value(f.resolution, kCommand, "--resolution", Range::closed(2, 360)));
  const double f0 = number_flag_value(f.f0, kCommand, "--f0", Range::closed(0.0, 0.99));
  const uint64_t seed = uint64_flag_value(f.seed, kCommand, "--seed");
  check_output(f.output, "-o");

  const float alpha = gloss_to_alpha(static_cast<float>(gloss));  // Chan 2018 eq. (2)
  LambertianMicrosurfaceParams p;
  p.albedo = 1.0f;  // §5.4: the simulation bounces 100% of the light
  p.diffuse_fresnel = !f.no_fresnel;
  p.f0 = static_cast<float>(f0);
  const LambertianMicrosurface surface(MicrofacetDistribution(MicrofacetType::GGX, alpha, alpha), p);
  const CodMultiscatterDiffuseBsdf fit(Rgb(1.0f), static_cast<float>(gloss));

  std::vector<double> value(static_cast<size_t>(res) * res), error(value.size()), fitted(value.size());
  tbb::parallel_for(0, res * res, [&](int cell) {
    const int i = cell % res, j = cell / res;  // i along θ_h, j along θ_d
    const double theta_h = (i + 0.5) * 0.5 * kPi / res, theta_d = (j + 0.5) * 0.5 * kPi / res;
    Vec3 l, v;
    LambertianMicrosurface::slice_directions(theta_h, theta_d, &l, &v);
    Pcg32 rng(mix64(seed ^ (static_cast<uint64_t>(cell) * 0x9e3779b97f4a7c15ull)), static_cast<uint64_t>(cell));
    double se = 0.0;
    value[cell] = kPi * surface.eval_mean(v, l, samples, rng, &se);
    error[cell] = kPi * se;
    fitted[cell] = fit.shape(v, l);  // fd + fb of eqs. (64)–(68), = π fr / ρ of eq. (69)
  });

  std::string csv = "x,y,value\n";
  // Over all cells, and over those where n·l = n·v > 0.2 (θ < 78°): the hand fit trades accuracy at grazing
  // angles (§5.8: "larger errors where they are not noticeable"), and the grazing cells are the noisiest.
  double max_err = 0.0, sum2 = 0.0, max_se = 0.0, max_in = 0.0, sum2_in = 0.0;
  int n_in = 0;
  for (int j = 0; j < res; ++j) {
    for (int i = 0; i < res; ++i) {
      const int cell = j * res + i;
      const double theta_h = (i + 0.5) * 0.5 * kPi / res, theta_d = (j + 0.5) * 0.5 * kPi / res;
      csv += fmt::format("{:.9g},{:.9g},{:.9g}\n", std::cos(theta_h), std::cos(theta_d), value[cell]);
      const double e = fitted[cell] - value[cell];
      max_err = std::max(max_err, std::abs(e));
      sum2 += e * e;
      max_se = std::max(max_se, error[cell]);
      if (std::cos(theta_h) * std::cos(theta_d) > 0.2) {
        max_in = std::max(max_in, std::abs(e));
        sum2_in += e * e;
        ++n_in;
      }
    }
  }
  write_file_atomic(f.output, csv);
  std::printf(
      "gloss %.3g (alpha %.4g), %s, %dx%d cells, %d walks each: hand fit (eqs. 64-69) - simulation: "
      "max |error| %.4f, RMS %.4f; where n.l > 0.2: max %.4f, RMS %.4f; largest standard error of a cell %.4f\n",
      gloss, alpha, p.diffuse_fresnel ? fmt::format("diffuse Fresnel F0 = {:g}", f0).c_str() : "no Fresnel", res, res,
      samples, max_err, std::sqrt(sum2 / value.size()), max_in, n_in > 0 ? std::sqrt(sum2_in / n_in) : 0.0, max_se);
  return 0;
}

}  // namespace

Command add_cod_diffuse_reference_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "cod-diffuse-reference",
      "Simulate the multiple-scattering Lambertian GGX microsurface (Chan 2018 §5) and write its BRDF slice as CSV");
  auto f = std::make_shared<Flags>();
  cmd->add_option("--gloss", f->gloss, "WWII gloss in [0, 1] (alpha by Chan 2018 eq. 2)")->required();
  cmd->add_option("--samples", f->samples, "Walks per cell, in [1, 1e7] (default 1024)");
  cmd->add_option("--resolution", f->resolution, "Cells per axis of the theta_h x theta_d slice, in [2, 360] (90)");
  cmd->add_option("--f0", f->f0, "F0 of the diffuse Fresnel, eqs. 61-62, in [0, 0.99] (0.04)");
  cmd->add_flag("--no-fresnel", f->no_fresnel, "Plain Lambertian facets (no diffuse Fresnel)");
  cmd->add_option("--seed", f->seed, "Seed of the walks (default 1)");
  cmd->add_option("-o,--output", f->output, "Output: the slice as CSV x,y,value (x = n.h, y = l.h)")->required();
  return [cmd, f]() -> int {
    if (!cmd->parsed()) return 2;
    try {
      return run_reference(*f);
    } catch (const std::exception& e) {
      return report_failure("cod-diffuse-reference", e);
    }
  };
}

}  // namespace kozu::app
