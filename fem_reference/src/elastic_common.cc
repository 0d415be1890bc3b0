#include "elastic_common.h"

#include <Epetra_CrsMatrix.h>
#include <Epetra_MultiVector.h>
#include <Teuchos_ParameterList.hpp>
#include <libpd/time/sparse_cholesky.hpp>
#include <algorithm>
#include <chrono>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/mapping_q1.h>
#include <deal.II/lac/solver_cg.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/trilinos_precondition.h>
#include <memory>
#include <vector>

namespace pdfem {
namespace {
double seconds_since(const std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Why: aggregation-based AMG for elasticity needs the near null space of the operator, the
// rigid-body modes, in 3D the six
//   translations  (1,0,0), (0,1,0), (0,0,1)
//   rotations     (0,-z,y), (z,0,-x), (-y,x,0)   (about `centre`),
// in 2D the three (1,0), (0,1), (-y,x), evaluated at the support point of every dof. deal.II 9.4
// has no DoFTools::extract_rigid_body_modes and AdditionalData::constant_modes only takes 0/1
// masks, so the real-valued modes go to ML through the Teuchos parameter list.
template <int dim>
void initialize_amg(const DoFHandler<dim>& dof_handler,
                    const TrilinosWrappers::SparseMatrix& system_matrix, const Point<dim>& centre,
                    TrilinosWrappers::PreconditionAMG& amg) {
  const auto n = dof_handler.n_dofs();
  const auto& fe = dof_handler.get_fe();
  std::vector<Point<dim>> support_points(n);
  // Simplices (mesh bodies) have no MappingQ1: their own linear mapping.
  if (fe.reference_cell().is_hyper_cube())
    DoFTools::map_dofs_to_support_points(MappingQ1<dim>(), dof_handler, support_points);
  else
    DoFTools::map_dofs_to_support_points(
        fe.reference_cell().template get_default_linear_mapping<dim, dim>(), dof_handler,
        support_points);
  std::vector<unsigned int> dof_component(n, 0);
  std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
  for (const auto& cell : dof_handler.active_cell_iterators()) {
    cell->get_dof_indices(dofs);
    for (unsigned int i = 0; i < dofs.size(); ++i)
      dof_component[dofs[i]] = fe.system_to_component_index(i).first;
  }

  TrilinosWrappers::PreconditionAMG::AdditionalData data;
  data.elliptic = true;
  data.higher_order_elements = (fe.degree > 1);
  data.smoother_sweeps = 2;
  data.aggregation_threshold = 1e-4;
  Teuchos::ParameterList parameter_list;
  std::unique_ptr<Epetra_MultiVector> unused_modes;
  data.set_parameters(parameter_list, unused_modes, system_matrix);

  const int n_modes = dim == 2 ? 3 : 6;
  Epetra_MultiVector modes(system_matrix.trilinos_matrix().DomainMap(), n_modes);
  for (types::global_dof_index i = 0; i < n; ++i) {
    const int li = static_cast<int>(i); // serial: local = global
    const unsigned int c = dof_component[i];
    const Tensor<1, dim> r = support_points[i] - centre;
    modes[c][li] = 1.;
    if constexpr (dim == 2) {
      const double rot[2] = {-r[1], r[0]};
      modes[2][li] = rot[c];
    } else {
      // rotation about x: (0,-z,y); about y: (z,0,-x); about z: (-y,x,0)
      const double rot[3][3] = {{0., -r[2], r[1]}, {r[2], 0., -r[0]}, {-r[1], r[0], 0.}};
      for (unsigned int k = 0; k < 3; ++k)
        modes[3 + k][li] = rot[k][c];
    }
  }
  parameter_list.set("PDE equations", dim);
  parameter_list.set("null space: type", "pre-computed");
  parameter_list.set("null space: dimension", n_modes);
  parameter_list.set("null space: vectors", modes.Values());
  amg.initialize(system_matrix, parameter_list);
}

// The lower triangle of the assembled stiffness (all that a symmetric factorisation reads). Read
// through Epetra's row views: deal.II's matrix iterators copy each row, which took longer than the
// factorisation.
std::vector<pd::LowerEntry> lower_triangle(const TrilinosWrappers::SparseMatrix& matrix) {
  const Epetra_CrsMatrix& crs = matrix.trilinos_matrix();
  std::vector<pd::LowerEntry> entries;
  entries.reserve(static_cast<std::size_t>(crs.NumMyNonzeros() / 2 + crs.NumMyRows()));
  for (int row = 0; row < crs.NumMyRows(); ++row) {
    int n = 0;
    double* values = nullptr;
    int* columns = nullptr;
    crs.ExtractMyRowView(row, n, values, columns);
    for (int k = 0; k < n; ++k) {
      const int column = crs.GCID(columns[k]); // serial: global = local row index
      if (column <= row)
        entries.push_back({static_cast<std::size_t>(row), static_cast<std::size_t>(column),
                           values[k]});
    }
  }
  return entries;
}

// x = K⁻¹ b by libpd's sparse Cholesky; false (and x untouched) if K is not positive definite.
bool solve_direct(const TrilinosWrappers::SparseMatrix& system_matrix,
                  const TrilinosWrappers::MPI::Vector& system_rhs,
                  TrilinosWrappers::MPI::Vector& x, CgStatistics& stats) {
  const auto n = static_cast<std::size_t>(system_rhs.locally_owned_size());
  std::unique_ptr<pd::SparseCholesky> factor;
  try {
    factor = std::make_unique<pd::SparseCholesky>(n, lower_triangle(system_matrix));
  } catch (const std::runtime_error&) {
    return false;
  }
  const std::vector<double> solution = factor->solve({system_rhs.begin(), n});
  std::copy(solution.begin(), solution.end(), x.begin());
  stats.solver = factor->name();
  stats.factor_bytes = factor->factor_bytes();
  return true;
}
} // namespace

std::string solver_summary(const CgStatistics& stats) {
  if (stats.factor_bytes > 0)
    return stats.solver + ", factor " + std::to_string(stats.factor_bytes >> 20) + " MB";
  return std::to_string(stats.iterations) + " CG its (" + stats.solver + ")";
}

LameConstants lame_constants(const double E, const double nu, const bool plane_stress) {
  const double lambda = E * nu / ((1. + nu) * (1. - 2. * nu));
  const double mu = E / (2. * (1. + nu));
  return {plane_stress ? 2. * lambda * mu / (lambda + 2. * mu) : lambda, mu};
}

template <int dim>
void add_elastic_cell_matrix(const FEValues<dim>& fv, const std::vector<unsigned int>& component,
                             const LameConstants& lame, std::vector<Tensor<1, dim>>& grad,
                             FullMatrix<double>& cell_matrix) {
  const unsigned int n = fv.get_fe().n_dofs_per_cell();
  grad.resize(n);
  for (const unsigned int q : fv.quadrature_point_indices()) {
    for (unsigned int i = 0; i < n; ++i)
      grad[i] = fv.shape_grad_component(i, q, component[i]);
    const double JxW = fv.JxW(q);
    for (unsigned int i = 0; i < n; ++i) {
      const unsigned int ci = component[i];
      const Tensor<1, dim>& gi = grad[i];
      for (unsigned int j = 0; j <= i; ++j) {
        const unsigned int cj = component[j];
        const Tensor<1, dim>& gj = grad[j];
        double a = lame.lambda * gi[ci] * gj[cj] + lame.mu * gi[cj] * gj[ci];
        if (ci == cj)
          a += lame.mu * (gi * gj);
        cell_matrix(i, j) += a * JxW;
      }
    }
  }
  for (unsigned int i = 0; i < n; ++i)
    for (unsigned int j = i + 1; j < n; ++j)
      cell_matrix(i, j) = cell_matrix(j, i);
}

// Why: the stiffness matrix is symmetric positive definite once the supported dofs are
// eliminated. Up to direct_solver_max_dofs unknowns it is factored (sparse Cholesky, CHOLMOD):
// ML's smoothed aggregation needed 230-280 CG iterations to 1e-10 on the slender and notched
// scenes (Q2, 4e4-9e4 unknowns: 19 s and 37 s on one core), which the factor solves in 3.8 s and
// 8.3 s, exactly to round-off (the plate's gold-file levels agree to 1.6e-12). Beyond, CG: its
// iteration count grows like sqrt(cond(A)) ~ 1/h for SSOR, so the larger levels are
// preconditioned with smoothed-aggregation AMG (Trilinos ML).
template <int dim>
CgStatistics solve_elasticity(const DoFHandler<dim>& dof_handler,
                              const TrilinosWrappers::SparseMatrix& system_matrix,
                              const TrilinosWrappers::MPI::Vector& system_rhs,
                              const AffineConstraints<double>& constraints,
                              const Point<dim>& centre, const std::string& preconditioner,
                              const double relative_tolerance, const unsigned int max_iterations,
                              Vector<double>& solution) {
  const auto t0 = std::chrono::steady_clock::now();
  CgStatistics stats;
  TrilinosWrappers::MPI::Vector x(complete_index_set(dof_handler.n_dofs()), MPI_COMM_WORLD);
  if (dof_handler.n_dofs() <= direct_solver_max_dofs(dim) &&
      solve_direct(system_matrix, system_rhs, x, stats)) {
    constraints.distribute(x);
    solution = Vector<double>(x);
    stats.solve_time = seconds_since(t0);
    return stats;
  }
  SolverControl solver_control(max_iterations, relative_tolerance * system_rhs.l2_norm());
  SolverCG<TrilinosWrappers::MPI::Vector> cg(solver_control);
  stats.solver = "CG, " + preconditioner;
  if (preconditioner == "AMG") {
    TrilinosWrappers::PreconditionAMG amg;
    initialize_amg(dof_handler, system_matrix, centre, amg);
    stats.preconditioner_time = seconds_since(t0);
    cg.solve(system_matrix, x, system_rhs, amg);
  } else {
    TrilinosWrappers::PreconditionSSOR ssor;
    ssor.initialize(system_matrix, TrilinosWrappers::PreconditionSSOR::AdditionalData(1.2));
    stats.preconditioner_time = seconds_since(t0);
    cg.solve(system_matrix, x, system_rhs, ssor);
  }
  constraints.distribute(x);
  solution = Vector<double>(x);
  stats.iterations = solver_control.last_step();
  stats.solve_time = seconds_since(t0);
  return stats;
}

template void add_elastic_cell_matrix<2>(const FEValues<2>&, const std::vector<unsigned int>&,
                                         const LameConstants&, std::vector<Tensor<1, 2>>&,
                                         FullMatrix<double>&);
template void add_elastic_cell_matrix<3>(const FEValues<3>&, const std::vector<unsigned int>&,
                                         const LameConstants&, std::vector<Tensor<1, 3>>&,
                                         FullMatrix<double>&);
template CgStatistics
solve_elasticity<2>(const DoFHandler<2>&, const TrilinosWrappers::SparseMatrix&,
                    const TrilinosWrappers::MPI::Vector&, const AffineConstraints<double>&,
                    const Point<2>&, const std::string&, double, unsigned int, Vector<double>&);
template CgStatistics
solve_elasticity<3>(const DoFHandler<3>&, const TrilinosWrappers::SparseMatrix&,
                    const TrilinosWrappers::MPI::Vector&, const AffineConstraints<double>&,
                    const Point<3>&, const std::string&, double, unsigned int, Vector<double>&);
} // namespace pdfem
