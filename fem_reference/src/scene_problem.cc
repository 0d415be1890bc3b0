#include "scene_problem.h"

#include "libpd/app/probes.hpp"
#include "libpd/discretisation/lattice.hpp"
#include "libpd/discretisation/surface_load.hpp"
#include "report.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <stdexcept>

namespace pdfem {
namespace {

void add_box_planes(const pd::Box& box, const int dim, std::array<std::vector<double>, 3>& planes) {
  for (int a = 0; a < dim; ++a) {
    planes[a].push_back(box.lo[a]);
    planes[a].push_back(box.hi[a]);
  }
}

// Why: PD spreads a load over the particles it selects in proportion to their volumes, i.e. a
// uniform force density over the union of their cells. The mesh needs faces on the boundary of
// that union: the faces of the bounding box of the load's cells are added (exact for the usual
// box-shaped loaded layers).
pd::Box cell_bounds(const LatticeCells& cells) {
  pd::Box box;
  std::array<long long, 3> lo{}, hi{};
  bool first = true;
  for (const auto& c : cells.cells) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = first ? c[a] : std::min(lo[a], c[a]);
      hi[a] = first ? c[a] : std::max(hi[a], c[a]);
    }
    first = false;
  }
  for (int a = 0; a < cells.dim; ++a) {
    box.lo[a] = cells.origin[a] + static_cast<double>(lo[a]) * cells.spacing;
    box.hi[a] = cells.origin[a] + static_cast<double>(hi[a] + 1) * cells.spacing;
  }
  return box;
}

SolidRegion solids_of(const pd::Region& region) {
  SolidRegion out;
  for (const pd::Box& box : region.boxes) {
    Solid s;
    s.box = box;
    out.parts.push_back(s);
  }
  out.parts.insert(out.parts.end(), region.shapes.begin(), region.shapes.end());
  out.holes = region.minus;
  return out;
}

// Why: box shapes and box holes are grid planes too; any other shape needs Gmsh.
bool add_region_planes(const pd::Region& region, const int dim,
                       std::array<std::vector<double>, 3>& planes) {
  bool curved = false;
  for (const pd::Box& box : region.boxes)
    add_box_planes(box, dim, planes);
  for (const auto* list : {&region.shapes, &region.minus})
    for (const pd::Shape& s : *list) {
      if (s.kind == pd::Shape::Kind::box)
        add_box_planes(s.box, dim, planes);
      else
        curved = true;
    }
  return curved;
}

// Sorted, without duplicates (closer than `tol`), clipped to [lo, hi].
std::vector<double> cleaned(std::vector<double> v, const double lo, const double hi,
                            const double tol) {
  for (double& x : v)
    x = std::clamp(x, lo, hi);
  v.push_back(lo);
  v.push_back(hi);
  std::sort(v.begin(), v.end());
  std::vector<double> out;
  for (const double x : v)
    if (out.empty() || x - out.back() > tol)
      out.push_back(x);
  return out;
}

