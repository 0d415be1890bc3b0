// pd bench SCENE [--steps N] [--repeats N] [--threads N] [--stretch exact|modified|fast]
//                [--kernel simd|scalar] [--damage] [--bond-model micro-elastic|virtual-fibres]
//                [--lammps LMP [--lammps-input F]
//                [--lammps-steps N] [--lammps-var NAME=VALUE ...]] [--json]
// Force-evaluation throughput in bond updates per second: the median of several repeats of N
// force evaluations on a slightly deformed configuration, after an untimed warm-up (a second
// thread's first few hundred milliseconds are slow on a VM), with the CPU that other processes
// took meanwhile and the load average before and after.
// With --lammps, each repeat runs LAMMPS first and libpd right after, so both see the same load;
// the libpd/LAMMPS ratio is taken per repeat and its median reported.
#include "commands.hpp"
#include "lammps.hpp"
#include "libpd/app/run.hpp"
#include "libpd/core/threads.hpp"
#include "libpd/kernel/force_kernel.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

namespace pd::cli {

namespace {

struct BenchArgs {
  std::string scene;
  std::size_t steps = 100;
  int repeats = 5;
  int threads = 0;
  std::string stretch;
  std::string bond_model; ///< empty: the scene's
  std::string kernel = std::string(name_of(KernelPath::simd));
  bool damage = false;
  std::string lammps;                         ///< LAMMPS binary; empty: no LAMMPS runs
  std::string lammps_input = PD_LAMMPS_INPUT; ///< its input file (Model A)
  std::size_t lammps_steps = 600;
  std::vector<std::string> lammps_vars; ///< extra `-var NAME VALUE` pairs, as NAME=VALUE
  bool json = false;
};

/// What the repeats measured: libpd seconds, and with --lammps the LAMMPS rates and the ratios.
struct Timings {
  std::vector<double> seconds;
  std::vector<double> lammps_rates;
  std::vector<double> ratios;
  std::size_t lammps_bonds = 0;
  std::string load_before;
  std::string load_after;
  double other_cpu_cores = 0; ///< mean CPU other processes took during the timed evaluations
};

/// Above this many cores taken by others during the timed evaluations a figure is flagged as
/// measured under load: more than a tenth of a core is more than timer and kernel noise.
constexpr double busy_machine_cores = 0.1;

/// Untimed warm-up: at least this long, so that every thread has run at full speed before the
/// clock starts (measured: 2-thread repeats are up to 5× slow for the first ~0.5 s on this VM).
constexpr double warm_up_seconds = 0.5;

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

/// A small smooth deformation so that every bond is stretched (no special zero-stretch path).
std::vector<double> deformed_positions(const Model& model) {
  std::vector<double> y(3 * model.size());
  for (std::size_t i = 0; i < model.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const double x = model.particles.position[i][c];
      y[3 * i + c] = x + 1e-4 * std::sin(3.0 * x + c);
    }
  }
  return y;
}

/// One LAMMPS run into `t` (rate and bond count); false if it failed.
bool time_lammps(const BenchArgs& a, Timings& t) {
  const auto run = run_lammps(a.lammps, a.lammps_input, a.lammps_steps, a.lammps_vars);
  if (!run) {
    fmt::print(stderr, "error: LAMMPS run failed: {} -in {}\n", a.lammps, a.lammps_input);
    return false;
  }
  t.lammps_bonds = run->bonds;
  t.lammps_rates.push_back(bond_updates_per_second(run->bonds, a.lammps_steps, run->loop_seconds));
  return true;
}

/// Seconds of `a.steps` force evaluations once per repeat (each after a LAMMPS run with --lammps).
std::optional<Timings> time_evaluations(const BenchArgs& a, const Model& model,
                                        ForceEvaluator& forces, int repeats) {
  std::vector<double> y = deformed_positions(model), b(3 * model.size());
  const auto warm_start = std::chrono::steady_clock::now();
  do {
    forces.compute(y.data(), b.data());
  } while (std::chrono::duration<double>(std::chrono::steady_clock::now() - warm_start).count() <
           warm_up_seconds);
  Timings t;
  OtherCpuMeter others;
  t.load_before = load_average();
  for (int r = 0; r < repeats; ++r) {
    // The default follows the idle processors (core/threads.hpp); read before LAMMPS runs, which
    // the readings would count as another program's load.
    refresh_thread_count();
    if (!a.lammps.empty() && !time_lammps(a, t)) {
      return std::nullopt;
    }
    others.start();
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t s = 0; s < a.steps; ++s) {
      forces.compute(y.data(), b.data());
    }
    t.seconds.push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    others.stop();
    if (!a.lammps.empty()) {
      const double rate =
          bond_updates_per_second(model.family.bond_count(), a.steps, t.seconds.back());
      t.ratios.push_back(rate / t.lammps_rates.back());
    }
  }
  t.load_after = load_average();
  t.other_cpu_cores = others.cores();
  return t;
}

