#include "elliptic_disk.hpp"

#include "libpd/discretisation/point_cloud.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace pd::verification {

namespace {

/// Semi-axes (a, b) = c (cosh ξ_max, sinh ξ_max) of the disk's outline.
std::pair<double, double> semi_axes(const EllipticDiskSpec& s) {
  const double c = s.table.focal_half_distance;
  return {c * std::cosh(s.xi_max), c * std::sinh(s.xi_max)};
}

/// The body as the scene reader generates it: the paper's graded ellipse, or for `uniform` a
/// graded box of one zone width (grading 1) over the ellipse's bounding box, cut to the ellipse
/// below. Both get the generator's Monte Carlo noise (Fig. 8): its step and spacing defaults, the
/// spec's sweeps.
std::string body_text(const EllipticDiskSpec& s) {
  if (s.particles == DiskParticles::graded) {
    return fmt::format(
        "    graded: {{shape: ellipse, focal_half_distance: {:.17g}, xi_max: {:.17g}, "
        "zones: [{}, {}], pattern: {}, seed: {}, sweeps: {}}}\n",
        s.table.focal_half_distance, s.xi_max, s.zones_xi(), s.zones_eta(), s.pattern, s.seed,
        s.sweeps);
  }
  if (!(s.uniform_spacing > 0)) {
    throw std::invalid_argument("elliptic disk: a uniform particle set needs uniform_spacing > 0");
  }
  const auto [a, b] = semi_axes(s);
  const long columns = std::max(1L, std::lround(2 * a / s.uniform_spacing));
  // The box's rows are as far apart as its columns; an even number of them keeps every row off
  // the crack (y = 0), where a particle would lose every arm but those along the crack.
  const double pitch = 2 * a / static_cast<double>(columns);
  const double half_height = pitch * std::ceil(b / pitch);
  return fmt::format("    graded: {{shape: box, box: [[{:.17g}, {:.17g}], [{:.17g}, {:.17g}]], "
                     "zones: [{}, 1], pattern: 1, seed: {}, sweeps: {}}}\n",
                     -a, -half_height, a, half_height, columns, s.seed, s.sweeps);
}

std::string scene_text(const EllipticDiskSpec& s) {
  const EllipticDiskTable1& t = s.table;
  std::string effects;
  std::string limits;
  if (s.plasticity) {
    effects = s.elongation_limit ? "effects: [plasticity, damage]\n" : "effects: [plasticity]\n";
    limits += fmt::format("    yield_stretch: {:.17g}\n", t.yield_strain);
  }
  if (s.elongation_limit) {
    limits += fmt::format("    elongation_limit: {:.17g}\n", t.elongation_limit());
  }
  const double c = t.focal_half_distance;
  // The lattice spacing only scales the tolerance of region tests (10⁻⁶ λ): c/100 keeps it far
  // below the closest particles of the finest set. The scene reader also estimates the memory
  // of a lattice at that spacing over the disk's box, so a disk whose semi-major axis a is over
  // 4c (a short crack in a large disk) takes a/400, still far below its closest particles.
  return fmt::format(
      "title: \"Elliptical disk with a crack between the focal points (Olsson et al. 2021)\"\n"
      "dimension: 2\n"
      "plane: strain\n"
      "thickness: 1\n"
      "lattice:\n  spacing: {:.17g}\n"
      "materials:\n  steel:\n    youngs_modulus: {:.17g}\n    poisson_ratio: {:.17g}\n"
      "    density: {:.17g}\n{}"
      "bodies:\n  - name: disk\n    material: steel\n{}"
      "cracks:\n  - name: focal\n    segment: [[{:.17g}, 0], [{:.17g}, 0]]\n"
      "{}"
      "model:\n  bond_model: virtual-fibres\n  fibre_kernel_exponent: 2\n"
      "  fibre_kernel_alpha: {:.17g}\n  fibre_size_neighbours: {}\n"
      "solver:\n  integrator: adr\n  dt: 1\n  end_time: 2000000\n"
      "  steady: {{kinetic_tolerance: 1e-12, force_tolerance: 1e-7, check_every: 100}}\n",
      std::max(c / 100, semi_axes(s).first / 400), t.youngs_modulus, t.poisson_ratio, t.density,
      limits, body_text(s), -c, c, effects, t.kernel_alpha, t.size_neighbours);
}

/// The uniform set: the box's particles inside the ellipse, their sizes again by eq. 115 among
/// the particles kept.
void cut_to_ellipse(const EllipticDiskSpec& s, BodySpec& body) {
  const auto [a, b] = semi_axes(s);
  auto cloud = std::make_shared<PointCloud>();
  for (std::size_t i = 0; i < body.points->count(); ++i) {
    const Vec3& p = body.points->position[i];
    if ((p[0] / a) * (p[0] / a) + (p[1] / b) * (p[1] / b) <= 1.0) {
      cloud->position.push_back(p);
      cloud->volume.push_back(body.points->volume[i]);
    }
  }
  cloud->size = sizes_from_neighbours(cloud->position, 2, s.table.size_neighbours);
  body.points = std::move(cloud);
}

/// The path band: the particles inside it replaced by a lattice of `spacing` (columns and rows
/// rounded to fill the band exactly; an even number of rows, so that none lies on the crack's
/// line y = 0), each with its cell's area as volume, and every size again by eq. 115. Outside the
/// band the graded particles keep the volumes the generator gave them (their Voronoi cells among
/// all the graded particles, graded_set.hpp), so the cells cut by the band's edge are counted
/// once on either side (EllipticDisk.PathBandTilesTheDisk measures what that costs).
void fill_path_band(const EllipticDiskSpec& s, double thickness, BodySpec& body) {
  const PathBand& band = s.path_band;
  if (!(band.spacing > 0 && band.half_length > 0 && band.half_width > 0)) {
    throw std::invalid_argument("elliptic disk: a path band needs a spacing, a half length and a "
                                "half width > 0");
  }
  if (s.particles != DiskParticles::graded) {
    throw std::invalid_argument("elliptic disk: a path band refines the graded set only");
  }
  const auto in_band = [&](const Vec3& p) {
    return std::abs(p[0]) <= band.half_length && std::abs(p[1]) <= band.half_width;
  };
  auto cloud = std::make_shared<PointCloud>();
  for (std::size_t i = 0; i < body.points->count(); ++i) {
    if (!in_band(body.points->position[i])) {
      cloud->position.push_back(body.points->position[i]);
      cloud->volume.push_back(body.points->volume[i]);
    }
  }
  const long columns = std::max(1L, std::lround(2 * band.half_length / band.spacing));
  const long rows = 2 * std::max(1L, std::lround(band.half_width / band.spacing));
  const double dx = 2 * band.half_length / static_cast<double>(columns);
  const double dy = 2 * band.half_width / static_cast<double>(rows);
  for (long i = 0; i < columns; ++i) {
    for (long j = 0; j < rows; ++j) {
      const Vec3 p{-band.half_length + (static_cast<double>(i) + 0.5) * dx,
                   -band.half_width + (static_cast<double>(j) + 0.5) * dy, 0.0};
      if (s.held(p)) {
        throw std::invalid_argument("elliptic disk: the path band reaches into the held zone");
      }
      cloud->position.push_back(p);
      cloud->volume.push_back(dx * dy * thickness);
    }
  }
  cloud->size = sizes_from_neighbours(cloud->position, 2, s.table.size_neighbours);
  body.points = std::move(cloud);
}

/// Every free particle's horizon α h inside the disk (32 points of its circle tested), so that
/// the held zone completes each free particle's neighbourhood.
void check_boundary_zone(const EllipticDiskSpec& s, const PointCloud& cloud) {
  const auto [a, b] = semi_axes(s);
  std::size_t reaching = 0;
  for (std::size_t i = 0; i < cloud.count(); ++i) {
    const Vec3& p = cloud.position[i];
    if (s.held(p)) {
      continue;
    }
    const double r = s.table.kernel_alpha * cloud.size[i];
    for (int k = 0; k < 32; ++k) {
      const double phi = 2.0 * std::numbers::pi * k / 32;
      const double x = p[0] + r * std::cos(phi), y = p[1] + r * std::sin(phi);
      if ((x / a) * (x / a) + (y / b) * (y / b) > 1.0) {
        ++reaching;
        break;
      }
    }
  }
  if (reaching > 0) {
    throw std::invalid_argument(
        fmt::format("elliptic disk: {} free particles have a horizon reaching outside the disk; "
                    "the held zone ({} rings of zones) is thinner than a horizon at this density",
                    reaching, s.boundary_rings));
  }
}

} // namespace

