#include "libpd/io/resources.hpp"

#include "libpd/discretisation/corrections.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fmt/format.h>
#include <fstream>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace pd {

namespace {

constexpr double inf = std::numeric_limits<double>::infinity();

/// Lattice index interval [first, last] of one axis, in floating point so that boxes far beyond
/// the range of long long cannot overflow. The rule is the one of lattice.cpp's `index_range`.
struct Interval {
  double first = 0;
  double last = -1;
  double count() const {
    if (!std::isfinite(first) || !std::isfinite(last)) {
      return std::isnan(first) || std::isnan(last) || first == inf || last == -inf ? 0.0 : inf;
    }
    return last >= first ? last - first + 1 : 0.0;
  }
};

Interval axis_interval(const LatticeSpec& l, int axis, double lo, double hi) {
  const double shift = l.convention == LatticeConvention::cell_centered ? 0.5 : 0.0;
  const double tol = 1e-6;
  const double a = (lo - l.origin[axis]) / l.spacing - shift;
  const double b = (hi - l.origin[axis]) / l.spacing - shift;
  return {std::ceil(a - tol), std::floor(b + tol)};
}

/// Sum over boxes of the points per box: an upper bound of the union.
double sum_over_boxes(const ModelDimension& d, const LatticeSpec& lattice, const Region& region) {
  double sum = 0;
  for (const Box& b : region.boxes) {
    sum += lattice_points_in_box(d, lattice, b);
  }
  return sum;
}

/// The items that lie in no other one (`inside(a, b)`: a within b). Of equal items the first
/// stays; a strictly larger one always wins. Work k² for k items.
template <class T, class Inside>
std::vector<T> outermost(const std::vector<T>& items, Inside inside) {
  std::vector<T> kept;
  for (std::size_t i = 0; i < items.size(); ++i) {
    bool redundant = false;
    for (std::size_t j = 0; j < items.size() && !redundant; ++j) {
      redundant = j != i && inside(items[i], items[j]) && (j < i || !inside(items[j], items[i]));
    }
    if (!redundant) {
      kept.push_back(items[i]);
    }
  }
  return kept;
}

/// Lattice sites outside a box within the horizon of its points (ghost_layers.hpp): a site whose
/// distances beyond the box's faces are (a_x, a_y, a_z) layers (0 where it lies within the box's
/// range) is within the horizon of the box's nearest point iff Σ a² is, and there are
/// Π (a_i = 0 ? n_i : 2) such sites. Exact for one box.
double ghost_sites_around_box(const ModelDimension& d, const LatticeSpec& lattice, HorizonRule rule,
                              const Box& box) {
  std::array<double, 3> n{1, 1, 1};
  for (int a = 0; a < d.dim; ++a) {
    n[static_cast<std::size_t>(a)] = axis_interval(lattice, a, box.lo[a], box.hi[a]).count();
    if (n[static_cast<std::size_t>(a)] == 0 || !std::isfinite(n[static_cast<std::size_t>(a)])) {
      return n[static_cast<std::size_t>(a)];
    }
  }
  const InHorizon inside(lattice.horizon_factor, rule);
  const auto reach = static_cast<long long>(std::ceil(lattice.horizon_factor));
  double count = 0;
  const long long ry = d.dim > 1 ? reach : 0;
  const long long rz = d.dim > 2 ? reach : 0;
  for (long long az = 0; az <= rz; ++az) {
    for (long long ay = 0; ay <= ry; ++ay) {
      for (long long ax = 0; ax <= reach; ++ax) {
        const auto s2 = static_cast<double>(ax * ax + ay * ay + az * az);
        if (s2 > 0 && inside(s2)) {
          count += (ax == 0 ? n[0] : 2.0) * (ay == 0 ? n[1] : 2.0) * (az == 0 ? n[2] : 2.0);
        }
      }
    }
  }
  return count;
}

/// Ghost sites around a union of boxes, never fewer than there are: a ghost near a box nested in
/// another is near the outer one too, so nested and repeated boxes are left out, and the sum over
/// the others can only count too many (where boxes touch, their faces' ghosts are body sites).
/// Work (m + 1)^dim per box, m capped by the scene checks.
double ghost_sites_around_union(const ModelDimension& d, const LatticeSpec& lattice,
                                HorizonRule rule, const Region& all) {
  const auto inside = [&](const Box& a, const Box& b) {
    for (int ax = 0; ax < d.dim; ++ax) {
      if (a.lo[ax] < b.lo[ax] || a.hi[ax] > b.hi[ax]) {
        return false;
      }
    }
    return true;
  };
  double ghosts = 0;
  for (const Box& box : outermost(all.boxes, inside)) {
    ghosts += ghost_sites_around_box(d, lattice, rule, box);
  }
  return ghosts;
}

std::size_t distinct_materials(const ModelSpec& spec) {
  std::vector<int> used;
  for (const BodySpec& b : spec.bodies) {
    if (std::find(used.begin(), used.end(), b.material) == used.end()) {
      used.push_back(b.material);
    }
  }
  return used.size();
}

} // namespace

