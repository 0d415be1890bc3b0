// The elliptical disk's scene (verification/runner/elliptic_disk.hpp): the particles the paper's
// grid gives, the boundary zone held at eq. 116 and nothing else, the crack cutting arms, and
// the refusal of a held zone thinner than a horizon. A small grid keeps each build well under a
// second.
#include "elliptic_disk.hpp"
#include "libpd/discretisation/model.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <gtest/gtest.h>
#include <stdexcept>
#include <vector>

namespace pd::verification {
namespace {

EllipticDiskSpec small_disk() {
  EllipticDiskSpec s;
  s.table.zones_xi = 12; // 6 zones along ξ, 16 around
  s.table.zones_eta = 8;
  s.pattern = 4;
  return s;
}

TEST(EllipticDisk, ParticlesFillThePapersZones) {
  const EllipticDiskSpec s = small_disk();
  const Scene scene = elliptic_disk_scene(s);
  const PointCloud& cloud = *scene.model.bodies.front().points;
  EXPECT_EQ(cloud.count(), 6U * 16U * 16U);
  // Every particle inside the ellipse ξ ≤ ξ_max, and the volumes tile its area π a b.
  double area = 0;
  for (std::size_t i = 0; i < cloud.count(); ++i) {
    EXPECT_LE(elliptic_coordinates(cloud.position[i][0], cloud.position[i][1],
                                   s.table.focal_half_distance)
                  .first,
              s.xi_max + 1e-12);
    area += cloud.volume[i];
  }
  const double c = s.table.focal_half_distance;
  EXPECT_NEAR(area / (std::numbers::pi * c * c * std::cosh(s.xi_max) * std::sinh(s.xi_max)), 1.0,
              0.01);
}

TEST(EllipticDisk, BoundaryZoneIsHeldAtEquation116AndNothingElse) {
  const EllipticDiskSpec s = small_disk();
  const Scene scene = elliptic_disk_scene(s);
  const Model m = build_model(scene);
  std::size_t held = 0;
  for (std::size_t i = 0; i < m.body_particle_count(); ++i) {
    held += s.held(m.particles.position[i]) ? 1 : 0;
  }
  ASSERT_GT(held, 0U);
  // x and y of each held particle, at eq. 116 there; no other particle constrained.
  EXPECT_EQ(m.constraints.size(), 2 * held);
  for (const Constraint& k : m.constraints) {
    const Vec3& x = m.particles.position[k.particle];
    EXPECT_TRUE(s.held(x));
    EXPECT_DOUBLE_EQ(k.value, s.exact_displacement(x)[k.component]);
  }
  // The crack between the focal points cuts arms, and the model is the fibre model in plane
  // strain with Table 1's ν.
  ASSERT_EQ(m.bonds_cut_by_crack.size(), 1U);
  EXPECT_GT(m.bonds_cut_by_crack.front(), 0U);
  EXPECT_EQ(m.effects.bond_model, BondModel::virtual_fibres);
  EXPECT_EQ(m.spec.dimension.plane, PlaneMode::plane_strain);
  EXPECT_DOUBLE_EQ(m.spec.materials.front().poisson_ratio, s.table.poisson_ratio);
}

TEST(EllipticDisk, RefusesAHeldZoneThinnerThanAHorizon) {
  EllipticDiskSpec s = small_disk();
  s.boundary_rings = 0.25;
  EXPECT_THROW(elliptic_disk_scene(s), std::invalid_argument);
}

TEST(EllipticDisk, UniformSetHasOneSpacing) {
  EllipticDiskSpec s = small_disk();
  s.particles = DiskParticles::uniform;
  s.uniform_spacing = s.table.focal_half_distance / 6;
  const Scene scene = elliptic_disk_scene(s);
  const PointCloud& cloud = *scene.model.bodies.front().points;
  const double c = s.table.focal_half_distance;
  const double a = c * std::cosh(s.xi_max), b = c * std::sinh(s.xi_max);
  for (std::size_t i = 0; i < cloud.count(); ++i) {
    const Vec3& p = cloud.position[i];
    EXPECT_LE((p[0] / a) * (p[0] / a) + (p[1] / b) * (p[1] / b), 1.0);
  }
  // The Monte Carlo moves give each particle its Voronoi cell (graded_set.hpp), which varies
  // from particle to particle; the typical one is a cell of the one spacing.
  std::vector<double> volume = cloud.volume;
  std::nth_element(volume.begin(), volume.begin() + static_cast<std::ptrdiff_t>(volume.size() / 2),
                   volume.end());
  const double thickness = scene.model.dimension.thickness;
  EXPECT_NEAR(volume[volume.size() / 2] / thickness / (s.uniform_spacing * s.uniform_spacing), 1.0,
              0.05);
  // About π a b / h² particles (the columns are rounded to whole rows).
  EXPECT_NEAR(static_cast<double>(cloud.count()) * s.uniform_spacing * s.uniform_spacing /
                  (std::numbers::pi * a * b),
              1.0, 0.1);
}

TEST(EllipticDisk, UniformRowsStayOffTheCrack) {
  // A row on y = 0 would put particles on the crack, with no arm across it but along it.
  EllipticDiskSpec s = small_disk();
  s.particles = DiskParticles::uniform;
  s.sweeps = 0;
  for (const double per_c : {6.0, 8.0, 12.0}) {
    s.uniform_spacing = s.table.focal_half_distance / per_c;
    const Scene scene = elliptic_disk_scene(s);
    for (const Vec3& p : scene.model.bodies.front().points->position) {
      ASSERT_GT(std::abs(p[1]), 0.4 * s.uniform_spacing) << "c/" << per_c;
    }
  }
}

TEST(EllipticDisk, ALargeDiskIsNotRefusedByTheMemoryEstimate) {
  // A short crack in a large disk: a = 24.7 c. The scene reader estimates the memory of a
  // lattice at the scene's spacing over the disk's box; at c/100 that is 2.2 × 10⁷ particles
  // (50 GiB, refused), at a/400 6.4 × 10⁵.
  EllipticDiskSpec s = small_disk();
  s.xi_max = 3.9;
  s.boundary_rings = 1;
  const Scene scene = elliptic_disk_scene(s);
  EXPECT_EQ(scene.model.bodies.front().points->count(), 6U * 16U * 16U);
}

EllipticDiskSpec banded_disk() {
  EllipticDiskSpec s = small_disk();
  const double c = s.table.focal_half_distance;
  s.path_band = {c / 10, 1.5 * c, 0.3 * c};
  return s;
}

TEST(EllipticDisk, PathBandIsOneLatticeAlongTheCrack) {
  const EllipticDiskSpec s = banded_disk();
  const PathBand& band = s.path_band;
  const Scene scene = elliptic_disk_scene(s); // owns the cloud
  const PointCloud& cloud = *scene.model.bodies.front().points;
  std::size_t inside = 0;
  double smallest = 1e300, largest = 0;
  for (std::size_t i = 0; i < cloud.count(); ++i) {
    const Vec3& p = cloud.position[i];
    if (std::abs(p[0]) > band.half_length || std::abs(p[1]) > band.half_width) {
      continue;
    }
    ++inside;
    // On the lattice: cell centres, no row on the crack's line.
    const double column = (p[0] + band.half_length) / band.spacing - 0.5;
    const double row = (p[1] + band.half_width) / band.spacing - 0.5;
    EXPECT_NEAR(column, std::round(column), 1e-9);
    EXPECT_NEAR(row, std::round(row), 1e-9);
    EXPECT_GT(std::abs(p[1]), 0.4 * band.spacing);
    EXPECT_NEAR(cloud.volume[i], band.spacing * band.spacing, 1e-12 * band.spacing);
    // Away from the band's edge every particle has the same neighbours, so the same size.
    if (std::abs(p[0]) < band.half_length - 2 * band.spacing &&
        std::abs(p[1]) < band.half_width - 2 * band.spacing) {
      smallest = std::min(smallest, cloud.size[i]);
      largest = std::max(largest, cloud.size[i]);
    }
  }
  EXPECT_EQ(inside, 30U * 6U);
  EXPECT_NEAR(largest / smallest, 1.0, 1e-9);
}

TEST(EllipticDisk, PathBandTilesTheDisk) {
  // The graded particles outside the band keep their zones' volumes; the volumes still add up
  // to the ellipse's area π a b within what the cells cut by the band's edge cost.
  const EllipticDiskSpec s = banded_disk();
  const Scene scene = elliptic_disk_scene(s); // owns the cloud
  const PointCloud& cloud = *scene.model.bodies.front().points;
  double area = 0;
  for (const double v : cloud.volume) {
    area += v;
  }
  const double c = s.table.focal_half_distance;
  EXPECT_NEAR(area / (std::numbers::pi * c * c * std::cosh(s.xi_max) * std::sinh(s.xi_max)), 1.0,
              0.01);
}

TEST(EllipticDisk, RefusesAPathBandInTheHeldZone) {
  EllipticDiskSpec s = banded_disk();
  s.path_band.half_length = s.table.focal_half_distance * std::cosh(s.xi_max);
  EXPECT_THROW(elliptic_disk_scene(s), std::invalid_argument);
  s = banded_disk();
  s.particles = DiskParticles::uniform;
  s.uniform_spacing = s.table.focal_half_distance / 6;
  EXPECT_THROW(elliptic_disk_scene(s), std::invalid_argument);
}

} // namespace
} // namespace pd::verification
