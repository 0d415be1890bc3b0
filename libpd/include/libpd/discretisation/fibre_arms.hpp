// The arms of the virtual-fibre model (physics/fibres.hpp) on a particle set: each directed bond
// i→j of the bond family is the arm i–j seen from i and carries the weights of both its ends.
//
// Particle a of size h_a weights its arms with its own kernel slope, −f'(ξ/h_a)/h_a^(N+1)
// (eqs. 55, 57): the arm weight of eq. 41 split into the part of each end (§4.2). The paper
// normalises by the continuum value of the total weighted length, L = N/C^(N−1) (eqs. 59–63); we
// use the discrete sum of eq. 40 instead, per particle: with
//   A_k = N V_j w_ij / Σ_j V_j w_ij |ξ_ij|,   w_ij = −f'(|ξ_ij|/h_i)/h_i^(N+1)
// a homogeneous strain gives every particle with a full (or ghost-completed) neighbourhood the
// continuum stress whatever its neighbours' sizes and spacing (the lattice's or an irregular
// set's discrete sum differs from the integral by some per cent). The force density on i is
//   b_i = Σ_j (A_k S_i(q) + B_k S_j(q)) q,   B_k = A_{k'} V_j / V_i   (k' the reverse bond),
// so that V_i B_k = V_j A_{k'}: both ends feel the same tension (eq. 11),
// and the mean strain of eq. 73 is ε̄_i = (1/N) Σ_j A_k |ξ_k| ε_k, exact for any isotropic strain.
//
// On a regular lattice (every body a lattice region) the fourth moment Σ A|ξ| n⊗n⊗n⊗n has cubic,
// not isotropic, symmetry (−1.4 % in 3D at δ = 3.015λ, −7 % in 2D): enough to move ν by several per
// cent at ν = 0.1. Under any volume correction other than `none`, each weight is multiplied by a +
// b Σ_d n_d⁴ with a, b matching the continuum's two invariants, as the `moment` correction does for
// the bond-based model (corrections.hpp). With point-cloud bodies each particle gets its own factor
// instead, a quartic p(q) whose coefficients make that particle's weighted fourth moments the
// isotropic ones, so that a homogeneous strain gives every particle with a full horizon the
// continuum stress on any arrangement (graded, jittered: 2e-6, against 21 % with the kernel
// weights alone). Even moments cannot cancel the arms' forces on an irregular set: that is the
// third moment of the pair weights α_ab = V_a A_ab + V_b A_ba, about 0.2 σ/h at interior particles
// of a graded, jittered plate. So point clouds are then balanced (fibre_arms.cpp,
// balance_arms): every arm weight changes, by the least relative change, so that every particle
// with a full horizon has zero third moment (no net force under any homogeneous strain: the
// integration constraint of meshfree methods) and the isotropic fourth moments, and every other
// particle keeps its fourth moments; 1e-7 σ/h is left. Arms are held at 10 % of their weight at
// least; where the conditions cannot then be met (the Monte Carlo sets of Fig. 8) no weight is
// changed, and the interior forces let the particles relax off a homogeneous field: the body is
// then softer than its material, more in shear than in bulk (about 4.6 % and 7.2 % of the energy
// on the disks of Fig. 8 at Table 1's α, so ν 0.305 for 0.3, at every density).
// fibre_relaxation.cpp's relax_moduli measures that relaxation once (each homogeneous strain
// imposed, the particles near a surface held, the rest solved to equilibrium with the linearised
// stiffness) and raises each particle's shear and bulk constants by what its neighbourhood
// releases, so that the relaxed network has the material's moduli. Arm tensions stay equal and
// opposite at both ends and derive from the energy below.
//
// Particles that are extrapolated (ghosts, quadratic clamps: ghost_layers.hpp) own no energy:
// their A is zero, so each body particle stores the bulk energy of the field it sees
// (E = Σ_a V_a [½ G(N+2) Σ_j A_k |ξ| ε² + ½ (NK − G(N+2)) N ε̄_a²]), and their forces fold back
// onto their sources as for the bond-based model.
#pragma once

#include "libpd/discretisation/bond_family.hpp"
#include "libpd/discretisation/corrections.hpp"
#include "libpd/discretisation/lattice.hpp"
#include "libpd/physics/fibres.hpp"

#include <cstdint>
#include <vector>

namespace pd {

struct FibreArms {
  int dim = 3;
  std::vector<double> own;        ///< A_k per directed bond [1/m]
  std::vector<double> other;      ///< B_k per directed bond [1/m]
  std::vector<double> shear;      ///< G(N+2) of each particle's material [Pa]
  std::vector<double> volumetric; ///< NK − G(N+2) of each particle's material [Pa]
  /// Point clouds (fibre_arms.cpp, balance_arms): the interior particles whose third moments
  /// are to be zeroed and fourth moments made isotropic, the conditions' relative residual, the
  /// arms held at their floor (10 % of their weight before the balance), the least-change solves,
  /// and whether the balance was applied (residual ≤ 1e-6; else no weight changed).
  std::size_t balanced = 0;
  double balance_residual = 0;
  std::size_t balance_floored = 0;
  int balance_passes = 0;
  bool balance_applied = false;
  /// Where the balance is not applied: the relaxed network's moduli made the material's
  /// (fibre_relaxation.cpp, relax_moduli). The body-wide fractions of a homogeneous strain's energy
  /// that the particles' relaxation releases (isotropic and deviatoric modes, before the
  /// correction), the particles relaxed, the range of the per-particle deviatoric fractions
  /// applied, and how many per-particle fractions were held in [0, 0.5].
  struct RelaxedModuli {
    bool applied = false;
    std::size_t free = 0;
    double bulk = 0;
    double shear = 0;
    double shear_low = 0;
    double shear_high = 0;
    std::size_t bounded = 0;
  } relaxed;

  bool empty() const { return own.empty(); }
};

/// Particle sizes h_a: δ/α for lattice particles, so that the horizon α·h is the lattice's δ and
/// their arms are the bond family; a particle file's h where it gives one; otherwise eq. 115 from
/// the `kernel.size_neighbours` nearest particles.
std::vector<double> fibre_particle_sizes(const LatticeSpec& lattice, const FibreKernel& kernel,
                                         const ParticleSet& particles, int dim);

/// The arms of `family` on `particles` of sizes `size` (`geometry`: the model's dimension,
/// lattice and volume correction); `owns_energy[i]` is 0 for extrapolated
/// particles. Throws std::runtime_error for a body particle with no arm of positive weight.
FibreArms fibre_arms(const CorrectionSpec& geometry, const FibreKernel& kernel,
                     const std::vector<Material>& materials, const ParticleSet& particles,
                     const BondFamily& family, const std::vector<double>& size,
                     const std::vector<std::uint8_t>& owns_energy);

/// A pair stiffness c_k V_j per directed bond whose linearised operator bounds the fibre
/// model's from above, for the stable time step (eq. 31) and ADR's fictitious density: by
/// Cauchy–Schwarz N ε̄² ≤ Σ_j A_k |ξ| ε_k², so the volumetric energy is at most
/// max(NK − G(N+2), 0) times the deviatoric one's sum, and
///   c_k V_j = (G(N+2) + max(NK − G(N+2), 0))_i A_k + (…)_j B_k.
std::vector<double> fibre_stiffness_bound(const FibreArms& arms, const BondFamily& family);

} // namespace pd
