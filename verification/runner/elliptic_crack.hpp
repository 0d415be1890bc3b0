// The elliptical disk with a crack between its focal points (Olsson, Ander & Williams 2021,
// §10.2–10.4, Table 1): the geometry of eq. 114 and the plane-strain closed form of eq. 116.
// Shared by the disk's elastic convergence case and the Griffith case, which hold the boundary
// zone at this field (a support's `displacement_field`) and read the interior against it.
//
// Eq. 116 is the field of an infinite plate with a crack of half-length c on the x axis under a
// remote equibiaxial stress S: far away it is the uniform strain (1 − 2ν)S/(2G) in both
// directions, on the crack faces (ξ = 0) the opening is v = ±(1 − ν)(S/G)·√(c² − x²), Griffith's.
// Restricted to the ellipse ξ ≤ ξ_max with its boundary held at the same field, it is the exact
// solution of the disk, so the interior error is the discretisation's alone.
#pragma once

#include "libpd/core/geometry.hpp"

#include <cmath>
#include <complex>
#include <utility>

namespace pd::verification {

/// Table 1 of Olsson et al. (steel, plane strain). `elongation_limit` is δ = c/1000 [m].
struct EllipticDiskTable1 {
  double focal_half_distance = 1.0 / 24; ///< c [m]
  int zones_eta = 20;                    ///< nη
  int zones_xi = 40;                     ///< nξ
  int pattern = 5;                       ///< particles per zone side (5 × 5)
  double kernel_alpha = 5.1;             ///< α of eq. 112–113 (k = 2)
  int size_neighbours = 5;               ///< n of eq. 115
  double youngs_modulus = 210e9;         ///< E [Pa]
  double poisson_ratio = 0.3;            ///< ν
  double density = 7800;                 ///< ρ [kg/m³]
  double yield_strain = 1.0 / 500;       ///< ε_y
  double yield_stress = 4.2e8;           ///< σ_y [Pa]
  double elongation_limit() const { return focal_half_distance / 1000; }
  double shear_modulus() const { return youngs_modulus / (2 * (1 + poisson_ratio)); }
};

/// (ξ, η) of the point (x, y): x + i y = c cosh(ξ + i η) (eq. 114), ξ ≥ 0. The principal branch
/// puts η in (0, π) above the x axis and in (−π, 0) below it (a signed zero y picks the side of
/// the crack a point on it belongs to).
inline std::pair<double, double> elliptic_coordinates(double x, double y, double c) {
  const std::complex<double> zeta = std::acosh(std::complex<double>(x, y) / c);
  return {zeta.real(), zeta.imag()};
}

/// Eq. 116 (plane strain): the displacement (u, v, 0) at (x, y). G is the shear modulus.
inline Vec3 elliptic_crack_displacement(double x, double y, double c, double remote_stress,
                                        double shear_modulus, double poisson_ratio) {
  const auto [xi, eta] = elliptic_coordinates(x, y, c);
  const double sh = std::sinh(xi), ch = std::cosh(xi), s = std::sin(eta), co = std::cos(eta);
  const double denominator = ch * ch - co * co; // sinh²ξ + sin²η: zero only at a crack tip
  if (denominator <= 0) {
    return {0, 0, 0}; // at a tip both (sinh ξ cos η) and (cosh ξ sin η) vanish
  }
  const double factor = 3 - 4 * poisson_ratio - (sh * sh - s * s) / denominator;
  const double scale = remote_stress * c / (4 * shear_modulus);
  // u − i v = scale · (sinh ξ cos η − i cosh ξ sin η) · factor
  return {scale * sh * co * factor, scale * ch * s * factor, 0};
}

} // namespace pd::verification
