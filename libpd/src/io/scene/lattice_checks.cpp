// Checks of a scene against its lattice: first from the estimate of its size alone (memory,
// 32-bit indices, coordinates far from 0), then by counting lattice points in regions, and last,
// for mirror supports only, by generating the particles.
#include "libpd/discretisation/point_cloud.hpp"
#include "libpd/io/resources.hpp"
#include "sections.hpp"

#include <algorithm>
#include <iterator>

namespace pd::scene {

namespace {

/// Intersection of `region` with every body box. Lattice membership uses a tolerance of 1e-6 λ,
/// so boxes that miss each other by less than that may still share a lattice point: such slivers
/// are kept as degenerate boxes and the lattice count decides.
Region intersect_with_bodies(const Region& region, const std::vector<BodySpec>& bodies, int dim,
                             double spacing) {
  Region out;
  for (const Box& a : region.boxes) {
    for (const BodySpec& body : bodies) {
      for (const Box& b : body.region.cover(dim)) {
        Box c = a;
        bool empty = false;
        for (int k = 0; k < dim; ++k) {
          c.lo[k] = std::max(a.lo[k], b.lo[k]);
          c.hi[k] = std::min(a.hi[k], b.hi[k]);
          if (c.lo[k] > c.hi[k]) {
            if (c.lo[k] - c.hi[k] > 2e-6 * spacing) {
              empty = true;
            }
            c.lo[k] = c.hi[k] = 0.5 * (c.lo[k] + c.hi[k]);
          }
        }
        if (!empty) {
          out.boxes.push_back(c);
        }
      }
    }
  }
  return out;
}

double distance_to_box(const Vec3& p, const Box& b, int dim) {
  double sum = 0;
  for (int k = 0; k < dim; ++k) {
    const double d = std::max({b.lo[k] - p[k], 0.0, p[k] - b.hi[k]});
    sum += d * d;
  }
  return std::sqrt(sum);
}

/// Whether a region holds a lattice point. A union of boxes does if some box does, counted per
/// axis in floating point, so it needs no enumeration and cannot overflow, whatever the box;
/// shapes and holes are counted point by point (the memory guard has bounded the work).
bool holds_lattice_point(const ModelDimension& d, const LatticeSpec& lattice, const Region& r) {
  if (!r.only_boxes()) {
    return count_lattice_points(d, lattice, r) > 0;
  }
  return std::any_of(r.boxes.begin(), r.boxes.end(),
                     [&](const Box& b) { return lattice_points_in_box(d, lattice, b) > 0; });
}

std::string format_count(double n) {
  return n < 1e6 ? fmt::format("{:.0f}", n) : fmt::format("{:.2g}", n);
}

/// Refuse a scene whose model cannot fit in the memory available (or whose particles cannot be
/// indexed with 32 bits), from the estimate alone: nothing is enumerated or allocated, so a
/// request for 10^12 particles fails in microseconds instead of being killed by the OOM killer.
void check_resources(const Reader& r, const Scene& scene, const YAML::Node& spacing) {
  const ResourceEstimate e = estimate_resources(scene.model, scene.solver);
  const int dim = scene.model.dimension.dim;
  const std::string shrink =
      fmt::format("coarsen 'lattice.spacing' (memory grows as λ^-{}), shrink the bodies or lower "
                  "'horizon_factor' (bonds grow as m^{}); 'pd info' shows the estimate",
                  dim, dim);
  constexpr double max_particles = std::numeric_limits<std::uint32_t>::max();
  if (!(e.particles <= max_particles)) {
    r.fail(spacing,
           fmt::format("this scene has about {} particles; libpd indexes particles with 32 bits "
                       "(at most {:.3g})",
                       std::isfinite(e.particles) ? format_count(e.particles) : "infinitely many",
                       max_particles),
           shrink);
  }
  std::optional<MemoryBudget> budget;
  try {
    budget = available_memory();
  } catch (const std::invalid_argument& ex) {
    throw SceneError(r.file(), {}, ex.what(),
                     "unset PD_MEMORY_LIMIT or give it in bytes, e.g. PD_MEMORY_LIMIT=2G");
  }
  if (budget && !(e.bytes <= budget->bytes)) {
    const bool grid = e.grid_bytes > 0.5 * e.bytes;
    r.fail(spacing,
           fmt::format("this scene needs about {} ({} particles, {} bonds{}); {} {}",
                       format_bytes(e.bytes), format_count(e.particles), format_count(e.bonds),
                       grid ? ", most of it for the neighbour-search grid over the bounding box "
                              "of the bodies"
                            : "",
                       format_bytes(budget->bytes),
                       budget->source == "PD_MEMORY_LIMIT" ? "are allowed by PD_MEMORY_LIMIT"
                                                           : "are available"),
           grid ? "move the bodies closer together (the grid spans their bounding box with cells "
                  "of one horizon), or " +
                      shrink
                : shrink);
  }
}

/// Set-up visits every lattice offset within the horizon, and the moment-matched corrections
/// every offset within m + 1 spacings: (2m + 3)^d of them, whatever the size of the bodies. Past
/// this many the set-up alone takes minutes (and beyond ~10^18 the count itself overflows).
constexpr double max_setup_offsets = 1e8;

/// Refuse a horizon factor whose set-up work, not memory, is out of reach (m = 10^9 hung).
void check_setup_work(const Reader& r, const Scene& scene, const YAML::Node& where) {
  const double m = scene.model.lattice.horizon_factor;
  const int dim = scene.model.dimension.dim;
  const double offsets = std::pow(2.0 * m + 3.0, dim);
  if (!(offsets <= max_setup_offsets)) {
    const double largest = 0.5 * (std::pow(max_setup_offsets, 1.0 / dim) - 3.0);
    r.fail(where,
           fmt::format("horizon_factor {:.4g} means about {} lattice offsets to visit while "
                       "setting up the bonds and corrections; libpd visits at most {:.0e}",
                       m, format_count(offsets), max_setup_offsets),
           fmt::format("use horizon_factor ≤ {:.0f} in {}D (typically 3.015 or 2√3)",
                       std::floor(largest), dim));
  }
}

/// Lattice positions are origin + kλ in double precision: far from 0 (in spacings) they lose the
/// digits that bond lengths need, and lattice indices beyond 2^63 cannot even be formed. 10^9
/// spacings keep positions exact to 10^-7 λ.
constexpr double max_spacings_from_zero = 1e9;

void check_coordinate(const Reader& r, const YAML::Node& node, const std::string& what, double x,
                      double spacing) {
  if (!(std::abs(x) / spacing <= max_spacings_from_zero)) {
    r.fail(node,
           fmt::format("{} has a coordinate {} m, more than 10^9 spacings ({} m each) from 0: "
                       "lattice positions that far out lose the precision bond lengths need",
                       what, format_number(x), format_number(spacing)),
           "move the scene's coordinates closer to 0, or coarsen the spacing");
  }
}

void check_coordinates(const Reader& r, const ModelSpec& model, const Marks& marks) {
  const LatticeSpec& lattice = model.lattice;
  const Fields& lat = marks.lattice;
  const int dim = model.dimension.dim;
  const auto& body_box_nodes = marks.body_box_nodes;
  for (int a = 0; a < dim; ++a) {
    if (lat.has("origin")) {
      check_coordinate(r, lat.find("origin")->at(), "'lattice.origin'", lattice.origin[a],
                       lattice.spacing);
    }
  }
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    if (const PointCloud* cloud = model.bodies[i].points.get()) {
      // Each particle, not the bounding box the region is made of: the message names it.
      for (std::size_t k = 0; k < cloud->count(); ++k) {
        for (int a = 0; a < dim; ++a) {
          check_coordinate(r, body_box_nodes[i].front(),
                           fmt::format("particle {} of body '{}'", k + 1, model.bodies[i].name),
                           cloud->position[k][static_cast<std::size_t>(a)], lattice.spacing);
        }
      }
      continue;
    }
    const auto& boxes = model.bodies[i].region.boxes;
    for (std::size_t k = 0; k < boxes.size(); ++k) {
      for (int a = 0; a < dim; ++a) {
        for (double x : {boxes[k].lo[a], boxes[k].hi[a]}) {
          check_coordinate(r, body_box_nodes[i][k],
                           fmt::format("a box of body '{}'", model.bodies[i].name), x,
                           lattice.spacing);
        }
      }
    }
  }
}

/// The most a given particle's volume may be, in cells of its size: (2h)^dim, times the thickness
/// in 2D. A particle file's volumes tile its body, so each is about one cell; one a thousand
/// cells large is a wrong unit or a wrong column, and at 1e300 m³ the forces V_i V_j overflow.
constexpr double max_cells_per_particle = 1e3;

/// Particle files: every particle's volume against the cell its size h gives (the file's h, or
/// eq. 115 from its neighbours, as the model will derive it). Runs after check_coordinates, so
/// the neighbour search never sees a particle far out.
void check_particle_volumes(const Reader& r, const ModelSpec& model, const Marks& marks) {
  const ModelDimension& d = model.dimension;
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const PointCloud* cloud = model.bodies[i].points.get();
    if (cloud == nullptr) {
      continue;
    }
    const std::vector<double> size =
        cloud->size.empty()
            ? sizes_from_neighbours(cloud->position, d.dim, model.fibre_kernel.size_neighbours)
            : cloud->size;
    for (std::size_t k = 0; k < cloud->count(); ++k) {
      const double cell = cell_volume(d, 2 * size[k]);
      if (!(cell > 0) || cloud->volume[k] <= max_cells_per_particle * cell) {
        continue; // a lone particle has no neighbours to size it by
      }
      r.fail(marks.body_box_nodes[i].front(),
             fmt::format("particle {} of body '{}' has volume {} {}, {:.3g} times the cell of its "
                         "size h = {} m ((2h)^{}{} = {:.3g}); a particle may be at most {:g} "
                         "cells",
                         k + 1, model.bodies[i].name, format_number(cloud->volume[k]),
                         d.dim == 3 ? "m³" : "m³ (with the thickness)", cloud->volume[k] / cell,
                         format_number(size[k]), d.dim,
                         d.dim == 3   ? ""
                         : d.dim == 2 ? " × thickness"
                                      : " × cross-section",
                         cell, max_cells_per_particle),
             "check the file's volume column and its unit (m³; in 2D area × thickness)");
    }
  }
}

