#include "libpd/physics/material.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace pd {

std::optional<double> bond_based_poisson_ratio(const ModelDimension& d) {
  if (d.dim == 3) {
    return 0.25;
  }
  if (d.dim == 2) {
    return d.plane == PlaneMode::plane_stress ? 1.0 / 3.0 : 0.25;
  }
  return std::nullopt;
}

double micromodulus(const ModelDimension& d, double youngs_modulus, double horizon) {
  const double pi = std::numbers::pi;
  const double E = youngs_modulus;
  const double delta = horizon;
  switch (d.dim) {
  case 3:
    return 12.0 * E / (pi * std::pow(delta, 4)); // Miranda eq. 8 with k = 2E/3 (ν = 1/4)
  case 2:
    return d.plane == PlaneMode::plane_stress
               ? 9.0 * E / (pi * d.thickness * std::pow(delta, 3))
               : 48.0 * E / (5.0 * pi * d.thickness * std::pow(delta, 3));
  case 1:
    return 2.0 * E / (d.cross_section * delta * delta);
  default:
    throw std::invalid_argument("micromodulus: dimension must be 1, 2 or 3");
  }
}

double critical_stretch_from_fracture_energy(const ModelDimension& d, double youngs_modulus,
                                             double horizon, double fracture_energy) {
  const double pi = std::numbers::pi;
  const double E = youngs_modulus;
  const double G0 = fracture_energy;
  const double delta = horizon;
  switch (d.dim) {
  case 3: {
    const double c = micromodulus(d, E, delta);
    return std::sqrt(10.0 * G0 / (pi * c * std::pow(delta, 5))); // Miranda eq. 11
  }
  case 2:
    return d.plane == PlaneMode::plane_stress ? std::sqrt(4.0 * pi * G0 / (9.0 * E * delta))
                                              : std::sqrt(5.0 * pi * G0 / (12.0 * E * delta));
  case 1:
    return std::sqrt(3.0 * G0 / (E * delta));
  default:
    throw std::invalid_argument("critical stretch: dimension must be 1, 2 or 3");
  }
}

} // namespace pd
