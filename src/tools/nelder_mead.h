// Nelder–Mead downhill simplex minimisation of a function of a few variables, without derivatives (for the LTC
// fits, tools/ltc_fit.h, whose error is a sampled integral with kinks).
//
// Citation: Nelder & Mead 1965, "A simplex method for function minimization"; the standard coefficients
// (reflection 1, expansion 2, contraction 1/2, shrink 1/2) and the order of the steps as in Lagarias, Reeds,
// Wright, Wright 1998, "Convergence properties of the Nelder–Mead simplex method in low dimensions", §2.
#pragma once

#include <functional>
#include <vector>

namespace kozu {

struct NelderMeadOptions {
  double initial_step = 0.05;  // the first simplex: x0 and x0 + step along each axis (relative where |x| > 1)
  double tolerance = 1e-7;     // stop when the simplex's values differ by less than this (absolute)
  int max_evaluations = 2000;
};

struct NelderMeadResult {
  std::vector<double> x;
  double value = 0;
  int evaluations = 0;
};

NelderMeadResult nelder_mead(const std::function<double(const std::vector<double>&)>& f, std::vector<double> x0,
                             const NelderMeadOptions& options = {});

}  // namespace kozu
