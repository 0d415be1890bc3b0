// The `probes` list: displacements, reactions, stresses and damage recorded during a run, at a
// point, averaged over a region, or summed over a support.
#include "bind.hpp"
#include "sections.hpp"

namespace pd::scene {

namespace {

constexpr Key probe_keys[] = {
    name_key("unique name of the probe", "tip"),
    {.name = "point",
     .type = Type::vector,
     .doc = "records the particle nearest to this point (within one spacing of a body)",
     .unit = "m",
     .example = "[1, 0.05, 0.05]",
     .need = Need::one_of,
     .group = 1},
    box_key("instead of point: records the average over the particles in a box",
            "[[0.99, 0.04, 0.04], [1, 0.06, 0.06]]", Show::commented),
    boxes_key("instead of point: the average over a union of boxes",
              "[[[0.99, 0.04, 0.04], [1, 0.06, 0.06]]]"),
    group_key("instead of point: the average over a mesh body's physical group"),
    {.name = "support",
     .type = Type::string,
     .doc = "instead of point: the support whose reaction is recorded, the force it exerts on "
            "the body, summed over its particles held (fixed or displaced) in 'component'",
     .example = "grip",
     .need = Need::one_of,
     .group = 1,
     .show = Show::commented},
    {.name = "quantity",
     .type = Type::choice,
     .doc = "what is recorded: a displacement component [m]; the reaction of a 'support' [N]; the "
            "normal stress σ_cc from the bond forces, ½ Σ f ⊗ ξ V (Lehoucq & Silling) [Pa]; the "
            "damage index (needs the damage effect); means over a region, sums for a reaction",
     .choices = enum_words<ProbeSpec::Quantity>,
     .bind = {.default_text =
                  [] { return std::string(name_of(ProbeSpec::Quantity::displacement)); }}},
    {.name = "component",
     .type = Type::choice,
     .doc = "component recorded (displacement, reaction) or of the normal stress σ_cc",
     .choices = axis_names,
     .bind = {.default_text = [] { return std::string(axis_names[ProbeSpec{}.component]); }}},
};

} // namespace

constinit const Section probe_section{"in a probe", probe_keys};

void read_probes(Reader& r, std::vector<ProbeSpec>& probes, Marks& marks) {
  std::map<std::string, YAML::Node> names;
  const auto list = r.items(marks.top, "probes");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const Fields f = r.item(list[i], probe_section, "probe", "probes", i);
    ProbeSpec p;
    p.name = *r.string(f, "name");
    check_unique(r, names, p.name, f.find("name")->at(), "probe");
    if (const Entry* q = f.find("quantity")) {
      p.quantity = static_cast<ProbeSpec::Quantity>(*r.choice(f, "quantity"));
      marks.probe_quantities.emplace_back(p.quantity, q->at());
    }
    if (auto support = r.string(f, "support")) {
      p.kind = ProbeSpec::Kind::support;
      p.support = *support;
      if (f.has("quantity") && p.quantity != ProbeSpec::Quantity::reaction) {
        r.fail(f.find("quantity")->at(),
               fmt::format("probe '{}' reads a support, which has only a reaction", p.name),
               "remove 'quantity' or write 'quantity: reaction'");
      }
      p.quantity = ProbeSpec::Quantity::reaction;
      marks.reaction_supports.emplace_back(p.support, f.find("support")->at());
    } else if (p.quantity == ProbeSpec::Quantity::reaction) {
      r.fail(f.find("quantity")->at(),
             fmt::format("probe '{}' records a reaction but names no 'support'", p.name),
             "replace 'point' or 'box' with 'support: <name of a support>'");
    } else if (auto point = r.vector(f, "point")) {
      p.kind = ProbeSpec::Kind::point;
      p.point = *point;
      marks.probe_points.emplace_back(p.point, f.find("point")->at());
      marks.probe_point_names.push_back("probe '" + p.name + "'");
    } else {
      p.kind = ProbeSpec::Kind::region;
      const Reader::RegionRead region = r.region(f);
      p.region = region.region;
      marks.must_touch_bodies.push_back(
          {p.region, region.node,
           fmt::format("probe '{}' averages over no particle: its region holds no lattice point "
                       "of any body",
                       p.name)});
    }
    // Not bound: a component must exist in the scene's dimension.
    if (const Entry* c = f.find("component")) {
      p.component = r.component(c->at(), f.label("component"));
    }
    probes.push_back(std::move(p));
  }
}

} // namespace pd::scene
