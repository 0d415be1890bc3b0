#include "elastic_reference.h"

#include "kirchhoff_plate.h"

#include <Epetra_MultiVector.h>
#include <Teuchos_ParameterList.hpp>
#include <chrono>
#include <cmath>
#include <deal.II/base/function.h>
#include <deal.II/base/multithread_info.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/base/utilities.h>
#include <deal.II/base/work_stream.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_q.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_q1.h>
#include <deal.II/grid/grid_generator.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/solver_cg.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/trilinos_precondition.h>
#include <deal.II/numerics/data_out.h>
#include <deal.II/numerics/fe_field_function.h>
#include <deal.II/numerics/vector_tools.h>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace pdfem {
namespace {
const char* const face_names = "x-|x+|y-|y+|z-|z+";

unsigned int face_id(const std::string& name) {
  const std::vector<std::string> names{"x-", "x+", "y-", "y+", "z-", "z+"};
  for (unsigned int i = 0; i < names.size(); ++i)
    if (names[i] == name)
      return i;
  throw std::runtime_error("unknown face '" + name + "'");
}

double seconds_since(const std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

Point<3> parse_point(const std::vector<double>& v, const std::size_t first) {
  return Point<3>(v.at(first), v.at(first + 1), v.at(first + 2));
}
} // namespace

// ---------------------------------------------------------------------
// Parameters
// ---------------------------------------------------------------------

double Parameters::traction() const {
  return load_kind == "line load" ? load_magnitude / width_y : load_magnitude;
}

double Parameters::line_load() const {
  return traction() * width_y;
}

void Parameters::declare(ParameterHandler& prm) {
  prm.enter_subsection("Problem");
  {
    prm.declare_entry("Name", "problem", Patterns::Anything(),
                      "Short name of the problem; names the default output "
                      "directory fem_reference/out/NAME and the summary.");
    prm.declare_entry(
        "Theory", "none",
        Patterns::Selection("clamped-clamped beam|cantilever beam|kirchhoff plate|none"),
        "Classical solution printed beside the FE result: Euler-Bernoulli "
        "and Timoshenko beam theory with span Length x, width Width y, depth "
        "Thickness z (clamped-clamped: midspan; cantilever: tip), or a "
        "Kirchhoff plate with the clamped faces x-, x+, y-, y+ as built-in "
        "edges and all other edges free (Rayleigh-Ritz series solution).");
  }
  prm.leave_subsection();

  prm.enter_subsection("Geometry");
  {
    prm.declare_entry("Length x", "3.5", Patterns::Double(0., 1e6),
                      "Extent of the body in x (span of a beam), in m. "
                      "The body is [0,Length x] x [0,Width y] x "
                      "[0,Thickness z]; gravity points in -z.");
    prm.declare_entry("Width y", "0.3", Patterns::Double(0., 1e6),
                      "Extent of the body in y (width b of a beam section), "
                      "in m.");
    prm.declare_entry("Thickness z", "0.4", Patterns::Double(0., 1e6),
                      "Extent of the body in z (depth h of a beam section, "
                      "thickness t of a plate), in m.");
  }
  prm.leave_subsection();

  prm.enter_subsection("Material");
  {
    prm.declare_entry("Young modulus", "20e9", Patterns::Double(0., 1e15),
                      "Young's modulus E of the isotropic linear elastic "
                      "material, in Pa.");
    prm.declare_entry("Poisson ratio", "0.25", Patterns::Double(-0.999, 0.499),
                      "Poisson's ratio nu (-1 < nu < 0.5).");
  }
  prm.leave_subsection();

  prm.enter_subsection("Load");
  {
    prm.declare_entry("Kind", "line load", Patterns::Selection("line load|pressure"),
                      "How Magnitude is to be read. 'line load': a load p "
                      "per unit length of x (N/m), applied as the uniform "
                      "traction p/(Width y) on the top face z = Thickness "
                      "z. 'pressure': a uniform traction q (N/m^2) on the "
                      "top face. The traction always points in -z.");
    prm.declare_entry("Magnitude", "1e4", Patterns::Double(0., 1e12),
                      "Magnitude of the load: N/m for a line load, N/m^2 "
                      "for a pressure.");
  }
  prm.leave_subsection();

  prm.enter_subsection("Boundary conditions");
  {
    prm.declare_entry("Clamped faces", "x-, x+",
                      Patterns::List(Patterns::Selection(face_names), 0, 6, ","),
                      "Comma separated list of the faces on which all three displacement "
                      "components are zero: x- (x=0), x+ (x=Length x), y- (y=0), y+ "
                      "(y=Width y), z- (z=0), z+ (z=Thickness z). All other faces are "
                      "traction free except the loaded top face.");
  }
  prm.leave_subsection();

  prm.enter_subsection("Discretisation");
  {
    prm.declare_entry("Finite element degree", "2", Patterns::Integer(1, 6),
                      "Polynomial degree p of the FE_Q^3 displacement "
                      "element. p = 1 locks in bending; use p >= 2.");
    prm.declare_entry("Base element size", "0.4", Patterns::Double(0., 1e6),
                      "Target edge length of the cells of the coarsest "
                      "mesh, in m. The number of subdivisions in each "
                      "direction is max(1, round(extent/size)), so cells "
                      "are nearly cubes. Each further level halves every "
                      "cell edge (global refinement).");
    prm.declare_entry("Number of levels", "4", Patterns::Integer(1, 8),
                      "Number of meshes of the reference run (level 0 is "
                      "the base mesh). Three or more are needed for the "
                      "Richardson error estimate.");
    prm.declare_entry("Coarse levels", "3", Patterns::Integer(1, 8),
                      "Number of meshes used with --coarse (quick tests).");
  }
  prm.leave_subsection();

  prm.enter_subsection("Solver");
  {
    prm.declare_entry("Preconditioner", "AMG", Patterns::Selection("AMG|SSOR"),
                      "Preconditioner of the conjugate gradient solver: "
                      "Trilinos ML smoothed-aggregation AMG with the six "
                      "rigid-body modes as near null space, or SSOR.");
    prm.declare_entry("Relative tolerance", "1e-10", Patterns::Double(0., 1.),
                      "CG stops when |b - A x| <= tolerance * |b|.");
    prm.declare_entry("Maximum iterations", "10000", Patterns::Integer(1),
                      "Maximum number of CG iterations.");
  }
  prm.leave_subsection();

  prm.enter_subsection("Output");
  {
    prm.declare_entry("Quantities of interest", "midspan: 1.75, 0.15, 0.2",
                      Patterns::Map(Patterns::Anything(),
                                    Patterns::List(Patterns::Double(), 3, 3, ","), 1,
                                    Patterns::Map::max_int_value, ";", ":"),
                      "Points at which the vertical deflection -u_z (positive downward) "
                      "is reported per level and extrapolated, as 'name: x, y, z' "
                      "entries separated by ';'.");
    prm.declare_entry("Sample lines", "centreline: 0, 0.15, 0.2, 3.5, 0.15, 0.2, 71",
                      Patterns::Map(Patterns::Anything(),
                                    Patterns::List(Patterns::Double(), 7, 7, ","), 0,
                                    Patterns::Map::max_int_value, ";", ":"),
                      "Straight lines along which the finest solution is sampled into "
                      "NAME.csv, as 'name: x0, y0, z0, x1, y1, z1, number of points' "
                      "entries separated by ';'.");
    prm.declare_entry("Write VTU", "true", Patterns::Bool(),
                      "Write solution.vtu (finest level, second order "
                      "Lagrange cells) for ParaView.");
  }
  prm.leave_subsection();
}

void Parameters::parse(ParameterHandler& p) {
  p.enter_subsection("Problem");
  name = p.get("Name");
  theory = p.get("Theory");
  p.leave_subsection();

  p.enter_subsection("Geometry");
  length_x = p.get_double("Length x");
  width_y = p.get_double("Width y");
  thickness_z = p.get_double("Thickness z");
  p.leave_subsection();

  p.enter_subsection("Material");
  youngs_modulus = p.get_double("Young modulus");
  poisson_ratio = p.get_double("Poisson ratio");
  p.leave_subsection();

  p.enter_subsection("Load");
  load_kind = p.get("Kind");
  load_magnitude = p.get_double("Magnitude");
  p.leave_subsection();

  p.enter_subsection("Boundary conditions");
  clamped_faces.clear();
  for (const auto& f : Utilities::split_string_list(p.get("Clamped faces")))
    clamped_faces.push_back(face_id(f));
  p.leave_subsection();

  p.enter_subsection("Discretisation");
  degree = static_cast<unsigned int>(p.get_integer("Finite element degree"));
  base_element_size = p.get_double("Base element size");
  n_levels = static_cast<unsigned int>(p.get_integer("Number of levels"));
  n_coarse_levels = static_cast<unsigned int>(p.get_integer("Coarse levels"));
  p.leave_subsection();

  p.enter_subsection("Solver");
  preconditioner = p.get("Preconditioner");
  relative_tolerance = p.get_double("Relative tolerance");
  max_iterations = static_cast<unsigned int>(p.get_integer("Maximum iterations"));
  p.leave_subsection();

  p.enter_subsection("Output");
  quantities.clear();
  for (const auto& entry : Utilities::split_string_list(p.get("Quantities of interest"), ';')) {
    const auto kv = Utilities::split_string_list(entry, ':');
    const auto v = Utilities::string_to_double(Utilities::split_string_list(kv.at(1), ','));
    quantities.push_back({kv.at(0), parse_point(v, 0)});
  }
  lines.clear();
  for (const auto& entry : Utilities::split_string_list(p.get("Sample lines"), ';')) {
    const auto kv = Utilities::split_string_list(entry, ':');
    const auto v = Utilities::string_to_double(Utilities::split_string_list(kv.at(1), ','));
    if (v.at(6) < 2.)
      throw std::runtime_error("sample line '" + kv.at(0) + "' needs at least 2 points");
    lines.push_back({kv.at(0), parse_point(v, 0), parse_point(v, 3),
                     static_cast<unsigned int>(std::lround(v.at(6)))});
  }
  write_vtu = p.get_bool("Write VTU");
  p.leave_subsection();

  if (clamped_faces.empty())
    throw std::runtime_error("Boundary conditions/Clamped faces is empty: the body would be free "
                             "to move as a rigid body and the problem singular.");
}

// ---------------------------------------------------------------------
// The solver
// ---------------------------------------------------------------------

ElasticReference::ElasticReference(const Parameters& parameters, const unsigned int levels,
                                   const std::filesystem::path& out_dir)
    : prm(parameters), n_levels(levels), output_directory(out_dir),
      fe(FE_Q<3>(parameters.degree), 3), dof_handler(triangulation) {}

// Why: the reference must be mesh-converged, which we demonstrate by a
// sequence of uniformly refined meshes with nearly cubic cells (aspect
// ratio close to 1 keeps the error constant of every level similar).  The
// base mesh has n_i = max(1, round(extent_i / h0)) cells per direction;
// each further level halves every edge, so h_{k+1} = h_k / 2 and the
// Richardson ratio is r = 2.  colorize = true numbers the faces
// 0..5 = x-, x+, y-, y+, z-, z+.
void ElasticReference::make_grid() {
  if (triangulation.n_active_cells() > 0) {
    triangulation.refine_global(1);
    return;
  }
  const std::array<double, 3> extent{prm.length_x, prm.width_y, prm.thickness_z};
  std::vector<unsigned int> repetitions(3);
  for (unsigned int d = 0; d < 3; ++d) {
    repetitions[d] =
        static_cast<unsigned int>(std::max(1L, std::lround(extent[d] / prm.base_element_size)));
    base_subdivisions[d] = repetitions[d];
  }
  GridGenerator::subdivided_hyper_rectangle(triangulation, repetitions, Point<3>(0., 0., 0.),
                                            Point<3>(prm.length_x, prm.width_y, prm.thickness_z),
                                            true);
}

// Why: distribute the degrees of freedom of the vector-valued Q_p element
// and express the clamped faces, u = 0 on Gamma_D, as constraints that are
// eliminated while assembling (AffineConstraints).  The sparsity pattern
// then already omits the couplings of constrained dofs.  We do not
// renumber: deal.II's default numbering keeps the three components of a
// support point consecutive, which ML's "PDE equations = 3" aggregation
// relies on.
void ElasticReference::setup_system() {
  dof_handler.distribute_dofs(fe);

  constraints.clear();
  DoFTools::make_hanging_node_constraints(dof_handler, constraints);
  for (const unsigned int id : prm.clamped_faces)
    VectorTools::interpolate_boundary_values(dof_handler, id, Functions::ZeroFunction<3>(3),
                                             constraints);
  constraints.close();

  DynamicSparsityPattern dsp(dof_handler.n_dofs());
  DoFTools::make_sparsity_pattern(dof_handler, dsp, constraints, false);
  const IndexSet all_dofs = complete_index_set(dof_handler.n_dofs());
  system_matrix.reinit(all_dofs, all_dofs, dsp, MPI_COMM_WORLD);
  system_rhs.reinit(all_dofs, MPI_COMM_WORLD);
  solution.reinit(dof_handler.n_dofs());
}

// Why: the weak form of small-strain isotropic elasticity.  Find u with
// u = 0 on the clamped faces such that for all admissible v
//
//   a(u, v) = ∫_Ω  λ (div u)(div v) + 2 μ ε(u):ε(v)  dx
//           = ∫_Γtop  t · v  ds = f(v),      t = (0, 0, -q),
//
// λ = E ν / ((1+ν)(1-2ν)),  μ = G = E / (2(1+ν)).  For the vector element
// every shape function φ_i has one non-zero component c_i, which gives the
// cell matrix (step-8)
//
//   A_ij = ∫ λ ∂_{c_i}φ_i ∂_{c_j}φ_j + μ ∂_{c_j}φ_i ∂_{c_i}φ_j
//          + δ_{c_i c_j} μ ∇φ_i·∇φ_j  dx.
//
// Gauss quadrature with p+1 points per direction integrates this exactly
// on the affine (box) cells.  Cells are processed on all cores with
// WorkStream; the copy into the global matrix runs serially.
void ElasticReference::assemble_system() {
  const double E = prm.youngs_modulus, nu = prm.poisson_ratio;
  const double lambda = E * nu / ((1. + nu) * (1. - 2. * nu));
  const double mu = E / (2. * (1. + nu));
  const Tensor<1, 3> traction({0., 0., -prm.traction()});
  const types::boundary_id loaded_face = 5; // z+

  const QGauss<3> quadrature(fe.degree + 1);
  const QGauss<2> face_quadrature(fe.degree + 1);

  struct ScratchData {
    ScratchData(const FiniteElement<3>& finite_element, const Quadrature<3>& q,
                const Quadrature<2>& fq)
        : fe_values(finite_element, q, update_gradients | update_JxW_values),
          fe_face_values(finite_element, fq, update_values | update_JxW_values) {}
    ScratchData(const ScratchData& s)
        : fe_values(s.fe_values.get_fe(), s.fe_values.get_quadrature(),
                    s.fe_values.get_update_flags()),
          fe_face_values(s.fe_face_values.get_fe(), s.fe_face_values.get_quadrature(),
                         s.fe_face_values.get_update_flags()) {}
    FEValues<3> fe_values;
    FEFaceValues<3> fe_face_values;
    std::vector<Tensor<1, 3>> grad; // ∇φ_i^{c_i} at one point
  };
  struct CopyData {
    FullMatrix<double> cell_matrix;
    Vector<double> cell_rhs;
    std::vector<types::global_dof_index> local_dof_indices;
  };

  const unsigned int dofs_per_cell = fe.n_dofs_per_cell();
  std::vector<unsigned int> component(dofs_per_cell);
  for (unsigned int i = 0; i < dofs_per_cell; ++i)
    component[i] = fe.system_to_component_index(i).first;

  auto worker = [&](const typename DoFHandler<3>::active_cell_iterator& cell, ScratchData& scratch,
                    CopyData& copy) {
    copy.cell_matrix.reinit(dofs_per_cell, dofs_per_cell);
    copy.cell_rhs.reinit(dofs_per_cell);
    copy.local_dof_indices.resize(dofs_per_cell);
    scratch.grad.resize(dofs_per_cell);

    scratch.fe_values.reinit(cell);
    const auto& fv = scratch.fe_values;
    for (const unsigned int q : fv.quadrature_point_indices()) {
      for (unsigned int i = 0; i < dofs_per_cell; ++i)
        scratch.grad[i] = fv.shape_grad_component(i, q, component[i]);
      const double JxW = fv.JxW(q);
      for (unsigned int i = 0; i < dofs_per_cell; ++i) {
        const unsigned int ci = component[i];
        const Tensor<1, 3>& gi = scratch.grad[i];
        for (unsigned int j = 0; j <= i; ++j) {
          const unsigned int cj = component[j];
          const Tensor<1, 3>& gj = scratch.grad[j];
          double a = lambda * gi[ci] * gj[cj] + mu * gi[cj] * gj[ci];
          if (ci == cj)
            a += mu * (gi * gj);
          copy.cell_matrix(i, j) += a * JxW;
        }
      }
    }
    for (unsigned int i = 0; i < dofs_per_cell; ++i)
      for (unsigned int j = i + 1; j < dofs_per_cell; ++j)
        copy.cell_matrix(i, j) = copy.cell_matrix(j, i);

    for (const auto& face : cell->face_iterators())
      if (face->at_boundary() && face->boundary_id() == loaded_face) {
        scratch.fe_face_values.reinit(cell, face);
        const auto& ffv = scratch.fe_face_values;
        for (const unsigned int q : ffv.quadrature_point_indices())
          for (unsigned int i = 0; i < dofs_per_cell; ++i)
            copy.cell_rhs(i) +=
                ffv.shape_value_component(i, q, component[i]) * traction[component[i]] * ffv.JxW(q);
      }
    cell->get_dof_indices(copy.local_dof_indices);
  };

  auto copier = [&](const CopyData& copy) {
    constraints.distribute_local_to_global(copy.cell_matrix, copy.cell_rhs, copy.local_dof_indices,
                                           system_matrix, system_rhs);
  };

  WorkStream::run(dof_handler.begin_active(), dof_handler.end(), worker, copier,
                  ScratchData(fe, quadrature, face_quadrature), CopyData());
  system_matrix.compress(VectorOperation::add);
  system_rhs.compress(VectorOperation::add);
}

// Why: the stiffness matrix is symmetric positive definite once the
// clamped dofs are eliminated, so CG is the method of choice.  Its
// iteration count grows like sqrt(cond(A)) ~ 1/h for SSOR, so for the
// larger levels we precondition with smoothed-aggregation AMG (Trilinos
// ML).  For elasticity, aggregation-based AMG needs the near null space of
// the operator, i.e. the six rigid-body modes
//
//   translations  (1,0,0), (0,1,0), (0,0,1)
//   rotations     (0,-z,y), (z,0,-x), (-y,x,0)   (about the centroid),
//
// evaluated at the support point of every dof.  deal.II 9.4 has no
// DoFTools::extract_rigid_body_modes and AdditionalData::constant_modes
// only takes 0/1 masks, so we hand the real-valued modes to ML through
// the Teuchos parameter list ("null space: type = pre-computed").
void ElasticReference::solve() {
  auto t0 = std::chrono::steady_clock::now();
  auto& level = summary.levels.back();
  const auto n = dof_handler.n_dofs();
  TrilinosWrappers::MPI::Vector x(complete_index_set(n), MPI_COMM_WORLD);

  SolverControl solver_control(prm.max_iterations, prm.relative_tolerance * system_rhs.l2_norm());
  SolverCG<TrilinosWrappers::MPI::Vector> cg(solver_control);

  if (prm.preconditioner == "AMG") {
    std::vector<Point<3>> support_points(n);
    DoFTools::map_dofs_to_support_points(MappingQ1<3>(), dof_handler, support_points);
    std::vector<unsigned int> dof_component(n, 0);
    {
      std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
      for (const auto& cell : dof_handler.active_cell_iterators()) {
        cell->get_dof_indices(dofs);
        for (unsigned int i = 0; i < dofs.size(); ++i)
          dof_component[dofs[i]] = fe.system_to_component_index(i).first;
      }
    }
    const Point<3> centre(prm.length_x / 2, prm.width_y / 2, prm.thickness_z / 2);

    TrilinosWrappers::PreconditionAMG::AdditionalData data;
    data.elliptic = true;
    data.higher_order_elements = (fe.degree > 1);
    data.smoother_sweeps = 2;
    data.aggregation_threshold = 1e-4;
    Teuchos::ParameterList parameter_list;
    std::unique_ptr<Epetra_MultiVector> unused_modes;
    data.set_parameters(parameter_list, unused_modes, system_matrix);

    Epetra_MultiVector modes(system_matrix.trilinos_matrix().DomainMap(), 6);
    for (types::global_dof_index i = 0; i < n; ++i) {
      const int li = static_cast<int>(i); // serial: local = global
      const unsigned int c = dof_component[i];
      const Tensor<1, 3> r = support_points[i] - centre;
      modes[c][li] = 1.;
      // rotation about x: (0,-z,y); about y: (z,0,-x); about z: (-y,x,0)
      const double rot[3][3] = {{0., -r[2], r[1]}, {r[2], 0., -r[0]}, {-r[1], r[0], 0.}};
      for (unsigned int k = 0; k < 3; ++k)
        modes[3 + k][li] = rot[k][c];
    }
    parameter_list.set("PDE equations", 3);
    parameter_list.set("null space: type", "pre-computed");
    parameter_list.set("null space: dimension", 6);
    parameter_list.set("null space: vectors", modes.Values());

    TrilinosWrappers::PreconditionAMG amg;
    amg.initialize(system_matrix, parameter_list);
    level.preconditioner_time = seconds_since(t0);
    cg.solve(system_matrix, x, system_rhs, amg);
  } else {
    TrilinosWrappers::PreconditionSSOR ssor;
    ssor.initialize(system_matrix, TrilinosWrappers::PreconditionSSOR::AdditionalData(1.2));
    level.preconditioner_time = seconds_since(t0);
    cg.solve(system_matrix, x, system_rhs, ssor);
  }
  constraints.distribute(x);
  solution = Vector<double>(x);
  level.iterations = solver_control.last_step();
  level.solve_time = seconds_since(t0);
}

// Why: the verification suite compares point deflections.  We evaluate
// the FE displacement at the requested points (VectorTools::point_value
// finds the cell, also for points on faces) and store -u_z, the vertical
// deflection positive downward.
void ElasticReference::evaluate_quantities() {
  Vector<double> u(3);
  for (const auto& q : prm.quantities) {
    VectorTools::point_value(dof_handler, solution, q.point, u);
    summary.levels.back().deflection[q.name] = -u[2];
  }
}

namespace {
struct Theory {
  std::string json; // the "theory" object
  std::string notes;
  // per quantity: classical values to print
  std::vector<std::pair<std::string, double>> values;
};

std::string fmt(const double v, const int precision = 6) {
  std::ostringstream s;
  s << std::setprecision(precision) << v;
  return s.str();
}

std::string percent(const double fe, const double ref) {
  std::ostringstream s;
  s << std::showpos << std::fixed << std::setprecision(2) << 100. * (fe - ref) / ref << " %";
  return s.str();
}

// Classical solutions; see the README for the formulas' sources.
Theory classical_theory(const Parameters& prm, const std::vector<QuantitySummary>& quantities) {
  Theory th;
  std::ostringstream js;
  JsonWriter w(js);
  const double E = prm.youngs_modulus, nu = prm.poisson_ratio;
  const double G = E / (2. * (1. + nu));
  w.begin_object();
  w.value("deflection_sign", "positive downward (-u_z), in m");
  if (prm.theory == "clamped-clamped beam" || prm.theory == "cantilever beam") {
    // Euler-Bernoulli and Timoshenko beam theory (e.g. Timoshenko &
    // Gere, Mechanics of Materials; shear coefficient 5/6 for a
    // rectangle):
    //   clamped-clamped, midspan:  p L^4/(384 E I) + p L^2/(8 kappa G A)
    //   cantilever, tip:           p L^4/(8 E I)   + p L^2/(2 kappa G A)
    const double L = prm.length_x, b = prm.width_y, h = prm.thickness_z;
    const double I = b * h * h * h / 12., A = b * h, kappa = 5. / 6.;
    const double p = prm.line_load();
    const bool cc = prm.theory == "clamped-clamped beam";
    const double bending =
        cc ? p * std::pow(L, 4) / (384. * E * I) : p * std::pow(L, 4) / (8. * E * I);
    const double shear = cc ? p * L * L / (8. * kappa * G * A) : p * L * L / (2. * kappa * G * A);
    w.value("kind", prm.theory);
    w.value("location", cc ? "midspan x = L/2" : "tip x = L");
    w.value("formula_euler_bernoulli", cc ? "p L^4 / (384 E I)" : "p L^4 / (8 E I)");
    w.value("formula_timoshenko_shear_part",
            cc ? "p L^2 / (8 kappa G A)" : "p L^2 / (2 kappa G A)");
    w.value("L", L).value("b", b).value("h", h).value("E", E).value("nu", nu);
    w.value("G", G).value("I", I).value("A", A).value("kappa", kappa);
    w.value("p_N_per_m", p);
    w.value("euler_bernoulli", bending);
    w.value("timoshenko", bending + shear);
    if (!quantities.empty()) {
      const double fe = quantities.front().richardson.extrapolated;
      w.value("fe_quantity", quantities.front().name);
      w.value("fe_extrapolated", fe);
      w.value("fe_vs_euler_bernoulli_rel", (fe - bending) / bending);
      w.value("fe_vs_timoshenko_rel", (fe - bending - shear) / (bending + shear));
      th.values = {{"Euler-Bernoulli", bending}, {"Timoshenko", bending + shear}};
      // Which share of Timoshenko's shear term does the 3D solution
      // show on top of Euler-Bernoulli?
      const double shear_share = (fe - bending) / shear;
      w.value("fe_minus_euler_bernoulli_over_timoshenko_shear_term", shear_share);
      std::ostringstream n;
      n << "3D FE " << quantities.front().name << " deflection " << fmt(fe) << " m is "
        << percent(fe, bending + shear) << " from Timoshenko (" << fmt(bending + shear)
        << " m) and " << percent(fe, bending) << " from Euler-Bernoulli (" << fmt(bending)
        << " m). Euler-Bernoulli omits shear "
        << "deformation; Timoshenko's shear term is " << fmt(100. * shear / (bending + shear), 3)
        << " % of its total (L/h = " << fmt(L / h, 4) << "). The 3D solution adds "
        << fmt(100. * shear_share, 3) << " % of that shear term to Euler-Bernoulli. ";
      if (shear_share < 1.)
        n << "It is stiffer than Timoshenko because (a) the load "
             "acts on the top face: the transverse normal stress it "
             "causes reduces the shear-type deflection through "
             "Poisson's effect (exact plane-stress solution of a "
             "top-loaded simply supported beam, Timoshenko & "
             "Goodier, Theory of Elasticity, 'Bending of a beam by "
             "uniform load': correction "
             "(12/5)(h/L)^2 (4/5 + nu/2) instead of Timoshenko's "
             "(12/5)(h/L)^2 (4/5)(1 + nu) with kappa = 5/6, i.e. "
          << fmt(100. * (0.8 + nu / 2.) / (0.8 * (1. + nu)), 3)
          << " % of it), and (b) the fully clamped end face(s) "
             "u = 0 forbid the Poisson contraction/expansion of the "
             "section (and its warping) where the bending stresses "
             "are largest, which beam theory's built-in section "
             "allows: a stiffening near the supports. Both are "
             "Poisson effects: for the reference beams of "
             "fem_reference/README.md, the same 3D runs with nu = 0 "
             "agree with Timoshenko to 0.1 % or better. The local 3D "
             "flexibility next to the clamped edges (stress "
             "singularity) acts the other way but is small.";
      else
        n << "It is more flexible than Timoshenko: the material "
             "next to the clamped faces deforms locally (3D stress "
             "concentration at the built-in edges, root "
             "flexibility), which beam theory's rigid built-in "
             "section ignores; this outweighs the stiffening by the "
             "restrained warping and Poisson contraction at the "
             "clamped faces.";
      th.notes = n.str();
    }
  } else if (prm.theory == "kirchhoff plate") {
    // Kirchhoff plate, Rayleigh-Ritz series (kirchhoff_plate.h).
    const double t = prm.thickness_z;
    const double D = E * t * t * t / (12. * (1. - nu * nu));
    KirchhoffPlate plate;
    plate.a = prm.length_x;
    plate.b = prm.width_y;
    plate.D = D;
    plate.nu = nu;
    plate.q = prm.traction();
    auto edge = [&](const unsigned int id) {
      for (const unsigned int c : prm.clamped_faces)
        if (c == id)
          return EdgeCondition::clamped;
      return EdgeCondition::free;
    };
    plate.x0 = edge(0);
    plate.x1 = edge(1);
    plate.y0 = edge(2);
    plate.y1 = edge(3);
    w.value("kind", "Kirchhoff plate, Rayleigh-Ritz series solution");
    w.value("edges", "x=0: " + to_string(plate.x0) + ", x=a: " + to_string(plate.x1) +
                         ", y=0: " + to_string(plate.y0) + ", y=b: " + to_string(plate.y1));
    w.value("a", plate.a).value("b", plate.b).value("t", t);
    w.value("E", E).value("nu", nu).value("D", D).value("q", plate.q);
    const std::vector<unsigned int> terms{8, 12, 16, 20, 24, 28, 32};
    std::vector<KirchhoffRitz> ritz;
    for (const unsigned int N : terms)
      ritz.emplace_back(plate, N);
    w.begin_object("quantities");
    std::ostringstream n;
    for (const auto& q : quantities) {
      w.begin_object(q.name);
      w.begin_array("ritz_sequence");
      for (const auto& r : ritz) {
        w.begin_object();
        w.value("terms_per_direction", r.n_terms());
        w.value("deflection", r.deflection(q.point[0], q.point[1]));
        w.end_object();
      }
      w.end_array();
      const double kirchhoff = ritz.back().deflection(q.point[0], q.point[1]);
      const double previous = ritz[ritz.size() - 2].deflection(q.point[0], q.point[1]);
      w.value("kirchhoff", kirchhoff);
      w.value("kirchhoff_series_rel_change_last_step",
              std::abs(kirchhoff - previous) / std::abs(kirchhoff));
      w.value("coefficient_w_D_over_q_a4", kirchhoff * D / (plate.q * std::pow(plate.a, 4)));
      const double fe = q.richardson.extrapolated;
      w.value("fe_extrapolated", fe);
      w.value("fe_vs_kirchhoff_rel", (fe - kirchhoff) / kirchhoff);
      w.end_object();
      th.values.push_back({"Kirchhoff " + q.name, kirchhoff});
      n << "3D FE " << q.name << " deflection " << fmt(fe) << " m is " << percent(fe, kirchhoff)
        << " from Kirchhoff (" << fmt(kirchhoff) << " m). ";
    }
    w.end_object();
    n << "Kirchhoff (thin plate) theory neglects transverse shear "
         "deformation and treats a clamped edge as w = dw/dn = 0 on "
         "the mid-surface. The plate is moderately thick (t/b = "
      << fmt(t / plate.b, 3) << ", t/a = " << fmt(t / plate.a, 3)
      << "): the 3D solution includes the shear deflection, which "
         "grows like (t/span)^2 relative to bending and is "
         "comparatively large for clamped edges, and the local 3D "
         "flexibility at the clamped faces (stress concentration at "
         "the built-in edges). Both make the 3D plate more flexible "
         "than Kirchhoff; the clamped faces also restrain the Poisson "
         "contraction there (a small stiffening). The difference "
         "shrinks towards zero as t -> 0 (see fem_reference/README.md, "
         "thickness study).";
    th.notes = n.str();
  } else
    w.value("kind", "none");
  w.end_object();
  th.json = js.str();
  return th;
}

void write_csv_line(const std::filesystem::path& file, const Parameters::SampleLine& line,
                    const DoFHandler<3>& dof_handler, const Vector<double>& solution) {
  Functions::FEFieldFunction<3, Vector<double>> field(dof_handler, solution);
  write_atomically(file, [&](std::ostream& out) {
    out << "s,x,y,z,u_x,u_y,u_z,deflection\n";
    out << std::setprecision(10);
    Vector<double> u(3);
    const double length = line.start.distance(line.end);
    for (unsigned int k = 0; k < line.n_points; ++k) {
      const double s = static_cast<double>(k) / (line.n_points - 1);
      const Point<3> x = line.start + s * (line.end - line.start);
      field.vector_value(x, u);
      out << s * length << ',' << x[0] << ',' << x[1] << ',' << x[2] << ',' << u[0] << ',' << u[1]
          << ',' << u[2] << ',' << -u[2] << '\n';
    }
  });
}
} // namespace

// Why: the finest solution is the reference.  Richardson extrapolation of
// the last three levels (h, h/2, h/4) gives the observed order
// p = log2(|q1-q0|/|q2-q1|), the extrapolated value q2 + (q2-q1)/(2^p-1)
// and, as their difference, an estimate of the discretisation error of
// the finest value.  Everything is written atomically: summary.json,
// one CSV per sample line and solution.vtu.
void ElasticReference::output_results(const std::string& command_line,
                                      const std::string& parameters_json,
                                      const std::string& parameters_prm) {
  summary.quantities.clear();
  for (const auto& q : prm.quantities) {
    std::vector<double> values;
    for (const auto& l : summary.levels)
      values.push_back(l.deflection.at(q.name));
    QuantitySummary s;
    s.name = q.name;
    s.point = q.point;
    s.finest = values.back();
    s.richardson = richardson(values, 2.);
    summary.quantities.push_back(s);
  }

  std::filesystem::create_directories(output_directory);
  for (const auto& line : prm.lines)
    write_csv_line(output_directory / (line.name + ".csv"), line, dof_handler, solution);

  if (prm.write_vtu) {
    DataOut<3> data_out;
    data_out.attach_dof_handler(dof_handler);
    const std::vector<std::string> names(3, "displacement");
    const std::vector<DataComponentInterpretation::DataComponentInterpretation> interpretation(
        3, DataComponentInterpretation::component_is_part_of_vector);
    data_out.add_data_vector(solution, names, DataOut<3>::type_dof_data, interpretation);
    data_out.build_patches(fe.degree);
    DataOutBase::VtkFlags flags;
    flags.write_higher_order_cells = true;
    data_out.set_flags(flags);
    write_atomically(output_directory / "solution.vtu",
                     [&](std::ostream& out) { data_out.write_vtu(out); });
  }

  write_atomically(output_directory / "parameters.prm",
                   [&](std::ostream& out) { out << parameters_prm; });

  const Theory theory = classical_theory(prm, summary.quantities);

  write_atomically(output_directory / "summary.json", [&](std::ostream& out) {
    JsonWriter w(out);
    w.begin_object();
    w.value("problem", prm.name);
    w.begin_object("provenance");
    w.value("command", command_line);
    w.value("date", iso_date_time());
    w.value("deal_ii_version", DEAL_II_PACKAGE_VERSION);
    w.value("threads", MultithreadInfo::n_threads());
    w.end_object();
    w.raw("parameters", parameters_json);
    w.value("element", fe.get_name());
    w.value("deflection_sign", "positive downward: deflection = -u_z, in m");
    w.value("base_subdivisions", std::to_string(base_subdivisions[0]) + " x " +
                                     std::to_string(base_subdivisions[1]) + " x " +
                                     std::to_string(base_subdivisions[2]));
    w.begin_array("levels");
    for (const auto& l : summary.levels) {
      w.begin_object();
      w.value("level", l.level);
      w.value("subdivisions", std::to_string(l.subdivisions[0]) + " x " +
                                  std::to_string(l.subdivisions[1]) + " x " +
                                  std::to_string(l.subdivisions[2]));
      w.value("cells", l.cells);
      w.value("dofs", static_cast<unsigned long>(l.dofs));
      w.begin_object("deflection");
      for (const auto& q : prm.quantities)
        w.value(q.name, l.deflection.at(q.name));
      w.end_object();
      w.value("iterations", l.iterations);
      w.value("setup_time_s", l.setup_time);
      w.value("assembly_time_s", l.assembly_time);
      w.value("preconditioner_setup_time_s", l.preconditioner_time);
      w.value("solve_time_s", l.solve_time);
      w.value("level_time_s", l.total_time);
      w.end_object();
    }
    w.end_array();
    w.begin_object("quantities");
    for (const auto& q : summary.quantities) {
      w.begin_object(q.name);
      w.begin_array("point");
      for (unsigned int d = 0; d < 3; ++d)
        w.value("", q.point[d]);
      w.end_array();
      w.value("value", q.finest);
      w.value("extrapolated", q.richardson.extrapolated);
      w.value("observed_order", q.richardson.order);
      w.value("richardson_valid", q.richardson.valid);
      w.value("error_estimate", q.richardson.error_estimate);
      w.value("relative_error_estimate", q.richardson.relative_error);
      w.value("converged_to_0.1_percent",
              q.richardson.valid && q.richardson.relative_error <= 1e-3);
      w.end_object();
    }
    w.end_object();
    w.raw("theory", theory.json);
    w.value("notes", theory.notes);
    w.value("wall_time_s", summary.wall_time);
    w.end_object();
  });
}

RunSummary ElasticReference::run(const std::string& command_line,
                                 const std::string& parameters_json,
                                 const std::string& parameters_prm) {
  const auto t_start = std::chrono::steady_clock::now();
  for (unsigned int level = 0; level < n_levels; ++level) {
    const auto t0 = std::chrono::steady_clock::now();
    summary.levels.emplace_back();
    LevelResult& r = summary.levels.back();
    r.level = level;

    make_grid();
    setup_system();
    r.cells = triangulation.n_active_cells();
    r.dofs = dof_handler.n_dofs();
    for (unsigned int d = 0; d < 3; ++d)
      r.subdivisions[d] = base_subdivisions[d] << level;
    r.setup_time = seconds_since(t0);

    const auto t1 = std::chrono::steady_clock::now();
    assemble_system();
    r.assembly_time = seconds_since(t1);

    solve();
    evaluate_quantities();
    r.total_time = seconds_since(t0);

    std::cerr << "[" << prm.name << "] level " << level << ": " << r.subdivisions[0] << "x"
              << r.subdivisions[1] << "x" << r.subdivisions[2] << " cells, " << r.dofs << " dofs, "
              << r.iterations << " CG its, assembly " << std::setprecision(3) << r.assembly_time
              << " s, solve " << r.solve_time << " s;";
    for (const auto& q : prm.quantities)
      std::cerr << " " << q.name << " = " << std::setprecision(8) << r.deflection[q.name];
    std::cerr << std::endl;
  }
  summary.wall_time = seconds_since(t_start);
  output_results(command_line, parameters_json, parameters_prm);
  return summary;
}
} // namespace pdfem
