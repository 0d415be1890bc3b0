// Mesh bodies (scene_problem.h, MeshBodyElements; scene_mesh.h, mesh_body_level): the elements
// libpd made a body's particles of, and the FE meshes refined from them.
#include "scene_mesh.h"

#include <algorithm>
#include <cmath>
#include <deal.II/grid/grid_in.h>
#include <fstream>
#include <gmsh.h>
#include <limits>
#include <map>
#include <stdexcept>

namespace pdfem {
namespace {

// Why: the FE meshes must be the mesh libpd made the particles of, so Gmsh is driven exactly as
// libpd drives it (libpd/src/io/mesh_file.cpp: one thread, the file opened, a geometry meshed
// with Mesh.MeshSizeMax = λ). STL surfaces, which libpd first turns into a volume, are not
// taken here.
void open_as_libpd(const pd::BodySpec& body, const int dim, const double spacing) {
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::option::setNumber("General.NumThreads", 1);
  std::string extension = std::filesystem::path(body.mesh_file).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension == ".stl")
    throw std::runtime_error("pd-fem --scene: body '" + body.name + "' is the STL surface '" +
                             body.mesh_file +
                             "'; the FE reference on mesh bodies takes meshes and CAD files "
                             "(.msh, .geo, .step, ...), not STL surfaces yet");
  gmsh::open(body.mesh_file);
  if (body.mesh_is_geometry) {
    gmsh::option::setNumber("Mesh.MeshSizeMax", spacing);
    gmsh::model::mesh::generate(dim);
  }
}

// Runs `calls` in a Gmsh session opened as libpd opens the body's file; Gmsh's own errors
// (it throws bare values) become messages naming the file.
template <class F>
void with_body_mesh(const pd::BodySpec& body, const int dim, const double spacing, F&& calls) {
  try {
    open_as_libpd(body, dim, spacing);
    calls();
  } catch (const std::exception&) {
    gmsh::finalize();
    throw;
  } catch (...) {
    std::string error;
    gmsh::logger::getLastError(error);
    gmsh::finalize();
    throw std::runtime_error("pd-fem --scene: Gmsh failed on '" + body.mesh_file +
                             "': " + (error.empty() ? std::string("no message") : error));
  }
  gmsh::finalize();
}

double barycentric_minimum(const std::array<pd::Vec3, 4>& c, const int dim, const pd::Vec3& p) {
  // Solve p - c0 = Σ λ_k (c_k - c0) for the dim coordinates λ_1..λ_dim by Cramer's rule.
  double m[3][3] = {}, rhs[3] = {};
  for (int a = 0; a < dim; ++a) {
    for (int k = 0; k < dim; ++k)
      m[a][k] = c[static_cast<std::size_t>(k + 1)][static_cast<std::size_t>(a)] -
                c[0][static_cast<std::size_t>(a)];
    rhs[a] = p[static_cast<std::size_t>(a)] - c[0][static_cast<std::size_t>(a)];
  }
  const auto det = [&](const double(&x)[3][3]) {
    if (dim == 2)
      return x[0][0] * x[1][1] - x[0][1] * x[1][0];
    return x[0][0] * (x[1][1] * x[2][2] - x[1][2] * x[2][1]) -
           x[0][1] * (x[1][0] * x[2][2] - x[1][2] * x[2][0]) +
           x[0][2] * (x[1][0] * x[2][1] - x[1][1] * x[2][0]);
  };
  const double d = det(m);
  double lambda0 = 1., smallest = std::numeric_limits<double>::max();
  for (int k = 0; k < dim; ++k) {
    double mk[3][3];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        mk[a][b] = b == k ? rhs[a] : m[a][b];
    const double l = det(mk) / d;
    lambda0 -= l;
    smallest = std::min(smallest, l);
  }
  return std::min(smallest, lambda0);
}
} // namespace

