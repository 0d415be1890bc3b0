// The static solve's linear solver on a model split over MPI ranks (time/static_solver.cpp),
// private to libpd: PETSc's conjugate gradients preconditioned by its algebraic multigrid (GAMG,
// smoothed aggregation) on the assembled stiffness, each rank holding the rows of the unknowns it
// owns. CHOLMOD factors the whole matrix in one process; that matrix does not split.
//
// A rank's model (discretisation/ownership.hpp) holds everything its owned particles' forces
// depend on, and a row of the reduced stiffness depends on exactly what the particle's force
// does (the linearisation of the same sum), so the rows of the owned unknowns are assembled from
// the local model alone (static_assembly.hpp); the halo's rows are incomplete and dropped. Rows
// and columns are numbered rank by rank, each rank's unknowns in their global order, so the
// matrix and the solve depend on the rank count only, never on timing.
#pragma once

#include "sparse_factorisation.hpp"
#include "static_assembly.hpp"

#include <Eigen/Core>
#include <functional>
#include <memory>

namespace pd {

/// Dot products and norms of vectors over a (local) DofMap's unknowns: over all of them in one
/// process, over the owned ones summed exactly over the ranks (core/exact_sum.hpp) in a split
/// model, so that every rank takes the same decisions.
class UnknownReductions {
public:
  UnknownReductions(const Model& m, const DofMap& d);
  double dot(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const;
  double norm(const Eigen::VectorXd& a) const;
  /// Eigen's isZero (every entry within 1e-12 of zero) over all the unknowns.
  bool is_zero(const Eigen::VectorXd& a) const;

private:
  const Model* model_;
  std::vector<std::uint8_t> owned_; ///< per unknown; empty: one process
};

/// Whether libpd was built with PETSc (LIBPD_HAVE_PETSC).
bool have_distributed_solver();

/// The solver of K x = b for the owned unknowns of `d` on a split model, K given by `system`
/// (assemble_reduced with RowPart::full on the local model). Its solve takes and returns vectors
/// over all of d's unknowns: it reads the owned entries and returns zero on the others (the halo
/// takes its owners' values when the constraints are applied). Each solve iterates until
/// ‖b − K x‖ ≤ relative_tolerance ‖b‖; `stop` is polled at every iteration on every rank and,
/// true on any, ends the solve with StopRequested. Collective over the model's communicator.
std::unique_ptr<SparseFactorisation> distributed_solver(const Model& m, const DofMap& d,
                                                        const StaticSystem& system,
                                                        double relative_tolerance,
                                                        std::function<bool()> stop);

/// Thrown by a distributed solve that a stop request ended.
struct StopRequested : std::runtime_error {
  using std::runtime_error::runtime_error;
};

} // namespace pd