double lattice_points_in_box(const ModelDimension& d, const LatticeSpec& lattice, const Box& box) {
  double product = 1;
  for (int a = 0; a < d.dim; ++a) {
    const double n = axis_interval(lattice, a, box.lo[a], box.hi[a]).count();
    if (n == 0) {
      return 0; // an empty axis empties the box even if another axis is unbounded
    }
    product *= n;
  }
  return product;
}

double lattice_points_in_union(const ModelDimension& d, const LatticeSpec& lattice,
                               const Region& region) {
  const std::size_t k = region.boxes.size();
  // One box, or so many that even dropping the nested ones (k² comparisons) is too slow: the sum
  // over the boxes, which can only count too many.
  if (k <= 1 || k > 5000) {
    return sum_over_boxes(d, lattice, region);
  }
  std::vector<std::array<Interval, 3>> boxes;
  for (const Box& b : region.boxes) {
    std::array<Interval, 3> iv{};
    bool empty = false;
    for (int a = 0; a < d.dim; ++a) {
      iv[a] = axis_interval(lattice, a, b.lo[a], b.hi[a]);
      const double n = iv[a].count();
      if (n == 0) {
        empty = true;
      } else if (!std::isfinite(n)) {
        return inf;
      }
    }
    if (!empty) {
      boxes.push_back(iv);
    }
  }
  // Boxes inside another box (copies included) add no points: drop them first, so that a union
  // of many repeated or nested boxes costs what its distinct boxes cost (40 copies of one box
  // were counted 40 times when the slab count below gave up).
  const auto inside = [&](const std::array<Interval, 3>& a, const std::array<Interval, 3>& b) {
    for (int ax = 0; ax < d.dim; ++ax) {
      if (a[ax].first < b[ax].first || a[ax].last > b[ax].last) {
        return false;
      }
    }
    return true;
  };
  boxes = outermost(boxes, inside);
  // Coordinate compression: the box interval ends cut every axis into at most 2k − 1 slabs; a
  // cell of slabs is either inside a box or not, so the union is the sum of the covered cells.
  // Cost (2k)^dim · k, kept below 2·10^7 operations; beyond it the sum over the boxes, which
  // can only count too many, never too few.
  const double cost =
      std::pow(2.0 * static_cast<double>(boxes.size()), d.dim) * static_cast<double>(boxes.size());
  if (cost > 2e7) {
    double sum = 0;
    for (const auto& iv : boxes) {
      double p = 1;
      for (int a = 0; a < d.dim; ++a) {
        p *= iv[a].count();
      }
      sum += p;
    }
    return sum;
  }
  // Half-open slab ends [first, last + 1) per axis.
  std::array<std::vector<double>, 3> cuts;
  for (int a = 0; a < 3; ++a) {
    if (a >= d.dim) {
      cuts[a] = {0.0, 1.0};
      continue;
    }
    for (const auto& iv : boxes) {
      cuts[a].push_back(iv[a].first);
      cuts[a].push_back(iv[a].last + 1);
    }
    std::sort(cuts[a].begin(), cuts[a].end());
    cuts[a].erase(std::unique(cuts[a].begin(), cuts[a].end()), cuts[a].end());
  }
  auto covered = [&](const std::array<double, 3>& start) {
    return std::any_of(boxes.begin(), boxes.end(), [&](const std::array<Interval, 3>& iv) {
      for (int a = 0; a < d.dim; ++a) {
        if (start[a] < iv[a].first || start[a] > iv[a].last) {
          return false;
        }
      }
      return true;
    });
  };
  double total = 0;
  for (std::size_t z = 0; z + 1 < cuts[2].size(); ++z) {
    for (std::size_t y = 0; y + 1 < cuts[1].size(); ++y) {
      for (std::size_t x = 0; x + 1 < cuts[0].size(); ++x) {
        if (covered({cuts[0][x], cuts[1][y], cuts[2][z]})) {
          total += (cuts[0][x + 1] - cuts[0][x]) * (d.dim > 1 ? cuts[1][y + 1] - cuts[1][y] : 1) *
                   (d.dim > 2 ? cuts[2][z + 1] - cuts[2][z] : 1);
        }
      }
    }
  }
  return total;
}

