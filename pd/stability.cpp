// pd stability SCENE... [--integrator X]... [--steps N] [--tolerance T] [--gate G] [--json]
// Largest stable fixed time step of each scene and integrator, measured by bisection, beside
// eq. 31 and the sharp prediction from the largest frequency of the linearised operator; exit
// code 4 if --gate is given and a measurement strays from the prediction.
#include "libpd/time/stability.hpp"

#include "commands.hpp"
#include "libpd/core/json.hpp"
#include "libpd/core/text.hpp"
#include "libpd/kernel/spectrum.hpp"

#include <cmath>
#include <cstdio>
#include <fmt/format.h>
#include <memory>
#include <optional>
#include <vector>

namespace pd::cli {

namespace {

struct StabilityArgs {
  std::vector<std::string> scenes, integrators;
  std::size_t steps = 1000;
  double tolerance = 0.01;
  double gate = 0;
  bool json = false;
  int threads = 0;
};

std::optional<StabilityTarget> parse_target(const std::string& word) {
  StabilityTarget t;
  // Fixed-step integrators by their own word; adr has no stable step to measure.
  if (const auto kind = from_name<IntegratorKind>(word);
      kind && *kind != IntegratorKind::adr && *kind != IntegratorKind::arkode) {
    t.kind = *kind;
    return t;
  }
  const std::string name = word.starts_with("arkode:") ? word.substr(7) : word;
  if (const auto table = from_name<ArkodeTable>(name)) {
    t.kind = IntegratorKind::arkode;
    t.table = *table;
    return t;
  }
  return std::nullopt;
}

/// The integrators named on the command line (default: verlet and every offered ARKode table);
/// nothing, with the reason on stderr, if one is unknown or not built.
std::optional<std::vector<StabilityTarget>> parse_targets(std::vector<std::string> integrators) {
  if (integrators.empty()) {
    integrators.push_back("verlet");
    if (arkode_available()) {
      for (const std::string_view table : enum_words<ArkodeTable>) {
        integrators.push_back("arkode:" + std::string(table));
      }
    }
  }
  std::vector<StabilityTarget> targets;
  for (const auto& w : integrators) {
    auto t = parse_target(w);
    if (!t) {
      fmt::print(stderr,
                 "error: unknown integrator '{}' (verlet, euler-cromer, damped-euler or "
                 "arkode:TABLE)\n",
                 printable(w));
      return std::nullopt;
    }
    if (t->kind == IntegratorKind::arkode && !arkode_available()) {
      fmt::print(stderr, "error: '{}' needs SUNDIALS, which this build lacks\n", printable(w));
      return std::nullopt;
    }
    targets.push_back(*t);
  }
  return targets;
}

Json result_row(const std::string& name, const std::string& path, const StabilityResult& r,
                const FrequencyEstimate& freq, std::size_t steps) {
  Json j;
  j["case"] = name;
  j["scene"] = path;
  j["integrator"] = r.integrator;
  j["interval"] = r.interval;
  j["omega_max"] = r.omega_max;
  j["lanczos_iterations"] = freq.iterations;
  j["measured_dt"] = r.measured;
  j["unstable_dt"] = r.unstable;
  j["eq31_dt"] = r.eq31;
  j["sharp_dt"] = r.sharp;
  j["interval_finite_horizon"] = r.interval_finite;
  j["sharp_finite_horizon_dt"] = r.sharp_finite;
  j["measured_over_sharp"] = r.sharp > 0 ? r.measured / r.sharp : 0.0;
  j["measured_over_sharp_finite_horizon"] = r.measured / r.sharp_finite;
  j["measured_over_eq31"] = r.measured / r.eq31;
  j["steps_per_run"] = steps;
  j["runs"] = r.runs;
  j["wall_seconds"] = r.seconds;
  return j;
}

/// The gate: the prediction the bounded run can be held to is the finite-horizon one; for
/// Verlet the measured limit must also respect the conservative eq. 31 bound.
void check_gate(const std::string& name, const StabilityTarget& t, const StabilityResult& r,
                double gate, std::vector<std::string>& failures) {
  const double ratio = r.measured / r.sharp_finite;
  if (!(std::abs(ratio - 1.0) <= gate)) {
    failures.push_back(
        fmt::format("{} {}: measured / predicted = {:.4f}", name, r.integrator, ratio));
  }
  if (t.kind != IntegratorKind::arkode && r.measured < r.eq31) {
    failures.push_back(fmt::format("{} {}: measured {:.4e} s below eq. 31 {:.4e} s", name,
                                   r.integrator, r.measured, r.eq31));
  }
}

void print_row(const std::string& name, const StabilityResult& r) {
  fmt::print("{:<16} {:<24} {:>6.4f} {:>10.4e} {:>10.4e} {:>10.4e} {:>7.4f} {:>7.4f} "
             "{:>10.4e} {:>7.4f} {:>4} {:>5.0f}s\n",
             name, r.integrator, r.interval, r.measured, r.eq31, r.sharp,
             r.sharp > 0 ? r.measured / r.sharp : 0.0, r.measured / r.eq31, r.sharp_finite,
             r.measured / r.sharp_finite, r.runs, r.seconds);
  std::fflush(stdout);
}

int stability(const StabilityArgs& a) {
  const StopOnInterrupt stop("stability");
  set_threads(a.threads);
  const auto targets = parse_targets(a.integrators);
  if (!targets) {
    return 1;
  }
  StabilityOptions opt;
  opt.steps = a.steps;
  opt.relative_tolerance = a.tolerance;
  Json rows = Json::array();
  std::vector<std::string> gate_failures;
  if (!a.json) {
    fmt::print("{:<16} {:<24} {:>6} {:>10} {:>10} {:>10} {:>7} {:>7} {:>10} {:>7} {:>4} {:>6}\n",
               "case", "integrator", "beta", "measured", "eq31", "sharp", "m/sharp", "m/eq31",
               "sharp_N", "m/shN", "runs", "wall");
  }
  for (const auto& path : a.scenes) {
    const Scene scene = load_or_explain(path);
    const Model model = build_model(stability_model(scene.model));
    const FrequencyEstimate freq = max_frequency(model);
    const std::string name = std::filesystem::path(path).stem().string();
    for (const auto& t : *targets) {
      const StabilityResult r =
          measure_stability(scene.model, scene.solver, t, opt, freq.omega_max);
      if (a.gate > 0) {
        check_gate(name, t, r, a.gate, gate_failures);
      }
      if (a.json) {
        rows.push_back(result_row(name, path, r, freq, opt.steps));
      } else {
        print_row(name, r);
      }
    }
  }
  if (a.json) {
    fmt::print("{}\n", rows.dump());
  }
  if (!gate_failures.empty()) {
    fmt::print(stderr, "stability gate ({:.0f} %) failed:\n", 100 * a.gate);
    for (const auto& f : gate_failures) {
      fmt::print(stderr, "  {}\n", f);
    }
    return 4;
  }
  return 0;
}

} // namespace

Command add_stability_command(CLI::App& app) {
  auto a = std::make_shared<StabilityArgs>();
  auto* cmd = app.add_subcommand(
      "stability", "Largest stable fixed time step, measured by bisection, beside eq. 31 and the "
                   "sharp prediction from the largest frequency of the linearised operator");
  cmd->add_option("scenes", a->scenes, "scene files (YAML)")->required();
  cmd->add_option("--integrator", a->integrators,
                  "verlet, euler-cromer, damped-euler or arkode:TABLE (repeatable; default: "
                  "verlet and every offered table)");
  add_count_option(*cmd, "--steps", a->steps, "steps of each bounded run",
                   static_cast<double>(min_stability_steps));
  cmd->add_option("--tolerance", a->tolerance, "relative bisection tolerance")
      ->check(finite_in(0, 0.5))
      ->capture_default_str();
  cmd->add_option("--gate", a->gate,
                  "exit with status 4 unless every measured limit is within this fraction "
                  "of the finite-horizon prediction (and, for Verlet, not below eq. 31)")
      ->check(finite_in(0, 10));
  cmd->add_flag("--json", a->json, "machine-readable output");
  add_threads_option(*cmd, a->threads);
  return {cmd, [a] { return stability(*a); }};
}

} // namespace pd::cli
