// pd-fem --scene: the linear-elastic continuum problem of a libpd scene (scene_problem.h) solved
// with deal.II on a sequence of refined meshes, with Richardson extrapolation per probe.
#pragma once

#include "scene_problem.h"

#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/fe_system.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping.h>
#include <deal.II/grid/tria.h>
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>
#include <deal.II/lac/vector.h>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace pdfem {
using namespace dealii;

struct SceneOptions {
  unsigned int levels = 0; // 0: as many as fit the default budget (at least 3)
  bool coarse = false;     // 3 levels: a quick run for the tests
  bool gmsh = false;       // mesh with Gmsh even if every shape is a box
  std::filesystem::path output_directory;
};

struct SceneLevel {
  unsigned int cells = 0;
  types::global_dof_index dofs = 0;
  double h = 0.;              // target cell size of the level, m
  double seconds = 0.;        // wall time of the level
  std::string solver;         // solver_summary: how K u = f was solved
  std::vector<double> values; // one per probe
};

// Solve the scene's problem in its dimension and write fe.json into the output directory;
// returns the levels (each with one value per probe).
std::vector<SceneLevel> solve_scene(const SceneProblem& problem, const SceneOptions& options);

template <int dim>
class SceneReference {
public:
  SceneReference(const SceneProblem& problem, const SceneOptions& options);
  // Solve on the levels, then write fe.json.
  std::vector<SceneLevel> run();

private:
  void make_grid(unsigned int level);
  void setup_system();
  void assemble_system();
  void solve();
  void evaluate_probes();
  void output_results(double wall_time) const;

  unsigned int choose_levels() const;
  double budget() const;
  void mesh(double h0, unsigned int level);
  void measure_loads();
  unsigned int load_subdivisions(const typename DoFHandler<dim>::active_cell_iterator& cell) const;
  // Calls add(x, JxW) at the points of the quadrature that integrates the loads over `cell`.
  template <class Add>
  void load_quadrature(const typename DoFHandler<dim>::active_cell_iterator& cell,
                       FEValues<dim>& fe_values, UpdateFlags flags, Add&& add) const;
  void add_pressure(const typename DoFHandler<dim>::active_cell_iterator& cell,
                    Vector<double>& cell_rhs) const;
  void cell_system(const typename DoFHandler<dim>::active_cell_iterator& cell,
                   FEValues<dim>& fe_values, FullMatrix<double>& cell_matrix,
                   Vector<double>& cell_rhs) const;
  double reaction(const SceneProbe& probe) const;
  // The stress σ = λ tr ε I + 2 μ ε of the body's material at x, all 3×3 components.
  std::array<std::array<double, 3>, 3> stress(const pd::Vec3& x,
                                              const std::vector<Tensor<1, dim>>& grad) const;
  void pin_rigid_motion(std::map<types::global_dof_index, double>& value) const;
  void require_balanced_loads() const;
  void remove_rigid_motion();

  const SceneProblem& problem;
  const SceneOptions options;

  // Does load l act at x, a point of `cell` (its lattice cells; on a mesh body the elements
  // the cell was refined from)?
  bool load_acts(std::size_t l, const typename DoFHandler<dim>::active_cell_iterator& cell,
                 const pd::Vec3& x) const;

  Triangulation<dim> triangulation;
  const bool on_mesh_body; // the scene's body is a mesh: simplices refined from its elements
  const FESystem<dim> fe;
  const Quadrature<dim> quadrature; // of the cells' integrals: Gauss, degree + 1 points per axis
  const bool use_gmsh;
  std::unique_ptr<Mapping<dim>> mapping;
  std::unique_ptr<DoFHandler<dim>> dof_handler;
  AffineConstraints<double> constraints;
  std::vector<unsigned int> component; // of each local shape function
  std::vector<types::global_dof_index> dof_component;
  std::vector<Point<dim>> dof_points; // support point of each dof
  // No support holds the body: its rigid motion is pinned, then removed (pin_rigid_motion).
  bool free_body = false;

  TrilinosWrappers::SparseMatrix system_matrix;
  TrilinosWrappers::MPI::Vector system_rhs;
  Vector<double> solution;

  double base_size = 0.; // target cell size of level 0
  // Per support: the dofs it constrains (a reaction probe sums the residual over them).
  std::vector<std::vector<types::global_dof_index>> support_dofs;
  // Per load: force density [N/m³] on its cells on this level's mesh.
  std::vector<Tensor<1, dim>> load_density;
  std::vector<SceneLevel> levels;
  std::vector<long> cell_element; // mesh body: per active cell, the element it was refined from
  std::string stopped_for_memory; // why refinement stopped before the levels asked for
};
} // namespace pdfem