void check_supported(const pd::Scene& scene) {
  const pd::ModelSpec& m = scene.model;
  if (m.dimension.dim != 2 && m.dimension.dim != 3)
    throw std::runtime_error("pd-fem --scene: dimension " + std::to_string(m.dimension.dim) +
                             " is not supported (2 or 3)");
  if (m.effects.damage)
    throw std::runtime_error("pd-fem --scene: the scene has the effect 'damage'; the FE "
                             "reference is linear elastic (remove damage to verify the elastic "
                             "response)");
  if (m.effects.plasticity)
    throw std::runtime_error("pd-fem --scene: the scene has the effect 'plasticity'; the FE "
                             "reference is linear elastic");
  if (!m.cracks.empty() && m.dimension.dim == 3)
    throw std::runtime_error("pd-fem --scene: the scene has the pre-crack '" +
                             m.cracks.front().name +
                             "'; the FE reference represents 2D cracks (segments) only");
  // The FE domain is built from boxes and shapes, or from one mesh body's elements; a body of
  // given particles has only their bounding box as its region, which is not its shape.
  const pd::BodySpec* mesh = nullptr;
  for (const pd::BodySpec& b : m.bodies) {
    if (!b.points)
      continue;
    if (!b.mesh)
      throw std::runtime_error("pd-fem --scene: body '" + b.name +
                               "' is given as particles; the FE reference needs its shape");
    if (mesh != nullptr)
      throw std::runtime_error("pd-fem --scene: bodies '" + mesh->name + "' and '" + b.name +
                               "' are both meshes; the FE reference takes one mesh body");
    mesh = &b;
  }
  if (mesh != nullptr) {
    if (!m.cracks.empty())
      throw std::runtime_error("pd-fem --scene: the scene has the pre-crack '" +
                               m.cracks.front().name + "' in the mesh body '" + mesh->name +
                               "'; the FE reference on mesh bodies has no cracks");
    for (const pd::LoadSpec& l : m.loads)
      if (l.load.kind == pd::BoxRegionLoad::Kind::pressure)
        throw std::runtime_error("pd-fem --scene: pressure load '" + l.name +
                                 "' on the mesh body '" + mesh->name +
                                 "'; the FE reference on mesh bodies takes region, point and "
                                 "body loads");
  }
  if (m.lattice.convention != pd::LatticeConvention::cell_centered)
    std::cerr << "pd-fem: warning: node-based lattice: its particles stand λ/2 beyond the boxes' "
                 "faces; the FE body is the boxes themselves\n";
  if (m.lattice.position_jitter > 0 || m.lattice.volume_variation > 0)
    std::cerr << "pd-fem: warning: the lattice's jitter / volume variation is ignored by the FE "
                 "reference\n";
}

pd::ParticleSet scene_particles(const pd::Scene& scene) {
  if (scene.particles)
    return scene.particles->particles;
  return pd::generate_lattice(scene.model.dimension, scene.model.lattice, scene.model.bodies);
}

LatticeCells cells_of(const pd::ModelSpec& spec, const pd::ParticleSet& particles,
                      const std::vector<std::uint32_t>& members) {
  LatticeCells cells;
  cells.origin = spec.lattice.origin;
  cells.spacing = spec.lattice.spacing;
  cells.dim = spec.dimension.dim;
  for (const std::uint32_t i : members)
    cells.cells.insert(cells.cell_of(particles.position[i]));
  return cells;
}

// Why: on a mesh body a particle stands for its element, so a set of its particles (a load's, a
// support's) acts on the union of their elements. Particles of other bodies are not counted.
std::vector<std::uint8_t> elements_of(const MeshBodyElements& mesh,
                                      const std::vector<std::uint32_t>& members) {
  std::vector<std::uint8_t> out(mesh.size(), 0);
  for (const std::uint32_t i : members) {
    if (i < mesh.first_particle || i >= mesh.first_particle + mesh.particles())
      continue;
    const std::size_t k = i - mesh.first_particle;
    const long e = mesh.particle_element.empty() ? static_cast<long>(k) : mesh.particle_element[k];
    if (e >= 0)
      out[static_cast<std::size_t>(e)] = 1;
  }
  return out;
}

