// The virtual-fibre law (Olsson, Ander & Williams 2021): the kernel of eq. 112 and the elastic
// constants of eqs. 77–84.
#include "libpd/physics/fibres.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>

namespace {

/// ∫_0^α g(u) 2(N−1)π u^(N−1) du by the composite Simpson rule.
template <class G>
double radial(int dim, double alpha, G g) {
  const int n = 20000;
  const double h = alpha / n;
  double s = 0;
  for (int i = 0; i <= n; ++i) {
    const double u = i * h;
    const double w = (i == 0 || i == n) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    s += w * g(u) * 2.0 * (dim - 1) * std::numbers::pi * std::pow(u, dim - 1);
  }
  return s * h / 3.0;
}

TEST(FibreKernel, IntegratesToOneInEveryDimensionAndExponent) {
  // Eq. 54 for the kernel of eq. 112, and eq. 59: −∫ f'(u) u ·2(N−1)π u^(N−1) du = N, the total
  // weighted length that the arm weights are normalised by.
  for (int dim : {2, 3}) {
    for (int k : {1, 2, 3, 5}) {
      pd::FibreKernel kernel{k, 5.1};
      EXPECT_NEAR(radial(dim, kernel.alpha, [&](double u) { return kernel.value(dim, u); }), 1.0,
                  1e-9)
          << "dim " << dim << " k " << k;
      EXPECT_NEAR(radial(dim, kernel.alpha, [&](double u) { return -kernel.slope(dim, u) * u; }),
                  dim, 1e-8)
          << "dim " << dim << " k " << k;
      EXPECT_NEAR(radial(dim, kernel.alpha, [&](double u) { return -kernel.slope(dim, u); }) /
                      kernel.slope_volume(dim),
                  1.0, 1e-8)
          << "dim " << dim << " k " << k;
    }
  }
}

TEST(FibreKernel, MatchesEquation113ForExponentTwo) {
  const pd::FibreKernel kernel{2, 5.1};
  for (int n : {2, 3}) {
    const double N = n;
    const double z = 2.0 * (N - 1) * std::numbers::pi * std::pow(kernel.alpha, N) *
                     (1 / N - 2 / (N + 2) + 1 / (N + 4));
    EXPECT_NEAR(kernel.normalisation(n) / z, 1.0, 1e-14);
  }
  EXPECT_EQ(kernel.value(3, 5.2), 0.0);
  EXPECT_EQ(kernel.slope(3, 5.2), 0.0);
  // The slope is the derivative of the value.
  const double u = 2.3, h = 1e-6;
  EXPECT_NEAR(kernel.slope(2, u), (kernel.value(2, u + h) - kernel.value(2, u - h)) / (2 * h),
              1e-9);
}

TEST(FibreModuli, VolumetricTermVanishesWhereBondBasedPdHoldsAndShearIsG) {
  const double E = 210e9;
  pd::ModelDimension d3{3};
  pd::ModelDimension strain{2, pd::PlaneMode::plane_strain};
  pd::ModelDimension stress{2, pd::PlaneMode::plane_stress};
  // Eqs. 82–84: zero at ν = 1/4 (3D, plane strain) and ν = 1/3 (plane stress).
  EXPECT_NEAR(pd::fibre_moduli(d3, E, 0.25).volumetric / E, 0.0, 1e-15);
  EXPECT_NEAR(pd::fibre_moduli(strain, E, 0.25).volumetric / E, 0.0, 1e-15);
  EXPECT_NEAR(pd::fibre_moduli(stress, E, 1.0 / 3.0).volumetric / E, 0.0, 1e-15);
  // Eq. 82 at ν = 0.3: E(2(1+ν) − 5(1−2ν)) / (2(1+ν)(1−2ν)).
  const double nu = 0.3;
  EXPECT_NEAR(pd::fibre_moduli(d3, E, nu).volumetric,
              E * (2 * (1 + nu) - 5 * (1 - 2 * nu)) / (2 * (1 + nu) * (1 - 2 * nu)), 1e-3);
  EXPECT_NEAR(pd::fibre_moduli(strain, E, nu).volumetric,
              E * (1 - 2 * (1 - 2 * nu)) / ((1 - 2 * nu) * (1 + nu)), 1e-3); // eq. 84
  EXPECT_NEAR(pd::fibre_moduli(stress, E, nu).volumetric,
              E * ((1 + nu) - 2 * (1 - nu)) / ((1 + nu) * (1 - nu)), 1e-3); // eq. 83
  EXPECT_NEAR(pd::fibre_moduli(d3, E, nu).shear, 5 * E / (2 * (1 + nu)), 1e-3);
  EXPECT_THROW(pd::fibre_moduli(pd::ModelDimension{1}, E, nu), std::invalid_argument);
  EXPECT_THROW(pd::fibre_moduli(d3, E, 0.5), std::invalid_argument);
}

} // namespace
