#include "scene_mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/grid_in.h>
#include <deal.II/grid/manifold_lib.h>
#include <fstream>
#include <gmsh.h>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

namespace pdfem {
namespace {
namespace occ = gmsh::model::occ;
using DimTags = gmsh::vectorpair;

template <int dim>
pd::Vec3 to_vec3(const Point<dim>& p) {
  pd::Vec3 v{0, 0, 0};
  for (unsigned int d = 0; d < dim; ++d)
    v[d] = p[d];
  return v;
}

// A length beyond the whole scene: cylinders "through everything" and half-spaces become solids
// of this size around the scene's bounding box.
double beyond(const SceneProblem& p) {
  double d = 0.;
  for (int a = 0; a < 3; ++a)
    d += std::pow(p.bounding_box.hi[a] - p.bounding_box.lo[a], 2);
  return 4. * std::sqrt(d) + 1.;
}

int add_box(const pd::Box& b, const int dim) {
  if (dim == 2)
    return occ::addRectangle(b.lo[0], b.lo[1], 0., b.hi[0] - b.lo[0], b.hi[1] - b.lo[1]);
  return occ::addBox(b.lo[0], b.lo[1], b.lo[2], b.hi[0] - b.lo[0], b.hi[1] - b.lo[1],
                     b.hi[2] - b.lo[2]);
}

// The half-space (p - c)·n >= 0 cut down to a box of size R beyond the scene: built with its
// inner normal along z (3D) or x (2D), then rotated onto n about c.
int add_half_space(const Solid& s, const int dim, const double R) {
  const pd::Vec3& c = s.centre;
  const double nn =
      std::sqrt(s.normal[0] * s.normal[0] + s.normal[1] * s.normal[1] + s.normal[2] * s.normal[2]);
  const pd::Vec3 n{s.normal[0] / nn, s.normal[1] / nn, s.normal[2] / nn};
  if (dim == 2) {
    const int tag = occ::addRectangle(c[0], c[1] - R, 0., 2 * R, 2 * R);
    occ::rotate({{2, tag}}, c[0], c[1], 0., 0., 0., 1., std::atan2(n[1], n[0]));
    return tag;
  }
  const int tag = occ::addBox(c[0] - R, c[1] - R, c[2], 2 * R, 2 * R, 2 * R);
  // Rotate e_z onto n: about e_z × n = (-n_y, n_x, 0) by acos(n_z).
  const double s_xy = std::hypot(n[0], n[1]);
  if (s_xy > 1e-12)
    occ::rotate({{3, tag}}, c[0], c[1], c[2], -n[1], n[0], 0.,
                std::acos(std::clamp(n[2], -1., 1.)));
  else if (n[2] < 0)
    occ::rotate({{3, tag}}, c[0], c[1], c[2], 1., 0., 0., M_PI);
  return tag;
}

int add_solid(const Solid& s, const int dim, const double R) {
  switch (s.kind) {
  case Solid::Kind::box:
    return add_box(s.box, dim);
  case Solid::Kind::sphere:
    if (dim == 2)
      return occ::addDisk(s.centre[0], s.centre[1], 0., s.radius, s.radius);
    return occ::addSphere(s.centre[0], s.centre[1], s.centre[2], s.radius);
  case Solid::Kind::cylinder: {
    if (dim == 2) {
      if (s.axis != 2)
        throw std::runtime_error("a cylinder in 2D must have its axis along z (a disk)");
      return occ::addDisk(s.centre[0], s.centre[1], 0., s.radius, s.radius);
    }
    const double L = s.length > 0 && std::isfinite(s.length) ? s.length : 2 * R;
    pd::Vec3 base = s.centre, along{0, 0, 0};
    base[s.axis] -= L / 2;
    along[s.axis] = L;
    return occ::addCylinder(base[0], base[1], base[2], along[0], along[1], along[2], s.radius);
  }
  case Solid::Kind::half_space:
    return add_half_space(s, dim, R);
  }
  return -1;
}

// The union of the region's parts less the union of its holes.
DimTags add_region(const SolidRegion& region, const int dim, const double R) {
  DimTags parts, holes, out;
  std::vector<DimTags> map;
  for (const Solid& s : region.parts)
    parts.emplace_back(dim, add_solid(s, dim, R));
  for (const Solid& s : region.holes)
    holes.emplace_back(dim, add_solid(s, dim, R));
  if (parts.size() > 1) {
    occ::fuse({parts.front()}, DimTags(parts.begin() + 1, parts.end()), out, map);
    parts = out;
  }
  if (!holes.empty() && !parts.empty()) {
    occ::cut(parts, holes, out, map);
    parts = out;
  }
  return parts;
}

// Why: the body of the scene as CSG solids, split along the faces between bodies, of the
// supports and of the region loads' cells (intersected with the body first, so nothing outside
// it is added).
DimTags build_body(const SceneProblem& p, const int dim) {
  const double R = beyond(p);
  DimTags body, out;
  std::vector<DimTags> map;
  for (const SolidRegion& r : p.body_solids) {
    const DimTags part = add_region(r, dim, R);
    if (body.empty())
      body = part;
    else if (!part.empty()) {
      // Fragments, not a fusion: faces between bodies stay mesh faces, so every cell lies in
      // one material.
      occ::fragment(body, part, out, map);
      body = out;
    }
  }
  DimTags removed;
  for (const SolidRegion& r : p.removed_solids) {
    const DimTags part = add_region(r, dim, R);
    removed.insert(removed.end(), part.begin(), part.end());
  }
  if (!removed.empty()) {
    occ::cut(body, removed, out, map);
    body = out;
  }
  if (body.empty())
    throw std::runtime_error("the scene's continuum body is empty");
  DimTags pieces;
  for (const pd::Box& b : p.conforming) {
    DimTags copy;
    occ::copy(body, copy);
    occ::intersect({{dim, add_box(b, dim)}}, copy, out, map);
    pieces.insert(pieces.end(), out.begin(), out.end());
  }
  if (!pieces.empty()) {
    occ::fragment(body, pieces, out, map);
    body = out;
  }
  return body;
}
// Distance of p from the surface of a sphere or cylinder (signed: outside > 0).
double surface_distance(const Solid& s, const pd::Vec3& p, const int dim) {
  double r2 = 0.;
  for (int k = 0; k < dim; ++k)
    if (s.kind == Solid::Kind::sphere || k != s.axis)
      r2 += (p[k] - s.centre[k]) * (p[k] - s.centre[k]);
  return std::sqrt(r2) - s.radius;
}

// Why: Gmsh puts the nodes of curved surfaces on them, but the cells between are straight.
// Boundary faces whose vertices all lie on a sphere or cylinder of the scene get that surface as
// their manifold, so that MappingQ(2) curves them: the geometric error drops from O(h²) to
// O(h³).
template <int dim>
void attach_manifolds(const SceneProblem& problem, Triangulation<dim>& triangulation) {
  std::vector<Solid> round;
  for (const auto* regions : {&problem.body_solids, &problem.removed_solids})
    for (const SolidRegion& r : *regions)
      for (const auto* list : {&r.parts, &r.holes})
        for (const Solid& s : *list)
          if (s.kind == Solid::Kind::sphere || s.kind == Solid::Kind::cylinder)
            round.push_back(s);
  for (std::size_t k = 0; k < round.size(); ++k) {
    const Solid& s = round[k];
    const auto id = static_cast<types::manifold_id>(k + 1);
    bool used = false;
    for (const auto& cell : triangulation.active_cell_iterators())
      for (const auto& face : cell->face_iterators()) {
        if (!face->at_boundary())
          continue;
        bool on = true;
        for (const unsigned int v : face->vertex_indices())
          on =
              on && std::abs(surface_distance(s, to_vec3(face->vertex(v)), dim)) <= 1e-6 * s.radius;
        if (on) {
          face->set_manifold_id(id);
          used = true;
        }
      }
    if (!used)
      continue;
    Point<dim> centre;
    for (unsigned int d = 0; d < dim; ++d)
      centre[d] = s.centre[d];
    if constexpr (dim == 3) {
      if (s.kind == Solid::Kind::cylinder) {
        Tensor<1, 3> axis;
        axis[static_cast<unsigned int>(s.axis)] = 1.;
        triangulation.set_manifold(id, CylindricalManifold<3>(axis, centre));
        continue;
      }
    }
    triangulation.set_manifold(id, SphericalManifold<dim>(centre));
  }
}
// Why: a 2D pre-crack is a slit. Each segment, cut to the body, is embedded in the surface
// (fragment) and gathered in a physical group for Gmsh's Crack plugin, which duplicates its
// nodes after meshing; its ends on the body's boundary go to the plugin's open boundary, so an
// edge crack opens at its mouth. Returns the group tags (crack curves, open ends; 0 if none).
std::pair<int, int> embed_cracks(const SceneProblem& p, DimTags& body) {
  if (p.cracks.empty())
    return {0, 0};
  DimTags lines, out;
  std::vector<DimTags> map;
  for (const pd::Crack& c : p.cracks) {
    const pd::Vec3 &a = c.vertices.at(0), &b = c.vertices.at(1);
    const int line = occ::addLine(occ::addPoint(a[0], a[1], 0.), occ::addPoint(b[0], b[1], 0.));
    DimTags copy;
    occ::copy(body, copy);
    occ::intersect({{1, line}}, copy, out, map);
    lines.insert(lines.end(), out.begin(), out.end());
  }
  if (lines.empty())
    return {0, 0};
  occ::fragment(body, lines, out, map);
  body.clear();
  std::vector<int> curves;
  for (const auto& [d, tag] : out) {
    if (d == 2)
      body.emplace_back(d, tag);
    else
      curves.push_back(tag);
  }
  occ::synchronize();
  DimTags ends, curve_tags;
  for (const int c : curves)
    curve_tags.emplace_back(1, c);
  gmsh::model::getBoundary(curve_tags, ends, true, false, false);
  std::vector<int> open;
  for (const auto& [d, tag] : ends) {
    std::vector<double> x;
    gmsh::model::getValue(0, std::abs(tag), {}, x);
    if (!p.in_domain({x[0], x[1], 0.}, -1e-9 * p.spacing))
      open.push_back(std::abs(tag));
  }
  const int group = gmsh::model::addPhysicalGroup(1, curves);
  const int open_group = open.empty() ? 0 : gmsh::model::addPhysicalGroup(0, open);
  return {group, open_group};
}

void split_cracks(const std::pair<int, int> groups) {
  if (groups.first == 0)
    return;
  gmsh::plugin::setNumber("Crack", "Dimension", 1);
  gmsh::plugin::setNumber("Crack", "PhysicalGroup", groups.first);
  gmsh::plugin::setNumber("Crack", "OpenBoundaryPhysicalGroup", groups.second);
  gmsh::plugin::run("Crack");
  // Only the cells are written: the crack faces become boundary faces of the mesh.
  DimTags remove{{1, groups.first}};
  if (groups.second != 0)
    remove.emplace_back(0, groups.second);
  gmsh::model::removePhysicalGroups(remove);
}

// Why: Gmsh's Crack plugin (4.8) duplicates the nodes of a crack but may leave cells of both
// sides on one copy where thin cells meet the crack's mouth (measured on the DCB scene: one copy
// of the mouth node in 1 cell, the other in 5 cells of both arms), so the arms stay joined at a
// node and the FE solves a closed crack. Each cell that touches a node with two copies gets the
// copy of its own side of the crack line (the side its centroid lies on), in the .msh text before
// deal.II reads it (Gmsh 4.8's API cannot change a cell's nodes).
void give_crack_sides_their_own_nodes(const SceneProblem& p, const std::filesystem::path& msh) {
  std::ifstream in(msh);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);)
    lines.push_back(line);
  const auto section = [&](const std::string& name) {
    const auto at = std::find(lines.begin(), lines.end(), name);
    if (at == lines.end())
      throw std::runtime_error(msh.string() + ": no " + name + " section");
    return static_cast<std::size_t>(at - lines.begin());
  };
  // $Nodes (format 4.1): blocks of "dim tag parametric n", n tags, n coordinate lines.
  std::map<std::size_t, std::array<double, 2>> position;
  std::size_t k = section("$Nodes") + 1;
  std::size_t blocks = std::stoul(lines[k++]);
  for (std::size_t b = 0; b < blocks; ++b) {
    std::istringstream head(lines[k++]);
    int entity_dim = 0, entity = 0, parametric = 0;
    std::size_t n = 0;
    head >> entity_dim >> entity >> parametric >> n;
    for (std::size_t i = 0; i < n; ++i) {
      std::istringstream xyz(lines[k + n + i]);
      double x = 0., y = 0.;
      xyz >> x >> y;
      position[std::stoul(lines[k + i])] = {x, y};
    }
    k += 2 * n;
  }
  // Nodes on a crack segment, grouped by position: a group of two is a node and its copy.
  const double tol = 1e-9 * p.spacing;
  std::map<std::pair<long long, long long>, std::vector<std::size_t>> at_point;
  std::map<std::size_t, std::size_t> crack_of;
  for (const auto& [tag, x] : position)
    for (std::size_t c = 0; c < p.cracks.size(); ++c) {
      const pd::Vec3 &a = p.cracks[c].vertices.at(0), &b = p.cracks[c].vertices.at(1);
      const double ex = b[0] - a[0], ey = b[1] - a[1], length2 = ex * ex + ey * ey;
      const double t = ((x[0] - a[0]) * ex + (x[1] - a[1]) * ey) / length2;
      const double off = std::abs((x[0] - a[0]) * ey - (x[1] - a[1]) * ex) / std::sqrt(length2);
      if (off < tol && t > -tol && t < 1. + tol) {
        at_point[{std::llround(x[0] / tol), std::llround(x[1] / tol)}].push_back(tag);
        crack_of[tag] = c;
      }
    }
  std::map<std::size_t, std::array<std::size_t, 2>> copies; // either tag -> {one, other}
  for (const auto& [point, tags] : at_point)
    if (tags.size() == 2)
      for (const std::size_t tag : tags)
        copies[tag] = {tags[0], tags[1]};
  if (copies.empty())
    return;
  // $Elements: blocks of "dim tag type n", then n lines "element node...". Only cells change.
  k = section("$Elements") + 1;
  blocks = std::stoul(lines[k++]);
  for (std::size_t b = 0; b < blocks; ++b) {
    std::istringstream head(lines[k++]);
    int entity_dim = 0, entity = 0, type = 0;
    std::size_t n = 0;
    head >> entity_dim >> entity >> type >> n;
    for (std::size_t i = 0; i < n && entity_dim == 2; ++i) {
      std::istringstream cell(lines[k + i]);
      std::size_t element = 0;
      cell >> element;
      std::vector<std::size_t> nodes;
      for (std::size_t v; cell >> v;)
        nodes.push_back(v);
      double cx = 0., cy = 0.;
      for (const std::size_t v : nodes) {
        cx += position.at(v)[0] / static_cast<double>(nodes.size());
        cy += position.at(v)[1] / static_cast<double>(nodes.size());
      }
      bool changed = false;
      for (std::size_t& v : nodes)
        if (const auto twin = copies.find(v); twin != copies.end()) {
          const pd::Crack& c = p.cracks[crack_of.at(v)];
          const pd::Vec3 &a = c.vertices.at(0), &e = c.vertices.at(1);
          const bool left = (e[0] - a[0]) * (cy - a[1]) - (e[1] - a[1]) * (cx - a[0]) > 0.;
          const std::size_t mine = twin->second[left ? 0 : 1];
          changed = changed || mine != v;
          v = mine;
        }
      if (changed) {
        std::ostringstream line;
        line << element;
        for (const std::size_t v : nodes)
          line << ' ' << v;
        lines[k + i] = line.str() + ' ';
      }
    }
    k += n;
  }
  std::ofstream out(msh);
  for (const std::string& line : lines)
    out << line << '\n';
}
} // namespace

