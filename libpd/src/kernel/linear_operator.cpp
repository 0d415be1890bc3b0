#include "libpd/kernel/linear_operator.hpp"

#include "libpd/kernel/force_kernel.hpp"

namespace pd {

void apply_linearised_operator(const Model& m, const double* u, double* out) {
  const auto n = static_cast<std::ptrdiff_t>(m.size());
#pragma omp parallel for schedule(static) if (m.size() >= parallel_min_particles)
  for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    double acc[3] = {0, 0, 0};
    for_each_linearised_bond(m, i, BrokenBonds::left_out, [&](const LinearisedBond& b) {
      const std::size_t j = b.neighbour;
      double proj = 0;
      for (std::size_t c = 0; c < 3; ++c) {
        proj += b.direction[c] * (u[3 * i + c] - u[3 * j + c]);
      }
      for (std::size_t c = 0; c < 3; ++c) {
        acc[c] += b.stiffness * proj * b.direction[c];
      }
    });
    for (std::size_t c = 0; c < 3; ++c) {
      out[3 * i + c] = acc[c];
    }
  }
}

} // namespace pd