double bulk_family_size(const ModelDimension& d, const LatticeSpec& lattice, HorizonRule rule) {
  const double m = lattice.horizon_factor;
  const double ball = d.dim == 1   ? 2.0 * m
                      : d.dim == 2 ? std::numbers::pi * m * m
                                   : 4.0 / 3.0 * std::numbers::pi * m * m * m;
  if (!(m <= 40)) {
    // The lattice sum converges to the ball volume (in cells) as m grows; beyond m = 40 the
    // difference is below 1 % and the sum would cost 81³ evaluations.
    return ball;
  }
  double count = 0;
  for_each_offset_within(m, d.dim, rule, [&count](const std::array<long long, 3>&) { count += 1; });
  // Jitter moves particles in and out of the horizon; on average the family follows the ball.
  return lattice.position_jitter > 0 ? std::max(count, ball) : count;
}

/// The bodies' particles: those of particle files and graded sets counted, the lattice's
/// estimated in `lattice_region`, the union of the other bodies' boxes (shapes by their bounding
/// boxes, holes ignored: never fewer particles than there are).
namespace {

double body_particles(const ModelSpec& spec, Region& lattice_region) {
  double given = 0;
  for (const BodySpec& b : spec.bodies) {
    if (b.points) {
      given += static_cast<double>(b.points->count());
      continue;
    }
    const std::vector<Box> cover = b.region.cover(spec.dimension.dim);
    lattice_region.boxes.insert(lattice_region.boxes.end(), cover.begin(), cover.end());
  }
  return given + lattice_points_in_union(spec.dimension, spec.lattice, lattice_region);
}

/// The lattice bodies' region and the mesh bodies' bounding boxes: where ghost sites surround a
/// body (mesh bodies are counted by their particles, not in the lattice region).
Region with_mesh_boxes(const ModelSpec& spec, Region region) {
  for (const BodySpec& b : spec.bodies) {
    if (b.mesh) {
      region.boxes.insert(region.boxes.end(), b.region.boxes.begin(), b.region.boxes.end());
    }
  }
  return region;
}

/// Particles per lattice cell, averaged over the bodies' particles: a mesh body's elements are
/// smaller than the cells (Gmsh's tetrahedra of size λ: about six per cell), so each particle has
/// that many times the lattice's neighbours.
double particles_per_cell(const ModelSpec& spec, double bodies) {
  double mesh_particles = 0, mesh_cells = 0;
  for (const BodySpec& b : spec.bodies) {
    if (b.mesh) {
      const double volume = std::accumulate(b.points->volume.begin(), b.points->volume.end(), 0.0);
      mesh_particles += static_cast<double>(b.points->count());
      mesh_cells += volume / cell_volume(spec.dimension, spec.lattice.spacing);
    }
  }
  return bodies > 0 && mesh_cells > 0
             ? (bodies - mesh_particles + mesh_particles * (mesh_particles / mesh_cells)) / bodies
             : 1.0;
}

} // namespace

