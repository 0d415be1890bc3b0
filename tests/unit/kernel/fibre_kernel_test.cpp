// The virtual-fibre kernel (src/kernel/fibre_kernel.cpp) on lattice blocks: a homogeneous strain
// gives the continuum's stress and energy at every body particle that ghost layers complete; the
// forces are the energy's gradient; at ν = 1/4 the model is a bond-based pair model whose stiffness
// is the bound the time step uses.
#include "libpd/discretisation/model.hpp"
#include "libpd/kernel/force_kernel.hpp"
#include "libpd/kernel/stable_time_step.hpp"

#include <array>
#include <cmath>
#include <gtest/gtest.h>
#include <vector>

namespace {

using Matrix = std::array<std::array<double, 3>, 3>;
constexpr double lambda = 0.01;
constexpr double E = 200e9;

pd::ModelSpec block(int dim, pd::PlaneMode plane, double nu, pd::SurfaceCorrection surface,
                    pd::VolumeCorrection volume, int n = 8) {
  pd::ModelSpec s;
  s.dimension.dim = dim;
  s.dimension.plane = plane;
  s.lattice.spacing = lambda;
  s.lattice.horizon_factor = 3.015;
  s.effects.bond_model = pd::BondModel::virtual_fibres;
  s.surface_correction = surface;
  s.volume_correction = volume;
  s.mirror_coupling = pd::MirrorCoupling::quadratic;
  pd::Material m;
  m.youngs_modulus = E;
  m.poisson_ratio = nu;
  m.density = 7800;
  s.materials.push_back(m);
  pd::BodySpec b;
  b.region.boxes = {pd::Box{{0, 0, 0}, {n * lambda, n * lambda, dim == 3 ? n * lambda : 0}}};
  s.bodies.push_back(b);
  return s;
}

/// y = (I + ε) x for every particle (ghosts included: they extrapolate linear fields exactly).
std::vector<double> strained(const pd::Model& m, const Matrix& eps) {
  std::vector<double> y(3 * m.size());
  for (std::size_t i = 0; i < m.size(); ++i) {
    const auto& x = m.particles.position[i];
    for (std::size_t a = 0; a < 3; ++a) {
      y[3 * i + a] = x[a] + eps[a][0] * x[0] + eps[a][1] * x[1] + eps[a][2] * x[2];
    }
  }
  return y;
}

/// The continuum's σ = 2Gε + (K − 2G/N) tr ε I (eqs. 75–76), K per eqs. 79–81.
Matrix continuum_stress(const pd::ModelDimension& d, double nu, const Matrix& eps) {
  const double G = E / (2 * (1 + nu));
  const double K = d.dim == 3                               ? E / (3 * (1 - 2 * nu))
                   : d.plane == pd::PlaneMode::plane_strain ? E / (2 * (1 - 2 * nu) * (1 + nu))
                                                            : E / (2 * (1 - nu));
  double tr = 0;
  for (int a = 0; a < d.dim; ++a) {
    tr += eps[a][a];
  }
  Matrix s{};
  for (int a = 0; a < d.dim; ++a) {
    for (int b = 0; b < d.dim; ++b) {
      s[a][b] = 2 * G * eps[a][b] + (a == b ? (K - 2 * G / d.dim) * tr : 0.0);
    }
  }
  return s;
}

/// σ_i = Σ_j A_k S_i(q) r q⊗q, the stress particle i's own half-arms carry (eq. 36 summed as in
/// the virial), with S_i of eq. 77 from the arms' strains.
Matrix particle_stress(const pd::Model& m, const std::vector<double>& y, std::size_t i) {
  const pd::FibreArms& a = m.fibre_arms;
  const auto& f = m.family;
  double mean = 0;
  for (std::size_t k = f.offsets[i]; k < f.offsets[i + 1]; ++k) {
    const std::size_t j = f.neighbour[k];
    double r2 = 0;
    for (std::size_t c = 0; c < 3; ++c) {
      r2 += (y[3 * j + c] - y[3 * i + c]) * (y[3 * j + c] - y[3 * i + c]);
    }
    mean += a.own[k] / f.inverse_length[k] * (std::sqrt(r2) * f.inverse_length[k] - 1) / a.dim;
  }
  Matrix s{};
  for (std::size_t k = f.offsets[i]; k < f.offsets[i + 1]; ++k) {
    const std::size_t j = f.neighbour[k];
    std::array<double, 3> d{};
    double r2 = 0;
    for (std::size_t c = 0; c < 3; ++c) {
      d[c] = y[3 * j + c] - y[3 * i + c];
      r2 += d[c] * d[c];
    }
    const double r = std::sqrt(r2);
    const double S = a.shear[i] * (r * f.inverse_length[k] - 1) + a.volumetric[i] * mean;
    for (std::size_t p = 0; p < 3; ++p) {
      for (std::size_t q = 0; q < 3; ++q) {
        s[p][q] += a.own[k] * S * d[p] * d[q] / r;
      }
    }
  }
  return s;
}

double magnitude(const Matrix& s) {
  double m = 0;
  for (const auto& row : s) {
    for (double v : row) {
      m = std::max(m, std::abs(v));
    }
  }
  return m;
}

struct Setting {
  int dim;
  pd::PlaneMode plane;
  double nu;
};

class FibreHomogeneous : public ::testing::TestWithParam<Setting> {};

TEST_P(FibreHomogeneous, GhostCompletedParticlesCarryTheContinuumStressEnergyAndNoForce) {
  const Setting p = GetParam();
  pd::Model m = pd::build_model(
      block(p.dim, p.plane, p.nu, pd::SurfaceCorrection::ghost, pd::VolumeCorrection::moment));
  ASSERT_GT(m.ghost_count, 0U);
  const double e = 1e-7;
  Matrix eps{};
  eps[0][0] = e;
  eps[1][1] = -0.4 * e;
  eps[0][1] = eps[1][0] = 0.7 * e;
  if (p.dim == 3) {
    eps[2][2] = 0.3 * e;
    eps[1][2] = eps[2][1] = -0.5 * e;
  }
  const auto y = strained(m, eps);
  const Matrix expected = continuum_stress(m.spec.dimension, p.nu, eps);
  const double scale = magnitude(expected);
  const std::size_t body = m.body_particle_count();
  // Every body particle, surface ones included: the ghosts complete their horizons.
  double worst = 0;
  for (std::size_t i = 0; i < body; ++i) {
    const Matrix s = particle_stress(m, y, i);
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        worst = std::max(worst, std::abs(s[a][b] - expected[a][b]));
      }
    }
  }
  EXPECT_LT(worst / scale, 1e-5);
  // The energy: ½ σ:ε per unit volume at every body particle.
  auto f = pd::make_force_evaluator(m);
  double volume = 0, density = 0;
  for (std::size_t i = 0; i < body; ++i) {
    volume += m.particles.volume[i];
  }
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      density += 0.5 * expected[a][b] * eps[a][b];
    }
  }
  EXPECT_NEAR(f->strain_energy(y.data()) / volume / density, 1.0, 1e-5);
  // No force on a particle whose neighbours are all body particles (one horizon inside): their
  // ghost-completed weights are the bulk's, so B = A and the family's ±ξ pairs cancel.
  std::vector<double> b(3 * m.size());
  f->compute(y.data(), b.data());
  const double delta = m.horizon();
  const double force_scale = scale / lambda;
  double worst_force = 0;
  int interior = 0;
  for (std::size_t i = 0; i < body; ++i) {
    const auto& x = m.particles.position[i];
    bool inside = true;
    for (int a = 0; a < p.dim; ++a) {
      inside = inside && x[a] > delta && x[a] < 8 * lambda - delta;
    }
    if (!inside) {
      continue;
    }
    ++interior;
    for (int c = 0; c < 3; ++c) {
      worst_force = std::max(worst_force, std::abs(b[3 * i + c]));
    }
  }
  ASSERT_GT(interior, 0);
  EXPECT_LT(worst_force / force_scale, 1e-6);
}

