// Stable time step (Miranda eq. 31) evaluated by hand on small chains.
#include "libpd/discretisation/model.hpp"
#include "libpd/kernel/stable_time_step.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <gtest/gtest.h>
#include <vector>

namespace {

constexpr double lambda = 0.01;
constexpr double area = 1e-4;
constexpr double m = 3.015; // δ/λ: three neighbours each side, none on the horizon
constexpr double E = 2e9;
constexpr double rho = 2500;

pd::Material material(double stiffness_factor = 1.0, double density = rho) {
  pd::Material mat;
  mat.youngs_modulus = E;
  mat.density = density;
  mat.stiffness_factor = stiffness_factor;
  return mat;
}

/// A 1D chain of `n` cell-centred particles; the first `soft` belong to material 0, the rest to
/// material 1 (if there are two materials).
pd::ModelSpec chain(int n, int soft, std::vector<pd::Material> materials) {
  pd::ModelSpec s;
  s.surface_correction = pd::SurfaceCorrection::none; // the bare model
  s.volume_correction = pd::VolumeCorrection::none;
  s.dimension.dim = 1;
  s.dimension.cross_section = area;
  s.lattice.spacing = lambda;
  s.lattice.horizon_factor = m;
  s.materials = std::move(materials);
  pd::BodySpec a;
  a.name = "a";
  a.region.boxes = {pd::Box{{0, 0, 0}, {soft * lambda, 0, 0}}};
  a.material = 0;
  s.bodies.push_back(a);
  if (soft < n) {
    pd::BodySpec b;
    b.name = "b";
    b.region.boxes = {pd::Box{{soft * lambda, 0, 0}, {n * lambda, 0, 0}}};
    b.material = 1;
    s.bodies.push_back(b);
  }
  return s;
}

/// Micromodulus of a 1D bar, c = 2E/(Aδ²), derived in material_test.
double c1d(double youngs) {
  const double delta = m * lambda;
  return 2 * youngs / (area * delta * delta);
}

/// Eq. 31 by hand: Δt_i = sqrt(2ρ_i / Σ_p V_p c_ip/|ξ_ip|) with neighbours up to 3 cells away.
/// `c_of(i, j)` is the bond's micromodulus times corrections, `vol(j)` the neighbour volume.
template <class C, class Vol>
std::vector<double> eq31(int n, const std::vector<double>& density, C c_of, Vol vol) {
  std::vector<double> dt(n);
  for (int i = 0; i < n; ++i) {
    double sum = 0;
    for (int j = std::max(0, i - 3); j <= std::min(n - 1, i + 3); ++j) {
      if (j != i) {
        sum += vol(j) * c_of(i, j) / (std::abs(i - j) * lambda);
      }
    }
    dt[i] = std::sqrt(2 * density[i] / sum);
  }
  return dt;
}

TEST(StableTimeStep, SevenParticleChainByHand) {
  const pd::Model model = pd::build_model(chain(7, 7, {material()}));
  ASSERT_EQ(model.size(), 7u);
  const auto dt = pd::stable_time_step_per_particle(model);
  const auto expected = eq31(
      7, std::vector<double>(7, rho), [](int, int) { return c1d(E); },
      [](int) { return lambda * area; });
  ASSERT_EQ(dt.size(), 7u);
  for (int i = 0; i < 7; ++i) {
    EXPECT_NEAR(dt[i], expected[i], 1e-12 * expected[i]) << i;
  }
  // The middle particle has the full family and the smallest step:
  // Σ = cV/λ · 2(1 + 1/2 + 1/3) = cV/λ · 11/3.
  const double middle = std::sqrt(2 * rho / (c1d(E) * lambda * area / lambda * 11.0 / 3.0));
  EXPECT_NEAR(dt[3], middle, 1e-12 * middle);
  EXPECT_NEAR(pd::stable_time_step(model), middle, 1e-12 * middle);
  // End particles only see one side: Σ halves, Δt grows by √2.
  EXPECT_NEAR(dt[0] / dt[3], std::sqrt(2.0), 1e-12);
  // Same numbers in closed form of the material: Σ = (2E/δ²)·(11/3): Δt = sqrt(3ρδ²/(11E)).
  const double delta = m * lambda;
  EXPECT_NEAR(middle, std::sqrt(3 * rho * delta * delta / (11 * E)), 1e-12 * middle);
}

TEST(StableTimeStep, StiffRegionGovernsTheMinimum) {
  const int n = 20, soft = 10;
  const pd::Model one = pd::build_model(chain(n, n, {material()}));
  const pd::Model two = pd::build_model(chain(n, soft, {material(), material(100.0)}));
  ASSERT_EQ(two.size(), static_cast<std::size_t>(n));
  ASSERT_TRUE(two.effects.per_bond_field);
  // Interface bonds take the weaker material (Miranda §5.2).
  const auto c_of = [&](int i, int j) {
    const double ci = i < soft ? c1d(E) : 100 * c1d(E);
    const double cj = j < soft ? c1d(E) : 100 * c1d(E);
    return std::min(ci, cj);
  };
  const auto expected =
      eq31(n, std::vector<double>(n, rho), c_of, [](int) { return lambda * area; });
  const auto dt = pd::stable_time_step_per_particle(two);
  for (int i = 0; i < n; ++i) {
    EXPECT_NEAR(dt[i], expected[i], 1e-12 * expected[i]) << i;
  }
  const double min_expected = *std::min_element(expected.begin(), expected.end());
  EXPECT_NEAR(pd::stable_time_step(two), min_expected, 1e-12 * min_expected);
  // Particles 13–16 are stiff with a full stiff family: their step is 1/√100 of the soft bulk.
  EXPECT_NEAR(pd::stable_time_step(two) / pd::stable_time_step(one), 0.1, 1e-12);
  const auto min_at = std::min_element(dt.begin(), dt.end()) - dt.begin();
  EXPECT_GE(min_at, 13);
  EXPECT_LE(min_at, 16);
}

TEST(StableTimeStep, DensityEntersPerParticle) {
  // A heavy stiff material: Δt_i ∝ sqrt(ρ_i), so 100× stiffer and 100× denser gives the soft step.
  const int n = 20, soft = 10;
  const pd::Model one = pd::build_model(chain(n, n, {material()}));
  const pd::Model two = pd::build_model(chain(n, soft, {material(), material(100.0, 100 * rho)}));
  const auto dt = pd::stable_time_step_per_particle(two);
  const auto dt1 = pd::stable_time_step_per_particle(one);
  for (int i = 13; i <= 16; ++i) {
    EXPECT_NEAR(dt[i], dt1[i], 1e-12 * dt1[i]) << i;
  }
  // At the interface the stiff particles keep their density but lose stiffness: larger step.
  EXPECT_GT(dt[10], dt1[10]);
}

TEST(StableTimeStep, LinearVolumeCorrectionUsesCorrectedStiffness) {
  pd::ModelSpec spec = chain(7, 7, {material()});
  spec.volume_correction = pd::VolumeCorrection::linear;
  const pd::Model model = pd::build_model(spec);
  ASSERT_TRUE(model.effects.per_bond_field);
  // Only bonds with r > δ − λ/2 = 2.515λ are cut: the 3λ bonds keep (δ + λ/2 − 3λ)/λ = 0.515 of
  // the neighbour's cell.
  const auto c_of = [](int i, int j) { return c1d(E) * (std::abs(i - j) == 3 ? 0.515 : 1.0); };
  const auto expected =
      eq31(7, std::vector<double>(7, rho), c_of, [](int) { return lambda * area; });
  const auto dt = pd::stable_time_step_per_particle(model);
  for (int i = 0; i < 7; ++i) {
    EXPECT_NEAR(dt[i], expected[i], 1e-12 * expected[i]) << i;
  }
  const pd::Model plain = pd::build_model(chain(7, 7, {material()}));
  // Σ drops from 11/3 to 2(1 + 1/2 + 0.515/3) in units of cV/λ.
  const double ratio = std::sqrt((11.0 / 3.0) / (2 * (1.5 + 0.515 / 3)));
  EXPECT_NEAR(pd::stable_time_step(model) / pd::stable_time_step(plain), ratio, 1e-12);
}

TEST(StableTimeStep, NeighbourVolumesEnter) {
  // With volume variation the neighbour's volume V_p (not the particle's own) weighs each bond.
  pd::ModelSpec spec = chain(9, 9, {material()});
  spec.lattice.volume_variation = 0.3;
  spec.lattice.seed = 7;
  const pd::Model model = pd::build_model(spec);
  const auto& vol = model.particles.volume;
  ASSERT_NE(vol[0], vol[1]);
  const auto expected = eq31(
      9, std::vector<double>(9, rho), [](int, int) { return c1d(E); },
      [&](int j) { return vol[static_cast<std::size_t>(j)]; });
  const auto dt = pd::stable_time_step_per_particle(model);
  for (int i = 0; i < 9; ++i) {
    EXPECT_NEAR(dt[i], expected[i], 1e-12 * expected[i]) << i;
  }
}

TEST(StableTimeStep, NoBondsGivesInfinity) {
  pd::ModelSpec spec = chain(1, 1, {material()});
  const pd::Model model = pd::build_model(spec);
  ASSERT_EQ(model.size(), 1u);
  EXPECT_TRUE(std::isinf(pd::stable_time_step(model)));
}

} // namespace
