// solver.integrator: static (issue 15, first landing): the one sparse solve refined by Newton
// agrees with dynamic relaxation's steady state, its operator is symmetric under consistent
// mirror coupling, and what it cannot do (damage) is refused.
#include "libpd/app/run.hpp"
#include "libpd/io/scene.hpp"

#include <cmath>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <regex>
#include <string>

namespace {

/// A small 3D cantilever (λ = h/4), clamped by a mirror at x = 0, tip load down.
std::string cantilever(const std::string& integrator, const std::string& coupling) {
  return fmt::format(R"(title: small cantilever
dimension: 3
lattice:
  spacing: 0.025
materials:
  steel:
    youngs_modulus: 200e9
    density: 7850
bodies:
  - name: beam
    material: steel
    box: [[0, 0, 0], [0.6, 0.1, 0.1]]
  - name: clamp
    material: steel
    box: [[-0.1, 0, 0], [0, 0.1, 0.1]]
supports:
  - name: clamp
    box: [[-0.1, 0, 0], [0, 0.1, 0.1]]
    mirror: {{x: 0}}
loads:
  - name: tip
    box: [[0.575, 0, 0], [0.6, 0.1, 0.1]]
    value: [0, 0, -2e4]
model:
  mirror_coupling: {}
solver:
  integrator: {}
  end_time: 1e6
  steady:
    kinetic_tolerance: 1e-16
    force_tolerance: 1e-9
    check_every: 50
probes:
  - name: tip
    box: [[0.575, 0, 0], [0.6, 0.1, 0.1]]
    component: z
)",
                     coupling, integrator);
}

pd::RunOutcome run(const std::string& text) {
  const pd::Scene scene = pd::parse_scene(text, "cantilever.yaml");
  pd::RunOptions opt;
  opt.stop_on_interrupt = false;
  return pd::run_scene(scene, opt);
}

TEST(StaticSolver, AgreesWithDynamicRelaxation) {
  for (const std::string coupling : {"copy", "consistent"}) {
    SCOPED_TRACE(coupling);
    const pd::RunOutcome s = run(cantilever("static", coupling));
    const pd::RunOutcome a = run(cantilever("adr", coupling));
    ASSERT_EQ(s.result.status, pd::RunStatus::converged) << s.result.message;
    ASSERT_EQ(a.result.status, pd::RunStatus::converged) << a.result.message;
    const double ws = s.probes.at("tip"), wa = a.probes.at("tip");
    EXPECT_LT(ws, 0);
    EXPECT_NEAR(ws / wa, 1.0, 1e-6) << "static " << ws << ", adr " << wa;
    // The static run needs a handful of force evaluations, dynamic relaxation thousands.
    EXPECT_LT(s.result.force_evaluations, 20u);
  }
}

TEST(StaticSolver, ConsistentMirrorCouplingGivesASymmetricOperator) {
  const pd::RunOutcome s = run(cantilever("static", "consistent"));
  std::smatch m;
  ASSERT_TRUE(std::regex_search(s.result.message, m,
                                std::regex(R"((\w+) operator, ‖K−Kᵀ‖/‖K‖ = ([0-9.e+-]+))")))
      << s.result.message;
  EXPECT_EQ(m[1].str(), "symmetric");
  EXPECT_LE(std::stod(m[2]), 1e-12);
  // A Cholesky factorisation: CHOLMOD's, or Eigen's where libpd is built without SuiteSparse.
  EXPECT_TRUE(s.result.message.find("CHOLMOD supernodal LLT") != std::string::npos ||
              s.result.message.find("Eigen SimplicialLDLT") != std::string::npos)
      << s.result.message;
  const pd::Json* details = s.summary.find("integrator_details");
  ASSERT_NE(details, nullptr);
  EXPECT_GT(details->find("factor_bytes")->number().value_or(0), 0);
}

TEST(StaticSolver, RefusesDamage) {
  std::string text = cantilever("static", "copy");
  text.replace(text.find("    density: 7850\n"), 18,
               "    density: 7850\n    critical_stretch: 1e-3\n");
  text += "effects: [damage]\n";
  EXPECT_THROW(run(text), std::invalid_argument);
}

} // namespace
