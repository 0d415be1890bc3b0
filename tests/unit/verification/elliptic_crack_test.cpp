// Eq. 116 of Olsson et al. (verification/runner/elliptic_crack.hpp) against the two limits the
// elliptical-disk cases lean on: Griffith's crack opening on ξ = 0 and the uniform equibiaxial
// strain far from the crack. A sign or branch error in the closed form would make every
// interior error of those cases meaningless.
#include "elliptic_crack.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>

namespace pd::verification {
namespace {

const EllipticDiskTable1 table;
const double c = table.focal_half_distance;
const double nu = table.poisson_ratio;
const double G = table.shear_modulus();
const double S = 1e8;

TEST(EllipticCrack, EllipticCoordinatesInvertEquation114) {
  for (double xi : {0.1, 0.7, 2.0}) {
    for (double eta : {-2.5, -0.3, 0.4, 1.5, 3.0}) {
      const double x = c * std::cosh(xi) * std::cos(eta), y = c * std::sinh(xi) * std::sin(eta);
      const auto [xi2, eta2] = elliptic_coordinates(x, y, c);
      EXPECT_NEAR(xi2, xi, 1e-12);
      EXPECT_NEAR(eta2, eta, 1e-12);
    }
  }
}

TEST(EllipticCrack, CrackFacesOpenAsGriffith) {
  // Plane strain: v = ±(1 − ν)(S/G)·√(c² − x²) on the faces, u = 0 there.
  for (double x : {-0.9 * c, -0.2 * c, 0.0, 0.5 * c}) {
    const double opening = (1 - nu) * S / G * std::sqrt(c * c - x * x);
    const Vec3 upper = elliptic_crack_displacement(x, +0.0, c, S, G, nu);
    const Vec3 lower = elliptic_crack_displacement(x, -0.0, c, S, G, nu);
    EXPECT_NEAR(upper[1], opening, 1e-12 * opening);
    EXPECT_NEAR(lower[1], -opening, 1e-12 * opening);
    EXPECT_NEAR(upper[0], 0.0, 1e-12 * opening);
  }
}

TEST(EllipticCrack, FarFieldIsTheUniformEquibiaxialStrain) {
  // ε = (1 − 2ν)S/(2G) in x and y; the crack's own field decays as c²/r², so at r = 1e4 c the
  // relative difference is ~1e-8.
  const double strain = (1 - 2 * nu) * S / (2 * G);
  const double r = 1e4 * c;
  for (double theta : {0.3, 1.2, 2.0, 4.0}) {
    const double x = r * std::cos(theta), y = r * std::sin(theta);
    const Vec3 u = elliptic_crack_displacement(x, y, c, S, G, nu);
    EXPECT_NEAR(u[0], strain * x, 1e-6 * strain * r);
    EXPECT_NEAR(u[1], strain * y, 1e-6 * strain * r);
  }
}

TEST(EllipticCrack, ContinuousAcrossTheAxisBeyondTheTips) {
  // η = 0 and π (the x axis outside the crack) are not a cut: the field is continuous there.
  for (double x : {1.5 * c, -3.0 * c}) {
    const Vec3 above = elliptic_crack_displacement(x, 1e-12 * c, c, S, G, nu);
    const Vec3 below = elliptic_crack_displacement(x, -1e-12 * c, c, S, G, nu);
    const double scale = S * c / G;
    EXPECT_NEAR(above[0], below[0], 1e-9 * scale);
    EXPECT_NEAR(above[1], below[1], 1e-9 * scale);
  }
}

} // namespace
} // namespace pd::verification