INSTANTIATE_TEST_SUITE_P(Settings, FibreHomogeneous,
                         ::testing::Values(Setting{3, pd::PlaneMode::plane_stress, 0.1},
                                           Setting{3, pd::PlaneMode::plane_stress, 0.45},
                                           Setting{2, pd::PlaneMode::plane_strain, 0.3},
                                           Setting{2, pd::PlaneMode::plane_stress, 0.1}));

TEST(FibreKernel, ForceIsMinusTheEnergyGradient) {
  // A free block without corrections, deformed non-uniformly: b_i V_i = −∂E/∂y_i.
  pd::Model m = pd::build_model(block(3, pd::PlaneMode::plane_stress, 0.12,
                                      pd::SurfaceCorrection::none, pd::VolumeCorrection::none, 5));
  auto f = pd::make_force_evaluator(m);
  std::vector<double> y(3 * m.size());
  for (std::size_t i = 0; i < m.size(); ++i) {
    const auto& x = m.particles.position[i];
    for (std::size_t c = 0; c < 3; ++c) {
      y[3 * i + c] = x[c] + 1e-4 * std::sin(37.0 * x[0] + 11.0 * x[c] + 5.0 * x[1] * x[2] * 1e3);
    }
  }
  std::vector<double> b(3 * m.size());
  f->compute(y.data(), b.data());
  double worst = 0, largest = 0;
  for (std::size_t i = 0; i < m.size(); i += 17) {
    for (std::size_t c = 0; c < 3; ++c) {
      const double h = 1e-8;
      auto yp = y, ym = y;
      yp[3 * i + c] += h;
      ym[3 * i + c] -= h;
      const double grad = (f->strain_energy(yp.data()) - f->strain_energy(ym.data())) / (2 * h);
      const double force = b[3 * i + c] * m.particles.volume[i];
      worst = std::max(worst, std::abs(force + grad));
      largest = std::max(largest, std::abs(force));
    }
  }
  ASSERT_GT(largest, 0.0);
  EXPECT_LT(worst / largest, 1e-5);
}

