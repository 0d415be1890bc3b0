// The generated graded particle set of Olsson, Ander & Williams (2021), §10.2, Figs. 7–8.
#include "libpd/discretisation/graded_set.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <numbers>
#include <vector>

namespace {

/// The exact area of point `a`'s Voronoi cell within the box [lo, hi]²: the box clipped by the
/// bisector of a and every other point (Sutherland–Hodgman), then the shoelace formula.
double voronoi_area(const std::vector<pd::Vec3>& points, std::size_t a, const pd::Vec3& lo,
                    const pd::Vec3& hi) {
  using Point = std::array<double, 2>;
  std::vector<Point> cell{{lo[0], lo[1]}, {hi[0], lo[1]}, {hi[0], hi[1]}, {lo[0], hi[1]}};
  const Point pa{points[a][0], points[a][1]};
  for (std::size_t b = 0; b < points.size(); ++b) {
    if (b == a) {
      continue;
    }
    // Keep the side nearer a: n·x ≤ n·m with n = b − a and m the midpoint.
    const Point n{points[b][0] - pa[0], points[b][1] - pa[1]};
    const double limit = n[0] * (pa[0] + 0.5 * n[0]) + n[1] * (pa[1] + 0.5 * n[1]);
    const auto side = [&](const Point& x) { return n[0] * x[0] + n[1] * x[1] - limit; };
    std::vector<Point> kept;
    for (std::size_t k = 0; k < cell.size(); ++k) {
      const Point& p = cell[k];
      const Point& q = cell[(k + 1) % cell.size()];
      const double sp = side(p), sq = side(q);
      if (sp <= 0) {
        kept.push_back(p);
      }
      if ((sp < 0 && sq > 0) || (sp > 0 && sq < 0)) {
        const double t = sp / (sp - sq);
        kept.push_back({p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])});
      }
    }
    cell = std::move(kept);
  }
  double twice = 0;
  for (std::size_t k = 0; k < cell.size(); ++k) {
    const Point& p = cell[k];
    const Point& q = cell[(k + 1) % cell.size()];
    twice += p[0] * q[1] - q[0] * p[1];
  }
  return 0.5 * std::abs(twice);
}

pd::GradedSetSpec disk() {
  pd::GradedSetSpec s;
  s.focal_half_distance = 1.0 / 24; // Table 1
  s.xi_max = 2.0;
  s.zones = {16, 12};
  s.pattern = 3;
  return s;
}

TEST(GradedSet, EllipseVolumesTileTheEllipseAndSizesVaryManyFold) {
  const pd::GradedSetSpec s = disk();
  const pd::PointCloud p = pd::generate_graded_set(s, 1.0);
  ASSERT_EQ(p.count(), 16U * 12U * 9U);
  const double c = s.focal_half_distance;
  const double area = std::numbers::pi * c * std::cosh(s.xi_max) * c * std::sinh(s.xi_max);
  double sum = 0;
  for (const double v : p.volume) {
    sum += v;
  }
  // The midpoint rule on 48 × 36 sub-cells of a smooth Jacobian.
  EXPECT_NEAR(sum / area, 1.0, 2e-3);
  const auto [lo, hi] = std::minmax_element(p.size.begin(), p.size.end());
  EXPECT_GT(*hi / *lo, 10.0); // zones shrink towards the focal points
  const double a = c * std::cosh(s.xi_max), b = c * std::sinh(s.xi_max);
  for (const pd::Vec3& x : p.position) {
    EXPECT_LE((x[0] / a) * (x[0] / a) + (x[1] / b) * (x[1] / b), 1.0);
  }
}

