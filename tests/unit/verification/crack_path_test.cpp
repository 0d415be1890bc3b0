// Reading a crack out of a damage field (verification/runner/crack_path.hpp): the direction of a
// path, the Rayleigh wave speed, the tip speed from lattice-quantised positions and where a path
// splits.
#include "crack_path.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace pd::verification {
namespace {

TEST(CrackPath, PrincipalAxisOfPointsOnALineIsItsAngle) {
  for (double deg : {0.0, 35.0, 70.0, 90.0, 135.0}) {
    const double a = deg * std::numbers::pi / 180;
    std::vector<Vec3> p;
    for (int k = -5; k <= 20; ++k) {
      p.push_back({0.05 + 1e-3 * k * std::cos(a), 0.025 + 1e-3 * k * std::sin(a), 0});
    }
    EXPECT_NEAR(principal_axis_degrees(p), deg, 1e-9) << deg;
  }
  EXPECT_THROW(principal_axis_degrees({{0, 0, 0}}), std::invalid_argument);
  EXPECT_THROW(principal_axis_degrees({{1, 1, 0}, {1, 1, 0}}), std::invalid_argument);
}

TEST(CrackPath, PrincipalAxisOfTwoFacesOfACrackIsTheCrack) {
  // The particles on both faces of a crack at 70°, half a spacing either side of it.
  const double a = 70 * std::numbers::pi / 180;
  const Vec3 n{-std::sin(a), std::cos(a), 0};
  std::vector<Vec3> p;
  for (int k = 0; k < 40; ++k) {
    for (double side : {-0.5e-3, 0.5e-3}) {
      p.push_back({1e-3 * k * std::cos(a) + side * n[0], 1e-3 * k * std::sin(a) + side * n[1], 0});
    }
  }
  EXPECT_NEAR(principal_axis_degrees(p), 70.0, 1e-9);
}

TEST(CrackPath, RayleighSpeedOfAPoissonSolid) {
  // ν = 1/4 in plane strain (c_p² = 3 c_s²): c_R/c_s = √(2 − 2/√3) (Rayleigh's classic root).
  // Plane stress with ν = 1/3 has the same c_p/c_s (1/ν' = 1/ν + 1 with ν' = 1/4).
  const double ratio = std::sqrt(2 - 2 / std::sqrt(3.0));
  const double strain = rayleigh_wave_speed(1.0, std::sqrt(3.0));
  EXPECT_NEAR(strain, ratio, 1e-12);
  const WaveSpeeds w = plane_wave_speeds(72e9, 1.0 / 3, 2440, true);
  EXPECT_NEAR(w.shear, std::sqrt(72e9 / (2 * 2440 * 4.0 / 3)), 1e-9);
  EXPECT_NEAR(w.longitudinal / w.shear, std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(w.rayleigh / w.shear, ratio, 1e-12);
  const WaveSpeeds s = plane_wave_speeds(72e9, 0.25, 2440, false);
  EXPECT_NEAR(s.longitudinal / s.shear, std::sqrt(3.0), 1e-12);
  // Below the shear wave speed, and nearer to it as ν grows.
  const WaveSpeeds hi = plane_wave_speeds(1, 0.45, 1, false);
  EXPECT_LT(hi.rayleigh / hi.shear, 1.0);
  EXPECT_GT(hi.rayleigh / hi.shear, ratio);
}

TEST(CrackPath, ChordSpeedOfASmoothTipIsItsSpeed) {
  std::vector<double> t;
  std::vector<Vec3> r;
  for (int k = 0; k <= 100; ++k) {
    t.push_back(0.25e-6 * k);
    r.push_back({0.05 + 1500 * t.back(), 0, 0});
  }
  EXPECT_NEAR(max_chord_speed(t, r, 2e-6), 1500, 1e-6);
  EXPECT_EQ(max_chord_speed({0.0}, {{0, 0, 0}}, 2e-6), 0.0);
}

TEST(CrackPath, ChordSpeedOfALatticeTipIsBoundedByOneSpacingOverTheWindow) {
  // A tip at 1500 m/s seen on a lattice of 0.5 mm: positions rounded down to the spacing.
  const double spacing = 0.5e-3, speed = 1500, window = 2e-6;
  std::vector<double> t;
  std::vector<Vec3> r;
  for (int k = 0; k <= 200; ++k) {
    t.push_back(0.25e-6 * k);
    r.push_back({spacing * std::floor(speed * t.back() / spacing), 0, 0});
  }
  const double v = max_chord_speed(t, r, window);
  EXPECT_GT(v, speed);
  EXPECT_LE(v, speed + spacing / window);
}

TEST(CrackPath, BranchingOfAYIsWhereItsArmsPartBeyondTheGap) {
  // A stem along y = 0 up to x = 20 mm, then two arms at ±15°, points every 0.5 mm along x.
  const double spacing = 0.5e-3, fork = 0.02, slope = std::tan(15 * std::numbers::pi / 180);
  std::vector<Vec3> p;
  for (double x = 0; x <= 0.05; x += spacing) {
    if (x <= fork) {
      p.push_back({x, 0.25e-3, 0});
      p.push_back({x, -0.25e-3, 0});
    } else {
      p.push_back({x, 0.25e-3 + slope * (x - fork), 0});
      p.push_back({x, -0.25e-3 - slope * (x - fork), 0});
    }
  }
  const double gap = 1.5 * spacing;
  const auto b = branching_x(p, 0.0, spacing, gap, 2e-3);
  ASSERT_TRUE(b.has_value());
  // The arms are more than `gap` apart once 2 (x − fork) tan 15° + 0.5 mm exceeds it.
  const double parted = fork + (gap - 0.5e-3) / (2 * slope);
  EXPECT_NEAR(*b, parted, spacing);
  // A straight crack never splits; a single stray point beside it is not a branch.
  std::vector<Vec3> straight;
  for (double x = 0; x <= 0.05; x += spacing) {
    straight.push_back({x, 0.25e-3, 0});
    straight.push_back({x, -0.25e-3, 0});
  }
  EXPECT_FALSE(branching_x(straight, 0.0, spacing, gap, 2e-3).has_value());
  straight.push_back({0.03, 5e-3, 0});
  EXPECT_FALSE(branching_x(straight, 0.0, spacing, gap, 2e-3).has_value());
}

} // namespace
} // namespace pd::verification
