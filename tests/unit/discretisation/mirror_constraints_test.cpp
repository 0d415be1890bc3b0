// Variationally consistent mirror supports (issue 14, item 1): the linearised constrained operator
// is symmetric, the integrators' forces are its action, and an undamped Verlet run with mirror
// clamps conserves energy for every surface/volume correction pair.
#include "libpd/discretisation/mirror_constraints.hpp"
#include "libpd/kernel/linear_operator.hpp"
#include "libpd/time/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <random>
#include <string>
#include <vector>

namespace {

constexpr double lambda = 1.0;

const pd::SurfaceCorrection all_surface[] = {
    pd::SurfaceCorrection::none, pd::SurfaceCorrection::volume, pd::SurfaceCorrection::energy,
    pd::SurfaceCorrection::macek_silling, pd::SurfaceCorrection::tensor};
const pd::VolumeCorrection all_volume[] = {pd::VolumeCorrection::none, pd::VolumeCorrection::linear,
                                           pd::VolumeCorrection::exact,
                                           pd::VolumeCorrection::moment};

/// A short beam (3D: 9λ × 3λ × 3λ, 2D: 9λ × 4λ) on x ∈ [0, 9λ], with a 3λ block beyond x = 0
/// mirrored across x = 0 (the structural scenes' clamp), m = 3.
pd::ModelSpec clamped_beam(int dim, pd::SurfaceCorrection s, pd::VolumeCorrection v) {
  pd::ModelSpec spec;
  spec.dimension.dim = dim;
  spec.dimension.thickness = 1.0;
  spec.lattice.spacing = lambda;
  spec.lattice.horizon_factor = 3.0;
  pd::Material mat;
  mat.youngs_modulus = 1e9;
  mat.density = 1000;
  spec.materials = {mat};
  const double depth = dim == 3 ? 3 * lambda : 4 * lambda;
  pd::BodySpec body;
  body.region.boxes = {
      pd::Box{{-3 * lambda, 0, 0}, {9 * lambda, depth, dim == 3 ? 3 * lambda : 0.0}}};
  spec.bodies = {body};
  pd::SupportSpec clamp;
  clamp.name = "clamp";
  clamp.region.boxes = {pd::Box{{-3 * lambda, 0, 0}, {0, depth, dim == 3 ? 3 * lambda : 0.0}}};
  clamp.mirror[0] = true;
  clamp.mirror_at = {0, 0, 0};
  spec.supports = {clamp};
  spec.surface_correction = s;
  spec.volume_correction = v;
  spec.mirror_coupling = pd::MirrorCoupling::consistent; // the coupling under test (not default)
  return spec;
}

std::vector<std::uint8_t> free_dofs(const pd::Model& m) {
  std::vector<std::uint8_t> free(3 * m.size(), 1);
  for (const pd::Constraint& c : m.constraints) {
    free[3 * c.particle + c.component] = 0;
  }
  for (std::size_t d = 0; d < free.size(); ++d) {
    if (static_cast<int>(d % 3) >= m.spec.dimension.dim) {
      free[d] = 0;
    }
  }
  return free;
}

/// ‖K − Kᵀ‖_F / ‖K‖_F of an operator on the free dofs, in force units (rows × V_i), assembled
/// column by column by `apply(u, ku)` with u a unit vector.
template <class Apply>
double asymmetry(const pd::Model& m, Apply apply) {
  const auto free = free_dofs(m);
  std::vector<std::size_t> dofs;
  for (std::size_t d = 0; d < free.size(); ++d) {
    if (free[d]) {
      dofs.push_back(d);
    }
  }
  const std::size_t n = dofs.size();
  std::vector<double> k(n * n), u(3 * m.size()), ku(3 * m.size());
  for (std::size_t col = 0; col < n; ++col) {
    std::fill(u.begin(), u.end(), 0.0);
    u[dofs[col]] = 1.0;
    apply(u.data(), ku.data());
    for (std::size_t row = 0; row < n; ++row) {
      k[row * n + col] = ku[dofs[row]] * m.particles.volume[dofs[row] / 3];
    }
  }
  double diff = 0, norm = 0;
  for (std::size_t r = 0; r < n; ++r) {
    for (std::size_t c = 0; c < n; ++c) {
      const double a = k[r * n + c], b = k[c * n + r];
      diff += (a - b) * (a - b);
      norm += a * a;
    }
  }
  return std::sqrt(diff / norm);
}

TEST(MirrorConstraints, BondWeightsCountSupportBondsHalfAndImageBondsNot) {
  const pd::Model m =
      pd::build_model(clamped_beam(3, pd::SurfaceCorrection::none, pd::VolumeCorrection::none));
  const auto dependent = pd::mirror_dependent_particles(m.size(), m.constraints);
  const auto w = pd::mirror_bond_weights(m.family, dependent);
  int seen[3] = {0, 0, 0};
  for (std::size_t i = 0; i < m.size(); ++i) {
    for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
      const std::size_t j = m.family.neighbour[k];
      const int ends = (dependent[i] ? 0 : 1) + (dependent[j] ? 0 : 1);
      EXPECT_EQ(w[k], 0.5 * ends);
      ++seen[ends];
    }
  }
  // Bonds between two supports carry weight 0 and leave the family (build_model): none is left.
  EXPECT_EQ(seen[0], 0);
  EXPECT_GT(seen[1], 0);
  EXPECT_GT(seen[2], 0);
}

