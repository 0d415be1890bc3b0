// What both pd-fem solvers share (the .prm problems of elastic_reference.cc and the scenes of
// scene_reference.cc): the Lamé constants of 3D / plane strain / plane stress, the Q_p cell
// stiffness of small-strain isotropic elasticity, and CG preconditioned by smoothed-aggregation
// AMG with the rigid-body modes.
#pragma once

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>
#include <deal.II/lac/vector.h>
#include <string>
#include <vector>

namespace pdfem {
using namespace dealii;

struct LameConstants {
  double lambda = 0.; // λ, or λ* = 2λμ/(λ+2μ) = Eν/(1-ν²) in plane stress
  double mu = 0.;     // μ = G = E / (2(1+ν))
};

// Why: 3D and plane strain (ε_zz = 0) keep λ = Eν/((1+ν)(1-2ν)); plane stress (σ_zz = 0)
// eliminates ε_zz = -λ/(λ+2μ)(ε_xx+ε_yy), which leaves λ* = 2λμ/(λ+2μ) in its place.
LameConstants lame_constants(double youngs_modulus, double poisson_ratio, bool plane_stress);

// Add ∫ λ (div φ_i)(div φ_j) + 2μ ε(φ_i):ε(φ_j) dx over the quadrature points of `fv` (already
// reinit'ed on the cell) to `cell_matrix`. For the vector element every shape function φ_i has
// one non-zero component c_i = component[i], which gives (step-8)
//   A_ij = ∫ λ ∂_{c_i}φ_i ∂_{c_j}φ_j + μ ∂_{c_j}φ_i ∂_{c_i}φ_j + δ_{c_i c_j} μ ∇φ_i·∇φ_j dx.
// `grad` is scratch space.
template <int dim>
void add_elastic_cell_matrix(const FEValues<dim>& fv, const std::vector<unsigned int>& component,
                             const LameConstants& lame, std::vector<Tensor<1, dim>>& grad,
                             FullMatrix<double>& cell_matrix);

struct CgStatistics {
  std::string solver;              // "CHOLMOD supernodal LLT", "CG, AMG", ...
  unsigned int iterations = 0;     // CG iterations (0: factored)
  std::size_t factor_bytes = 0;    // the direct solver's factor
  double preconditioner_time = 0.; // s, AMG (or SSOR) setup
  double solve_time = 0.;          // s, setup + CG, or factorisation and solve
};

// "275 CG its (CG, AMG)" or "CHOLMOD supernodal LLT, factor 512 MB": the progress lines' words.
std::string solver_summary(const CgStatistics& stats);

// Unknowns up to which solve_elasticity factors K instead of iterating. The --coarse budgets
// (3D 6e4, 2D 1.5e5 unknowns on the finest level, overshot up to 1.6x by whole cells) stay below
// it. Measured on one core (Q2): the notched beam's 93,075 unknowns give a 546 MB factor, the
// plate's 85,995 a 410 MB one; a 3D factor grows like n^(4/3), a 2D one like n log n.
constexpr types::global_dof_index direct_solver_max_dofs(const int dim) {
  return dim == 3 ? 150'000 : 600'000;
}

// Solve K x = b: up to direct_solver_max_dofs(dim) unknowns by sparse Cholesky (CG if K is
// not positive definite), beyond by CG to the relative tolerance `relative_tolerance`·|b|,
// preconditioned by ML AMG with the rigid-body modes about `centre` (preconditioner "AMG") or
// SSOR ("SSOR"); then distribute the constraints into `solution`.
template <int dim>
CgStatistics solve_elasticity(const DoFHandler<dim>& dof_handler,
                              const TrilinosWrappers::SparseMatrix& system_matrix,
                              const TrilinosWrappers::MPI::Vector& system_rhs,
                              const AffineConstraints<double>& constraints,
                              const Point<dim>& centre, const std::string& preconditioner,
                              double relative_tolerance, unsigned int max_iterations,
                              Vector<double>& solution);
} // namespace pdfem