double base_cell_size(const SceneProblem& problem, const bool gmsh) {
  double h = std::numeric_limits<double>::max();
  const auto side = [&](const pd::Box& box) {
    for (int a = 0; a < problem.dim(); ++a)
      if (box.hi[a] - box.lo[a] > problem.tolerance())
        h = std::min(h, box.hi[a] - box.lo[a]);
  };
  for (const pd::BodySpec& b : problem.bodies)
    for (const pd::Box& box : b.region.boxes)
      side(box);
  for (const SolidRegion& r : problem.body_solids)
    for (const auto* list : {&r.parts, &r.holes})
      for (const Solid& s : *list)
        if (s.kind == Solid::Kind::cylinder || s.kind == Solid::Kind::sphere)
          h = std::min(h, s.radius);
  // Gmsh grades the cells between thin supports or loaded layers and the rest: starting from
  // the largest size would leave distorted cells there.
  if (gmsh)
    for (const pd::Box& box : problem.conforming)
      side(box);
  return h;
}

template <int dim>
void box_grid(const SceneProblem& problem, const double h, Triangulation<dim>& triangulation) {
  std::vector<std::vector<double>> steps(dim);
  Point<dim> lo, hi;
  for (unsigned int a = 0; a < dim; ++a) {
    const std::vector<double>& planes = problem.planes[a];
    lo[a] = planes.front();
    hi[a] = planes.back();
    for (std::size_t k = 0; k + 1 < planes.size(); ++k) {
      const double length = planes[k + 1] - planes[k];
      const long n = std::max(1L, std::lround(length / h));
      for (long i = 0; i < n; ++i)
        steps[a].push_back(length / static_cast<double>(n));
    }
  }
  Triangulation<dim> box;
  GridGenerator::subdivided_hyper_rectangle(box, steps, lo, hi, false);
  std::set<typename Triangulation<dim>::active_cell_iterator> outside;
  for (const auto& cell : box.active_cell_iterators())
    if (!problem.in_domain(to_vec3(cell->center())))
      outside.insert(cell);
  if (outside.size() == box.n_active_cells())
    throw std::runtime_error("the scene's continuum body is empty (every cell lies behind a "
                             "mirror support or in a hole)");
  triangulation.clear();
  if (outside.empty())
    triangulation.copy_triangulation(box);
  else
    GridGenerator::create_triangulation_with_removed_cells(box, outside, triangulation);
}