TEST(MirrorConstraints, LinearisedConstrainedOperatorIsSymmetric) {
  for (int dim : {2, 3}) {
    for (pd::SurfaceCorrection s : {pd::SurfaceCorrection::tensor, pd::SurfaceCorrection::energy}) {
      for (pd::VolumeCorrection v : {pd::VolumeCorrection::moment, pd::VolumeCorrection::linear}) {
        const pd::Model m = pd::build_model(clamped_beam(dim, s, v));
        const double consistent =
            asymmetry(m, [&](double* u, double* ku) { pd::apply_constrained_operator(m, u, ku); });
        EXPECT_LE(consistent, 1e-12) << "dim " << dim;
        // The former operator K_ff + K_fs R (dependants' forces dropped) on the same model: the
        // measure does see the difference.
        const double one_sided = asymmetry(m, [&](double* u, double* ku) {
          for (const pd::Constraint& c : m.constraints) {
            u[3 * c.particle + c.component] = c.mirror_sign * u[3 * c.mirror_of + c.component];
          }
          pd::apply_linearised_operator(m, u, ku);
        });
        EXPECT_GT(one_sided, 1e-3) << "dim " << dim;
      }
    }
  }
}

TEST(MirrorConstraints, SimulationForcesAreTheConstrainedOperator) {
  // The forces every integrator gets (Simulation's evaluator) linearise to −Rᵀ K R on the free
  // dofs: central differences of a small displacement against apply_constrained_operator.
  pd::Model m =
      pd::build_model(clamped_beam(3, pd::SurfaceCorrection::tensor, pd::VolumeCorrection::moment));
  auto forces = pd::make_constrained_force_evaluator(m);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  std::vector<double> u(3 * m.size());
  for (double& x : u) {
    x = dist(rng);
  }
  const double h = 1e-6 * lambda;
  std::vector<double> yp(3 * m.size()), ym(3 * m.size()), bp(3 * m.size()), bm(3 * m.size());
  std::vector<double> uc = u, ku(3 * m.size());
  pd::apply_constrained_operator(m, uc.data(), ku.data());
  for (std::size_t d = 0; d < u.size(); ++d) {
    const double x = m.particles.position[d / 3][d % 3];
    yp[d] = x + h * uc[d];
    ym[d] = x - h * uc[d];
  }
  forces->compute(yp.data(), bp.data());
  forces->compute(ym.data(), bm.data());
  const auto free = free_dofs(m);
  double diff = 0, norm = 0;
  for (std::size_t d = 0; d < u.size(); ++d) {
    if (free[d]) {
      const double fd = (bp[d] - bm[d]) / (2 * h);
      diff += (fd + ku[d]) * (fd + ku[d]);
      norm += ku[d] * ku[d];
    }
  }
  EXPECT_LE(std::sqrt(diff / norm), 1e-6);
}

