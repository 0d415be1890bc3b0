// Irregular particle sets (scenes/irregular.yaml): positions jittered by up to 0.3 λ, volumes
// varied by ±50 %.
//
// What must hold with dt: auto:
//  * the automatic step is eq. 31 over the actual (jittered) bond lengths and neighbour volumes:
//    it equals eq. 31 recomputed from scratch (own O(N²) neighbour search);
//  * it is still a safe bound: the measured stability limit is not below it;
//  * the undamped run stays finite and its energy behaves as velocity Verlet's must
//    (stab::check_verlet_energy: never above E(0), dip within (ω_max Δt)²/4, shrinking as Δt²).
// The irregular set with damage is exercised by the cascade (cascade_test.cpp).
#include "libpd/time/stability.hpp"
#include "libpd/kernel/stable_time_step.hpp"
#include "stability_support.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace {

struct IrregularCase {
  double spacing;
  double probe_spacing;
  std::size_t steps;
  unsigned seed;
};

void run_irregular(const IrregularCase& ic) {
  pd::Scene scene = stab::load("irregular.yaml");
  scene.model.lattice.spacing = ic.spacing;
  scene.model.lattice.seed = ic.seed;
  scene.solver.max_steps = ic.steps;
  pd::Model model = pd::build_model(scene.model);
  ASSERT_TRUE(model.field.per_bond()) << "varying volumes need the per-bond field";
  const double eq31 = pd::stable_time_step(model);
  EXPECT_NEAR(eq31, stab::eq31_from_scratch(model), 1e-12 * eq31);

  // The regular lattice's step, for the record: the jitter shortens some bonds, so it drops.
  pd::Scene regular = scene;
  regular.model.lattice.position_jitter = 0;
  regular.model.lattice.volume_variation = 0;
  const double eq31_regular = pd::stable_time_step(pd::build_model(regular.model));

  pd::Scene probe = scene;
  probe.model.lattice.spacing = ic.probe_spacing;
  pd::StabilityOptions opt;
  opt.steps = 500;
  opt.relative_tolerance = 0.02;
  const pd::StabilityResult st =
      pd::measure_stability(probe.model, probe.solver, pd::StabilityTarget{pd::IntegratorKind::verlet}, opt);
  EXPECT_GE(st.measured, st.eq31) << "eq. 31 is not a safe bound on the irregular set";

  const stab::EnergyCheck ec = stab::check_verlet_energy(scene, ic.steps);
  fmt::print("irregular λ={:g} seed {}: {} particles, eq31 {:.4g} s (regular lattice {:.4g} s), "
             "measured limit {:.4g} s = {:.3f} x eq31 (probe λ={:g}, bisection {:.2f} s); {}\n",
             ic.spacing, ic.seed, model.size(), eq31, eq31_regular, st.measured,
             st.measured / st.eq31, ic.probe_spacing, st.seconds, ec.summary());
}

TEST(StabilityIrregular, JitterAndVolumes) {
  run_irregular({0.002, 0.004, 800, 7});
}
TEST(StabilityIrregularFull, JitterAndVolumes) {
  run_irregular({0.001, 0.002, 1200, 7});
}
TEST(StabilityIrregularFull, OtherSeed) {
  run_irregular({0.001, 0.002, 1200, 12345});
}

} // namespace
