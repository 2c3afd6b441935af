#pragma once
/// Least-squares fits of measured curves, small enough to need no library: y = a + b·x for a
/// basis function x(N), with the coefficient of determination R².
#include <cmath>
#include <functional>
#include <vector>

namespace raylab::experiments {

struct LinearFit {
  double a = 0, b = 0, r2 = 0;
};

/// Fits y ≈ a + b·basis(n) over the points (n_i, y_i).
inline LinearFit fit_linear(const std::vector<double>& n, const std::vector<double>& y,
                            const std::function<double(double)>& basis) {
  const std::size_t k = n.size();
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < k; ++i) {
    const double x = basis(n[i]);
    sx += x; sy += y[i]; sxx += x * x; sxy += x * y[i];
  }
  LinearFit f;
  const double det = k * sxx - sx * sx;
  if (k < 2 || det == 0) return f;
  f.b = (k * sxy - sx * sy) / det;
  f.a = (sy - f.b * sx) / k;
  double ss_res = 0, ss_tot = 0;
  const double mean = sy / k;
  for (std::size_t i = 0; i < k; ++i) {
    const double e = y[i] - (f.a + f.b * basis(n[i]));
    ss_res += e * e;
    ss_tot += (y[i] - mean) * (y[i] - mean);
  }
  f.r2 = ss_tot > 0 ? 1 - ss_res / ss_tot : 1;
  return f;
}

/// The exponent α of y ≈ c·N^α (a straight-line fit in log-log space).
inline LinearFit fit_power(const std::vector<double>& n, const std::vector<double>& y) {
  std::vector<double> ly(y.size());
  for (std::size_t i = 0; i < y.size(); ++i) ly[i] = std::log(y[i]);
  return fit_linear(n, ly, [](double x) { return std::log(x); });
}

}  // namespace raylab::experiments