void check_regions(const Reader& r, const ModelSpec& model, const Marks& marks) {
  const LatticeSpec& lattice = model.lattice;
  const ModelDimension& d = model.dimension;
  const int dim = d.dim;
  for (const RegionUse& use : marks.must_have_particles) {
    if (!holds_lattice_point(d, lattice, use.region)) {
      r.fail(use.node, use.what + fmt::format(" (spacing {} m)", format_number(lattice.spacing)),
             "enlarge the box to at least one spacing in every direction, or refine the spacing");
    }
  }
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      const BodySpec& a = model.bodies[j];
      const BodySpec& b = model.bodies[i];
      // A shaped or holed body's boxes are not its region (a hole may hold the other body):
      // those pairs are checked on the generated particles (check_shaped_bodies).
      if (a.material == b.material || !a.region.only_boxes() || !b.region.only_boxes()) {
        continue;
      }
      for (std::size_t k = 0; k < b.region.boxes.size(); ++k) {
        const Region common =
            intersect_with_bodies(Region{{b.region.boxes[k]}}, {a}, dim, lattice.spacing);
        if (holds_lattice_point(d, lattice, common)) {
          r.fail(marks.body_box_nodes[i][k],
                 fmt::format("bodies '{}' and '{}' overlap but have different materials ('{}' and "
                             "'{}')",
                             a.name, b.name, model.materials[a.material].name,
                             model.materials[b.material].name),
                 fmt::format("shared particles would silently belong to '{}' (listed first); "
                             "separate the boxes or use one material",
                             a.name));
        }
      }
    }
  }
  // Bodies of given particles (particle files, graded sets) are checked against their own
  // particles: their spacing need not be the lattice's.
  std::vector<BodySpec> lattice_bodies;
  std::copy_if(model.bodies.begin(), model.bodies.end(), std::back_inserter(lattice_bodies),
               [](const BodySpec& b) { return !b.points; });
  const double tol = 1e-6 * lattice.spacing;
  const auto holds_given_particle = [&](const Region& region) {
    return std::any_of(model.bodies.begin(), model.bodies.end(), [&](const BodySpec& b) {
      return b.points && std::any_of(b.points->position.begin(), b.points->position.end(),
                                     [&](const Vec3& p) { return region.contains(p, dim, tol); });
    });
  };
  for (const RegionUse& use : marks.must_touch_bodies) {
    const Region common = intersect_with_bodies(use.region, lattice_bodies, dim, lattice.spacing);
    if (!holds_lattice_point(d, lattice, common) && !holds_given_particle(use.region)) {
      r.fail(use.node, use.what,
             "move or enlarge the box so that it contains particles of a body (particles sit at "
             "lattice points inside the body boxes)");
    }
  }
  for (std::size_t i = 0; i < marks.probe_points.size(); ++i) {
    const auto& [p, node] = marks.probe_points[i];
    double nearest = inf;
    for (const BodySpec& b : model.bodies) {
      for (const Box& box : b.region.cover(dim)) {
        nearest = std::min(nearest, distance_to_box(p, box, dim));
      }
    }
    if (nearest > lattice.spacing * (1 + 1e-9)) {
      r.fail(node,
             fmt::format("{} is {} m from the nearest body, farther than one spacing ({} "
                         "m)",
                         marks.probe_point_names[i], fmt::format("{:.3g}", nearest),
                         format_number(lattice.spacing)),
             "put the point inside a body or on its surface");
    }
  }
}

