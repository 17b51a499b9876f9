// `kozu fit-rational DATA.csv --num N|--num-terms LIST --den M|--den-terms LIST [--constraint X=Y ...]
// [--2d-symmetric] [--clamp LO,HI] [--minimax] [--no-refine] --json OUT.json`:
// fits a rational function P/Q (Q's constant term 1) to a table by least squares, with equality constraints met
// exactly (src/tools/rational_fit.h; D. Chan, "Material Advances in Call of Duty: WWII", SIGGRAPH 2018 course
// Advances in Real-Time Rendering in Games, §3, eqs. (39)–(42), (35)–(37)), and writes
// {"numerator": [...], "denominator": [...], "max_abs_error": e, "mean_abs_error": m, ...}, coefficients lowest
// power first (the term order is written beside them). A table with the header `x,y,value` is fitted in two
// variables: all monomials x^i y^j of total degree up to N (M), or with --2d-symmetric the symmetric pairs
// x^i y^j + x^j y^i of eqs. (35)–(36). A constraint is `X=Y` in one variable and `X,Y=V` in two. --clamp fits
// clamp(P/Q, LO, HI) as eq. (37) uses it; --minimax minimises the largest error instead of the sum of squares.
// Exit codes: 0 success, 1 a bad value, table or fit, or an output that cannot be written (checked before the fit),
// 2 a usage error.
#include "apps/command_errors.h"
#include "apps/commands.h"
#include "core/error.h"
#include "core/file_io.h"
#include "core/json_reader.h"
#include "render/output_paths.h"
#include "tools/rational_fit.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

