#include "libpd/physics/fibres.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace pd {

namespace {

/// ∫_0^1 (1 − t²)^k t^(N−1) dt = ½ B(N/2, k+1), by the binomial sum Σ_i C(k,i)(−1)^i/(N+2i).
double radial_integral(int dim, int k) {
  double sum = 0, binomial = 1;
  for (int i = 0; i <= k; ++i) {
    sum += (i % 2 == 0 ? 1.0 : -1.0) * binomial / (dim + 2 * i);
    binomial = binomial * (k - i) / (i + 1);
  }
  return sum;
}

} // namespace

double FibreKernel::normalisation(int dim) const {
  // Substituting u = α t in eq. 112's denominator.
  return 2.0 * (dim - 1) * std::numbers::pi * std::pow(alpha, dim) * radial_integral(dim, exponent);
}

double FibreKernel::value(int dim, double u) const {
  if (u > alpha) {
    return 0.0;
  }
  const double t = 1.0 - u * u / (alpha * alpha);
  return std::pow(t, exponent) / normalisation(dim);
}

double FibreKernel::slope(int dim, double u) const {
  if (u > alpha) {
    return 0.0;
  }
  const double t = 1.0 - u * u / (alpha * alpha);
  return -2.0 * exponent * u / (alpha * alpha) * std::pow(t, exponent - 1) / normalisation(dim);
}

double FibreKernel::slope_volume(int dim) const {
  return 2.0 * (dim - 1) * std::numbers::pi * (dim - 1) * std::pow(alpha, dim - 1) *
         radial_integral(dim - 1, exponent) / normalisation(dim);
}

FibreModuli fibre_moduli(const ModelDimension& d, double youngs_modulus, double poisson_ratio) {
  const double E = youngs_modulus, nu = poisson_ratio;
  const bool plane_stress = d.dim == 2 && d.plane == PlaneMode::plane_stress;
  if (d.dim != 2 && d.dim != 3) {
    throw std::invalid_argument("virtual fibres: the model needs dimension 2 or 3");
  }
  if (!(nu > -1.0) || !(plane_stress ? nu < 1.0 : nu < 0.5)) {
    throw std::invalid_argument("virtual fibres: Poisson ratio outside the stable range");
  }
  const double G = E / (2.0 * (1.0 + nu)); // eq. 78
  double K = 0;
  if (d.dim == 3) {
    K = E / (3.0 * (1.0 - 2.0 * nu)); // eq. 79
  } else if (plane_stress) {
    K = E / (2.0 * (1.0 - nu)); // eq. 80
  } else {
    K = E / (2.0 * (1.0 - 2.0 * nu) * (1.0 + nu)); // eq. 81
  }
  const double N = d.dim;
  return {G * (N + 2.0), N * K - G * (N + 2.0)};
}

} // namespace pd
