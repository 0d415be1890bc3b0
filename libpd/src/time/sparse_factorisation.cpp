// The direct solvers of the static solve: CHOLMOD (symmetric) and an LU factorisation
// (nonsymmetric), with Eigen's own solvers when libpd is built without SuiteSparse.
#include "sparse_factorisation.hpp"

#include "libpd/core/memory.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <fmt/format.h>
#include <optional>
#include <stdexcept>
#include <string_view>

#ifdef LIBPD_HAVE_SUITESPARSE
#include <Eigen/CholmodSupport>
#include <Eigen/UmfPackSupport>
#endif

namespace pd {

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

/// Throws when a factor of `bytes` would not fit into the memory the run may use (with room for
/// the matrix and the solver's workspace: 80 %).
void check_fits(double bytes) {
  const std::optional<MemoryBudget> budget = available_memory();
  if (budget && bytes > 0.8 * budget->bytes) {
    throw std::runtime_error(fmt::format(
        "static solve: the Cholesky factor would take {} but {} are available ({}): use "
        "'integrator: adr' (memory proportional to the bonds), a coarser spacing, or raise "
        "PD_MEMORY_LIMIT if the machine has more",
        format_bytes(bytes), format_bytes(budget->bytes), budget->source));
  }
}

[[noreturn]] void singular(std::string_view what) {
  throw std::runtime_error(std::string("static solve: ") + std::string(what) +
                           " failed: the stiffness matrix is singular (is the body held against "
                           "rigid motion by its supports?)");
}

#ifdef LIBPD_HAVE_SUITESPARSE

/// CHOLMOD supernodal K = L Lᵀ. Eigen's wrapper keeps the cholmod_factor to itself; deriving
/// from it reaches the factor's sizes.
class Cholmod final : public SparseFactorisation {
public:
  explicit Cholmod(const SparseMatrix& K) {
    // The symbolic analysis knows the factor's size: refuse a factor the machine cannot hold
    // before the numeric factorisation runs into the OOM killer.
    llt_.analyzePattern(K);
    if (llt_.info() == Eigen::Success) {
      check_fits(static_cast<double>(llt_.factor_bytes()));
    }
    llt_.factorize(K);
    if (llt_.info() != Eigen::Success) {
      singular("the Cholesky factorisation (CHOLMOD)");
    }
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const override { return llt_.solve(b); }
  std::string name() const override { return "CHOLMOD supernodal LLT"; }
  std::size_t factor_nonzeros() const override { return llt_.factor_nonzeros(); }
  std::size_t factor_bytes() const override { return llt_.factor_bytes(); }

private:
  class LLT : public Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower> {
  public:
    std::size_t factor_nonzeros() const {
      const cholmod_factor& L = *m_cholmodFactor;
      return L.is_super ? L.xsize : L.nzmax;
    }
    std::size_t factor_bytes() const {
      const cholmod_factor& L = *m_cholmodFactor;
      const std::size_t index = L.itype == CHOLMOD_LONG ? sizeof(SuiteSparse_long) : sizeof(int);
      // Values, then the integer arrays: Perm and ColCount (n each); supernodal: s and the
      // super, pi, px pointers; simplicial: i, and p, nz, next, prev.
      const std::size_t integers =
          2 * L.n + (L.is_super ? L.ssize + 3 * (L.nsuper + 1) : L.nzmax + 4 * L.n + 2);
      return factor_nonzeros() * sizeof(double) + integers * index;
    }
  };
  LLT llt_;
};

/// UMFPACK's unsymmetric multifrontal LU.
class Umfpack final : public SparseFactorisation {
public:
  explicit Umfpack(const SparseMatrix& K) {
    // No iterative refinement: Newton refines the answer on the force kernel. The ordering as
    // CHOLMOD's: AMD, and METIS when AMD fills badly (measured on the structural scenes, 1 thread:
    // the plate's factor 98 M entries instead of AMD's 131 M and 33 s instead of Eigen SparseLU's
    // 56 s; the beams keep AMD, where UMFPACK takes 1.5 s against SparseLU's 1.0 s).
    lu_.umfpackControl()(UMFPACK_IRSTEP) = 0;
    lu_.umfpackControl()(UMFPACK_ORDERING) = UMFPACK_ORDERING_CHOLMOD;
    lu_.compute(K);
    if (lu_.info() != Eigen::Success) {
      singular("the LU factorisation (UMFPACK)");
    }
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const override { return lu_.solve(b); }
  std::string name() const override { return "UMFPACK LU"; }
  std::size_t factor_nonzeros() const override { return lu_.factor_nonzeros(); }
  std::size_t factor_bytes() const override { return lu_.factor_bytes(); }

private:
  class LU : public Eigen::UmfPackLU<SparseMatrix> {
  public:
    std::size_t factor_nonzeros() const {
      return static_cast<std::size_t>(m_umfpackInfo[UMFPACK_LNZ] + m_umfpackInfo[UMFPACK_UNZ]);
    }
    /// The Numeric object's final size: L, U, the permutations and UMFPACK's bookkeeping.
    std::size_t factor_bytes() const {
      return static_cast<std::size_t>(m_umfpackInfo[UMFPACK_NUMERIC_SIZE] *
                                      m_umfpackInfo[UMFPACK_SIZE_OF_UNIT]);
    }
  };
  LU lu_;
};

#endif

/// Eigen's SimplicialLDLT, when libpd is built without SuiteSparse.
class EigenLDLT final : public SparseFactorisation {
public:
  explicit EigenLDLT(const SparseMatrix& K) {
    ldlt_.compute(K);
    if (ldlt_.info() != Eigen::Success) {
      singular("the LDLᵀ factorisation (Eigen)");
    }
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const override { return ldlt_.solve(b); }
  std::string name() const override { return "Eigen SimplicialLDLT"; }
  std::size_t factor_nonzeros() const override {
    return static_cast<std::size_t>(ldlt_.matrixL().nestedExpression().nonZeros() + ldlt_.rows());
  }
  std::size_t factor_bytes() const override {
    return factor_nonzeros() * (sizeof(double) + sizeof(int));
  }

private:
  Eigen::SimplicialLDLT<SparseMatrix> ldlt_;
};

/// Eigen's supernodal SparseLU.
class EigenLU final : public SparseFactorisation {
public:
  explicit EigenLU(const SparseMatrix& K) {
    lu_.analyzePattern(K);
    lu_.factorize(K);
    if (lu_.info() != Eigen::Success) {
      singular("the LU factorisation (Eigen SparseLU)");
    }
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const override { return lu_.solve(b); }
  std::string name() const override { return "Eigen SparseLU"; }
  std::size_t factor_nonzeros() const override {
    return static_cast<std::size_t>(lu_.nnzL() + lu_.nnzU());
  }
  std::size_t factor_bytes() const override {
    return factor_nonzeros() * (sizeof(double) + sizeof(int));
  }

private:
  Eigen::SparseLU<SparseMatrix> lu_;
};

} // namespace

std::unique_ptr<SparseFactorisation> factorise(const SparseMatrix& K, bool symmetric) {
#ifdef LIBPD_HAVE_SUITESPARSE
  if (symmetric) {
    return std::make_unique<Cholmod>(K);
  }
  return std::make_unique<Umfpack>(K);
#else
  if (symmetric) {
    return std::make_unique<EigenLDLT>(K);
  }
  return std::make_unique<EigenLU>(K);
#endif
}

} // namespace pd
