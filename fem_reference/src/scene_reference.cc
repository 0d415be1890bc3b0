// pd-fem --scene: a libpd scene's linear-elastic continuum problem in deal.II.
//
// The body is the union of the scene's body boxes, less the regions of mirror supports (their
// particles stand behind the clamp plane; the continuum body ends on it) and less each region's
// `minus` shapes. In the default cell-centred lattice the particles' volumes tile the boxes, so
// the FE body is the boxes themselves:
//
//     -div σ(u) = b      in Ω,        σ = λ tr ε I + 2 μ ε   (λ → λ* in plane stress),
//     u_c = g_c          on the nodes of fixed / displacement supports (component c),
//     u = 0              on the clamp plane of a mirror support,
//     σ n = −p n         on the surface of a pressure load (where it bounds Ω),
//     σ n = 0            elsewhere on ∂Ω,
//
// with b the loads as PD applies them: a resultant F shared among the particles a load selects
// in proportion to their volumes is the density F/V on the union of their lattice cells (V its
// volume, times the thickness in 2D); a `body` load is its density on the same cells.
//
// The mesh is a tensor-product grid whose lines contain every box face of bodies, supports and
// loaded cells, subdivided to a target size, with the cells outside Ω removed; each level
// refines it globally (h, h/2, h/4, ...), so Richardson extrapolation with ratio 2 applies.
// Curved shapes are meshed by Gmsh from the geometry alone (scene_mesh.h).
// Probes read what PD reads: the mean of a displacement component over the particles libpd
// resolves for the probe (evaluated at their positions), or a support's reaction, the sum of
// the residual K u - f over the dofs it constrains.
#include "scene_reference.h"

#include "elastic_common.h"
#include "libpd/app/probes.hpp"
#include "libpd/core/memory.hpp"
#include "libpd/discretisation/surface_load.hpp"
#include "report.h"
#include "scene_mesh.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_q.h>
#include <deal.II/fe/fe_simplex_p.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_fe.h>
#include <deal.II/fe/mapping_q.h>
#include <deal.II/fe/mapping_q1.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/numerics/fe_field_function.h>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

