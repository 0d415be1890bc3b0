// The 3D linear-elasticity reference solver of pd-fem and its parameters.
// See pd_fem.cc for the problem statement and usage.
#pragma once

#include "report.h"

#include <deal.II/base/parameter_handler.h>
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
#include <string>
#include <vector>

namespace pdfem {
using namespace dealii;

// Everything a .prm file can set.  declare() documents every entry;
// `pd-fem --print-parameters` prints them with their documentation.
struct Parameters {
  // Problem
  std::string name;
  std::string theory; // "clamped-clamped beam" | "cantilever beam" |
                      // "kirchhoff plate" | "none"
  // Geometry: the body is [0,length_x] x [0,width_y] x [0,thickness_z]
  double length_x = 0., width_y = 0., thickness_z = 0.;
  // Material
  double youngs_modulus = 0., poisson_ratio = 0.;
  // Load on the top face z = thickness_z, pointing in -z
  std::string load_kind; // "line load" | "pressure"
  double load_magnitude = 0.;
  // Boundary conditions: boundary ids (0..5 = x-,x+,y-,y+,z-,z+) clamped
  std::vector<unsigned int> clamped_faces;
  // Discretisation
  unsigned int degree = 2;
  double base_element_size = 0.;
  unsigned int n_levels = 3, n_coarse_levels = 3;
  // Solver
  std::string preconditioner; // "AMG" | "SSOR"
  double relative_tolerance = 1e-10;
  unsigned int max_iterations = 10000;
  // Output
  struct NamedPoint {
    std::string name;
    Point<3> point;
  };
  struct SampleLine {
    std::string name;
    Point<3> start, end;
    unsigned int n_points = 2;
  };
  std::vector<NamedPoint> quantities;
  std::vector<SampleLine> lines;
  bool write_vtu = true;

  // Traction magnitude on the top face (N/m^2): p/b for a line load p.
  double traction() const;
  // Load per unit length of span (N/m): q*b for a pressure q.
  double line_load() const;

  static void declare(ParameterHandler& prm);
  void parse(ParameterHandler& prm);
};

struct LevelResult {
  unsigned int level = 0;
  std::array<unsigned int, 3> subdivisions{};
  unsigned int cells = 0;
  types::global_dof_index dofs = 0;
  std::map<std::string, double> deflection; // positive downward (-u_z), m
  double setup_time = 0., assembly_time = 0., solve_time = 0., preconditioner_time = 0.,
         total_time = 0.;
  unsigned int iterations = 0;
};

struct QuantitySummary {
  std::string name;
  Point<3> point;
  double finest = 0.;    // value on the finest level
  Richardson richardson; // extrapolation from the last three levels
};

struct RunSummary {
  std::vector<LevelResult> levels;
  std::vector<QuantitySummary> quantities;
  double wall_time = 0.;
};

class ElasticReference {
public:
  ElasticReference(const Parameters& parameters, unsigned int n_levels,
                   const std::filesystem::path& output_directory);

  // Solve on n_levels globally refined meshes, then write the outputs.
  RunSummary run(const std::string& command_line, const std::string& parameters_json,
                 const std::string& parameters_prm);

private:
  void make_grid();
  void setup_system();
  void assemble_system();
  void solve();
  void evaluate_quantities();
  void output_results(const std::string& command_line, const std::string& parameters_json,
                      const std::string& parameters_prm);

  const Parameters prm;
  const unsigned int n_levels;
  const std::filesystem::path output_directory;

  Triangulation<3> triangulation;
  const FESystem<3> fe;
  DoFHandler<3> dof_handler;
  AffineConstraints<double> constraints;

  TrilinosWrappers::SparseMatrix system_matrix;
  TrilinosWrappers::MPI::Vector system_rhs;
  Vector<double> solution;

  std::array<unsigned int, 3> base_subdivisions{};
  RunSummary summary;
};
} // namespace pdfem
