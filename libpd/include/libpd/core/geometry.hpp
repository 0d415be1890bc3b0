// Geometry primitives: points, axis-aligned boxes and unions of boxes.
#pragma once

#include <array>
#include <cmath>
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

/// A region is a union of boxes; a point belongs to it if it is in any box.
struct Region {
  std::vector<Box> boxes;

  bool contains(const Vec3& p, int dim, double tol) const {
    for (const Box& b : boxes) {
      if (b.contains(p, dim, tol)) {
        return true;
      }
    }
    return false;
  }
  bool operator==(const Region&) const = default;
};

} // namespace pd
