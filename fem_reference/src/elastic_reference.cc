#include "elastic_reference.h"

#include "elastic_common.h"

#include <algorithm>
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
#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/numerics/data_out.h>
#include <deal.II/numerics/fe_field_function.h>
#include <deal.II/numerics/vector_tools.h>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace pdfem {
namespace {
double seconds_since(const std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

template <int dim>
Point<dim> to_point(const Point<3>& p) {
  Point<dim> q;
  for (unsigned int d = 0; d < dim; ++d)
    q[d] = p[d];
  return q;
}

std::string joined(const std::vector<unsigned int>& n, const char* separator) {
  std::string s;
  for (std::size_t d = 0; d < n.size(); ++d)
    s += (d ? separator : "") + std::to_string(n[d]);
  return s;
}

// Why: a clamped face meeting a free one makes an edge singularity, u ~ r^0.7, which holds
// uniform refinement of Q_p to a point-value rate near 2 x 0.7 whatever p is.  Grading the mesh
// toward such faces restores the rate of a smooth solution (Babuska, Kellogg & Pitkaranta 1979;
// Apel 1999 for the anisotropic, edge-wise form used here).  On one axis, with s = x / L of a
// uniform mesh, the map is
//   x/L = k (sigma/beta) (s/sigma)^beta                 within the layer s < sigma (graded lo end),
//   x/L = 1 - k (sigma/beta) ((1-s)/sigma)^beta          within 1 - s < sigma (graded hi end),
//   x/L = k s - [lo graded] k sigma (1 - 1/beta)         between them,
// with k = 1 / (1 - (number of graded ends) sigma (1 - 1/beta)): continuous with a continuous
// slope, so neighbouring cells differ in size by O(1/n).  A map per axis keeps boxes boxes.
double graded_coordinate(const double s, const bool lo, const bool hi, const double beta,
                         const double sigma) {
  const double ends = (lo ? 1. : 0.) + (hi ? 1. : 0.);
  const double k = 1. / (1. - ends * sigma * (1. - 1. / beta));
  if (lo && s < sigma)
    return k * sigma / beta * std::pow(s / sigma, beta);
  if (hi && s > 1. - sigma)
    return 1. - k * sigma / beta * std::pow((1. - s) / sigma, beta);
  return k * s - (lo ? k * sigma * (1. - 1. / beta) : 0.);
}

// Why: the vertical axis is the last one, so the deflection (positive downward) is -u_{dim-1}
// and the loaded top face is the last axis's upper face (boundary id 2 dim - 1: z+ resp. y+).
constexpr unsigned int vertical(const int dim) {
  return static_cast<unsigned int>(dim - 1);
}

template <int dim>
void write_csv_line(const std::filesystem::path& file, const Parameters::SampleLine& line,
                    const DoFHandler<dim>& dof_handler, const Vector<double>& solution) {
  Functions::FEFieldFunction<dim, Vector<double>> field(dof_handler, solution);
  write_atomically(file, [&](std::ostream& out) {
    out << (dim == 2 ? "s,x,y,u_x,u_y,deflection\n" : "s,x,y,z,u_x,u_y,u_z,deflection\n");
    out << std::setprecision(10);
    Vector<double> u(dim);
    const Point<dim> start = to_point<dim>(line.start), end = to_point<dim>(line.end);
    const double length = start.distance(end);
    for (unsigned int k = 0; k < line.n_points; ++k) {
      const double s = static_cast<double>(k) / (line.n_points - 1);
      const Point<dim> x = start + s * (end - start);
      field.vector_value(x, u);
      out << s * length;
      for (unsigned int d = 0; d < dim; ++d)
        out << ',' << x[d];
      for (unsigned int d = 0; d < dim; ++d)
        out << ',' << u[d];
      out << ',' << -u[vertical(dim)] << '\n';
    }
  });
}
} // namespace

template <int dim>
ElasticReference<dim>::ElasticReference(const Parameters& parameters, const unsigned int levels,
                                        const std::filesystem::path& out_dir)
    : prm(parameters), n_levels(levels), output_directory(out_dir),
      fe(FE_Q<dim>(parameters.degree), dim) {
  AssertThrow(parameters.dimension == dim, ExcMessage("parameters of another dimension"));
}

// Why: the reference must be mesh-converged, which we demonstrate by a
// sequence of meshes with nearly cubic cells (aspect ratio close to 1
// keeps the error constant of every level similar).  The base mesh has
// n_i = max(1, round(extent_i / h0)) cells per direction; level k has
// n_i m_k (m_k = 2^k unless Level multipliers says otherwise), so its mesh
// size is h0/m_k, the h of the Richardson extrapolation.  Each level is
// built afresh, since a graded mesh (Graded faces) is a map of the uniform
// one and the refinement of a graded mesh would not be the graded mesh of
// the finer level.  colorize = true numbers the faces 0..2dim-1 =
// x-, x+, y-, y+(, z-, z+); the map moves vertices only, so the ids stay.
template <int dim>
void ElasticReference<dim>::make_grid(const unsigned int level) {
  const std::vector<double> extent = prm.extent();
  base_subdivisions.assign(dim, 1);
  std::vector<unsigned int> repetitions(dim);
  Point<dim> far_corner;
  for (unsigned int d = 0; d < dim; ++d) {
    base_subdivisions[d] =
        static_cast<unsigned int>(std::max(1L, std::lround(extent[d] / prm.base_element_size)));
    repetitions[d] = base_subdivisions[d] * prm.level_multiplier(level);
    far_corner[d] = extent[d];
  }
  auto mesh = std::make_unique<Triangulation<dim>>();
  GridGenerator::subdivided_hyper_rectangle(*mesh, repetitions, Point<dim>(), far_corner, true);
  if (!prm.graded_faces.empty() && prm.grading_exponent != 1.)
    grade(*mesh, extent);
  dof_handler.reinit(*mesh);
  triangulation = std::move(mesh);
}

// The map of graded_coordinate on every axis with a graded face.
template <int dim>
void ElasticReference<dim>::grade(Triangulation<dim>& mesh,
                                  const std::vector<double>& extent) const {
  const auto graded = [&](const unsigned int face) {
    return std::find(prm.graded_faces.begin(), prm.graded_faces.end(), face) !=
           prm.graded_faces.end();
  };
  GridTools::transform(
      [&](const Point<dim>& p) {
        Point<dim> q;
        for (unsigned int d = 0; d < dim; ++d)
          q[d] = extent[d] * graded_coordinate(p[d] / extent[d], graded(2 * d), graded(2 * d + 1),
                                               prm.grading_exponent, prm.graded_layer);
        return q;
      },
      mesh);
}

// Why: distribute the degrees of freedom of the vector-valued Q_p element
// and express the clamped faces, u = 0 on Gamma_D, as constraints that are
// eliminated while assembling (AffineConstraints).  The sparsity pattern
// then already omits the couplings of constrained dofs.  We do not
// renumber: deal.II's default numbering keeps the components of a
// support point consecutive, which ML's "PDE equations = dim" aggregation
// relies on.
template <int dim>
void ElasticReference<dim>::setup_system() {
  dof_handler.distribute_dofs(fe);

  constraints.clear();
  DoFTools::make_hanging_node_constraints(dof_handler, constraints);
  for (const unsigned int id : prm.clamped_faces)
    VectorTools::interpolate_boundary_values(dof_handler, id, Functions::ZeroFunction<dim>(dim),
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
//           = ∫_Γtop  t · v  ds = f(v),      t = -q e_vertical,
//
// λ = E ν / ((1+ν)(1-2ν)),  μ = G = E / (2(1+ν)) in 3D and in plane strain
// (ε_zz = 0 leaves exactly these 2D equations); in plane stress σ_zz = 0
// eliminates ε_zz, which leaves λ* = 2λμ/(λ+2μ) = Eν/(1-ν²) in place of λ
// (Parameters::lame_lambda).  For the vector element
// every shape function φ_i has one non-zero component c_i, which gives the
// cell matrix (step-8)
//
//   A_ij = ∫ λ ∂_{c_i}φ_i ∂_{c_j}φ_j + μ ∂_{c_j}φ_i ∂_{c_i}φ_j
//          + δ_{c_i c_j} μ ∇φ_i·∇φ_j  dx.
//
// Gauss quadrature with p+1 points per direction integrates this exactly
// on the affine (box) cells.  Cells are processed on all cores with
// WorkStream; the copy into the global matrix runs serially.
template <int dim>
void ElasticReference<dim>::assemble_system() {
  const LameConstants lame{prm.lame_lambda(), prm.lame_mu()};
  Tensor<1, dim> traction;
  traction[vertical(dim)] = -prm.traction();
  const types::boundary_id loaded_face = 2 * dim - 1; // z+ (2D: y+)

  const QGauss<dim> quadrature(fe.degree + 1);
  const QGauss<dim - 1> face_quadrature(fe.degree + 1);

  struct ScratchData {
    ScratchData(const FiniteElement<dim>& finite_element, const Quadrature<dim>& q,
                const Quadrature<dim - 1>& fq)
        : fe_values(finite_element, q, update_gradients | update_JxW_values),
          fe_face_values(finite_element, fq, update_values | update_JxW_values) {}
    ScratchData(const ScratchData& s)
        : fe_values(s.fe_values.get_fe(), s.fe_values.get_quadrature(),
                    s.fe_values.get_update_flags()),
          fe_face_values(s.fe_face_values.get_fe(), s.fe_face_values.get_quadrature(),
                         s.fe_face_values.get_update_flags()) {}
    FEValues<dim> fe_values;
    FEFaceValues<dim> fe_face_values;
    std::vector<Tensor<1, dim>> grad; // ∇φ_i^{c_i} at one point
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

  auto worker = [&](const typename DoFHandler<dim>::active_cell_iterator& cell,
                    ScratchData& scratch, CopyData& copy) {
    copy.cell_matrix.reinit(dofs_per_cell, dofs_per_cell);
    copy.cell_rhs.reinit(dofs_per_cell);
    copy.local_dof_indices.resize(dofs_per_cell);

    scratch.fe_values.reinit(cell);
    add_elastic_cell_matrix(scratch.fe_values, component, lame, scratch.grad, copy.cell_matrix);

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

// Why: CG with AMG and the rigid-body modes about the centroid (elastic_common.h).
template <int dim>
void ElasticReference<dim>::solve() {
  auto& level = summary.levels.back();
  Point<dim> centre;
  const std::vector<double> extent = prm.extent();
  for (unsigned int d = 0; d < dim; ++d)
    centre[d] = extent[d] / 2;
  const CgStatistics stats =
      solve_elasticity(dof_handler, system_matrix, system_rhs, constraints, centre,
                       prm.preconditioner, prm.relative_tolerance, prm.max_iterations, solution);
  level.iterations = stats.iterations;
  level.solver = solver_summary(stats);
  level.preconditioner_time = stats.preconditioner_time;
  level.solve_time = stats.solve_time;
}

// Why: the verification suite compares point deflections.  We evaluate
// the FE displacement at the requested points (VectorTools::point_value
// finds the cell, also for points on faces) and store -u_z (2D: -u_y), the
// vertical deflection positive downward.
template <int dim>
void ElasticReference<dim>::evaluate_quantities() {
  Vector<double> u(dim);
  for (const auto& q : prm.quantities) {
    VectorTools::point_value(dof_handler, solution, to_point<dim>(q.point), u);
    summary.levels.back().deflection[q.name] = -u[vertical(dim)];
  }
}

// Why: the finest solution is the reference.  Richardson extrapolation of
// the last three levels (h, h/2, h/4) gives the observed order
// p = log2(|q1-q0|/|q2-q1|), the extrapolated value q2 + (q2-q1)/(2^p-1)
// and, as their difference, an estimate of the discretisation error of
// the finest value.  Everything is written atomically: summary.json,
// one CSV per sample line and solution.vtu.
template <int dim>
void ElasticReference<dim>::output_results(const std::string& command_line,
                                           const std::string& parameters_json,
                                           const std::string& parameters_prm) {
  summary.quantities.clear();
  std::vector<double> mesh_sizes; // h_k / h0
  for (const auto& l : summary.levels)
    mesh_sizes.push_back(1. / l.multiplier);
  for (const auto& q : prm.quantities) {
    std::vector<double> values;
    for (const auto& l : summary.levels)
      values.push_back(l.deflection.at(q.name));
    QuantitySummary s;
    s.name = q.name;
    s.point = q.point;
    s.finest = values.back();
    s.richardson = richardson(values, mesh_sizes);
    s.triples = richardson_per_triple(values, mesh_sizes);
    summary.quantities.push_back(s);
  }

  std::filesystem::create_directories(output_directory);
  for (const auto& line : prm.lines)
    write_csv_line<dim>(output_directory / (line.name + ".csv"), line, dof_handler, solution);

  if (prm.write_vtu) {
    DataOut<dim> data_out;
    data_out.attach_dof_handler(dof_handler);
    const std::vector<std::string> names(dim, "displacement");
    const std::vector<DataComponentInterpretation::DataComponentInterpretation> interpretation(
        dim, DataComponentInterpretation::component_is_part_of_vector);
    data_out.add_data_vector(solution, names, DataOut<dim>::type_dof_data, interpretation);
    data_out.build_patches(fe.degree);
    DataOutBase::VtkFlags flags;
    flags.write_higher_order_cells = true;
    data_out.set_flags(flags);
    write_atomically(output_directory / "solution.vtu",
                     [&](std::ostream& out) { data_out.write_vtu(out); });
  }

  write_atomically(output_directory / "parameters.prm",
                   [&](std::ostream& out) { out << parameters_prm; });
  write_summary(command_line, parameters_json);
}

template <int dim>
void ElasticReference<dim>::write_summary(const std::string& command_line,
                                          const std::string& parameters_json) {
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
    w.value("model", prm.model_name());
    w.value("element", fe.get_name());
    w.value("deflection_sign", dim == 2 ? "positive downward: deflection = -u_y, in m"
                                        : "positive downward: deflection = -u_z, in m");
    w.value("base_subdivisions", joined(base_subdivisions, " x "));
    w.begin_array("levels");
    for (const auto& l : summary.levels) {
      w.begin_object();
      w.value("level", l.level);
      w.value("subdivisions", joined(l.subdivisions, " x "));
      w.value("mesh_size_over_base", 1. / l.multiplier);
      w.value("cells", l.cells);
      w.value("dofs", static_cast<unsigned long>(l.dofs));
      w.begin_object("deflection");
      for (const auto& q : prm.quantities)
        w.value(q.name, l.deflection.at(q.name));
      w.end_object();
      w.value("iterations", l.iterations);
      w.value("solver", l.solver);
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
      for (unsigned int d = 0; d < dim; ++d)
        w.value("", q.point[d]);
      w.end_array();
      w.value("value", q.finest);
      w.value("extrapolated", q.richardson.extrapolated);
      w.value("observed_order", q.richardson.order);
      // The order of every triple of consecutive levels, coarsest first: where the orders
      // settle, the extrapolation is in its asymptotic range.
      w.begin_array("observed_orders_per_triple");
      for (const auto& t : q.triples)
        w.value("", t.order);
      w.end_array();
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

template <int dim>
RunSummary ElasticReference<dim>::run(const std::string& command_line,
                                      const std::string& parameters_json,
                                      const std::string& parameters_prm) {
  const auto t_start = std::chrono::steady_clock::now();
  for (unsigned int level = 0; level < n_levels; ++level) {
    const auto t0 = std::chrono::steady_clock::now();
    summary.levels.emplace_back();
    LevelResult& r = summary.levels.back();
    r.level = level;

    make_grid(level);
    setup_system();
    r.cells = triangulation->n_active_cells();
    r.dofs = dof_handler.n_dofs();
    r.multiplier = prm.level_multiplier(level);
    for (const unsigned int n : base_subdivisions)
      r.subdivisions.push_back(n * r.multiplier);
    r.setup_time = seconds_since(t0);

    const auto t1 = std::chrono::steady_clock::now();
    assemble_system();
    r.assembly_time = seconds_since(t1);

    solve();
    evaluate_quantities();
    r.total_time = seconds_since(t0);

    std::cerr << "[" << prm.name << "] level " << level << ": " << joined(r.subdivisions, "x")
              << " cells, " << r.dofs << " dofs, " << r.solver << ", assembly "
              << std::setprecision(3) << r.assembly_time << " s, solve " << r.solve_time << " s;";
    for (const auto& q : prm.quantities)
      std::cerr << " " << q.name << " = " << std::setprecision(8) << r.deflection[q.name];
    std::cerr << std::endl;
  }
  summary.wall_time = seconds_since(t_start);
  output_results(command_line, parameters_json, parameters_prm);
  return summary;
}

RunSummary solve_reference(const Parameters& parameters, const unsigned int n_levels,
                           const std::filesystem::path& output_directory,
                           const std::string& command_line, const std::string& parameters_json,
                           const std::string& parameters_prm) {
  if (parameters.dimension == 2)
    return ElasticReference<2>(parameters, n_levels, output_directory)
        .run(command_line, parameters_json, parameters_prm);
  return ElasticReference<3>(parameters, n_levels, output_directory)
      .run(command_line, parameters_json, parameters_prm);
}

template class ElasticReference<2>;
template class ElasticReference<3>;
} // namespace pdfem
