// bar-vibration (Pasupathy, Table 1): a bar fixed at x = 0, free at x = L, released from rest
// with u(x, 0) = εx. The wave equation u_tt = c² u_xx (c² = E/ρ) gives the modal series
//   u(x, t) = Σ_n a_n sin(k_n x) cos(c k_n t),  k_n = (2n − 1)π/(2L),
//   a_n = (2/L) ∫₀ᴸ εx sin(k_n x) dx = 2ε(−1)^(n+1)/(L k_n²),
// whose free-end history is a triangle wave of period 4L/c and amplitude εL.
// Gates: period error ≤ 1 %, amplitude error ≤ 2 %, over at least 5 periods.
//
// bar-energy: the same bar, undamped velocity Verlet for 10^4 steps at 0.9 × the eq. 31 step;
// total energy (kinetic + stored) must not drift by more than 1e-4 of its initial value.
#include "libpd/app/run.hpp"
#include "libpd/io/scene.hpp"
#include "verification.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <numbers>

namespace pd::verification {

double bar_modal_series(double x, double t, double strain, double length, double wave_speed) {
  double u = 0;
  for (int n = 1; n <= 4000; ++n) {
    const double k = (2.0 * n - 1.0) * std::numbers::pi / (2.0 * length);
    const double a = 2.0 * strain * ((n % 2) ? 1.0 : -1.0) / (length * k * k);
    u += a * std::sin(k * x) * std::cos(wave_speed * k * t);
  }
  return u;
}

namespace {

/// Times where the signal changes sign, by linear interpolation.
std::vector<double> zero_crossings(const std::vector<double>& t, const std::vector<double>& u) {
  std::vector<double> out;
  for (std::size_t i = 1; i < u.size(); ++i) {
    if ((u[i - 1] < 0) != (u[i] < 0)) {
      out.push_back(t[i - 1] + (t[i] - t[i - 1]) * u[i - 1] / (u[i - 1] - u[i]));
    }
  }
  return out;
}

struct Oscillation {
  double period = 0;
  double amplitude = 0;
  double cycles = 0;
};

/// Period from the first to the last zero crossing; amplitude as the mean of the peak |u| of each
/// half cycle between crossings.
Oscillation analyse(const std::vector<double>& t, const std::vector<double>& u) {
  Oscillation o;
  const auto z = zero_crossings(t, u);
  if (z.size() < 3) {
    return o;
  }
  o.period = 2.0 * (z.back() - z.front()) / static_cast<double>(z.size() - 1);
  o.cycles = (t.back() - t.front()) / o.period;
  double sum = 0;
  std::size_t halves = 0;
  for (std::size_t c = 0; c + 1 < z.size(); ++c) {
    double peak = 0;
    for (std::size_t i = 0; i < t.size(); ++i) {
      if (t[i] > z[c] && t[i] < z[c + 1]) {
        peak = std::max(peak, std::abs(u[i]));
      }
    }
    sum += peak;
    ++halves;
  }
  o.amplitude = sum / static_cast<double>(halves);
  return o;
}

} // namespace

Json run_bar_vibration(const Context& ctx) {
  const Scene scene = load_scene((ctx.folder / "bar-vibration.yaml").string());
  const RunOptions opt = case_run_options(ctx, "bar-vibration");
  const RunOutcome run = run_scene(scene, opt);

  const Material& steel = scene.model.materials.front();
  const double wave_speed = std::sqrt(steel.youngs_modulus / steel.density);
  const double strain = scene.initial.displacement_gradient[0][0];
  const double length = 1.0; // the bar's box; the clamp particles lie outside it
  const double x_probe = scene.probes.front().point[0];

  std::vector<double> pd_u, exact_u;
  for (std::size_t r = 0; r < run.history.time.size(); ++r) {
    pd_u.push_back(run.history.values[r][0]);
    exact_u.push_back(bar_modal_series(x_probe, run.history.time[r], strain, length, wave_speed));
  }
  const Oscillation pd_osc = analyse(run.history.time, pd_u);
  const Oscillation exact = analyse(run.history.time, exact_u);
  double rms = 0;
  for (std::size_t r = 0; r < pd_u.size(); ++r) {
    rms += (pd_u[r] - exact_u[r]) * (pd_u[r] - exact_u[r]);
  }
  rms = std::sqrt(rms / static_cast<double>(std::max<std::size_t>(pd_u.size(), 1))) /
        (strain * length);

  const double period_error = relative_error(pd_osc.period, exact.period);
  const double amplitude_error = relative_error(pd_osc.amplitude, exact.amplitude);
  const bool stable = run.result.status == RunStatus::end_time;
  const bool passed =
      stable && pd_osc.cycles >= 5 && period_error <= 0.01 && amplitude_error <= 0.02;

  Json out;
  out["case"] = "bar-vibration";
  out["quantity"] = "free-end displacement history u(x = 0.9995 m, t)";
  out["pd"]["period"] = pd_osc.period;
  out["pd"]["amplitude"] = pd_osc.amplitude;
  out["pd"]["cycles"] = pd_osc.cycles;
  out["reference"]["period"] = exact.period;
  out["reference"]["amplitude"] = exact.amplitude;
  out["reference"]["period_4L_over_c"] = 4.0 * length / wave_speed;
  out["error"]["period"] = period_error;
  out["error"]["amplitude"] = amplitude_error;
  out["error"]["history_rms_over_eps_L"] = rms;
  out["gate"]["period"] = 0.01;
  out["gate"]["amplitude"] = 0.02;
  out["gate"]["min_cycles"] = 5;
  out["run"] = run.summary;
  out["passed"] = passed;
  fmt::print("   period {:.6e} s vs {:.6e} s (error {:.3f} %), amplitude {:.6e} vs {:.6e} m (error "
             "{:.3f} %), {:.1f} cycles, history RMS {:.3f} % of eps*L\n",
             pd_osc.period, exact.period, 100 * period_error, pd_osc.amplitude, exact.amplitude,
             100 * amplitude_error, pd_osc.cycles, 100 * rms);
  return out;
}

Json run_bar_energy(const Context& ctx) {
  Scene scene = load_scene((ctx.folder / "bar-vibration.yaml").string());
  scene.solver.dt.reset();
  scene.solver.safety = 0.9;
  scene.solver.end_time.reset();
  scene.solver.max_steps = 10000;
  Model model = build_model(scene.model);
  Simulation sim(model, scene.solver, scene.initial);
  std::vector<double> energy{sim.kinetic_energy() + sim.strain_energy()};
  const RunResult r = sim.run([&](const Simulation& s) {
    if (s.state().step % 10 == 0) {
      energy.push_back(s.kinetic_energy() + s.strain_energy());
    }
    return true;
  });
  const double e0 = energy.front();
  double fluctuation = 0;
  for (double e : energy) {
    fluctuation = std::max(fluctuation, std::abs(e - e0) / e0);
  }
  // Drift = change of the mean energy between the first and the last tenth of the run. Verlet
  // conserves a shadow energy, so E itself oscillates; the drift measures secular change.
  const std::size_t w = std::max<std::size_t>(energy.size() / 10, 1);
  double first = 0, last = 0;
  for (std::size_t i = 0; i < w; ++i) {
    first += energy[i];
    last += energy[energy.size() - 1 - i];
  }
  const double drift = std::abs(last - first) / (static_cast<double>(w) * e0);
  const bool passed = r.status == RunStatus::max_steps && r.steps == 10000 && drift <= 1e-4;

  Json out;
  out["case"] = "bar-energy";
  out["quantity"] = "total energy E = kinetic + stored, undamped Verlet, 10^4 steps";
  out["pd"]["initial_energy"] = e0;
  out["pd"]["steps"] = r.steps;
  out["pd"]["dt"] = r.dt;
  out["pd"]["dt_stable_eq31"] = r.dt_stable;
  out["reference"]["energy"] = e0;
  out["error"]["drift"] = drift;
  out["error"]["max_fluctuation"] = fluctuation;
  out["gate"]["drift"] = 1e-4;
  out["passed"] = passed;
  fmt::print("   {} steps at dt = {:.4e} s (0.9 x eq. 31 = {:.4e} s): drift {:.2e}, max "
             "fluctuation {:.2e}\n",
             r.steps, r.dt, r.dt_stable, drift, fluctuation);
  return out;
}

PD_VERIFICATION_RUN("bar-vibration", run_bar_vibration);
PD_VERIFICATION_RUN("bar-energy", run_bar_energy);

} // namespace pd::verification
