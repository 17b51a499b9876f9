#include "tools/profile_fit.h"

#include "core/rng.h"
#include "tools/chandrasekhar_h.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>

namespace kozu {

double normalized_diffusion_annulus_fraction(double d, double r_lo, double r_hi) {
  // cdf(r) = 1 − e^{−r/d}/4 − 3 e^{−r/(3d)}/4 (eq. 11), so the difference is
  // e^{−lo/d}(1 − e^{−Δ/d})/4 + 3 e^{−lo/(3d)}(1 − e^{−Δ/(3d)})/4 with Δ = hi − lo.
  const double delta = r_hi - r_lo;
  return -0.25 * std::exp(-r_lo / d) * std::expm1(-delta / d) -
         0.75 * std::exp(-r_lo / (3.0 * d)) * std::expm1(-delta / (3.0 * d));
}

std::vector<int> select_bins(const std::vector<ProfileBin>& bins, double max_relative_se) {
  std::vector<int> use;
  for (size_t i = 0; i < bins.size(); ++i)
    if (bins[i].R > 0.0 && bins[i].R_se <= max_relative_se * bins[i].R) use.push_back(static_cast<int>(i));
  return use;
}

double mean_relative_error(const std::vector<ProfileBin>& bins, const std::vector<int>& use, double A, double s) {
  if (use.empty()) return 0.0;
  const double d = 1.0 / s;  // eq. (3) with ℓ = 1: d = ℓ/s
  double sum = 0.0;
  for (int i : use) {
    const ProfileBin& b = bins[i];
    const double area = std::numbers::pi * (b.r_hi * b.r_hi - b.r_lo * b.r_lo);
    const double model = A * normalized_diffusion_annulus_fraction(d, b.r_lo, b.r_hi) / area;
    sum += std::abs(model - b.R) / b.R;
  }
  return sum / static_cast<double>(use.size());
}

ScaleFit fit_scale(const std::vector<ProfileBin>& bins, const std::vector<int>& use, double A) {
  // Coarse scan on a log grid, then golden-section search between the best point's neighbours.
  constexpr double kMin = 0.05, kMax = 200.0;
  constexpr int kScan = 360;
  const double ratio = std::pow(kMax / kMin, 1.0 / kScan);
  int best = 0;
  double best_error = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= kScan; ++i) {
    const double e = mean_relative_error(bins, use, A, kMin * std::pow(ratio, i));
    if (e < best_error) best_error = e, best = i;
  }
  double lo = kMin * std::pow(ratio, std::max(best - 1, 0)), hi = kMin * std::pow(ratio, std::min(best + 1, kScan));
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  double f1 = mean_relative_error(bins, use, A, x1), f2 = mean_relative_error(bins, use, A, x2);
  while (hi - lo > 1e-7 * hi) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1;
      x1 = hi - g * (hi - lo);
      f1 = mean_relative_error(bins, use, A, x1);
    } else {
      lo = x1, x1 = x2, f1 = f2;
      x2 = lo + g * (hi - lo);
      f2 = mean_relative_error(bins, use, A, x2);
    }
  }
  ScaleFit fit{kMin * std::pow(ratio, best), best_error};
  const double s = 0.5 * (lo + hi), e = mean_relative_error(bins, use, A, s);
  if (e < fit.error) fit = {s, e};
  return fit;
}

int bins_within(const RadialBins& bins, double r_max) {
  int k = 0;
  while (k < bins.count && bins.edge(k + 1) <= r_max * (1.0 + 1e-9)) ++k;
  return k;
}

const char* parameterization_name(SubsurfaceParameterization p) {
  switch (p) {
    case SubsurfaceParameterization::Searchlight:
      return "searchlight";
    case SubsurfaceParameterization::Diffuse:
      return "diffuse";
    case SubsurfaceParameterization::Dmfp:
      return "dmfp";
  }
  return "?";
}

