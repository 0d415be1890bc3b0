// pd — the libpd command line.
//
//   pd run SCENE [-o DIR] [--threads N]       run a scene, write summary.json, probes.csv, VTU
//   pd info SCENE [--json]                    sizes, memory estimate, stable time step
//   pd bench SCENE [--steps N] [--threads N]  force-evaluation throughput
//   pd verify [CASE...] [-o DIR] [--list]     verification cases with their gates
//
// Exit codes: 0 success, 1 bad input or usage, 2 a verification gate failed, 3 the run became
// unstable.
#include "libpd/force_kernel.hpp"
#include "libpd/run.hpp"
#include "libpd/scene.hpp"
#include "libpd/stable_time_step.hpp"
#include "verification.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fmt/format.h>
#include <iostream>
#include <unistd.h>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace {

void set_threads(int threads) {
#ifdef _OPENMP
  if (threads > 0) {
    omp_set_num_threads(threads);
  }
#else
  (void)threads;
#endif
}

int thread_count() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

pd::Scene load_or_explain(const std::string& path) {
  pd::Scene scene = pd::load_scene(path);
  for (const auto& w : scene.warnings) {
    fmt::print(stderr, "{}\n", w);
  }
  return scene;
}

int cmd_run(const std::string& scene_path, const std::string& out_dir, int threads) {
  set_threads(threads);
  const pd::Scene scene = load_or_explain(scene_path);
  pd::RunOptions opt;
  opt.output_dir = out_dir;
  opt.progress = ::isatty(STDERR_FILENO) != 0;
  const pd::RunOutcome out = pd::run_scene(scene, opt);
  fmt::print(
      "{}: {} particles, {} bonds, {} steps of {:.4g} s (eq. 31 limit {:.4g} s), status {}\n",
      scene_path, out.particles, out.bonds, out.result.steps, out.result.dt, out.result.dt_stable,
      pd::to_string(out.result.status));
  fmt::print(
      "wall {:.3f} s, {:.3g} bond updates/s, {} threads\n", out.result.wall_seconds,
      pd::bond_updates_per_second(out.bonds, out.result.force_evaluations, out.result.wall_seconds),
      thread_count());
  for (const auto& [name, value] : out.probes) {
    fmt::print("  probe {:<20} {:.9g}\n", name, value);
  }
  if (!out_dir.empty()) {
    fmt::print("results in {}/summary.json\n", out_dir);
  }
  if (out.result.status == pd::RunStatus::unstable) {
    fmt::print(stderr, "error: {}\n", out.result.message);
    return 3;
  }
  return 0;
}

int cmd_info(const std::string& scene_path, bool json) {
  const pd::Scene scene = load_or_explain(scene_path);
  const pd::ModelSizeEstimate est = pd::estimate_model_size(scene.model);
  const pd::Model model = pd::build_model(scene.model);
  const double dt = pd::stable_time_step(model);
  const double per_particle = 2.0 * static_cast<double>(model.family.bond_count()) /
                              static_cast<double>(std::max<std::size_t>(model.size(), 1));
  pd::Json j;
  j["scene"] = scene_path;
  j["particles"] = model.size();
  j["bonds"] = model.family.bond_count();
  j["bonds_per_particle"] = per_particle;
  j["horizon"] = model.horizon();
  j["memory_bytes"] = model.memory_bytes();
  j["memory_estimate_bytes"] = est.bytes;
  j["dt_stable"] = dt;
  j["effects"] = pd::Json::array_of(model.effects.names());
  if (json) {
    fmt::print("{}", j.dump());
    return 0;
  }
  fmt::print("scene              {}\n", scene_path);
  fmt::print("particles          {}\n", model.size());
  fmt::print("bonds              {}\n", model.family.bond_count());
  fmt::print("bonds per particle {:.2f} (family size, both directions)\n", per_particle);
  fmt::print("horizon            {:.6g} m\n", model.horizon());
  fmt::print("memory             {:.1f} MiB (estimate before building: {:.1f} MiB)\n",
             static_cast<double>(model.memory_bytes()) / 1048576.0, est.bytes / 1048576.0);
  fmt::print("stable dt (eq. 31) {:.6g} s\n", dt);
  fmt::print("effects            {}\n", fmt::join(model.effects.names(), ", "));
  return 0;
}

int cmd_bench(const std::string& scene_path, std::size_t steps, int threads, bool json,
              const std::string& stretch, int repeats) {
  set_threads(threads);
  pd::Scene scene = load_or_explain(scene_path);
  if (!stretch.empty()) {
    scene.model.effects.stretch = stretch == "exact"      ? pd::StretchKind::exact
                                  : stretch == "modified" ? pd::StretchKind::modified
                                                          : pd::StretchKind::fast;
  }
  pd::Model model = pd::build_model(scene.model);
  auto forces = pd::make_force_evaluator(model);
  // A small smooth deformation so that every bond is stretched (no special zero-stretch path).
  std::vector<double> y(3 * model.size()), b(3 * model.size());
  for (std::size_t i = 0; i < model.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const double x = model.particles.position[i][c];
      y[3 * i + c] = x + 1e-4 * std::sin(3.0 * x + c);
    }
  }
  forces->compute(y.data(), b.data()); // warm-up: page in every array
  std::vector<double> seconds;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t s = 0; s < steps; ++s) {
      forces->compute(y.data(), b.data());
    }
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(seconds.begin(), seconds.end());
  const double median = seconds[seconds.size() / 2];
  const double rate = pd::bond_updates_per_second(model.family.bond_count(), steps, median);
  pd::Json j;
  j["scene"] = scene_path;
  j["kernel"] = forces->description();
  j["threads"] = thread_count();
  j["particles"] = model.size();
  j["bonds"] = model.family.bond_count();
  j["steps"] = steps;
  j["repeats"] = repeats;
  j["seconds"] = median;
  j["seconds_all"] = pd::Json::array_of(seconds);
  j["bond_updates_per_second"] = rate;
  if (json) {
    fmt::print("{}", j.dump());
  } else {
    fmt::print("{}: {} particles, {} bonds, kernel {}, {} threads\n", scene_path, model.size(),
               model.family.bond_count(), forces->description(), thread_count());
    fmt::print("{} evaluations: median {:.4f} s of {} repeats -> {:.4g} bond updates/s\n", steps,
               median, repeats, rate);
  }
  return 0;
}

