// Integrator comparison (`pd compare`): bar-vibration error vs cost, clamped-beam cost to the
// steady state.
#include "integrator_comparison.hpp"

#include "libpd/app/run.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/kernel/stable_time_step.hpp"
#include "libpd/time/stability.hpp"
#include "structures.hpp"
#include "verification.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace pd::verification {

namespace {

struct CompareConfig {
  IntegratorKind kind;
  ArkodeTable table = ArkodeTable::rk4;
  bool adaptive = false;
  double dt_factor = 0; ///< × eq. 31 × stability scale; 0: the scene's dt
  double rtol = 1e-6;
};

std::string config_table(const CompareConfig& c) {
  return c.kind == IntegratorKind::arkode ? to_string(c.table) : std::string("-");
}

Scene configured(const Scene& base, const CompareConfig& c, double eq31) {
  Scene s = base;
  s.solver.integrator = c.kind;
  s.solver.arkode.table = c.table;
  s.solver.arkode.adaptive = c.adaptive;
  s.solver.arkode.rtol = c.rtol;
  s.output.vtu = false;
  if (c.dt_factor > 0) {
    double scale = 1.0;
    if (c.kind == IntegratorKind::arkode) {
      const double beta = imaginary_stability_interval(butcher_tableau(c.table));
      scale = beta > 0 ? 0.5 * beta : 0.5;
    }
    s.solver.dt = c.dt_factor * eq31 * scale;
  }
  if (c.kind == IntegratorKind::euler_cromer || c.kind == IntegratorKind::verlet) {
    s.solver.damping = 0; // undamped schemes; ADR ignores c_v, arkode uses it
    s.model.effects.damping = false;
  }
  return s;
}

std::vector<ArkodeTable> offered_tables() {
  std::vector<ArkodeTable> tables;
  if (arkode_available()) {
    for (int i = 0; i < arkode_table_count; ++i) {
      tables.push_back(static_cast<ArkodeTable>(i));
    }
  }
  return tables;
}

/// The free-end displacement history of a PD run, linearly interpolated between its samples.
struct History {
  std::vector<double> t, u;

  bool empty() const { return t.empty(); }
  double at(double time) const {
    const auto it = std::lower_bound(t.begin(), t.end(), time);
    if (it == t.begin()) {
      return u.front();
    }
    if (it == t.end()) {
      return u.back();
    }
    const std::size_t k = static_cast<std::size_t>(it - t.begin());
    const double w = (time - t[k - 1]) / (t[k] - t[k - 1]);
    return (1 - w) * u[k - 1] + w * u[k];
  }
};

/// Reference PD solution (temporal error only): Dormand–Prince at 1/20 of its stable step (1/5
/// with --quick), 2.25× below the finest row's step, so that its own error, ~2.25⁻⁵ = 1.7 % of
/// that row's, does not mask it. Empty without ARKode.
History reference_history(const Scene& base, double eq31, bool quick) {
  History ref;
  if (!arkode_available()) {
    return ref;
  }
  CompareConfig rc{IntegratorKind::arkode, ArkodeTable::dormand_prince, false, quick ? 0.2 : 0.05};
  Scene s = configured(base, rc, eq31);
  s.output.history_every = 1;
  const RunOutcome ro = run_scene(s, RunOptions{});
  for (std::size_t r = 0; r < ro.history.time.size(); ++r) {
    ref.t.push_back(ro.history.time[r]);
    ref.u.push_back(ro.history.values[r][0]);
  }
  return ref;
}

std::vector<CompareConfig> dynamic_configs(bool quick) {
  std::vector<CompareConfig> configs;
  const std::vector<double> factors =
      quick ? std::vector<double>{0.9, 0.45} : std::vector<double>{0.9, 0.45, 0.225, 0.1125};
  for (double f : factors) {
    configs.push_back({IntegratorKind::verlet, ArkodeTable::rk4, false, f});
  }
  for (auto t : offered_tables()) {
    if (t == ArkodeTable::heun_euler) {
      continue; // no imaginary-axis stability interval: undamped runs grow for any Δt
    }
    // --quick keeps one table per order class (3, 4, 5), which is what the report plots.
    if (quick && t != ArkodeTable::bogacki_shampine && t != ArkodeTable::rk4 &&
        t != ArkodeTable::dormand_prince) {
      continue;
    }
    for (double f : factors) {
      configs.push_back({IntegratorKind::arkode, t, false, f});
    }
  }
  return configs;
}

std::vector<CompareConfig> quasistatic_configs(bool quick) {
  // The static solve first: its equilibrium (Newton to a tenth of the scene's force tolerance)
  // is every row's reference.
  std::vector<CompareConfig> configs = {
      {IntegratorKind::static_solve},
      {IntegratorKind::damped_euler},
      {IntegratorKind::adr},
  };
  // Each ARKode row costs 4–6× damped-euler's (22,000 and 27,000 force evaluations against
  // 7,800 at twice the spacing, and SUNDIALS' vector sums on top): --quick keeps one table,
  // rk4; the full comparison adds Bogacki–Shampine and adaptive Dormand–Prince (~16× the force
  // evaluations of damped-euler: 72,863 vs 4,600).
  if (arkode_available()) {
    configs.push_back({IntegratorKind::arkode, ArkodeTable::rk4});
  }
  if (arkode_available() && !quick) {
    configs.push_back({IntegratorKind::arkode, ArkodeTable::bogacki_shampine});
    configs.push_back({IntegratorKind::arkode, ArkodeTable::dormand_prince, true, 0, 1e-6});
  }
  return configs;
}

} // namespace