Vec3 EllipticDiskSpec::exact_displacement(const Vec3& x) const {
  return elliptic_crack_displacement(x[0], x[1], table.focal_half_distance, remote_stress,
                                     table.shear_modulus(), table.poisson_ratio);
}

bool EllipticDiskSpec::held(const Vec3& x) const {
  return elliptic_coordinates(x[0], x[1], table.focal_half_distance).first >= held_from_xi();
}

Scene elliptic_disk_scene(const EllipticDiskSpec& spec) {
  if (spec.elongation_limit && !spec.plasticity) {
    throw std::invalid_argument("elliptic disk: the elongation limit (eq. 118) needs plasticity");
  }
  Scene scene = parse_scene(scene_text(spec), "elliptic-disk.yaml");
  BodySpec& body = scene.model.bodies.front();
  if (spec.particles == DiskParticles::uniform) {
    cut_to_ellipse(spec, body);
  }
  if (spec.path_band.spacing != 0) {
    fill_path_band(spec, scene.model.dimension.thickness, body);
  }
  check_boundary_zone(spec, *body.points);
  // The held zone as a support: one point box per particle in it (a region holds boxes and
  // round shapes, not an elliptical ring), each held in x and y at eq. 116.
  SupportSpec boundary;
  boundary.name = "boundary";
  for (const Vec3& p : body.points->position) {
    if (spec.held(p)) {
      boundary.region.boxes.push_back(Box{p, p});
    }
  }
  boundary.prescribed = {true, true, false};
  boundary.displacement_field = [spec](const Vec3& x) { return spec.exact_displacement(x); };
  scene.model.supports.push_back(std::move(boundary));
  return scene;
}

} // namespace pd::verification