SceneLoad translate_load(const pd::ModelSpec& spec, const pd::ParticleSet& particles,
                         const pd::LoadSpec& load, const std::optional<MeshBodyElements>& mesh) {
  SceneLoad out;
  out.name = load.name;
  using Kind = pd::BoxRegionLoad::Kind;
  if (load.load.kind == Kind::pressure) {
    // The same test as PD's: a surface that bounds no body is an error in both.
    if (pd::pressure_forces(spec.dimension, spec.lattice.spacing, spec.bodies, particles,
                            particles.size(), load.load.surface, load.load.pressure)
            .particle.empty())
      throw std::runtime_error("pressure load '" + load.name +
                               "' acts on no particle: its surface bounds no body");
    out.pressure = true;
    out.pressure_value = load.load.pressure;
    out.surface = load.load.surface;
    return out;
  }
  const auto members = pd::load_particles(spec, particles, load, particles.size());
  if (members.empty())
    throw std::runtime_error("load '" + load.name + "' acts on no particle");
  out.cells = cells_of(spec, particles, members);
  if (mesh) {
    out.elements = elements_of(*mesh, members);
    if (std::count(out.elements.begin(), out.elements.end(), 1) == 0)
      throw std::runtime_error("load '" + load.name + "' acts on no particle of the mesh body");
  }
  out.bounds = cell_bounds(out.cells);
  out.conforming = load.load.kind != Kind::point;
  switch (load.load.kind) {
  case Kind::body:
    out.density = true;
    out.value = load.load.value;
    break;
  case Kind::total:
  case Kind::point: // the particles nearest the point share it in proportion to volume
    out.value = load.load.value;
    break;
  case Kind::per_area:
  case Kind::per_length:
    for (int c = 0; c < 3; ++c)
      out.value[c] = load.load.value[c] * load.load.measure;
    break;
  case Kind::pressure:
    break;
  }
  return out;
}

// Why: the FE meshes of a mesh body are its elements refined, so the body must be the whole FE
// domain (lattice bodies only where mirror supports take them away) and its elements must be
// the particles libpd made: each particle is checked to be its element's centroid.
MeshBodyElements mesh_body_of(const pd::ModelSpec& spec, const pd::ParticleSet& particles,
                              const std::size_t body, const std::vector<pd::Region>& removed) {
  const int dim = spec.dimension.dim;
  const double tol = 1e-6 * spec.lattice.spacing;
  const pd::BodySpec& b = spec.bodies[body];
  for (std::size_t i = 0; i < particles.size(); ++i) {
    if (particles.body[i] == body)
      continue;
    const bool taken = std::any_of(removed.begin(), removed.end(), [&](const pd::Region& r) {
      return r.contains(particles.position[i], dim, tol);
    });
    if (!taken)
      throw std::runtime_error(
          "pd-fem --scene: body '" + spec.bodies[particles.body[i]].name +
          "' is a lattice body beside the mesh body '" + b.name +
          "'; the FE reference on a mesh body takes it alone (lattice bodies only behind "
          "mirror supports)");
  }
  MeshBodyElements mesh = read_mesh_body_elements(b, body, dim, spec.lattice.spacing);
  const auto first = std::find(particles.body.begin(), particles.body.end(), body);
  mesh.first_particle = static_cast<std::size_t>(first - particles.body.begin());
  const auto count = static_cast<std::size_t>(
      std::count(particles.body.begin(), particles.body.end(), static_cast<std::uint16_t>(body)));
  if (b.fill == pd::MeshFill::lattice) {
    // The particles are lattice sites inside the elements: each acts through the element holding
    // it (one within a tenth of its size when a site lies on the boundary).
    for (std::size_t k = 0; k < count; ++k) {
      const long e = mesh.element_at(particles.position[mesh.first_particle + k]);
      if (e < 0)
        throw std::runtime_error("pd-fem --scene: particle " + std::to_string(k) + " of body '" +
                                 b.name + "' lies in no element of '" + b.mesh_file +
                                 "' read again");
      mesh.particle_element.push_back(e);
    }
    return mesh;
  }
  if (count != mesh.size())
    throw std::runtime_error("pd-fem --scene: '" + b.mesh_file + "' read again has " +
                             std::to_string(mesh.size()) + " elements, libpd made " +
                             std::to_string(count) + " particles of it");
  for (std::size_t e = 0; e < mesh.size(); ++e) {
    pd::Vec3 centroid{0, 0, 0};
    for (int k = 0; k <= dim; ++k)
      for (std::size_t a = 0; a < 3; ++a)
        centroid[a] += mesh.corners[e][static_cast<std::size_t>(k)][a] / (dim + 1);
    const pd::Vec3& x = particles.position[mesh.first_particle + e];
    for (std::size_t a = 0; a < 3; ++a)
      if (std::abs(centroid[a] - x[a]) > 1e-6 * spec.lattice.spacing)
        throw std::runtime_error("pd-fem --scene: element " + std::to_string(e) + " of '" +
                                 b.mesh_file + "' read again is not where libpd's particle is");
  }
  return mesh;
}