TEST(FibreKernel, AtAQuarterPoissonRatioItIsThePairModelOfItsStiffnessBound) {
  // Eq. 82: NK − G(N+2) = 0 at ν = 1/4 in 3D, so the arm tension is (A + B) G(N+2) ε: exactly the
  // bond-based force with the per-bond field fibre_stiffness_bound fills (up to rounding).
  pd::Model m = pd::build_model(block(3, pd::PlaneMode::plane_stress, 0.25,
                                      pd::SurfaceCorrection::none, pd::VolumeCorrection::none, 5));
  auto fibres = pd::make_force_evaluator(m);
  std::vector<double> y(3 * m.size());
  for (std::size_t i = 0; i < m.size(); ++i) {
    for (std::size_t c = 0; c < 3; ++c) {
      y[3 * i + c] = m.particles.position[i][c] * (1 + 1e-4 * static_cast<double>(c + 1)) +
                     1e-6 * std::cos(static_cast<double>(i + c));
    }
  }
  std::vector<double> b_fibre(3 * m.size()), b_pair(3 * m.size());
  fibres->compute(y.data(), b_fibre.data());
  pd::Model pair = m;
  pair.effects.bond_model = pd::BondModel::micro_elastic;
  pd::make_force_evaluator(pair, pd::KernelPath::scalar)->compute(y.data(), b_pair.data());
  double worst = 0, largest = 0;
  for (std::size_t d = 0; d < b_fibre.size(); ++d) {
    worst = std::max(worst, std::abs(b_fibre[d] - b_pair[d]));
    largest = std::max(largest, std::abs(b_pair[d]));
  }
  EXPECT_LT(worst / largest, 1e-10);
  // Away from ν = 1/4 the bound stays above: the time step shrinks as K grows.
  EXPECT_GT(pd::stable_time_step(m), 0.0);
  pd::Model stiff =
      pd::build_model(block(3, pd::PlaneMode::plane_stress, 0.45, pd::SurfaceCorrection::none,
                            pd::VolumeCorrection::none, 5));
  EXPECT_LT(pd::stable_time_step(stiff), pd::stable_time_step(m));
}

TEST(FibreKernel, RefusesDamageWithoutPlasticity) {
  // Arms fail by their plastic elongation (eq. 118): damage alone has nothing to break on.
  pd::ModelSpec s = block(3, pd::PlaneMode::plane_stress, 0.3, pd::SurfaceCorrection::none,
                          pd::VolumeCorrection::none, 4);
  s.effects.damage = true;
  s.materials[0].elongation_limit = 1e-5;
  pd::Model m = pd::build_model(s);
  EXPECT_THROW(pd::make_fibre_evaluator(m), std::logic_error);
}

} // namespace

