// Particle sets beyond the lattice (issue 17, item 3): sizes from the nearest neighbours
// (eq. 115), the arms of particles with their own horizons, and the fibre model's patch test on
// irregular, graded particles.
#include "libpd/discretisation/model.hpp"
#include "libpd/discretisation/point_cloud.hpp"
#include "libpd/kernel/force_kernel.hpp"

#include <array>
#include <cmath>
#include <gtest/gtest.h>
#include <random>
#include <vector>

namespace {

TEST(PointCloud, SizesAreHalfTheMeanDistanceToTheNearestNeighbours) {
  // Square lattice of spacing s: 4 neighbours at s, the fifth at √2 s (eq. 115, n = 5).
  const double s = 0.1;
  std::vector<pd::Vec3> p;
  for (int j = 0; j < 9; ++j) {
    for (int i = 0; i < 9; ++i) {
      p.push_back({i * s, j * s, 0});
    }
  }
  const auto h = pd::sizes_from_neighbours(p, 2, 5);
  EXPECT_NEAR(h[4 * 9 + 4], (4 * s + std::sqrt(2.0) * s) / 10, 1e-15);
  // A corner: 2 at s, 1 at √2 s, 2 at 2s.
  EXPECT_NEAR(h[0], (2 * s + std::sqrt(2.0) * s + 4 * s) / 10, 1e-15);
}

TEST(PointCloud, ArmsJoinPairsInsideEitherHorizonInBothDirections) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<pd::Vec3> p(400);
  std::vector<double> horizon(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    p[i] = {u(rng), u(rng), u(rng)};
    horizon[i] = 0.05 + 0.15 * u(rng);
  }
  const pd::BondFamily f = pd::variable_horizon_family(p, 3, horizon);
  std::size_t expected = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    std::size_t row = 0;
    for (std::size_t j = 0; j < p.size(); ++j) {
      const double d = std::sqrt((p[i][0] - p[j][0]) * (p[i][0] - p[j][0]) +
                                 (p[i][1] - p[j][1]) * (p[i][1] - p[j][1]) +
                                 (p[i][2] - p[j][2]) * (p[i][2] - p[j][2]));
      row += (j != i && d <= std::max(horizon[i], horizon[j])) ? 1 : 0;
    }
    EXPECT_EQ(f.family_size(i), row) << "particle " << i;
    expected += row;
  }
  EXPECT_EQ(f.directed_bond_count(), expected);
  const auto reverse = pd::reverse_bond_index(f);
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (std::size_t k = f.offsets[i]; k < f.offsets[i + 1]; ++k) {
      EXPECT_EQ(f.neighbour[reverse[k]], i);
    }
  }
}

} // namespace
