// The readers of a scene's sections, one file each, and the checks between sections.
//
// Each reader fills its part of the Scene and leaves in `Marks` where things were written, so
// that the checks that need several sections (checks.cpp) can point at the right line.
#pragma once

#include "libpd/core/names.hpp"
#include "reader.hpp"

#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace pd::scene {

/// The words of `effects`, each with the flag of EffectSet it switches on.
inline constexpr NameTable<bool EffectSet::*, 3> effect_table{{
    {"damage", &EffectSet::damage, "brittle bonds that break at the critical stretch"},
    {"plasticity", &EffectSet::plasticity, "micro-plastic bonds that yield at the yield stretch"},
    {"damping", &EffectSet::damping, "kinematic damping of coefficient solver.damping"},
}};
inline constexpr auto effect_words = words_of(effect_table);

/// The `name` key of a list item.
constexpr Key name_key(std::string_view doc, std::string_view example) {
  return {
      .name = "name", .type = Type::string, .doc = doc, .example = example, .need = Need::required};
}

/// The `box` key of a section with a region, and its alternative `boxes` (group 1: exactly one
/// of them, read by Reader::region).
constexpr Key box_key(std::string_view doc, std::string_view example, Show show = Show::active) {
  return {.name = "box",
          .type = Type::box,
          .doc = doc,
          .unit = "m",
          .example = example,
          .need = Need::one_of,
          .group = 1,
          .show = show};
}
/// `group`: a physical group of a mesh body (io/mesh_file.hpp), one of the alternatives of
/// group 1, beside `box`.
constexpr Key group_key(std::string_view doc) {
  return {.name = "group",
          .type = Type::string,
          .doc = doc,
          .example = "clamp",
          .need = Need::one_of,
          .group = 1,
          .show = Show::commented};
}
constexpr Key boxes_key(std::string_view doc, std::string_view example) {
  return {.name = "boxes",
          .type = Type::boxes,
          .doc = doc,
          .unit = "m",
          .example = example,
          .need = Need::one_of,
          .group = 1,
          .show = Show::commented};
}

/// A key holding a shape (`cylinder`, `sphere`, `half_space`): one of the alternatives of group 1,
/// beside `box`.
constexpr Key shape_key(std::string_view name, std::string_view doc, const Section* section) {
  return {.name = name,
          .type = Type::section,
          .doc = doc,
          .need = Need::one_of,
          .group = 1,
          .show = Show::commented,
          .section = section};
}

/// A region that the scene must not leave empty, with what to say if it is.
struct RegionUse {
  Region region;
  YAML::Node node;
  std::string what;
};

/// Where the sections were written, for the checks between them.
struct Marks {
  Fields top;
  Fields lattice;
  Fields solver;
  Fields output;
  Fields model;
  std::vector<YAML::Node> material_nodes; ///< the name of each material
  std::vector<Fields> material_fields;
  std::vector<std::vector<YAML::Node>> body_box_nodes; ///< per body, per box
  std::vector<YAML::Node> body_nodes;                  ///< per body: its box(es) or shape
  std::vector<YAML::Node> support_nodes;               ///< where a support's own errors point
  std::vector<YAML::Node> crack_nodes;                 ///< per crack: its segment or polygon
  std::vector<RegionUse> must_have_particles;          ///< bodies
  std::vector<RegionUse> must_touch_bodies;            ///< supports, loads, region probes
  std::vector<std::pair<Vec3, YAML::Node>> probe_points;
  std::vector<std::string> probe_point_names; ///< "probe 'tip'", "point load 'P'"
  YAML::Node damping_effect;
  std::vector<std::pair<std::string, YAML::Node>> reaction_supports; ///< support named by a probe
  std::vector<std::pair<ProbeSpec::Quantity, YAML::Node>> probe_quantities;
  YAML::Node stop_when_probe; ///< the probe solver.stop_when watches
};

void read_top_level(const YAML::Node& root, Reader& r, Scene& scene, Marks& marks);
void read_lattice(Reader& r, ModelSpec& model, Marks& marks);
void read_materials(Reader& r, ModelSpec& model, Marks& marks);
void read_bodies(Reader& r, ModelSpec& model, Marks& marks);
/// A body's `cylinder` or `sphere`, if it has one instead of boxes (shapes.cpp).
std::optional<Shape> read_body_shape(Reader& r, const Fields& f);
/// The `cracks` list (shapes.cpp).
void read_cracks(Reader& r, ModelSpec& model, Marks& marks);
/// A body's `minus` list: the shapes taken out of it.
std::vector<Shape> read_minus(Reader& r, const Fields& f);
/// The `surface` section of `f` (a pressure load's shape: box, cylinder or sphere).
Shape read_surface(Reader& r, const Fields& f);
void read_supports(Reader& r, ModelSpec& model, Marks& marks);
void read_loads(Reader& r, ModelSpec& model, Marks& marks);
/// `effects` and the `model` section.
void read_model_options(Reader& r, ModelSpec& model, Marks& marks);
void read_solver(Reader& r, SolverSpec& solver, StopWhenSpec& stop_when, Marks& marks);
void read_initial(Reader& r, InitialSpec& initial, const Marks& marks);
void read_probes(Reader& r, std::vector<ProbeSpec>& probes, Marks& marks);
void read_output(Reader& r, OutputSpec& output, Marks& marks);

/// Items with a name must have unique, non-empty names.
void check_unique(const Reader& r, std::map<std::string, YAML::Node>& seen, const std::string& name,
                  const YAML::Node& node, std::string_view kind);

/// Checks between sections that need no lattice: effects against materials and solver, solver
/// options against each other, output against probes.
void check_consistency(Reader& r, const Scene& scene, const Marks& marks);
/// What the virtual-fibre model cannot run with (model_options.cpp).
void check_bond_model(Reader& r, const Scene& scene, const Marks& marks);
/// After the bodies: a bond-based model with a mesh body takes mesh_surface_correction and
/// mesh_volume_correction (model.hpp) for the keys left out, and refuses lattice-only ones.
void settle_mesh_corrections(Reader& r, ModelSpec& model, const Marks& marks);
/// Checks against the lattice, from the estimate of its size first, then by counting lattice
/// points in regions, last (mirror supports) by generating it: the particles, if generated.
std::optional<ParticleSet> check_against_lattice(Reader& r, const Scene& scene, const Marks& marks);

/// The whole scene, section by section, then the checks between sections.
Scene read_scene(const YAML::Node& root, Reader& r);

} // namespace pd::scene
