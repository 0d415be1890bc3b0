// Shapes beside boxes (issue 19): cylinder and sphere bodies, and the `minus` list of a body, the
// shapes taken out of it (holes, notches, cuts). The geometry itself is core/geometry.hpp.
#include "sections.hpp"

#include <cmath>

namespace pd::scene {

namespace {

constexpr Key centre_key(std::string_view doc) {
  return {.name = "centre",
          .type = Type::vector,
          .doc = doc,
          .unit = "m",
          .example = "[0.5, 0.5, 0]",
          .need = Need::required};
}
constexpr Key radius_key{.name = "radius",
                         .type = Type::number,
                         .doc = "radius",
                         .unit = "m",
                         .range = positive,
                         .example = "0.05",
                         .need = Need::required};

constexpr Key cylinder_keys[] = {
    centre_key("centre of the cylinder (of its axis segment)"),
    radius_key,
    {.name = "axis",
     .type = Type::choice,
     .doc = "the axis the cylinder runs along; in 2D a cylinder along z is a disk",
     .choices = axis_names,
     .fallback = "z"},
    {.name = "length",
     .type = Type::number,
     .doc = "extent along the axis, centred on 'centre'; omitted: unbounded along the axis (a "
            "hole through the body; a body cylinder in 3D needs it)",
     .unit = "m",
     .range = positive,
     .example = "1",
     .show = Show::commented},
};
constexpr Key sphere_keys[] = {
    centre_key("centre of the sphere (in 2D: of the disk)"),
    radius_key,
};
constexpr Key half_space_keys[] = {
    {.name = "point",
     .type = Type::vector,
     .doc = "a point on the bounding plane",
     .unit = "m",
     .example = "[1, 0, 0]",
     .need = Need::required},
    {.name = "normal",
     .type = Type::vector,
     .doc = "normal of the plane; the half-space is the side it points to",
     .example = "[1, 1, 0]",
     .need = Need::required},
};

} // namespace

constinit const Section cylinder_section{"in a cylinder", cylinder_keys};
constinit const Section sphere_section{"in a sphere", sphere_keys};
constinit const Section half_space_section{"in a half_space", half_space_keys};

namespace {

constexpr Key shape_keys[] = {
    {.name = "box",
     .type = Type::box,
     .doc = "a box [[lo], [hi]] taken out",
     .unit = "m",
     .example = "[[0.49, 0, 0], [0.51, 0.05, 0.1]]",
     .need = Need::one_of,
     .group = 1},
    shape_key("cylinder", "a cylinder (2D: a disk) taken out", &cylinder_section),
    shape_key("sphere", "a sphere (2D: a disk) taken out", &sphere_section),
    shape_key("half_space", "the half-space on the side the normal points to, taken out (a cut)",
              &half_space_section),
};

Shape read_round(Reader& r, const Fields& parent, std::string_view key) {
  const Fields f = r.section(parent, key);
  Shape s;
  s.kind = key == "sphere" ? Shape::Kind::sphere : Shape::Kind::cylinder;
  s.centre = *r.vector(f, "centre");
  s.radius = *r.number(f, "radius");
  if (s.kind == Shape::Kind::cylinder) {
    if (const Entry* a = f.find("axis")) {
      s.axis = r.word(a->at(), f.label("axis"), axis_names);
      if (r.dim == 2 && s.axis != 2) {
        r.fail(a->at(), "in a 2D scene a cylinder runs along z, out of the plane (a disk)",
               "remove 'axis' or write 'axis: z'");
      }
    }
    if (auto length = r.number(f, "length")) {
      s.length = *length;
    }
  }
  return s;
}

} // namespace

constinit const Section shape_section{"in a shape of 'minus'", shape_keys};

namespace {

constexpr Key surface_keys[] = {
    {.name = "box",
     .type = Type::box,
     .doc = "a box [[lo], [hi]]: its faces",
     .unit = "m",
     .example = "[[0, 0, 0], [1, 0.1, 0.1]]",
     .need = Need::one_of,
     .group = 1},
    shape_key("cylinder",
              "a cylinder (2D: a disk): its wall, and in 3D its ends if it has a 'length'",
              &cylinder_section),
    shape_key("sphere", "a sphere (2D: a disk)", &sphere_section),
};

} // namespace

constinit const Section surface_section{"in the surface of a load", surface_keys};

Shape read_surface(Reader& r, const Fields& parent) {
  const Fields f = r.section(parent, "surface");
  Shape s;
  if (const Entry* b = f.find("box")) {
    s.kind = Shape::Kind::box;
    s.box = r.box(b->at(), f.label("box"));
  } else if (f.has("cylinder") || f.has("sphere")) {
    s = read_round(r, f, f.has("cylinder") ? "cylinder" : "sphere");
  } else {
    r.lookup(f, "box"); // reports the missing alternatives
  }
  return s;
}

namespace {

constexpr Key crack_keys[] = {
    name_key("unique name of the crack", "notch"),
    {.name = "segment",
     .type = Type::points,
     .doc = "2D: the crack as a segment [[x0, y0], [x1, y1]]",
     .unit = "m",
     .example = "[[0.45, 0.1], [0.55, 0.1]]",
     .need = Need::one_of,
     .group = 1,
     .only_dim = 2},
    {.name = "polygon",
     .type = Type::points,
     .doc = "3D: the crack as a planar polygon, its vertices in order",
     .unit = "m",
     .example = "[[0.45, 0, 0.1], [0.55, 0, 0.1], [0.55, 0.1, 0.1], [0.45, 0.1, 0.1]]",
     .need = Need::one_of,
     .group = 1,
     .only_dim = 3,
     .show = Show::commented},
};

} // namespace

constinit const Section crack_section{"in a crack", crack_keys};

void read_cracks(Reader& r, ModelSpec& model, Marks& marks) {
  std::map<std::string, YAML::Node> names;
  const auto list = r.items(marks.top, "cracks");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const Fields f = r.item(list[i], crack_section, "crack", "cracks", i);
    Crack c;
    c.name = *r.string(f, "name");
    check_unique(r, names, c.name, f.find("name")->at(), "crack");
    const std::string_view key = r.dim == 2 ? "segment" : "polygon";
    const Entry* e = r.lookup(f, key);
    if (e == nullptr) {
      r.fail(f.anchor, fmt::format("crack '{}' needs '{}' in a {}D scene", c.name, key, r.dim),
             fmt::format("add {}", example_line(key_of(crack_section, key))));
    }
    const YAML::Node n = e->at();
    const std::size_t want = r.dim == 2 ? 2 : 3;
    if (!n.IsSequence() || n.size() < want || (r.dim == 2 && n.size() != 2)) {
      r.fail(n,
             fmt::format("{} must be a list of {} points, got {}", f.label(key),
                         r.dim == 2 ? "two" : "three or more", describe(n)),
             fmt::format("write e.g. {}", example_line(*e->key)));
    }
    for (std::size_t k = 0; k < n.size(); ++k) {
      c.vertices.push_back(
          r.coordinates(n[k], fmt::format("point {} of {}", k + 1, f.label(key)), "m"));
    }
    if (r.dim == 2 && c.vertices[0] == c.vertices[1]) {
      // A crack of no length cuts no bond, and the FE reference cannot mesh a slit of none.
      r.fail(n, fmt::format("crack '{}' has no length: its two points are the same", c.name),
             "give the crack's two different end points");
    }
    if (r.dim == 3) {
      const Vec3& a = c.vertices[0];
      const Vec3& b = c.vertices[1];
      const Vec3& d = c.vertices[2];
      const Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      const Vec3 v{d[0] - a[0], d[1] - a[1], d[2] - a[2]};
      const Vec3 normal{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                        u[0] * v[1] - u[1] * v[0]};
      const double scale = norm(u) * norm(v);
      for (const Vec3& p : c.vertices) {
        const Vec3 w{p[0] - a[0], p[1] - a[1], p[2] - a[2]};
        if (!(scale > 0) || std::abs(dot(normal, w)) > 1e-9 * scale * (norm(w) + norm(u))) {
          r.fail(n,
                 fmt::format("the polygon of crack '{}' is not planar (or its first three "
                             "vertices are in line)",
                             c.name),
                 "give the vertices of a flat polygon, in order around it");
        }
      }
    }
    // A crack away from every body cuts no bond: almost surely a coordinate slip (a unit, a sign).
    Box bounds{c.vertices.front(), c.vertices.front()};
    for (const Vec3& p : c.vertices) {
      for (int a = 0; a < r.dim; ++a) {
        bounds.lo[a] = std::min(bounds.lo[a], p[a]);
        bounds.hi[a] = std::max(bounds.hi[a], p[a]);
      }
    }
    const double reach = model.lattice.spacing;
    bool near_a_body = false;
    for (const BodySpec& body : model.bodies) {
      for (const Box& b : body.region.cover(r.dim)) {
        bool meets = true;
        for (int a = 0; a < r.dim; ++a) {
          meets = meets && bounds.lo[a] <= b.hi[a] + reach && b.lo[a] - reach <= bounds.hi[a];
        }
        near_a_body = near_a_body || meets;
      }
    }
    if (!near_a_body) {
      r.warn(n, fmt::format("crack '{}' lies outside every body: it cuts no bond", c.name));
    }
    model.cracks.push_back(std::move(c));
    marks.crack_nodes.push_back(n);
  }
}