/// The checks of check_regions that shapes and holes make inexact, on the generated particles:
/// bodies of different materials sharing a particle, regions that must touch a body, and the
/// volume a shaped body's particles represent.
void check_shaped_bodies(const Reader& r, const ModelSpec& model, const Marks& marks,
                         const ParticleSet& particles) {
  const int dim = model.dimension.dim;
  const double tol = 1e-6 * model.lattice.spacing;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const std::size_t a = particles.body[i];
    for (std::size_t b = a + 1; b < model.bodies.size(); ++b) {
      const BodySpec& later = model.bodies[b];
      if (later.material != model.bodies[a].material &&
          later.region.contains(particles.position[i], dim, tol)) {
        r.fail(marks.body_nodes[b],
               fmt::format("bodies '{}' and '{}' overlap but have different materials (at {})",
                           model.bodies[a].name, later.name,
                           fmt::format("[{:.6g}, {:.6g}, {:.6g}]", particles.position[i][0],
                                       particles.position[i][1], particles.position[i][2])),
               fmt::format("shared particles would silently belong to '{}' (listed first); "
                           "take the other body out with 'minus' or use one material",
                           model.bodies[a].name));
      }
    }
  }
  for (const RegionUse& use : marks.must_touch_bodies) {
    const bool touches =
        std::any_of(particles.position.begin(), particles.position.end(),
                    [&](const Vec3& p) { return use.region.contains(p, dim, tol); });
    if (!touches) {
      r.fail(use.node, use.what,
             "move or enlarge the box so that it contains particles of a body (particles sit at "
             "lattice points inside the bodies)");
    }
  }
}

