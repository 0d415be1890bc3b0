#include "libpd/kernel/round_off.hpp"

#include "libpd/kernel/linear_operator.hpp"

#include <cmath>
#include <limits>

namespace pd {

namespace {

/// Variance of a coordinate rounded to the nearest double: uniform over one ulp.
double rounding_variance(double y) {
  const double a = std::abs(y);
  const double ulp = std::nextafter(a, std::numeric_limits<double>::infinity()) - a;
  return ulp * ulp / 12.0;
}

} // namespace

double residual_round_off_floor(const Model& model, const double* y,
                                const std::vector<std::uint8_t>& held) {
  constexpr double u = std::numeric_limits<double>::epsilon() / 2; // unit round-off
  const std::size_t n = model.size();
  std::vector<double> variance(3 * n);
  for (std::size_t d = 0; d < 3 * n; ++d) {
    variance[d] = rounding_variance(y[d]);
  }
  // Standard deviation of each force density component, before the dependants fold.
  std::vector<double> deviation(3 * n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    double own[3][3] = {}; // K_ii
    double var[3] = {0, 0, 0};
    for_each_linearised_bond(model, i, BrokenBonds::left_out, [&](const LinearisedBond& b) {
      const double* n_ij = b.direction.data();
      double spread = 0; // Σ_c n_c² σ_jc²
      for (std::size_t c = 0; c < 3; ++c) {
        spread += n_ij[c] * n_ij[c] * variance[3 * b.neighbour + c];
      }
      const double length = 1.0 / model.family.inverse_length[b.index];
      const double arithmetic = b.stiffness * length * u;
      for (std::size_t a = 0; a < 3; ++a) {
        var[a] += b.stiffness * b.stiffness * n_ij[a] * n_ij[a] * spread +
                  arithmetic * arithmetic * n_ij[a] * n_ij[a];
        for (std::size_t c = 0; c < 3; ++c) {
          own[a][c] += b.stiffness * n_ij[a] * n_ij[c];
        }
      }
    });
    for (std::size_t a = 0; a < 3; ++a) {
      for (std::size_t c = 0; c < 3; ++c) {
        var[a] += own[a][c] * own[a][c] * variance[3 * i + c];
      }
      deviation[3 * i + a] = std::sqrt(var[a]);
    }
  }
  fold_mirror_bounds(model, deviation.data());
  ExactSum sum;
  for (std::size_t d = 0; d < 3 * n; ++d) {
    if (!held[d] && model.ownership.owns(d / 3)) {
      const double v = model.particles.volume[d / 3] * deviation[d];
      sum.add(v * v);
    }
  }
  return std::sqrt(model.ownership.communicator().sum(sum));
}

} // namespace pd