namespace {

constexpr int kMinBins = 5;

ProfileTableRow fit_row(const std::vector<ProfileBin>& bins, double max_relative_se, SubsurfaceParameterization p,
                        double A, const SemiInfiniteMcResult& mc) {
  ProfileTableRow row;
  row.A = A;
  row.alpha = mc.settings.albedo;
  row.A_mc = mc.A;
  row.A_mc_se = mc.A_se;
  row.truncated = mc.truncated;
  row.dmfp = mc.dmfp;
  const std::vector<int> use = select_bins(bins, max_relative_se);
  row.bins_used = static_cast<int>(use.size());
  double rel_se = 0.0;
  for (int i : use) rel_se += bins[i].R_se / bins[i].R;
  row.noise_floor = use.empty() ? 0.0 : std::sqrt(2.0 / std::numbers::pi) * rel_se / static_cast<double>(use.size());
  row.s_formula = normalized_diffusion::scale(p, A);
  if (row.bins_used < kMinBins) {  // too few photons for a meaningful fit: left out of the means
    row.s_opt = row.error_opt = row.error_formula = std::numeric_limits<double>::quiet_NaN();
    return row;
  }
  const ScaleFit fit = fit_scale(bins, use, mc.A);
  row.s_opt = fit.s;
  row.error_opt = fit.error;
  row.error_formula = mean_relative_error(bins, use, mc.A, row.s_formula);
  return row;
}

std::vector<ProfileBin> first_bins(const std::vector<ProfileBin>& bins, int count) {
  return {bins.begin(), bins.begin() + std::min<std::ptrdiff_t>(count, static_cast<std::ptrdiff_t>(bins.size()))};
}

std::vector<ProfileTableColumn> empty_columns() {
  std::vector<ProfileTableColumn> columns;
  for (SubsurfaceParameterization p : {SubsurfaceParameterization::Searchlight, SubsurfaceParameterization::Diffuse,
                                       SubsurfaceParameterization::Dmfp}) {
    ProfileTableColumn c;
    c.parameterization = p;
    columns.push_back(c);
  }
  return columns;
}

// Adds the rows of one albedo: from a searchlight run the searchlight and dmfp columns, from a diffuse run the
// diffuse column. `count` keeps the leading bins only (the range scan).
void add_rows(std::vector<ProfileTableColumn>& columns, const SemiInfiniteMcResult& mc, double A,
              double max_relative_se, int count) {
  if (mc.settings.illumination == SubsurfaceIllumination::Searchlight) {
    columns[0].rows.push_back(
        fit_row(first_bins(mc.profile(), count), max_relative_se, SubsurfaceParameterization::Searchlight, A, mc));
    columns[2].rows.push_back(
        fit_row(first_bins(mc.dmfp_profile(), count), max_relative_se, SubsurfaceParameterization::Dmfp, A, mc));
  } else {
    columns[1].rows.push_back(
        fit_row(first_bins(mc.profile(), count), max_relative_se, SubsurfaceParameterization::Diffuse, A, mc));
  }
}

void finish_columns(std::vector<ProfileTableColumn>& columns) {
  for (ProfileTableColumn& c : columns) {
    double opt = 0.0, formula = 0.0;
    c.albedos_fitted = 0;
    for (const ProfileTableRow& r : c.rows) {
      if (!(r.bins_used >= kMinBins)) continue;
      opt += r.error_opt, formula += r.error_formula;
      ++c.albedos_fitted;
    }
    c.optimal_s_error = c.albedos_fitted ? opt / c.albedos_fitted : std::numeric_limits<double>::quiet_NaN();
    c.formula_error = c.albedos_fitted ? formula / c.albedos_fitted : std::numeric_limits<double>::quiet_NaN();
  }
}

}  // namespace

ProfileTable build_profile_table(const ProfileTableSettings& settings,
                                 const std::function<void(const std::string&)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  ProfileTable table;
  table.settings = settings;
  if (table.settings.albedos.empty())
    for (int i = 1; i <= 99; ++i) table.settings.albedos.push_back(i / 100.0);
  table.columns = empty_columns();
  for (double r_max : settings.rmax_scan) {
    ProfileRangeScan scan;
    scan.requested = r_max;
    scan.bins = bins_within(settings.bins, r_max);
    scan.r_max = settings.bins.edge(scan.bins);
    scan.columns = empty_columns();
    table.scans.push_back(scan);
  }
  const auto& albedos = table.settings.albedos;
  for (size_t k = 0; k < albedos.size(); ++k) {
    const double A = albedos[k];
    for (SubsurfaceIllumination illum : {SubsurfaceIllumination::Searchlight, SubsurfaceIllumination::Diffuse}) {
      const bool searchlight = illum == SubsurfaceIllumination::Searchlight;
      SemiInfiniteMcSettings s;
      s.albedo = chandrasekhar::single_scattering_albedo(illum, A);
      s.illumination = illum;
      s.photons = settings.photons;
      // An independent stream per (illumination, albedo), all derived from the one seed.
      s.seed = mix64(settings.seed * 0x9e3779b97f4a7c15ull + (searchlight ? 0u : 1000u) + k);
      s.bins = settings.bins;
      if (searchlight) s.dmfp_bins = settings.bins;
      s.max_collisions = settings.max_collisions;
      const SemiInfiniteMcResult mc = simulate_semi_infinite(s);
      add_rows(table.columns, mc, A, settings.max_relative_se, settings.bins.count);
      for (ProfileRangeScan& scan : table.scans) add_rows(scan.columns, mc, A, settings.max_relative_se, scan.bins);
    }
    if (progress) {
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const ProfileTableRow& a = table.columns[0].rows.back();
      const ProfileTableRow& b = table.columns[1].rows.back();
      const ProfileTableRow& c = table.columns[2].rows.back();
      progress(
          fmt::format("A = {:.2f} ({}/{}, {:.0f} s): s_opt / error / formula error  searchlight {:.3f} {:.1f}% "
                      "{:.1f}%  diffuse {:.3f} {:.1f}% {:.1f}%  dmfp {:.3f} {:.1f}% {:.1f}%",
                      A, k + 1, albedos.size(), seconds, a.s_opt, 100 * a.error_opt, 100 * a.error_formula, b.s_opt,
                      100 * b.error_opt, 100 * b.error_formula, c.s_opt, 100 * c.error_opt, 100 * c.error_formula));
    }
  }
  finish_columns(table.columns);
  for (ProfileRangeScan& scan : table.scans) finish_columns(scan.columns);
  table.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return table;
}

