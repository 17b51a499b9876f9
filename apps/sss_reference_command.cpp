// `kozu sss-reference`: the brute-force Monte Carlo reference of Christensen & Burley 2015 § 3.1
// (src/tools/semi_infinite_mc.h) and the reproduction of their table of fit errors
// (src/tools/profile_fit.h; docs/subsurface.md).
//
//   kozu sss-reference --surface-albedo 0.5 --illumination diffuse -o profile.csv
//   kozu sss-reference --albedo 0.99 --photons 1e6 -o profile.json
//   kozu sss-reference --table --json docs/data/sss_table.json --rmax-scan 1,2.3714,5.6235
//
// Single-profile output by extension: .json (settings, totals, and the bins, plus the same profile in units of the
// dmfp for a searchlight with α < 1) or .csv (lines starting with '#' hold the totals, then the header line
// r_lo,r_hi,r,R,R_se,rR,rR_se: bin edges, geometric-mean radius, annulus-averaged R per unit area and unit incident
// power, its standard error, r·R and its standard error; lengths in units of --mfp's unit). Without -o the CSV goes
// to stdout. Bad values (out of range, or no number) give a one-line message and exit code 1, as does an output
// that cannot be written (checked before the simulation); usage errors (an unknown option, a missing argument) give
// exit code 2 like every kozu command.
#include "apps/command_errors.h"
#include "apps/commands.h"
#include "core/file_io.h"
#include "core/json_reader.h"
#include "render/output_paths.h"
#include "render/renderer.h"
#include "tools/chandrasekhar_h.h"
#include "tools/profile_fit.h"
#include "tools/semi_infinite_mc.h"

#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <vector>

