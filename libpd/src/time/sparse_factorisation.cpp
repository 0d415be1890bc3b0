// The direct solvers of the static solve: CHOLMOD (symmetric) and an LU factorisation
// (nonsymmetric), with Eigen's own solvers when libpd is built without SuiteSparse.
#include "sparse_factorisation.hpp"

#include "libpd/core/blas.hpp"
#include "libpd/core/memory.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <fmt/format.h>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <vector>

#ifdef LIBPD_HAVE_SUITESPARSE
#include <Eigen/UmfPackSupport>
#include <algorithm>
#include <cholmod.h>
#include <chrono>
#endif

namespace pd {

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

[[noreturn]] void singular(std::string_view what) {
  throw std::runtime_error(std::string("static solve: ") + std::string(what) +
                           " failed: the stiffness matrix is singular (is the body held against "
                           "rigid motion by its supports?)");
}

#ifdef LIBPD_HAVE_SUITESPARSE

/// Throws when a factor of `bytes` would not fit into the memory the run may use (with room for
/// the matrix and the solver's workspace: 80 %). Only CHOLMOD's analysis tells the size before
/// the factorisation, hence only with SuiteSparse.
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

/// CHOLMOD's workspace for the lifetime of its owner: finished on every path out, a throw from
/// the owner's constructor included.
class CholmodCommon {
public:
  CholmodCommon() { cholmod_start(&common_); }
  ~CholmodCommon() { cholmod_finish(&common_); }
  CholmodCommon(const CholmodCommon&) = delete;
  CholmodCommon& operator=(const CholmodCommon&) = delete;
  cholmod_common& get() { return common_; }

private:
  cholmod_common common_{};
};

/// A CHOLMOD factor, freed with the workspace that made it on every path out.
class CholmodFactor {
public:
  CholmodFactor(cholmod_factor* factor, cholmod_common& common)
      : factor_(factor), common_(&common) {}
  ~CholmodFactor() {
    if (factor_ != nullptr) {
      cholmod_free_factor(&factor_, common_);
    }
  }
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;
  cholmod_factor* get() const { return factor_; }

private:
  cholmod_factor* factor_;
  cholmod_common* common_;
};

/// A fill-reducing ordering of K's unknowns that keeps each group's unknowns together (a
/// particle's components), found on the graph of the groups: CHOLMOD's own choice (AMD, and METIS
/// where AMD fills badly) on a graph with nine times fewer entries than K's. Ordering K itself
/// took most of the plate's analysis (METIS on 14 M entries: 1.9 s of 6 s; on the particles
/// 0.45 s, for 4 % more flops in the factorisation; the beams' AMD: 10 % fewer).
std::vector<int> group_ordering(const SparseMatrix& K, const std::vector<std::size_t>& group,
                                cholmod_common& common, int& ordering) {
  const auto n = static_cast<std::size_t>(K.cols());
  if (group.size() != n || n == 0) {
    return {};
  }
  std::vector<std::size_t> first(1, 0); // first unknown of each group, then n
  std::vector<int> index(n, 0);         // each unknown's group, numbered from 0
  for (std::size_t j = 1; j < n; ++j) {
    if (group[j] != group[j - 1]) {
      first.push_back(j);
    }
    index[j] = static_cast<int>(first.size() - 1);
  }
  const std::size_t groups = first.size();
  first.push_back(n);
  // The groups' lower-triangle pattern, by columns (K's unknowns are in group order, so a group's
  // rows are at or below it).
  std::vector<int> p(1, 0), rows;
  std::vector<std::size_t> seen(groups, groups);
  for (std::size_t g = 0; g < groups; ++g) {
    const std::size_t start = rows.size();
    for (std::size_t j = first[g]; j < first[g + 1]; ++j) {
      for (SparseMatrix::InnerIterator it(K, static_cast<Eigen::Index>(j)); it; ++it) {
        const int h = index[static_cast<std::size_t>(it.row())];
        if (seen[static_cast<std::size_t>(h)] != g) {
          seen[static_cast<std::size_t>(h)] = g;
          rows.push_back(h);
        }
      }
    }
    std::sort(rows.begin() + static_cast<std::ptrdiff_t>(start), rows.end());
    p.push_back(static_cast<int>(rows.size()));
  }
  cholmod_sparse pattern{};
  pattern.nrow = pattern.ncol = groups;
  pattern.nzmax = rows.size();
  pattern.p = p.data();
  pattern.i = rows.data();
  pattern.stype = -1;
  pattern.itype = CHOLMOD_INT;
  pattern.xtype = CHOLMOD_PATTERN;
  pattern.dtype = CHOLMOD_DOUBLE;
  pattern.sorted = 1;
  pattern.packed = 1;
  const CholmodFactor symbolic(cholmod_analyze(&pattern, &common), common);
  if (symbolic.get() == nullptr) {
    return {};
  }
  ordering = common.method[common.selected].ordering;
  std::vector<int> order;
  order.reserve(n);
  const int* perm = static_cast<const int*>(symbolic.get()->Perm);
  for (std::size_t k = 0; k < groups; ++k) {
    const auto g = static_cast<std::size_t>(perm[k]);
    for (std::size_t j = first[g]; j < first[g + 1]; ++j) {
      order.push_back(static_cast<int>(j));
    }
  }
  return order;
}

/// CHOLMOD supernodal K = L Lᵀ, called directly (Eigen's wrapper chooses the ordering itself).
class Cholmod final : public SparseFactorisation {
public:
  Cholmod(const SparseMatrix& K, const std::vector<std::size_t>& group) {
    cholmod_common& common = workspace_.get();
    common.supernodal = CHOLMOD_SUPERNODAL;
    common.final_asis = 1;
    const auto start = std::chrono::steady_clock::now();
    cholmod_sparse A = view(K);
    std::vector<int> order = group_ordering(K, group, common, ordering_);
    if (!order.empty()) {
      common.nmethods = 1;
      common.method[0].ordering = CHOLMOD_GIVEN;
      common.postorder = 1;
    }
    holder_.emplace(
        cholmod_analyze_p(&A, order.empty() ? nullptr : order.data(), nullptr, 0, &common), common);
    factor_ = holder_->get();
    if (factor_ == nullptr) {
      singular("the analysis of the Cholesky factorisation (CHOLMOD)");
    }
    analysis_seconds_ =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // The symbolic analysis knows the factor's size: refuse a factor the machine cannot hold
    // before the numeric factorisation runs into the OOM killer.
    check_fits(static_cast<double>(factor_bytes()));
    // The BLAS runs on one thread, whatever the factor's size. OpenBLAS splits a dense block's
    // work by its thread count, so a factor made with 2 BLAS threads differed from the 1-thread
    // factor in the last bits, and so did every result solved with it. And each supernode is a
    // short parallel region whose threads mostly wait: on a 2-core machine beside two busy
    // processes (and other load, 3.5-12) the plate's factorisation (32.9 M entries) took 14-21 s
    // with 2 BLAS threads against 7-10 s with 1; the clamped beam's (9.6 M), at load 11-14, 9.5 s
    // against 4.9 s.
    const SerialBlas serial;
    if (!cholmod_factorize(&A, factor_, &common) || common.status != CHOLMOD_OK ||
        factor_->minor < factor_->n) {
      singular("the Cholesky factorisation (CHOLMOD)");
    }
  }
  Cholmod(const Cholmod&) = delete;
  Cholmod& operator=(const Cholmod&) = delete;