/// Planes and cracks that the format puts on cell faces, checked on the particles: a crack
/// through particle centres cuts every bond of those particles that crosses it, so they hang on
/// the bonds along the crack alone (a static solve finds the stiffness singular, relaxation
/// leaves them loose): an error for lattice particles, a warning for given ones (a particle
/// file or graded set need not have rows). A symmetry plane through particle centres is warned
/// about: the format puts it on a cell face.
void check_cracks_and_planes(Reader& r, const ModelSpec& model, const Marks& marks,
                             const ParticleSet& particles) {
  const int dim = model.dimension.dim;
  const double spacing = model.lattice.spacing;
  const double tol = 1e-6 * spacing;
  const auto given = [&](std::size_t i) {
    return static_cast<bool>(model.bodies.at(particles.body[i]).points);
  };
  const auto where = [](const Vec3& p) {
    return fmt::format("[{:.6g}, {:.6g}, {:.6g}]", p[0], p[1], p[2]);
  };
  for (std::size_t c = 0; c < model.cracks.size(); ++c) {
    const Crack& crack = model.cracks[c];
    const auto& v = crack.vertices;
    Vec3 normal{0, 0, 0};
    if (dim == 2) {
      normal = {v[0][1] - v[1][1], v[1][0] - v[0][0], 0};
    } else {
      const Vec3 u{v[1][0] - v[0][0], v[1][1] - v[0][1], v[1][2] - v[0][2]};
      const Vec3 w{v[2][0] - v[0][0], v[2][1] - v[0][1], v[2][2] - v[0][2]};
      normal = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    }
    const double length = norm(normal);
    if (!(length > 0)) {
      continue; // refused by read_cracks
    }
    std::size_t on_lattice = 0, on_given = 0;
    Vec3 first{}, last{};
    for (std::size_t i = 0; i < particles.size(); ++i) {
      const Vec3& p = particles.position[i];
      Vec3 a = p, b = p;
      for (std::size_t k = 0; k < 3; ++k) {
        a[k] -= tol * normal[k] / length;
        b[k] += tol * normal[k] / length;
      }
      if (crack.cuts(a, b, dim)) {
        (given(i) ? on_given : on_lattice) += 1;
        first = on_lattice + on_given == 1 ? p : first;
        last = p;
      }
    }
    const std::string what = fmt::format(
        "crack '{}' runs through the centres of {} particles (from {} to {}): it cuts every "
        "bond of theirs that crosses it, so they hang on the bonds along the crack alone "
        "(isolated from the body: a static solve finds the stiffness singular)",
        crack.name, on_lattice + on_given, where(first), where(last));
    const std::string hint = fmt::format(
        "put the crack on the cell faces between particle rows: shift it by half a spacing "
        "({} m) across",
        format_number(0.5 * spacing));
    if (on_lattice > 0) {
      r.fail(marks.crack_nodes.at(c), what, hint);
    } else if (on_given > 0) {
      r.warn(marks.crack_nodes.at(c), what + "; " + hint);
    }
  }
  for (std::size_t s = 0; s < model.supports.size(); ++s) {
    const SupportSpec& sup = model.supports[s];
    for (std::size_t a = 0; a < static_cast<std::size_t>(dim); ++a) {
      if (!sup.symmetry[a]) {
        continue;
      }
      const auto count =
          std::count_if(particles.position.begin(), particles.position.end(),
                        [&](const Vec3& p) { return std::abs(p[a] - sup.symmetry_at[a]) <= tol; });
      if (count > 0) {
        r.warn(marks.support_nodes.at(s),
               fmt::format("the symmetry plane {} = {} of support '{}' runs through the centres "
                           "of {} particles, not along a cell face as a symmetry plane must (a "
                           "half model's body ends on the plane, half a spacing beyond its last "
                           "particles); move the plane by half a spacing ({} m)",
                           "xyz"[a], format_number(sup.symmetry_at[a]), sup.name, count,
                           format_number(0.5 * spacing)));
      }
    }
  }
}