template <int dim>
void gmsh_mesh(const SceneProblem& problem, const double h0, const unsigned int level,
               const std::filesystem::path& msh_file, Triangulation<dim>& triangulation) {
  gmsh::initialize();
  try {
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::model::add("scene");
    DimTags body = build_body(problem, dim);
    const auto crack_groups = dim == 2 ? embed_cracks(problem, body) : std::pair<int, int>{0, 0};
    occ::synchronize();
    // Only the cells are written (a physical group of the body's entities): boundary ids all
    // stay 0, supports are found by position.
    std::vector<int> tags;
    for (const auto& [d, tag] : body)
      if (d == dim)
        tags.push_back(tag);
    gmsh::model::addPhysicalGroup(dim, tags, 1);
    // Subdivision halves the cells Gmsh makes: ask for 2h to get h.
    gmsh::option::setNumber("Mesh.MeshSizeMax", 2 * h0);
    // The sizes OpenCASCADE gives its points (a fraction of the model) would override h0.
    gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
    if (problem.curved)
      gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 8.);
    gmsh::option::setNumber("Mesh.ElementOrder", 1);
    if (dim == 2) {
      gmsh::option::setNumber("Mesh.Algorithm", 6); // Frontal-Delaunay (8 crashes in 4.8.4)
      gmsh::option::setNumber("Mesh.RecombineAll", 1);
      gmsh::option::setNumber("Mesh.SubdivisionAlgorithm", 1); // all quadrilaterals
    } else {
      gmsh::option::setNumber("Mesh.SubdivisionAlgorithm", 2); // all hexahedra
    }
    gmsh::model::mesh::generate(dim);
    // Level k is level 0 split k times (new boundary nodes land on the CAD surfaces): every
    // cell halves per level, also where small features set the size, as Richardson needs.
    for (unsigned int k = 0; k < level; ++k)
      gmsh::model::mesh::refine();
    split_cracks(crack_groups);
    std::filesystem::create_directories(msh_file.parent_path());
    gmsh::write(msh_file.string());
    if (crack_groups.first != 0)
      give_crack_sides_their_own_nodes(problem, msh_file);
  } catch (...) {
    gmsh::finalize();
    throw;
  }
  gmsh::finalize();
  triangulation.clear();
  GridIn<dim> grid_in;
  grid_in.attach_triangulation(triangulation);
  // The stream reader: reading the file through the Gmsh API merges the nodes the Crack plugin
  // duplicated, which would close the cracks.
  std::ifstream in(msh_file);
  grid_in.read_msh(in);
  if (!triangulation.all_reference_cells_are_hyper_cube())
    throw std::runtime_error("Gmsh left cells that are not quadrilaterals / hexahedra");
  // Level 0 is chosen among valid meshes (SceneReference::make_grid); a split one must stay so.
  if (level > 0 && has_inverted_cells(triangulation))
    throw std::runtime_error("Gmsh's level-" + std::to_string(level) +
                             " mesh (level 0 split that many times) has inverted cells");
  attach_manifolds(problem, triangulation);
}

