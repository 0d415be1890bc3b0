// Variationally consistent mirror supports (issue 14, item 1).
//
// A mirror support ties each of its particles s to the image j of s across the clamped face,
// u_s = σ u_j (σ = ±1 per component, SupportSpec::mirror): a linear constraint u_dep = R u_free.
// Setting u_s from u_j and letting j feel only its own bonds gives the operator K_ff + K_fs R,
// which is not symmetric for σ = −1 (the bond directions reflect with the plane, the
// displacements with −I), and its complex eigenvalues grow under an undamped or lightly damped
// integrator.
//
// The consistent form derives the forces from one energy of the free displacements,
//   W_c(u_f) = Σ_{free–free bonds} w + ½ Σ_{free–support bonds} w,   u_s = R u_f,
// so that b_f = −∂W_c/∂u_f = (direct force on f) + Rᵀ (force on its dependants) and the
// linearised operator is Rᵀ K_w R with K_w the stiffness of the weighted bonds: symmetric.
// The weights are the ones that make W_c exact for a support that is a true reflection of the
// body (for an even field a free–support bond and its image carry the same energy, and the image
// of the doubled body counts each once); bonds between two support particles belong to the
// image body and carry no weight. In uniform strain u = ε x (which the odd reflection
// reproduces) the forces are those of the unweighted model, so the mirror clamp still holds the
// displacement to zero at the face.
//
// Support particles carry no mass: the body's kinetic energy is that of the free particles, and
// E = T_free + W_c is conserved by an undamped integrator.
//
// All of this applies with ModelSpec::mirror_coupling = consistent. With `copy` (the default until
// issue 14's default surface treatment lands) the weights are 1, nothing is folded and the
// support particles keep their mass: the one-sided clamp the structural scenes were tuned on.
//
// Where the pieces live: this header holds what build_model needs (model.hpp includes it, so it
// sees constraints, not the Model). The pieces that act on a built Model — the transpose Rᵀ on
// force densities and bounds, the massless particles, the constrained operator Rᵀ K R and the
// folding force evaluator — are in the kernel layer (kernel/linear_operator.hpp,
// kernel/force_kernel.hpp).
#pragma once

#include "libpd/core/names.hpp"
#include "libpd/discretisation/bond_family.hpp"
#include "libpd/discretisation/constraint.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pd {

/// How a mirror support's particles are coupled to their images. `copy`: the support particles
/// take their images' displacements and keep their forces (operator K_ff + K_fs R, not symmetric
/// for a clamp, can grow). `consistent`: forces from one energy of the free particles, support
/// forces sent back to the images (Rᵀ K_w R, symmetric, energy-conserving).
enum class MirrorCoupling { copy, consistent, quadratic };

template <>
struct EnumName<MirrorCoupling> {
  static constexpr NameTable<MirrorCoupling, 3> table{{
      {"copy", MirrorCoupling::copy,
       "support particles copy their images' displacements and keep their forces (one-sided)"},
      {"consistent", MirrorCoupling::consistent,
       "support forces sent back to the images: symmetric, energy-conserving"},
      {"quadratic", MirrorCoupling::quadratic,
       "support particles extrapolated from the body by quadratics that vanish on the face "
       "(ghost_layers.hpp): symmetric, exact for every quadratic field the clamp allows"},
  }};
};

/// True if any constraint is a mirror constraint.
bool has_mirror_constraints(const std::vector<Constraint>& constraints);

/// True if there are mirror constraints and they are coupled consistently (W_c, Rᵀ K_w R): only
/// then are bonds weighted, forces and bounds folded and the dependants massless.
bool consistent_mirror_coupling(MirrorCoupling coupling,
                                const std::vector<Constraint>& constraints);

/// Per particle: 1 if any of its components is tied to another particle by a mirror constraint.
std::vector<std::uint8_t> mirror_dependent_particles(std::size_t particles,
                                                     const std::vector<Constraint>& constraints);

/// Per particle: 1 for the dependants of W_c (forces folded onto their sources, no mass, weight 0
/// on bonds among themselves): the mirror dependants under consistent coupling and every
/// extrapolated particle (ghost_layers.hpp).
std::vector<std::uint8_t> energy_dependants(std::size_t particles, MirrorCoupling coupling,
                                            const std::vector<Constraint>& constraints,
                                            const ExtrapolatedParticles& extrapolated);

/// Weight of every directed bond of `family` in W_c: (number of its ends that are not mirror
/// dependants) / 2, i.e. 1, ½ or 0. Symmetric: bond i→j and j→i get the same weight.
std::vector<double> mirror_bond_weights(const BondFamily& family,
                                        const std::vector<std::uint8_t>& dependent);

} // namespace pd