/// Volume of a shaped body's region, by sampling each covering box on a grid 4 times finer than
/// the lattice (nullopt if that would take more than 2·10^7 samples).
std::optional<double> sampled_volume(const ModelSpec& model, const Region& region) {
  const int dim = model.dimension.dim;
  const double step = 0.25 * model.lattice.spacing;
  double samples = 0;
  const std::vector<Box> cover = region.cover(dim);
  for (const Box& b : cover) {
    double n = 1;
    for (int a = 0; a < dim; ++a) {
      n *= std::ceil((b.hi[a] - b.lo[a]) / step);
    }
    samples += n;
  }
  if (samples > 2e7 || cover.size() != 1) {
    return std::nullopt; // several covering boxes would count their overlaps twice
  }
  const Box& b = cover.front();
  std::array<long long, 3> n{1, 1, 1};
  for (int a = 0; a < dim; ++a) {
    n[a] = static_cast<long long>(std::ceil((b.hi[a] - b.lo[a]) / step));
  }
  long long inside = 0;
  for (long long k = 0; k < n[2]; ++k) {
    for (long long j = 0; j < n[1]; ++j) {
      for (long long i = 0; i < n[0]; ++i) {
        const std::array<long long, 3> idx{i, j, k};
        Vec3 p = b.lo;
        for (int a = 0; a < dim; ++a) {
          const double h = (b.hi[a] - b.lo[a]) / static_cast<double>(n[a]);
          p[a] = b.lo[a] + (static_cast<double>(idx[a]) + 0.5) * h;
        }
        inside += region.contains(p, dim, 0.0) ? 1 : 0;
      }
    }
  }
  double cell = cell_volume(model.dimension, 1.0);
  for (int a = 0; a < dim; ++a) {
    cell *= (b.hi[a] - b.lo[a]) / static_cast<double>(n[a]);
  }
  return static_cast<double>(inside) * cell;
}

