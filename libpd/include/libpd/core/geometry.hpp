// Geometry primitives: points, axis-aligned boxes, shapes, and regions made of them.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace pd {

using Vec3 = std::array<double, 3>;

inline double dot(const Vec3& a, const Vec3& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline double norm(const Vec3& a) {
  return std::sqrt(dot(a, a));
}

/// Closed axis-aligned box [lo, hi]. In 1D and 2D the unused coordinates are ignored.
struct Box {
  Vec3 lo{0, 0, 0};
  Vec3 hi{0, 0, 0};

  /// True if p lies in the box, faces included within an absolute tolerance `tol`.
  /// Only the first `dim` coordinates are checked.
  bool contains(const Vec3& p, int dim, double tol) const {
    for (int k = 0; k < dim; ++k) {
      if (p[k] < lo[k] - tol || p[k] > hi[k] + tol) {
        return false;
      }
    }
    return true;
  }
  bool operator==(const Box&) const = default;
};

/// A solid shape beside boxes (issue 19): bodies may be cylinders or spheres, and any body may
/// have shapes taken out of it (holes, notches, cuts). Only the first `dim` coordinates count, so
/// in 2D a cylinder along z and a sphere are both disks.
struct Shape {
  enum class Kind { box, cylinder, sphere, half_space } kind = Kind::box;
  Box box;              ///< box
  Vec3 centre{0, 0, 0}; ///< cylinder, sphere: centre; half_space: a point on its plane
  double radius = 0;    ///< cylinder, sphere
  int axis = 2;         ///< cylinder: the axis it runs along (0, 1, 2 = x, y, z)
  /// cylinder: extent along its axis, centred on `centre`; infinite: unbounded along the axis
  double length = std::numeric_limits<double>::infinity();
  Vec3 normal{0, 0, 1}; ///< half_space: the points p with (p − centre)·normal ≥ 0

  /// True if p lies in the shape, its surface included within `tol` (a negative `tol` shrinks it).
  bool contains(const Vec3& p, int dim, double tol) const {
    switch (kind) {
    case Kind::box:
      return box.contains(p, dim, tol);
    case Kind::sphere:
      return distance_from_centre(p, dim, -1) <= radius + tol;
    case Kind::cylinder:
      if (axis < dim && std::abs(p[static_cast<std::size_t>(axis)] -
                                 centre[static_cast<std::size_t>(axis)]) > 0.5 * length + tol) {
        return false;
      }
      return distance_from_centre(p, dim, axis) <= radius + tol;
    case Kind::half_space: {
      double s = 0;
      for (std::size_t k = 0; k < static_cast<std::size_t>(dim); ++k) {
        s += (p[k] - centre[k]) * normal[k];
      }
      double n2 = 0;
      for (std::size_t k = 0; k < static_cast<std::size_t>(dim); ++k) {
        n2 += normal[k] * normal[k];
      }
      return s >= -tol * std::sqrt(n2);
    }
    }
    return false;
  }
  /// Whether the shape is bounded in the first `dim` coordinates (a half-space never is).
  bool bounded(int dim) const {
    return kind == Kind::box || kind == Kind::sphere ||
           (kind == Kind::cylinder && (axis >= dim || std::isfinite(length)));
  }
  /// The smallest box holding the shape; only for bounded shapes.
  Box bounds(int dim) const {
    if (kind == Kind::box) {
      return box;
    }
    Box b{centre, centre};
    for (std::size_t k = 0; k < static_cast<std::size_t>(dim); ++k) {
      const double half =
          kind == Kind::cylinder && static_cast<int>(k) == axis ? 0.5 * length : radius;
      b.lo[k] -= half;
      b.hi[k] += half;
    }
    return b;
  }
  bool operator==(const Shape&) const = default;

private:
  /// Distance from the centre in the first `dim` coordinates, leaving out axis `skip`.
  double distance_from_centre(const Vec3& p, int dim, int skip) const {
    double s = 0;
    for (int k = 0; k < dim; ++k) {
      if (k != skip) {
        const double d = p[static_cast<std::size_t>(k)] - centre[static_cast<std::size_t>(k)];
        s += d * d;
      }
    }
    return std::sqrt(s);
  }
};

/// A region is a union of boxes and shapes, minus the shapes in `minus`. A point on the surface
/// of a hole belongs to the region (the hole is shrunk by the tolerance), as a point on the
/// surface of a box does.
struct Region {
  Region() = default;
  /// A plain union of boxes (brace-initialisable: Region{{box}}).
  Region(std::vector<Box> union_of_boxes) : boxes(std::move(union_of_boxes)) {} // NOLINT

  std::vector<Box> boxes;
  std::vector<Shape> shapes; ///< added to the union
  std::vector<Shape> minus;  ///< taken out of it: holes, notches, cuts
  /// Added to the union: particles named one by one (a mesh's physical group, io/mesh_file.hpp),
  /// sorted. They are copies of a mesh body's particle positions, so membership is exact
  /// equality: no tolerance could separate an unstructured set's neighbours reliably.
  std::shared_ptr<const std::vector<Vec3>> points;
  std::string group; ///< the physical group `points` came from ("" if none), for messages

  bool contains(const Vec3& p, int dim, double tol) const {
    bool inside = points && std::binary_search(points->begin(), points->end(), p);
    for (const Box& b : boxes) {
      if (b.contains(p, dim, tol)) {
        inside = true;
        break;
      }
    }
    for (std::size_t k = 0; !inside && k < shapes.size(); ++k) {
      inside = shapes[k].contains(p, dim, tol);
    }
    if (!inside) {
      return false;
    }
    for (const Shape& hole : minus) {
      if (hole.contains(p, dim, -tol)) {
        return false;
      }
    }
    return true;
  }
  /// Whether the region is a plain union of boxes (what the box-only checks can handle exactly).
  bool only_boxes() const { return shapes.empty() && minus.empty() && !points; }
  /// Boxes that together cover the region: its boxes, the bounds of its shapes and of its points.
  std::vector<Box> cover(int dim) const {
    std::vector<Box> out = boxes;
    for (const Shape& s : shapes) {
      out.push_back(s.bounds(dim));
    }
    if (points && !points->empty()) {
      Box b{points->front(), points->front()};
      for (const Vec3& p : *points) {
        for (std::size_t a = 0; a < 3; ++a) {
          b.lo[a] = std::min(b.lo[a], p[a]);
          b.hi[a] = std::max(b.hi[a], p[a]);
        }
      }
      out.push_back(b);
    }
    return out;
  }
  bool operator==(const Region&) const = default;
};

/// A pre-crack: a segment (2D, two vertices) or a planar polygon (3D, three or more vertices in
/// order). Bonds that cross it with both ends over it are never created (bond_cuts.cpp says why a
/// bond reaching past its front is kept).
struct Crack {
  std::string name;
  std::vector<Vec3> vertices;

  /// Whether the segment a–b crosses the crack (touching counts; a bond lying in the crack's
  /// plane does not cross it).
  bool cuts(const Vec3& a, const Vec3& b, int dim) const {
    return dim == 2 ? cuts_2d(a, b) : cuts_3d(a, b);
  }
  /// Whether p lies over the crack: its projection onto the crack's line (2D) or plane (3D) falls
  /// inside the segment or polygon (its edge included).
  bool covers(const Vec3& p, int dim) const {
    if (dim == 2) {
      const Vec3& c = vertices[0];
      const Vec3& d = vertices[1];
      const double along = (p[0] - c[0]) * (d[0] - c[0]) + (p[1] - c[1]) * (d[1] - c[1]);
      return along >= 0 && along <= (d[0] - c[0]) * (d[0] - c[0]) + (d[1] - c[1]) * (d[1] - c[1]);
    }
    const Vec3 n = normal();
    const double h = dot(n, sub(p, vertices[0])) / dot(n, n);
    return inside_polygon({p[0] - h * n[0], p[1] - h * n[1], p[2] - h * n[2]}, n);
  }
  bool operator==(const Crack&) const = default;

private:
  static double cross2(const Vec3& o, const Vec3& p, const Vec3& q) {
    return (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0]);
  }
  bool cuts_2d(const Vec3& a, const Vec3& b) const {
    const Vec3& c = vertices[0];
    const Vec3& d = vertices[1];
    const double d1 = cross2(c, d, a);
    const double d2 = cross2(c, d, b);
    const double d3 = cross2(a, b, c);
    const double d4 = cross2(a, b, d);
    return d1 * d2 <= 0 && d3 * d4 <= 0 && !(d1 == 0 && d2 == 0);
  }
  static Vec3 sub(const Vec3& p, const Vec3& q) { return {p[0] - q[0], p[1] - q[1], p[2] - q[2]}; }
  Vec3 normal() const {
    const Vec3 p = sub(vertices[1], vertices[0]);
    const Vec3 q = sub(vertices[2], vertices[0]);
    return {p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0]};
  }
  bool cuts_3d(const Vec3& a, const Vec3& b) const {
    const Vec3 n = normal();
    const double da = dot(n, sub(a, vertices[0]));
    const double db = dot(n, sub(b, vertices[0]));
    if (da * db > 0 || da == db) {
      return false; // both on one side, or the bond lies in the plane
    }
    const double t = da / (da - db);
    return inside_polygon(
        {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])}, n);
  }
  /// Whether x, projected along the normal n, falls inside the (convex or not) polygon: the
  /// crossing number in the plane's dominant projection.
  bool inside_polygon(const Vec3& x, const Vec3& n) const {
    std::size_t u = 0, v = 1;
    if (std::abs(n[0]) >= std::abs(n[1]) && std::abs(n[0]) >= std::abs(n[2])) {
      u = 1, v = 2;
    } else if (std::abs(n[1]) >= std::abs(n[2])) {
      u = 0, v = 2;
    }
    bool inside = false;
    for (std::size_t i = 0, j = vertices.size() - 1; i < vertices.size(); j = i++) {
      const Vec3& p = vertices[i];
      const Vec3& q = vertices[j];
      if ((p[v] > x[v]) != (q[v] > x[v]) &&
          x[u] < (q[u] - p[u]) * (x[v] - p[v]) / (q[v] - p[v]) + p[u]) {
        inside = !inside;
      }
    }
    return inside;
  }
};

} // namespace pd
