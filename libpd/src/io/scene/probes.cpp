// The `probes` list: displacements, reactions and moments, stresses, strains, openings and
// damage recorded during a run, at a point, averaged over a region, or summed over a support.
#include "bind.hpp"
#include "sections.hpp"

#include <cmath>

namespace pd::scene {

namespace {

constexpr Key line_keys[] = {
    {.name = "from",
     .type = Type::vector,
     .doc = "the line's first point",
     .unit = "m",
     .example = "[0, 0.05, 0.05]",
     .need = Need::required},
    {.name = "to",
     .type = Type::vector,
     .doc = "the line's last point",
     .unit = "m",
     .example = "[1, 0.05, 0.05]",
     .need = Need::required},
    {.name = "points",
     .type = Type::integer,
     .doc = "points along the line, evenly spaced, the ends included",
     .range = {2, 10000, false, false},
     .example = "21",
     .need = Need::required},
};

constinit const Section line_section{"in a probe's 'line'", line_keys};

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
    {.name = "line",
     .type = Type::section,
     .doc = "instead of point: the quantity at points along a segment, each read as a point "
            "probe named NAME[k], k = 0 at 'from'",
     .need = Need::one_of,
     .group = 1,
     .show = Show::commented,
     .section = &line_section},
    {.name = "to",
     .type = Type::vector,
     .doc = "opening: the second point; the probe reads the displacement of the particle "
            "nearest 'to' less that of the particle nearest 'point', along the line between them",
     .unit = "m",
     .example = "[0.5, 0.051, 0]",
     .show = Show::commented},
    {.name = "support",
     .type = Type::string,
     .doc = "instead of point: the support whose reaction or moment is recorded, the force (or "
            "its moment about 'about') it exerts on the body, summed over its particles held "
            "(fixed or displaced)",
     .example = "grip",
     .need = Need::one_of,
     .group = 1,
     .show = Show::commented},
    {.name = "about",
     .type = Type::vector,
     .doc = "moment: the point the support's moment is taken about",
     .unit = "m",
     .example = "[0, 0.05, 0]",
     .show = Show::commented},
    {.name = "quantity",
     .type = Type::choice,
     .doc = "what is recorded: a displacement component [m]; the reaction [N] or moment [N m] "
            "of a 'support'; a stress component from the bond forces, ½ Σ f ⊗ ξ V (Lehoucq & "
            "Silling) [Pa]; a strain component of the displacement fitted over the family [-]; "
            "the von Mises stress [Pa]; the opening between 'point' and 'to' [m]; the damage "
            "index (needs the damage effect); means over a region, sums for a support",
     .choices = enum_words<ProbeSpec::Quantity>,
     .bind = {.default_text =
                  [] { return std::string(name_of(ProbeSpec::Quantity::displacement)); }}},
    {.name = "component",
     .type = Type::choice,
     .doc = "component of a displacement or reaction (x, y, z), axis of a moment (z in 2D), "
            "component of a stress or strain (xx, yy, zz, xy, yz, zx; x means xx)",
     .choices = probe_component_words,
     .bind = {.default_text =
                  [] { return std::string(probe_component_words[ProbeSpec{}.component]); }}},
};

using Q = ProbeSpec::Quantity;

/// The probe's component from its word: an axis for a vector quantity or a moment, a tensor
/// component for a stress or strain; in 2D the out-of-plane ones do not exist (a moment's axis
/// is z there, the only one).
int read_component(const Reader& r, const ProbeSpec& p, const Entry* e) {
  const bool tensor = p.quantity == Q::stress || p.quantity == Q::strain;
  if (e == nullptr) {
    return p.quantity == Q::moment && r.dim == 2 ? 2 : 0;
  }
  const YAML::Node n = e->at();
  if (p.quantity == Q::von_mises || p.quantity == Q::opening) {
    r.fail(n,
           fmt::format("probe '{}' reads {}, which has no component", p.name, name_of(p.quantity)),
           "remove 'component'");
  }
  const int w = r.word(n, "component of probe '" + p.name + "'", probe_component_words);
  if (!tensor && w >= 3) {
    r.fail(n,
           fmt::format("component '{}' is a tensor component; {} is a vector", n.Scalar(),
                       name_of(p.quantity)),
           "use x, y or z");
  }
  const int c = w >= 3 ? w - 3 : w;
  const bool in_plane = c < r.dim || (r.dim == 2 && c == 3);
  const bool exists = r.dim == 3 || (p.quantity == Q::moment ? r.dim == 2 && c == 2
                                     : tensor                ? in_plane
                                                             : c < r.dim);
  if (!exists) {
    r.fail(n,
           fmt::format("component '{}' of {} does not exist in a {}D scene", n.Scalar(),
                       name_of(p.quantity), r.dim),
           p.quantity == Q::moment ? "a 2D moment is about z: write z or leave it out"
           : tensor                ? fmt::format("use {}", r.dim == 2 ? "xx, yy or xy" : "xx")
                                   : fmt::format("use {}", join(axes(r.dim), " or ")));
  }
  return c;
}

/// A line probe as `points` point probes LINE[k] evenly along it: each is then read, checked,
/// compared and written like any point probe, and `line` groups them again for a profile.
void read_line(Reader& r, const Fields& f, const ProbeSpec& p, std::vector<ProbeSpec>& probes,
               std::map<std::string, YAML::Node>& names, Marks& marks) {
  const Fields line = r.section(f, "line");
  const Vec3 from = *r.vector(line, "from");
  const Vec3 to = *r.vector(line, "to");
  const int n = *r.integer<int>(line, "points");
  double length = 0;
  for (std::size_t c = 0; c < 3; ++c) {
    length += (to[c] - from[c]) * (to[c] - from[c]);
  }
  length = std::sqrt(length);
  if (length == 0) {
    r.fail(line.find("to")->at(), fmt::format("line probe '{}' has 'from' = 'to'", p.name),
           "give the segment's two different ends");
  }
  for (int k = 0; k < n; ++k) {
    ProbeSpec q = p;
    q.kind = ProbeSpec::Kind::point;
    q.name = fmt::format("{}[{}]", p.name, k);
    q.line = p.name;
    q.line_index = k;
    const double t = static_cast<double>(k) / (n - 1);
    q.line_distance = t * length;
    for (std::size_t c = 0; c < 3; ++c) {
      q.point[c] = from[c] + t * (to[c] - from[c]);
    }
    check_unique(r, names, q.name, f.find("name")->at(), "probe");
    marks.probe_points.emplace_back(q.point, f.find("line")->at());
    marks.probe_point_names.push_back("probe '" + q.name + "'");
    probes.push_back(std::move(q));
  }
}

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
      if (f.has("quantity") && p.quantity != Q::reaction && p.quantity != Q::moment) {
        r.fail(f.find("quantity")->at(),
               fmt::format("probe '{}' reads a support, which has a reaction and a moment", p.name),
               "remove 'quantity' or write 'quantity: reaction' or 'quantity: moment'");
      }
      if (p.quantity != Q::moment) {
        p.quantity = Q::reaction;
      }
      marks.reaction_supports.emplace_back(p.support, f.find("support")->at());
    } else if (p.quantity == Q::reaction || p.quantity == Q::moment) {
      r.fail(f.find("quantity")->at(),
             fmt::format("probe '{}' records a {} but names no 'support'", p.name,
                         name_of(p.quantity)),
             "replace 'point' or 'box' with 'support: <name of a support>'");
    } else if (auto point = r.vector(f, "point")) {
      p.kind = ProbeSpec::Kind::point;
      p.point = *point;
      marks.probe_points.emplace_back(p.point, f.find("point")->at());
      marks.probe_point_names.push_back("probe '" + p.name + "'");
      if (p.quantity == Q::opening) {
        const auto to = r.vector(f, "to");
        if (!to) {
          r.fail(f.find("point")->at(),
                 fmt::format("opening probe '{}' needs the second point 'to'", p.name),
                 "add 'to: [x, y, z]' on the other side of the crack");
        }
        p.to = *to;
        marks.probe_points.emplace_back(p.to, f.find("to")->at());
        marks.probe_point_names.push_back("probe '" + p.name + "' (to)");
      }
    } else if (f.has("line")) {
      p.kind = ProbeSpec::Kind::line;
      if (p.quantity == Q::opening) {
        r.fail(f.find("line")->at(),
               fmt::format("opening probe '{}' reads two points, not a line", p.name),
               "write 'point: [x, y, z]' and 'to: [x, y, z]' on either side of the crack");
      }
    } else if (p.quantity == Q::opening) {
      r.fail(list[i], fmt::format("opening probe '{}' reads two points", p.name),
             "write 'point: [x, y, z]' and 'to: [x, y, z]' on either side of the crack");
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
    if (const Entry* to = f.find("to"); to != nullptr && p.quantity != Q::opening) {
      r.fail(to->at(),
             fmt::format("'to' belongs to an opening probe; '{}' reads {}", p.name,
                         name_of(p.quantity)),
             "remove 'to' or write 'quantity: opening'");
    }
    if (const Entry* about = f.find("about")) {
      if (p.quantity != Q::moment) {
        r.fail(about->at(),
               fmt::format("'about' belongs to a moment probe; '{}' reads {}", p.name,
                           name_of(p.quantity)),
               "remove 'about' or write 'quantity: moment'");
      }
      p.about = *r.vector(f, "about");
    } else if (p.quantity == Q::moment) {
      r.fail(f.find("support")->at(),
             fmt::format("moment probe '{}' needs the point the moment is taken 'about'", p.name),
             "add 'about: [x, y, z]'");
    }
    // Not bound: a component must exist in the scene's dimension and fit the quantity.
    p.component = read_component(r, p, f.find("component"));
    if (p.kind == ProbeSpec::Kind::line) {
      read_line(r, f, p, probes, names, marks);
      continue;
    }
    probes.push_back(std::move(p));
  }
}

} // namespace pd::scene
