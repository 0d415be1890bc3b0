// Long undamped runs (scenes/bar-long.yaml): 10^5 velocity Verlet steps of the clamped bar with
// dt: auto (the fast subset runs 2·10^4). Nothing injects or removes energy, so E(t) = E(0) up to
// the integrator: velocity Verlet is symplectic, its energy error oscillates with bounded
// amplitude O((ωΔt)²) and does not accumulate. Measured: the largest |E − E0|/E0 over the run
// (gate ≤ 1e-3, the bound) and the secular drift, the change of the mean energy between
// the first and the last tenth of the run (which for a symplectic scheme is round-off only).
#include "libpd/kernel/stable_time_step.hpp"
#include "stability_support.hpp"

#include <cmath>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <numeric>

namespace {

void run_long(std::size_t steps) {
  pd::Scene scene = stab::load("bar-long.yaml");
  scene.solver.max_steps = steps;
  pd::Model model = pd::build_model(scene.model);
  const stab::Trace tr = stab::run_traced(model, scene, 100);
  EXPECT_EQ(tr.result.status, pd::RunStatus::max_steps) << tr.result.message;
  EXPECT_EQ(tr.result.steps, steps);
  EXPECT_TRUE(tr.finite);
  EXPECT_EQ(tr.work, 0.0) << "fixed supports do no work";
  ASSERT_GT(tr.e0, 0.0);
  const double max_dev = tr.max_deviation / tr.e0;
  EXPECT_LE(max_dev, 1e-3);
  // Started from rest, Verlet's sampled energy never exceeds E0 in a linear system (see
  // stab::check_verlet_energy); beyond round-off it would be growth.
  EXPECT_LE(tr.max_excess / tr.e0, 1e-5) << "energy grew";

  const std::size_t tenth = tr.balance.size() / 10;
  ASSERT_GT(tenth, 0u);
  const double first =
      std::accumulate(tr.balance.begin(), tr.balance.begin() + static_cast<std::ptrdiff_t>(tenth),
                      0.0) /
      static_cast<double>(tenth);
  const double last = std::accumulate(tr.balance.end() - static_cast<std::ptrdiff_t>(tenth),
                                      tr.balance.end(), 0.0) /
                      static_cast<double>(tenth);
  const double drift = std::abs(last - first) / tr.e0;
  EXPECT_LE(drift, 1e-3);
  // The free-end period of the continuum bar is 4L/c; report how many the run covers.
  const double period = 4.0 / std::sqrt(200e9 / 7850.0);
  fmt::print(
      "long run: {} steps of {:.5g} s (eq31 {:.5g} s), {:.1f} periods, "
      "max |E-E0|/E0 = {:.3e}, max (E-E0)/E0 = {:.2e}, secular drift = {:.3e}, run {:.2f} s\n",
      tr.result.steps, tr.result.dt, tr.result.dt_stable, tr.result.time / period, max_dev,
      tr.max_excess / tr.e0, drift, tr.seconds);
}

TEST(StabilityLongRun, Bar20kSteps) {
  run_long(20'000);
}
TEST(StabilityLongRunFull, Bar100kSteps) {
  run_long(100'000);
}

} // namespace
