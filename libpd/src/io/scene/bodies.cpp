// The `bodies` list: regions of the lattice or particle files, each made of one material.
#include "bind.hpp"
#include "libpd/core/memory.hpp"
#include "libpd/core/plugin.hpp"
#include "libpd/discretisation/graded_set.hpp"
#include "libpd/discretisation/lattice_fill.hpp"
#include "libpd/io/mesh_file.hpp"
#include "libpd/io/particle_file.hpp"
#include "sections.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>

namespace pd::scene {

namespace {

/// `bodies[].graded`: a generated graded particle set (discretisation/graded_set.hpp).
constexpr Key graded_keys[] = {
    {.name = "shape",
     .type = Type::choice,
     .doc = "the zone grid",
     .choices = enum_words<GradedShape>,
     .bind = field_with_default<&GradedSetSpec::shape>()},
    {.name = "focal_half_distance",
     .type = Type::number,
     .doc = "ellipse: c of eq. 114, half the distance between the focal points (a crack between "
            "them is a 'cracks' entry)",
     .unit = "m",
     .range = positive,
     .example = "0.0416667",
     .bind = field<&GradedSetSpec::focal_half_distance>()},
    {.name = "xi_max",
     .type = Type::number,
     .doc = "ellipse: ξ of the boundary; semi-axes c cosh ξ_max, c sinh ξ_max",
     .range = positive,
     .bind = field_with_default<&GradedSetSpec::xi_max>()},
    {.name = "box",
     .type = Type::box,
     .doc = "box: the region [[lo], [hi]]",
     .unit = "m",
     .example = "[[0, 0], [1, 0.5]]",
     .show = Show::commented},
    {.name = "grading",
     .type = Type::number,
     .doc = "box: the last zone's width along x over the first's (geometric growth)",
     .range = positive,
     .bind = field_with_default<&GradedSetSpec::grading>()},
    {.name = "zones",
     .type = Type::vector,
     .doc = "numbers of zones along ξ and η (ellipse) or x and y (box), integers ≥ 1",
     .bind = {.default_text =
                  [] {
                    const auto z = GradedSetSpec{}.zones;
                    return fmt::format("[{}, {}]", z[0], z[1]);
                  }}},
    {.name = "pattern",
     .type = Type::integer,
     .doc = "each zone holds pattern × pattern particles (the paper: 5)",
     .range = at_least_one,
     .bind = field_with_default<&GradedSetSpec::pattern>()},
    {.name = "noise",
     .type = Type::number,
     .doc = "Monte Carlo step, a fraction of the particle's size h (Fig. 8)",
     .range = non_negative,
     .bind = field_with_default<&GradedSetSpec::noise>()},
    {.name = "min_spacing",
     .type = Type::number,
     .doc = "a move is kept only if the particle stays this × (h_a + h_b) from its neighbours",
     .range = non_negative,
     .bind = field_with_default<&GradedSetSpec::min_spacing>()},
    {.name = "sweeps",
     .type = Type::integer,
     .doc = "Monte Carlo sweeps over all particles; sizes are refreshed every fifth; once "
            "particles have moved, each one's volume is its Voronoi cell",
     .range = non_negative,
     .bind = field_with_default<&GradedSetSpec::sweeps>()},
    {.name = "seed",
     .type = Type::integer,
     .doc = "seed of the random moves: the same seed gives the same particles",
     .range = non_negative,
     .bind = field_with_default<&GradedSetSpec::seed>()},
};

constexpr Section graded_section{"under 'graded'", graded_keys};

constexpr Key body_keys[] = {
    name_key("unique name of the body", "bar"),
    {.name = "material",
     .type = Type::string,
     .doc = "name of one of the materials",
     .example = "steel",
     .need = Need::required},
    box_key("region [[lo], [hi]] filled with lattice particles", "[[0, 0, 0], [1, 0.1, 0.1]]"),
    boxes_key("instead of box: a union of boxes",
              "[[[0, 0, 0], [0.5, 0.1, 0.1]], [[0.5, 0, 0], [1, 0.1, 0.1]]]"),
    shape_key("cylinder", "instead of box: a cylinder (2D: a disk)", &cylinder_section),
    shape_key("sphere", "instead of box: a sphere (2D: a disk)", &sphere_section),
    {.name = "minus",
     .type = Type::list,
     .doc = "shapes taken out of the body: holes, notches, cuts",
     .show = Show::commented,
     .section = &shape_section},
    {.name = "particles",
     .type = Type::string,
     .doc = "instead of box: a particle file, CSV (.csv) or VTU (.vtu): x, y[, z], volume or "
            "mass and density, optional h; relative to the scene file; virtual fibres only",
     .example = "plate.csv",
     .need = Need::one_of,
     .group = 1,
     .show = Show::commented},
    {.name = "mesh",
     .type = Type::string,
     .doc = "instead of box: a mesh file (.msh, or another format Gmsh reads): one particle per "
            "element at its centroid with its volume (2D: area × thickness); relative to the "
            "scene file",
     .example = "part.msh",
     .need = Need::one_of,
     .group = 1,
     .show = Show::commented},
    {.name = "geometry",
     .type = Type::string,
     .doc = "instead of box: a geometry file (.geo, .step, .iges, .brep; 3D also a closed .stl) "
            "meshed by Gmsh with elements no larger than lattice.spacing, then filled as 'fill' "
            "says",
     .example = "part.step",
     .need = Need::one_of,
     .group = 1,
     .show = Show::commented},
    {.name = "fill",
     .type = Type::choice,
     .doc = "what a 'mesh' or 'geometry' body's particles are: its elements, or the lattice "
            "sites inside them (lattice.spacing apart; a physical group holds the sites inside "
            "its elements)",
     .choices = enum_words<MeshFill>,
     .show = Show::commented,
     .bind = {.default_text =
                  [] {
                    return std::string(name_of(geometry_file_fill)) + " for 'geometry', " +
                           std::string(name_of(mesh_file_fill)) + " for 'mesh'";
                  }}},
    {.name = "graded",
     .type = Type::section,
     .doc = "instead of box: a generated graded particle set (Olsson et al. 2021, §10.2); 2D, "
            "virtual fibres only",
     .need = Need::one_of,
     .group = 1,
     .only_dim = 2,
     .show = Show::commented,
     .section = &graded_section},
};

/// A body of given particles: its file read (errors name the file and the row), its region the
/// particles' bounding box, which supports, loads and probes are checked against.
void read_particle_body(Reader& r, const Fields& f, BodySpec& body, Marks& marks) {
  const Entry* e = f.find("particles");
  std::filesystem::path path = *r.string(f, "particles");
  if (path.is_relative()) {
    path = std::filesystem::path(r.file()).parent_path() / path;
  }
  try {
    body.points = std::make_shared<const PointCloud>(read_particle_file(path.string(), r.dim));
  } catch (const ParticleFileError& error) {
    r.fail(e->at(), error.what(), "fix the file (see docs/scenes.md, particle files)");
  }
  Box bounds{body.points->position.front(), body.points->position.front()};
  for (const Vec3& p : body.points->position) {
    for (std::size_t a = 0; a < 3; ++a) {
      bounds.lo[a] = std::min(bounds.lo[a], p[a]);
      bounds.hi[a] = std::max(bounds.hi[a], p[a]);
    }
  }
  body.region.boxes = {bounds};
  marks.body_box_nodes.push_back({e->at()});
}

/// The particles' bounding box: the region supports, loads and probes are checked against.
Box bounding_box(const PointCloud& points) {
  Box bounds{points.position.front(), points.position.front()};
  for (const Vec3& p : points.position) {
    for (std::size_t a = 0; a < 3; ++a) {
      bounds.lo[a] = std::min(bounds.lo[a], p[a]);
      bounds.hi[a] = std::max(bounds.hi[a], p[a]);
    }
  }
  return bounds;
}

/// A body from a mesh, or from a geometry file meshed at the lattice spacing (io/mesh_file.hpp):
/// errors name the file and the element; Gmsh's warnings become the scene's.
void read_mesh_body(Reader& r, const Fields& f, const ModelSpec& model, BodySpec& body,
                    Marks& marks) {
  const bool meshed = f.has("mesh");
  const Entry* e = f.find(meshed ? "mesh" : "geometry");
  std::filesystem::path path = *r.string(f, meshed ? "mesh" : "geometry");
  if (path.is_relative()) {
    path = std::filesystem::path(r.file()).parent_path() / path;
  }
  const int dim = model.dimension.dim;
  if (dim == 1) {
    r.fail(e->at(), "a body from a mesh needs dimension 2 or 3", "fill a box with the lattice");
  }
  MeshBody mesh;
  try {
    mesh = meshed ? read_mesh_file(path.string(), dim, model.dimension.thickness)
                  : mesh_geometry_file(path.string(), dim, model.dimension.thickness,
                                       model.lattice.spacing);
  } catch (const MeshFileError& error) {
    r.fail(e->at(), error.what(),
           mesh_files_supported() ? "fix the mesh or the geometry (docs/scenes.md, meshes)"
                                  : "build libpd with Gmsh (Debian: libgmsh-dev)");
  } catch (const PluginError& error) {
    r.fail(e->at(), error.what(),
           "install libpd's plug-ins with it, or name their folder in LIBPD_PLUGIN_DIR");
  }
  for (const std::string& w : mesh.warnings) {
    r.warn(e->at(), w);
  }
  body.fill = f.has("fill") ? static_cast<MeshFill>(*r.choice(f, "fill"))
              : meshed      ? mesh_file_fill
                            : geometry_file_fill;
  if (body.fill == MeshFill::lattice) {
    // The sites inside the elements become the particles; a group holds the sites inside its
    // elements (a face group: inside the layer of elements along the face).
    LatticeFill filled = fill_with_lattice(model.dimension, model.lattice, mesh.cloud);
    if (filled.cloud.count() == 0) {
      r.fail(e->at(),
             fmt::format("'{}' holds no lattice site: the part is thinner than lattice.spacing "
                         "({} m)",
                         path.string(), model.lattice.spacing),
             "reduce lattice.spacing, or use 'fill: elements'");
    }
    std::vector<std::vector<std::uint32_t>> sites_of(mesh.cloud.count());
    for (std::size_t s = 0; s < filled.element.size(); ++s) {
      sites_of[filled.element[s]].push_back(static_cast<std::uint32_t>(s));
    }
    for (auto& [name, particles] : mesh.groups) {
      std::vector<std::uint32_t> sites;
      for (const std::uint32_t p : particles) {
        sites.insert(sites.end(), sites_of[p].begin(), sites_of[p].end());
      }
      std::sort(sites.begin(), sites.end());
      particles = std::move(sites);
    }
    mesh.cloud = std::move(filled.cloud);
  }
  for (const auto& [name, particles] : mesh.groups) {
    std::vector<Vec3>& points = r.mesh_groups[name];
    for (const std::uint32_t p : particles) {
      points.push_back(mesh.cloud.position[p]);
    }
    std::sort(points.begin(), points.end());
  }
  r.mesh_files.push_back(path.string());
  body.points = std::make_shared<const PointCloud>(std::move(mesh.cloud));
  body.mesh = true;
  body.mesh_file = path.string();
  body.mesh_is_geometry = !meshed;
  body.region.boxes = {bounding_box(*body.points)};
  marks.body_box_nodes.push_back({e->at()});
}

/// A generated graded body: its spec read (keys bound to GradedSetSpec, `box` and `zones` by
/// hand), its particles generated now, deterministically, and its region their bounding box.
void read_graded_body(Reader& r, const Fields& body_fields, const ModelSpec& model, BodySpec& body,
                      Marks& marks) {
  const Fields f = r.section(body_fields, "graded");
  const YAML::Node at = body_fields.find("graded")->at();
  GradedSetSpec spec;
  r.read_bound(f, spec);
  spec.size_neighbours = model.fibre_kernel.size_neighbours;
  if (const Entry* z = f.find("zones")) {
    const Vec3 v = *r.vector(f, "zones");
    for (std::size_t a = 0; a < 2; ++a) {
      if (!(v[a] >= 1) || v[a] != std::floor(v[a]) || v[a] > 1e6) {
        r.fail(z->at(), fmt::format("{} must be two integers ≥ 1", f.label("zones")),
               "write e.g. 'zones: [40, 20]'");
      }
      spec.zones[a] = static_cast<int>(v[a]);
    }
  }
  if (spec.shape == GradedShape::ellipse && !f.has("focal_half_distance")) {
    r.fail(at, "a graded ellipse needs 'focal_half_distance'",
           "add 'focal_half_distance: 0.0416667' (c of eq. 114)");
  }
  if (spec.shape == GradedShape::box) {
    const Entry* b = f.find("box");
    if (b == nullptr) {
      r.fail(at, "a graded box needs 'box'", "add 'box: [[0, 0], [1, 0.5]]'");
    }
    spec.box = r.box(b->at(), f.label("box"));
    if (!(spec.box.hi[0] > spec.box.lo[0] && spec.box.hi[1] > spec.box.lo[1])) {
      r.fail(b->at(), fmt::format("{} has no area", f.label("box")), "give lo < hi in x and y");
    }
  }
  // Counted before it is made: a set too large for the memory (or too large to index) is refused
  // in microseconds, not found out by std::bad_alloc after minutes.
  const double count = graded_set_size(spec);
  std::optional<MemoryBudget> budget;
  try {
    budget = available_memory();
  } catch (const std::invalid_argument&) {
    // A malformed PD_MEMORY_LIMIT is reported by the scene's memory check.
  }
  const double bytes = count * graded_bytes_per_particle;
  const bool too_many = !(count <= max_graded_particles);
  if (too_many || (budget && !(bytes <= budget->bytes))) {
    const std::string how_many =
        !std::isfinite(count) ? std::string("infinitely many (the grading leaves a zone no width)")
        : too_many            ? fmt::format("more than {:.0e}", max_graded_particles)
                              : fmt::format("about {:.3g}", count);
    const std::string why =
        too_many
            ? fmt::format("; at most {:.0e} are generated", max_graded_particles)
            : fmt::format(", {} to generate; {} {}", format_bytes(bytes),
                          format_bytes(budget->bytes),
                          budget->source == "PD_MEMORY_LIMIT" ? "are allowed by PD_MEMORY_LIMIT"
                                                              : "are available");
    r.fail(at, fmt::format("this graded set has {} particles{}", how_many, why),
           "lower 'zones' or 'pattern' (particles grow as zones × pattern²), or the grading");
  }
  try {
    body.points =
        std::make_shared<const PointCloud>(generate_graded_set(spec, model.dimension.thickness));
  } catch (const std::invalid_argument& e) {
    r.fail(at, e.what(), "lower 'zones' or 'pattern', or the grading");
  }
  Box bounds{body.points->position.front(), body.points->position.front()};
  for (const Vec3& p : body.points->position) {
    for (std::size_t a = 0; a < 3; ++a) {
      bounds.lo[a] = std::min(bounds.lo[a], p[a]);
      bounds.hi[a] = std::max(bounds.hi[a], p[a]);
    }
  }
  body.region.boxes = {bounds};
  marks.body_box_nodes.push_back({at});
}

} // namespace

constinit const Section body_section{"in a body", body_keys};

void read_bodies(Reader& r, ModelSpec& model, Marks& marks) {
  std::vector<std::string_view> material_names;
  for (const Material& m : model.materials) {
    material_names.push_back(m.name);
  }
  const auto list = r.items(marks.top, "bodies");
  if (list.empty()) {
    r.fail(marks.top.find("bodies")->at(), "'bodies' is empty: a scene needs at least one body",
           "add a body: '- name: bar', 'material: <name>', 'box: [[lo], [hi]]'");
  }
  if (list.size() > std::numeric_limits<std::uint16_t>::max()) {
    r.fail(marks.top.find("bodies")->value, "too many bodies (at most 65535)",
           "merge bodies of the same material into one body with 'boxes'");
  }
  std::map<std::string, YAML::Node> names;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const Fields f = r.item(list[i], body_section, "body", "bodies", i);
    BodySpec body;
    body.name = *r.string(f, "name");
    check_unique(r, names, body.name, f.find("name")->at(), "body");
    const Entry* m = f.find("material");
    const std::string material = *r.string(f, "material");
    const auto found = std::find(material_names.begin(), material_names.end(), material);
    if (found == material_names.end()) {
      r.fail(m->at(), fmt::format("body '{}' names unknown material '{}'", body.name, material),
             suggestion(material, material_names, "materials defined"));
    }
    body.material = static_cast<int>(found - material_names.begin());
    if (const Entry* fill = f.find("fill");
        fill != nullptr && !f.has("mesh") && !f.has("geometry")) {
      r.fail(fill->name,
             fmt::format("body '{}': 'fill' applies to 'mesh' and 'geometry' bodies", body.name),
             "remove 'fill': a box or shape body is filled with the lattice already");
    }
    if (f.has("particles") || f.has("graded") || f.has("mesh") || f.has("geometry")) {
      const char* key = f.has("particles") ? "particles"
                        : f.has("graded")  ? "graded"
                        : f.has("mesh")    ? "mesh"
                                           : "geometry";
      if (f.has("particles")) {
        read_particle_body(r, f, body, marks);
      } else if (f.has("graded")) {
        read_graded_body(r, f, model, body, marks);
      } else {
        read_mesh_body(r, f, model, body, marks);
      }
      marks.body_nodes.push_back(f.find(key)->at());
      if (const Entry* minus = f.find("minus")) {
        r.fail(minus->name,
               fmt::format("body '{}' is given as particles: 'minus' applies only to lattice "
                           "bodies",
                           body.name),
               "remove the particles inside the hole from the file (or the mesh), or drop 'minus'");
      }
      model.bodies.push_back(std::move(body));
      continue;
    }
    YAML::Node where;
    if (std::optional<Shape> shape = read_body_shape(r, f)) {
      body.region.shapes.push_back(*shape);
      where = f.find(shape->kind == Shape::Kind::sphere ? "sphere" : "cylinder")->at();
      marks.body_box_nodes.emplace_back();
    } else {
      const Reader::RegionRead region = r.region(f);
      body.region = region.region;
      where = region.node;
      marks.body_box_nodes.push_back(region.box_nodes);
    }
    body.region.minus = read_minus(r, f);
    marks.body_nodes.push_back(where);
    marks.must_have_particles.push_back(
        {body.region, where, fmt::format("body '{}' contains no lattice point", body.name)});
    model.bodies.push_back(std::move(body));
  }
}

} // namespace pd::scene
