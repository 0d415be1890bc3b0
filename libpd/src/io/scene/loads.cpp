// The `loads` list: forces on the particles in a region, as a total, a traction or a density.
#include "bind.hpp"
#include "sections.hpp"

namespace pd::scene {

namespace {

constexpr Key load_keys[] = {
    name_key("unique name of the load", "pull"),
    box_key("region whose particles (of any body) carry the load", "[[0.99, 0, 0], [1, 0.1, 0.1]]"),
    boxes_key("instead of box: a union of boxes", "[[[0.99, 0, 0], [1, 0.1, 0.1]]]"),
    group_key("instead of box: the particles of a mesh body's physical group"),
    {.name = "point",
     .type = Type::vector,
     .doc = "instead of box: a point load, shared by the body particles nearest the point (the "
            "run's summary says how many); type 'point' or omitted, value in N",
     .unit = "m",
     .example = "[1, 0.05, 0.1]",
     .need = Need::one_of,
     .group = 1,
     .show = Show::commented},
    shape_key("surface",
              "instead of box: a pressure on the surface of this shape (a hole's wall, a "
              "body's outer face) where it bounds a body; type 'pressure' or omitted",
              &surface_section),
    {.name = "type",
     .type = Type::choice,
     .doc = "total force [N] spread over the region, or a traction per_area [N/m²], per_length "
            "[N/m], or a body force density [N/m³]; point and pressure follow from 'point' and "
            "'surface'",
     .choices = enum_words<BoxRegionLoad::Kind>,
     .bind = field_with_default<&LoadSpec::load, &BoxRegionLoad::kind>()},
    {.name = "value",
     .type = Type::vector,
     .doc = "force vector, in the unit its type implies",
     .example = "[1000, 0, 0]",
     .need = Need::one_of,
     .group = 2,
     .bind = field<&LoadSpec::load, &BoxRegionLoad::value>()},
    {.name = "pressure",
     .type = Type::number,
     .doc = "instead of value, with 'surface': the pressure, pushing into the body along the "
            "surface's normal (negative: suction); the load's resultant is pressure × area",
     .unit = "Pa",
     .example = "1e8",
     .need = Need::one_of,
     .group = 2,
     .show = Show::commented,
     .bind = field<&LoadSpec::load, &BoxRegionLoad::pressure>()},
    {.name = "measure",
     .type = Type::number,
     .doc = "loaded area [m²] (per_area) or length [m] (per_length); only for these types",
     .unit = "m² or m",
     .range = positive,
     .example = "0.01",
     .show = Show::commented},
};

} // namespace

constinit const Section load_section{"in a load", load_keys};

void read_loads(Reader& r, ModelSpec& model, Marks& marks) {
  std::map<std::string, YAML::Node> names;
  const auto list = r.items(marks.top, "loads");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const Fields f = r.item(list[i], load_section, "load", "loads", i);
    LoadSpec l;
    l.name = *r.string(f, "name");
    check_unique(r, names, l.name, f.find("name")->at(), "load");
    Reader::RegionRead region;
    const bool surface = f.has("surface");
    if (surface) {
      l.load.surface = read_surface(r, f);
      region.node = f.find("surface")->at();
    } else if (auto point = r.vector(f, "point")) {
      l.load.point = *point;
      region.node = f.find("point")->at();
      marks.probe_points.emplace_back(*point, region.node);
      marks.probe_point_names.push_back("point load '" + l.name + "'");
    } else {
      region = r.region(f);
      l.load.region = region.region;
    }
    r.read_bound(f, l);
    if (f.has("point")) {
      if (f.has("type") && l.load.kind != BoxRegionLoad::Kind::point) {
        r.fail(f.find("type")->at(),
               fmt::format("load '{}' has a 'point', so its type is 'point', not '{}'", l.name,
                           name_of(l.load.kind)),
               "remove 'type' or write 'type: point'");
      }
      l.load.kind = BoxRegionLoad::Kind::point;
    } else if (l.load.kind == BoxRegionLoad::Kind::point) {
      r.fail(f.find("type")->at(), fmt::format("load '{}' of type point needs 'point'", l.name),
             "replace 'box' with 'point: [x, y, z]'");
    }
    if (surface) {
      if (f.has("type") && l.load.kind != BoxRegionLoad::Kind::pressure) {
        r.fail(f.find("type")->at(),
               fmt::format("load '{}' has a 'surface', so its type is 'pressure', not '{}'", l.name,
                           name_of(l.load.kind)),
               "remove 'type' or write 'type: pressure'");
      }
      l.load.kind = BoxRegionLoad::Kind::pressure;
      if (!f.has("pressure")) {
        r.fail(f.find("value")->name,
               fmt::format("load '{}' on a surface takes a 'pressure' [Pa], not a 'value'", l.name),
               "write e.g. 'pressure: 1e8' (positive pushes into the body)");
      }
    } else if (l.load.kind == BoxRegionLoad::Kind::pressure) {
      r.fail(
          f.find("type")->at(),
          fmt::format("load '{}' of type pressure needs 'surface', the shape it acts on", l.name),
          "replace 'box' with e.g. 'surface: {cylinder: {centre: [0, 0], radius: 0.05}}'");
    } else if (f.has("pressure")) {
      r.fail(f.find("pressure")->name,
             fmt::format("'pressure' of load '{}' needs 'surface', the shape it acts on", l.name),
             "give 'surface: {cylinder: ...}' or write the load as 'value: [x, y, z]'");
    } else {
      r.check_in_space(f.find("value")->at(), f.label("value"), l.load.value);
    }
    const bool needs_measure = l.load.kind == BoxRegionLoad::Kind::per_area ||
                               l.load.kind == BoxRegionLoad::Kind::per_length;
    if (auto measure = r.number(f, "measure")) {
      if (!needs_measure) {
        r.fail(f.find("measure")->name,
               fmt::format("'measure' of load '{}' applies only to per_area and per_length loads",
                           l.name),
               "remove it: total and body loads need no area or length");
      }
      l.load.measure = *measure;
    } else if (needs_measure) {
      r.fail(f.anchor,
             fmt::format("load '{}' of type {} needs 'measure', the loaded {}", l.name,
                         name_of(l.load.kind),
                         l.load.kind == BoxRegionLoad::Kind::per_area ? "area [m²]" : "length [m]"),
             "add e.g. 'measure: 0.01'");
    }
    if (l.load.kind != BoxRegionLoad::Kind::point && !surface) {
      marks.must_touch_bodies.push_back(
          {l.load.region, region.node, fmt::format("load '{}' acts on no particle", l.name)});
    }
    model.loads.push_back(std::move(l));
  }
}

} // namespace pd::scene
