#include "tools/nelder_mead.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace kozu {

NelderMeadResult nelder_mead(const std::function<double(const std::vector<double>&)>& f, std::vector<double> x0,
                             const NelderMeadOptions& o) {
  const size_t n = x0.size();
  std::vector<std::vector<double>> s(n + 1, x0);
  for (size_t i = 0; i < n; ++i) s[i + 1][i] += o.initial_step * std::max(1.0, std::abs(x0[i]));
  std::vector<double> v(n + 1);
  int evals = 0;
  const auto eval = [&](const std::vector<double>& x) {
    ++evals;
    const double y = f(x);
    return std::isfinite(y) ? y : 1e300;  // a point outside the function's domain is simply bad
  };
  for (size_t i = 0; i <= n; ++i) v[i] = eval(s[i]);
  std::vector<size_t> order(n + 1);
  const auto point = [&](const std::vector<double>& c, const std::vector<double>& w, double t) {
    std::vector<double> x(n);
    for (size_t k = 0; k < n; ++k) x[k] = c[k] + t * (w[k] - c[k]);
    return x;
  };
  while (evals < o.max_evaluations) {
    std::iota(order.begin(), order.end(), size_t(0));
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return v[a] < v[b]; });
    const size_t best = order[0], worst = order[n], second = order[n - 1];
    if (v[worst] - v[best] < o.tolerance) break;
    std::vector<double> c(n, 0.0);  // centroid of all but the worst
    for (size_t i = 0; i <= n; ++i)
      if (i != worst)
        for (size_t k = 0; k < n; ++k) c[k] += s[i][k] / double(n);
    const std::vector<double> r = point(c, s[worst], -1.0);
    const double vr = eval(r);
    if (vr < v[best]) {
      const std::vector<double> e = point(c, s[worst], -2.0);
      const double ve = eval(e);
      if (ve < vr) {
        s[worst] = e, v[worst] = ve;
      } else {
        s[worst] = r, v[worst] = vr;
      }
      continue;
    }
    if (vr < v[second]) {
      s[worst] = r, v[worst] = vr;
      continue;
    }
    // Contract towards the better of the worst point and its reflection.
    const bool outside = vr < v[worst];
    const std::vector<double> k = point(c, outside ? r : s[worst], 0.5);
    const double vk = eval(k);
    if (vk < (outside ? vr : v[worst])) {
      s[worst] = k, v[worst] = vk;
      continue;
    }
    for (size_t i = 0; i <= n; ++i)  // shrink towards the best
      if (i != best) {
        s[i] = point(s[best], s[i], 0.5);
        v[i] = eval(s[i]);
      }
  }
  const size_t best = static_cast<size_t>(std::min_element(v.begin(), v.end()) - v.begin());
  return {s[best], v[best], evals};
}

}  // namespace kozu
