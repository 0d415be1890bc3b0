#include "libpd/discretisation/lattice.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <stdexcept>
#include <tuple>
#include <unordered_map>
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

namespace {

bool curved(const Shape& s) {
  return s.kind != Shape::Kind::box;
}

} // namespace

bool has_curved_surface(const Region& r) {
  return std::any_of(r.shapes.begin(), r.shapes.end(), curved) ||
         std::any_of(r.minus.begin(), r.minus.end(), curved);
}

// Boxes are tested at the cell's centre, as before, so a box face on or between cell faces keeps
// the lattice's whole cells, and a notch narrower than a cell never leaves a cell holding material
// on both its sides. The count runs on sub-cell midpoints (16² in 2D, 8³ in 3D) after a first look
// at the cell's corners, face centres and centre, which decides a cell no curved surface crosses.
CellShare cell_share(const Region& region, int dim, const Vec3& centre, double spacing) {
  const double tol = 1e-6 * spacing;
  bool whole_in =
      region.points && std::binary_search(region.points->begin(), region.points->end(), centre);
  for (const Box& b : region.boxes) {
    whole_in = whole_in || b.contains(centre, dim, tol);
  }
  for (const Shape& s : region.shapes) {
    whole_in = whole_in || (!curved(s) && s.contains(centre, dim, tol));
  }
  for (const Shape& hole : region.minus) {
    if (!curved(hole) && hole.contains(centre, dim, -tol)) {
      return {};
    }
  }
  const auto holds = [&](const Vec3& p) {
    bool in = whole_in;
    for (std::size_t k = 0; !in && k < region.shapes.size(); ++k) {
      in = curved(region.shapes[k]) && region.shapes[k].contains(p, dim, 0.0);
    }
    for (std::size_t k = 0; in && k < region.minus.size(); ++k) {
      in = !(curved(region.minus[k]) && region.minus[k].contains(p, dim, 0.0));
    }
    return in;
  };
  struct Count {
    int inside = 0;
    int total = 0;
    Vec3 offset_sum{0, 0, 0}; ///< of the points inside, from the centre
  };
  const auto count = [&](int n, bool midpoints) {
    // n points per axis: the sub-cell midpoints, or n = 3 points from face to face.
    Count c;
    const int nj = dim > 1 ? n : 1;
    const int nk = dim > 2 ? n : 1;
    for (int k = 0; k < nk; ++k) {
      for (int j = 0; j < nj; ++j) {
        for (int i = 0; i < n; ++i) {
          const std::array<int, 3> ijk{i, j, k};
          Vec3 p = centre;
          for (std::size_t a = 0; a < static_cast<std::size_t>(dim); ++a) {
            const double t = midpoints ? (ijk[a] + 0.5) / n : static_cast<double>(ijk[a]) / (n - 1);
            p[a] += (t - 0.5) * spacing;
          }
          if (holds(p)) {
            ++c.inside;
            for (std::size_t a = 0; a < 3; ++a) {
              c.offset_sum[a] += p[a] - centre[a];
            }
          }
          ++c.total;
        }
      }
    }
    return c;
  };
  const Count coarse = count(3, false);
  if (coarse.inside == 0 || coarse.inside == coarse.total) {
    return coarse.inside == 0 ? CellShare{} : CellShare{1.0, {0, 0, 0}};
  }
  const Count fine = count(dim == 3 ? 8 : dim == 2 ? 16 : 64, true);
  CellShare out;
  out.share = static_cast<double>(fine.inside) / static_cast<double>(fine.total);
  for (std::size_t a = 0; a < 3 && fine.inside > 0; ++a) {
    out.centroid_offset[a] = fine.offset_sum[a] / fine.inside;
  }
  return out;
}

namespace {

/// The lattice sites the bodies hold, one particle each, with the share of its cell.
class LatticeSites {
public:
  struct Entry {
    std::array<long long, 3> index;
    std::uint16_t body;
    double share = 1;       ///< of the owning body
    double total_share = 1; ///< of all bodies, and of slivers joined to it
  };

  LatticeSites(const ModelDimension& d, const LatticeSpec& lattice) : d_(d), lattice_(lattice) {}

