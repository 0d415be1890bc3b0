#include "libpd/discretisation/lattice.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <tuple>
#include <unordered_set>

namespace pd {

double cell_volume(const ModelDimension& d, double spacing) {
  switch (d.dim) {
  case 1:
    return spacing * d.cross_section;
  case 2:
    return spacing * spacing * d.thickness;
  default:
    return spacing * spacing * spacing;
  }
}

double lattice_coordinate(const LatticeSpec& l, int axis, long long n) {
  const double shift = l.convention == LatticeConvention::cell_centered ? 0.5 : 0.0;
  return l.origin[axis] + (static_cast<double>(n) + shift) * l.spacing;
}

std::array<long long, 3> nearest_lattice_site(const LatticeSpec& l, int dim, const Vec3& x) {
  const double shift = l.convention == LatticeConvention::cell_centered ? 0.5 : 0.0;
  std::array<long long, 3> s{0, 0, 0};
  for (std::size_t a = 0; a < static_cast<std::size_t>(dim); ++a) {
    s[a] = std::llround((x[a] - l.origin[a]) / l.spacing - shift);
  }
  return s;
}

std::pair<long long, long long> index_range(const LatticeSpec& l, int axis, double lo, double hi) {
  const double shift = l.convention == LatticeConvention::cell_centered ? 0.5 : 0.0;
  const double tol = 1e-6;
  const double a = (lo - l.origin[axis]) / l.spacing - shift;
  const double b = (hi - l.origin[axis]) / l.spacing - shift;
  return {static_cast<long long>(std::ceil(a - tol)), static_cast<long long>(std::floor(b + tol))};
}

namespace {

struct IndexHash {
  std::size_t operator()(const std::array<long long, 3>& k) const {
    std::size_t h = 1469598103934665603ULL;
    for (long long v : k) {
      h = (h ^ static_cast<std::size_t>(v)) * 1099511628211ULL;
    }
    return h;
  }
};

template <class Visit>
void for_each_lattice_point(const ModelDimension& d, const LatticeSpec& l, const Box& box,
                            Visit&& visit) {
  std::array<std::pair<long long, long long>, 3> r{};
  for (int a = 0; a < 3; ++a) {
    r[a] =
        a < d.dim ? index_range(l, a, box.lo[a], box.hi[a]) : std::pair<long long, long long>{0, 0};
    if (r[a].first > r[a].second) {
      return;
    }
  }
  for (long long k = r[2].first; k <= r[2].second; ++k) {
    for (long long j = r[1].first; j <= r[1].second; ++j) {
      for (long long i = r[0].first; i <= r[0].second; ++i) {
        visit(std::array<long long, 3>{i, j, k});
      }
    }
  }
}

Vec3 point_of(const ModelDimension& d, const LatticeSpec& l, const std::array<long long, 3>& idx) {
  Vec3 p{0, 0, 0};
  for (int a = 0; a < d.dim; ++a) {
    p[a] = lattice_coordinate(l, a, idx[a]);
  }
  return p;
}

} // namespace

std::size_t count_lattice_points(const ModelDimension& d, const LatticeSpec& lattice,
                                 const Region& region) {
  // Counting by index ranges first keeps absurd requests (10^12 particles) cheap to reject.
  double upper = 0;
  const std::vector<Box> cover = region.cover(d.dim);
  for (const Box& b : cover) {
    double product = 1;
    for (int a = 0; a < d.dim; ++a) {
      const auto r = index_range(lattice, a, b.lo[a], b.hi[a]);
      product *= r.second >= r.first ? static_cast<double>(r.second - r.first + 1) : 0.0;
    }
    upper += product;
  }
  if (upper >= 1.8e19) {
    return std::numeric_limits<std::size_t>::max(); // beyond size_t: clamp, never wrap to 0
  }
  if ((cover.size() <= 1 && region.only_boxes()) || upper > 2e7) {
    return static_cast<std::size_t>(upper); // exact for one box, an upper bound otherwise
  }
  std::unordered_set<std::array<long long, 3>, IndexHash> seen;
  const double tol = 1e-6 * lattice.spacing;
  for (const Box& b : cover) {
    for_each_lattice_point(d, lattice, b, [&](const std::array<long long, 3>& idx) {
      if (region.only_boxes() || region.contains(point_of(d, lattice, idx), d.dim, tol)) {
        seen.insert(idx);
      }
    });
  }
  return seen.size();
}

ParticleSet generate_lattice(const ModelDimension& d, const LatticeSpec& lattice,
                             const std::vector<BodySpec>& bodies) {
  if (!(lattice.spacing > 0)) {
    throw std::invalid_argument("lattice spacing must be positive");
  }
  struct Entry {
    std::array<long long, 3> index;
    std::uint16_t body;
  };
  std::vector<Entry> entries;
  std::unordered_set<std::array<long long, 3>, IndexHash> seen;
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    if (bodies[b].points) {
      continue; // its own particles, appended below
    }
    const Region& region = bodies[b].region;
    // Shapes and holes: the lattice points of the covering boxes that the region holds, with the
    // tolerance of index_range.
    const bool filter = !region.only_boxes();
    const double tol = 1e-6 * lattice.spacing;
    for (const Box& box : region.cover(d.dim)) {
      for_each_lattice_point(d, lattice, box, [&](const std::array<long long, 3>& idx) {
        if (filter && !region.contains(point_of(d, lattice, idx), d.dim, tol)) {
          return;
        }
        if (seen.insert(idx).second) {
          entries.push_back({idx, static_cast<std::uint16_t>(b)});
        }
      });
    }
  }
  // x fastest, then y, then z: neighbours along a beam's span sit next to each other in memory.
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return std::tie(a.index[2], a.index[1], a.index[0]) <
           std::tie(b.index[2], b.index[1], b.index[0]);
  });

  ParticleSet ps;
  ps.position.reserve(entries.size());
  const double v0 = cell_volume(d, lattice.spacing);
  std::mt19937_64 rng(lattice.seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (const Entry& e : entries) {
    Vec3 p = point_of(d, lattice, e.index);
    double v = v0;
    if (lattice.position_jitter > 0) {
      for (int a = 0; a < d.dim; ++a) {
        p[a] += lattice.position_jitter * lattice.spacing * unit(rng);
      }
    }
    if (lattice.volume_variation > 0) {
      v *= 1.0 + lattice.volume_variation * unit(rng);
    }
    ps.position.push_back(p);
    ps.volume.push_back(v);
    ps.body.push_back(e.body);
    ps.material.push_back(static_cast<std::uint16_t>(bodies[e.body].material));
  }
  // Point-cloud bodies follow the lattice particles, in file order.
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const PointCloud* cloud = bodies[b].points.get();
    if (cloud == nullptr) {
      continue;
    }
    ps.particle_size.resize(ps.position.size(), 0.0);
    for (std::size_t i = 0; i < cloud->count(); ++i) {
      if (bodies[b].fill == MeshFill::lattice) {
        // A site a lattice body (or an earlier filled mesh) already holds stays that body's, as
        // where two boxes overlap.
        if (!seen.insert(nearest_lattice_site(lattice, d.dim, cloud->position[i])).second) {
          continue;
        }
      }
      ps.position.push_back(cloud->position[i]);
      ps.volume.push_back(cloud->volume[i]);
      ps.body.push_back(static_cast<std::uint16_t>(b));
      ps.material.push_back(static_cast<std::uint16_t>(bodies[b].material));
      ps.particle_size.push_back(cloud->size.empty() ? std::numeric_limits<double>::quiet_NaN()
                                                     : cloud->size[i]);
    }
  }
  return ps;
}

} // namespace pd
