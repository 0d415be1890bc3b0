// The static solver's sparse Cholesky (CHOLMOD where SuiteSparse is found) for programs built on
// libpd, such as the deal.II reference solvers: they factor their own stiffness with the same
// code, so a PD and an FE solve of one problem differ by the discretisation, not by the solver.
// The interface speaks plain vectors because libpd keeps Eigen to itself.
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace pd {

class SparseFactorisation;

/// One stored entry of a sparse matrix's lower triangle (row ≥ column).
struct LowerEntry {
  std::size_t row = 0;
  std::size_t column = 0;
  double value = 0;
};

class SparseCholesky {
public:
  /// Factors the symmetric matrix of order `size` whose lower triangle is `lower` (entries at
  /// the same place are summed, in order). Throws std::runtime_error if the matrix is singular
  /// or not positive definite.
  SparseCholesky(std::size_t size, const std::vector<LowerEntry>& lower);
  ~SparseCholesky();
  SparseCholesky(SparseCholesky&&) noexcept;
  SparseCholesky& operator=(SparseCholesky&&) noexcept;

  /// x = K⁻¹ b; b has `size` entries.
  std::vector<double> solve(std::span<const double> b) const;
  /// The library and method, e.g. "CHOLMOD supernodal LLT".
  std::string name() const;
  /// Bytes of the factor's values and indices.
  std::size_t factor_bytes() const;

private:
  std::unique_ptr<SparseFactorisation> factor_;
  std::size_t size_ = 0;
};

} // namespace pd