TEST(MirrorConstraints, CopyCouplingIsTheOneSidedClamp) {
  // The scene default `copy` keeps the operator the structural scenes were calibrated on: full
  // bond weights, nothing folded (K_ff + K_fs R), the support particles keep their mass.
  auto spec = clamped_beam(3, pd::SurfaceCorrection::tensor, pd::VolumeCorrection::moment);
  const pd::Model consistent = pd::build_model(spec);
  spec.mirror_coupling = pd::MirrorCoupling::copy;
  const pd::Model copy = pd::build_model(spec);
  EXPECT_FALSE(pd::consistent_mirror_coupling(copy));
  EXPECT_TRUE(pd::consistent_mirror_coupling(consistent));
  const auto massless = pd::massless_dependants(copy);
  EXPECT_EQ(std::count(massless.begin(), massless.end(), 1), 0);
  // Bond by bond (i, j): the consistent model's family lacks the weight-0 support–support bonds,
  // which build_model drops, so the two families are matched by their ends.
  const auto weight = pd::mirror_bond_weights(
      copy.family, pd::mirror_dependent_particles(copy.size(), copy.constraints));
  std::size_t matched = 0;
  for (std::size_t i = 0; i < copy.size(); ++i) {
    std::size_t kc = consistent.family.offsets[i];
    for (std::size_t k = copy.family.offsets[i]; k < copy.family.offsets[i + 1]; ++k) {
      if (weight[k] == 0) {
        continue;
      }
      ASSERT_LT(kc, consistent.family.offsets[i + 1]);
      ASSERT_EQ(consistent.family.neighbour[kc], copy.family.neighbour[k]);
      ASSERT_DOUBLE_EQ(consistent.field.bond_stiffness[kc],
                       weight[k] * copy.field.bond_stiffness[k]);
      ++kc;
      ++matched;
    }
    ASSERT_EQ(kc, consistent.family.offsets[i + 1]);
  }
  EXPECT_EQ(matched, consistent.family.directed_bond_count());
  const double one_sided =
      asymmetry(copy, [&](double* u, double* ku) { pd::apply_constrained_operator(copy, u, ku); });
  EXPECT_GT(one_sided, 1e-3);
}

/// Largest relative change of Verlet's conserved energy over 10^4 undamped steps from a random
/// small displacement (every mode excited) with a mirror clamp.
double verlet_energy_drift(int dim, pd::SurfaceCorrection s, pd::VolumeCorrection v) {
  pd::Model m = pd::build_model(clamped_beam(dim, s, v));
  pd::SolverSpec solver;
  solver.integrator = pd::IntegratorKind::verlet;
  solver.safety = 0.5;
  solver.max_steps = 10'000;
  pd::Simulation sim(m, solver);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  std::vector<double> du(3 * m.size(), 0.0);
  for (std::size_t d = 0; d < du.size(); ++d) {
    if (static_cast<int>(d % 3) < dim) {
      du[d] = 1e-6 * lambda * dist(rng); // stretches ~1e-6: linear, far above round-off
    }
  }
  sim.perturb(du);
  const auto massless = pd::mirror_dependent_particles(m.size(), m.constraints);
  // Velocity Verlet conserves H = T − (Δt²/8) aᵀM a + W exactly for a symmetric linear operator
  // (½ v_{n−½}ᵀ M v_{n+½} + W, the leapfrog invariant); T + W itself oscillates by O((ωΔt)²).
  // State::force is the force at the current positions after every step.
  const auto energy = [&](const pd::Simulation& x) {
    double correction = 0;
    const double dt = x.dt();
    for (std::size_t i = 0; i < m.size(); ++i) {
      if (massless[i]) {
        continue;
      }
      for (int c = 0; c < dim; ++c) {
        const double b = x.state().force[3 * i + c];
        correction += m.particles.volume[i] * b * b / m.density[i];
      }
    }
    return x.kinetic_energy() + x.strain_energy() - dt * dt / 8.0 * correction;
  };
  double e0 = -1, worst = 0;
  const pd::RunResult r = sim.run([&](const pd::Simulation& x) {
    const double e = energy(x);
    if (e0 < 0) {
      e0 = e; // after the first step: the first step primes the force
    }
    worst = std::max(worst, std::abs(e - e0) / e0);
    return true;
  });
  EXPECT_EQ(r.status, pd::RunStatus::max_steps) << r.message;
  return worst;
}

TEST(MirrorConstraints, UndampedVerletConservesEnergyForEveryCorrectionPair) {
  for (int dim : {2, 3}) {
    for (pd::SurfaceCorrection s : all_surface) {
      for (pd::VolumeCorrection v : all_volume) {
        EXPECT_LE(verlet_energy_drift(dim, s, v), 1e-6)
            << "dim " << dim << " surface " << static_cast<int>(s) << " volume "
            << static_cast<int>(v);
      }
    }
  }
}

} // namespace
