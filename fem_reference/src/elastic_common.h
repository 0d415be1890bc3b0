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
  unsigned int iterations = 0;
  double preconditioner_time = 0.; // s, AMG (or SSOR) setup
  double solve_time = 0.;          // s, setup + CG
};

// Solve K x = b by CG to the relative tolerance `relative_tolerance`·|b|, preconditioned by ML
// AMG with the rigid-body modes about `centre` (preconditioner "AMG") or SSOR ("SSOR"), then
// distribute the constraints into `solution`.
template <int dim>
CgStatistics solve_elasticity(const DoFHandler<dim>& dof_handler,
                              const TrilinosWrappers::SparseMatrix& system_matrix,
                              const TrilinosWrappers::MPI::Vector& system_rhs,
                              const AffineConstraints<double>& constraints,
                              const Point<dim>& centre, const std::string& preconditioner,
                              double relative_tolerance, unsigned int max_iterations,
                              Vector<double>& solution);
} // namespace pdfem