void compare_integrators_dynamic(const std::filesystem::path& cases_dir, bool quick,
                                 const ComparisonRow& emit) {
  Scene base = load_scene((cases_dir / "bar-vibration" / "bar-vibration.yaml").string());
  BodySpec& bar = base.model.bodies.front();
  double length = bar.region.boxes.front().hi[0] - bar.region.boxes.front().lo[0];
  const Material& steel = base.model.materials.front();
  const double wave_speed = std::sqrt(steel.youngs_modulus / steel.density);
  if (quick) {
    // Half the bar (500 particles, same spacing, so the same stable step and the same error per
    // step) for one of its periods 4L/c instead of the case's 6.4: a quarter of the steps on half
    // the particles. The rows' errors are not the whole bar's (Verlet at 0.9× eq. 31 against the
    // modal series: 4.3e-3 of εL, the whole bar over one of its periods 2.2e-3); their ratios
    // between integrators and step sizes are what the report plots.
    length *= 0.5;
    bar.region.boxes.front().hi[0] = bar.region.boxes.front().lo[0] + length;
    base.probes.front().point[0] -= length; // the free end's particle, λ/2 inside the end
    base.solver.end_time = 4.0 * length / wave_speed;
  }
  const Model probe_model = build_model(base.model);
  const double eq31 = stable_time_step(probe_model);
  const double strain = base.initial.displacement_gradient[0][0];
  const double x_probe = base.probes.front().point[0];
  const double sample = 10 * base.solver.dt.value_or(eq31); // the case's sampling interval
  const History reference = reference_history(base, eq31, quick);
  for (const auto& c : dynamic_configs(quick)) {
    Scene s = configured(base, c, eq31);
    const double dt = s.solver.dt.value_or(eq31);
    s.output.history_every = std::max<std::size_t>(1, static_cast<std::size_t>(sample / dt));
    const RunOutcome ro = run_scene(s, RunOptions{});
    double rms = 0, rms_ref = 0;
    const std::size_t n = ro.history.time.size();
    for (std::size_t r = 0; r < n; ++r) {
      const double t = ro.history.time[r];
      const double u = ro.history.values[r][0];
      const double e = u - bar_modal_series(x_probe, t, strain, length, wave_speed);
      rms += e * e;
      if (!reference.empty()) {
        const double er = u - reference.at(t);
        rms_ref += er * er;
      }
    }
    const double norm = strain * length;
    const double samples = static_cast<double>(std::max<std::size_t>(n, 1));
    Json j;
    j["case"] = "bar-vibration";
    j["integrator"] = to_string(c.kind);
    j["table"] = config_table(c);
    j["dt"] = ro.result.dt;
    j["dt_over_eq31"] = ro.result.dt / eq31;
    j["error"] = std::sqrt(rms / samples) / norm;
    j["error_vs_reference_pd"] = reference.empty() ? 0.0 : std::sqrt(rms_ref / samples) / norm;
    j["error_measure"] = "free-end history RMS / (eps L)";
    j["bar_length"] = length;
    j["end_time"] = base.solver.end_time.value_or(0.0);
    j["force_evaluations"] = ro.result.force_evaluations;
    j["wall_seconds"] = ro.result.wall_seconds;
    j["steps"] = ro.result.steps;
    j["status"] = to_string(ro.result.status);
    emit(j);
  }
}

void compare_integrators_quasistatic(const std::filesystem::path& cases_dir, bool quick,
                                     const ComparisonRow& emit) {
  Scene base = load_scene((cases_dir / "clamped-beam" / "clamped-beam.yaml").string());
  if (quick) {
    // Twice the paper's spacing: 1,976 instead of 9,328 particles and half the wave transits to
    // relax, so every integrator's row costs about 1/20 (the report's default mode; the relative
    // costs of the integrators are what it shows, and they hold at either spacing).
    set_spacing(base, 2 * base.model.lattice.spacing);
  }
  double reference = 0;
  for (const auto& c : quasistatic_configs(quick)) {
    const Scene s = configured(base, c, 0);
    const RunOutcome ro = run_scene(s, RunOptions{});
    const double w =
        ro.probes.count("midspan_deflection") ? ro.probes.at("midspan_deflection") : 0.0;
    if (c.kind == IntegratorKind::static_solve) {
      reference = w;
    }
    Json j;
    j["case"] = "clamped-beam";
    j["spacing"] = s.model.lattice.spacing;
    j["integrator"] = to_string(c.kind);
    j["table"] = config_table(c);
    j["adaptive"] = c.adaptive;
    j["dt"] = ro.result.dt;
    j["midspan_deflection"] = w;
    j["error"] = reference != 0 ? std::abs(w - reference) / std::abs(reference) : 0.0;
    j["error_measure"] = "|w - w(static)| / |w(static)|";
    j["force_tolerance"] = s.solver.steady.force_tolerance;
    j["residual"] = ro.result.residual;
    if (const Json* details = ro.summary.find("integrator_details")) {
      if (const Json* r = details->find("residual")) {
        j["residual"] = *r; // the static solve's own: relative to the load, like force_tolerance
      }
    }
    j["force_evaluations"] = ro.result.force_evaluations;
    j["wall_seconds"] = ro.result.wall_seconds;
    j["setup_seconds"] = ro.setup_seconds;
    j["solve_seconds"] = ro.result.wall_seconds;
    if (const Json* peak = ro.summary.find("peak_memory_bytes")) {
      j["peak_memory_bytes"] = *peak;
    }
    j["steps"] = ro.result.steps;
    j["internal_steps"] = ro.result.internal_steps;
    j["status"] = to_string(ro.result.status);
    emit(j);
  }
}

} // namespace pd::verification
