// The sharp prediction of what `pd stability` measures (libpd/time/stability.hpp): a bounded run of
// N steps is unstable once its energy grows by more than `growth`, and each mode's energy grows by
// |a(ωΔt)|^{2N}. Checked here against closed forms derived independently of the library code.
#include "libpd/discretisation/model.hpp"
#include "libpd/time/integrator.hpp"
#include "libpd/time/stability.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>
#include <random>
#include <vector>

namespace {

pd::PerturbationSpectrum single_mode(double omega) {
  pd::PerturbationSpectrum s;
  s.omega_squared = {omega * omega};
  s.energy = {1.0};
  return s;
}

double log_modulus(const pd::ButcherTableau& table, double y) {
  return std::log(pd::stability_modulus_on_imaginary_axis(pd::stability_polynomial(table), y));
}

TEST(BoundedRunLimit, HeunEulerHasAFiniteLimitDespiteNoImaginaryInterval) {
  // R(z) = 1 + z + z²/2 gives |R(iy)|² = (1 − y²/2)² + y² = 1 + y⁴/4, so the energy of one mode
  // grows by (1 + y⁴/4)^N and the bounded run fails at y = (4 (growth^{1/N} − 1))^{1/4}.
  const pd::ButcherTableau heun = pd::butcher_tableau(pd::ArkodeTable::heun_euler);
  ASSERT_EQ(pd::imaginary_stability_interval(heun), 0.0);
  const double omega = 3.0e5, growth = 1e3;
  for (std::size_t steps : {100u, 1000u, 10000u}) {
    const double expected =
        std::pow(4.0 * (std::pow(growth, 1.0 / static_cast<double>(steps)) - 1.0), 0.25) / omega;
    const double dt = pd::bounded_run_limit(
        single_mode(omega), [&](double y) { return log_modulus(heun, y); }, steps, growth);
    EXPECT_NEAR(dt / expected, 1.0, 1e-6) << steps << " steps";
  }
}

TEST(BoundedRunLimit, TendsToTheImaginaryIntervalForLongRuns) {
  // RK4: β = 2√2. With more steps the same growth budget allows less excess per step, so the
  // limit decreases towards β/ω from above.
  const pd::ButcherTableau rk4 = pd::butcher_tableau(pd::ArkodeTable::rk4);
  const double omega = 1.0;
  double previous = 1e300;
  for (std::size_t steps : {1000u, 100000u, 10000000u}) {
    const double y = pd::bounded_run_limit(
        single_mode(omega), [&](double x) { return log_modulus(rk4, x); }, steps, 1e3);
    EXPECT_GT(y, 2.0 * std::numbers::sqrt2);
    EXPECT_LT(y, previous);
    previous = y;
  }
  EXPECT_NEAR(previous, 2.0 * std::numbers::sqrt2, 1e-4);
}

TEST(BoundedRunLimit, CentralDifferencesJustAboveTwo) {
  // μ² − (2 − y²)μ + 1 = 0: at y > 2 the roots are real, |μ| = ((y² − 2) + √((y² − 2)² − 4))/2.
  EXPECT_EQ(pd::central_difference_log_amplification(1.99), 0.0);
  const double y = 2.1, b = y * y - 2.0;
  EXPECT_NEAR(pd::central_difference_log_amplification(y),
              std::log(0.5 * (b + std::sqrt(b * b - 4.0))), 1e-14);
  const double limit =
      pd::bounded_run_limit(single_mode(1.0), pd::central_difference_log_amplification, 1000, 1e3);
  EXPECT_GT(limit, 2.0);
  EXPECT_LT(limit, 2.001);
}

TEST(BoundedRunLimit, TheMostExcitedGrowingModeDecides) {
  // Two modes; only the upper one grows past its interval. Halving its energy share moves the
  // limit only through log(growth / share), i.e. by a small amount, and in the right direction.
  const pd::ButcherTableau rk4 = pd::butcher_tableau(pd::ArkodeTable::rk4);
  auto limit = [&](double upper_share) {
    pd::PerturbationSpectrum s;
    s.omega_squared = {0.25, 1.0};
    s.energy = {1.0 - upper_share, upper_share};
    return pd::bounded_run_limit(
        s, [&](double x) { return log_modulus(rk4, x); }, 1000, 1e3);
  };
  EXPECT_GT(limit(0.25), limit(0.5));
  EXPECT_LT(limit(0.25) / limit(0.5), 1.01);
}

pd::ModelSpec chain(int n) {
  pd::ModelSpec s;
  s.surface_correction = pd::SurfaceCorrection::none; // the bare model
  s.volume_correction = pd::VolumeCorrection::none;
  s.dimension.dim = 1;
  s.dimension.cross_section = 1e-4;
  s.lattice.spacing = 0.01;
  s.lattice.horizon_factor = 3.015;
  pd::Material mat;
  mat.youngs_modulus = 1e9;
  mat.density = 1000;
  s.materials = {mat};
  pd::BodySpec b;
  b.region.boxes = {pd::Box{{0, 0, 0}, {n * 0.01, 0, 0}}};
  s.bodies = {b};
  return s;
}

TEST(PerturbationSpectrum, EnergiesSumToTheStrainEnergyAndNodesSpanTheSpectrum) {
  const pd::Model model = pd::build_model(chain(40));
  std::vector<double> du(3 * model.size(), 0.0);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> dist(-1e-6, 1e-6);
  for (std::size_t i = 0; i < model.size(); ++i) {
    du[3 * i] = dist(rng);
  }
  // Strain energy of the linearised bonds: ¼ Σ_i V_i Σ_j c V_j (n·(u_j − u_i))² / |ξ| over
  // ordered pairs (each bond counted from both ends, hence ¼); bond_stiffness is c V_j.
  double energy = 0;
  for (std::size_t i = 0; i < model.size(); ++i) {
    for (std::size_t k = model.family.offsets[i]; k < model.family.offsets[i + 1]; ++k) {
      const std::size_t j = model.family.neighbour[k];
      const double length = 1.0 / model.family.inverse_length[k];
      const double e = du[3 * j] - du[3 * i];
      energy += 0.25 * pd::bond_stiffness(model, k) * model.particles.volume[i] * e * e / length;
    }
  }
  const pd::PerturbationSpectrum s = pd::perturbation_spectrum(model, du, 200);
  double sum = 0, top = 0;
  for (std::size_t k = 0; k < s.energy.size(); ++k) {
    sum += s.energy[k];
    top = std::max(top, s.omega_squared[k]);
  }
  EXPECT_NEAR(sum / energy, 1.0, 1e-9);
  EXPECT_NEAR(std::sqrt(top) / pd::max_frequency(model).omega_max, 1.0, 1e-6);
}

} // namespace
