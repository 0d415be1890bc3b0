// Distributed linear solves of the static solver (distributed_solve.hpp): PETSc, CG + GAMG.
//
// Determinism. PETSc's parallel matrix-vector product sums each row's diagonal-block and
// off-diagonal-block parts in a fixed order, and its dot products and norms are MPI_Allreduce,
// which Open MPI computes with an algorithm chosen by the communicator's size and the message
// length, not by timing: for a given rank count the same numbers arrive. GAMG's aggregation and
// Chebyshev eigenvalue estimates are deterministic (the estimate's start vector comes from
// PetscRandom with its fixed default seed). MPI does not promise reproducible reductions, so this
// is a property of the MPI library, measured (tests/mpi: two runs on the same rank count are
// compared bitwise), not one PETSc guarantees; different rank counts give answers that differ
// within the solve's tolerance.
#include "distributed_solve.hpp"

#include "libpd/core/exact_sum.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <stdexcept>

#ifdef LIBPD_HAVE_PETSC
#include <mpi.h>
#include <petscksp.h>
#endif

namespace pd {

UnknownReductions::UnknownReductions(const Model& m, const DofMap& d) : model_(&m) {
  if (m.ownership.partial()) {
    owned_.resize(d.free_dofs.size());
    for (std::size_t k = 0; k < d.free_dofs.size(); ++k) {
      owned_[k] = m.ownership.owns(d.free_dofs[k] / 3) ? 1 : 0;
    }
  }
}

double UnknownReductions::dot(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const {
  if (owned_.empty()) {
    return a.dot(b);
  }
  ExactSum s;
  for (std::size_t k = 0; k < owned_.size(); ++k) {
    if (owned_[k]) {
      s.add(a[static_cast<Eigen::Index>(k)] * b[static_cast<Eigen::Index>(k)]);
    }
  }
  return model_->ownership.communicator().sum(s);
}

double UnknownReductions::norm(const Eigen::VectorXd& a) const {
  return owned_.empty() ? a.norm() : std::sqrt(dot(a, a));
}

bool UnknownReductions::is_zero(const Eigen::VectorXd& a) const {
  if (owned_.empty()) {
    return a.isZero();
  }
  bool zero = true;
  for (std::size_t k = 0; k < owned_.size(); ++k) {
    zero = zero && (!owned_[k] || a.segment(static_cast<Eigen::Index>(k), 1).isZero());
  }
  return !model_->ownership.communicator().any(!zero);
}

#ifndef LIBPD_HAVE_PETSC

bool have_distributed_solver() {
  return false;
}

std::unique_ptr<SparseFactorisation> distributed_solver(const Model&, const DofMap&,
                                                        const StaticSystem&, double,
                                                        std::function<bool()>) {
  throw std::runtime_error("solver.integrator: static on several MPI ranks needs PETSc, and libpd "
                           "was built without it: run with one rank");
}

#else

namespace {

void check(PetscErrorCode code, const char* what) {
  if (code != 0) {
    throw std::runtime_error(fmt::format("PETSc: {} failed (error {})", what, code));
  }
}

/// PETSc on the run's communicator, once per process. Its signal handlers stay off: SIGTERM,
/// SIGINT and SIGHUP belong to the run's interrupt handling (app/interrupt.hpp). PETSc is not
/// finalised: MPI belongs to the run, and PETSc holds no files.
void initialise_petsc(MPI_Comm comm) {
  static const bool done = [comm] {
    PETSC_COMM_WORLD = comm;
    check(PetscOptionsSetValue(nullptr, "-no_signal_handler", "true"), "PetscOptionsSetValue");
    check(PetscInitializeNoArguments(), "PetscInitialize");
    return true;
  }();
  (void)done;
}

class PetscAmgSolve final : public SparseFactorisation {
public:
  PetscAmgSolve(const Model& m, const DofMap& d, const StaticSystem& system, double rtol,
                std::function<bool()> stop)
      : stop_(std::move(stop)), comm_(&m.ownership.communicator()) {
    const MPI_Comm mpi = *static_cast<const MPI_Comm*>(comm_->native());
    initialise_petsc(mpi);
    const auto t0 = std::chrono::steady_clock::now();
    number_unknowns(m, d, mpi);
    assemble(m, d, system, mpi);
    check(KSPCreate(mpi, &ksp_), "KSPCreate");
    check(KSPSetOperators(ksp_, matrix_, matrix_), "KSPSetOperators");
    check(KSPSetType(ksp_, KSPCG), "KSPSetType");
    PC pc = nullptr;
    check(KSPGetPC(ksp_, &pc), "KSPGetPC");
    check(PCSetType(pc, PCGAMG), "PCSetType");
    check(KSPSetTolerances(ksp_, rtol, 0.0, PETSC_DEFAULT, max_iterations), "KSPSetTolerances");
    check(KSPSetNormType(ksp_, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType");
    check(KSPMonitorSet(ksp_, &PetscAmgSolve::monitor, this, nullptr), "KSPMonitorSet");
    // Options prefixed pd_static_ (PETSC_OPTIONS, e.g. -pd_static_ksp_view) tune it further.
    check(KSPSetOptionsPrefix(ksp_, "pd_static_"), "KSPSetOptionsPrefix");
    check(KSPSetFromOptions(ksp_), "KSPSetFromOptions");
    check(KSPSetUp(ksp_), "KSPSetUp");
    setup_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

  ~PetscAmgSolve() override {
    KSPDestroy(&ksp_);
    MatDestroy(&matrix_);
  }
  PetscAmgSolve(const PetscAmgSolve&) = delete;
  PetscAmgSolve& operator=(const PetscAmgSolve&) = delete;

  Eigen::VectorXd solve(const Eigen::VectorXd& b) const override {
    Vec rhs = nullptr, x = nullptr;
    check(MatCreateVecs(matrix_, &x, &rhs), "MatCreateVecs");
    PetscScalar* p = nullptr;
    check(VecGetArray(rhs, &p), "VecGetArray");
    for (std::size_t k = 0; k < owned_unknowns_.size(); ++k) {
      p[k] = b[static_cast<Eigen::Index>(owned_unknowns_[k])];
    }
    check(VecRestoreArray(rhs, &p), "VecRestoreArray");
    // A monitor's error would be printed with a traceback; a stop request is not an error.
    check(PetscPushErrorHandler(PetscReturnErrorHandler, nullptr), "PetscPushErrorHandler");
    const PetscErrorCode code = KSPSolve(ksp_, rhs, x);
    PetscPopErrorHandler();
    if (stopped_) {
      VecDestroy(&rhs);
      VecDestroy(&x);
      throw StopRequested("a stop was requested during the distributed static solve");
    }
    check(code, "KSPSolve");
    KSPConvergedReason reason{};
    PetscInt iterations = 0;
    KSPGetConvergedReason(ksp_, &reason);
    KSPGetIterationNumber(ksp_, &iterations);
    iterations_ += static_cast<std::size_t>(iterations);
    ++solves_;
    Eigen::VectorXd out = Eigen::VectorXd::Zero(b.size());
    const PetscScalar* xs = nullptr;
    check(VecGetArrayRead(x, &xs), "VecGetArrayRead");
    for (std::size_t k = 0; k < owned_unknowns_.size(); ++k) {
      out[static_cast<Eigen::Index>(owned_unknowns_[k])] = xs[k];
    }
    check(VecRestoreArrayRead(x, &xs), "VecRestoreArrayRead");
    VecDestroy(&rhs);
    VecDestroy(&x);
    if (reason < 0) {
      throw std::runtime_error(fmt::format(
          "static solve on {} ranks: CG with GAMG did not converge (KSP reason {}, {} iterations)",
          comm_->size(), static_cast<int>(reason), iterations));
    }
    return out;
  }

  std::string name() const override {
    return fmt::format("PETSc CG + GAMG on {} ranks (block size {}; {} iterations in {} solves)",
                       comm_->size(), block_size_, iterations_, solves_);
  }
  std::size_t factor_nonzeros() const override { return 0; }
  std::size_t factor_bytes() const override { return 0; }
  double analysis_seconds() const override { return setup_seconds_; }

private:
  static constexpr PetscInt max_iterations = 10000;

  /// Rows rank by rank, each rank's owned unknowns in their local (= global) order; the halo's
  /// unknowns learn their owners' numbers through a map over every global dof.
  void number_unknowns(const Model& m, const DofMap& d, MPI_Comm mpi) {
    for (std::size_t k = 0; k < d.free_dofs.size(); ++k) {
      if (m.ownership.owns(d.free_dofs[k] / 3)) {
        owned_unknowns_.push_back(k);
      }
    }
    const auto mine = static_cast<long long>(owned_unknowns_.size());
    long long first = 0;
    MPI_Exscan(&mine, &first, 1, MPI_LONG_LONG, MPI_SUM, mpi);
    if (comm_->rank() == 0) {
      first = 0; // MPI_Exscan leaves rank 0's result undefined
    }
    first_row_ = static_cast<PetscInt>(first);
    std::vector<std::int32_t> row_of_dof(3 * m.ownership.global_particles, -1);
    for (std::size_t k = 0; k < owned_unknowns_.size(); ++k) {
      const std::size_t g = d.free_dofs[owned_unknowns_[k]];
      row_of_dof[3 * m.ownership.global(g / 3) + g % 3] = static_cast<std::int32_t>(first + k);
    }
    comm_->max(row_of_dof);
    row_of_unknown_.resize(d.free_dofs.size());
    for (std::size_t k = 0; k < d.free_dofs.size(); ++k) {
      const std::size_t g = d.free_dofs[k];
      row_of_unknown_[k] = row_of_dof[3 * m.ownership.global(g / 3) + g % 3];
    }
    // GAMG's block size: the dimension, where every particle with an unknown has all its
    // in-plane components free (then each block of rows is one particle).
    const int dim = m.spec.dimension.dim;
    bool whole = owned_unknowns_.size() % static_cast<std::size_t>(dim) == 0;
    for (std::size_t k = 0; whole && k < owned_unknowns_.size(); ++k) {
      const std::size_t g = d.free_dofs[owned_unknowns_[k]];
      whole = g % 3 == k % static_cast<std::size_t>(dim);
    }
    block_size_ = comm_->any(!whole) ? 1 : dim;
  }

  void assemble(const Model& m, const DofMap& d, const StaticSystem& s, MPI_Comm mpi) {
    const auto n = static_cast<PetscInt>(owned_unknowns_.size());
    std::vector<PetscInt> diagonal(owned_unknowns_.size()), off(owned_unknowns_.size());
    for (std::size_t k = 0; k < owned_unknowns_.size(); ++k) {
      const std::size_t r = owned_unknowns_[k];
      for (int q = s.row_offsets[r]; q < s.row_offsets[r + 1]; ++q) {
        const PetscInt col = row_of_unknown_[static_cast<std::size_t>(s.columns[q])];
        if (col < 0) { // PETSc would drop the entry silently
          throw std::logic_error("distributed static solve: a column's unknown has no owner");
        }
        ++((col >= first_row_ && col < first_row_ + n) ? diagonal[k] : off[k]);
      }
    }
    check(MatCreate(mpi, &matrix_), "MatCreate");
    check(MatSetSizes(matrix_, n, n, PETSC_DETERMINE, PETSC_DETERMINE), "MatSetSizes");
    check(MatSetBlockSize(matrix_, block_size_), "MatSetBlockSize");
    check(MatSetType(matrix_, MATAIJ), "MatSetType");
    check(MatSeqAIJSetPreallocation(matrix_, 0, diagonal.data()), "MatSeqAIJSetPreallocation");
    check(MatMPIAIJSetPreallocation(matrix_, 0, diagonal.data(), 0, off.data()),
          "MatMPIAIJSetPreallocation");
    std::vector<PetscInt> columns;
    for (std::size_t k = 0; k < owned_unknowns_.size(); ++k) {
      const std::size_t r = owned_unknowns_[k];
      columns.clear();
      for (int q = s.row_offsets[r]; q < s.row_offsets[r + 1]; ++q) {
        columns.push_back(row_of_unknown_[static_cast<std::size_t>(s.columns[q])]);
      }
      const PetscInt row = first_row_ + static_cast<PetscInt>(k);
      check(MatSetValues(matrix_, 1, &row, static_cast<PetscInt>(columns.size()), columns.data(),
                         s.values.data() + s.row_offsets[r], INSERT_VALUES),
            "MatSetValues");
    }
    check(MatAssemblyBegin(matrix_, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
    check(MatAssemblyEnd(matrix_, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
    if (block_size_ > 1) {
      set_rigid_body_modes(m, d, mpi);
    }
  }

  /// GAMG's near-null space: the rigid motions (translations and rotations about the reference
  /// positions), which smoothed aggregation must represent on every level for an elastic body.
  void set_rigid_body_modes(const Model& m, const DofMap& d, MPI_Comm mpi) {
    Vec coordinates = nullptr;
    check(VecCreateMPI(mpi, static_cast<PetscInt>(owned_unknowns_.size()), PETSC_DETERMINE,
                       &coordinates),
          "VecCreateMPI");
    check(VecSetBlockSize(coordinates, block_size_), "VecSetBlockSize");
    PetscScalar* p = nullptr;
    check(VecGetArray(coordinates, &p), "VecGetArray");
    for (std::size_t k = 0; k < owned_unknowns_.size(); ++k) {
      const std::size_t g = d.free_dofs[owned_unknowns_[k]];
      p[k] = m.particles.position[g / 3][g % 3];
    }
    check(VecRestoreArray(coordinates, &p), "VecRestoreArray");
    MatNullSpace modes = nullptr;
    check(MatNullSpaceCreateRigidBody(coordinates, &modes), "MatNullSpaceCreateRigidBody");
    check(MatSetNearNullSpace(matrix_, modes), "MatSetNearNullSpace");
    MatNullSpaceDestroy(&modes);
    VecDestroy(&coordinates);
  }

  /// Each iteration: a stop requested on any rank ends the solve on all of them together (an
  /// allreduce of one integer, small beside the iteration's own reductions).
  static PetscErrorCode monitor(KSP, PetscInt, PetscReal, void* self) {
    auto* s = static_cast<PetscAmgSolve*>(self);
    if (s->stop_ && s->comm_->any(s->stop_())) {
      s->stopped_ = true;
      return PETSC_ERR_USER;
    }
    return 0;
  }

  std::function<bool()> stop_;
  const Communicator* comm_;
  Mat matrix_ = nullptr;
  KSP ksp_ = nullptr;
  std::vector<std::size_t> owned_unknowns_; ///< d's index of each owned unknown
  std::vector<PetscInt> row_of_unknown_;    ///< per unknown of d (owned or halo): its row
  PetscInt first_row_ = 0;
  int block_size_ = 1;
  double setup_seconds_ = 0;
  mutable std::size_t iterations_ = 0, solves_ = 0;
  mutable bool stopped_ = false;
};

} // namespace

bool have_distributed_solver() {
  return true;
}

std::unique_ptr<SparseFactorisation> distributed_solver(const Model& m, const DofMap& d,
                                                        const StaticSystem& system,
                                                        double relative_tolerance,
                                                        std::function<bool()> stop) {
  return std::make_unique<PetscAmgSolve>(m, d, system, relative_tolerance, std::move(stop));
}

#endif

} // namespace pd
