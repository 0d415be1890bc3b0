// The PETSc plug-in (time/petsc_plugin.h): CG preconditioned by GAMG on a stiffness split over
// ranks (distributed_solve.hpp). A module of its own, loaded by time/distributed_solve.cpp on the
// first split static solve, so that libpd and the programs linking it do not load PETSc at
// start-up. It calls nothing compiled into libpd.
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
#include "petsc_plugin.h"

#include <cstdio>
#include <exception>
#include <fmt/format.h>
#include <memory>
#include <petscksp.h>
#include <stdexcept>
#include <vector>

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

class PetscAmgSolve {
public:
  explicit PetscAmgSolve(const pd_petsc_system& s)
      : stop_(s.stop), stop_context_(s.stop_context), owned_(s.owned),
        first_row_(static_cast<PetscInt>(s.first_row)), block_size_(s.block_size) {
    initialise_petsc(s.comm);
    assemble(s);
    check(KSPCreate(s.comm, &ksp_), "KSPCreate");
    check(KSPSetOperators(ksp_, matrix_, matrix_), "KSPSetOperators");
    check(KSPSetType(ksp_, KSPCG), "KSPSetType");
    PC pc = nullptr;
    check(KSPGetPC(ksp_, &pc), "KSPGetPC");
    check(PCSetType(pc, PCGAMG), "PCSetType");
    check(KSPSetTolerances(ksp_, s.relative_tolerance, 0.0, PETSC_DEFAULT, max_iterations),
          "KSPSetTolerances");
    check(KSPSetNormType(ksp_, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType");
    check(KSPMonitorSet(ksp_, &PetscAmgSolve::monitor, this, nullptr), "KSPMonitorSet");
    // Options prefixed pd_static_ (PETSC_OPTIONS, e.g. -pd_static_ksp_view) tune it further.
    check(KSPSetOptionsPrefix(ksp_, "pd_static_"), "KSPSetOptionsPrefix");
    check(KSPSetFromOptions(ksp_), "KSPSetFromOptions");
    check(KSPSetUp(ksp_), "KSPSetUp");
  }

  ~PetscAmgSolve() {
    KSPDestroy(&ksp_);
    MatDestroy(&matrix_);
  }
  PetscAmgSolve(const PetscAmgSolve&) = delete;
  PetscAmgSolve& operator=(const PetscAmgSolve&) = delete;

  /// false: a stop request ended the solve.
  bool solve(const double* b, double* x_out, int& reason_out, long long& iterations_out) {
    Vec rhs = nullptr, x = nullptr;
    check(MatCreateVecs(matrix_, &x, &rhs), "MatCreateVecs");
    PetscScalar* p = nullptr;
    check(VecGetArray(rhs, &p), "VecGetArray");
    for (std::size_t k = 0; k < owned_; ++k) {
      p[k] = b[k];
    }
    check(VecRestoreArray(rhs, &p), "VecRestoreArray");
    // A monitor's error would be printed with a traceback; a stop request is not an error.
    check(PetscPushErrorHandler(PetscReturnErrorHandler, nullptr), "PetscPushErrorHandler");
    const PetscErrorCode code = KSPSolve(ksp_, rhs, x);
    PetscPopErrorHandler();
    if (stopped_) {
      VecDestroy(&rhs);
      VecDestroy(&x);
      return false;
    }
    check(code, "KSPSolve");
    KSPConvergedReason reason{};
    PetscInt iterations = 0;
    KSPGetConvergedReason(ksp_, &reason);
    KSPGetIterationNumber(ksp_, &iterations);
    const PetscScalar* xs = nullptr;
    check(VecGetArrayRead(x, &xs), "VecGetArrayRead");
    for (std::size_t k = 0; k < owned_; ++k) {
      x_out[k] = xs[k];
    }
    check(VecRestoreArrayRead(x, &xs), "VecRestoreArrayRead");
    VecDestroy(&rhs);
    VecDestroy(&x);
    reason_out = static_cast<int>(reason);
    iterations_out = static_cast<long long>(iterations);
    return true;
  }

private:
  static constexpr PetscInt max_iterations = 10000;

  void assemble(const pd_petsc_system& s) {
    const auto n = static_cast<PetscInt>(owned_);
    std::vector<PetscInt> diagonal(owned_), off(owned_);
    for (std::size_t k = 0; k < owned_; ++k) {
      const std::size_t r = s.owned_unknown[k];
      for (int q = s.row_offsets[r]; q < s.row_offsets[r + 1]; ++q) {
        const PetscInt col = s.row_of_unknown[static_cast<std::size_t>(s.columns[q])];
        ++((col >= first_row_ && col < first_row_ + n) ? diagonal[k] : off[k]);
      }
    }
    check(MatCreate(s.comm, &matrix_), "MatCreate");
    check(MatSetSizes(matrix_, n, n, PETSC_DETERMINE, PETSC_DETERMINE), "MatSetSizes");
    check(MatSetBlockSize(matrix_, block_size_), "MatSetBlockSize");
    check(MatSetType(matrix_, MATAIJ), "MatSetType");
    check(MatSeqAIJSetPreallocation(matrix_, 0, diagonal.data()), "MatSeqAIJSetPreallocation");
    check(MatMPIAIJSetPreallocation(matrix_, 0, diagonal.data(), 0, off.data()),
          "MatMPIAIJSetPreallocation");
    std::vector<PetscInt> columns;
    for (std::size_t k = 0; k < owned_; ++k) {
      const std::size_t r = s.owned_unknown[k];
      columns.clear();
      for (int q = s.row_offsets[r]; q < s.row_offsets[r + 1]; ++q) {
        columns.push_back(s.row_of_unknown[static_cast<std::size_t>(s.columns[q])]);
      }
      const PetscInt row = first_row_ + static_cast<PetscInt>(k);
      check(MatSetValues(matrix_, 1, &row, static_cast<PetscInt>(columns.size()), columns.data(),
                         s.values + s.row_offsets[r], INSERT_VALUES),
            "MatSetValues");
    }
    check(MatAssemblyBegin(matrix_, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
    check(MatAssemblyEnd(matrix_, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
    if (block_size_ > 1) {
      set_rigid_body_modes(s);
    }
  }

  /// GAMG's near-null space: the rigid motions (translations and rotations about the reference
  /// positions), which smoothed aggregation must represent on every level for an elastic body.
  void set_rigid_body_modes(const pd_petsc_system& s) {
    Vec coordinates = nullptr;
    check(VecCreateMPI(s.comm, static_cast<PetscInt>(owned_), PETSC_DETERMINE, &coordinates),
          "VecCreateMPI");
    check(VecSetBlockSize(coordinates, block_size_), "VecSetBlockSize");
    PetscScalar* p = nullptr;
    check(VecGetArray(coordinates, &p), "VecGetArray");
    for (std::size_t k = 0; k < owned_; ++k) {
      p[k] = s.coordinate[k];
    }
    check(VecRestoreArray(coordinates, &p), "VecRestoreArray");
    MatNullSpace modes = nullptr;
    check(MatNullSpaceCreateRigidBody(coordinates, &modes), "MatNullSpaceCreateRigidBody");
    check(MatSetNearNullSpace(matrix_, modes), "MatSetNearNullSpace");
    MatNullSpaceDestroy(&modes);
    VecDestroy(&coordinates);
  }

  /// Each iteration: a stop requested on any rank ends the solve on all of them together (libpd's
  /// callback reduces over the ranks).
  static PetscErrorCode monitor(KSP, PetscInt, PetscReal, void* self) {
    auto* s = static_cast<PetscAmgSolve*>(self);
    if (s->stop_ && s->stop_(s->stop_context_) != 0) {
      s->stopped_ = true;
      return PETSC_ERR_USER;
    }
    return 0;
  }

  int (*stop_)(void*);
  void* stop_context_;
  std::size_t owned_;
  PetscInt first_row_;
  int block_size_;
  Mat matrix_ = nullptr;
  KSP ksp_ = nullptr;
  bool stopped_ = false;
};

void copy_error(const char* what, char* error, std::size_t size) {
  if (error && size > 0) {
    std::snprintf(error, size, "%s", what);
  }
}

void* create(const pd_petsc_system* system, char* error, std::size_t error_size) {
  try {
    return new PetscAmgSolve(*system);
  } catch (const std::exception& e) {
    copy_error(e.what(), error, error_size);
  } catch (...) {
    copy_error("PETSc plug-in: unknown error", error, error_size);
  }
  return nullptr;
}

int solve(void* solver, const double* b, double* x, int* reason, long long* iterations, char* error,
          std::size_t error_size) {
  try {
    return static_cast<PetscAmgSolve*>(solver)->solve(b, x, *reason, *iterations)
               ? pd_petsc_ok
               : pd_petsc_stopped;
  } catch (const std::exception& e) {
    copy_error(e.what(), error, error_size);
  } catch (...) {
    copy_error("PETSc plug-in: unknown error", error, error_size);
  }
  return pd_petsc_failed;
}

void destroy(void* solver) {
  delete static_cast<PetscAmgSolve*>(solver);
}

} // namespace

extern "C" __attribute__((visibility("default"))) const pd_petsc_plugin* libpd_petsc_plugin() {
  static const pd_petsc_plugin table{pd_petsc_plugin_version, create, solve, destroy};
  return &table;
}
