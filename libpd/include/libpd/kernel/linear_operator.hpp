// The linearised bond operator K at the reference configuration (Miranda eq. 30 with
// C = c ξ⊗ξ/|ξ|³): bond ij, with stiffness k_ij = c_ij V_j/|ξ_ij| and unit vector n = ξ/|ξ|,
// contributes the 3×3 blocks K_ii += k_ij n⊗n and K_ij = −k_ij n⊗n. The bonds are walked here
// once, for the product K u of the spectral estimates (kernel/spectrum.hpp) and for the
// Gershgorin row sums of ADR's fictitious density (time/adr.cpp).
#pragma once

#include "libpd/discretisation/model.hpp"

#include <array>
#include <cstddef>

namespace pd {

/// One directed bond i→j of the linearised operator.
struct LinearisedBond {
  std::size_t index = 0;             ///< k, the directed bond in CSR order
  std::size_t neighbour = 0;         ///< j
  double stiffness = 0;              ///< k_ij = c_ij V_j / |ξ_ij|
  std::array<double, 3> direction{}; ///< n = ξ_ij / |ξ_ij|
};

/// Whether a walk over the operator's bonds leaves out the bonds that damage has broken.
enum class BrokenBonds { included, left_out };

/// Visit every bond of particle i's row in CSR order (the order every sum over it keeps).
template <class Visit>
void for_each_linearised_bond(const Model& m, std::size_t i, BrokenBonds broken, Visit&& visit) {
  const bool skip_broken = broken == BrokenBonds::left_out && !m.state.broken.empty();
  for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
    if (skip_broken && m.state.broken[k]) {
      continue;
    }
    LinearisedBond b;
    b.index = k;
    b.neighbour = m.family.neighbour[k];
    const double inv = m.family.inverse_length[k];
    b.stiffness = bond_stiffness(m, k) * inv;
    for (std::size_t c = 0; c < 3; ++c) {
      b.direction[c] = (m.particles.position[b.neighbour][c] - m.particles.position[i][c]) * inv;
    }
    visit(b);
  }
}

/// out = K u per unit volume, (K u)_i = Σ_j k_ij n (n·(u_i − u_j)), broken bonds left out;
/// u and out hold 3N values.
void apply_linearised_operator(const Model& m, const double* u, double* out);

} // namespace pd
