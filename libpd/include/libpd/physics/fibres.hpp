// The virtual-fibre bond model (Olsson, Ander & Williams 2021, "The use of peridynamic virtual
// fibres to simulate yielding and brittle fracture"): the law, apart from the neighbour loop that
// applies it (kernel/fibre_kernel.hpp) and the arm weights of a particle set
// (discretisation/fibre_arms.hpp).
//
// An arm a–b carries the tension (eqs. 36, 64, 70)
//   T_ab = V_a V_b (ω̂_ab S_a(q_ab) + ω̂_ba S_b(q_ab)),
// the force flux density of each end weighted by that end's kernel slope. The force flux density
// of a linear elastic continuum in the arm's direction q is (eq. 77, eq. 110 without plasticity)
//   S_a(q) = G(N+2) ε_ab + (NK − G(N+2)) ε̄_a,
// with ε_ab the arm's engineering strain and ε̄_a = tr(ε)/N the particle's mean strain (eq. 73),
// which a first pass over the arms estimates. The split of the stress into its deviatoric and
// mean parts makes E and ν both free: NK − G(N+2) vanishes at ν = 1/4 (3D, plane strain) and
// ν = 1/3 (plane stress), where the model is the bond-based one (eqs. 82–84).
#pragma once

#include "libpd/core/names.hpp"
#include "libpd/physics/material.hpp"

namespace pd {

/// Which constitutive model the bonds carry. `micro_elastic` is the bond-based model of the
/// rest of the library (one constant per bond: ν fixed by the dimension).
enum class BondModel { micro_elastic, virtual_fibres };

template <>
struct EnumName<BondModel> {
  static constexpr NameTable<BondModel, 2> table{{
      {"micro-elastic", BondModel::micro_elastic,
       "bond-based micro-elastic (or micro-plastic) bonds: ν = 1/4 (3D, plane strain), 1/3 "
       "(plane stress)"},
      {"virtual-fibres", BondModel::virtual_fibres,
       "virtual fibres (Olsson et al. 2021): arm tensions from the force flux density with a "
       "bulk/shear split, any E and ν"},
  }};
};

/// The kernel of eq. 112: f(u) = (1 − u²/α²)^k / Z for u ≤ α, 0 beyond, with Z making
/// ∫ f(u) 2(N−1)π u^(N−1) du = 1 (eq. 54). A particle of size h has W(r) = f(r/h)/h^N (eq. 53)
/// and horizon α·h.
struct FibreKernel {
  int exponent = 2;        ///< k (the paper uses 2, eq. 113)
  double alpha = 5.1;      ///< α, horizon over particle size (the paper's Table 1)
  int size_neighbours = 5; ///< n of eq. 115: a particle's size from its n nearest neighbours

  /// Z of eq. 112 in N = `dim` dimensions (2 or 3): for k = 2 it is
  /// 2(N−1)π α^N (1/N − 2/(N+2) + 1/(N+4)), eq. 113 (whose extra factor C is a misprint).
  double normalisation(int dim) const;
  /// f(u), eq. 112.
  double value(int dim, double u) const;
  /// f'(u) = df/du (eq. 56), ≤ 0 on [0, α].
  double slope(int dim, double u) const;
  /// ∫ −f'(u) 2(N−1)π u^(N−1) du over [0, α]: a particle of size h whose horizon the body fills
  /// has the kernel-weighted volume Σ_j V_j w_j (eq. 57's weights) of this over h. By parts it is
  /// (N−1) ∫ f(u) 2(N−1)π u^(N−2) du.
  double slope_volume(int dim) const;
};

/// The two elastic constants of eq. 77 for a material in a setting: S = shear·ε_ab + bulk·ε̄.
struct FibreModuli {
  double shear = 0;      ///< G(N+2) [Pa]
  double volumetric = 0; ///< NK − G(N+2) [Pa], eqs. 82–84; may be negative (ν < 1/4)
};

/// G from eq. 78 and K from eq. 79 (3D), 80 (plane stress) or 81 (plane strain).
/// Throws std::invalid_argument in 1D or for ν outside the stable range.
FibreModuli fibre_moduli(const ModelDimension& d, double youngs_modulus, double poisson_ratio);

} // namespace pd