namespace kozu::app {

namespace {

const std::string kCommand = "kozu fit-rational";

// "X=Y" (one variable) or "X,Y=V" (two): each a number by the rule of every flag.
RationalSample parse_constraint(const std::string& text, bool two_d) {
  const auto bad = [&](const std::string& why) {
    return InputError(kCommand, "--constraint",
                      fmt::format("{} ('{}'; expected {})", why, text_excerpt(text), two_d ? "X,Y=V" : "X=Y"));
  };
  const size_t eq = text.find('=');
  if (eq == std::string::npos || text.find('=', eq + 1) != std::string::npos) throw bad("one '=' is needed");
  const std::string lhs = text.substr(0, eq), rhs = text.substr(eq + 1);
  const size_t comma = lhs.find(',');
  if (two_d != (comma != std::string::npos))
    throw bad(two_d ? "a two-variable table needs both coordinates" : "a one-variable table takes one coordinate");
  RationalSample s;
  const Range bound = Range::closed(-1e12, 1e12);
  s.x = number_flag_value(two_d ? lhs.substr(0, comma) : lhs, kCommand, "--constraint", bound);
  if (two_d) s.y = number_flag_value(lhs.substr(comma + 1), kCommand, "--constraint", bound);
  s.value = number_flag_value(rhs, kCommand, "--constraint", bound);
  return s;
}

std::string basis_description(RationalBasis b) {
  switch (b) {
    case RationalBasis::OneD:
      return "powers of x, lowest first";
    case RationalBasis::TwoD:
      return "monomials x^i*y^j by total degree d = i + j, lowest first; within a degree x^d first, y^d last";
    case RationalBasis::TwoDSymmetric:
      return "symmetric pairs x^i*y^j + x^j*y^i (x^i*y^i once when i = j) by total degree d = i + j, lowest first; "
             "within a degree i = d first";
  }
  return {};
}

struct Flags {
  std::string data, num, den, num_terms, den_terms, clamp, output;
  std::vector<std::string> constraints;
  bool symmetric = false, no_refine = false, minimax = false;
};

int run_fit_rational(const Flags& f) {
  const std::string& data = f.data;
  const std::string& output = f.output;
  const bool symmetric = f.symmetric, no_refine = f.no_refine;
  const std::string& num_text = f.num;
  const std::string& den_text = f.den;
  const auto num =
      num_text.empty() ? 0 : static_cast<int>(integer_flag_value(num_text, kCommand, "--num", Range::closed(0, 20)));
  const auto den =
      den_text.empty() ? 0 : static_cast<int>(integer_flag_value(den_text, kCommand, "--den", Range::closed(0, 20)));
  double clamp_lo = 0, clamp_hi = 1;
  if (!f.clamp.empty()) {
    const size_t comma = f.clamp.find(',');
    if (comma == std::string::npos)
      throw InputError(kCommand, "--clamp", fmt::format("expected LO,HI, got '{}'", text_excerpt(f.clamp)));
    clamp_lo = number_flag_value(f.clamp.substr(0, comma), kCommand, "--clamp", Range::closed(-1e12, 1e12));
    clamp_hi = number_flag_value(f.clamp.substr(comma + 1), kCommand, "--clamp", Range::closed(-1e12, 1e12));
    if (!(clamp_lo < clamp_hi))
      throw InputError(kCommand, "--clamp", fmt::format("expected LO < HI, got '{}'", text_excerpt(f.clamp)));
  }
  if (f.minimax && no_refine)
    throw InputError(kCommand, "--minimax", "needs the refinement (it iterates on it): drop --no-refine");
  // The output is checked before the table is read and fitted; the table is its input.
  check_output(output, "--json", {std::filesystem::path(data)});
  bool two_d = false;
  const std::vector<RationalSample> samples = read_rational_csv(data, &two_d);
  if (symmetric && !two_d)
    throw InputError(kCommand, "--2d-symmetric", fmt::format("{} has one variable (header 'x,value')", data));
  RationalFitOptions o;
  o.basis = !two_d ? RationalBasis::OneD : symmetric ? RationalBasis::TwoDSymmetric : RationalBasis::TwoD;
  if (two_d && (num > kMaxRationalDegree2D || den > kMaxRationalDegree2D))
    throw InputError(kCommand, num > kMaxRationalDegree2D ? "--num" : "--den",
                     fmt::format("expected a degree in [0, {}] for two variables, got {}", kMaxRationalDegree2D,
                                 std::max(num, den)));
  o.num_degree = num;
  o.den_degree = den;
  for (const auto& [text, terms, name] :
       {std::tuple{&f.num_terms, &o.num_terms, "--num-terms"}, std::tuple{&f.den_terms, &o.den_terms, "--den-terms"}}) {
    if (text->empty()) continue;
    try {
      *terms = parse_rational_terms(*text, o.basis);
      if (terms == &o.den_terms && std::find(terms->begin(), terms->end(), std::pair{0, 0}) == terms->end())
        throw std::invalid_argument("1 must be among the terms (Q's constant term, fixed to 1)");
    } catch (const std::invalid_argument& e) {
      throw InputError(kCommand, name, e.what());
    }
  }
  o.refine = !no_refine;
  o.clamp = !f.clamp.empty();
  o.clamp_lo = clamp_lo;
  o.clamp_hi = clamp_hi;
  o.minimax = f.minimax;
  for (const std::string& t : f.constraints) o.constraints.push_back(parse_constraint(t, two_d));
  RationalFit fit;
  try {
    fit = fit_rational(samples, o);
  } catch (const std::invalid_argument& e) {
    throw InputError(data, "", e.what());
  }

  nlohmann::json j;
  j["numerator"] = fit.numerator;
  j["denominator"] = fit.denominator;
  j["max_abs_error"] = fit.max_abs_error;
  j["mean_abs_error"] = fit.mean_abs_error;
  j["rms_error"] = fit.rms_error;
  j["samples"] = samples.size();
  j["variables"] = two_d ? nlohmann::json{"x", "y"} : nlohmann::json{"x"};
  j["terms"] = o.num_terms.empty() && o.den_terms.empty()
                   ? basis_description(o.basis)
                   : "as given by --num-terms / --den-terms (" + basis_description(o.basis) + ")";
  for (const auto& [key, degree] :
       {std::pair{"numerator_terms", &fit.numerator_terms}, std::pair{"denominator_terms", &fit.denominator_terms}}) {
    std::vector<std::string> names;
    for (const auto& [a, b] : *degree) names.push_back(rational_term_name(o.basis, a, b));
    j[key] = names;
  }
  nlohmann::json cs = nlohmann::json::array();
  for (const RationalSample& c : o.constraints) {
    const double v = fit(c.x, c.y);
    nlohmann::json e = {{"x", c.x}, {"value", c.value}, {"fitted", v}};
    if (two_d) e["y"] = c.y;
    cs.push_back(e);
  }
  j["constraints"] = cs;
  j["method"] = no_refine ? "linearised least squares (Chan 2018 eq. 39), constraints by null space (eq. 41)"
                          : "linearised least squares (Chan 2018 eq. 39), then Levenberg-Marquardt on P/Q - value; "
                            "constraints by null space (eq. 41)";
  j["objective"] = f.minimax ? "minimax (Lawson's iteration)" : "least squares";
  if (o.clamp) j["clamp"] = {clamp_lo, clamp_hi};
  j["linearised_max_abs_error"] = fit.linear_max_abs_error;
  j["refinement_steps"] = fit.iterations;
  write_file_atomic(output, j.dump(1) + "\n");
  std::fprintf(stderr, "%s: %zu samples, %zu + %zu coefficients; max |error| %.3g, mean %.3g\n", output.c_str(),
               samples.size(), fit.numerator.size(), fit.denominator.size() - 1, fit.max_abs_error, fit.mean_abs_error);
  return 0;
}

}  // namespace

Command add_fit_rational_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "fit-rational", "Fit a rational function P/Q with constraints to a table (Chan 2018 §3) and write it as JSON");
  // Values are read as text and checked after parsing, as fit-ltc does: a bad value is exit status 1.
  auto f = std::make_shared<Flags>();
  cmd->add_option("data", f->data, "Input table: CSV with the header 'x,value' or 'x,y,value'")->required();
  cmd->add_option("--num", f->num, "Degree of the numerator P, in [0, 20] ([0, 10] in two variables)");
  cmd->add_option("--den", f->den, "Degree of the denominator Q (constant term 1), in [0, 20] ([0, 10] in two)");
  cmd->add_option("--num-terms", f->num_terms, "The numerator's terms instead of a degree: e.g. 1,x,y,x^2,x*y,y^3");
  cmd->add_option("--den-terms", f->den_terms, "The denominator's terms instead of a degree; 1 among them");
  cmd->add_option("--constraint", f->constraints, "f(X) = Y met exactly: X=Y, or X,Y=V in two variables (repeatable)")
      ->allow_extra_args(false);
  cmd->add_flag("--2d-symmetric", f->symmetric, "Two variables, symmetric terms x^i*y^j + x^j*y^i (eqs. 35-36)");
  cmd->add_option("--clamp", f->clamp, "Fit clamp(P/Q, LO, HI), as eq. 37 uses its fit: LO,HI");
  cmd->add_flag("--minimax", f->minimax, "Minimise the largest error instead of the sum of squares");
  cmd->add_flag("--no-refine", f->no_refine, "Only the linearised least squares (eq. 39), no Levenberg-Marquardt");
  cmd->add_option("--json", f->output, "Output: the coefficients and errors as JSON")->required();
  return [cmd, f]() -> int {
    if (!cmd->parsed()) return 2;
    // Each polynomial by its degree or by its terms, one of the two: a usage error otherwise, like a missing option.
    for (const auto& [degree, terms, name] :
         {std::tuple{&f->num, &f->num_terms, "--num"}, std::tuple{&f->den, &f->den_terms, "--den"}}) {
      if (degree->empty() == terms->empty()) {
        std::fprintf(stderr, "error: %s: %s (%s --help)\n", kCommand.c_str(),
                     fmt::format(fmt::runtime(degree->empty() ? "{0} or {0}-terms is required"
                                                              : "{0} and {0}-terms exclude each other"),
                                 name)
                         .c_str(),
                     kCommand.c_str());
        return 2;
      }
    }
    try {
      return run_fit_rational(*f);
    } catch (const std::exception& e) {
      return report_failure("fit-rational", e);
    }
  };
}

}  // namespace kozu::app