TEST(GradedSet, MovesKeepTheMinimumSpacingAndTheCrackFaces) {
  pd::GradedSetSpec s = disk();
  const pd::PointCloud start = [&] {
    pd::GradedSetSpec still = s;
    still.sweeps = 0;
    return pd::generate_graded_set(still, 1.0);
  }();
  const pd::PointCloud p = pd::generate_graded_set(s, 1.0);
  std::size_t moved = 0;
  for (std::size_t a = 0; a < p.count(); ++a) {
    moved += p.position[a] == start.position[a] ? 0 : 1;
    // Particles beside the crack stay on their side of it (eq. 114: ξ > 0 is y ≠ 0 there).
    if (std::abs(start.position[a][0]) < s.focal_half_distance) {
      EXPECT_EQ(std::signbit(p.position[a][1]), std::signbit(start.position[a][1])) << a;
    }
  }
  EXPECT_GT(moved, p.count() / 2); // the relaxation does add noise
  // A move is kept only at min_spacing (h_a + h_b) from the nearest neighbours, so relaxation
  // never brings particles closer than that (the initial pattern of a stretched zone may); the
  // sizes it checks against are refreshed every fifth sweep, hence the 0.8 here.
  const auto too_close = [&](const pd::PointCloud& c) {
    const auto near = pd::nearest_neighbours(c.position, 2, 1);
    std::size_t n = 0;
    for (std::size_t a = 0; a < c.count(); ++a) {
      const auto b = near[a][0];
      const double d =
          std::hypot(c.position[a][0] - c.position[b][0], c.position[a][1] - c.position[b][1]);
      n += d < 0.8 * s.min_spacing * (c.size[a] + c.size[b]) ? 1 : 0;
    }
    return n;
  };
  EXPECT_LE(too_close(p), too_close(start));
}

TEST(GradedSet, TheSeedFixesTheSet) {
  pd::GradedSetSpec s = disk();
  const pd::PointCloud a = pd::generate_graded_set(s, 1.0);
  const pd::PointCloud b = pd::generate_graded_set(s, 1.0);
  EXPECT_EQ(a.position, b.position);
  EXPECT_EQ(a.size, b.size);
  s.seed = 2;
  EXPECT_NE(pd::generate_graded_set(s, 1.0).position, a.position);
}

TEST(GradedSet, BoxZonesGrowByTheGrading) {
  pd::GradedSetSpec s;
  s.shape = pd::GradedShape::box;
  s.box = pd::Box{{0, 0, 0}, {1, 0.5, 0}};
  s.zones = {10, 4};
  s.pattern = 2;
  s.grading = 10;
  s.sweeps = 0;
  const pd::PointCloud p = pd::generate_graded_set(s, 0.01);
  double sum = 0;
  for (const double v : p.volume) {
    sum += v;
  }
  EXPECT_NEAR(sum, 0.5 * 0.01, 1e-3 * 0.5 * 0.01);
  // Columns of particles (pattern 2: the first zone holds columns 0, 1, the last 18, 19).
  std::vector<double> x;
  for (const pd::Vec3& q : p.position) {
    if (x.empty() || q[0] != x.back()) {
      x.push_back(q[0]);
    }
  }
  ASSERT_EQ(x.size(), 20U);
  EXPECT_NEAR((x[19] - x[18]) / (x[1] - x[0]), 10.0, 0.5);
  // Each column holds particles about as far apart across as along: the fine end many rows.
  const auto rows = [&](double column) {
    return std::count_if(p.position.begin(), p.position.end(),
                         [&](const pd::Vec3& q) { return q[0] == column; });
  };
  EXPECT_NEAR(0.5 / static_cast<double>(rows(x[0])), x[1] - x[0], 0.2 * (x[1] - x[0]));
  EXPECT_GT(rows(x[0]), 5 * rows(x[19]));
}

TEST(GradedSet, MovedParticlesGetTheirVoronoiAreas) {
  // A square of 12 × 12 particles with the Monte Carlo noise: each particle's volume is the area
  // nearest to it, measured by sampling; here against the exact cell by clipping.
  pd::GradedSetSpec s;
  s.shape = pd::GradedShape::box;
  s.box = pd::Box{{0, 0, 0}, {1, 1, 0}};
  s.zones = {4, 4};
  s.pattern = 3;
  const double thickness = 0.5;
  const pd::PointCloud p = pd::generate_graded_set(s, thickness);
  double sum = 0, worst = 0, spread = 0;
  for (std::size_t a = 0; a < p.count(); ++a) {
    const double exact = voronoi_area(p.position, a, s.box.lo, s.box.hi) * thickness;
    worst = std::max(worst, std::abs(p.volume[a] / exact - 1.0));
    spread = std::max(spread, std::abs(exact / (thickness / 144.0) - 1.0));
    sum += p.volume[a];
  }
  std::printf("sampled against exact Voronoi areas: worst %.2f %%, cells off the pattern's by up "
              "to %.0f %%\n",
              100 * worst, 100 * spread);
  EXPECT_NEAR(sum, thickness, 1e-12); // every sample's area goes to some particle
  // 256 samples per sub-cell; measured worst 3.1 % (the smallest cells hold the fewest samples).
  EXPECT_LT(worst, 0.06);
  EXPECT_GT(spread, 0.2); // the noise does move the cells far off the pattern's 1/144
}

} // namespace
