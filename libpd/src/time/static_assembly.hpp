// Assembly of the static solve's system (time/static_solver.cpp), private to libpd: where each
// degree of freedom's displacement comes from (DofMap), and the reduced stiffness Bᵀ K A on the
// unknowns, assembled particle by particle in 3×3 blocks.
#pragma once

#include "libpd/discretisation/model.hpp"
#include "libpd/time/static_solver.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pd {

/// Where a global dof's displacement comes from.
struct DofMap {
  static constexpr std::ptrdiff_t none = -1;
  /// One term u_g += coefficient · u_dof of a dependent dof (its sources are free or prescribed).
  struct Term {
    std::size_t dof;
    double coefficient;
  };
  std::vector<std::ptrdiff_t> free_index; ///< free unknown, or none
  std::vector<std::vector<Term>> terms;   ///< a dependant's sources (mirror image, extrapolation)
  std::vector<double> prescribed;         ///< value of a fixed/prescribed dof (full load)
  std::vector<std::uint8_t> kind;         ///< 0 free, 1 prescribed, 2 dependant
  std::vector<std::uint8_t> folds_row;    ///< a dependant whose equation folds onto its sources
  std::vector<std::size_t> free_dofs;     ///< global dof of each unknown

  /// Whether every dependant's equation folds onto its sources: then B = V A and the reduced
  /// matrix Aᵀ (V K) A is symmetric exactly when V K is (see bond_asymmetry).
  bool every_dependant_folds() const;
};

/// The model's dofs, its extrapolated particles taking their terms from `extrapolated`
/// (m.extrapolated, or a refit of it: refit_extrapolation).
DofMap map_dofs(const Model& m, const ExtrapolatedParticles& extrapolated);
inline DofMap map_dofs(const Model& m) {
  return map_dofs(m, m.extrapolated);
}

/// A body no support holds (the scene has none) is free to move rigidly: K
/// is singular. These global dofs, held at zero, remove exactly the rigid motions and nothing
/// else: a particle A (every component), the particle B farthest from it (the components across
/// AB) and, in 3D, the particle C farthest from the line AB (the component along the normal of
/// ABC). Under balanced loads they carry no reaction, so the solution is one of the free body's;
/// empty where the model has supports.
std::vector<std::size_t> rigid_motion_pins(const Model& m);

/// Holds `dofs` at zero in `d`: prescribed, no longer unknowns.
void pin_dofs(DofMap& d, const std::vector<std::size_t>& dofs);

/// Which entries of each row the assembly keeps.
enum class RowPart {
  full,       ///< every column
  upper_half, ///< the columns at or right of the diagonal: a symmetric matrix's upper triangle
};

/// The reduced system (static_solver.hpp) of the model's reference state, rows in full or only
/// their upper triangle (for a Cholesky factorisation, which reads one triangle).
StaticSystem assemble_reduced(const Model& m, const DofMap& d, RowPart part);

/// ‖V K − (V K)ᵀ‖_F / ‖V K‖_F over the bonds' off-diagonal blocks V_i k_ij n⊗n: the reduced
/// matrix Aᵀ (V K) A is symmetric to round-off when this is (and every dependant folds). One pass
/// over the bonds, instead of comparing the reduced matrix with its transpose (which has ten
/// times the entries once ghosts fold their sources together).
double bond_asymmetry(const Model& m);

} // namespace pd
