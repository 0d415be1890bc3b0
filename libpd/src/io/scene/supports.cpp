// The `supports` list: fixed, prescribed or mirrored displacements of the particles in a region.
#include "bind.hpp"
#include "sections.hpp"

#include <algorithm>

namespace pd::scene {

namespace {

/// Supports may leave out their region (symmetry planes).
constexpr Key optional_region(Key k) {
  k.need = Need::optional;
  return k;
}

constexpr Key support_keys[] = {
    name_key("unique name of the support", "clamp"),
    optional_region(box_key("region whose particles (of any body) are supported; required "
                            "except for a symmetry support (whole plane if omitted)",
                            "[[0, 0, 0], [0.03, 0.1, 0.1]]")),
    optional_region(
        boxes_key("instead of box: a union of boxes", "[[[0, 0, 0], [0.03, 0.1, 0.1]]]")),
    optional_region(group_key("instead of box: the particles of a mesh body's physical group "
                              "(fixed or displaced; a mirror or symmetry plane needs a box)")),
    {.name = "fixed",
     .type = Type::components,
     .doc = "components held at zero displacement",
     .example = "[x, y, z]",
     .bind = field<&SupportSpec::fixed>()},
    {.name = "displacement",
     .type = Type::component_values,
     .doc = "prescribed displacement per component, ramped with the load; a component may not be "
            "both fixed and displaced",
     .unit = "m",
     .example = "{x: 0.001}",
     .show = Show::commented},
    {.name = "mirror",
     .type = Type::component_values,
     .doc = "instead of fixed: a clamped face at these planes (x = value, ...). The support's "
            "particles take the body's displacement mirrored across every plane, negated once "
            "per plane, so the displacement vanishes on the face with the strain continuous "
            "across it; fixed particles put the clamp about one spacing behind the face",
     .unit = "m",
     .example = "{x: 0}",
     .show = Show::commented},
    {.name = "symmetry",
     .type = Type::component_values,
     .doc = "symmetry planes (x = value, ...) of a half (quarter, ...) model: the sites beyond the "
            "plane take their image's displacement with the normal component negated, so the "
            "normal displacement vanishes on the plane and the tangential one is free (a roller "
            "on a whole face is the same condition); the body lies on one side; needs the ghost "
            "surface correction (the default)",
     .unit = "m",
     .example = "{x: 0}",
     .show = Show::commented},
};

} // namespace

constinit const Section support_section{"in a support", support_keys};

void read_supports(Reader& r, ModelSpec& model, Marks& marks) {
  std::map<std::string, YAML::Node> names;
  const auto list = r.items(marks.top, "supports");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const Fields f = r.item(list[i], support_section, "support", "supports", i);
    SupportSpec s;
    s.name = *r.string(f, "name");
    check_unique(r, names, s.name, f.find("name")->at(), "support");
    Reader::RegionRead region;
    const bool has_region = f.has("box") || f.has("boxes") || f.has("group");
    if (has_region) {
      region = r.region(f);
      s.region = region.region;
    }
    r.read_bound(f, s);
    std::array<YAML::Node, 3> nodes;
    const auto displacement = r.component_values(f, "displacement", nodes);
    for (int c = 0; c < 3; ++c) {
      if (!displacement[c]) {
        continue;
      }
      if (s.fixed[c]) {
        r.fail(nodes[c],
               fmt::format("support '{}' both fixes and displaces component {}", s.name,
                           axis_names[c]),
               fmt::format("'fixed' means zero displacement: remove {} from 'fixed' or from "
                           "'displacement'",
                           axis_names[c]));
      }
      s.prescribed[c] = true;
      s.displacement[c] = *displacement[c];
    }
    std::array<YAML::Node, 3> mirror_nodes;
    const auto mirror = r.component_values(f, "mirror", mirror_nodes);
    marks.support_nodes.push_back(f.has("mirror")     ? f.find("mirror")->at()
                                  : f.has("symmetry") ? f.find("symmetry")->at()
                                                      : f.anchor);
    for (int c = 0; c < 3; ++c) {
      if (mirror[c]) {
        s.mirror[c] = true;
        s.mirror_at[c] = *mirror[c];
      }
    }
    std::array<YAML::Node, 3> symmetry_nodes;
    const auto symmetry = r.component_values(f, "symmetry", symmetry_nodes);
    for (int c = 0; c < 3; ++c) {
      if (symmetry[c]) {
        s.symmetry[c] = true;
        s.symmetry_at[c] = *symmetry[c];
      }
    }
    const bool holds =
        std::any_of(s.fixed.begin(), s.fixed.end(), [](bool b) { return b; }) ||
        std::any_of(s.prescribed.begin(), s.prescribed.end(), [](bool b) { return b; });
    if (s.mirrors() && holds) {
      r.fail(f.find("mirror")->at(),
             fmt::format("support '{}' both mirrors and fixes or displaces", s.name),
             "a mirror support moves all three components with the body: remove 'fixed' and "
             "'displacement', or 'mirror'");
    }
    if (s.symmetric() && (holds || s.mirrors())) {
      r.fail(f.find("symmetry")->at(),
             fmt::format("support '{}' is a symmetry plane and also fixes, displaces or mirrors",
                         s.name),
             "give the symmetry plane its own support");
    }
    if (!holds && !s.mirrors() && !s.symmetric()) {
      r.fail(f.anchor,
             fmt::format("support '{}' neither fixes nor displaces any component", s.name),
             "add 'fixed: [x, ...]', 'displacement: {x: value}', 'mirror: {x: value}' or "
             "'symmetry: {x: value}'");
    }
    if (f.has("group") && (s.mirrors() || s.symmetric())) {
      r.fail(region.node,
             fmt::format("support '{}' mirrors or is a symmetry plane, which needs the box behind "
                         "its face, not a physical group",
                         s.name),
             "give the support a 'box', or hold the group with 'fixed' or 'displacement'");
    }
    if (!has_region && !s.symmetric()) {
      r.fail(f.anchor, fmt::format("missing 'box' or 'boxes' in support '{}'", s.name),
             "add the region whose particles are supported, e.g. 'box: [[lo], [hi]]' (only a "
             "symmetry support may leave it out)");
    }
    if (!has_region) {
      model.supports.push_back(std::move(s));
      continue;
    }
    marks.must_touch_bodies.push_back(
        {s.region, region.node,
         fmt::format("support '{}' selects no particle: its region holds no lattice point of "
                     "any body",
                     s.name)});
    model.supports.push_back(std::move(s));
  }
}

} // namespace pd::scene