std::size_t support_index(const pd::Scene& scene, const pd::ProbeSpec& probe) {
  const auto& supports = scene.model.supports;
  for (std::size_t s = 0; s < supports.size(); ++s)
    if (supports[s].name == probe.support)
      return s;
  throw std::runtime_error("probe '" + probe.name + "' reads the reaction of support '" +
                           probe.support + "', which the scene does not have");
}

// Why: PD's displacement and stress probes read particles, the ones libpd resolves for them;
// the FE solution is evaluated at those particles' positions. resolve_probes reads only the
// particles and the model's dimension and lattice, so a model without bonds is enough
// (building the bond families of a fine lattice would cost more than the FE solve).
std::vector<SceneProbe> translate_probes(const pd::Scene& scene, const pd::ParticleSet& particles,
                                         const SceneProblem& problem) {
  using Q = pd::ProbeSpec::Quantity;
  std::vector<pd::ProbeSpec> located;
  for (const pd::ProbeSpec& spec : scene.probes) {
    if (spec.quantity == Q::damage)
      throw std::runtime_error("probe '" + spec.name +
                               "' reads damage; the FE reference is linear elastic");
    if (spec.quantity != Q::reaction && spec.quantity != Q::moment)
      located.push_back(spec);
  }
  pd::Model model;
  model.spec = scene.model;
  model.particles = particles;
  const auto resolved = pd::resolve_probes(located, model);
  std::vector<SceneProbe> out;
  std::size_t next = 0;
  for (const pd::ProbeSpec& spec : scene.probes) {
    SceneProbe p;
    p.name = spec.name;
    p.component = spec.component;
    p.quantity = spec.quantity;
    if (spec.quantity == Q::reaction || spec.quantity == Q::moment) {
      p.support = support_index(scene, spec);
      p.about = spec.about;
      out.push_back(std::move(p));
      continue;
    }
    const pd::ResolvedProbe& r = resolved[next++];
    p.direction = r.direction;
    for (const std::uint32_t i : r.particles) {
      const pd::Vec3& x = particles.position[i];
      if (!problem.in_domain(x, problem.tolerance()))
        throw std::runtime_error("probe '" + p.name +
                                 "' reads a particle outside the continuum body (behind a "
                                 "clamp plane or in a hole); the FE solution has no value there");
      p.points.push_back(x);
    }
    out.push_back(std::move(p));
  }
  return out;
}
} // namespace

std::array<long long, 3> LatticeCells::cell_of(const pd::Vec3& p) const {
  std::array<long long, 3> c{0, 0, 0};
  for (int a = 0; a < dim; ++a)
    c[a] = static_cast<long long>(std::floor((p[a] - origin[a]) / spacing));
  return c;
}

bool LatticeCells::touches(const pd::Vec3& p, const double tol) const {
  for (int corner = 0; corner < (1 << dim); ++corner) {
    pd::Vec3 q = p;
    for (int a = 0; a < dim; ++a)
      q[static_cast<std::size_t>(a)] += (corner >> a & 1) != 0 ? tol : -tol;
    if (contains(q))
      return true;
  }
  return false;
}

std::string SceneProblem::model_name() const {
  if (dim() == 3)
    return "3D";
  return plane_stress() ? "2D plane stress" : "2D plane strain";
}

bool SceneProblem::in_domain(const pd::Vec3& p, const double tol) const {
  const auto holds = [&](const pd::BodySpec& b) { return b.region.contains(p, dim(), tol); };
  const auto takes = [&](const pd::Region& r) { return r.contains(p, dim(), -tol); };
  return std::any_of(bodies.begin(), bodies.end(), holds) &&
         std::none_of(removed.begin(), removed.end(), takes);
}

