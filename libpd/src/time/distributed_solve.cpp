// Distributed linear solves of the static solver (distributed_solve.hpp): PETSc, CG + GAMG, in a
// plug-in (time/distributed_solve_petsc.cpp, loaded on the first split static solve, so that
// runs without one do not load PETSc). This side numbers the rows, which needs the model and its
// communicator; the plug-in assembles and solves.
#include "distributed_solve.hpp"

#include "libpd/core/exact_sum.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <stdexcept>

#ifdef LIBPD_HAVE_PETSC
#include "libpd/core/plugin.hpp"
#include "petsc_plugin.h"

#include <exception>
#include <utility>
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

const pd_petsc_plugin& plugin() {
  return *static_cast<const pd_petsc_plugin*>(
      load_plugin({"static solves on several MPI ranks (PETSc)", pd_petsc_plugin_module,
                   pd_petsc_plugin_entry, pd_petsc_plugin_version}));
}

class PetscAmgSolve final : public SparseFactorisation {
public:
  PetscAmgSolve(const Model& m, const DofMap& d, const StaticSystem& system, double rtol,
                std::function<bool()> stop)
      : stop_(std::move(stop)), comm_(&m.ownership.communicator()) {
    const pd_petsc_plugin& petsc = plugin();
    const MPI_Comm mpi = *static_cast<const MPI_Comm*>(comm_->native());
    const auto t0 = std::chrono::steady_clock::now();
    number_unknowns(m, d, mpi);
    check_columns(system);
    std::vector<double> coordinate(owned_unknowns_.size());
    for (std::size_t k = 0; k < owned_unknowns_.size(); ++k) {
      const std::size_t g = d.free_dofs[owned_unknowns_[k]];
      coordinate[k] = m.particles.position[g / 3][g % 3];
    }
    const pd_petsc_system s{mpi,
                            owned_unknowns_.size(),
                            first_row_,
                            owned_unknowns_.data(),
                            system.row_offsets.data(),
                            system.columns.data(),
                            system.values.data(),
                            row_of_unknown_.data(),
                            coordinate.data(),
                            block_size_,
                            rtol,
                            stop_ ? &PetscAmgSolve::poll_stop : nullptr,
                            this};
    char error[512] = "";
    solver_ = petsc.create(&s, error, sizeof error);
    rethrow_stop_failure();
    if (!solver_) {
      throw std::runtime_error(error);
    }
    destroy_ = petsc.destroy;
    solve_ = petsc.solve;
    setup_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

  ~PetscAmgSolve() override { destroy_(solver_); }
  PetscAmgSolve(const PetscAmgSolve&) = delete;
  PetscAmgSolve& operator=(const PetscAmgSolve&) = delete;

  Eigen::VectorXd solve(const Eigen::VectorXd& b) const override {
    std::vector<double> rhs(owned_unknowns_.size()), x(owned_unknowns_.size());
    for (std::size_t k = 0; k < owned_unknowns_.size(); ++k) {
      rhs[k] = b[static_cast<Eigen::Index>(owned_unknowns_[k])];
    }
    int reason = 0;
    long long iterations = 0;
    char error[512] = "";
    const int status =
        solve_(solver_, rhs.data(), x.data(), &reason, &iterations, error, sizeof error);
    rethrow_stop_failure();
    if (status == pd_petsc_stopped) {
      throw StopRequested("a stop was requested during the distributed static solve");
    }
    if (status != pd_petsc_ok) {
      throw std::runtime_error(error);
    }
    iterations_ += static_cast<std::size_t>(iterations);
    ++solves_;
    Eigen::VectorXd out = Eigen::VectorXd::Zero(b.size());
    for (std::size_t k = 0; k < owned_unknowns_.size(); ++k) {
      out[static_cast<Eigen::Index>(owned_unknowns_[k])] = x[k];
    }
    if (reason < 0) {
      throw std::runtime_error(fmt::format(
          "static solve on {} ranks: CG with GAMG did not converge (KSP reason {}, {} iterations)",
          comm_->size(), reason, iterations));
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
    first_row_ = first;
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

  void check_columns(const StaticSystem& s) const {
    for (const std::size_t r : owned_unknowns_) {
      for (int q = s.row_offsets[r]; q < s.row_offsets[r + 1]; ++q) {
        if (row_of_unknown_[static_cast<std::size_t>(s.columns[q])] < 0) {
          // PETSc would drop the entry silently
          throw std::logic_error("distributed static solve: a column's unknown has no owner");
        }
      }
    }
  }

  /// The plug-in's stop poll: a stop requested on any rank ends the solve on all of them together
  /// (an allreduce of one integer, small beside the iteration's own reductions). An exception
  /// must not cross the plug-in: it stops the solve and is thrown again here.
  static int poll_stop(void* self) noexcept {
    auto* s = static_cast<const PetscAmgSolve*>(self);
    try {
      return s->comm_->any(s->stop_()) ? 1 : 0;
    } catch (...) {
      s->stop_failure_ = std::current_exception();
      return 1;
    }
  }

  void rethrow_stop_failure() const {
    if (stop_failure_) {
      std::rethrow_exception(std::exchange(stop_failure_, nullptr));
    }
  }

  std::function<bool()> stop_;
  const Communicator* comm_;
  void* solver_ = nullptr;
  void (*destroy_)(void*) = nullptr;
  int (*solve_)(void*, const double*, double*, int*, long long*, char*, std::size_t) = nullptr;
  std::vector<std::size_t> owned_unknowns_;  ///< d's index of each owned unknown
  std::vector<std::int32_t> row_of_unknown_; ///< per unknown of d (owned or halo): its row
  long long first_row_ = 0;
  int block_size_ = 1;
  double setup_seconds_ = 0;
  mutable std::size_t iterations_ = 0, solves_ = 0;
  mutable std::exception_ptr stop_failure_;
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
