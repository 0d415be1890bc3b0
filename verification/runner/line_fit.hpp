// An ordinary least-squares line y = slope·x + intercept and its coefficient of determination
// R² = 1 − Σ(y − ŷ)² / Σ(y − ȳ)², for the Griffith case's σ_failure/σ_yield against √(δ/c)
// (Olsson et al. eq. 117, Fig. 14).
#pragma once

#include <cstddef>
#include <limits>
#include <stdexcept>
#include <vector>

namespace pd::verification {

struct LineFit {
  double slope = 0;
  double intercept = 0;
  double r_squared = 0; ///< NaN when the y values are all equal (nothing to explain)
};

/// The fit through (x[k], y[k]); throws std::invalid_argument for fewer than two points, sizes
/// that differ, or x values that are all equal.
inline LineFit fit_line(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size() || x.size() < 2) {
    throw std::invalid_argument("fit_line: needs two or more (x, y) pairs");
  }
  const double n = static_cast<double>(x.size());
  double mx = 0, my = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    mx += x[k] / n;
    my += y[k] / n;
  }
  double sxx = 0, sxy = 0, syy = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sxx += (x[k] - mx) * (x[k] - mx);
    sxy += (x[k] - mx) * (y[k] - my);
    syy += (y[k] - my) * (y[k] - my);
  }
  if (!(sxx > 0)) {
    throw std::invalid_argument("fit_line: the x values are all equal");
  }
  LineFit f;
  f.slope = sxy / sxx;
  f.intercept = my - f.slope * mx;
  double residual = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double r = y[k] - (f.slope * x[k] + f.intercept);
    residual += r * r;
  }
  f.r_squared = syy > 0 ? 1.0 - residual / syy : std::numeric_limits<double>::quiet_NaN();
  return f;
}

} // namespace pd::verification
