// A libpd scene read as a continuum problem: the facts pd-fem --scene needs to build the same
// linear-elastic problem in deal.II, taken from libpd itself (pd::load_scene, the particles it
// generates, the probes it resolves), so that every rule about a scene lives once, in libpd.
// No deal.II here: scene_reference.cc turns this into meshes, constraints and loads.
#pragma once

#include "libpd/io/scene.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace pdfem {

class JsonWriter;

// The set of lattice cells (cell-centred convention: the cell of edge λ around a particle) a
// load acts on: PD shares a load among these particles in proportion to their volumes, which is
// a uniform force density over the union of their cells.
struct LatticeCells {
  pd::Vec3 origin{0, 0, 0};
  double spacing = 1.;
  int dim = 3;
  std::set<std::array<long long, 3>> cells;

  std::array<long long, 3> cell_of(const pd::Vec3& p) const;
  bool contains(const pd::Vec3& p) const { return cells.count(cell_of(p)) > 0; }
  // Whether p lies in the closure of the cells: within `tol` of one of them.
  bool touches(const pd::Vec3& p, double tol) const;
};

struct SceneLoad {
  std::string name;
  bool density = false;    // true: `value` is a force density [N/m³] (kind body)
  pd::Vec3 value{0, 0, 0}; // the total force [N] spread over `cells`, or the density
  LatticeCells cells;
  // A mesh body's particles among them (per element of SceneProblem::mesh_body): PD shares the
  // load over those elements, so the density acts on their union.
  std::vector<std::uint8_t> elements;
  pd::Box bounds;         // of `cells`
  bool conforming = true; // the Gmsh mesh has faces on `bounds` (not for point loads)
  // A pressure [Pa] on the mesh's boundary faces that lie on `surface` (instead of cells).
  bool pressure = false;
  double pressure_value = 0.;
  pd::Shape surface;
};

struct SceneProbe {
  std::string name;
  // As PD reads it (pd::ProbeSpec): a mean over the probe's particles, a support's reaction or
  // moment, an opening between two particles; damage has no FE value.
  pd::ProbeSpec::Quantity quantity = pd::ProbeSpec::Quantity::displacement;
  int component = 0;            // as pd::ProbeSpec::component
  std::vector<pd::Vec3> points; // the particles PD reads (an opening: 'point', then 'to')
  std::size_t support = 0;      // reaction, moment: index into SceneProblem::supports
  pd::Vec3 about{0, 0, 0};      // moment
  pd::Vec3 direction{0, 0, 0};  // opening: unit vector from 'point' to 'to'
};

// A body read from a mesh or a geometry file (pd::BodySpec::mesh): the elements libpd made its
// particles of, read again through Gmsh as libpd reads them (particle k of the body is element
// k), so that the FE meshes are this mesh refined and a region of particles is the union of
// their elements. Linear simplices only (triangles, tetrahedra): dim + 1 corners each.
struct MeshBodyElements {
  std::string file;
  bool geometry = false;          // meshed from a geometry file at the lattice spacing
  std::size_t body = 0;           // index into SceneProblem::bodies
  std::size_t first_particle = 0; // its particles: [first_particle, first_particle + particles())
  int dim = 3;
  std::vector<std::array<pd::Vec3, 4>> corners;
  // A body filled with the lattice (pd::MeshFill::lattice): the element holding each of its
  // particles (a lattice site), so that a region of particles acts on the elements holding
  // them. Empty when particle k is element k.
  std::vector<long> particle_element;

  std::size_t size() const { return corners.size(); }
  std::size_t particles() const {
    return particle_element.empty() ? corners.size() : particle_element.size();
  }
  // What the FE meshes are, for fe.json's domain.
  std::string description() const;
  // The edge of the regular simplex of the elements' mean measure: a mesh file's h (a geometry
  // is meshed at λ).
  double element_size() const;
  // The element holding p (the one whose smallest barycentric coordinate is largest, among
  // those near p); -1 if no element is within a tenth of its own size of p.
  long element_at(const pd::Vec3& p) const;
  void build_locator();

private:
  pd::Vec3 origin_{0, 0, 0};
  double step_ = 1.;
  std::array<long, 3> bins_{1, 1, 1};
  std::vector<std::vector<std::uint32_t>> grid_; // elements whose bounding box meets each bin
};