ResourceEstimate estimate_resources(const ModelSpec& spec, const SolverSpec& solver) {
  ResourceEstimate e;
  const ModelDimension& d = spec.dimension;
  Region all;
  const double bodies = body_particles(spec, all);
  // `gradient` weights are solved for here only where that is cheap (their orbit table grows as
  // m³: 8 s at m = 40); beyond, the estimate keeps every offset within δ, which can only count too
  // many. Solved once, for both the ghosts' reach and the family.
  std::optional<GradientWeights> weights;
  if (spec.corrections().volume_correction == VolumeCorrection::gradient &&
      spec.lattice.horizon_factor <= 40 && spec.lattice.position_jitter == 0) {
    weights = gradient_matched_weights(spec.corrections());
  }
  // Ghost sites (surface_correction ghost): the lattice sites within reach of a stiff bond.
  double ghosts = 0;
  if (spec.surface_correction == SurfaceCorrection::ghost) {
    const GhostSiteReach reach = weights ? ghost_site_reach(spec.corrections(), *weights)
                                         : GhostSiteReach{spec.lattice, spec.horizon_rule};
    ghosts = ghost_sites_around_union(d, reach.lattice, reach.rule, with_mesh_boxes(spec, all));
  }
  const double n = bodies + ghosts;
  e.particles = n;
  // `gradient` weights leave only the offsets they weight in the family (model.cpp drops bonds
  // without stiffness); a ghost bonds only towards the body, about half a family.
  double family = bulk_family_size(d, spec.lattice, spec.horizon_rule);
  if (weights) {
    double weighted = 0;
    for (const auto& o : weights->orbits) {
      weighted += o.weight > 0 ? static_cast<double>(o.count) : 0.0;
    }
    family = std::min(family, weighted);
  }
  e.bonds_per_particle = std::min(family * particles_per_cell(spec, bodies), std::max(n - 1, 0.0));
  e.bonds = 0.5 * (bodies + 0.5 * ghosts) * e.bonds_per_particle;
  const double directed = 2.0 * e.bonds;

  constexpr double dbl = sizeof(double);
  const ModelStorage storage = model_storage(spec, kernel_effects(spec, distinct_materials(spec)));
  // Constraints: at most one per supported component of each particle in a support box.
  double constrained = 0;
  for (const SupportSpec& s : spec.supports) {
    int components = 0;
    for (int c = 0; c < 3; ++c) {
      components += s.fixed[c] || s.prescribed[c] ? 1 : 0;
    }
    if (s.mirrors()) {
      components = 3; // a mirror support moves all three with the body
    }
    double members = 0;
    for (const Box& box : s.region.boxes) {
      for (const Box& body : all.boxes) {
        Box common;
        for (int a = 0; a < 3; ++a) {
          common.lo[a] = std::max(box.lo[a], body.lo[a]);
          common.hi[a] = std::min(box.hi[a], body.hi[a]);
        }
        members += lattice_points_in_box(d, spec.lattice, common);
      }
    }
    constrained += std::min(members, n) * components;
  }
  // Extrapolated particles: the ghosts and, under `quadratic` coupling, the mirror supports'
  // particles (counted with the constraints above), each with at most a family of terms.
  const double dependants =
      ghosts + (spec.mirror_coupling == MirrorCoupling::quadratic ? constrained / 3.0 : 0.0);
  e.model_bytes = storage.bytes(n, directed, constrained) +
                  dependants * (ModelStorage::per_dependant +
                                (e.bonds_per_particle + 1) * ModelStorage::per_extrapolation_term) +
                  ModelStorage::fixed;

  // Integrator vectors beyond the run state (3N doubles each, per-dof flags of one byte).
  const double dof = 3 * n;
  switch (solver.integrator) {
  case IntegratorKind::adr:
    e.integrator_bytes = dof * (3 * dbl + 1); // fictitious density, velocity, previous force
    break;
  case IntegratorKind::arkode: {
    // [u; v] buffer, two scratch vectors, constraint rates and flags, plus SUNDIALS' own
    // vectors of length 2·3N: one per stage and about five for the error test and bookkeeping.
    // The largest offered table has 7 stages; its count is not needed to this precision.
    const double stages = 7;
    e.integrator_bytes = dof * (2 * dbl + 2 * dbl + dbl + 1) + 2 * dof * dbl * (stages + 5);
    break;
  }
  default:
    e.integrator_bytes = dof; // constrained-dof flags
    break;
  }

  // Building: the cell list of the neighbour search (edge = horizon over the bounding box of the
  // bodies, one size_t per cell plus two per particle), and the correction factors.
  Vec3 lo{inf, inf, inf};
  Vec3 hi{-inf, -inf, -inf};
  for (const Box& b : all.boxes) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], b.lo[a]);
      hi[a] = std::max(hi[a], b.hi[a]);
    }
  }
  double cells = 1;
  const double delta = spec.lattice.horizon();
  for (int a = 0; a < d.dim && !all.boxes.empty(); ++a) {
    cells *= std::floor((hi[a] - lo[a]) / delta) + 1;
  }
  e.grid_bytes = (cells + 1) * static_cast<double>(sizeof(std::size_t)) +
                 n * static_cast<double>(2 * sizeof(std::size_t) + sizeof(std::uint32_t));
  // Corrections hold up to two per-bond vectors while they are computed (volume factors and the
  // combined factors, or a reverse-bond index).
  e.build_bytes = e.grid_bytes + (spec.corrections().corrects() ? 2 * directed * dbl : 0);
  e.bytes = e.model_bytes + e.integrator_bytes + e.build_bytes;
  if (std::isnan(e.bytes)) {
    e.bytes = inf;
  }
  return e;
}

} // namespace pd