int cmd_verify(const std::vector<std::string>& names, const std::string& out_dir, bool list,
               const std::string& scenes_dir, int threads) {
  set_threads(threads);
  const auto& cases = pd::verification::all_cases();
  if (list) {
    for (const auto& c : cases) {
      fmt::print("{:<20} {}\n", c.name, c.summary);
    }
    return 0;
  }
  pd::verification::Context ctx;
  ctx.scenes_dir = scenes_dir.empty() ? pd::verification::default_scenes_dir()
                                      : std::filesystem::path(scenes_dir);
  ctx.output_dir = out_dir;
  ctx.progress = ::isatty(STDERR_FILENO) != 0;
  std::vector<const pd::verification::Case*> selected;
  for (const auto& name : names) {
    auto it =
        std::find_if(cases.begin(), cases.end(), [&](const auto& c) { return c.name == name; });
    if (it == cases.end()) {
      fmt::print(stderr, "error: unknown verification case '{}' (see pd verify --list)\n", name);
      return 1;
    }
    selected.push_back(&*it);
  }
  if (selected.empty()) {
    for (const auto& c : cases) {
      selected.push_back(&c);
    }
  }
  int failed = 0;
  for (const auto* c : selected) {
    fmt::print("== {} — {}\n", c->name, c->summary);
    std::fflush(stdout);
    const auto t0 = std::chrono::steady_clock::now();
    pd::Json result = c->run(ctx);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    result["wall_seconds"] = wall;
    pd::write_file_atomically(std::filesystem::path(out_dir) / (c->name + ".json"), result.dump());
    const pd::Json* verdict = result.find("passed");
    const bool passed = verdict != nullptr && verdict->boolean().value_or(false);
    fmt::print("   {} in {:.1f} s -> {}/{}.json\n", passed ? "PASSED" : "FAILED", wall, out_dir,
               c->name);
    if (!passed) {
      ++failed;
    }
  }
  fmt::print("{} passed, {} failed\n", selected.size() - static_cast<std::size_t>(failed), failed);
  return failed > 0 ? 2 : 0;
}

} // namespace

int main(int argc, char** argv) {
  CLI::App app{"pd — bond-based peridynamics with its own verification"};
  app.require_subcommand(1);
  int threads = 0;

  std::string scene, out_dir = "out";
  bool print_defaults = false;
  auto* run =
      app.add_subcommand("run", "Run a scene: writes DIR/summary.json, probes.csv and VTU files");
  run->add_option("scene", scene, "scene file (YAML)");
  run->add_option("-o,--output", out_dir, "output folder")->capture_default_str();
  run->add_option("--threads", threads, "OpenMP threads (default: all)");
  run->add_flag("--print-defaults", print_defaults, "print a commented scene template and exit");

  bool json = false;
  auto* info = app.add_subcommand("info", "Particles, bonds, memory estimate and stable time step");
  info->add_option("scene", scene, "scene file (YAML)")->required();
  info->add_flag("--json", json, "machine-readable output");

  std::size_t steps = 100;
  std::string stretch;
  int repeats = 5;
  auto* bench =
      app.add_subcommand("bench", "Force-evaluation throughput (bond updates per second)");
  bench->add_option("scene", scene, "scene file (YAML)")->required();
  bench->add_option("--steps", steps, "force evaluations per repeat")->capture_default_str();
  bench->add_option("--repeats", repeats, "repeats; the median is reported")->capture_default_str();
  bench->add_option("--threads", threads, "OpenMP threads (default: all)");
  bench->add_option("--stretch", stretch, "override the stretch measure")
      ->check(CLI::IsMember({"exact", "modified", "fast"}));
  bench->add_flag("--json", json, "machine-readable output");

  std::vector<std::string> cases;
  bool list = false;
  std::string scenes_dir;
  std::string verify_out = "verification-out";
  auto* verify =
      app.add_subcommand("verify", "Run verification cases; exit code 2 if a gate fails");
  verify->add_option("cases", cases, "case names (default: all)");
  verify->add_option("-o,--output", verify_out, "output folder")->capture_default_str();
  verify->add_flag("--list", list, "list the cases");
  verify->add_option("--scenes", scenes_dir, "folder with the shipped scenes");
  verify->add_option("--threads", threads, "OpenMP threads (default: all)");

  CLI11_PARSE(app, argc, argv);
  try {
    if (*run) {
      if (print_defaults) {
        fmt::print("{}", pd::scene_template());
        return 0;
      }
      if (scene.empty()) {
        fmt::print(stderr, "error: pd run needs a scene file (or --print-defaults)\n");
        return 1;
      }
      return cmd_run(scene, out_dir, threads);
    }
    if (*info) {
      return cmd_info(scene, json);
    }
    if (*bench) {
      return cmd_bench(scene, steps, threads, json, stretch, std::max(repeats, 1));
    }
    if (*verify) {
      return cmd_verify(cases, verify_out, list, scenes_dir, threads);
    }
  } catch (const pd::SceneError& e) {
    fmt::print(stderr, "{}\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
  return 0;
}