/// Whether a box lies in the mirror supports' regions (its corners and centre do): a clamp's own
/// box behind a mirror plane, not part of the continuum body.
bool behind_mirror_planes(const ModelSpec& model, const Box& b) {
  const int dim = model.dimension.dim;
  Region clamps;
  for (const SupportSpec& sup : model.supports) {
    if (sup.mirrors()) {
      clamps.boxes.insert(clamps.boxes.end(), sup.region.boxes.begin(), sup.region.boxes.end());
    }
  }
  Vec3 centre{};
  for (std::size_t a = 0; a < 3; ++a) {
    centre[a] = 0.5 * (b.lo[a] + b.hi[a]);
  }
  bool inside = clamps.contains(centre, dim, 1e-9);
  for (int corner = 0; inside && corner < (1 << dim); ++corner) {
    Vec3 p = b.lo;
    for (int a = 0; a < dim; ++a) {
      p[static_cast<std::size_t>(a)] = ((corner >> a) & 1) != 0 ? b.hi[static_cast<std::size_t>(a)]
                                                                : b.lo[static_cast<std::size_t>(a)];
    }
    inside = clamps.contains(p, dim, 1e-9);
  }
  return inside;
}

/// A body the lattice cannot fill exactly says what it represents: a box whose faces are not on
/// the cell faces of the (cell-centred) lattice, or a shaped body, whose particles' volume
/// differs from the shape's.
void warn_represented_volume(Reader& r, const ModelSpec& model, const Marks& marks,
                             const ParticleSet* particles) {
  const LatticeSpec& lattice = model.lattice;
  const ModelDimension& d = model.dimension;
  const double cell = cell_volume(d, lattice.spacing);
  const double unit = cell_volume(d, 1.0); // thickness (2D) or cross-section (1D)
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const BodySpec& body = model.bodies[i];
    if (body.points) {
      continue; // its particles carry their own volumes
    }
    if (body.region.only_boxes()) {
      if (lattice.convention != LatticeConvention::cell_centered) {
        continue; // node-based particles never tile their box
      }
      for (std::size_t k = 0; k < body.region.boxes.size(); ++k) {
        const Box& b = body.region.boxes[k];
        double volume = unit;
        bool aligned = true;
        for (int a = 0; a < d.dim; ++a) {
          volume *= b.hi[a] - b.lo[a];
          for (double x : {b.lo[a], b.hi[a]}) {
            const double cells = (x - lattice.origin[a]) / lattice.spacing;
            aligned = aligned && std::abs(cells - std::round(cells)) < 1e-6;
          }
        }
        if (aligned || behind_mirror_planes(model, b)) {
          continue;
        }
        const double represented = lattice_points_in_box(d, lattice, b) * cell;
        r.warn(marks.body_box_nodes[i].at(k),
               fmt::format("a box of body '{}' has faces between the lattice's cell faces "
                           "(spacing {} m): its particles represent {:.6g} of its {:.6g} {} "
                           "({:+.2f} %)",
                           body.name, format_number(lattice.spacing), represented, volume,
                           d.dim == 3 ? "m³" : "m³ (with the thickness)",
                           100 * (represented / volume - 1)));
      }
      continue;
    }
    if (particles == nullptr) {
      continue;
    }
    double count = 0;
    double represented = 0; // curved surfaces cut cells (lattice.hpp): the particles' volumes
    for (std::size_t k = 0; k < particles->size(); ++k) {
      if (particles->body[k] == i) {
        count += 1;
        represented += particles->volume[k];
      }
    }
    const auto volume = sampled_volume(model, body.region);
    // The sampled volume is itself good to a few 0.1 % of a curved shape's: only a larger
    // difference is the lattice's (a notch or a box between cell faces, a feature smaller than a
    // quarter of a cell).
    const double limit = has_curved_surface(body.region) ? 5e-3 : 1e-6;
    if (volume && std::abs(represented / *volume - 1) > limit) {
      r.warn(marks.body_nodes[i],
             fmt::format("body '{}' is shaped: its {:.0f} particles represent {:.6g} of its "
                         "{:.6g} {} ({:+.2f} %; box faces and notches between the lattice's "
                         "cell faces keep whole cells)",
                         body.name, count, represented, *volume,
                         d.dim == 3 ? "m³" : "m³ (with the thickness)",
                         100 * (represented / *volume - 1)));
    }
  }
}

} // namespace