namespace pdfem {
namespace {
double seconds_since(const std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

template <int dim>
pd::Vec3 to_vec3(const Point<dim>& p) {
  pd::Vec3 v{0, 0, 0};
  for (unsigned int d = 0; d < dim; ++d)
    v[d] = p[d];
  return v;
}

// Why: quadratic elements everywhere; a mesh body's cells are simplices (its own elements
// refined), every other mesh has quadrilaterals or hexahedra.
template <int dim>
std::unique_ptr<FiniteElement<dim>> base_element(const bool simplex) {
  if (simplex)
    return std::make_unique<FE_SimplexP<dim>>(2);
  return std::make_unique<FE_Q<dim>>(2);
}

template <int dim>
Quadrature<dim> cell_quadrature(const bool simplex) {
  if (simplex)
    return QGaussSimplex<dim>(3);
  return QGauss<dim>(3);
}
} // namespace

template <int dim>
SceneReference<dim>::SceneReference(const SceneProblem& p, const SceneOptions& o)
    : problem(p), options(o), on_mesh_body(p.mesh_body.has_value()),
      fe(*base_element<dim>(on_mesh_body), dim), quadrature(cell_quadrature<dim>(on_mesh_body)),
      use_gmsh(!on_mesh_body && (p.curved || o.gmsh)) {
  // Gmsh meshes may have curved boundary faces (scene_mesh.cc): map them with quadratics. A mesh
  // body's straight-sided simplices map linearly.
  if (on_mesh_body)
    mapping = std::make_unique<MappingFE<dim>>(FE_SimplexP<dim>(1));
  else if (use_gmsh)
    mapping = std::make_unique<MappingQ<dim>>(2);
  else
    mapping = std::make_unique<MappingQ1<dim>>();
  AssertThrow(p.dim() == dim, ExcMessage("scene of another dimension"));
  component.resize(fe.n_dofs_per_cell());
  for (unsigned int i = 0; i < component.size(); ++i)
    component[i] = fe.system_to_component_index(i).first;
}

namespace {
// Unknowns of a quadratic vector field on n cells, roughly, dim components: Q2 2^dim nodes per
// cell; P2 on simplices (vertices and edges) about 2 per triangle and 1.4 per tetrahedron.
double estimated_dofs(const int dim, const double cells, const bool simplex = false) {
  if (simplex)
    return dim * (dim == 2 ? 2. : 1.4) * cells;
  return dim * std::pow(2., dim) * cells;
}

// Why: the memory a level needs, estimated from its cells before anything of it is allocated,
// so that refining stops with a message instead of std::bad_alloc minutes later. Per unknown,
// Q2 couples about 64 nodes in 3D and 16 in 2D (a cell's 8 or 4 nodes weighted by how many cells
// share them): 3 · 64 entries of 12 bytes (value and column) in 3D, 2 · 16 in 2D, held about five
// times over (the sparsity pattern, the matrix, the triangle the factorisation reads, its input
// copy and the solver's work). The 3D Cholesky factor grows like n^(4/3) from the notched beam's
// 546 MB at 93,075 unknowns (elastic_common.h), the 2D one like n log n (taken at 30 n log2 n
// entries); beyond direct_solver_max_dofs the AMG hierarchy is about twice the matrix. The mesh's
// boundary nodes add a quarter to estimated_dofs (the 3D cantilever's levels: 18,603 and
// 133,875 unknowns for 14,976 and 119,808). Measured there at 133,875 unknowns: a 935 MB factor
// and 2.45 GB peak, estimated 2.8 GB.
double estimated_level_bytes(const int dim, const double cells, const bool simplex) {
  const double dofs = 1.25 * estimated_dofs(dim, cells, simplex);
  const double row = dim == 3 ? 3. * 64. * 12. : 2. * 16. * 12.;
  double bytes = 5. * row * dofs;
  if (dofs <= static_cast<double>(direct_solver_max_dofs(dim)))
    bytes += dim == 3 ? 546e6 * std::pow(dofs / 93075., 4. / 3.)
                      : 8. * 30. * dofs * std::log2(std::max(dofs, 2.));
  else
    bytes += 2. * row * dofs;
  return bytes;
}
} // namespace

// Why: the budget of unknowns on the finest level: a few seconds for --coarse (3D 6e4, 2D
// 1.5e5), a minute or two on one core otherwise (3D 3e5, 2D 6e5).
template <int dim>
double SceneReference<dim>::budget() const {
  if (options.coarse)
    return dim == 3 ? 6e4 : 1.5e5;
  return dim == 3 ? 3e5 : 6e5;
}

template <int dim>
void SceneReference<dim>::mesh(const double h0, const unsigned int level) {
  if (on_mesh_body) {
    dof_handler.reset();
    mesh_body_level(problem, level, options.output_directory / "mesh.msh", triangulation);
    cell_element.assign(triangulation.n_active_cells(), -1);
    for (const auto& cell : triangulation.active_cell_iterators()) {
      const long e = problem.mesh_body->element_at(to_vec3(cell->center()));
      if (e < 0)
        throw std::runtime_error("a cell of the refined mesh lies in no element of '" +
                                 problem.mesh_body->file + "'");
      cell_element[cell->active_cell_index()] = e;
    }
  } else if (use_gmsh) {
    dof_handler.reset();
    gmsh_mesh(problem, h0, level, options.output_directory / "mesh.msh", triangulation);
  } else if (level == 0) {
    dof_handler.reset();
    box_grid(problem, h0, triangulation);
  } else
    triangulation.refine_global(1);
  if (!dof_handler)
    dof_handler = std::make_unique<DoFHandler<dim>>(triangulation);
}

// Why: box grids are made once and refined globally; Gmsh meshes every level (scene_mesh.h).
// The level-0 size starts at the body's thinnest part (halved while Gmsh's mesh has inverted
// cells) and doubles while three levels would exceed the budget and a coarser valid mesh exists
// (thin layers keep their one cell across). The DoFHandler is rebuilt with a new mesh.
template <int dim>
void SceneReference<dim>::make_grid(const unsigned int level) {
  if (level > 0) {
    mesh(base_size, level);
    return;
  }
  if (on_mesh_body) { // level 0 is the particles' own mesh
    base_size = problem.mesh_body->element_size();
    mesh(base_size, 0);
    return;
  }
  base_size = base_cell_size(problem, use_gmsh);
  mesh(base_size, 0);
  for (int attempt = 0; attempt < 6 && has_inverted_cells(triangulation); ++attempt)
    mesh(base_size /= 2, 0);
  for (int attempt = 0; attempt < 6; ++attempt) {
    const auto cells = triangulation.n_active_cells();
    if (estimated_dofs(dim, cells * std::pow(2., 2 * dim)) <= budget())
      break;
    mesh(2 * base_size, 0);
    if (triangulation.n_active_cells() >= cells || has_inverted_cells(triangulation)) {
      mesh(base_size, 0);
      break;
    }
    base_size *= 2;
  }
}

// Why: the default sequence ends at the last level that stays within the budget, with at
// least three levels for Richardson extrapolation; --coarse runs three levels, --levels N
// exactly N.
template <int dim>
unsigned int SceneReference<dim>::choose_levels() const {
  if (options.levels > 0)
    return options.levels;
  if (options.coarse && !on_mesh_body)
    return 3;
  const double dofs0 = estimated_dofs(dim, triangulation.n_active_cells(), on_mesh_body);
  unsigned int n = 1;
  while (n < 8 && dofs0 * std::pow(2., dim * n) <= budget())
    ++n;
  // A mesh body's level 0 is already as fine as the particles (its size is not the budget's to
  // choose): two levels give the estimate (their difference) where a third would not fit, and
  // --coarse runs at most three.
  if (on_mesh_body)
    return std::clamp(n, 2u, options.coarse ? 3u : 8u);
  return std::max(3u, n);
}

// Why: supports become constraints on the dofs whose support points they hold. A fixed or
// displacement support holds the nodes in its region (closed, tolerance 1e-6 λ); a mirror
// support clamps u = 0 on its plane's face of Ω, within the support's extent across the plane;
// a symmetry support holds the normal component on its plane (within its region, or all of
// the plane if the region is empty), the tangential ones stay free.
// A later support overrides an earlier one on the same dof, as in libpd.
template <int dim>
void SceneReference<dim>::setup_system() {
  dof_handler->distribute_dofs(fe);
  const auto n = dof_handler->n_dofs();
  std::vector<Point<dim>> points(n);
  DoFTools::map_dofs_to_support_points(*mapping, *dof_handler, points);
  dof_points = points;
  dof_component.assign(n, 0);
  std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
  for (const auto& cell : dof_handler->active_cell_iterators()) {
    cell->get_dof_indices(dofs);
    for (unsigned int i = 0; i < dofs.size(); ++i)
      dof_component[dofs[i]] = component[i];
  }

  const double tol = problem.tolerance();
  std::map<types::global_dof_index, double> value;
  support_dofs.assign(problem.supports.size(), {});
  for (std::size_t s = 0; s < problem.supports.size(); ++s) {
    const pd::SupportSpec& sup = problem.supports[s];
    const bool whole_planes = sup.region.boxes.empty() && sup.region.shapes.empty();
    // On a mesh body a fixed or displaced support holds the union of its particles' elements:
    // every node of the cells refined from them; filled with the lattice, the union of its
    // particles' lattice cells, as PD holds them. Mirror and symmetry planes stay planes.
    std::vector<std::uint8_t> in_elements;
    const bool by_cells = on_mesh_body && !problem.support_cells.empty();
    const bool by_elements = on_mesh_body && !by_cells && !sup.mirrors() && !sup.symmetric();
    if (by_elements) {
      in_elements.assign(n, 0);
      for (const auto& cell : dof_handler->active_cell_iterators())
        if (problem.support_elements[s][static_cast<std::size_t>(
                cell_element[cell->active_cell_index()])] != 0) {
          cell->get_dof_indices(dofs);
          for (const auto i : dofs)
            in_elements[i] = 1;
        }
    }
    for (types::global_dof_index i = 0; i < n; ++i) {
      const pd::Vec3 p = to_vec3(points[i]);
      const unsigned int c = dof_component[i];
      const bool in_region = by_elements ? in_elements[i] != 0
                             : by_cells && !sup.mirrors() && !sup.symmetric()
                                 ? problem.support_cells[s].touches(p, tol)
                                 : sup.region.contains(p, dim, tol);
      bool held = false;
      double g = 0.;
      for (unsigned int a = 0; a < dim; ++a) {
        const bool on_mirror = sup.mirror[a] && std::abs(p[a] - sup.mirror_at[a]) <= tol;
        const bool on_symmetry = sup.symmetry[a] && c == a &&
                                 std::abs(p[a] - sup.symmetry_at[a]) <= tol &&
                                 (whole_planes || in_region);
        held = held || (on_mirror && in_region) || on_symmetry;
      }
      if (in_region && sup.prescribed[c]) {
        held = true;
        g = sup.displacement[c];
      } else if (in_region && sup.fixed[c])
        held = true;
      if (held) {
        value[i] = g;
        support_dofs[s].push_back(i);
      }
    }
    if (support_dofs[s].empty())
      throw std::runtime_error("support '" + sup.name + "' holds no node of the FE mesh");
  }

  free_body = problem.supports.empty();
  if (free_body)
    pin_rigid_motion(value);

  constraints.clear();
  for (const auto& [dof, g] : value) {
    constraints.add_line(dof);
    constraints.set_inhomogeneity(dof, g);
  }
  constraints.close();

  DynamicSparsityPattern dsp(n);
  DoFTools::make_sparsity_pattern(*dof_handler, dsp, constraints, false);
  const IndexSet all_dofs = complete_index_set(n);
  system_matrix.reinit(all_dofs, all_dofs, dsp, MPI_COMM_WORLD);
  system_rhs.reinit(all_dofs, MPI_COMM_WORLD);
  solution.reinit(n);
}

// Why: a body no support holds is free to move rigidly, and K is singular. As in PD's static
// solve (libpd time/static_assembly.hpp, rigid_motion_pins), a node A (every component), the
// node B farthest from it (the components across AB) and in 3D the node C farthest from the line
// AB (the component along the normal of ABC) are held at zero: that removes the rigid motions
// and nothing else, so under balanced loads they carry no reaction.
template <int dim>
void SceneReference<dim>::pin_rigid_motion(std::map<types::global_dof_index, double>& value) const {
  const auto n = dof_points.size();
  const auto dominant = [](const Tensor<1, 3>& v) {
    unsigned int k = 0;
    for (unsigned int a = 1; a < dim; ++a)
      k = std::abs(v[a]) > std::abs(v[k]) ? a : k;
    return k;
  };
  const auto as3 = [](const Point<dim>& p) {
    Tensor<1, 3> t;
    for (unsigned int a = 0; a < dim; ++a)
      t[a] = p[a];
    return t;
  };
  types::global_dof_index a = 0;
  for (types::global_dof_index i = 1; i < n; ++i) {
    const auto& p = dof_points[i];
    const auto& q = dof_points[a];
    if (std::lexicographical_compare(p.begin_raw(), p.end_raw(), q.begin_raw(), q.end_raw()))
      a = i;
  }
  const auto farthest = [&](const auto& distance) {
    types::global_dof_index best = 0;
    for (types::global_dof_index i = 1; i < n; ++i)
      best = distance(as3(dof_points[i])) > distance(as3(dof_points[best])) ? i : best;
    return best;
  };
  const Tensor<1, 3> xa = as3(dof_points[a]);
  const Tensor<1, 3> xb = as3(dof_points[farthest([&](const auto& p) { return (p - xa).norm(); })]);
  const Tensor<1, 3> ab = xb - xa;
  Tensor<1, 3> xc, normal;
  if (dim == 3) {
    xc = as3(
        dof_points[farthest([&](const auto& p) { return cross_product_3d(ab, p - xa).norm(); })]);
    normal = cross_product_3d(ab, xc - xa);
  }
  const double tol = problem.tolerance();
  for (types::global_dof_index i = 0; i < n; ++i) {
    const Tensor<1, 3> p = as3(dof_points[i]);
    const unsigned int c = dof_component[i];
    if ((p - xa).norm() <= tol || ((p - xb).norm() <= tol && c != dominant(ab)) ||
        (dim == 3 && (p - xc).norm() <= tol && c == dominant(normal)))
      value[i] = 0.;
  }
}

// Why: a free body has an equilibrium only under loads of zero resultant and zero moment: both
// are integrated over the loads' cells as the load vector integrates them (before the pinned
// dofs' rows are cleared).
template <int dim>
void SceneReference<dim>::require_balanced_loads() const {
  FEValues<dim> fv(*mapping, fe, quadrature, update_quadrature_points | update_JxW_values);
  Tensor<1, 3> force, moment;
  double scale = 0., size = 0.;
  for (const auto& cell : dof_handler->active_cell_iterators()) {
    fv.reinit(cell);
    for (const unsigned int q : fv.quadrature_point_indices()) {
      const pd::Vec3 x = to_vec3(fv.quadrature_point(q));
      Tensor<1, 3> r;
      for (unsigned int a = 0; a < dim; ++a)
        r[a] = x[a] - 0.5 * (problem.bounding_box.lo[a] + problem.bounding_box.hi[a]);
      for (std::size_t l = 0; l < problem.loads.size(); ++l)
        if (!problem.loads[l].pressure && load_acts(l, cell, x)) {
          Tensor<1, 3> f;
          for (unsigned int a = 0; a < dim; ++a)
            f[a] = load_density[l][a] * fv.JxW(q);
          force += f;
          moment += cross_product_3d(r, f);
          scale += f.norm();
          size = std::max(size, r.norm());
        }
    }
  }
  if (force.norm() > 1e-9 * scale || moment.norm() > 1e-9 * scale * size) {
    std::ostringstream what;
    what << "no support holds the body and its loads are not balanced (resultant " << force
         << ", moment " << moment
         << "), so it has no equilibrium: add a support (e.g. a fixed box) or balance the loads";
    throw std::runtime_error(what.str());
  }
}

// Why: the free body's solution is defined up to a rigid motion; the one reported has none in
// the mean (zero mean displacement and rotation about the centroid, the L2 projection off the
// rigid motions), as PD's static solve reports it. Q2 holds the rigid motions exactly, so they
// are subtracted node by node.
template <int dim>
void SceneReference<dim>::remove_rigid_motion() {
  FEValues<dim> fv(*mapping, fe, quadrature,
                   update_values | update_quadrature_points | update_JxW_values);
  std::vector<Vector<double>> u(quadrature.size(), Vector<double>(dim));
  double volume = 0.;
  Tensor<1, 3> centre, mean;
  std::vector<std::pair<Tensor<1, 3>, Tensor<1, 3>>> samples; // (x, u) per quadrature point
  std::vector<double> weights;
  for (const auto& cell : dof_handler->active_cell_iterators()) {
    fv.reinit(cell);
    fv.get_function_values(solution, u);
    for (const unsigned int q : fv.quadrature_point_indices()) {
      Tensor<1, 3> x, v;
      for (unsigned int a = 0; a < dim; ++a) {
        x[a] = fv.quadrature_point(q)[a];
        v[a] = u[q][a];
      }
      volume += fv.JxW(q);
      centre += fv.JxW(q) * x;
      mean += fv.JxW(q) * v;
      samples.emplace_back(x, v);
      weights.push_back(fv.JxW(q));
    }
  }
  centre /= volume;
  mean /= volume;
  FullMatrix<double> inertia(3, 3);
  Vector<double> torque(3);
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Tensor<1, 3> r = samples[k].first - centre;
    const Tensor<1, 3> t = cross_product_3d(r, samples[k].second - mean);
    for (unsigned int a = 0; a < 3; ++a) {
      torque(a) += weights[k] * t[a];
      for (unsigned int b = 0; b < 3; ++b)
        inertia(a, b) += weights[k] * ((a == b ? r * r : 0.) - r[a] * r[b]);
    }
  }
  Tensor<1, 3> omega;
  if (dim == 3) {
    FullMatrix<double> inverse(3, 3);
    inverse.invert(inertia);
    Vector<double> w(3);
    inverse.vmult(w, torque);
    for (unsigned int a = 0; a < 3; ++a)
      omega[a] = w(a);
  } else
    omega[2] = torque(2) / inertia(2, 2);
  for (types::global_dof_index i = 0; i < dof_points.size(); ++i) {
    Tensor<1, 3> r;
    for (unsigned int a = 0; a < dim; ++a)
      r[a] = dof_points[i][a] - centre[a];
    const Tensor<1, 3> rigid = mean + cross_product_3d(omega, r);
    solution[i] -= rigid[dof_component[i]];
  }
}

// Why: a Gmsh mesh does not follow point loads (scene_problem.h), so a cell may hold part of such
// a load's lattice cells: the load integrals over it take Gauss points on sub-cells of about λ/4,
// which resolve the loaded cells' boundary to a quarter spacing (in 3D at most 16 sub-cells per
// edge). 0: the cell's own quadrature is exact (the tensor-product grid, whose planes contain
// the loaded cells, cells of the conforming loads, and cells away from every point load).
template <int dim>
unsigned int SceneReference<dim>::load_subdivisions(
    const typename DoFHandler<dim>::active_cell_iterator& cell) const {
  if (!use_gmsh)
    return 0;
  const BoundingBox<dim> box = cell->bounding_box();
  const double reach = problem.spacing; // curved faces bulge past the vertices' box
  bool touches = false;
  for (const SceneLoad& load : problem.loads) {
    bool meets = !load.pressure && !load.conforming;
    for (unsigned int a = 0; a < dim && meets; ++a)
      meets = load.bounds.lo[a] <= box.get_boundary_points().second[a] + reach &&
              box.get_boundary_points().first[a] - reach <= load.bounds.hi[a];
    touches = touches || meets;
  }
  if (!touches)
    return 0;
  const double cap = dim == 2 ? 256. : 16.;
  return static_cast<unsigned int>(
      std::clamp(std::ceil(4. * cell->diameter() / problem.spacing), 2., cap));
}

template <int dim>
bool SceneReference<dim>::load_acts(const std::size_t l,
                                    const typename DoFHandler<dim>::active_cell_iterator& cell,
                                    const pd::Vec3& x) const {
  const SceneLoad& load = problem.loads[l];
  // A mesh body filled with the lattice is loaded as a lattice body: over its particles' cells.
  if (on_mesh_body && problem.mesh_body->particle_element.empty())
    return load.elements[static_cast<std::size_t>(cell_element[cell->active_cell_index()])] != 0;
  return load.cells.contains(x);
}

template <int dim>
template <class Add>
void SceneReference<dim>::load_quadrature(
    const typename DoFHandler<dim>::active_cell_iterator& cell, FEValues<dim>& fv,
    const UpdateFlags flags, Add&& add) const {
  const unsigned int m = load_subdivisions(cell);
  if (m == 0) {
    for (const unsigned int q : fv.quadrature_point_indices())
      add(fv, q);
    return;
  }
  FEValues<dim> sub(*mapping, fe, QIterated<dim>(QGauss<1>(2), m), flags);
  sub.reinit(cell);
  for (const unsigned int q : sub.quadrature_point_indices())
    add(sub, q);
}

// Why: PD conserves each load's resultant exactly, so the density F/V uses the volume V of the
// loaded cells as this mesh's load quadrature integrates it (the same number as the particles'
// volumes when the mesh resolves the cells, which the grid planes ensure for box regions). In
// 2D the problem is per unit thickness t: V = area · t.
template <int dim>
void SceneReference<dim>::measure_loads() {
  const UpdateFlags flags = update_quadrature_points | update_JxW_values;
  FEValues<dim> fv(*mapping, fe, quadrature, flags);
  std::vector<double> volume(problem.loads.size(), 0.);
  for (const auto& cell : dof_handler->active_cell_iterators()) {
    fv.reinit(cell);
    load_quadrature(cell, fv, flags, [&](const FEValues<dim>& v, const unsigned int q) {
      for (std::size_t l = 0; l < problem.loads.size(); ++l)
        if (!problem.loads[l].pressure && load_acts(l, cell, to_vec3(v.quadrature_point(q))))
          volume[l] += v.JxW(q);
    });
  }
  const double thickness = dim == 2 ? problem.dimension.thickness : 1.;
  load_density.assign(problem.loads.size(), Tensor<1, dim>());
  for (std::size_t l = 0; l < problem.loads.size(); ++l) {
    const SceneLoad& load = problem.loads[l];
    if (load.pressure)
      continue;
    if (volume[l] <= 0.)
      throw std::runtime_error("load '" + load.name + "': its cells hold no part of the body");
    for (unsigned int c = 0; c < dim; ++c)
      load_density[l][c] = load.density ? load.value[c] : load.value[c] / (volume[l] * thickness);
  }
}

// Why: a pressure is the Neumann condition σn = −p n on the boundary faces that lie on its
// surface (all vertices on one part of it, scene_problem.h), integrated with the mapping, so a
// curved wall's normal turns along the face. The FE problem in 2D is per unit thickness: the
// traction needs no thickness factor.
template <int dim>
void SceneReference<dim>::add_pressure(const typename DoFHandler<dim>::active_cell_iterator& cell,
                                       Vector<double>& cell_rhs) const {
  if (!cell->at_boundary())
    return;
  std::unique_ptr<FEFaceValues<dim>> fv;
  for (const SceneLoad& load : problem.loads) {
    if (!load.pressure)
      continue;
    const double tol = std::max(problem.tolerance(), 1e-6 * load.surface.radius);
    for (const unsigned int f : cell->face_indices()) {
      if (!cell->face(f)->at_boundary())
        continue;
      unsigned int shared = ~0U;
      for (const unsigned int v : cell->face(f)->vertex_indices())
        shared &= pd::surface_patches(load.surface, to_vec3(cell->face(f)->vertex(v)), dim, tol);
      if (shared == 0)
        continue;
      if (!fv)
        fv = std::make_unique<FEFaceValues<dim>>(*mapping, fe, QGauss<dim - 1>(fe.degree + 1),
                                                 update_values | update_normal_vectors |
                                                     update_JxW_values);
      fv->reinit(cell, f);
      for (const unsigned int q : fv->quadrature_point_indices())
        for (unsigned int i = 0; i < fe.n_dofs_per_cell(); ++i)
          cell_rhs(i) -= load.pressure_value * fv->normal_vector(q)[component[i]] *
                         fv->shape_value_component(i, q, component[i]) * fv->JxW(q);
    }
  }
}

// Why: one cell's stiffness (elastic_common.h, with the Lamé constants of the body that holds
// the cell's centre, E scaled by the material's stiffness factor as PD scales c) and its load
// vector: ∫ b·φ_i over the load quadrature's points inside each load's cells, and the
// pressures on its boundary faces.
template <int dim>
void SceneReference<dim>::cell_system(const typename DoFHandler<dim>::active_cell_iterator& cell,
                                      FEValues<dim>& fv, FullMatrix<double>& cell_matrix,
                                      Vector<double>& cell_rhs) const {
  const unsigned int n = fe.n_dofs_per_cell();
  cell_matrix.reinit(n, n);
  cell_rhs.reinit(n);
  fv.reinit(cell);
  const int body = problem.body_at(to_vec3(cell->center()));
  if (body < 0)
    throw std::runtime_error("a cell of the mesh lies in no body (at " +
                             std::to_string(cell->center()[0]) + ", " +
                             std::to_string(cell->center()[1]) + ")");
  const pd::Material& m = problem.materials.at(static_cast<std::size_t>(
      problem.bodies.at(static_cast<std::size_t>(std::max(body, 0))).material));
  const LameConstants lame = lame_constants(m.youngs_modulus * m.stiffness_factor, m.poisson_ratio,
                                            problem.plane_stress());
  std::vector<Tensor<1, dim>> grad;
  add_elastic_cell_matrix(fv, component, lame, grad, cell_matrix);
  load_quadrature(cell, fv, update_values | update_quadrature_points | update_JxW_values,
                  [&](const FEValues<dim>& v, const unsigned int q) {
                    const pd::Vec3 x = to_vec3(v.quadrature_point(q));
                    for (std::size_t l = 0; l < problem.loads.size(); ++l)
                      if (!problem.loads[l].pressure && load_acts(l, cell, x))
                        for (unsigned int i = 0; i < n; ++i)
                          cell_rhs(i) += v.shape_value_component(i, q, component[i]) *
                                         load_density[l][component[i]] * v.JxW(q);
                  });
  add_pressure(cell, cell_rhs);
}

template <int dim>
void SceneReference<dim>::assemble_system() {
  measure_loads();
  FEValues<dim> fv(*mapping, fe, quadrature,
                   update_values | update_gradients | update_quadrature_points | update_JxW_values);
  FullMatrix<double> cell_matrix;
  Vector<double> cell_rhs;
  std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
  for (const auto& cell : dof_handler->active_cell_iterators()) {
    cell_system(cell, fv, cell_matrix, cell_rhs);
    cell->get_dof_indices(dofs);
    constraints.distribute_local_to_global(cell_matrix, cell_rhs, dofs, system_matrix, system_rhs);
  }
  system_matrix.compress(VectorOperation::add);
  system_rhs.compress(VectorOperation::add);
}

template <int dim>
void SceneReference<dim>::solve() {
  Point<dim> centre;
  for (unsigned int a = 0; a < dim; ++a)
    centre[a] = (problem.bounding_box.lo[a] + problem.bounding_box.hi[a]) / 2;
  if (free_body)
    require_balanced_loads();
  const CgStatistics stats = solve_elasticity(*dof_handler, system_matrix, system_rhs, constraints,
                                              centre, "AMG", 1e-10, 10000, solution);
  if (free_body)
    remove_rigid_motion();
  levels.back().solver = solver_summary(stats);
}

// Why: fe.json is what `pd verify` reads beside the PD run: per level the mesh and time, per
// probe the values of every level, the best estimate (Richardson-extrapolated when the last
// three levels are in the asymptotic range, else the finest value), its estimated error
// |extrapolated - finest| (or the last difference) and the observed order.
template <int dim>
void SceneReference<dim>::output_results(const double wall_time) const {
  write_atomically(options.output_directory / "fe.json", [&](std::ostream& out) {
    JsonWriter w(out);
    w.begin_object();
    w.value("scene", problem.path);
    w.value("dimension", dim);
    w.value("model", problem.model_name());
    // The constants this solve used, as libpd resolved them from the scene: `pd verify` checks
    // them against the PD run's, so a verdict never compares two materials.
    w.begin_array("materials");
    for (const pd::Material& m : problem.materials) {
      w.begin_object();
      w.value("name", m.name);
      w.value("youngs_modulus", m.youngs_modulus * m.stiffness_factor);
      w.value("poisson_ratio", m.poisson_ratio);
      w.end_object();
    }
    w.end_array();
    // What the FE body and its meshes are, beside what PD made of the scene: `pd verify` records
    // both, so a reader sees which continuum each verdict compares.
    w.begin_object("domain");
    if (on_mesh_body) {
      const MeshBodyElements& m = *problem.mesh_body;
      w.value("kind", "mesh body");
      w.value("file", m.file);
      w.value("pd_particles", static_cast<unsigned long>(m.particles()));
      w.value("description", m.description());
    } else {
      w.value("kind", use_gmsh ? "gmsh" : "box grid");
      w.value("description",
              use_gmsh ? "Q2 on Gmsh (OpenCASCADE) meshes of the scene's shapes, split once per "
                         "level"
                       : "Q2 on a tensor-product grid through the scene's box faces, refined "
                         "globally per level");
    }
    w.end_object();
    write_supports_on_a_plane(w, problem);
    w.value("wall_time_s", wall_time);
    if (!stopped_for_memory.empty())
      w.value("refinement_stopped", stopped_for_memory);
    w.begin_array("levels");
    for (const SceneLevel& l : levels) {
      w.begin_object();
      w.value("cells", l.cells);
      w.value("dofs", static_cast<unsigned long>(l.dofs));
      w.value("solver", l.solver);
      w.value("h", l.h);
      w.value("seconds", l.seconds);
      w.end_object();
    }
    w.end_array();
    w.begin_array("probes");
    for (std::size_t k = 0; k < problem.probes.size(); ++k) {
      const SceneProbe& probe = problem.probes[k];
      std::vector<double> values;
      for (const SceneLevel& l : levels)
        values.push_back(l.values[k]);
      const Richardson r = richardson(values, 2.);
      w.begin_object();
      w.value("name", probe.name);
      w.value("quantity", std::string(pd::name_of(probe.quantity)));
      w.value("component", std::string(pd::probe_component_words[static_cast<std::size_t>(
                               probe.component >= 3 ? probe.component + 3 : probe.component)]));
      w.begin_array("values");
      for (const double v : values)
        w.value("", v);
      w.end_array();
      // Where the FE read the probe (the particles libpd resolves for it), for a few points:
      // on an unstructured set they are not where the scene's `point` says.
      if (!probe.points.empty() && probe.points.size() <= 16) {
        w.begin_array("points");
        for (const pd::Vec3& x : probe.points) {
          w.begin_array();
          for (unsigned int d = 0; d < dim; ++d)
            w.value("", x[d]);
          w.end_array();
        }
        w.end_array();
      }
      w.value("value", r.extrapolated);
      w.value("error_estimate", r.error_estimate);
      w.value("observed_order", r.order);
      w.end_object();
    }
    w.end_array();
    w.end_object();
  });
}

template <int dim>
std::vector<SceneLevel> SceneReference<dim>::run() {
  const auto t_start = std::chrono::steady_clock::now();
  unsigned int n_levels = 0;
  const std::optional<pd::MemoryBudget> memory = pd::available_memory();
  for (unsigned int level = 0; level == 0 || level < n_levels; ++level) {
    const auto t0 = std::chrono::steady_clock::now();
    make_grid(level);
    if (level == 0)
      n_levels = choose_levels();
    const double need = estimated_level_bytes(dim, triangulation.n_active_cells(), on_mesh_body);
    if (memory && need > memory->bytes) {
      std::ostringstream what;
      what << "level " << level << " (" << triangulation.n_active_cells()
           << " cells) would need about " << pd::format_bytes(need) << ", more than the "
           << pd::format_bytes(memory->bytes) << " "
           << (memory->source == "PD_MEMORY_LIMIT" ? "PD_MEMORY_LIMIT allows" : "available");
      if (level == 0)
        throw std::runtime_error(what.str() + ": coarsen the scene's smallest feature or raise "
                                              "the memory limit");
      std::cerr << "pd-fem: " << what.str() << ": refinement stops at " << level
                << " levels (the finished ones are kept)" << std::endl;
      stopped_for_memory = what.str();
      break;
    }
    levels.emplace_back();
    SceneLevel& l = levels.back();
    setup_system();
    l.cells = triangulation.n_active_cells();
    l.dofs = dof_handler->n_dofs();
    l.h = base_size / std::pow(2., level);
    assemble_system();
    solve();
    evaluate_probes();
    l.seconds = seconds_since(t0);
    std::cerr << "[" << std::filesystem::path(problem.path).stem().string() << "] level " << level
              << "/" << n_levels - 1 << ": " << l.cells << " cells, " << l.dofs
              << " dofs, h = " << std::setprecision(4) << l.h << " m, " << l.solver << ", "
              << std::setprecision(3) << l.seconds << " s;";
    for (std::size_t k = 0; k < problem.probes.size(); ++k)
      std::cerr << " " << problem.probes[k].name << " = " << std::setprecision(8) << l.values[k];
    std::cerr << std::endl;
  }
  output_results(seconds_since(t_start));
  return levels;
}

std::vector<SceneLevel> solve_scene(const SceneProblem& problem, const SceneOptions& options) {
  if (problem.dim() == 2)
    return SceneReference<2>(problem, options).run();
  return SceneReference<3>(problem, options).run();
}

template class SceneReference<2>;
template class SceneReference<3>;
} // namespace pdfem
