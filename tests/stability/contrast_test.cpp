// Stiffness contrast 100× and 1000× between two halves of a free block (scenes/contrast.yaml).
//
// What must hold with dt: auto:
//  * the automatic step is Miranda eq. 31 minimised over particles, so it follows the stiffest
//    bonds: it equals eq. 31 recomputed here from scratch (own neighbour search, own c), and for a
//    particle whose whole family is stiff it is the soft material's step / sqrt(factor);
//  * eq. 31 is a safe bound: the measured stability limit (bisection, `measure_stability`) is not
//    below it, while it is below the soft material's eq. 31 step — a step chosen from the soft
//    material alone would blow up;
//  * the undamped run stays finite and its energy behaves as velocity Verlet's must with no
//    loads and no supports (stab::check_verlet_energy): never above E(0), dips bounded by
//    (ω_max Δt)²/4 and shrinking as Δt² when the step is halved.
#include "libpd/time/stability.hpp"
#include "libpd/kernel/stable_time_step.hpp"
#include "stability_support.hpp"

#include <cmath>
#include <fmt/format.h>
#include <gtest/gtest.h>

namespace {

struct ContrastCase {
  double factor;
  double spacing;       ///< λ of the energy run
  double probe_spacing; ///< λ of the stability measurement (a bisection of many runs)
  std::size_t steps;
};

pd::Scene contrast_scene(double factor, double spacing, std::size_t steps) {
  pd::Scene s = stab::load("contrast.yaml");
  s.model.materials.at(1).stiffness_factor = factor;
  s.model.lattice.spacing = spacing;
  s.solver.max_steps = steps;
  return s;
}

void run_contrast(const ContrastCase& cc) {
  const double sqrt_factor = std::sqrt(cc.factor);

  // 1. dt: auto follows the stiffest bond.
  pd::Scene scene = contrast_scene(cc.factor, cc.spacing, cc.steps);
  pd::Model model = pd::build_model(scene.model);
  const double eq31 = pd::stable_time_step(model);
  EXPECT_NEAR(eq31, stab::eq31_from_scratch(model), 1e-12 * eq31);
  pd::Scene soft_scene = scene;
  soft_scene.model.materials.at(1).stiffness_factor = 1.0;
  const pd::Model soft_model = pd::build_model(soft_scene.model);
  const double eq31_soft = pd::stable_time_step(soft_model);
  // The stiff half is 16 λ wide and tall at this resolution, so it has particles whose whole
  // family is stiff: for them eq. 31 is exactly the homogeneous value / sqrt(factor), and they
  // govern (the homogeneous minimum is also at a full-family particle, with the same sum).
  const double ratio = eq31_soft / eq31;
  EXPECT_NEAR(ratio, sqrt_factor, 1e-9 * sqrt_factor)
      << "the automatic step does not follow the stiff bonds";

  // 2. The bound is safe, and needed: measured limit ≥ eq. 31, and < the soft material's step.
  pd::Scene probe = contrast_scene(cc.factor, cc.probe_spacing, cc.steps);
  pd::StabilityOptions opt;
  opt.steps = 500;
  opt.relative_tolerance = 0.02;
  const pd::StabilityResult st =
      pd::measure_stability(probe.model, probe.solver, pd::StabilityTarget{pd::IntegratorKind::verlet}, opt);
  pd::Scene probe_soft = probe;
  probe_soft.model.materials.at(1).stiffness_factor = 1.0;
  const double probe_eq31_soft = pd::stable_time_step(pd::build_model(probe_soft.model));
  EXPECT_GE(st.measured, st.eq31) << "eq. 31 is not a safe bound here";
  EXPECT_LT(st.unstable, probe_eq31_soft / 2.0)
      << "the soft material's step should be far beyond the stiff limit";
  EXPECT_LE(st.measured, st.sharp * 1.02) << "measured beyond the sharp 2/ω_max prediction";

  // 3. The undamped run with dt: auto: finite, and its energy behaves as velocity Verlet's must.
  const stab::EnergyCheck ec = stab::check_verlet_energy(scene, cc.steps);
  EXPECT_NEAR(ec.dt, 0.8 * eq31, 1e-12 * eq31);
  fmt::print("contrast {:g}x: {} particles, eq31 {:.4g} s (soft {:.4g} s, ratio {:.4f}), "
             "measured limit {:.4g} s = {:.3f} x eq31 (sharp {:.4g} s, probe soft eq31 {:.4g} s), "
             "bisection {:.2f} s; "
             "{}\n",
             cc.factor, model.size(), eq31, eq31_soft, ratio, st.measured, st.measured / st.eq31,
             st.sharp, probe_eq31_soft, st.seconds, ec.summary());
}

TEST(StabilityContrast, Factor100) {
  run_contrast({100.0, 0.002, 0.004, 800});
}
TEST(StabilityContrast, Factor1000) {
  run_contrast({1000.0, 0.002, 0.004, 800});
}
TEST(StabilityContrastFull, Factor100) {
  run_contrast({100.0, 0.001, 0.002, 1200});
}
TEST(StabilityContrastFull, Factor1000) {
  run_contrast({1000.0, 0.001, 0.002, 1200});
}

} // namespace