std::optional<Shape> read_body_shape(Reader& r, const Fields& f) {
  for (std::string_view key : {"cylinder", "sphere"}) {
    if (!f.has(key)) {
      continue;
    }
    Shape s = read_round(r, f, key);
    if (!s.bounded(r.dim)) {
      r.fail(f.find(key)->at(),
             fmt::format("the cylinder of {} is unbounded: a body must be finite", f.owner),
             "give the cylinder a 'length'");
    }
    return s;
  }
  return std::nullopt;
}

std::vector<Shape> read_minus(Reader& r, const Fields& f) {
  std::vector<Shape> out;
  const auto list = r.items(f, "minus");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const Fields item =
        r.open(list[i], list[i], shape_section, {},
               fmt::format("shape #{} of 'minus' of {}", i + 1, f.owner), "a shape");
    Shape s;
    if (const Entry* b = item.find("box")) {
      s.kind = Shape::Kind::box;
      s.box = r.box(b->at(), item.label("box"));
    } else if (item.has("half_space")) {
      const Fields h = r.section(item, "half_space");
      s.kind = Shape::Kind::half_space;
      s.centre = *r.vector(h, "point");
      s.normal = *r.vector(h, "normal");
      if (norm(s.normal) == 0) {
        r.fail(h.find("normal")->at(), "the normal of a half_space is zero",
               "give the direction the removed side lies in, e.g. [1, 0, 0]");
      }
    } else if (item.has("cylinder") || item.has("sphere")) {
      s = read_round(r, item, item.has("cylinder") ? "cylinder" : "sphere");
    } else {
      r.lookup(item, "box"); // reports the missing alternatives
    }
    out.push_back(s);
  }
  return out;
}

} // namespace pd::scene