  Eigen::VectorXd solve(const Eigen::VectorXd& b) const override {
    cholmod_dense rhs{};
    rhs.nrow = rhs.nzmax = rhs.d = static_cast<std::size_t>(b.size());
    rhs.ncol = 1;
    rhs.x = const_cast<double*>(b.data()); // CHOLMOD reads it only
    rhs.xtype = CHOLMOD_REAL;
    rhs.dtype = CHOLMOD_DOUBLE;
    cholmod_common& common = workspace_.get();
    const SerialBlas serial; // the triangular solves too: bitwise for any thread count
    cholmod_dense* x = cholmod_solve(CHOLMOD_A, factor_, &rhs, &common);
    if (x == nullptr) {
      throw std::runtime_error("static solve: CHOLMOD's triangular solves failed");
    }
    Eigen::VectorXd out = Eigen::Map<const Eigen::VectorXd>(static_cast<double*>(x->x), b.size());
    cholmod_free_dense(&x, &common);
    return out;
  }
  double analysis_seconds() const override { return analysis_seconds_; }
  std::string name() const override {
    switch (ordering_) {
    case CHOLMOD_AMD:
      return "CHOLMOD supernodal LLT (AMD ordering of particles)";
    case CHOLMOD_METIS:
      return "CHOLMOD supernodal LLT (METIS ordering of particles)";
    case CHOLMOD_NESDIS:
      return "CHOLMOD supernodal LLT (nested dissection of particles)";
    default:
      return "CHOLMOD supernodal LLT";
    }
  }
  std::size_t factor_nonzeros() const override {
    return factor_->is_super ? factor_->xsize : factor_->nzmax;
  }
  std::size_t factor_bytes() const override {
    const cholmod_factor& L = *factor_;
    const std::size_t index = L.itype == CHOLMOD_LONG ? sizeof(SuiteSparse_long) : sizeof(int);
    // Values, then the integer arrays: Perm and ColCount (n each); supernodal: s and the
    // super, pi, px pointers; simplicial: i, and p, nz, next, prev.
    const std::size_t integers =
        2 * L.n + (L.is_super ? L.ssize + 3 * (L.nsuper + 1) : L.nzmax + 4 * L.n + 2);
    return factor_nonzeros() * sizeof(double) + integers * index;
  }

private:
  /// K's lower triangle as CHOLMOD reads it (no copy).
  static cholmod_sparse view(const SparseMatrix& K) {
    cholmod_sparse A{};
    A.nrow = A.ncol = static_cast<std::size_t>(K.rows());
    A.nzmax = static_cast<std::size_t>(K.nonZeros());
    A.p = const_cast<int*>(K.outerIndexPtr()); // CHOLMOD reads them only
    A.i = const_cast<int*>(K.innerIndexPtr());
    A.x = const_cast<double*>(K.valuePtr());
    A.stype = -1;
    A.itype = CHOLMOD_INT;
    A.xtype = CHOLMOD_REAL;
    A.dtype = CHOLMOD_DOUBLE;
    A.sorted = 1;
    A.packed = 1;
    return A;
  }

  // Declared in this order so that the factor is freed before its workspace is finished.
  mutable CholmodCommon workspace_;
  std::optional<CholmodFactor> holder_;
  cholmod_factor* factor_ = nullptr; ///< holder_'s factor (set once analysed)
  double analysis_seconds_ = 0;
  int ordering_ = -1; ///< CHOLMOD's ordering method of the particles (-1: CHOLMOD's own of K)
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

std::unique_ptr<SparseFactorisation>
factorise(const SparseMatrix& K, bool symmetric,
          [[maybe_unused]] const std::vector<std::size_t>& group) {
#ifdef LIBPD_HAVE_SUITESPARSE
  if (symmetric) {
    return std::make_unique<Cholmod>(K, group);
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
