// The linear-elasticity reference solver of pd-fem, in 3D and in 2D (plane stress / plane
// strain). See pd_fem.cc for the problem statement and usage, parameters.h for its inputs.
#pragma once

#include "classical_theory.h"
#include "parameters.h"
#include "report.h"

#include <deal.II/base/point.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/fe_system.h>
#include <deal.II/grid/tria.h>
#include <deal.II/lac/affine_constraints.h>
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

struct LevelResult {
  unsigned int level = 0;
  std::vector<unsigned int> subdivisions; // one per axis
  unsigned int multiplier = 1;            // subdivisions = base subdivisions x multiplier
  unsigned int cells = 0;
  types::global_dof_index dofs = 0;
  std::map<std::string, double> deflection; // positive downward (-u_z; 2D: -u_y), m
  double setup_time = 0., assembly_time = 0., solve_time = 0., preconditioner_time = 0.,
         total_time = 0.;
  unsigned int iterations = 0;
  std::string solver; // solver_summary: how K u = f was solved
};

struct RunSummary {
  std::vector<LevelResult> levels;
  std::vector<QuantitySummary> quantities;
  double wall_time = 0.;
};

// Solve the problem `parameters` describes in its dimension on n_levels globally refined meshes
// and write the outputs into output_directory.
RunSummary solve_reference(const Parameters& parameters, unsigned int n_levels,
                           const std::filesystem::path& output_directory,
                           const std::string& command_line, const std::string& parameters_json,
                           const std::string& parameters_prm);

template <int dim>
class ElasticReference {
public:
  ElasticReference(const Parameters& parameters, unsigned int n_levels,
                   const std::filesystem::path& output_directory);

  // Solve on n_levels globally refined meshes, then write the outputs.
  RunSummary run(const std::string& command_line, const std::string& parameters_json,
                 const std::string& parameters_prm);

private:
  void make_grid(unsigned int level);
  void grade(Triangulation<dim>& mesh, const std::vector<double>& extent) const;
  void setup_system();
  void assemble_system();
  void solve();
  void evaluate_quantities();
  void output_results(const std::string& command_line, const std::string& parameters_json,
                      const std::string& parameters_prm);
  void write_summary(const std::string& command_line, const std::string& parameters_json);

  const Parameters prm;
  const unsigned int n_levels;
  const std::filesystem::path output_directory;

  // A level's mesh is built afresh (make_grid), then the DoFHandler moves over to it before the
  // previous one is released: a Triangulation may not be cleared while a DoFHandler uses it.
  std::unique_ptr<Triangulation<dim>> triangulation;
  const FESystem<dim> fe;
  DoFHandler<dim> dof_handler;
  AffineConstraints<double> constraints;

  TrilinosWrappers::SparseMatrix system_matrix;
  TrilinosWrappers::MPI::Vector system_rhs;
  Vector<double> solution;

  std::vector<unsigned int> base_subdivisions;
  RunSummary summary;
};
} // namespace pdfem
