// The top level of a scene: its table (which lists the sections), the dimension keys, and the
// order in which the sections are read and checked.
#include "bind.hpp"
#include "sections.hpp"

namespace pd::scene {

namespace {

using Dimension = ModelDimension;

constexpr Key root_keys[] = {
    {.name = "title",
     .type = Type::string,
     .doc = "free text shown in summaries and output files",
     .example = "\"Block in tension\"",
     .bind = field<&Scene::title>()},
    {.name = "dimension",
     .type = Type::integer,
     .doc = "spatial dimension: 1, 2 or 3",
     .range = {1, 3, false, false},
     .example = "3",
     .need = Need::required,
     .range_hint = "use dimension: 1, 2 or 3",
     .bind = field<&Scene::model, &ModelSpec::dimension, &Dimension::dim>()},
    {.name = "plane",
     .type = Type::choice,
     .doc = "2D assumption: plane stress (bond-based ν = 1/3) or plane strain (ν = 1/4)",
     .choices = enum_words<PlaneMode>,
     .only_dim = 2,
     .show = Show::commented,
     .bind = field_with_default<&Scene::model, &ModelSpec::dimension, &Dimension::plane>()},
    {.name = "thickness",
     .type = Type::number,
     .doc = "out-of-plane thickness of a 2D model",
     .unit = "m",
     .range = positive,
     .only_dim = 2,
     .show = Show::commented,
     .bind = field_with_default<&Scene::model, &ModelSpec::dimension, &Dimension::thickness>()},
    {.name = "cross_section",
     .type = Type::number,
     .doc = "cross-section area of a 1D model",
     .unit = "m²",
     .range = positive,
     .only_dim = 1,
     .show = Show::commented,
     .bind = field_with_default<&Scene::model, &ModelSpec::dimension, &Dimension::cross_section>()},
    {.name = "lattice",
     .type = Type::section,
     .doc = "the particle lattice shared by all bodies",
     .need = Need::required,
     .section = &lattice_section},
    {.name = "materials",
     .type = Type::named_map,
     .doc = "materials by name (at least one)",
     .example = "steel",
     .need = Need::required,
     .section = &material_section},
    {.name = "bodies",
     .type = Type::list,
     .doc = "bodies: regions of the lattice made of one material (at least one); where bodies "
            "overlap, their materials must agree",
     .need = Need::required,
     .section = &body_section},
    {.name = "supports",
     .type = Type::list,
     .doc = "fixed or prescribed displacements",
     .section = &support_section},
    {.name = "loads", .type = Type::list, .doc = "external forces", .section = &load_section},
    {.name = "cracks",
     .type = Type::list,
     .doc = "pre-cracks: no bond crosses them with both ends over them",
     .show = Show::commented,
     .section = &crack_section},
    {.name = "effects",
     .type = Type::names,
     .doc = "effects to simulate; damage needs fracture_energy or critical_stretch, plasticity "
            "needs yield_stretch, damping needs solver.damping > 0",
     .choices = effect_words,
     .fallback = "[]"},
    {.name = "model",
     .type = Type::section,
     .doc = "bond model options",
     .section = &model_section},
    {.name = "solver",
     .type = Type::section,
     .doc = "time integration and stopping",
     .section = &solver_section},
    {.name = "initial",
     .type = Type::section,
     .doc = "initial displacement and velocity",
     .section = &initial_section},
    {.name = "probes",
     .type = Type::list,
     .doc = "displacements recorded during the run",
     .section = &probe_section},
    {.name = "output",
     .type = Type::section,
     .doc = "files written by the run",
     .section = &output_section},
};

} // namespace

constinit const Section root_section{"at the top level", root_keys};

void read_top_level(const YAML::Node& root, Reader& r, Scene& scene, Marks& marks) {
  marks.top = r.open(root, root, root_section, {}, {}, "the scene");
  r.read_bound(marks.top, scene);
  r.dim = scene.model.dimension.dim;
  r.warn_foreign_keys(marks.top);
}

Scene read_scene(const YAML::Node& root, Reader& r) {
  Scene scene;
  Marks marks;
  read_top_level(root, r, scene, marks);
  read_lattice(r, scene.model, marks);
  read_model_options(r, scene.model, marks); // first: the bond model decides what ν means
  read_materials(r, scene.model, marks);
  read_bodies(r, scene.model, marks);
  settle_mesh_corrections(r, scene.model, marks);
  read_supports(r, scene.model, marks);
  read_loads(r, scene.model, marks);
  read_cracks(r, scene.model, marks);
  read_solver(r, scene.solver, scene.stop_when, marks);
  read_initial(r, scene.initial, marks);
  read_probes(r, scene.probes, marks);
  read_output(r, scene.output, marks);

  check_consistency(r, scene, marks);
  if (auto particles = check_against_lattice(r, scene, marks)) {
    scene.particles = std::make_shared<const GeneratedParticles>(GeneratedParticles{
        scene.model.dimension, scene.model.lattice, scene.model.bodies, std::move(*particles)});
  }
  return scene;
}

} // namespace pd::scene