namespace kozu::app {

namespace {

struct SssArgs {
  std::optional<double> albedo, surface_albedo;
  std::string illumination = "searchlight";
  double mfp = 1.0;
  std::optional<double> photons;  // a double so that 1e6 parses
  uint64_t seed = 1;
  int bins = 48;
  double r_min = 0.01, r_max = 10.0;
  int max_collisions = 100000;
  double max_relative_se = 0.05;
  int threads = 0;
  std::string output;
  bool table = false;
  std::string json;
  std::vector<double> rmax_scan;
};

constexpr double kDefaultProfilePhotons = 1e6;
constexpr double kDefaultTablePhotons = 400000;

nlohmann::json bins_json(const std::vector<ProfileBin>& bins) {
  nlohmann::json a = nlohmann::json::array();
  for (const ProfileBin& b : bins)
    a.push_back({{"r_lo", b.r_lo},
                 {"r_hi", b.r_hi},
                 {"r", b.r_mid},
                 {"R", b.R},
                 {"R_se", b.R_se},
                 {"rR", b.rR},
                 {"rR_se", b.rR_se}});
  return a;
}

std::string profile_csv(const SemiInfiniteMcResult& r, const std::string& illumination, double exact_A) {
  std::string s = fmt::format(
      "# kozu sss-reference: illumination {}, albedo {:.17g}, mfp {:.17g}, photons {}, seed {}\n"
      "# surface_albedo {:.8g} +- {:.3g} (H-function {:.8g}), truncated {:.3g}, below_r_min {:.6g}, "
      "above_r_max {:.6g}, dmfp {:.8g}\n"
      "r_lo,r_hi,r,R,R_se,rR,rR_se\n",
      illumination, r.settings.albedo, r.settings.mfp, r.settings.photons, r.settings.seed, r.A, r.A_se, exact_A,
      r.truncated, r.below, r.above, r.dmfp);
  for (const ProfileBin& b : r.profile())
    s += fmt::format("{:.8g},{:.8g},{:.8g},{:.8g},{:.4g},{:.8g},{:.4g}\n", b.r_lo, b.r_hi, b.r_mid, b.R, b.R_se, b.rR,
                     b.rR_se);
  return s;
}

int fail(const std::string& message) {
  std::fprintf(stderr, "error: kozu sss-reference: %s\n", message.c_str());
  return 1;
}

// The flags as typed: numbers are read after parsing by the rules of scene keys (kozu render's flags), so that a
// value that is no number ("--albedo x", "--bins 1e99") is exit status 1 naming the flag, as a value out of range
// is, rather than a CLI11 usage error (2).
struct SssFlagTexts {
  std::optional<std::string> albedo, surface_albedo, mfp, photons, seed, bins, r_min, r_max, max_collisions, threads,
      max_relative_se;
  std::vector<std::string> rmax_scan;
};

// Throws InputError("kozu sss-reference", "--flag", ...) for a value that is not a number of its kind.
void read_flag_texts(const SssFlagTexts& t, SssArgs& a) {
  const std::string command = "kozu sss-reference";
  const auto number = [&](const std::optional<std::string>& text, const char* flag, const Range& range = {}) {
    return number_flag_value(*text, command, flag, range);
  };
  const auto integer = [&](const std::optional<std::string>& text, const char* flag, const Range& range) {
    return static_cast<int>(integer_flag_value(*text, command, flag, range));
  };
  constexpr double kMaxInt = 2147483647.0;
  if (t.albedo) a.albedo = number(t.albedo, "--albedo");
  if (t.surface_albedo) a.surface_albedo = number(t.surface_albedo, "--surface-albedo");
  if (t.mfp) a.mfp = number(t.mfp, "--mfp", Range::positive());
  if (t.photons) a.photons = number(t.photons, "--photons");
  if (t.seed) a.seed = uint64_flag_value(*t.seed, command, "--seed");
  if (t.bins) a.bins = integer(t.bins, "--bins", Range::closed(1, 100000));
  if (t.r_min) a.r_min = number(t.r_min, "--rmin");
  if (t.r_max) a.r_max = number(t.r_max, "--rmax");
  if (t.max_collisions) a.max_collisions = integer(t.max_collisions, "--max-collisions", Range::closed(1, kMaxInt));
  if (t.threads) a.threads = integer(t.threads, "--threads", Range::closed(0, kMaxInt));
  if (t.max_relative_se) a.max_relative_se = number(t.max_relative_se, "--max-rel-se", Range::positive());
  for (const std::string& r : t.rmax_scan) a.rmax_scan.push_back(number_flag_value(r, command, "--rmax-scan"));
}

// The fitted errors of every column and of each --rmax-scan radius, on stderr.
void print_table_summary(const nlohmann::json& j, const ProfileTable& table) {
  for (const char* name : {"searchlight", "diffuse", "dmfp"})
    std::fprintf(stderr, "%-11s mean relative error: optimal s %.1f%% (paper %.1f%%), formula %.1f%% (paper %.1f%%)\n",
                 name, 100 * j[name]["optimal_s_error"].get<double>(),
                 100 * j[name]["paper"]["optimal_s_error"].get<double>(), 100 * j[name]["formula_error"].get<double>(),
                 100 * j[name]["paper"]["formula_error"].get<double>());
  for (const ProfileRangeScan& scan : table.scans)
    std::fprintf(stderr,
                 "r <= %-6.4g (%2d bins): searchlight %.1f%% / %.1f%%, diffuse %.1f%% / %.1f%%, dmfp %.1f%% / %.1f%%\n",
                 scan.r_max, scan.bins, 100 * scan.columns[0].optimal_s_error, 100 * scan.columns[0].formula_error,
                 100 * scan.columns[1].optimal_s_error, 100 * scan.columns[1].formula_error,
                 100 * scan.columns[2].optimal_s_error, 100 * scan.columns[2].formula_error);
}

// --table: the fit-error table of every albedo (Christensen & Burley 2015), written to --json.
int run_table(const SssArgs& a, const RadialBins& bins, int threads, tbb::task_arena& arena) {
  if (a.json.empty()) return fail("--table needs --json FILE");
  if (a.albedo || a.surface_albedo || !a.output.empty())
    return fail("--table runs every albedo; drop --albedo, --surface-albedo and -o");
  for (double r : a.rmax_scan)
    if (!(r > a.r_min && r <= a.r_max * (1.0 + 1e-9)) || bins_within(bins, r) < 1)
      return fail(fmt::format("--rmax-scan {} must lie in (rmin, rmax] and keep at least one bin", r));
  check_output(a.json, "--json");  // before the simulation (minutes), not after it
  ProfileTableSettings s;
  s.photons = static_cast<uint64_t>(a.photons.value_or(kDefaultTablePhotons));
  s.seed = a.seed;
  s.bins = bins;
  s.max_relative_se = a.max_relative_se;
  s.max_collisions = a.max_collisions;
  s.rmax_scan = a.rmax_scan;
  std::fprintf(stderr, "kozu sss-reference: table, %llu photons per albedo and illumination, %d threads\n",
               static_cast<unsigned long long>(s.photons), threads);
  ProfileTable table;
  arena.execute([&] {
    table = build_profile_table(s, [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); });
  });
  // A column without one fitted albedo has no mean error (it was written as null and printed as nan%): the photons
  // were too few for the table, which is then not written. A partly fitted column is reported.
  const char* kColumnNames[] = {"searchlight", "diffuse", "dmfp"};
  for (size_t i = 0; i < table.columns.size(); ++i) {
    const ProfileTableColumn& c = table.columns[i];
    const auto rows = static_cast<int>(c.rows.size());
    if (c.albedos_fitted == 0)
      return fail(
          fmt::format("--photons {} is too few to fill the table: no albedo of the {} column has enough "
                      "bins within --max-rel-se to fit (the default, {:g}, fits all {}); nothing written",
                      s.photons, kColumnNames[i], kDefaultTablePhotons, rows));
    if (c.albedos_fitted < rows)
      std::fprintf(stderr, "warning: kozu sss-reference: %s: %d of %d albedos fitted (more --photons fit the rest)\n",
                   kColumnNames[i], c.albedos_fitted, rows);
  }
  for (const ProfileRangeScan& scan : table.scans)
    for (size_t i = 0; i < scan.columns.size(); ++i)
      if (scan.columns[i].albedos_fitted == 0)
        return fail(
            fmt::format("--rmax-scan {:g}: no albedo of the {} column has enough bins to fit (more --photons "
                        "or a larger radius); nothing written",
                        scan.requested, kColumnNames[i]));
  nlohmann::json j = table_to_json(table);
  j["settings"]["threads"] = threads;
  try {
    write_file_atomic(a.json, j.dump(1) + "\n");
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  print_table_summary(j, table);
  std::fprintf(stderr, "%s: wrote the table in %.1f s\n", a.json.c_str(), table.seconds);
  return 0;
}

// One profile R(r) at one albedo, to -o (.csv or .json) or stdout.
int run_profile(const SssArgs& a, const RadialBins& bins, int threads, tbb::task_arena& arena) {
  if (!a.json.empty()) return fail("--json is for --table; use -o FILE.json for one profile");
  if (!a.rmax_scan.empty()) return fail("--rmax-scan is for --table");
  SubsurfaceIllumination illumination;
  if (a.illumination == "searchlight")
    illumination = SubsurfaceIllumination::Searchlight;
  else if (a.illumination == "diffuse")
    illumination = SubsurfaceIllumination::Diffuse;
  else
    return fail(fmt::format("--illumination must be searchlight or diffuse, not '{}'", a.illumination));
  if (a.albedo.has_value() == a.surface_albedo.has_value())
    return fail("give exactly one of --albedo (single-scattering) and --surface-albedo");
  if (a.albedo && !(*a.albedo >= 0.0 && *a.albedo <= 1.0)) return fail("--albedo must lie in [0, 1]");
  if (a.surface_albedo && !(*a.surface_albedo >= 0.0 && *a.surface_albedo <= 1.0))
    return fail("--surface-albedo must lie in [0, 1]");
  std::string format;
  if (!a.output.empty()) {
    format = lower_extension(a.output);
    if (format != ".csv" && format != ".json")
      return fail(fmt::format("{}: output must end in .csv or .json", a.output));
    check_output(a.output, "-o");  // before the simulation, not after it
  }

  SemiInfiniteMcSettings s;
  s.albedo = a.albedo ? *a.albedo : chandrasekhar::single_scattering_albedo(illumination, *a.surface_albedo);
  s.mfp = a.mfp;
  s.illumination = illumination;
  s.photons = static_cast<uint64_t>(a.photons.value_or(kDefaultProfilePhotons));
  s.seed = a.seed;
  s.bins = bins;
  if (illumination == SubsurfaceIllumination::Searchlight && s.albedo < 1.0) s.dmfp_bins = bins;
  s.max_collisions = a.max_collisions;
  const auto start = std::chrono::steady_clock::now();
  SemiInfiniteMcResult r;
  arena.execute([&] { r = simulate_semi_infinite(s); });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double exact_A = chandrasekhar::surface_albedo(illumination, s.albedo);

  std::string text;
  if (format == ".json") {
    nlohmann::json j = {{"illumination", a.illumination},
                        {"albedo", s.albedo},
                        {"mfp", s.mfp},
                        {"photons", s.photons},
                        {"seed", s.seed},
                        {"r_min", bins.r_min},
                        {"r_max", bins.r_max},
                        {"bins", bins.count},
                        {"max_collisions", s.max_collisions},
                        {"surface_albedo", r.A},
                        {"surface_albedo_se", r.A_se},
                        {"h_function_albedo", exact_A},
                        {"truncated", r.truncated},
                        {"below_r_min", r.below},
                        {"above_r_max", r.above},
                        {"mean_collisions", r.mean_collisions},
                        {"dmfp", std::isfinite(r.dmfp) ? nlohmann::json(r.dmfp) : nlohmann::json(nullptr)},
                        {"seconds", seconds},
                        {"threads", threads},
                        {"profile", bins_json(r.profile())}};
    if (r.dmfp_histogram) j["dmfp_profile"] = bins_json(r.dmfp_profile());
    text = j.dump(1) + "\n";
  } else {
    text = profile_csv(r, a.illumination, exact_A);
  }
  if (a.output.empty()) {
    std::fputs(text.c_str(), stdout);
  } else {
    try {
      write_file_atomic(a.output, text);
    } catch (const std::exception& e) {
      return fail(e.what());
    }
  }
  std::fprintf(stderr,
               "kozu sss-reference: %s, albedo %.8g, %llu photons in %.2f s: A = %.5f +- %.5f (H-function %.5f), "
               "truncated %.2g%s%s\n",
               a.illumination.c_str(), s.albedo, static_cast<unsigned long long>(s.photons), seconds, r.A, r.A_se,
               exact_A, r.truncated, a.output.empty() ? "" : ", wrote ", a.output.c_str());
  return 0;
}

int run_sss_reference(const SssArgs& a) {
  // Range checks here rather than in CLI11 validators: one line naming the option, exit code 1.
  if (!(a.r_min > 0.0) || !(a.r_max > a.r_min) || !std::isfinite(a.r_max))
    return fail("--rmin and --rmax need 0 < rmin < rmax");
  if (a.photons && !(*a.photons >= 1.0 && *a.photons <= 1e13)) return fail("--photons must lie in [1, 1e13]");
  // As kozu render: at most 4 x the hardware threads (more crashed inside TBB), said when lowered.
  const int threads =
      std::min(a.threads > 0 ? a.threads : static_cast<int>(tbb::info::default_concurrency()), max_render_threads());
  if (a.threads > threads)
    std::fprintf(stderr, "warning: --threads %d: using %d (4 x the hardware threads)\n", a.threads, threads);
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  tbb::task_arena arena(threads);
  const RadialBins bins{a.r_min, a.r_max, a.bins};

  if (a.table) return run_table(a, bins, threads, arena);
  return run_profile(a, bins, threads, arena);
}

}  // namespace

Command add_sss_reference_command(CLI::App& app) {
  auto args = std::make_shared<SssArgs>();
  auto texts = std::make_shared<SssFlagTexts>();
  CLI::App* cmd = app.add_subcommand(
      "sss-reference",
      "Monte Carlo reflectance profile R(r) of a semi-infinite medium, or (--table) the fit-error table of "
      "Christensen & Burley 2015");
  cmd->add_option("--albedo", texts->albedo, "Single-scattering albedo alpha = sigma_s / sigma_t, in [0, 1]");
  cmd->add_option("--surface-albedo", texts->surface_albedo,
                  "Surface albedo A in [0, 1]; alpha is solved from Chandrasekhar's H-function");
  cmd->add_option("--illumination", args->illumination, "searchlight (along the normal) or diffuse (cosine)")
      ->capture_default_str();
  cmd->add_option("--mfp", texts->mfp,
                  fmt::format("Mean free path 1/sigma_t (the unit of the radii); default {:g}", args->mfp));
  cmd->add_option("--photons", texts->photons,
                  fmt::format("Photons (default {:.0f} for a profile, {:.0f} per albedo and illumination for --table)",
                              kDefaultProfilePhotons, kDefaultTablePhotons));
  cmd->add_option("--seed", texts->seed,
                  fmt::format("Random seed; the result is the same for any thread count; default {}", args->seed));
  cmd->add_option(
      "--bins", texts->bins,
      fmt::format("Log-spaced radial bins between --rmin and --rmax, in [1, 100000]; default {}", args->bins));
  cmd->add_option("--rmin", texts->r_min, fmt::format("Inner edge of the first bin; default {:g}", args->r_min));
  cmd->add_option("--rmax", texts->r_max, fmt::format("Outer edge of the last bin; default {:g}", args->r_max));
  cmd->add_option("--max-collisions", texts->max_collisions,
                  fmt::format("Collisions per photon before it is dropped (its weight is reported as 'truncated'); "
                              "default {}",
                              args->max_collisions));
  cmd->add_option("--threads", texts->threads, "Worker threads (default: all cores)");
  cmd->add_option("-o,--output", args->output, "Profile output: .csv or .json (default: CSV on stdout)");
  cmd->add_flag("--table", args->table,
                "Reproduce the paper's table: fit s for A = 0.01 ... 0.99 (searchlight, diffuse, dmfp)");
  cmd->add_option("--json", args->json, "Table output (JSON) for --table");
  cmd->add_option("--max-rel-se", texts->max_relative_se,
                  fmt::format("--table: fit only bins whose Monte Carlo relative standard error is at most this; "
                              "default {:g}",
                              args->max_relative_se));
  cmd->add_option("--rmax-scan", texts->rmax_scan,
                  "--table: also refit every albedo over the bins inside each of these radii (comma-separated, in "
                  "units of the mfp or dmfp like --rmax; no extra simulation), reported under rmax_scan")
      ->delimiter(',');
  return [cmd, args, texts]() -> int {
    if (!cmd->parsed()) return 2;
    try {
      SssArgs a = *args;
      read_flag_texts(*texts, a);
      // An empty name would mean "no file" (the CSV on stdout, or --table's missing --json): refused as given.
      for (const char* flag : {"--output", "--json"})
        if (cmd->get_option(flag)->count() > 0 && (flag[2] == 'o' ? a.output : a.json).empty())
          throw InputError("kozu sss-reference", flag[2] == 'o' ? "-o" : flag, "an empty file name");
      return run_sss_reference(a);
    } catch (const std::exception& e) {
      return report_failure("sss-reference", e);
    }
  };
}

}  // namespace kozu::app
