// Private to libpd's discretisation: what fibre_arms.cpp and fibre_relaxation.cpp share, and the
// relaxed-moduli correction of unbalanced point clouds (fibre_relaxation.cpp, relax_moduli).
#pragma once

#include "libpd/discretisation/fibre_arms.hpp"

#include <Eigen/Sparse>
#ifdef LIBPD_HAVE_SUITESPARSE
#include <Eigen/CholmodSupport>
#endif
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace pd::fibre_detail {

/// The symmetric positive definite factorisation both the arm balance and the relaxation use:
/// CHOLMOD's supernodal Cholesky where libpd has SuiteSparse, else Eigen's LDLᵀ.
#ifdef LIBPD_HAVE_SUITESPARSE
using SparseCholesky = Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>>;
#else
using SparseCholesky = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>;
#endif

/// −f'(r/h)/h^(N+1) (eq. 57), the slope of particle i's kernel at distance r.
inline double kernel_weight(const FibreKernel& kernel, int dim, double r, double h) {
  return -kernel.slope(dim, r / h) / std::pow(h, dim + 1);
}

/// Unit vector from particle i to the neighbour of directed bond k.
inline std::array<double, 3> arm_direction(const ParticleSet& particles, const BondFamily& family,
                                           std::size_t i, std::size_t k) {
  const Vec3& pi = particles.position[i];
  const Vec3& pj = particles.position[family.neighbour[k]];
  const double inv = family.inverse_length[k];
  return {(pj[0] - pi[0]) * inv, (pj[1] - pi[1]) * inv, (pj[2] - pi[2]) * inv};
}

/// 1 for every particle that is marked or has an arm to a marked one.
inline std::vector<std::uint8_t> marked_or_next_to(const BondFamily& family,
                                                   const std::vector<std::uint8_t>& marked) {
  std::vector<std::uint8_t> out(marked.size(), 0);
  for (std::size_t i = 0; i < marked.size(); ++i) {
    bool any = marked[i] != 0;
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1] && !any; ++k) {
      any = marked[family.neighbour[k]] != 0;
    }
    out[i] = any ? 1 : 0;
  }
  return out;
}

/// Raise the constants of `arms` (arms.shear, arms.volumetric) so that the relaxed network of an
/// unbalanced point cloud has its material's moduli (fibre_relaxation.cpp); `size` the particles'
/// h, `owns_energy` 0 for extrapolated particles.
FibreArms::RelaxedModuli relax_moduli(const ModelDimension& d, const FibreKernel& kernel,
                                      const ParticleSet& particles, const BondFamily& family,
                                      const std::vector<double>& size,
                                      const std::vector<std::uint8_t>& owns_energy,
                                      FibreArms& arms);

} // namespace pd::fibre_detail