template <int dim>
bool has_inverted_cells(const Triangulation<dim>& triangulation) {
  for (const auto& cell : triangulation.active_cell_iterators()) {
    Point<dim> vertices[GeometryInfo<dim>::vertices_per_cell];
    for (unsigned int v = 0; v < GeometryInfo<dim>::vertices_per_cell; ++v)
      vertices[v] = cell->vertex(v);
    Tensor<0, dim> jacobians[GeometryInfo<dim>::vertices_per_cell];
    GeometryInfo<dim>::alternating_form_at_vertices(vertices, jacobians);
    for (const auto& j : jacobians)
      if (!(static_cast<double>(j) > 0))
        return true;
  }
  return false;
}

template bool has_inverted_cells<2>(const Triangulation<2>&);
template bool has_inverted_cells<3>(const Triangulation<3>&);
template void box_grid<2>(const SceneProblem&, double, Triangulation<2>&);
template void box_grid<3>(const SceneProblem&, double, Triangulation<3>&);
template void gmsh_mesh<2>(const SceneProblem&, double, unsigned int, const std::filesystem::path&,
                           Triangulation<2>&);
template void gmsh_mesh<3>(const SceneProblem&, double, unsigned int, const std::filesystem::path&,
                           Triangulation<3>&);
} // namespace pdfem
