#include "libpd/discretisation/mirror_constraints.hpp"

#include <algorithm>

namespace pd {

bool has_mirror_constraints(const std::vector<Constraint>& constraints) {
  return std::any_of(constraints.begin(), constraints.end(),
                     [](const Constraint& c) { return c.mirror_of != Constraint::no_mirror; });
}

bool consistent_mirror_coupling(MirrorCoupling coupling,
                                const std::vector<Constraint>& constraints) {
  return coupling == MirrorCoupling::consistent && has_mirror_constraints(constraints);
}

std::vector<std::uint8_t> mirror_dependent_particles(std::size_t particles,
                                                     const std::vector<Constraint>& constraints) {
  std::vector<std::uint8_t> dependent(particles, 0);
  for (const Constraint& c : constraints) {
    if (c.mirror_of != Constraint::no_mirror) {
      dependent[c.particle] = 1;
    }
  }
  return dependent;
}

std::vector<std::uint8_t> energy_dependants(std::size_t particles, MirrorCoupling coupling,
                                            const std::vector<Constraint>& constraints,
                                            const ExtrapolatedParticles& extrapolated) {
  std::vector<std::uint8_t> dependent = consistent_mirror_coupling(coupling, constraints)
                                            ? mirror_dependent_particles(particles, constraints)
                                            : std::vector<std::uint8_t>(particles, 0);
  for (const std::uint32_t d : extrapolated.particle) {
    dependent[d] = 1;
  }
  return dependent;
}

std::vector<double> mirror_bond_weights(const BondFamily& family,
                                        const std::vector<std::uint8_t>& dependent) {
  std::vector<double> weight(family.directed_bond_count(), 1.0);
  const std::size_t n = family.offsets.empty() ? 0 : family.offsets.size() - 1;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      const std::size_t j = family.neighbour[k];
      weight[k] = 0.5 * ((dependent[i] ? 0.0 : 1.0) + (dependent[j] ? 0.0 : 1.0));
    }
  }
  return weight;
}

} // namespace pd
