#include "libpd/discretisation/point_cloud.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <unordered_map>

namespace pd {

namespace {

using Cell = std::array<long long, 3>;

struct CellHash {
  std::size_t operator()(const Cell& c) const {
    return static_cast<std::size_t>(c[0] * 73856093LL ^ c[1] * 19349663LL ^ c[2] * 83492791LL);
  }
};

/// Points binned by a cube of edge `edge`.
struct CellList {
  double edge;
  int dim;
  std::unordered_map<Cell, std::vector<std::uint32_t>, CellHash> cells;

  CellList(const std::vector<Vec3>& p, int d, double e) : edge(e), dim(d) {
    for (std::size_t i = 0; i < p.size(); ++i) {
      cells[cell_of(p[i])].push_back(static_cast<std::uint32_t>(i));
    }
  }
  Cell cell_of(const Vec3& x) const {
    Cell c{0, 0, 0};
    for (int a = 0; a < dim; ++a) {
      c[static_cast<std::size_t>(a)] =
          static_cast<long long>(std::floor(x[static_cast<std::size_t>(a)] / edge));
    }
    return c;
  }
  /// Visit every point in the cells at Chebyshev ring distance exactly `ring` around c.
  template <class Visit>
  void ring(const Cell& c, long long ring, Visit&& visit) const {
    const long long rj = dim > 1 ? ring : 0, rk = dim > 2 ? ring : 0;
    for (long long k = -rk; k <= rk; ++k) {
      for (long long j = -rj; j <= rj; ++j) {
        for (long long i = -ring; i <= ring; ++i) {
          if (std::max({std::abs(i), std::abs(j), std::abs(k)}) != ring) {
            continue;
          }
          const auto it = cells.find({c[0] + i, c[1] + j, c[2] + k});
          if (it != cells.end()) {
            for (const std::uint32_t q : it->second) {
              visit(q);
            }
          }
        }
      }
    }
  }
};

double distance(const Vec3& a, const Vec3& b) {
  const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

} // namespace

std::vector<std::vector<std::uint32_t>> nearest_neighbours(const std::vector<Vec3>& points, int dim,
                                                           int count) {
  const std::size_t n = points.size();
  std::vector<std::vector<std::uint32_t>> out(n);
  if (n < 2) {
    return out;
  }
  const auto want = std::min<std::size_t>(static_cast<std::size_t>(count), n - 1);
  // A cell holding a few points on average: the bounding box's measure per point.
  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& p : points) {
    for (std::size_t a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  }
  double measure = 1;
  for (std::size_t a = 0; a < static_cast<std::size_t>(dim); ++a) {
    measure *= std::max(hi[a] - lo[a], 1e-300);
  }
  const double edge = std::pow(measure / static_cast<double>(n), 1.0 / dim);
  const CellList cells(points, dim, edge);
  std::vector<std::pair<double, std::uint32_t>> found;
  for (std::size_t i = 0; i < n; ++i) {
    found.clear();
    const Cell c = cells.cell_of(points[i]);
    // Grow rings until `want` points are known and no unseen one can be nearer: a point in
    // ring r + 1 is at least r·edge away.
    for (long long r = 0;; ++r) {
      cells.ring(c, r, [&](std::uint32_t q) {
        if (q != i) {
          found.emplace_back(distance(points[i], points[q]), q);
        }
      });
      if (found.size() >= want) {
        std::nth_element(found.begin(), found.begin() + static_cast<std::ptrdiff_t>(want - 1),
                         found.end());
        if (found[want - 1].first <= static_cast<double>(r) * edge) {
          break;
        }
      }
    }
    std::sort(found.begin(), found.end());
    out[i].reserve(want);
    for (std::size_t k = 0; k < want; ++k) {
      out[i].push_back(found[k].second);
    }
  }
  return out;
}

std::vector<double> sizes_from_neighbours(const std::vector<Vec3>& points, int dim,
                                          int neighbours) {
  const auto near = nearest_neighbours(points, dim, neighbours);
  std::vector<double> h(points.size(), 0.0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    double sum = 0;
    for (const std::uint32_t q : near[i]) {
      sum += distance(points[i], points[q]);
    }
    h[i] = near[i].empty() ? 0.0 : sum / (2.0 * static_cast<double>(near[i].size())); // eq. 115
  }
  return h;
}

BondFamily variable_horizon_family(const std::vector<Vec3>& position, int dim,
                                   const std::vector<double>& horizon) {
  const std::size_t n = position.size();
  BondFamily f;
  f.offsets.assign(1, 0);
  if (n == 0) {
    return f;
  }
  const double largest = *std::max_element(horizon.begin(), horizon.end());
  if (!(largest > 0)) {
    throw std::invalid_argument("variable_horizon_family: horizons must be positive");
  }
  const CellList cells(position, dim, largest);
  std::vector<std::pair<std::uint32_t, double>> row;
  for (std::size_t i = 0; i < n; ++i) {
    row.clear();
    const Cell c = cells.cell_of(position[i]);
    for (long long r = 0; r <= 1; ++r) {
      cells.ring(c, r, [&](std::uint32_t j) {
        if (j == i) {
          return;
        }
        const double d = distance(position[i], position[j]);
        if (d <= std::max(horizon[i], horizon[j])) {
          row.emplace_back(j, d);
        }
      });
    }
    std::sort(row.begin(), row.end());
    for (const auto& [j, d] : row) {
      f.neighbour.push_back(j);
      f.inverse_length.push_back(1.0 / d);
    }
    f.offsets.push_back(f.neighbour.size());
  }
  return f;
}

} // namespace pd
