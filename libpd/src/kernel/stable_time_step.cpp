#include "libpd/kernel/stable_time_step.hpp"

#include "libpd/kernel/linear_operator.hpp"

#include <algorithm>
#include <cmath>

namespace pd {

std::vector<double> stable_time_step_per_particle(const Model& m) {
  const std::size_t n = m.size();
  std::vector<double> sums(3 * n, 0.0); // per dof, for fold_mirror_bounds
  // An extrapolated neighbour moves with all its sources (constraint_row_norms); 1 otherwise.
  const auto reach = constraint_row_norms(m);
  for (std::size_t i = 0; i < n; ++i) {
    // Σ_p V_p |C_ip| with |C| = c/|ξ|; bond_stiffness already carries c·V_p·corrections.
    double sum = 0;
    for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
      sum += bond_stiffness(m, k) * m.family.inverse_length[k] * 0.5 *
             (reach[i] + reach[m.family.neighbour[k]]);
    }
    sums[3 * i] = sums[3 * i + 1] = sums[3 * i + 2] = sum;
  }
  // A source also carries its dependants' bonds (Aᵀ K A); dependants are not integrated.
  fold_mirror_bounds(m, sums.data());
  const auto dependent = massless_dependants(m);
  std::vector<double> dt(n, no_limit);
  for (std::size_t i = 0; i < n; ++i) {
    const double sum = std::max({sums[3 * i], sums[3 * i + 1], sums[3 * i + 2]});
    if (sum > 0 && !dependent[i]) {
      dt[i] = std::sqrt(2.0 * m.density[i] / sum); // eq. 31
    }
  }
  return dt;
}

double stable_time_step(const Model& m) {
  const auto dt = stable_time_step_per_particle(m);
  return dt.empty() ? no_limit : *std::min_element(dt.begin(), dt.end());
}

} // namespace pd