int SceneProblem::body_at(const pd::Vec3& p) const {
  if (mesh_body) // the FE domain is the mesh body's elements (lattice bodies stand behind clamps)
    return static_cast<int>(mesh_body->body);
  for (std::size_t b = 0; b < bodies.size(); ++b)
    if (bodies[b].region.contains(p, dim(), 0.))
      return static_cast<int>(b);
  // A straight-edged cell along a curved hole reaches a little into the hole: its body is the
  // one whose region holds the point with the holes left out.
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    pd::Region filled = bodies[b].region;
    filled.minus.clear();
    if (filled.contains(p, dim(), tolerance()))
      return static_cast<int>(b);
  }
  return -1;
}

// Why: a PD particle's displacement is the mean of its cell's, so a support that holds one
// layer of particles across an axis holds the layer's plane, not a band: where the support leaves
// a component free the material turns about that plane (the end column of a DCB's arm, moved in y
// and free in x, is a hinge). An FE that held every node of the support's box would hold that
// band straight and make the arm about twice as stiff (measured on the dcb scene: −37 % PD vs
// FE). A support that holds every component clamps the layer either way, and keeps its region
// (the clamp's face, where PD's multi-layer clamps act too); mirror and symmetry supports are
// planes of their own.
std::optional<SupportLayer> support_layer(const pd::SupportSpec& s,
                                          const pd::ParticleSet& particles, const int dim,
                                          const double tol) {
  if (s.mirrors() || s.symmetric())
    return std::nullopt;
  bool some_free = false;
  for (int c = 0; c < dim; ++c)
    some_free = some_free || !(s.fixed[c] || s.prescribed[c]);
  if (!some_free)
    return std::nullopt;
  std::array<double, 3> lo{}, hi{};
  std::size_t held = 0;
  for (std::uint32_t i = 0; i < particles.size(); ++i) {
    const pd::Vec3& x = particles.position[i];
    if (!s.region.contains(x, dim, tol))
      continue;
    for (int a = 0; a < dim; ++a) {
      lo[a] = held == 0 ? x[a] : std::min(lo[a], x[a]);
      hi[a] = held == 0 ? x[a] : std::max(hi[a], x[a]);
    }
    ++held;
  }
  // One layer across exactly one axis: a single particle (or a line of them in 3D) is a point or
  // an edge, singular in the continuum, and keeps its region.
  std::optional<SupportLayer> layer;
  int layers = 0;
  for (int a = 0; a < dim; ++a)
    if (held > 1 && hi[a] - lo[a] <= tol) {
      layer = SupportLayer{a, lo[a]};
      ++layers;
    }
  return layers == 1 ? layer : std::nullopt;
}

void write_supports_on_a_plane(JsonWriter& w, const SceneProblem& problem) {
  w.begin_array("supports_on_a_plane");
  for (std::size_t s = 0; s < problem.supports.size(); ++s)
    if (const auto& layer = problem.support_layers[s]) {
      w.begin_object();
      w.value("name", problem.supports[s].name);
      w.value("axis", std::string(1, "xyz"[layer->axis]));
      w.value("at", layer->at);
      w.end_object();
    }
  w.end_array();
}

SceneProblem read_scene_problem(const std::string& path) {
  return translate_scene(pd::load_scene(path));
}