namespace {

/// Two particles 1 λ apart, one arm: A = B = N/λ (the arm is each particle's whole weighted
/// length), ε̄ = ε at both ends.
pd::Model one_arm(bool damage) {
  pd::ModelSpec s = block(3, pd::PlaneMode::plane_stress, 0.3, pd::SurfaceCorrection::none,
                          pd::VolumeCorrection::none);
  s.lattice.horizon_factor = 1.5;
  s.bodies.front().region.boxes = {pd::Box{{0, 0, 0}, {2 * lambda, lambda, lambda}}};
  s.effects.plasticity = true;
  s.effects.damage = damage;
  s.materials.front().yield_stretch = 1e-3;
  s.materials.front().elongation_limit = 1.5e-3 * lambda;
  return pd::build_model(s);
}

/// Force density on particle 0 along x with the arm at strain ε.
double pull(pd::Model& m, pd::ForceEvaluator& f, double strain) {
  std::vector<double> y(6), b(6);
  for (std::size_t i = 0; i < 2; ++i) {
    for (std::size_t c = 0; c < 3; ++c) {
      y[3 * i + c] = m.particles.position[i][c];
    }
  }
  y[3] += strain * lambda;
  f.compute(y.data(), b.data());
  return b[0];
}

TEST(FibreKernel, ArmsAreElasticPerfectlyPlastic) {
  pd::Model m = one_arm(false);
  ASSERT_EQ(m.family.directed_bond_count(), 2U);
  auto f = pd::make_force_evaluator(m);
  const pd::FibreModuli k = pd::fibre_moduli(m.spec.dimension, E, 0.3);
  // b_0 = (A S_0 + B S_1) with A = B = 3/λ and S = G(N+2)(ε − ε^p) + (NK − G(N+2)) ε (eq. 110).
  const auto expected = [&](double strain, double plastic) {
    return 2 * 3 / lambda * (k.shear * (strain - plastic) + k.volumetric * strain);
  };
  const double y = 1e-3;
  // Eq. 111 along a loading path: elastic, yield in tension, elastic unloading, yield in
  // compression.
  const double path[][2] = {{0.5 * y, 0.0}, {3 * y, 2 * y}, {2.5 * y, 2 * y}, {0.0, 1 * y}};
  for (const auto& [strain, plastic] : path) {
    const double b = pull(m, *f, strain);
    EXPECT_NEAR(m.state.plastic_stretch[0], plastic, 1e-12)
        << "strain " << strain; // ε from positions
    EXPECT_EQ(m.state.plastic_stretch[0], m.state.plastic_stretch[1]);
    EXPECT_NEAR(b / expected(strain, plastic), 1.0, 1e-6) << "strain " << strain;
  }
}

TEST(FibreKernel, ArmsFailAtTheirElongationLimit) {
  pd::Model m = one_arm(true);
  auto f = pd::make_force_evaluator(m);
  // δ_e = 1.5 ε_y λ: plastic strain 1e-3 at ε = 2e-3 keeps the arm, 2e-3 at ε = 3e-3 breaks it
  // (eq. 118), for good, with damage index 1 = 1 − φ (eq. 119).
  EXPECT_GT(pull(m, *f, 2e-3), 0.0);
  EXPECT_EQ(m.state.broken[0], 0);
  EXPECT_EQ(m.state.damage[0], 0.0);
  EXPECT_EQ(pull(m, *f, 3e-3), 0.0);
  EXPECT_EQ(m.state.broken[0], 1);
  EXPECT_EQ(m.state.broken[1], 1);
  EXPECT_EQ(m.state.damage[0], 1.0);
  EXPECT_EQ(m.state.damage[1], 1.0);
  EXPECT_EQ(pull(m, *f, 0.0), 0.0);
}

} // namespace

namespace {

TEST(FibreKernel, InAQuasiStaticIncrementPlasticStrainDependsOnTheCurrentStrainOnly) {
  // quasi_static.cpp sets the increment's starting plastic stretch: an excursion of the
  // relaxation past the equilibrium (ε = 4 ε_y, then back to 2.5 ε_y) must leave what the
  // equilibrium alone gives (ε^p = 1.5 ε_y), not the excursion's 3 ε_y.
  const double y = 1e-3;
  pd::Model m = one_arm(false);
  auto f = pd::make_force_evaluator(m);
  m.state.plastic_stretch_at_increment_start.assign(2, 0.0);
  pull(m, *f, 4 * y);
  EXPECT_NEAR(m.state.plastic_stretch[0], 3 * y, 1e-12);
  const double b = pull(m, *f, 2.5 * y);
  EXPECT_NEAR(m.state.plastic_stretch[0], 1.5 * y, 1e-12);
  EXPECT_EQ(m.state.plastic_stretch[1], m.state.plastic_stretch[0]);
  pd::Model direct = one_arm(false);
  auto g = pd::make_force_evaluator(direct);
  EXPECT_EQ(b, pull(direct, *g, 2.5 * y));
  // Without it (dynamic runs) the plastic stretch is history: the excursion stays.
  m.state.plastic_stretch_at_increment_start.clear();
  pull(m, *f, 4 * y);
  pull(m, *f, 2.5 * y);
  EXPECT_NEAR(m.state.plastic_stretch[0], 3 * y, 1e-12);
}

} // namespace