  /// The sites of body b's region: the lattice points of its covering boxes that it holds, with
  /// the tolerance of index_range; with a curved surface, every cell it holds a share of at least
  /// min_cell_share of (the covering boxes widened by a cell to reach them).
  void add_body(std::size_t b, const Region& region) {
    const bool filter = !region.only_boxes();
    const bool cut = has_curved_surface(region);
    const double tol = 1e-6 * lattice_.spacing;
    for (Box box : region.cover(d_.dim)) {
      for (int a = 0; cut && a < d_.dim; ++a) {
        box.lo[a] -= lattice_.spacing;
        box.hi[a] += lattice_.spacing;
      }
      for_each_lattice_point(d_, lattice_, box, [&](const std::array<long long, 3>& idx) {
        const Vec3 centre = point_of(d_, lattice_, idx);
        if (!cut) {
          if (!filter || region.contains(centre, d_.dim, tol)) {
            add(idx, b, 1.0);
          }
          return;
        }
        const CellShare c = cell_share(region, d_.dim, centre, lattice_.spacing);
        if (c.share >= min_cell_share) {
          add(idx, b, c.share);
        } else if (c.share > 0) {
          slivers_.emplace(
              std::array<long long, 4>{idx[0], idx[1], idx[2], static_cast<long long>(b)}, c);
        }
      });
    }
  }

  /// A sliver joins the particle of its own site (a curved interface's other body) or the one
  /// next to it towards its centroid, so the bodies keep their volume (and mass); only a sliver
  /// with no particle beside it is lost. Equally large offsets along several axes (a sliver on a
  /// disk's diagonal) share it among their neighbours, so that a body symmetric about the
  /// diagonal stays so.
  void join_slivers() {
    for (const auto& [key, c] : slivers_) {
      const std::array<long long, 3> idx{key[0], key[1], key[2]};
      if (const auto own = entry_of_.find(idx); own != entry_of_.end()) {
        entries_[own->second].total_share += c.share;
        continue;
      }
      std::array<std::size_t, 3> axes{0, 1, 2};
      std::stable_sort(axes.begin(), axes.begin() + d_.dim, [&](std::size_t a, std::size_t b) {
        return std::abs(c.centroid_offset[a]) > std::abs(c.centroid_offset[b]);
      });
      std::vector<std::size_t> to;
      double level = -1;
      for (std::size_t k = 0; k < static_cast<std::size_t>(d_.dim); ++k) {
        const std::size_t a = axes[k];
        const double size = std::abs(c.centroid_offset[a]);
        if (!to.empty() && size < level * (1 - 1e-9)) {
          break; // the neighbours along the largest offsets found take it
        }
        level = size;
        if (size == 0) {
          break;
        }
        auto next = idx;
        next[a] += c.centroid_offset[a] > 0 ? 1 : -1;
        if (const auto it = entry_of_.find(next); it != entry_of_.end()) {
          to.push_back(it->second);
        }
      }
      for (const std::size_t e : to) {
        entries_[e].total_share += c.share / static_cast<double>(to.size());
      }
    }
    slivers_.clear();
  }

  /// Whether a point cloud's site is free, and taking it if so.
  bool take(const std::array<long long, 3>& site) { return entry_of_.emplace(site, 0).second; }

  std::vector<Entry>& entries() { return entries_; }

private:
  void add(const std::array<long long, 3>& idx, std::size_t b, double share) {
    const auto [it, added] = entry_of_.emplace(idx, entries_.size());
    if (added) {
      entries_.push_back({idx, static_cast<std::uint16_t>(b), share, share});
      return;
    }
    // A site two bodies hold a share of (a curved interface) is one particle: the body with the
    // larger share, holding both (a site of two overlapping bodies stays the first's).
    Entry& e = entries_[it->second];
    if (e.body == b) {
      return; // reached again through another covering box
    }
    if (share > e.share) {
      e.body = static_cast<std::uint16_t>(b);
      e.share = share;
    }
    e.total_share = std::min(1.0, e.total_share + share);
  }

  const ModelDimension& d_;
  const LatticeSpec& lattice_;
  std::vector<Entry> entries_;
  std::unordered_map<std::array<long long, 3>, std::size_t, IndexHash> entry_of_;
  std::map<std::array<long long, 4>, CellShare> slivers_; // by site and body, in a fixed order
};

} // namespace

ParticleSet generate_lattice(const ModelDimension& d, const LatticeSpec& lattice,
                             const std::vector<BodySpec>& bodies) {
  if (!(lattice.spacing > 0)) {
    throw std::invalid_argument("lattice spacing must be positive");
  }
  LatticeSites sites(d, lattice);
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    if (!bodies[b].points) { // a point cloud's own particles are appended below
      sites.add_body(b, bodies[b].region);
    }
  }
  sites.join_slivers();
  std::vector<LatticeSites::Entry>& entries = sites.entries();
  // x fastest, then y, then z: neighbours along a beam's span sit next to each other in memory.
  using Entry = LatticeSites::Entry;
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
    double v = v0 * e.total_share;
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
        if (!sites.take(nearest_lattice_site(lattice, d.dim, cloud->position[i]))) {
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