std::optional<ParticleSet> check_against_lattice(Reader& r, const Scene& scene,
                                                 const Marks& marks) {
  const ModelSpec& model = scene.model;
  // Resources first: before anything is enumerated or allocated.
  const auto* horizon = marks.lattice.find("horizon_factor");
  check_setup_work(r, scene, (horizon ? horizon : marks.lattice.find("spacing"))->at());
  check_resources(r, scene, marks.lattice.find("spacing")->at());
  check_coordinates(r, model, marks);
  check_particle_volumes(r, model, marks);
  check_regions(r, model, marks);
  // Mirror supports need each image to be a free particle, and regions checked against shaped
  // bodies were only checked against the shapes' bounding boxes so far: only the lattice can
  // tell (the memory guard has passed, so generating the particles is affordable). Model
  // building reuses them.
  const bool shaped = std::any_of(model.bodies.begin(), model.bodies.end(),
                                  [](const BodySpec& b) { return !b.region.only_boxes(); });
  const bool planes =
      std::any_of(model.supports.begin(), model.supports.end(), [](const SupportSpec& s) {
        return s.symmetry[0] || s.symmetry[1] || s.symmetry[2];
      });
  if (!shaped && model.cracks.empty() && !planes &&
      std::none_of(model.supports.begin(), model.supports.end(),
                   [](const SupportSpec& s) { return s.mirrors(); })) {
    warn_represented_volume(r, model, marks, nullptr);
    return std::nullopt;
  }
  ParticleSet particles = generate_lattice(model.dimension, model.lattice, model.bodies);
  if (shaped) {
    check_shaped_bodies(r, model, marks, particles);
  }
  warn_represented_volume(r, model, marks, &particles);
  check_cracks_and_planes(r, model, marks, particles);
  try {
    support_constraints(model, particles);
  } catch (const SupportError& e) {
    r.fail(marks.support_nodes.at(e.support), e.what(),
           "a mirror support needs a regular lattice (no position_jitter), a plane on a cell "
           "face, and free body particles beyond the plane at least as far as the support "
           "reaches");
  }
  return particles;
}

} // namespace pd::scene