void print_text(const BenchArgs& a, const Model& model, const ForceEvaluator& forces,
                const Timings& t) {
  const double median = median_of(t.seconds);
  fmt::print("{}: {} particles, {} bonds, kernel {}, {} threads\n", a.scene, model.size(),
             model.family.bond_count(), forces.description(), current_thread_count());
  fmt::print("{} evaluations: median {:.4f} s of {} repeats -> {:.4g} bond updates/s\n", a.steps,
             median, t.seconds.size(),
             bond_updates_per_second(model.family.bond_count(), a.steps, median));
  if (!a.lammps.empty()) {
    fmt::print("LAMMPS peri/pmb, 1 thread, {} bonds, {} steps: median {:.4g} bond updates/s\n",
               t.lammps_bonds, a.lammps_steps, median_of(t.lammps_rates));
    fmt::print("libpd / LAMMPS (median of same-repeat ratios): {:.2f}x  [{}]\n",
               median_of(t.ratios), fmt::join(t.ratios, ", "));
  }
  fmt::print("load average before {} / after {} ({} cores); other processes took {:.2f} cores "
             "during the timed evaluations{}\n",
             t.load_before, t.load_after, std::thread::hardware_concurrency(), t.other_cpu_cores,
             t.other_cpu_cores > busy_machine_cores ? ": MEASURED UNDER LOAD" : "");
}

void print_json(const BenchArgs& a, const Model& model, const ForceEvaluator& forces,
                const Timings& t) {
  const double median = median_of(t.seconds);
  Json j;
  j["scene"] = a.scene;
  j["kernel"] = forces.description();
  j["threads"] = current_thread_count();
  j["particles"] = model.size();
  j["bonds"] = model.family.bond_count();
  j["steps"] = a.steps;
  j["repeats"] = t.seconds.size();
  j["seconds"] = median;
  j["seconds_all"] = Json::array_of(t.seconds);
  j["bond_updates_per_second"] =
      bond_updates_per_second(model.family.bond_count(), a.steps, median);
  j["loadavg_before"] = t.load_before;
  j["loadavg_after"] = t.load_after;
  j["other_cpu_cores"] = t.other_cpu_cores;
  j["under_load"] = t.other_cpu_cores > busy_machine_cores;
  j["warm_up_seconds"] = warm_up_seconds;
  if (!a.lammps.empty()) {
    j["lammps_bonds"] = t.lammps_bonds;
    j["lammps_steps"] = a.lammps_steps;
    j["lammps_input"] = a.lammps_input;
    j["lammps_vars"] = Json::array_of(a.lammps_vars);
    j["lammps_bond_updates_per_second"] = median_of(t.lammps_rates);
    j["lammps_bond_updates_per_second_all"] = Json::array_of(t.lammps_rates);
    j["ratio_to_lammps"] = median_of(t.ratios);
    j["ratio_to_lammps_all"] = Json::array_of(t.ratios);
  }
  fmt::print("{}", j.dump());
}

int bench(const BenchArgs& a) {
  const StopOnInterrupt stop("bench");
  set_threads(a.threads);
  Scene scene = load_or_explain(a.scene);
  if (!a.stretch.empty()) {
    scene.model.effects.stretch = *from_name<StretchKind>(a.stretch);
  }
  if (a.damage) {
    scene.model.effects.damage = true; // with the scene's critical stretch: the cost of checking
  }
  if (!a.bond_model.empty()) {
    // The same particles and the scene's corrections, the other law (and its own family: see
    // the README on what each model keeps of a `gradient`-weighted lattice).
    scene.model.effects.bond_model = *from_name<BondModel>(a.bond_model);
  }
  Model model = build_model(scene.model);
  auto forces = make_force_evaluator(model, *from_name<KernelPath>(a.kernel));
  const auto timings = time_evaluations(a, model, *forces, a.repeats);
  if (!timings) {
    return 1;
  }
  if (a.json) {
    print_json(a, model, *forces, *timings);
  } else {
    print_text(a, model, *forces, *timings);
  }
  return 0;
}

void add_lammps_options(CLI::App& cmd, BenchArgs& a) {
  cmd.add_option("--lammps", a.lammps,
                 "also time this LAMMPS binary (e.g. lmp) on --lammps-input, alternating with "
                 "libpd each repeat, and print the ratio");
  cmd.add_option("--lammps-input", a.lammps_input, "LAMMPS input (Model A)")->capture_default_str();
  add_count_option(cmd, "--lammps-steps", a.lammps_steps, "LAMMPS steps per repeat");
  cmd.add_option("--lammps-var", a.lammps_vars,
                 "NAME=VALUE passed to LAMMPS as -var NAME VALUE (model-a.in: lambda 0.025 for "
                 "Model B, jitter 0.25 for an irregular set); repeatable")
      ->check([](const std::string& v) { return lammps_var_error(v); });
}

} // namespace

Command add_bench_command(CLI::App& app) {
  auto a = std::make_shared<BenchArgs>();
  auto* cmd = app.add_subcommand("bench", "Force-evaluation throughput (bond updates per second)");
  cmd->add_option("scene", a->scene, "scene file (YAML)")->required();
  add_count_option(*cmd, "--steps", a->steps, "force evaluations per repeat");
  add_count_option(*cmd, "--repeats", a->repeats, "repeats; the median is reported");
  add_threads_option(*cmd, a->threads);
  cmd->add_option("--stretch", a->stretch, "override the stretch measure")
      ->check(CLI::IsMember(enum_word_list<StretchKind>()));
  cmd->add_option("--kernel", a->kernel, "bond loop: simd (default) or the scalar reference")
      ->check(CLI::IsMember(enum_word_list<KernelPath>()));
  cmd->add_flag("--damage", a->damage, "switch the damage effect on");
  cmd->add_option("--bond-model", a->bond_model, "override the scene's bond model")
      ->check(CLI::IsMember(enum_word_list<BondModel>()));
  add_lammps_options(*cmd, *a);
  cmd->add_flag("--json", a->json, "machine-readable output");
  return {cmd, [a] { return bench(*a); }, true};
}

} // namespace pd::cli