// A solid of the scene's geometry as Gmsh builds it: a box or one of pd::Region's shapes.
using Solid = pd::Shape;

// A region as solids: the union of `parts` less the union of `holes`.
struct SolidRegion {
  std::vector<Solid> parts;
  std::vector<Solid> holes;
};

// A plane x[axis] = at, within a support's region.
struct SupportLayer {
  int axis = 0;
  double at = 0.;
};

struct SceneProblem {
  std::string path;
  std::string title;
  pd::ModelDimension dimension;
  double spacing = 0.; // λ
  std::vector<pd::Material> materials;
  std::vector<pd::BodySpec> bodies;
  std::vector<pd::Region> removed; // regions of mirror supports: behind the clamp planes
  std::vector<pd::SupportSpec> supports;
  std::vector<SceneLoad> loads;
  std::vector<SceneProbe> probes;
  // The same geometry as solids, for Gmsh: the bodies, and the mirror supports' regions that
  // are taken out of them; `conforming`: boxes whose faces the mesh must contain (supports, the
  // cells of region loads; a point load's few cells are resolved by quadrature instead). `curved`:
  // some shape is not a box, so the tensor-product grid cannot mesh it.
  std::vector<SolidRegion> body_solids;
  std::vector<SolidRegion> removed_solids;
  std::vector<pd::Box> conforming;
  std::vector<pd::Crack> cracks; // 2D segments: slits, both faces traction-free (Gmsh only)
  bool curved = false;
  // The scene's body is a mesh (one mesh body; lattice bodies only behind mirror clamps): the FE
  // meshes are its elements refined (scene_mesh.h, mesh_body_level), and fixed or displaced
  // supports hold the union of their particles' elements (per support, per element).
  std::optional<MeshBodyElements> mesh_body;
  std::vector<std::vector<std::uint8_t>> support_elements;
  // On a mesh body filled with the lattice: per support, its particles' cells (the region PD
  // holds), which the FE holds instead of elements.
  std::vector<LatticeCells> support_cells;
  // Per support: where its particles form one layer across an axis and it leaves a component
  // free, the plane of that layer (support_layer in scene_problem.cc); the support's region in
  // `supports` is then its boxes flattened onto that plane, so the FE holds the plane's nodes.
  std::vector<std::optional<SupportLayer>> support_layers;
  pd::Box bounding_box;                      // of the domain
  std::array<std::vector<double>, 3> planes; // per axis: every box face of the scene (sorted)

  int dim() const { return dimension.dim; }
  bool plane_stress() const { return dim() == 2 && dimension.plane == pd::PlaneMode::plane_stress; }
  // "3D", "2D plane stress" or "2D plane strain".
  std::string model_name() const;
  // Is p in the continuum body: in a body's region (grown by `tol`) and not strictly inside a
  // removed region (shrunk by `tol`)?
  bool in_domain(const pd::Vec3& p, double tol = 0.) const;
  // The body whose material holds at p (the first listed containing it, as the lattice does;
  // a point in a hole goes to the body the hole is cut from); -1 outside every body.
  int body_at(const pd::Vec3& p) const;
  // Tolerance of region membership, as libpd's: 1e-6 λ.
  double tolerance() const { return 1e-6 * spacing; }
};

// The elements of mesh body `body` (bodies[index]) as libpd made its particles (Gmsh, in
// scene_mesh_body.cc); throws std::runtime_error for elements other than linear simplices.
MeshBodyElements read_mesh_body_elements(const pd::BodySpec& body, std::size_t index, int dim,
                                         double spacing);

// Read `path` with pd::load_scene (throws pd::SceneError) and translate it. Throws
// std::runtime_error naming any feature the FE problem cannot represent (damage, plasticity,
// an unsupported shape, a probe on no body point).
SceneProblem read_scene_problem(const std::string& path);

// fe.json's `supports_on_a_plane`: the supports held on their layer's plane (name, axis, at).
void write_supports_on_a_plane(JsonWriter& w, const SceneProblem& problem);
// The same for a scene already read (tests set the features the reader cannot express yet).
SceneProblem translate_scene(const pd::Scene& scene);

} // namespace pdfem
