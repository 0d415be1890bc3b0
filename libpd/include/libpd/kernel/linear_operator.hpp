// The linearised bond operator K at the reference configuration (Miranda eq. 30 with
// C = c ξ⊗ξ/|ξ|³): bond ij, with stiffness k_ij = c_ij V_j/|ξ_ij| and unit vector n = ξ/|ξ|,
// contributes the 3×3 blocks K_ii += k_ij n⊗n and K_ij = −k_ij n⊗n. The bonds are walked here
// once, for the product K u of the spectral estimates (kernel/spectrum.hpp) and for the
// Gershgorin row sums of ADR's fictitious density (time/adr.cpp).
//
// Mirror supports under `model.mirror_coupling: consistent` make the operator Rᵀ K R
// (discretisation/mirror_constraints.hpp): the transpose Rᵀ on force densities and on bounds, the
// massless dependants, the constrained product and the force evaluator that folds the kernel's
// forces are here; the product uses the one bond loop above.
#pragma once

#include "libpd/discretisation/model.hpp"
#include "libpd/kernel/force_kernel.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

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

/// consistent_mirror_coupling for a built model.
bool consistent_mirror_coupling(const Model& model);

/// Whether the model has dependants whose forces are folded back onto their sources: mirror
/// supports under consistent coupling, ghosts and extrapolated clamps (ghost_layers.hpp).
bool folds_dependants(const Model& model);

/// Per particle: 1 for the particles that carry no mass and are not integrated: the mirror
/// dependants under consistent coupling (none under `copy`) and the extrapolated particles.
std::vector<std::uint8_t> massless_dependants(const Model& model);

/// Per particle: the 1-norm of its row of the constraint map u = A u_f (Σ_k |a_k| for an
/// extrapolated particle, 1 otherwise). A bond's share of a Gershgorin bound of Aᵀ K A is its
/// stiffness times the sum of its two ends' norms, before the rows are folded.
std::vector<double> constraint_row_norms(const Model& model);

/// v_source += a · v_dependant · V_dependant / V_source for every mirror constraint (a = σ) and
/// every extrapolated particle's term: the transpose of the constraints applied to a force
/// density (3N). The dependants' entries are left as they are (they are reactions, never
/// integrated). Mirror constraints fold only under consistent coupling.
void fold_mirror_forces(const Model& model, double* force_density);

/// The same with |a|, for non-negative per-dof bounds such as Gershgorin row sums (3N).
void fold_mirror_bounds(const Model& model, double* bound);

/// Sets every extrapolated particle's entries of a 3N displacement-like vector (displacements or
/// velocities, relative to the reference configuration) from its sources: v_d = Σ a v_s.
void set_extrapolated(const Model& model, double* v);

/// The linearised constrained operator: sets the mirror dependants' entries of u to R u (in place,
/// as apply_constraints does), applies K (apply_linearised_operator), then folds the dependants'
/// rows onto their masters (fold_mirror_forces): Rᵀ K R under consistent coupling, symmetric in
/// the free degrees of freedom (weighted by volume); K_ff + K_fs R under `copy`.
void apply_constrained_operator(const Model& m, double* u, double* ku);

/// make_force_evaluator whose compute() then folds the dependants' forces onto their sources
/// (fold_mirror_forces): the plain evaluator unless folds_dependants. The bond
/// weights are already in the model's bond field (build_model), so strain_energy() is W_c
/// (discretisation/mirror_constraints.hpp).
std::unique_ptr<ForceEvaluator> make_constrained_force_evaluator(Model& model);

/// The force of small displacements: b = −K (y − X) with the dependants' forces folded as
/// make_constrained_force_evaluator folds them, and the energy ½ uᵀ V K u. K is the kernel's
/// linearisation at the reference configuration (the same for every stretch measure), so this is
/// the linear-elastic problem a finite-element reference solves, with no rotation stiffening
/// (`solver.small_displacements`). Elastic bond-based models only: the caller refuses damage,
/// plasticity and virtual fibres.
std::unique_ptr<ForceEvaluator> make_linearised_force_evaluator(Model& model);

} // namespace pd
