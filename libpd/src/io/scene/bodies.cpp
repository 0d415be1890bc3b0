// The `bodies` list: regions of the lattice or particle files, each made of one material.
#include "libpd/io/particle_file.hpp"
#include "sections.hpp"

#include <algorithm>
#include <filesystem>
#include <memory>

namespace pd::scene {

namespace {

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
     .doc = "instead of box: a CSV file of particles (x, y[, z], volume or mass and density, "
            "optional h), relative to the scene file; virtual fibres only",
     .example = "plate.csv",
     .need = Need::one_of,
     .group = 1,
     .show = Show::commented},
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
    body.points = std::make_shared<const PointCloud>(read_particle_csv(path.string(), r.dim));
  } catch (const ParticleFileError& error) {
    r.fail(e->at(), error.what(), "fix the file (see SCENE_FORMAT.md, particle files)");
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
    if (f.has("particles")) {
      read_particle_body(r, f, body, marks);
      marks.body_nodes.push_back(f.find("particles")->at());
      if (const Entry* minus = f.find("minus")) {
        r.fail(minus->name,
               fmt::format("body '{}' is read from a particle file: 'minus' applies "
                           "only to lattice bodies",
                           body.name),
               "remove the particles inside the hole from the file, or drop 'minus'");
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
