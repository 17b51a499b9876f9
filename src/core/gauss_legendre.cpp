#include "core/gauss_legendre.h"

#include <cmath>
#include <numbers>

namespace kozu {

void gauss_legendre_unit(int n, std::vector<double>* nodes, std::vector<double>* weights) {
  nodes->assign(n, 0.0);
  weights->assign(n, 0.0);
  // Roots of P_n on [−1, 1] by Newton from Tricomi's initial guesses, then mapped to [0, 1].
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double x = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
    double dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = x;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (x * p1 - p0) / (x * x - 1.0);
      const double dx = p1 / dp;
      x -= dx;
      if (std::abs(dx) < 1e-16) break;
    }
    const double w = 2.0 / ((1.0 - x * x) * dp * dp);
    (*nodes)[i] = 0.5 * (1.0 - x);
    (*nodes)[n - 1 - i] = 0.5 * (1.0 + x);
    (*weights)[i] = (*weights)[n - 1 - i] = 0.5 * w;
  }
}

GaussLegendre::GaussLegendre(int n) {
  gauss_legendre_unit(n, &x, &w);
  for (size_t i = 0; i < x.size(); ++i) {
    x[i] = 2.0 * x[i] - 1.0;
    w[i] *= 2.0;
  }
}

}  // namespace kozu
