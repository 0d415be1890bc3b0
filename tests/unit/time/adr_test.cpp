// Adaptive dynamic relaxation (Kilic & Madenci 2010, libpd/src/time/adr.cpp): the fictitious
// density makes central differences with Δt = 1 stable (ω_max of Λ⁻¹K ≤ 2, checked with the Lanczos
// estimate of libpd/time/stability.hpp), and ADR reaches the same static answer as damped Euler
// under the same steady-state criterion. AdrSlow.* runs the clamped-beam acceptance case against
// the static solve (about 10 s).
#include "libpd/app/run.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/kernel/force_kernel.hpp"
#include "libpd/time/integrator.hpp"
#include "libpd/time/simulation.hpp"
#include "libpd/time/stability.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>
#include <string>
#include <vector>

namespace {

constexpr double lambda = 0.01;

pd::ModelSpec chain(int n, bool load) {
  pd::ModelSpec s;
  s.surface_correction = pd::SurfaceCorrection::none; // the bare model
  s.dimension.dim = 1;
  s.dimension.cross_section = 1e-4;
  s.lattice.spacing = lambda;
  s.lattice.horizon_factor = 3.015;
  s.volume_correction = pd::VolumeCorrection::linear;
  pd::Material mat;
  mat.youngs_modulus = 1e9;
  mat.density = 1000;
  s.materials = {mat};
  pd::BodySpec b;
  b.region.boxes = {pd::Box{{0, 0, 0}, {n * lambda, 0, 0}}};
  s.bodies = {b};
  pd::SupportSpec fix;
  fix.name = "fix";
  fix.region = pd::Region{{pd::Box{{0, 0, 0}, {3 * lambda, 0, 0}}}};
  fix.fixed[0] = true;
  s.supports = {fix};
  if (load) {
    pd::LoadSpec l;
    l.name = "tip";
    l.load.region = pd::Region{{pd::Box{{(n - 1) * lambda, 0, 0}, {n * lambda, 0, 0}}}};
    l.load.value = {100, 0, 0}; // N, total
    s.loads = {l};
  }
  return s;
}

pd::ModelSpec block() {
  pd::ModelSpec s;
  s.surface_correction = pd::SurfaceCorrection::none; // the bare model
  s.dimension.dim = 3;
  s.lattice.spacing = lambda;
  s.lattice.horizon_factor = 3.015;
  pd::Material mat;
  mat.youngs_modulus = 1e9;
  mat.density = 1000;
  s.materials = {mat};
  pd::BodySpec b;
  b.region.boxes = {pd::Box{{0, 0, 0}, {8 * lambda, 6 * lambda, 6 * lambda}}};
  s.bodies = {b};
  pd::SupportSpec fix;
  fix.name = "fix";
  fix.region = pd::Region{{pd::Box{{0, 0, 0}, {lambda, 6 * lambda, 6 * lambda}}}};
  fix.fixed = {true, true, true};
  s.supports = {fix};
  return s;
}

TEST(Adr, FictitiousDensityMakesUnitStepStable) {
  for (const pd::ModelSpec& spec : {chain(40, false), block()}) {
    const pd::Model model = pd::build_model(spec);
    const std::vector<double> lam = pd::adr_fictitious_density(model);
    const pd::FrequencyEstimate f = pd::max_frequency(model, lam);
    // Central differences with Δt = 1 are stable for ω_max ≤ 2 (Gershgorin guarantees it).
    EXPECT_LE(f.omega_max, 2.0) << spec.dimension.dim << "D";
    EXPECT_GT(f.omega_max, 1.0) << spec.dimension.dim << "D: the bound should not be loose";
  }
}

TEST(Adr, Eq31SumAloneWouldBeUnstable) {
  // λ = ¼ Σ_j c V_j/|ξ| (the eq. 31 sum without the factor 2 of the Gershgorin row sum) lets the
  // alternating mode of the 1D chain exceed ω = 2.
  const pd::Model model = pd::build_model(chain(40, false));
  std::vector<double> lam(3 * model.size(), 1.0);
  for (std::size_t i = 0; i < model.size(); ++i) {
    double sum = 0;
    for (std::size_t k = model.family.offsets[i]; k < model.family.offsets[i + 1]; ++k) {
      sum += pd::bond_stiffness(model, k) * model.family.inverse_length[k];
    }
    lam[3 * i] = 0.25 * sum;
  }
  EXPECT_GT(pd::max_frequency(model, lam).omega_max, 2.0);
}

TEST(Adr, ReachesTheDampedEulerSteadyState) {
  pd::SolverSpec solver;
  solver.steady.enabled = true;
  solver.steady.kinetic_tolerance = 1e-14;
  solver.steady.force_tolerance = 1e-8;
  solver.steady.check_every = 20;
  solver.max_steps = 2'000'000;
  double tip[2] = {0, 0};
  std::size_t evaluations[2] = {0, 0};
  for (int run = 0; run < 2; ++run) {
    pd::Model model = pd::build_model(chain(40, true));
    pd::SolverSpec s = solver;
    if (run == 0) {
      s.integrator = pd::IntegratorKind::damped_euler;
      // Near-critical damping of the lowest mode, c_v ≈ 2ρω₁, ω₁ = πc/(2L).
      s.damping = 2 * 1000 * (std::numbers::pi * std::sqrt(1e9 / 1000) / (2 * 0.4));
      model.effects.damping = true;
    } else {
      s.integrator = pd::IntegratorKind::adr;
    }
    pd::Simulation sim(model, s);
    const pd::RunResult r = sim.run();
    ASSERT_EQ(r.status, pd::RunStatus::converged) << r.message;
    tip[run] = sim.displacement(model.size() - 1, 0);
    evaluations[run] = r.force_evaluations;
  }
  EXPECT_NEAR(tip[1], tip[0], 1e-6 * std::abs(tip[0]));
  EXPECT_GT(tip[0], 0);
  RecordProperty("damped_euler_evaluations", std::to_string(evaluations[0]));
  RecordProperty("adr_evaluations", std::to_string(evaluations[1]));
}

TEST(AdrSlow, ClampedBeamMatchesTheStaticSolve) {
  // Acceptance (issues 13 and 15): the clamped beam of Miranda §5.1.1 relaxed by ADR under its
  // steady-state criterion against the static solver's equilibrium (residual 1e-10 of the load).
  // Damped Euler is compared in `pd compare quasistatic`: with the ghosts' 3× smaller stable step
  // it needed 250 s here, which the default test run cannot afford.
  const pd::Scene scene =
      pd::load_scene(std::string(PD_CASES_DIR) + "/clamped-beam/clamped-beam.yaml");
  ASSERT_EQ(scene.solver.integrator, pd::IntegratorKind::static_solve);
  pd::RunOptions opt;
  opt.stop_on_interrupt = false;
  const pd::RunOutcome exact = pd::run_scene(scene, opt);
  pd::Scene adr_scene = scene;
  adr_scene.solver.integrator = pd::IntegratorKind::adr;
  const pd::RunOutcome adr = pd::run_scene(adr_scene, opt);
  ASSERT_EQ(exact.result.status, pd::RunStatus::converged);
  ASSERT_EQ(adr.result.status, pd::RunStatus::converged);
  const double w0 = exact.probes.at("midspan_deflection");
  const double w1 = adr.probes.at("midspan_deflection");
  // ADR stops at residual ≤ 1e-6 of the load; issue 15 asks for the same deflection to 1e-6
  // (measured 2.8e-7).
  EXPECT_NEAR(w1, w0, 1e-6 * std::abs(w0));
  EXPECT_GT(adr.result.force_evaluations, 100 * exact.result.force_evaluations);
}

} // namespace
