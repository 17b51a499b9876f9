// The n-point Gauss–Legendre rule (exact for polynomials of degree 2n − 1), for tables built at run time (sheen.h),
// the offline tools and the tests' reference integrals.
#pragma once

#include <vector>

namespace kozu {

// Nodes and weights on [0, 1].
void gauss_legendre_unit(int n, std::vector<double>* nodes, std::vector<double>* weights);

// Nodes x and weights w on [−1, 1].
struct GaussLegendre {
  std::vector<double> x, w;
  explicit GaussLegendre(int n);
};

}  // namespace kozu
