// The direct solvers behind solver.integrator: static (time/static_solver.cpp), private to libpd
// because they speak Eigen. One factorisation of the assembled stiffness K, then any number of
// solves with it:
//   symmetric K (no mirror supports, or consistent mirror coupling): CHOLMOD's supernodal
//     Cholesky K = L Lᵀ (SuiteSparse, through Eigen's CholmodSupport): dense blocks through BLAS,
//     a fill-reducing ordering (AMD, METIS when AMD fills badly);
//   nonsymmetric K (`copy` mirror coupling): UMFPACK's multifrontal LU (SuiteSparse, through
//     Eigen's UmfPackSupport), K = P⁻¹ L U Q⁻¹.
// Without SuiteSparse (LIBPD_HAVE_SUITESPARSE unset) Eigen's own SimplicialLDLT and SparseLU
// stand in. Either way the factorisation says what it is and how many bytes its factor holds.
#pragma once

#include <Eigen/SparseCore>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace pd {

class SparseFactorisation {
public:
  virtual ~SparseFactorisation() = default;
  /// x = K⁻¹ b.
  virtual Eigen::VectorXd solve(const Eigen::VectorXd& b) const = 0;
  /// The library and method, e.g. "CHOLMOD supernodal LLT".
  virtual std::string name() const = 0;
  /// Entries the factor stores (L, or L and U; supernodal: with the blocks' explicit zeros).
  virtual std::size_t factor_nonzeros() const = 0;
  /// Bytes of the factor's values and indices.
  virtual std::size_t factor_bytes() const = 0;
  /// Seconds the ordering and symbolic analysis took, where they run apart from the numeric
  /// factorisation (CHOLMOD); 0 otherwise.
  virtual double analysis_seconds() const { return 0.0; }
};

/// Factor K (square, compressed, column-major). `symmetric`: K = Kᵀ (to round-off; only its lower
/// triangle is read). `group`: empty, or per unknown a number that is the same for unknowns that
/// belong together (a particle's components; consecutive, nondecreasing): the symmetric
/// factorisation then orders groups rather than unknowns. Throws std::runtime_error if K is
/// singular or not positive definite.
std::unique_ptr<SparseFactorisation> factorise(const Eigen::SparseMatrix<double>& K, bool symmetric,
                                               const std::vector<std::size_t>& group = {});

} // namespace pd