void MeshBodyElements::build_locator() {
  pd::Vec3 lo = corners.front()[0], hi = lo;
  double size = 0.;
  for (const auto& c : corners)
    for (int k = 0; k <= dim; ++k)
      for (std::size_t a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], c[static_cast<std::size_t>(k)][a]);
        hi[a] = std::max(hi[a], c[static_cast<std::size_t>(k)][a]);
        size = std::max(size, std::abs(c[static_cast<std::size_t>(k)][a] - c[0][a]));
      }
  origin_ = lo;
  // About one element per bin: the bins are as large as the largest element's extent.
  step_ = std::max(size, 1e-300);
  for (std::size_t a = 0; a < 3; ++a)
    bins_[a] =
        static_cast<int>(a) < dim ? static_cast<long>(std::floor((hi[a] - lo[a]) / step_)) + 1 : 1;
  grid_.assign(static_cast<std::size_t>(bins_[0] * bins_[1] * bins_[2]), {});
  for (std::size_t e = 0; e < corners.size(); ++e) {
    std::array<long, 3> b0{0, 0, 0}, b1{0, 0, 0};
    for (std::size_t a = 0; a < static_cast<std::size_t>(dim); ++a) {
      double l = corners[e][0][a], h = l;
      for (int k = 1; k <= dim; ++k) {
        l = std::min(l, corners[e][static_cast<std::size_t>(k)][a]);
        h = std::max(h, corners[e][static_cast<std::size_t>(k)][a]);
      }
      b0[a] = std::clamp(static_cast<long>(std::floor((l - origin_[a]) / step_)), 0L, bins_[a] - 1);
      b1[a] = std::clamp(static_cast<long>(std::floor((h - origin_[a]) / step_)), 0L, bins_[a] - 1);
    }
    for (long k = b0[2]; k <= b1[2]; ++k)
      for (long j = b0[1]; j <= b1[1]; ++j)
        for (long i = b0[0]; i <= b1[0]; ++i)
          grid_[static_cast<std::size_t>((k * bins_[1] + j) * bins_[0] + i)].push_back(
              static_cast<std::uint32_t>(e));
  }
}

double MeshBodyElements::element_size() const {
  double measure = 0.;
  for (const auto& c : corners) {
    std::array<pd::Vec3, 3> e{};
    for (std::size_t k = 0; k < 3; ++k)
      for (std::size_t a = 0; a < 3; ++a)
        e[k][a] = c[k + 1][a] - c[0][a];
    if (dim == 2)
      measure += 0.5 * std::abs(e[0][0] * e[1][1] - e[0][1] * e[1][0]);
    else
      measure += std::abs(e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                          e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                          e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0])) /
                 6.;
  }
  measure /= static_cast<double>(corners.size());
  // Regular triangle: A = √3/4 a²; regular tetrahedron: V = a³/(6√2).
  return dim == 2 ? std::sqrt(4. * measure / std::sqrt(3.))
                  : std::cbrt(6. * std::sqrt(2.) * measure);
}

long MeshBodyElements::element_at(const pd::Vec3& p) const {
  std::array<long, 3> b{0, 0, 0};
  for (std::size_t a = 0; a < static_cast<std::size_t>(dim); ++a)
    b[a] = std::clamp(static_cast<long>(std::floor((p[a] - origin_[a]) / step_)), 0L, bins_[a] - 1);
  long best = -1;
  double best_value = -0.1;
  for (const std::uint32_t e :
       grid_[static_cast<std::size_t>((b[2] * bins_[1] + b[1]) * bins_[0] + b[0])]) {
    const double v = barycentric_minimum(corners[e], dim, p);
    if (v > best_value) {
      best_value = v;
      best = e;
    }
  }
  return best;
}

std::string MeshBodyElements::description() const {
  return std::string(dim == 2 ? "P2 triangles" : "P2 tetrahedra") + ": the " +
         std::to_string(size()) + " elements of " + file +
         (geometry ? " meshed by Gmsh at the lattice spacing" : "") +
         (particle_element.empty() ? " (one PD particle each)"
                                   : " (the PD particles: the lattice sites inside them)") +
         ", split once per level" + (geometry ? ", new boundary nodes on the CAD surfaces" : "");
}

