// pd bench SCENE [--steps N] [--repeats N] [--threads N] [--stretch exact|modified|fast] [--json]
// Force-evaluation throughput in bond updates per second: the median of several repeats of N
// force evaluations on a slightly deformed configuration.
#include "commands.hpp"
#include "libpd/app/run.hpp"
#include "libpd/kernel/force_kernel.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <memory>
#include <vector>

namespace pd::cli {

namespace {

struct BenchArgs {
  std::string scene;
  std::size_t steps = 100;
  int repeats = 5;
  int threads = 0;
  std::string stretch;
  bool json = false;
};

/// Seconds of `steps` force evaluations, once per repeat, sorted.
std::vector<double> time_evaluations(const Model& model, ForceEvaluator& forces, std::size_t steps,
                                     int repeats) {
  // A small smooth deformation so that every bond is stretched (no special zero-stretch path).
  std::vector<double> y(3 * model.size()), b(3 * model.size());
  for (std::size_t i = 0; i < model.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const double x = model.particles.position[i][c];
      y[3 * i + c] = x + 1e-4 * std::sin(3.0 * x + c);
    }
  }
  forces.compute(y.data(), b.data()); // warm-up: page in every array
  std::vector<double> seconds;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t s = 0; s < steps; ++s) {
      forces.compute(y.data(), b.data());
    }
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(seconds.begin(), seconds.end());
  return seconds;
}

int bench(const BenchArgs& a) {
  const int repeats = std::max(a.repeats, 1);
  set_threads(a.threads);
  Scene scene = load_or_explain(a.scene);
  if (!a.stretch.empty()) {
    scene.model.effects.stretch = *from_name<StretchKind>(a.stretch);
  }
  Model model = build_model(scene.model);
  auto forces = make_force_evaluator(model);
  const std::vector<double> seconds = time_evaluations(model, *forces, a.steps, repeats);
  const double median = seconds[seconds.size() / 2];
  const double rate = bond_updates_per_second(model.family.bond_count(), a.steps, median);
  if (!a.json) {
    fmt::print("{}: {} particles, {} bonds, kernel {}, {} threads\n", a.scene, model.size(),
               model.family.bond_count(), forces->description(), thread_count());
    fmt::print("{} evaluations: median {:.4f} s of {} repeats -> {:.4g} bond updates/s\n", a.steps,
               median, repeats, rate);
    return 0;
  }
  Json j;
  j["scene"] = a.scene;
  j["kernel"] = forces->description();
  j["threads"] = thread_count();
  j["particles"] = model.size();
  j["bonds"] = model.family.bond_count();
  j["steps"] = a.steps;
  j["repeats"] = repeats;
  j["seconds"] = median;
  j["seconds_all"] = Json::array_of(seconds);
  j["bond_updates_per_second"] = rate;
  fmt::print("{}", j.dump());
  return 0;
}

} // namespace

Command add_bench_command(CLI::App& app) {
  auto a = std::make_shared<BenchArgs>();
  auto* cmd = app.add_subcommand("bench", "Force-evaluation throughput (bond updates per second)");
  cmd->add_option("scene", a->scene, "scene file (YAML)")->required();
  cmd->add_option("--steps", a->steps, "force evaluations per repeat")->capture_default_str();
  cmd->add_option("--repeats", a->repeats, "repeats; the median is reported")
      ->capture_default_str();
  add_threads_option(*cmd, a->threads);
  cmd->add_option("--stretch", a->stretch, "override the stretch measure")
      ->check(CLI::IsMember(enum_word_list<StretchKind>()));
  cmd->add_flag("--json", a->json, "machine-readable output");
  return {cmd, [a] { return bench(*a); }};
}

} // namespace pd::cli
