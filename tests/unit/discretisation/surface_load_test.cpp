// Pressure loads on a shape's surface (surface_load.hpp): the resultant is pressure × area along
// the body's inward normal, whatever the lattice's staircase, and only where the surface bounds
// a body.
#include "libpd/discretisation/surface_load.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>

namespace {

pd::Shape cylinder(double r) {
  pd::Shape s;
  s.kind = pd::Shape::Kind::cylinder;
  s.radius = r;
  return s;
}

pd::Shape half_space(pd::Vec3 normal) {
  pd::Shape s;
  s.kind = pd::Shape::Kind::half_space;
  s.normal = normal;
  return s;
}

// The quarter ring a ≤ r ≤ b, x, y ≥ 0 in plane stress, on the cell-centred lattice.
struct QuarterRing {
  pd::ModelDimension dimension{2, pd::PlaneMode::plane_stress, 0.01};
  std::vector<pd::BodySpec> bodies;
  pd::ParticleSet particles;

  QuarterRing(double a, double b, double spacing) {
    pd::BodySpec body;
    body.region.shapes.push_back(cylinder(b));
    body.region.minus = {cylinder(a), half_space({-1, 0, 0}), half_space({0, -1, 0})};
    bodies.push_back(body);
    const auto n = static_cast<int>(std::lround(b / spacing));
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const pd::Vec3 x{(i + 0.5) * spacing, (j + 0.5) * spacing, 0};
        if (body.region.contains(x, 2, 1e-6 * spacing)) {
          particles.position.push_back(x);
          particles.volume.push_back(spacing * spacing * dimension.thickness);
        }
      }
  }
};

TEST(PressureForces, BoreOfAQuarterRingTakesPressureTimesAreaOutwards) {
  const double a = 0.05, b = 0.1, p = 1e8;
  for (const double spacing : {0.005, 0.0025}) {
    const QuarterRing ring(a, b, spacing);
    const pd::SurfaceForces f =
        pd::pressure_forces(ring.dimension, spacing, ring.bodies, ring.particles,
                            ring.particles.size(), cylinder(a), p);
    const double area = std::numbers::pi / 2 * a * ring.dimension.thickness;
    EXPECT_NEAR(f.area, area, 1e-3 * area);
    // Outwards (into the ring), the quarter's resultant is p a t along x and along y.
    double fx = 0, fy = 0, magnitude = 0;
    for (std::size_t k = 0; k < f.particle.size(); ++k) {
      fx += f.force[k][0];
      fy += f.force[k][1];
      magnitude += std::hypot(f.force[k][0], f.force[k][1]);
      EXPECT_LT(std::hypot(ring.particles.position[f.particle[k]][0],
                           ring.particles.position[f.particle[k]][1]),
                a + spacing);
    }
    EXPECT_NEAR(fx, p * a * ring.dimension.thickness, 2e-3 * p * a * ring.dimension.thickness);
    EXPECT_NEAR(fy, fx, 2e-3 * fx);
    EXPECT_NEAR(magnitude, p * area, 1e-2 * p * area);
  }
}

// The quarter ring is its own mirror image across the diagonal x = y, and so must be its load:
// the particle at (y, x) takes the force at (x, y) with its components swapped. An odd number of
// pieces around the bore broke this by 0.2 % in the displacements (ring-pressure.yaml).
TEST(PressureForces, TheBoreOfAQuarterRingIsLoadedLikeItsMirrorImage) {
  const double a = 0.05, spacing = 0.0025;
  const QuarterRing ring(a, 0.1, spacing);
  const pd::SurfaceForces f =
      pd::pressure_forces(ring.dimension, spacing, ring.bodies, ring.particles,
                          ring.particles.size(), cylinder(a), 1e8);
  ASSERT_GT(f.particle.size(), 20u);
  for (std::size_t k = 0; k < f.particle.size(); ++k) {
    const pd::Vec3& x = ring.particles.position[f.particle[k]];
    std::size_t image = f.particle.size();
    for (std::size_t m = 0; m < f.particle.size(); ++m) {
      const pd::Vec3& y = ring.particles.position[f.particle[m]];
      if (std::abs(y[0] - x[1]) < 1e-9 && std::abs(y[1] - x[0]) < 1e-9) {
        image = m;
      }
    }
    ASSERT_LT(image, f.particle.size())
        << "no loaded particle at the image of " << x[0] << ", " << x[1];
    const double scale = std::hypot(f.force[k][0], f.force[k][1]);
    EXPECT_NEAR(f.force[image][0], f.force[k][1], 1e-12 * scale) << "at " << x[0] << ", " << x[1];
    EXPECT_NEAR(f.force[image][1], f.force[k][0], 1e-12 * scale) << "at " << x[0] << ", " << x[1];
  }
}

TEST(PressureForces, OuterFacePushesInwardsAndAnInnerSurfaceCarriesNothing) {
  const double a = 0.05, b = 0.1, spacing = 0.0025;
  const QuarterRing ring(a, b, spacing);
  const pd::SurfaceForces outer = pd::pressure_forces(
      ring.dimension, spacing, ring.bodies, ring.particles, ring.particles.size(), cylinder(b), 1);
  double fx = 0;
  for (const pd::Vec3& f : outer.force)
    fx += f[0];
  EXPECT_NEAR(fx, -b * ring.dimension.thickness, 2e-3 * b * ring.dimension.thickness);
  // r = 0.075 runs through the ring's inside: no side of it is free.
  const pd::SurfaceForces inside =
      pd::pressure_forces(ring.dimension, spacing, ring.bodies, ring.particles,
                          ring.particles.size(), cylinder(0.075), 1);
  EXPECT_TRUE(inside.particle.empty());
}

TEST(PressureForces, BoxFaceParticlesTakeTractionTimesTheirFace) {
  // A 3D box of 4 × 2 × 2 cells; pressure on its faces: each x = 0 face particle takes p λ².
  const double spacing = 0.5;
  pd::BodySpec body;
  body.region.boxes.push_back(pd::Box{{0, 0, 0}, {2, 1, 1}});
  pd::ParticleSet particles;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 4; ++i) {
        particles.position.push_back(
            {(i + 0.5) * spacing, (j + 0.5) * spacing, (k + 0.5) * spacing});
        particles.volume.push_back(spacing * spacing * spacing);
      }
  pd::Shape box;
  box.box = body.region.boxes.front();
  const pd::SurfaceForces f =
      pd::pressure_forces({3}, spacing, {body}, particles, particles.size(), box, 2.0);
  EXPECT_DOUBLE_EQ(f.area, 2 * (2 * 1 + 2 * 1 + 1 * 1));
  ASSERT_EQ(f.particle.size(), particles.size()); // every particle of this box is on a face
  // Particle 0 sits in the corner x = y = z = 0: pushed by +x, +y and +z faces' pressure.
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(f.force[0][c], 2.0 * spacing * spacing, 1e-12);
  EXPECT_EQ(pd::surface_patches(box, {0, 0.3, 0.3}, 3, 1e-9), 1U);
  EXPECT_EQ(pd::surface_patches(box, {2, 1, 0.3}, 3, 1e-9), (1U << 1) | (1U << 3));
  EXPECT_EQ(pd::surface_patches(box, {1, 0.5, 0.5}, 3, 1e-9), 0U);
}

} // namespace