MeshBodyElements read_mesh_body_elements(const pd::BodySpec& body, const std::size_t index,
                                         const int dim, const double spacing) {
  MeshBodyElements out;
  out.file = body.mesh_file;
  out.geometry = body.mesh_is_geometry;
  out.body = index;
  out.dim = dim;
  with_body_mesh(body, dim, spacing, [&] {
    std::vector<std::size_t> node_tags;
    std::vector<double> coords, parametric;
    gmsh::model::mesh::getNodes(node_tags, coords, parametric, -1, -1, true, false);
    std::map<std::size_t, pd::Vec3> node;
    for (std::size_t i = 0; i < node_tags.size(); ++i)
      node[node_tags[i]] = {coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]};
    std::vector<int> types;
    gmsh::model::mesh::getElementTypes(types, dim);
    // The particles' order: element types as Gmsh lists them, elements of a type in its order.
    for (const int type : types) {
      std::string name;
      int type_dim = 0, order = 0, nodes_per = 0, primary = 0;
      std::vector<double> local;
      gmsh::model::mesh::getElementProperties(type, name, type_dim, order, nodes_per, local,
                                              primary);
      if (primary != dim + 1)
        throw std::runtime_error("pd-fem --scene: body '" + body.name + "' ('" + body.mesh_file +
                                 "') has elements of type " + name +
                                 "; the FE reference on mesh bodies takes triangles (2D) or "
                                 "tetrahedra (3D) only");
      std::vector<std::size_t> tags, nodes;
      gmsh::model::mesh::getElementsByType(type, tags, nodes);
      const auto n = static_cast<std::size_t>(nodes_per);
      for (std::size_t e = 0; e < tags.size(); ++e) {
        std::array<pd::Vec3, 4> c{};
        for (std::size_t k = 0; k <= static_cast<std::size_t>(dim); ++k)
          c[k] = node.at(nodes[e * n + k]);
        out.corners.push_back(c);
      }
    }
  });
  if (out.corners.empty())
    throw std::runtime_error("pd-fem --scene: body '" + body.name + "' ('" + body.mesh_file +
                             "') has no element of the scene's dimension");
  out.build_locator();
  return out;
}

template <int dim>
void mesh_body_level(const SceneProblem& problem, const unsigned int level,
                     const std::filesystem::path& msh_file, Triangulation<dim>& triangulation) {
  const pd::BodySpec& body = problem.bodies.at(problem.mesh_body->body);
  with_body_mesh(body, dim, problem.spacing, [&] {
    gmsh::model::mesh::setOrder(1);
    // Each split halves every element (new boundary nodes of a geometry on its CAD surfaces):
    // the levels are nested refinements of the particles' elements, as Richardson needs.
    for (unsigned int k = 0; k < level; ++k)
      gmsh::model::mesh::refine();
    // Only the body's cells are written: one physical group of its entities of dimension dim.
    gmsh::vectorpair groups;
    gmsh::model::getPhysicalGroups(groups);
    for (const auto& [d, tag] : groups) {
      std::string name;
      gmsh::model::getPhysicalName(d, tag, name);
      if (!name.empty())
        gmsh::model::removePhysicalName(name);
    }
    gmsh::model::removePhysicalGroups();
    gmsh::vectorpair entities;
    gmsh::model::getEntities(entities, dim);
    std::vector<int> tags;
    for (const auto& [d, tag] : entities)
      tags.push_back(tag);
    gmsh::model::addPhysicalGroup(dim, tags, 1);
    gmsh::option::setNumber("Mesh.SaveAll", 0);
    std::filesystem::create_directories(msh_file.parent_path());
    gmsh::write(msh_file.string());
  });
  triangulation.clear();
  GridIn<dim> grid_in;
  grid_in.attach_triangulation(triangulation);
  std::ifstream in(msh_file);
  grid_in.read_msh(in);
  if (!triangulation.all_reference_cells_are_simplex())
    throw std::runtime_error("the refined mesh of '" + body.mesh_file +
                             "' has cells that are not simplices");
}

template void mesh_body_level<2>(const SceneProblem&, unsigned int, const std::filesystem::path&,
                                 Triangulation<2>&);
template void mesh_body_level<3>(const SceneProblem&, unsigned int, const std::filesystem::path&,
                                 Triangulation<3>&);
} // namespace pdfem