nlohmann::json table_to_json(const ProfileTable& table) {
  using nlohmann::json;
  // Christensen & Burley 2015, § 3.2, § 4 and § 5.
  const double paper[3][2] = {{0.049, 0.055}, {0.026, 0.039}, {0.064, 0.077}};
  json out = json::object();
  for (size_t i = 0; i < table.columns.size(); ++i) {
    const ProfileTableColumn& c = table.columns[i];
    json rows = json::array();
    for (const ProfileTableRow& r : c.rows)
      rows.push_back({{"A", r.A},
                      {"alpha", r.alpha},
                      {"A_mc", r.A_mc},
                      {"A_mc_se", r.A_mc_se},
                      {"truncated", r.truncated},
                      {"dmfp", r.dmfp},
                      {"s_opt", r.s_opt},
                      {"error_opt", r.error_opt},
                      {"s_formula", r.s_formula},
                      {"error_formula", r.error_formula},
                      {"bins_used", r.bins_used},
                      {"noise_floor", r.noise_floor}});
    out[parameterization_name(c.parameterization)] = {
        {"optimal_s_error", c.optimal_s_error},
        {"formula_error", c.formula_error},
        {"albedos_fitted", c.albedos_fitted},
        {"paper", {{"optimal_s_error", paper[i][0]}, {"formula_error", paper[i][1]}}},
        {"per_albedo", rows}};
  }
  // NaN (a row with too few bins) becomes null in the JSON.
  const auto number = [](double x) { return std::isfinite(x) ? json(x) : json(nullptr); };
  json scans = json::array();
  for (const ProfileRangeScan& scan : table.scans) {
    json entry = {{"requested", scan.requested}, {"r_max", scan.r_max}, {"bins", scan.bins}};
    for (const ProfileTableColumn& c : scan.columns) {
      json s_opt = json::array(), error_opt = json::array(), error_formula = json::array();
      for (const ProfileTableRow& r : c.rows) {
        s_opt.push_back(number(r.s_opt));
        error_opt.push_back(number(r.error_opt));
        error_formula.push_back(number(r.error_formula));
      }
      entry[parameterization_name(c.parameterization)] = {{"optimal_s_error", number(c.optimal_s_error)},
                                                          {"formula_error", number(c.formula_error)},
                                                          {"albedos_fitted", c.albedos_fitted},
                                                          {"s_opt", s_opt},
                                                          {"error_opt", error_opt},
                                                          {"error_formula", error_formula}};
    }
    scans.push_back(entry);
  }
  out["rmax_scan"] = scans;
  const ProfileTableSettings& s = table.settings;
  out["settings"] = {
      {"photons", s.photons},
      {"seed", s.seed},
      {"r_min", s.bins.r_min},
      {"r_max", s.bins.r_max},
      {"bins", s.bins.count},
      {"binning", "log-spaced annuli; radii in units of the mfp l (searchlight, diffuse) or the dmfp l_d (dmfp)"},
      {"max_relative_se", s.max_relative_se},
      {"max_collisions", s.max_collisions},
      {"rmax_scan", s.rmax_scan},
      {"albedos", s.albedos},
      {"error", "mean over selected bins of |Rbar_model - R_MC| / R_MC, Rbar = exact annulus average"},
      {"seconds", table.seconds}};
  return out;
}

}  // namespace kozu