SceneProblem translate_scene(const pd::Scene& scene) {
  check_supported(scene);
  const pd::ModelSpec& spec = scene.model;
  SceneProblem p;
  p.path = scene.path;
  p.title = scene.title;
  p.dimension = spec.dimension;
  p.spacing = spec.lattice.spacing;
  p.materials = spec.materials;
  p.bodies = spec.bodies;
  p.supports = spec.supports;
  const int dim = spec.dimension.dim;

  std::array<std::vector<double>, 3> planes;
  bool first = true;
  for (const pd::BodySpec& b : spec.bodies) {
    p.body_solids.push_back(solids_of(b.region));
    p.curved = add_region_planes(b.region, dim, planes) || p.curved;
    for (const pd::Box& box : b.region.cover(dim)) {
      for (int a = 0; a < 3; ++a) {
        p.bounding_box.lo[a] = first ? box.lo[a] : std::min(p.bounding_box.lo[a], box.lo[a]);
        p.bounding_box.hi[a] = first ? box.hi[a] : std::max(p.bounding_box.hi[a], box.hi[a]);
      }
      first = false;
    }
  }
  for (const pd::SupportSpec& s : spec.supports) {
    p.curved = add_region_planes(s.region, dim, planes) || p.curved;
    if (s.region.only_boxes())
      p.conforming.insert(p.conforming.end(), s.region.boxes.begin(), s.region.boxes.end());
    if (s.mirrors()) {
      p.removed.push_back(s.region);
      p.removed_solids.push_back(solids_of(s.region));
    }
  }

  // A crack is a slit in the mesh: only the Gmsh route makes one.
  p.cracks = spec.cracks;
  p.curved = p.curved || !p.cracks.empty();

  const pd::ParticleSet particles = scene_particles(scene);
  for (std::size_t b = 0; b < spec.bodies.size(); ++b)
    if (spec.bodies[b].mesh)
      p.mesh_body = mesh_body_of(spec, particles, b, p.removed);
  if (p.mesh_body)
    for (const pd::SupportSpec& s : spec.supports) {
      std::vector<std::uint32_t> held;
      for (std::uint32_t i = 0; i < particles.size(); ++i)
        if (s.region.contains(particles.position[i], dim, p.tolerance()))
          held.push_back(i);
      p.support_elements.push_back(elements_of(*p.mesh_body, held));
      if (!p.mesh_body->particle_element.empty())
        p.support_cells.push_back(cells_of(spec, particles, held));
    }
  for (pd::SupportSpec& s : p.supports) {
    p.support_layers.push_back(p.mesh_body || !s.region.only_boxes()
                                   ? std::nullopt
                                   : support_layer(s, particles, dim, p.tolerance()));
    const auto& layer = p.support_layers.back();
    if (!layer)
      continue;
    // The layer's plane must be a mesh face within the support's box, and is all it holds.
    const auto a = static_cast<std::size_t>(layer->axis);
    planes[a].push_back(layer->at);
    for (pd::Box& box : s.region.boxes) {
      pd::Box face = box;
      if (layer->at - box.lo[a] > p.tolerance())
        face.hi[a] = layer->at;
      else
        face.lo[a] = layer->at;
      if (face.hi[a] - face.lo[a] > p.tolerance())
        p.conforming.push_back(face);
      box.lo[a] = box.hi[a] = layer->at;
    }
  }
  // Why: a load's cells become grid planes of the tensor-product grid (nested, exact) and, for
  // region loads (layers, patches), faces of a Gmsh mesh. A point load's cells do not: many of
  // them on a curved body made as many small features and slivers between them (80 loads on a
  // hole failed after minutes); the load integrals resolve those cells by quadrature.
  for (const pd::LoadSpec& load : spec.loads) {
    p.loads.push_back(translate_load(spec, particles, load, p.mesh_body));
    const SceneLoad& l = p.loads.back();
    if (l.conforming && !l.pressure)
      p.conforming.push_back(l.bounds);
    if (!l.pressure)
      add_box_planes(l.bounds, dim, planes);
    else if (l.surface.kind == pd::Shape::Kind::box)
      add_box_planes(l.surface.box, dim, planes);
    else
      p.curved = true;
  }
  p.probes = translate_probes(scene, particles, p);

  // The domain's extent is the bodies' bounding box less what the mirror supports take away.
  for (int a = 0; a < dim; ++a)
    p.planes[a] = cleaned(planes[a], p.bounding_box.lo[a], p.bounding_box.hi[a], p.tolerance());
  return p;
}

} // namespace pdfem
